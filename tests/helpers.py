"""Small scenario builders for tests."""

from __future__ import annotations

from radarnode.radar.setup import parse_scenario


def scenario(actors_yaml: str = "", *, ego: str = "{speed_mps: 20.0}", radar: str = "{preset: ars408_like}",
             road: str = "{lanes: 3, lane_width_m: 3.5, ego_lane: 1}", duration: float = 3.0, seed: int = 1,
             extra: str = ""):
    """A scenario of these actors (YAML list items) on this road; ``extra``: more top-level YAML (``signal: …``)."""
    text = f"""
name: test
duration_s: {duration}
seed: {seed}
radar: {radar}
ego: {ego}
road: {road}
{extra}
actors:
{actors_yaml if actors_yaml.strip() else "  []"}
"""
    if not actors_yaml.strip():
        text = text.replace("actors:\n  []", "actors: []")
    return parse_scenario(text)


def masking_inputs(p, scene, times):
    """What the object level's masking and centroid read at ``times`` of ``scene`` with preset ``p``, as its chunk
    computes them: (truth, view at the nearest points inside the field of view, range, azimuth, observable, SNR)."""
    import dataclasses

    import numpy as np

    from radarnode.radar import equation
    from radarnode.radar.object_model import in_fov, nearest_in_fov
    truth = scene.views(times)
    x_in, y_in = nearest_in_fov(p, truth, scene.length_m, scene.width_m)
    view = dataclasses.replace(truth, x_m=x_in, y_m=y_in)
    rng_m, az = view.range_m, view.azimuth_rad
    snr = equation.snr_db(p, rng_m, scene.rcs_dbsm + np.zeros(rng_m.shape), 0.0, az)
    return truth, view, rng_m, az, in_fov(p, rng_m, az), snr


def can_unshare(flags: str = "-n") -> bool:
    """Whether ``unshare <flags>`` and iproute2 work here (udp_multicast tests keep their traffic inside a private
    network namespace so it never leaves this machine)."""
    import shutil
    import subprocess
    if not shutil.which("unshare") or not shutil.which("ip"):
        return False
    return subprocess.run(["unshare", flags, "true"], capture_output=True).returncode == 0


#: the lines that give a new network namespace a loopback interface carrying multicast
MULTICAST_LOOPBACK = """set -e
ip link set lo up
ip link set lo multicast on
ip route add 224.0.0.0/4 dev lo
"""


def cli(capsys, *argv) -> tuple[int, str, str]:
    """Run a radarnode command in-process (the console entry point): (exit status, stdout, stderr)."""
    from radarnode.cli.main import main
    try:
        rc = main([str(a) for a in argv])
    except SystemExit as exc:           # argparse's usage errors
        rc = exc.code
    out, err = capsys.readouterr()
    return rc, out, err


def node_and_consumer_over_multicast(tmp_path, group: str, node_args: str, consume_args: str, out_name: str) -> str:
    """``radarnode consume`` and ``radarnode node`` as two processes over udp_multicast inside a private network
    namespace (nothing leaves this machine); asserts both ended well and returns the consumer's standard output.
    The node's stderr is left in ``tmp_path/node.err``, the consumer's in ``tmp_path/consume.err``."""
    import os
    import subprocess
    import sys
    from pathlib import Path
    root = Path(__file__).resolve().parents[1]
    script = MULTICAST_LOOPBACK + f"""
{sys.executable} -m radarnode.cli consume -i udp_multicast -c {group} {consume_args} > {tmp_path}/{out_name} 2> {tmp_path}/consume.err &
CONSUMER=$!
for i in $(seq 100); do grep -q listening {tmp_path}/consume.err && break; sleep 0.1; done
{sys.executable} -m radarnode.cli node {node_args} -i udp_multicast -c {group} 2> {tmp_path}/node.err
wait $CONSUMER
"""
    r = subprocess.run(["unshare", "-n", "bash", "-c", script], capture_output=True, text=True, timeout=120,
                       cwd=root, env={**os.environ, "PYTHONPATH": str(root)})
    assert r.returncode == 0, (r.stderr, (tmp_path / "consume.err").read_text(), (tmp_path / "node.err").read_text())
    return (tmp_path / out_name).read_text()


def measured_objects(*rows: dict):
    """An object list as the ECU receives it, a row for each dict of ObjectList fields (``id``, ``dist_long_m``,
    ``vrel_long_mps``, ``rcs_dbsm``, ``obj_class``, ``dyn_prop``, …): every row measured, σ 0.2 m and 0.2 m/s, a car's
    4.5 × 1.8 m, unless the row says otherwise."""
    from radarnode.perception.types import MEAS_MEASURED, ObjectList
    defaults = {"meas_state": MEAS_MEASURED, "dist_long_sigma_m": 0.2, "dist_lat_sigma_m": 0.2,
                "vrel_long_sigma_mps": 0.2, "vrel_lat_sigma_mps": 0.2, "length_m": 4.5, "width_m": 1.8}
    ol = ObjectList.empty(len(rows))
    for j, row in enumerate(rows):
        for name, value in {**defaults, **row}.items():
            getattr(ol, name)[j] = value
    return ol


def feed_ecu(ecu, k: int, t_s: float, ego_mps: float | None, *rows: dict):
    """Radar cycle ``k`` at ``t_s`` of these object rows (:func:`measured_objects`) into ``ecu``, after the ego's speed
    (none: left as it is); returns its decision."""
    from radarnode.consumer.assembler import ObjectCycle
    if ego_mps is not None:
        ecu.set_ego(t_s, ego_mps, 0.0)
    return ecu.on_cycle(t_s, ObjectCycle(k, t_s, measured_objects(*rows), True, True))
