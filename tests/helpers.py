"""Small scenario builders for tests."""

from __future__ import annotations

from radarnode.radar.setup import parse_scenario


def scenario(actors_yaml: str = "", *, ego: str = "{speed_mps: 20.0}", radar: str = "{preset: ars408_like}",
             road: str = "{lanes: 3, lane_width_m: 3.5, ego_lane: 1}", duration: float = 3.0, seed: int = 1):
    text = f"""
name: test
duration_s: {duration}
seed: {seed}
radar: {radar}
ego: {ego}
road: {road}
actors:
{actors_yaml if actors_yaml.strip() else "  []"}
"""
    if not actors_yaml.strip():
        text = text.replace("actors:\n  []", "actors: []")
    return parse_scenario(text)


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
