"""``radarnode export LOG -o run.mcap [--scenario SCENARIO] [--channel CH]``: any CAN log as MCAP for Foxglove.

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

from radarnode.cli import options
from radarnode.cli.common import ChannelPick, SensorCensus, add_channel_option, atomic_path, progress
from radarnode.cli.foxglove import is_mcap, require_foxglove, scenario_metadata, summary
from radarnode.errors import FileError, UsageError
from radarnode.viz import MAX_STAMP_S
from radarnode.wire.logfiles import FORMATS, ReadReport, check_input, check_input_format, check_stem, read_frames


def _speed_warning(rec, scenario_path: str) -> str | None:
    """One line where the log's vehicle speed (SpeedInformation on the radar's ID, as ``radarnode log`` writes it)
    differs from the scenario's ego in most decoded cycles (the recorder compares them at each cycle it gives the
    truth), else None: a log exported with another run's scenario got that run's ground truth, status 0 and no word
    (an independent tester's finding)."""
    from radarnode.viz.recorder import SPEED_TOLERANCE_MPS
    if not rec.speed_compared or 2 * rec.speed_off <= rec.speed_compared:
        return None
    return (f"warning: the log's vehicle speed (SpeedInformation) is not the ego's of --scenario {scenario_path!r}: "
            f"{rec.speed_off} of {rec.speed_compared} cycles compared differ by more than {SPEED_TOLERANCE_MPS:g} m/s "
            f"(up to {rec.speed_worst_mps:.1f} m/s); its ground truth, ego and /tf are likely another run's (check "
            "--scenario and --start-time; a closed-loop run's ego is not the scenario's)")


def add_subparser(sub) -> None:
    p = sub.add_parser("export", help="write a CAN log (plus its scenario) as MCAP for Foxglove",
                       description=__doc__)
    p.add_argument("log", help="python-can log file (" + " ".join(FORMATS) + "; .mf4 with radarnode[mf4])")
    p.add_argument("-o", "--output", required=True, help="MCAP file to write (.mcap)")
    p.add_argument("--scenario", help="the scenario the log was rendered from: adds the ego and the ground truth")
    p.add_argument("--start-time", type=options.START_TIME, default=None,
                   help="timestamp of the scenario's start in the log, s, with --scenario (log --start-time; "
                        "default 0)")
    p.add_argument("--sensor-id", type=options.SENSOR_ID, default=None,
                   help="the radar whose frames are decoded, 0..7 (default: the --scenario's radar.sensor_id, else 0)")
    add_channel_option(p)
    p.set_defaults(func=cmd)


def cmd(args) -> int:
    from radarnode.viz.recorder import FoxgloveRecorder
    if args.start_time is not None and not args.scenario:
        # it places the scenario's ego and truth on the log's time line; without a scenario nothing uses it
        raise UsageError(f"option --start-time: value {args.start_time:g} is not allowed without --scenario; "
                         "expected --scenario with it (or no --start-time)")
    check_stem(args.output, "--output", (".mcap",))
    if not is_mcap(args.output):
        raise UsageError(f"option --output: value {args.output!r} is not allowed; expected a file name ending in "
                         ".mcap")
    require_foxglove("--output", args.output)     # before anything is read
    check_input_format(args.log, "argument LOG")
    fmt = check_input(args.log, "argument LOG")
    pick = ChannelPick(args.channel, fmt)
    scenario = None
    if args.scenario:
        from radarnode.radar.setup import load_scenario
        scenario = load_scenario(args.scenario)
    sensor_id = args.sensor_id if args.sensor_id is not None else scenario.radar.sensor_id if scenario else 0
    if scenario is not None:
        # the truth and /tf of the radar whose frames are decoded: its own mount (radar 1 of front_and_corners.yaml
        # was drawn on radar 0's)
        from radarnode.radar.setup import radar_scenarios
        radars = radar_scenarios(scenario)
        mine = [sc for sc in radars if sc.radar.sensor_id == sensor_id]
        if not mine:
            ids = ", ".join(str(sc.radar.sensor_id) for sc in radars)
            raise UsageError(f"option --sensor-id: value {sensor_id} is not allowed with --scenario "
                             f"{args.scenario!r}: its radars have sensor ID {ids}; expected one of them (its truth "
                             "is drawn around that radar's mount)")
        scenario = mine[0]
    rec = FoxgloveRecorder(sensor_id=sensor_id)
    census = SensorCensus()
    report = ReadReport(args.log, fmt)
    with atomic_path(args.output, "--output") as tmp:
        try:
            meta, attachments = ({"log": Path(args.log).name}, [])
            if scenario is not None:
                from radarnode.scene.world import Scene
                m, attachments = scenario_metadata(scenario, "unknown (from a log)")
                meta.update(m)
                rec.attach_scene(Scene(scenario), args.start_time or 0.0)
            rec.open_mcap(tmp, metadata=meta, attachments=attachments)
            bar = progress(None, f"exporting {Path(args.log).name}", unit="frame")
            try:
                for msg in pick(read_frames(args.log, report)):
                    rec.on_message_received(msg)
                    census.note(msg)
                    bar.update(1)
            finally:
                bar.close()
        finally:
            rec.close()
        if report.frames == 0:      # an empty log, or not a log of this format: no output file at all
            raise FileError(report.message("argument LOG"))
        refused = pick.refusal()
        if refused:                 # --channel picked no frame: no output file either (status 1: found in the log,
            raise FileError(refused)    # not on the command line alone, as the README's table of statuses says)
        if rec.frames_without_time == report.frames:        # nothing to put on a time line: no output file either
            raise FileError(f"argument LOG: {_no_time(rec, args.log)}; expected frames timed in [0, {MAX_STAMP_S}) s")
    print(f"read {report.frames} frames from {args.log}", file=sys.stderr)
    print(summary(rec, args.output), file=sys.stderr)
    # the sensor asked for sent nothing here, or its frames came on two buses (merged into one recording)
    for warning in (census.warning(sensor_id, "--sensor-id", args.channel),
                    census.channel_warning(sensor_id, "--channel")):
        if warning:
            print(warning, file=sys.stderr)
    speed_warning = _speed_warning(rec, args.scenario) if scenario is not None else None
    if speed_warning:
        print(speed_warning, file=sys.stderr)
    if scenario is not None and rec.cycles_outside_run:
        # (a log read back from another time base had no ground truth at all, and nothing said so)
        start = args.start_time or 0.0
        print(f"warning: {rec.cycles_outside_run} of {rec.cycles_outside_run + rec.truth_cycles} decoded cycles lie "
              f"outside the scenario's {scenario.duration_s:g}-s run from --start-time {start!r} s (the first at "
              f"{rec.first_outside_s:.6f} s): they have no ground truth, ego or /tf; give --start-time the log's "
              "start (log --start-time)", file=sys.stderr)
    if report.damaged:
        # everything readable is in the MCAP; the status says the log itself is not whole
        if rec.frames_without_time:
            print(f"warning: {_no_time(rec, args.log)}", file=sys.stderr)
        raise FileError(report.message("argument LOG"))
    if rec.frames_without_time:
        # the rest is in the MCAP; the status says the export is not whole
        raise FileError(f"argument LOG: {_no_time(rec, args.log)}; the other {report.frames - rec.frames_without_time} "
                        f"are in {args.output}")
    return 0


def _no_time(rec, log: str) -> str:
    """What the recorder left out of ``log`` for want of a time (:func:`radarnode.viz.stamp_ok`)."""
    n = rec.frames_without_time
    return (f"{log!r}: {n} frame{'s' if n != 1 else ''} left out: a timestamp an MCAP file cannot hold (a finite "
            f"number of seconds from 0 up to {MAX_STAMP_S}; the first {rec.first_bad_time!r})")
