"""``radarnode export LOG -o run.mcap [--scenario SCENARIO]``: any CAN log as MCAP for Foxglove.

Reads any python-can log (.blf .asc .log .csv .mf4 .trc …: ``radarnode log``'s, a bench capture, the real
ARS 408's) and writes what its frames carry in Foxglove's schemas: the decoded objects, clusters, road
boundaries and the ECU's AccStatus/FcwStatus, and every raw frame. With the log's scenario (and the
``--start-time`` it was logged with) the ego and the ground truth go on topics of their own, evaluated at the
scenario time of each decoded cycle (the truth does not depend on the seed, only the radar's noise does).
The range–Doppler map is not in a log: ``radarnode log --fidelity signal -o run.mcap`` has it.
"""

from __future__ import annotations

import sys
from pathlib import Path

import can

from radarnode.cli.common import atomic_path, progress
from radarnode.cli.foxglove import is_mcap, require_foxglove, scenario_metadata, summary
from radarnode.errors import ConfigError, FieldError


def add_subparser(sub) -> None:
    p = sub.add_parser("export", help="write a CAN log (plus its scenario) as MCAP for Foxglove",
                       description=__doc__)
    p.add_argument("log", help="python-can log file (.blf .asc .log .csv .mf4 .trc …)")
    p.add_argument("-o", "--output", required=True, help="MCAP file to write (.mcap)")
    p.add_argument("--scenario", help="the scenario the log was rendered from: adds the ego and the ground truth")
    p.add_argument("--start-time", type=float, default=0.0,
                   help="timestamp of the scenario's start in the log, s (log --start-time; default 0)")
    p.add_argument("--sensor-id", type=int, default=0, help="the radar whose frames are decoded (default 0)")
    p.set_defaults(func=cmd)


def cmd(args) -> int:
    from radarnode import validate
    from radarnode.viz.recorder import FoxgloveRecorder
    if not is_mcap(args.output):
        raise ConfigError(f"option --output: value {args.output!r} is not allowed; expected a file name ending in "
                          ".mcap")
    try:
        validate.integer("--sensor-id", args.sensor_id, lo=0, hi=7)
        validate.number("--start-time", args.start_time, lo=-1e11, hi=1e11)
    except FieldError as exc:
        raise ConfigError(f"option {exc.field}: value {exc.value!r} is not allowed; expected {exc.allowed}") from None
    if not Path(args.log).is_file():
        raise ConfigError(f"argument LOG: {args.log!r} is not a file; expected a python-can log file")
    require_foxglove("--output", args.output)     # before anything is read
    scenario = None
    if args.scenario:
        from radarnode.radar.setup import load_scenario
        scenario = load_scenario(args.scenario)
    try:
        reader = can.LogReader(args.log)
    except (ValueError, OSError) as exc:
        raise ConfigError(f"argument LOG: cannot read {args.log!r}: {exc}; expected a python-can log (.asc .blf "
                          ".csv .log .mf4 .trc …)") from None
    rec = FoxgloveRecorder(sensor_id=args.sensor_id)
    frames = 0
    with atomic_path(args.output, "--output") as tmp:
        try:
            meta, attachments = ({"log": Path(args.log).name}, [])
            if scenario is not None:
                from radarnode.scene.world import Scene
                m, attachments = scenario_metadata(scenario, "unknown (from a log)")
                meta.update(m)
                rec.attach_scene(Scene(scenario), args.start_time)
            rec.open_mcap(tmp, metadata=meta, attachments=attachments)
            bar = progress(None, f"exporting {Path(args.log).name}", unit="frame")
            try:
                for msg in reader:
                    rec.on_message_received(msg)
                    frames += 1
                    bar.update(1)
            except Exception as exc:  # noqa: BLE001 - python-can's readers raise many kinds on a damaged file
                raise ConfigError(f"argument LOG: {args.log!r} is damaged after {frames} frames: {exc}") from None
            finally:
                bar.close()
        finally:
            rec.close()
            stop = getattr(reader, "stop", None)
            if stop is not None:
                stop()
    print(f"read {frames} frames from {args.log}", file=sys.stderr)
    print(summary(rec, args.output), file=sys.stderr)
    return 0
