"""A run in Foxglove (issue 14 item 3): MCAP from ``log``/``export``, the live view of ``run``/``node``, the layout.

The MCAP files are read back with the ``mcap`` reader (protobuf payloads through ``mcap-protobuf-support``)
and checked against what the same scenario and seed put in a .blf log, decoded independently: every topic,
schema and message count, and the values of the objects, clusters, boundaries, ECU frames and raw frames.
"""

from __future__ import annotations

import asyncio
import base64
import json
import math
import os
import queue
import re
import signal
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

import can
import numpy as np
import pytest

pytest.importorskip("foxglove")
mcap_reader = pytest.importorskip("mcap.reader")
mcap_protobuf = pytest.importorskip("mcap_protobuf.decoder")

from radarnode.cli.main import main  # noqa: E402
from radarnode.consumer.assembler import ClusterCycle, CycleAssembler, ObjectCycle  # noqa: E402
from radarnode.radar.setup import load_scenario  # noqa: E402
from radarnode.scene.world import Scene  # noqa: E402
from radarnode.viz import TOPICS  # noqa: E402
from radarnode.viz import layout as fl  # noqa: E402
from radarnode.viz.messages import CLUSTER_FIELDS  # noqa: E402
from radarnode.wire import ids  # noqa: E402
from radarnode.wire.dbc import load_bus_database, load_own_database  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
HIGHWAY = ROOT / "scenarios" / "highway_cut_in.yaml"
CLUSTERS = ROOT / "scenarios" / "guardrail_traffic.yaml"
DURATION = "9"          # through the cut-in (4 s) and the FCW warning (8.3 s)

WIRE_TOPICS = {"/can/frames", "/radar/objects", "/radar/road_boundaries", "/ecu/acc", "/ecu/fcw"}
SCENE_TOPICS = {"/tf", "/ego", "/ego/state", "/ground_truth/actors", "/ground_truth/road"}


def read_mcap(path: Path) -> dict:
    """Topic -> (schema name, schema encoding, message encoding, [(log_time, decoded)]) plus the summary."""
    decoder = mcap_protobuf.DecoderFactory()
    out: dict = {}
    with open(path, "rb") as f:
        reader = mcap_reader.make_reader(f)
        summary = reader.get_summary()
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            entry = out.setdefault(channel.topic, (schema.name, schema.encoding, channel.message_encoding, []))
            if channel.message_encoding == "json":
                value = json.loads(message.data)
            else:
                value = decoder.decoder_for(channel.message_encoding, schema)(message.data)
            entry[3].append((message.log_time, value))
        meta = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
        attachments = {a.name: a.data for a in reader.iter_attachments()}
    counts = {summary.channels[cid].topic: n for cid, n in summary.statistics.channel_message_counts.items()}
    return {"topics": out, "counts": counts, "metadata": meta, "attachments": attachments}


def meta(entity) -> dict:
    return {kv.key: kv.value for kv in entity.metadata}


def decode_blf(path: Path, sensor_id: int = 0):
    frames = list(can.LogReader(str(path)))
    asm = CycleAssembler(sensor_id=sensor_id)
    cycles = list(asm.feed(frames))
    return frames, cycles, asm


@pytest.fixture(scope="module")
def highway(tmp_path_factory):
    """The same scenario and seed logged as MCAP and as BLF (byte-identical frames)."""
    d = tmp_path_factory.mktemp("fox")
    mcap_file, blf = d / "run.mcap", d / "run.blf"
    assert main(["log", str(HIGHWAY), "--fidelity", "object", "--duration", DURATION, "-o", str(mcap_file)]) == 0
    assert main(["log", str(HIGHWAY), "--fidelity", "object", "--duration", DURATION, "--ecu", "-o", str(blf)]) == 0
    return mcap_file, blf, read_mcap(mcap_file), decode_blf(blf)


def test_log_mcap_has_every_topic_with_its_schema_and_one_message_per_cycle_or_frame(highway):
    _, _, m, (frames, cycles, asm) = highway
    sc = load_scenario(HIGHWAY)
    n_cycles = int(float(DURATION) / sc.period_s + 1e-9)
    assert set(m["topics"]) == WIRE_TOPICS | SCENE_TOPICS          # object level: no clusters, no range–Doppler
    for topic, (schema, schema_enc, msg_enc, _) in m["topics"].items():
        assert schema == TOPICS[topic][0], topic
        if schema.startswith("foxglove."):
            assert (schema_enc, msg_enc) == ("protobuf", "protobuf"), topic
        else:
            assert (schema_enc, msg_enc) == ("jsonschema", "json"), topic
    counts = m["counts"]
    assert counts["/can/frames"] == len(frames)
    assert counts["/radar/objects"] == asm.stats.object_cycles == n_cycles
    assert counts["/radar/road_boundaries"] == asm.stats.boundary_frames == 2 * n_cycles
    assert counts["/ecu/acc"] == sum(f.arbitration_id == ids.ACC_STATUS for f in frames) == n_cycles
    assert counts["/ecu/fcw"] == sum(f.arbitration_id == ids.FCW_STATUS for f in frames) == n_cycles
    for topic in SCENE_TOPICS:
        assert counts[topic] == n_cycles, topic
    assert {t: len(v[3]) for t, v in m["topics"].items()} == counts
    assert m["metadata"]["radarnode"]["scenario"] == "highway_cut_in"
    assert m["metadata"]["radarnode"]["fidelity"] == "object"
    assert m["attachments"]["highway_cut_in.yaml"] == HIGHWAY.read_bytes()


def test_log_mcap_objects_are_the_decoded_frames(highway):
    _, _, m, (_, cycles, _) = highway
    objects = [c for c in cycles if isinstance(c, ObjectCycle)]
    published = m["topics"]["/radar/objects"][3]
    assert len(published) == len(objects)
    seen = 0
    for (log_time, update), cyc in zip(published, objects):
        assert abs(log_time - cyc.timestamp * 1e9) < 1e3              # stamped with the header frame (BLF: µs)
        assert [d.type for d in update.deletions] == [1]              # ALL: the list replaces the previous one
        ol = cyc.objects
        assert [e.id for e in update.entities] == [f"object {i}" for i in ol.id]
        for k, e in enumerate(update.entities):
            md = meta(e)
            assert int(md["id"]) == ol.id[k]
            for key, arr, lsb in (("dist_long_m", ol.dist_long_m, 0.2), ("dist_lat_m", ol.dist_lat_m, 0.2),
                                  ("vrel_long_mps", ol.vrel_long_mps, 0.25), ("vrel_lat_mps", ol.vrel_lat_mps, 0.25),
                                  ("rcs_dbsm", ol.rcs_dbsm, 0.5), ("length_m", ol.length_m, 0.2),
                                  ("width_m", ol.width_m, 0.2)):
                assert abs(float(md[key]) - arr[k]) < lsb / 100, (key, md[key], arr[k])
            assert md["class"] in ("car", "truck", "point", "pedestrian", "motorcycle", "bicycle", "wide")
            assert md["prob_of_exist"].endswith("%") or md["prob_of_exist"] == "Invalid"
            cube = e.cubes[0]
            assert abs(cube.size.x - ol.length_m[k]) < 1e-6 and abs(cube.size.y - ol.width_m[k]) < 1e-6
            text = e.texts[0].text
            assert text.startswith(f"{ol.id[k]} {md['class']}") and "m/s" in text and "P " in text
            seen += 1
    assert seen > 100


def test_log_mcap_boundaries_ecu_and_raw_frames_are_the_decoded_frames(highway):
    _, _, m, (frames, _, _) = highway
    raw = m["topics"]["/can/frames"][3]
    names = {msg.frame_id: msg.name for msg in load_bus_database().messages}
    for (log_time, rec), f in zip(raw, frames):
        assert rec["can_id"] == f.arbitration_id and rec["data"] == bytes(f.data).hex().upper()
        assert rec["dlc"] == f.dlc and abs(rec["timestamp"] - f.timestamp) < 1e-6
        assert rec["message"] == names.get(f.arbitration_id, "")
        assert abs(log_time - f.timestamp * 1e9) < 1e3
    own = load_own_database()
    for topic, can_id in (("/ecu/acc", ids.ACC_STATUS), ("/ecu/fcw", ids.FCW_STATUS)):
        sent = [own.decode_message(f.arbitration_id, f.data, decode_choices=False) for f in frames
                if f.arbitration_id == can_id]
        got = [rec for _, rec in m["topics"][topic][3]]
        assert len(sent) == len(got)
        for s, g in zip(sent, got):
            for name, value in s.items():
                assert abs(g[name] - value) < 1e-9, (topic, name)
    fcw = [rec["FCW_WarningLevel_label"] for _, rec in m["topics"]["/ecu/fcw"][3]]
    assert "Warning" in fcw and fcw[0] == "None"                      # the warning at 8.3 s, as `run` shows it
    sides = {ids.ROAD_BOUNDARY_LEFT: "left", ids.ROAD_BOUNDARY_RIGHT: "right"}
    sent = [(sides[f.arbitration_id], own.decode_message(f.arbitration_id, f.data, decode_choices=False))
            for f in frames if f.arbitration_id in sides]
    got = m["topics"]["/radar/road_boundaries"][3]
    assert len(sent) == len(got)
    for (side, s), (_, update) in zip(sent, got):
        prefix = "RBL" if side == "left" else "RBR"
        if not s[f"{prefix}_Valid"]:
            assert [d.id for d in update.deletions] == [f"boundary {side}"]
            continue
        (e,) = update.entities
        assert e.id == f"boundary {side}"
        assert abs(float(meta(e)["offset_m"]) - s[f"{prefix}_LatOffset"]) < 1e-6
        line = e.lines[0]
        assert abs(line.points[0].x - s[f"{prefix}_RangeStart"]) < 1e-6
        assert abs(line.points[-1].x - s[f"{prefix}_RangeEnd"]) < 1e-6
        for p in (line.points[0], line.points[len(line.points) // 2], line.points[-1]):
            y = (s[f"{prefix}_LatOffset"] + math.tan(math.radians(s[f"{prefix}_Heading"])) * p.x
                 + 0.5 * s[f"{prefix}_Curvature"] * p.x ** 2)
            assert abs(p.y - y) < 1e-9


def test_log_mcap_truth_and_ego_come_from_the_scenario(highway):
    _, _, m, _ = highway
    sc = load_scenario(HIGHWAY)
    scene = Scene(sc)
    truth = m["topics"]["/ground_truth/actors"][3]
    tf = m["topics"]["/tf"][3]
    ego = m["topics"]["/ego/state"][3]
    for k in (0, 40, 100):
        t_s = k * sc.period_s
        view = scene.view(t_s)
        _, update = truth[k]
        assert [e.id for e in update.entities] == [f"truth {a.id}" for a in sc.actors]
        for i, e in enumerate(update.entities):
            assert abs(float(meta(e)["centre_x_m"]) - view.centre_x_m[i]) < 1e-3
            assert abs(float(meta(e)["centre_y_m"]) - view.centre_y_m[i]) < 1e-3
        state = scene.ego_state(t_s)
        _, transforms = tf[k]
        world_ego, ego_radar = transforms.transforms
        assert (world_ego.parent_frame_id, world_ego.child_frame_id) == ("world", "ego")
        assert (ego_radar.parent_frame_id, ego_radar.child_frame_id) == ("ego", "radar")
        assert abs(world_ego.translation.x - state.x_m) < 1e-9
        assert abs(ego_radar.translation.x - sc.radar.mount.x_m) < 1e-9
        assert abs(ego_radar.translation.z - sc.radar.mount.z_m) < 1e-9
        _, rec = ego[k]
        assert abs(rec["speed_mps"] - state.speed_mps) < 1e-9
        assert abs(rec["wire_speed_mps"] - state.speed_mps) < 0.02 + 1e-9     # 0x300 carries 0.02 m/s LSB


def test_export_of_the_log_gives_the_same_wire_topics(highway, tmp_path):
    _, blf, m, _ = highway
    out = tmp_path / "export.mcap"
    assert main(["export", str(blf), "--scenario", str(HIGHWAY), "-o", str(out)]) == 0
    e = read_mcap(out)
    assert e["counts"] == m["counts"]
    def content(v):            # what was decoded; a BLF keeps time stamps to the µs and channels as numbers
        if isinstance(v, dict):
            return {k: x for k, x in v.items() if k not in ("timestamp", "channel")}
        return [(x.id, meta(x), [(p.x, p.y) for line in x.lines for p in line.points]) for x in v.entities]

    for topic in WIRE_TOPICS:
        a, b = m["topics"][topic][3], e["topics"][topic][3]
        assert np.allclose([t for t, _ in a], [t for t, _ in b], rtol=0, atol=1e3), topic
        assert [content(v) for _, v in a] == [content(v) for _, v in b], topic
    # the truth is evaluated at the decoded cycles' scenario times: the same actors at the same places
    for (_, x), (_, y) in zip(m["topics"]["/ground_truth/actors"][3], e["topics"]["/ground_truth/actors"][3]):
        assert [content_truth for content_truth in map(meta, x.entities)] == list(map(meta, y.entities))
    bare = tmp_path / "bare.mcap"
    assert main(["export", str(blf), "-o", str(bare)]) == 0
    assert set(read_mcap(bare)["counts"]) == WIRE_TOPICS           # no scenario: nothing but the wire


@pytest.mark.parametrize("suffix", [".blf", ".asc", ".log"])
def test_export_picks_one_bus_of_a_two_bus_capture(capsys, tmp_path, suffix):
    """A capture of two buses, a radar with sensor ID 0 on each (two seeds of one scene: other objects). ``export``
    took every frame and decoded the two radars' cycles as one (a noticed gap, session 75). Now ``--channel`` picks
    one bus, named as ``decode --channel`` names it: each export holds exactly that bus's frames and cycles; without
    it a warning says that sensor 0 came on two channels; a channel with no frame is refused and writes no file."""
    from radarnode.wire import logfiles
    runs = []
    for seed in ("1", "2"):
        blf = tmp_path / f"seed{seed}.blf"
        assert main(["log", str(HIGHWAY), "--fidelity", "object", "--duration", "1.5", "--seed", seed,
                     "-o", str(blf)]) == 0
        runs.append(list(can.LogReader(str(blf))))
    both = tmp_path / f"both{suffix}"
    writer = logfiles.open_writer(str(both))
    for bus, frames in enumerate(runs):
        for m in frames:
            m.channel = f"can{bus}"
    for m in sorted(runs[0] + runs[1], key=lambda m: m.timestamp):
        writer.on_message_received(m)
    writer.stop()
    capsys.readouterr()
    names = ("1", "2") if suffix != ".log" else ("can0", "can1")       # as decode --format json names them
    for bus, name in enumerate(names):
        for channel in (name, f"can{bus}"):
            out = tmp_path / f"bus{bus}-{channel}.mcap"
            assert main(["export", str(both), "--channel", channel, "-o", str(out)]) == 0
            err = capsys.readouterr().err
            assert "warning" not in err, err
            m = read_mcap(out)
            _, cycles, asm = decode_blf(tmp_path / f"seed{bus + 1}.blf")
            assert m["counts"]["/can/frames"] == len(runs[bus])
            assert m["counts"]["/radar/objects"] == asm.stats.object_cycles > 10
            got = [sorted(int(meta(e)["id"]) for e in v.entities) for _, v in m["topics"]["/radar/objects"][3]]
            assert got == [sorted(c.objects.id.tolist()) for c in cycles if isinstance(c, ObjectCycle)]
    merged = tmp_path / "merged.mcap"
    assert main(["export", str(both), "-o", str(merged)]) == 0
    err = capsys.readouterr().err
    assert "frames of sensor 0 on 2 channels" in err and "pick one with --channel" in err, err
    none = tmp_path / "none.mcap"
    # status 1: the log, read, has no frame there (2 is for a command line wrong before any file is opened)
    assert main(["export", str(both), "--channel", "can7", "-o", str(none)]) == 1
    err = capsys.readouterr().err
    assert "option --channel: value 'can7' is not allowed" in err and f"{names[0]}, {names[1]}" in err, err
    assert not none.exists()


def test_export_reads_the_real_ars408_capture(reference_dir, tmp_path):
    log = reference_dir / "candump-ars408-parked.log"
    out = tmp_path / "real.mcap"
    assert main(["export", str(log), "-o", str(out)]) == 0
    _, cycles, asm = decode_blf(log)
    m = read_mcap(out)
    assert m["counts"]["/radar/objects"] == asm.stats.object_cycles == 515
    first = m["topics"]["/radar/objects"][3][0][1]
    assert [int(meta(e)["id"]) for e in first.entities] == list(cycles[0].objects.id)


def test_clusters_are_points_with_their_decoded_values(tmp_path):
    mc, blf = tmp_path / "cl.mcap", tmp_path / "cl.blf"
    assert main(["log", str(CLUSTERS), "--duration", "1.0", "-o", str(mc)]) == 0
    assert main(["log", str(CLUSTERS), "--duration", "1.0", "--ecu", "-o", str(blf)]) == 0
    _, cycles, asm = decode_blf(blf)
    clusters = [c for c in cycles if isinstance(c, ClusterCycle)]
    m = read_mcap(mc)
    assert m["topics"]["/radar/clusters"][0] == "foxglove.PointCloud"
    assert "/radar/objects" not in m["counts"]
    assert m["counts"]["/radar/clusters"] == asm.stats.cluster_cycles == len(clusters) > 0
    n_points = 0
    for (log_time, cloud), cyc in zip(m["topics"]["/radar/clusters"][3], clusters):
        assert abs(log_time - cyc.timestamp * 1e9) < 1e3
        assert [f.name for f in cloud.fields] == list(CLUSTER_FIELDS)
        pts = np.frombuffer(cloud.data, dtype="<f4").reshape(-1, len(CLUSTER_FIELDS))
        cl = cyc.clusters
        assert len(pts) == len(cl) and cloud.point_stride == 4 * len(CLUSTER_FIELDS)
        np.testing.assert_allclose(pts[:, 0], cl.dist_long_m, atol=1e-3)      # float32 of 0.2 m LSB values
        np.testing.assert_allclose(pts[:, 1], cl.dist_lat_m, atol=1e-3)
        np.testing.assert_allclose(pts[:, 3], cl.rcs_dbsm, atol=1e-3)
        np.testing.assert_array_equal(pts[:, 7], cl.id)
        n_points += len(pts)
    assert n_points > 50


def test_signal_level_writes_the_range_doppler_map_as_an_image(tmp_path):
    out = tmp_path / "sig.mcap"
    assert main(["log", str(HIGHWAY), "--fidelity", "signal", "--duration", "0.3", "-o", str(out)]) == 0
    m = read_mcap(out)
    n = m["counts"]["/radar/objects"]
    assert n == 4
    assert m["counts"]["/radar/range_doppler"] == m["counts"]["/radar/range_doppler/annotations"] == n
    from radarnode.radar.setup import radar_config
    preset = radar_config(load_scenario(HIGHWAY)).preset
    images = m["topics"]["/radar/range_doppler"][3]
    notes = m["topics"]["/radar/range_doppler/annotations"][3]
    for (t_img, img), (t_note, note) in zip(images, notes):
        assert t_img == t_note
        assert img.encoding == "rgb8" and img.width == preset.num_chirps and img.step == 3 * img.width
        assert img.height == math.ceil(preset.max_range_m / preset.range_resolution_m) + 1
        pix = np.frombuffer(img.data, dtype=np.uint8).reshape(img.height, img.width, 3)
        # the strongest cell is the top of the colour map (yellow), the floor its bottom (dark violet)
        assert (pix == [253, 231, 37]).all(axis=2).any()
        assert (pix == [68, 1, 84]).all(axis=2).any()
        labels = [t.text for t in note.texts]
        assert f"{(img.height - 1) * preset.range_resolution_m:.0f} m" in labels and "0 m" in labels
        assert f"{-(img.width // 2) * preset.doppler_bin_mps:+.1f} m/s" in labels


def test_a_failed_mcap_log_leaves_no_file(tmp_path, monkeypatch, capsys):
    from radarnode.viz.recorder import FoxgloveRecorder

    calls = [0]
    real = FoxgloveRecorder.on_node_cycle

    def failing(self, out):
        calls[0] += 1
        if calls[0] == 5:
            raise OSError("disk full")
        real(self, out)

    monkeypatch.setattr(FoxgloveRecorder, "on_node_cycle", failing)
    out = tmp_path / "run.mcap"
    assert main(["log", str(HIGHWAY), "--duration", "1", "-o", str(out)]) == 1      # one error line, no traceback
    assert capsys.readouterr().err.strip().splitlines()[-1] == "error: disk full"
    assert list(tmp_path.iterdir()) == []


def test_layout_file_is_current_and_reads_only_topics_the_recorder_writes():
    path = fl.layout_path()
    assert path is not None and path.name == "foxglove_radarnode.json"
    committed = json.loads(path.read_text(encoding="utf-8"))
    assert committed == fl.layout(), "layouts/foxglove_radarnode.json is stale: run python -m radarnode.viz.layout"
    used = fl.topics_used(committed)
    assert used <= set(TOPICS), used - set(TOPICS)
    assert {"/radar/objects", "/radar/clusters", "/radar/road_boundaries", "/ground_truth/actors", "/ego",
            "/radar/range_doppler", "/ecu/acc", "/ecu/fcw", "/can/frames"} <= used
    panels = {key.split("!")[0] for key in committed["configById"]}
    assert {"3D", "Image", "StateTransitions", "Plot", "RawMessages"} <= panels

    def leaves(node):
        return [node] if isinstance(node, str) else leaves(node["first"]) + leaves(node["second"])
    assert sorted(leaves(committed["layout"])) == sorted(committed["configById"])


def test_bad_live_options_are_usage_errors(capsys):
    with pytest.raises(SystemExit) as exit_:            # refused as the command line is parsed
        main(["run", str(HIGHWAY), "--fast", "--duration", "0.2", "--quiet", "--foxglove", "--foxglove-port", "70000"])
    assert exit_.value.code == 2
    assert "option --foxglove-port: value 70000 is not allowed; expected an integer in [0, 65535]" in \
        capsys.readouterr().err
    import socket
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        assert main(["run", str(HIGHWAY), "--fast", "--duration", "0.2", "--quiet", "--foxglove",
                     "--foxglove-port", str(port)]) == 1          # a port in use: not the command line's fault
    err = capsys.readouterr().err
    assert f"option --foxglove-port: cannot serve the live view on 127.0.0.1:{port}" in err
    assert main(["export", str(HIGHWAY), "-o", "x.blf"]) == 2
    assert "expected a file name ending in .mcap" in capsys.readouterr().err


def test_without_foxglove_sdk_the_commands_say_what_to_install(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "foxglove", None)          # as if foxglove-sdk were not installed
    out = tmp_path / "run.mcap"
    assert main(["log", str(HIGHWAY), "--duration", "0.2", "-o", str(out)]) == 2
    assert f"option --output: value '{out}' needs foxglove-sdk" in capsys.readouterr().err
    assert main(["run", str(HIGHWAY), "--fast", "--duration", "0.2", "--quiet", "--foxglove"]) == 2
    assert "option --foxglove: value True needs foxglove-sdk" in capsys.readouterr().err
    assert main(["export", str(HIGHWAY), "-o", str(out)]) == 2
    assert "pip install 'radarnode[foxglove]'" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


# --- the live view ----------------------------------------------------------------------------------------

async def _first_object_message(port: int, timeout_s: float):
    """Connect as a Foxglove client, subscribe to /radar/objects, return the first SceneUpdate with entities."""
    import websockets
    from mcap.records import Schema

    deadline = time.monotonic() + timeout_s
    async with websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=["foxglove.sdk.v1"],
                                  open_timeout=timeout_s, max_size=None) as ws:
        channel = None
        while time.monotonic() < deadline:
            raw = await asyncio.wait_for(ws.recv(), timeout=max(deadline - time.monotonic(), 0.1))
            if isinstance(raw, str):
                op = json.loads(raw)
                if op["op"] == "advertise" and channel is None:
                    for c in op["channels"]:
                        if c["topic"] == "/radar/objects":
                            channel = c
                            await ws.send(json.dumps({"op": "subscribe",
                                                      "subscriptions": [{"id": 7, "channelId": c["id"]}]}))
                continue
            opcode, sub_id, log_time = struct.unpack_from("<BIQ", raw)
            assert opcode == 1 and sub_id == 7
            schema = Schema(id=1, name=channel["schemaName"], encoding=channel["schemaEncoding"],
                            data=base64.b64decode(channel["schema"]))
            update = mcap_protobuf.DecoderFactory().decoder_for(channel["encoding"], schema)(raw[13:])
            if update.entities:
                return channel, log_time, update
    raise AssertionError("no object message within the time-out")


def _stderr_lines(proc) -> queue.Queue:
    lines: queue.Queue = queue.Queue()

    def pump():
        for line in proc.stderr:
            lines.put(line)
        lines.put(None)
    threading.Thread(target=pump, daemon=True).start()
    return lines


@pytest.mark.parametrize("command", [
    ["run", str(HIGHWAY), "--quiet"],
    ["node", str(HIGHWAY), "-i", "virtual", "-c", "radarnode-fox-test", "--send-ego-motion"],
])
def test_live_view_serves_object_messages_over_foxglove_websocket(command):
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen([sys.executable, "-m", "radarnode", *command, "--duration", "20", "--foxglove",
                             "--foxglove-port", "0"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True, env=env)
    try:
        lines = _stderr_lines(proc)
        port, deadline, seen = None, time.monotonic() + 60, []
        while port is None and time.monotonic() < deadline:
            try:
                line = lines.get(timeout=1.0)
            except queue.Empty:
                continue
            if line is None:
                break
            seen.append(line)
            found = re.search(r"live view on ws://127\.0\.0\.1:(\d+)", line)
            port = int(found.group(1)) if found else None
        assert port, "".join(seen)
        channel, log_time, update = asyncio.run(_first_object_message(port, timeout_s=30.0))
        assert channel["schemaName"] == "foxglove.SceneUpdate" and channel["encoding"] == "protobuf"
        assert log_time > 1e18                                   # real time: wall-clock stamps (ns)
        e = update.entities[0]
        assert e.frame_id == "radar" and e.id.startswith("object ")
        assert {"id", "class", "vrel_long_mps", "prob_of_exist"} <= set(meta(e))
        proc.send_signal(signal.SIGINT)                          # stops after the current cycle
        assert proc.wait(timeout=30) == 130
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(timeout=10)


def test_export_decodes_the_scenarios_sensor_id_unless_told_otherwise(tmp_path, capsys):
    """A sensor-5 scenario's log exported with --scenario: sensor 5's objects, not an MCAP of raw frames only."""
    text = (ROOT / "scenarios" / "highway_cut_in.yaml").read_text()
    s5 = tmp_path / "s5.yaml"
    s5.write_text(re.sub(r"(?m)^(\s*)sensor_id:.*$", r"\1sensor_id: 5", text))
    assert load_scenario(s5).radar.sensor_id == 5
    log = tmp_path / "s5.blf"
    assert main(["log", str(s5), "--duration", "0.5", "-o", str(log)]) == 0
    capsys.readouterr()
    out = tmp_path / "s5.mcap"
    assert main(["export", str(log), "--scenario", str(s5), "-o", str(out)]) == 0
    assert "warning" not in capsys.readouterr().err
    assert "/radar/objects" in read_mcap(out)["counts"]
    # without the scenario: sensor 0, which sent nothing here; said on stderr with the IDs there are
    assert main(["export", str(log), "-o", str(tmp_path / "s0.mcap")]) == 0
    err = capsys.readouterr().err
    assert "warning: no frame of sensor 0" in err and "sensor ID 5" in err and "--sensor-id" in err


def test_decoded_values_carry_no_binary_noise(tmp_path):
    """scale × raw + offset in floating point gives 2.84e-14 for 0 m and 3.6500000000000004 for 3.65: the MCAP
    has each value at its signal's resolution (the JSON of /ecu/*, the metadata text of /radar/objects)."""
    out = tmp_path / "run.mcap"
    assert main(["log", str(ROOT / "scenarios" / "highway_cut_in.yaml"), "--duration", "8", "-o", str(out)]) == 0
    got = read_mcap(out)["topics"]
    noisy = re.compile(r"e-|\.\d{7,}")
    seen = 0
    for topic in ("/ecu/acc", "/ecu/fcw"):
        for _, rec in got[topic][3]:
            for key, v in rec.items():
                if key != "timestamp" and isinstance(v, float):
                    seen += 1
                    assert v == round(v, 3) and not noisy.search(repr(v)), (topic, key, v)
    for _, update in got["/radar/objects"][3]:
        for entity in update.entities:
            for key, text in meta(entity).items():
                seen += 1
                assert not noisy.search(text), (key, text)
    assert seen > 100


def test_signal_value_rounds_to_the_dbc_resolution():
    from radarnode.wire.busdbc import frame_table, signal_value
    sig = next(s for info in frame_table().values() for s in info.message.signals if s.name == "Obj_DistLat")
    assert signal_value(sig, -204.6 + 1023 * 0.2) == 0 and signal_value(sig, 3.6000000000000014) == 3.6
    assert isinstance(signal_value(sig, -2.0), float)          # a scaled signal stays a float when whole


def test_export_of_one_radar_of_several_draws_it_on_its_own_mount(tmp_path, capsys):
    """front_and_corners.yaml: `export --sensor-id 1` published radar 1's objects with radar 0's mount in /tf (3.7 m,
    0 m, 0°, where radar 1 sits at 3.5 m, 0.73 m, 45°: an independent tester's finding). Now /tf gives each radar's
    own mount and the truth is taken around it; a sensor ID the scenario has no radar for is refused."""
    fc = HIGHWAY.parent / "front_and_corners.yaml"
    sc = load_scenario(fc)
    blf = tmp_path / "fc.blf"
    assert main(["log", str(fc), "--duration", "1.0", "-o", str(blf)]) == 0
    for radar in sc.radars[:2]:
        out = tmp_path / f"fc{radar.sensor_id}.mcap"
        assert main(["export", str(blf), "--scenario", str(fc), "--sensor-id", str(radar.sensor_id),
                     "-o", str(out)]) == 0
        tf = read_mcap(out)["topics"]["/tf"][3][0][1]
        (to_radar,) = [t for t in tf.transforms if t.child_frame_id == "radar"]
        m = radar.mount
        assert (to_radar.translation.x, to_radar.translation.y) == pytest.approx((m.x_m, m.y_m))
        assert 2.0 * math.degrees(math.atan2(to_radar.rotation.z, to_radar.rotation.w)) == pytest.approx(m.yaw_deg)
    capsys.readouterr()
    assert main(["export", str(blf), "--scenario", str(fc), "--sensor-id", "5", "-o", str(tmp_path / "x.mcap")]) == 2
    assert "option --sensor-id: value 5 is not allowed" in capsys.readouterr().err
    assert not (tmp_path / "x.mcap").exists()


@pytest.fixture(scope="module")
def short_log(tmp_path_factory):
    """One second of highway_cut_in as a candump .log: one frame per line, its time in brackets."""
    path = tmp_path_factory.mktemp("short") / "h.log"
    assert main(["log", str(HIGHWAY), "--duration", "1", "-o", str(path)]) == 0
    return path


@pytest.mark.parametrize("bad", ["nan", "inf", "-inf", "1e300", "4294967296.0", "-1.0"])
def test_export_leaves_out_frames_whose_time_mcap_cannot_hold_and_says_how_many(short_log, tmp_path, capsys, bad):
    # a NaN, infinite or huge time in a damaged log ended the export with a traceback from deep inside the recorder
    # (an independent tester's finding): the frame is left out, counted, and the status says the export is not whole
    lines = short_log.read_text().splitlines()
    assert re.match(r"^\(\d+\.\d+\) ", lines[40]) and re.match(r"^\(\d+\.\d+\) ", lines[41])
    lines[40] = re.sub(r"^\([^)]*\)", f"({bad})", lines[40])
    damaged = tmp_path / "d.log"
    damaged.write_text("\n".join(lines) + "\n")
    out = tmp_path / "d.mcap"
    assert main(["export", str(damaged), "-o", str(out)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith(f"error: argument LOG: {str(damaged)!r}: 1 frame left out: a timestamp an MCAP file "
                              "cannot hold") and f"the other {len(lines) - 1} are in {out}" in err[-1], err
    assert "Traceback" not in "\n".join(err)
    raw = read_mcap(out)["topics"]["/can/frames"][3]
    assert len(raw) == len(lines) - 1                 # every other frame is in it
    # the frame next to it is, at its own time
    t41 = float(re.match(r"^\(([^)]*)\)", lines[41]).group(1))
    assert any(abs(t - t41 * 1e9) < 1e3 for t, _ in raw)


def _export_with(short_log: Path, tmp_path: Path, frames: list[str]) -> tuple[list[str], list[dict]]:
    """The short log with candump ``frames`` (``ID#data``) after its 11th line, at that line's time, exported: (the
    log's lines, the /can/frames records)."""
    lines = short_log.read_text().splitlines()
    t = re.match(r"^\(([^)]*)\)", lines[10]).group(1)
    lines[11:11] = [f"({t}) can0 {frame}" for frame in frames]
    log = tmp_path / "with.log"
    log.write_text("\n".join(lines) + "\n")
    out = tmp_path / "with.mcap"
    assert main(["export", str(log), "-o", str(out)]) == 0
    return lines, [rec for _, rec in read_mcap(out)["topics"]["/can/frames"][3]]


def test_export_marks_a_can_fd_frame_and_gives_it_no_message_name(short_log, tmp_path):
    # a CAN FD frame on 0x300 (SpeedInformation's ID) went into /can/frames under that message's name, nothing saying
    # it was FD (session 71's note): the node and the consumer drop it, so the raw topic must not name it the message
    lines, recs = _export_with(short_log, tmp_path, ["300##1" + "AB" * 64, "300#R"])
    assert len(recs) == len(lines)
    fd = [r for r in recs if r["is_fd"]]
    assert len(fd) == 1 and fd[0]["can_id"] == 0x300 and fd[0]["message"] == "" and fd[0]["dlc"] == 64
    assert fd[0]["data"] == "AB" * 64
    remote = [r for r in recs if r["is_remote_frame"]]
    assert len(remote) == 1 and remote[0]["can_id"] == 0x300 and not remote[0]["is_fd"]
    classical = [r for r in recs if r["can_id"] == 0x300 and not r["is_fd"] and not r["is_remote_frame"]]
    assert classical and all(r["message"] == "SpeedInformation" for r in classical)


def test_export_writes_a_candump_error_frame_of_any_class_as_an_error_frame(short_log, tmp_path):
    # python-can's candump reader made an error frame only of the bus-error class: a controller-state error frame
    # (20000004#…, as candump logs it) went into /can/frames as a data frame on extended ID 0x4
    lines, recs = _export_with(short_log, tmp_path, [
        "20000004#0004000000000000", "00000004#0004000000000000",
        "20000204#0004000000000860",      # the class's bits are a message's ID (0x204): no name
        "20000080#0004000000000860"])     # python-can's own (bus error): its data kept
    assert len(recs) == len(lines)
    errors = [r for r in recs if r["is_error_frame"]]
    assert [(r["can_id"], r["message"], r["data"]) for r in errors] == [
        (0x4, "", "0004000000000000"), (0x204, "", "0004000000000860"), (0x80, "", "0004000000000860")]
    data = [r for r in recs if r["can_id"] == 0x4 and not r["is_error_frame"]]
    assert len(data) == 1 and data[0]["is_extended_id"]


def test_export_of_a_log_with_no_frame_mcap_can_time_writes_no_file(short_log, tmp_path, capsys):
    damaged = tmp_path / "all.log"
    damaged.write_text("".join(re.sub(r"^\([^)]*\)", "(nan)", ln) + "\n" for ln in short_log.read_text().splitlines()))
    out = tmp_path / "all.mcap"
    assert main(["export", str(damaged), "-o", str(out)]) == 1
    assert "expected frames timed in [0, 4294967296) s" in capsys.readouterr().err
    assert not out.exists() and list(tmp_path.iterdir()) == [damaged]


@pytest.mark.parametrize("start,ok", [(4294967294.0, True), (4294967294.98, False), (4294967296.0, False),
                                      (1e10, False)])
def test_an_mcap_log_must_end_before_foxglove_time_ends(tmp_path, capsys, start, ok):
    # Foxglove's timestamps hold 32-bit seconds: a log to .mcap from --start-time 1e10 ran, then crashed on its first
    # message (an independent tester's finding); now refused before the run, the limit tested at its edge (the run is
    # 1 s plus the ECU's 0.02 s latency)
    out = tmp_path / "t.mcap"
    status = main(["log", str(HIGHWAY), "--duration", "1", "-o", str(out), "--start-time", repr(start)])
    err = capsys.readouterr().err
    if ok:
        assert status == 0 and out.exists(), err
        assert all(t < 2 ** 32 * 1e9 for t, _ in read_mcap(out)["topics"]["/can/frames"][3])
    else:
        assert status == 2 and not out.exists()
        assert f"error: option --start-time: value {start!r} is not allowed for an .mcap log" in err
        assert "expected a start below 4294967294.980 s" in err
