"""Helpers shared by the subcommands: scenario loading, stop handling, tables, progress, atomic output, bit rate."""

from __future__ import annotations

import contextlib
import dataclasses
import errno
import json
import os
import signal
import stat
import sys
import tempfile
import threading
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from radarnode.cli import interrupt
from radarnode.errors import FileError, Terminated, UsageError
from radarnode.perception.types import CLASS_NAMES, DYN_NAMES
from radarnode.radar.setup import load_scenario
from radarnode.scene.scenario import Scenario

if TYPE_CHECKING:
    from collections.abc import Iterator

    from radarnode.consumer.assembler import ClusterCycle, ConsumerStats


def _scheduler_address(text: str) -> str:
    import argparse
    from radarnode.montecarlo.executor import valid_scheduler
    if not valid_scheduler(text):
        raise argparse.ArgumentTypeError(f"value {text!r} is not allowed; expected a Dask scheduler address such as "
                                         "tcp://host:8786 (tcp, tls, ws, wss or ucx; a port 1..65535)")
    return text


def add_scale_out_arguments(parser, what: str) -> None:
    """``--workers``, ``--scheduler``, ``--dask-local``: where the independent ``what`` (points, runs) are computed."""
    from radarnode.cli import options
    parser.add_argument("--workers", type=options.integer(lo=1, hi=1024), default=None,
                        help="local worker processes, 1..1024 (default: all cores)")
    parser.add_argument("--scheduler", type=_scheduler_address, default=None, metavar="ADDRESS",
                        help=f"run the {what} on the Dask cluster of this scheduler, e.g. tcp://host:8786 "
                             "(needs radarnode[dask])")
    parser.add_argument("--dask-local", type=options.integer(lo=1, hi=256), default=None, metavar="N",
                        help=f"run the {what} on a Dask LocalCluster of N single-threaded processes on this machine")


def check_scale_out(args) -> None:
    """Refuse contradictory scale-out options (UsageError) and a Dask option without dask installed."""
    if args.scheduler is not None and args.dask_local is not None:
        raise UsageError(f"option --dask-local: value {args.dask_local} is not allowed with --scheduler; expected one "
                         "of them (a cluster to connect to, or one to start here)")
    if args.workers is not None and (args.scheduler is not None or args.dask_local is not None):
        which = "--scheduler" if args.scheduler is not None else "--dask-local"
        raise UsageError(f"option --workers: value {args.workers} is not allowed with {which}; expected no --workers "
                         "(the cluster's workers do the work)")
    if args.scheduler is not None or args.dask_local is not None:
        from radarnode.montecarlo.executor import require_dask
        require_dask("--scheduler" if args.scheduler is not None else "--dask-local")


def add_scenario_argument(parser) -> None:
    from radarnode.cli import options
    parser.add_argument("scenario", help="scenario file (YAML), e.g. scenarios/highway_cut_in.yaml")
    parser.add_argument("--seed", type=options.SEED, help="override the scenario's seed (an integer >= 0)")
    parser.add_argument("--duration", type=options.DURATION,
                        help="override the scenario's duration in seconds, (0, 86400]")
    parser.add_argument("--fidelity", choices=("object", "detection", "signal", "auto"),
                        help="radar model level (default: the scenario's)")
    parser.add_argument("--doa", choices=options.DOA_CHOICES,
                        help="angle estimator of the signal chain (default: the scenario's signal.dsp.doa, else fft); "
                             "the others are super-resolution on the cells that hold more than one source, "
                             "at fidelity signal")


def scenario_from_args(args) -> Scenario:
    import dataclasses

    from radarnode import validate
    from radarnode.errors import FieldError
    sc = load_scenario(args.scenario)
    try:
        if args.seed is not None:
            sc = dataclasses.replace(sc, seed=validate.integer("--seed", args.seed, lo=0))
        if getattr(args, "fidelity", None):
            sc = dataclasses.replace(sc, fidelity=args.fidelity)
        if getattr(args, "doa", None):
            sc = with_doa(sc, args.doa)
            check_doa_presets(sc, args.doa)
        if args.duration is not None:
            sc = dataclasses.replace(sc, duration_s=validate.number("--duration", args.duration, lo=0.0,
                                                                      hi=86_400.0, lo_open=True))
    except FieldError as exc:
        raise UsageError(f"option {exc.field}: value {exc.value!r} is not allowed; expected {exc.allowed}") from None
    if args.duration is not None and sc.num_cycles < 1:
        # a run of no cycle writes a log of no frame: refused, as the duration the radar's cycle needs at least
        raise UsageError(f"option --duration: value {args.duration:g} is not allowed; expected at least one "
                         f"radar cycle of {sc.period_s:g} s: a duration in [{sc.period_s:g}, 86400] s")
    if getattr(args, "doa", None) and args.doa != "fft":
        check_doa_option(args.doa, sc.fidelity)
    if getattr(args, "fidelity", None) == "auto":
        check_auto_presets(sc)
    return sc


def check_auto_presets(scenario: Scenario) -> None:
    """``--fidelity auto`` on every radar of the scenario, by the models' own rule
    (``radarnode.radar.levels.auto_refused``): a UsageError naming the option and the radar."""
    from radarnode.radar.levels import auto_refused
    from radarnode.radar.presets import get_preset
    setups = [(f"radars[{i}]", s) for i, s in enumerate(scenario.radars)] if scenario.radars \
        else [("radar", scenario.radar)]
    for where, setup in setups:
        preset = get_preset(setup.preset).with_overrides(setup.overrides)
        why = auto_refused(preset)
        if why is not None:
            raise UsageError(f"option --fidelity: value 'auto' is not allowed with preset {preset.name} of {where} "
                             f"({why}); expected object, detection or signal")


def check_doa_option(doa: str, fidelity: str) -> None:
    """``--doa`` other than fft needs fidelity signal (UsageError naming the option: the command line conflicts)."""
    if doa != "fft" and fidelity != "signal":
        raise UsageError(f"option --doa: value {doa!r} is not allowed at fidelity {fidelity!r}; expected fft, or "
                         "--fidelity signal (super-resolution exists only in the signal chain: the object and "
                         "detection levels model the FFT beamformer)")


def check_doa_presets(scenario: Scenario, doa: str) -> None:
    """``--doa`` on every radar of the scenario, by the chain's own rule (``radarnode.radar.chain.preset_conflicts``):
    a UsageError naming the option and the radar (the command line asks what the scenario's preset cannot do)."""
    from radarnode.radar.chain import DspConfig, preset_conflicts
    from radarnode.radar.presets import get_preset
    setups = [(f"radars[{i}]", s) for i, s in enumerate(scenario.radars)] if scenario.radars \
        else [("radar", scenario.radar)]
    for where, setup in setups:
        preset = get_preset(setup.preset).with_overrides(setup.overrides)
        conflicts = preset_conflicts(DspConfig(doa=doa), preset)
        if conflicts:
            _, why, allowed = conflicts[0]
            raise UsageError(f"option --doa: value {doa!r} is not allowed with preset {preset.name} of {where} "
                             f"({why}); expected {allowed}")


class Stop(threading.Event):
    """Set by SIGINT or SIGTERM; ``signum`` says which (None while not stopped by a signal)."""

    signum: int | None = None

    @property
    def exit_status(self) -> int:
        """0, or 128 + the signal that stopped the command (130 for SIGINT, 143 for SIGTERM), as a shell reports a
        process the signal ended — here after the files were closed complete."""
        return 128 + self.signum if self.signum else 0


@contextlib.contextmanager
def stop_on_signals():
    """A :class:`Stop` event set by Ctrl-C or SIGTERM, so loops can finish the current cycle and close files.

    A second signal gives up at once (KeyboardInterrupt for SIGINT, :class:`Terminated` for SIGTERM). A signal the
    process was started with ignored (SIG_IGN: a job a non-interactive shell put in the background gets SIGINT so)
    stays ignored, as during the start-up (an independent tester: such a job ended with 130 on a SIGINT once its run
    had begun, 0 before)."""
    stop = Stop()
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return
    previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}

    def handler(signum, frame):
        if stop.is_set():          # a second signal: give up at once (once no module is loading)
            if interrupt.held(signum, frame):
                return
            if signum == signal.SIGINT:
                raise KeyboardInterrupt
            raise Terminated(signum)
        stop.signum = signum
        stop.set()

    for s, h in previous.items():
        if h is not signal.SIG_IGN:    # a signal ignored (a background job of a shell): it stays ignored
            signal.signal(s, handler)
    try:
        yield stop
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


def format_cycle(cycle: ObjectCycle | ClusterCycle, t_s: float | None = None, max_rows: int = 20) -> str:
    """A small fixed-width table of one decoded cycle."""
    when = f" t={t_s:7.2f} s" if t_s is not None else f" ts={cycle.timestamp:.3f}"
    from radarnode.consumer.assembler import ObjectCycle     # the consumer's types: not for every command
    if isinstance(cycle, ObjectCycle):
        ol = cycle.objects
        lines = [f"cycle {cycle.meas_counter:5d}{when}  {len(ol)} objects",
                 "   ID  class       dynprop     long_m   lat_m  vlong_m/s vlat_m/s  rcs_dBsm  LxW_m"]
        for k in range(min(len(ol), max_rows)):
            cls = CLASS_NAMES[ol.obj_class[k]] if 0 <= ol.obj_class[k] < 8 else "-"
            size = f"{ol.length_m[k]:.1f}x{ol.width_m[k]:.1f}" if np.isfinite(ol.length_m[k]) else "-"
            lines.append(f"  {ol.id[k]:3d}  {cls:10s}  {DYN_NAMES[ol.dyn_prop[k]]:10s} {ol.dist_long_m[k]:7.1f} "
                         f"{ol.dist_lat_m[k]:7.1f} {ol.vrel_long_mps[k]:9.2f} {ol.vrel_lat_mps[k]:8.2f} "
                         f"{ol.rcs_dbsm[k]:8.1f}  {size}")
    else:
        cl = cycle.clusters
        n_near = int(cl.is_near.sum())
        lines = [f"cycle {cycle.meas_counter:5d}{when}  {len(cl)} clusters ({n_near} near, {len(cl) - n_near} far)",
                 "   ID  dynprop     long_m   lat_m  vlong_m/s vlat_m/s  rcs_dBsm"]
        for k in range(min(len(cl), max_rows)):
            lines.append(f"  {cl.id[k]:3d}  {DYN_NAMES[cl.dyn_prop[k]]:10s} {cl.dist_long_m[k]:7.1f} "
                         f"{cl.dist_lat_m[k]:7.1f} {cl.vrel_long_mps[k]:9.2f} {cl.vrel_lat_mps[k]:8.2f} "
                         f"{cl.rcs_dbsm[k]:8.1f}")
    n = len(cycle.objects) if isinstance(cycle, ObjectCycle) else len(cycle.clusters)
    if n > max_rows:
        lines.append(f"  ... {n - max_rows} more")
    return "\n".join(lines)


def format_fused(fused, max_rows: int = 20) -> str:
    """A small fixed-width table of a fused object list (several radars, vehicle frame)."""
    from radarnode.perception.types import CLASS_NAMES as names
    lines = [f"fused t={fused.t_s:7.2f} s  {len(fused)} objects (vehicle frame, from the rear axle)",
             "   ID  class          x_m     y_m   vx_m/s  vy_m/s  rcs_dBsm  sensors"]
    for k in range(min(len(fused), max_rows)):
        cls = names[fused.obj_class[k]] if 0 <= fused.obj_class[k] < 8 else "-"
        seen = ",".join(map(str, fused.sensor_ids(k))) or "coasting"
        lines.append(f"  {fused.id[k]:3d}  {cls:10s} {fused.x_m[k]:7.1f} {fused.y_m[k]:7.1f} {fused.vx_mps[k]:8.2f} "
                     f"{fused.vy_mps[k]:7.2f} {fused.rcs_dbsm[k]:8.1f}  {seen}")
    if len(fused) > max_rows:
        lines.append(f"  ... {len(fused) - max_rows} more")
    return "\n".join(lines)


def require_matplotlib(who: str):
    """matplotlib's pyplot on the Agg backend, or a UsageError saying that ``who`` ("option --plots", "radarnode
    image") needs it and which extra installs it."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise UsageError(f"{who} needs matplotlib, which is not installed: pip install 'radarnode[image]'") from None
    # the texts are plain: a scenario's name or an actor's id with two '$' in it was read as TeX and ended the command
    # in matplotlib's traceback (an independent tester's finding); no label of ours is TeX
    matplotlib.rcParams["text.parse_math"] = False
    return plt


@contextlib.contextmanager
def plots_into(path: str) -> Iterator[Path]:
    """:func:`plot_dir` for a command that writes its plots into it: the directories it created are removed again,
    where they are still empty, when the command fails or is interrupted before it is done (a report interrupted
    before its first plot left an empty ``--plots`` directory: an independent tester's finding)."""
    d = Path(path)
    made = [p for p in (d, *d.parents) if not p.exists()]       # the directories mkdir will make, deepest first
    d = plot_dir(path)
    try:
        yield d
    except BaseException:
        for p in made:
            try:
                p.rmdir()           # only an empty one; a plot written stays
            except OSError:
                break
        raise


def plot_dir(path: str) -> Path:
    """``--plots DIR`` created if missing and writable, or a FileError naming the option."""
    d = Path(path)
    try:
        d.mkdir(parents=True, exist_ok=True)
    except FileExistsError:
        raise FileError(f"option --plots: value {path!r} is not allowed; expected a directory (it is a file)") \
            from None
    except NotADirectoryError:
        # (not the directory itself: one above it, which said "it is a file" of a name that did not exist)
        above = next((str(p) for p in reversed(d.parents) if p.is_file()), str(d.parent))
        raise FileError(f"option --plots: value {path!r} is not allowed; expected a directory ({above!r} above it is "
                        "a file)") from None
    except OSError as exc:
        raise FileError(f"option --plots: cannot create directory {path!r}: {exc.strerror or exc}") from None
    if not os.access(d, os.W_OK):
        raise FileError(f"option --plots: cannot write into directory {path!r}: permission denied")
    return d


def with_doa(scenario: Scenario, doa: str | None) -> Scenario:
    """The scenario with the signal chain's angle estimator given on the command line (``--doa``)."""
    if doa is None:
        return scenario
    sig = dict(scenario.signal)
    sig["dsp"] = {**(sig.get("dsp") or {}), "doa": doa}
    return dataclasses.replace(scenario, signal=sig)


def with_bitrate(scenario: Scenario, bit_s: int) -> Scenario:
    """The scenario with its bus's bit rate set (every radar's, when it has several)."""
    if bit_s == scenario.radar.bitrate:
        return scenario
    if scenario.radars:
        return dataclasses.replace(scenario, radars=tuple(dataclasses.replace(r, bitrate=bit_s)
                                                          for r in scenario.radars))
    return dataclasses.replace(scenario, radar=dataclasses.replace(scenario.radar, bitrate=bit_s))


def fusion_mounts(scenario: Scenario) -> dict:
    """Sensor ID → mount of every radar of ``scenario`` (what a fusing ECU has calibrated)."""
    from radarnode.consumer.path import SensorMount
    return {r.sensor_id: SensorMount.of(r.mount) for r in scenario.sensors}


def format_boundaries(boundaries: dict) -> str:
    """One line with the decoded road boundaries (radarnode's RoadBoundary_Left/Right, 0x680/0x681 + 8 × SensorID)."""
    parts = []
    for side in ("left", "right"):
        b = boundaries.get(side)
        if b is None:
            continue
        if not b.valid:
            parts.append(f"{side} unavailable")
        else:
            parts.append(f"{side} {b.offset_m:+.2f} m, heading {np.degrees(b.heading_rad):+.1f}°, "
                         f"{b.range_start_m:.0f}-{b.range_end_m:.0f} m, confidence {b.confidence:.2f}")
    return "road: " + "; ".join(parts) if parts else ""


def format_stats(stats: ConsumerStats) -> str:
    d = stats.as_dict()
    shown = {k: v for k, v in d.items() if v or k in ("frames", "cycles")}
    return "consumer: " + ", ".join(f"{k}={v}" for k, v in shown.items())


def progress(total: int | None, label: str, unit: str = "cycle", *, to_stdout: bool = False):
    """A tqdm progress bar on stderr, shown only when stderr is a terminal (never in piped output or logs).

    ``to_stdout``: the command writes its records to standard output as it goes (``decode`` without ``-o``);
    then no bar when standard output is a terminal too — the bar's redraws would land in the middle of the
    records, and the records scrolling by show the progress themselves.

    tqdm rather than a hand-written bar: it measures the rate and the time left, redraws at most ~10 times a
    second whatever the loop's speed, adapts to the terminal width and to resizes, and leaves a clean line when
    closed or interrupted. ``total`` None shows a running count without a bar.
    """
    if not sys.stderr.isatty() or (to_stdout and sys.stdout.isatty()):
        return _NoBar()                # (tqdm not even imported: some 6 ms of a command's start)
    from tqdm import tqdm
    return tqdm(total=total, desc=label, unit=unit, file=sys.stderr, dynamic_ncols=True, leave=False)


class _NoBar:
    """What :func:`progress` gives where no bar is shown: a disabled tqdm's interface (``update``, ``close``,
    ``disable``, ``write``), doing nothing but ``write``'s printing."""

    disable = True

    def update(self, n: int = 1) -> None:
        pass

    def close(self) -> None:
        pass

    @staticmethod
    def write(s: str, file=None, end: str = "\n") -> None:
        print(s, file=sys.stdout if file is None else file, end=end)


def _special(path: str | os.PathLike) -> bool:
    """Whether ``path`` exists and is neither a regular file nor a directory (a device such as /dev/null, a FIFO,
    a socket): such a target is written into, not replaced."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return False
    return not (stat.S_ISREG(mode) or stat.S_ISDIR(mode))


def _temporary(path: str | os.PathLike, option: str, keep_suffix: bool) -> tuple[Path, str]:
    """A new empty temporary file beside ``path`` (created, closed): ``.<name>_<random>_part<suffix>``; for a ``.gz``
    output, the target's own name in a new directory ``.<name>_<random>_part`` beside it (its gzip header names it).

    A symbolic link is followed: the file it points to is the one replaced (the link stays a link). Raises
    FileError naming the option when ``path`` is a directory or its directory cannot be written — before any work
    is done, not at the rename."""
    target = Path(path)
    if target.is_symlink():
        target = Path(os.path.realpath(target))
    if target.is_dir():
        raise FileError(f"option {option}: cannot write {str(path)!r}: it is a directory; expected a file name")
    if target.exists() and not os.access(target, os.W_OK):
        # a read-only file is one not to replace (the rename would have replaced it, taking its owner and mode)
        raise FileError(f"option {option}: cannot write {str(path)!r}: it is read-only; expected a file that may be "
                        "written, or a new name")
    if target.suffix.lower() == ".gz":
        # gzip keeps the file's name in its header (gunzip -N restores it): the temporary file has the target's own
        # name, in a temporary directory beside it, so that the header names the target, not the temporary file
        try:
            folder = tempfile.mkdtemp(prefix=f".{target.name.replace('.', '_')}_", suffix="_part", dir=target.parent)
            tmp = os.path.join(folder, target.name)
            open(tmp, "xb").close()
        except OSError as exc:
            raise _cannot_write(option, path, exc) from None
        return target, tmp
    suffixes = target.suffixes[-1:]
    suffix = "".join(suffixes) if keep_suffix else ""
    # no dot in the random part, so that a writer choosing its format by suffix sees the target's suffix and only it
    base = target.name[: len(target.name) - len("".join(suffixes))] if suffixes else target.name
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{base.replace('.', '_')}_", suffix="_part" + suffix,
                                   dir=target.parent)
        os.close(fd)
    except OSError as exc:
        raise _cannot_write(option, path, exc) from None
    return target, tmp


def _cannot_write(option: str, path: str | os.PathLike, exc: OSError) -> FileError:
    """The one error of an output that cannot be written: the option, the file and the system's reason."""
    return FileError(f"option {option}: cannot write {str(path)!r}: {exc.strerror or exc}")


#: errors of a write that has no room or no device under it: named as the output's, not passed on bare
_WRITE_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EIO})


@contextlib.contextmanager
def _named_write_errors(path: str | os.PathLike, option: str):
    """A full disk (or device: /dev/full), a quota or a file-size limit met while the output is written becomes
    one error naming the option and the file."""
    try:
        yield
    except OSError as exc:
        if exc.errno not in _WRITE_ERRNOS:
            raise
        raise _cannot_write(option, path, exc) from None


def _commit(tmp: str, target: Path, option: str) -> None:
    os.chmod(tmp, 0o666 & ~_umask())
    try:
        os.replace(tmp, target)
    except OSError as exc:
        raise _cannot_write(option, target, exc) from None
    _remove_folder(tmp, target)


def _discard(tmp: str, target: Path) -> None:
    """A failed write's temporary file removed (and its temporary directory, for a .gz output)."""
    with contextlib.suppress(OSError):
        os.unlink(tmp)
    _remove_folder(tmp, target)


def _remove_folder(tmp: str, target: Path) -> None:
    folder = os.path.dirname(tmp)
    if os.path.realpath(folder) != os.path.realpath(target.parent):       # the .gz output's own directory
        with contextlib.suppress(OSError):
            os.rmdir(folder)


@contextlib.contextmanager
def _signals_held():
    """SIGINT and SIGTERM held (where the system can hold them) until the ``release`` this yields is called, or the
    block ends: a temporary file's creation and the ``try`` that removes it on failure are then one step for them (a
    SIGTERM that came inside ``tempfile.mkstemp``, after it made the file and before its name came back, left the
    empty file behind: an independent tester, 1 in 40 early SIGTERMs of a ``radarnode log``)."""
    hold = getattr(signal, "pthread_sigmask", None)
    before = hold(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM}) if hold is not None else None
    done = [before is None]

    def release() -> None:
        if not done[0]:
            done[0] = True
            hold(signal.SIG_SETMASK, before)          # a signal held meanwhile comes here

    try:
        yield release
    finally:
        release()


@contextlib.contextmanager
def _replacing(path: str | os.PathLike, option: str, keep_suffix: bool):
    """A new temporary file for ``path`` (:func:`_temporary`, made with the signals held), yielded by name: renamed
    over ``path`` when the block ends, removed if it fails."""
    with _signals_held() as release:
        target, tmp = _temporary(path, option, keep_suffix=keep_suffix)
        try:
            release()
            yield tmp
            _commit(tmp, target, option)
        except BaseException:
            _discard(tmp, target)
            raise


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike, option: str, mode: str = "w", newline: str | None = None):
    """Write ``path`` through a temporary name in the same directory, renamed over it only on success.

    A reader never sees a half-written file: an exception (or Ctrl-C, SIGTERM) removes the temporary file and
    leaves any earlier ``path`` untouched. Yields the open file; ``option`` names the option in error messages.
    A symbolic link's file is replaced, not the link; a device, FIFO or socket (``-o /dev/null``, a pipe's
    reader) is written into directly — it was never a file to replace."""
    kw = {} if "b" in mode else {"encoding": "utf-8"}
    if _special(path):
        try:
            f = open(path, mode, newline=newline, **kw)
        except OSError as exc:
            raise _cannot_write(option, path, exc) from None
        with _named_write_errors(path, option), f:
            yield f
        return
    with _replacing(path, option, keep_suffix=False) as tmp, _named_write_errors(path, option), \
            open(tmp, mode, newline=newline, **kw) as f:
        yield f


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, option: str):
    """Like :func:`atomic_output`, for writers that want a file name (python-can, matplotlib): yields the
    temporary path, renamed to ``path`` on success, removed on failure. The temporary name ends in the target's
    suffix (both of ``.log.gz``), so writers that choose the format by suffix still do. A device, FIFO or socket
    is yielded itself (the writer writes into it)."""
    if _special(path):
        with _named_write_errors(path, option):
            yield str(path)
        return
    with _replacing(path, option, keep_suffix=True) as tmp, _named_write_errors(path, option):
        yield tmp


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@dataclasses.dataclass(frozen=True)
class Bitrate:
    """The CAN bit rate in force and where it came from (for the bus-load budget's message)."""

    bit_s: int
    source: str

    def __str__(self) -> str:
        return f"{self.bit_s} bit/s ({self.source})"


def resolve_bitrate(cli_bitrate: int | None, scenario_bitrate: int, *, use_can_config: bool = True,
                    context: str | None = None) -> Bitrate:
    """The bit rate for the bus-load budget, as python-can would open the bus.

    In order: ``-b/--bitrate`` on the command line; python-can's configuration — the environment
    (``CAN_BITRATE``, or ``bitrate`` in the JSON of ``CAN_CONFIG``), then its configuration files
    (``~/can.conf``, ``/etc/can.conf``, ``~/.can``, ``~/.canrc``; section ``[default]``), the same sources and
    precedence as ``can.util.load_config``; last the scenario's ``radar.bitrate`` (500 kbit/s unless the
    scenario says otherwise). ``use_can_config=False`` skips python-can's configuration (``radarnode log``
    opens no bus, so its output must not depend on the machine it runs on).

    Raises UsageError naming the source when the value is not an integer in 10 000..1 000 000 bit/s.
    """
    import can.util

    candidates: list[tuple[object, str]] = []
    if cli_bitrate is not None:
        candidates.append((cli_bitrate, "command line -b/--bitrate"))
    elif use_can_config:
        suffix = f"_{context}" if context else ""
        env = os.environ.get(f"CAN_BITRATE{suffix}")
        if env:
            candidates.append((env, f"python-can environment CAN_BITRATE{suffix}"))
        else:
            try:
                env_json = json.loads(os.environ.get(f"CAN_CONFIG{suffix}", "{}"))
            except ValueError:
                env_json = {}
            if isinstance(env_json, dict) and "bitrate" in env_json:
                candidates.append((env_json["bitrate"], f"python-can environment CAN_CONFIG{suffix}"))
            else:
                found = None
                for name in can.util.CONFIG_FILES:      # later files override earlier ones, as ConfigParser.read
                    f = os.path.expanduser(name)
                    if os.path.isfile(f):
                        with contextlib.suppress(OSError, ValueError):
                            value = can.util.load_file_config(f, context or "default").get("bitrate")
                            if value:
                                found = (value, f"python-can config file {f}")
                if found:
                    candidates.append(found)
    if not candidates:
        return Bitrate(int(scenario_bitrate), "scenario radar.bitrate")
    value, source = candidates[0]
    try:
        bit_s = int(str(value).strip())
    except ValueError:
        bit_s = None
    if bit_s is None or not 10_000 <= bit_s <= 1_000_000:
        raise UsageError(f"{source}: bit rate value {value!r} is not allowed; expected an integer "
                         "10000..1000000 bit/s")
    return Bitrate(bit_s, source)


def saturation_note(node) -> str | None:
    """One line of the values a node (or radar group) sent at their DBC signal's limit, by signal, or None: the ARS
    408's own limits (a lateral speed of −76.6 m/s went out as −64.0 without a word: a tester's finding)."""
    saturated = node.saturated
    if not saturated:
        return None
    return (f"note: {sum(saturated.values())} values lay beyond their signal's range and were sent at its limit (the "
            "DBC's minimum or maximum, as the sensor's fields allow): "
            + ", ".join(f"{k} {v}" for k, v in sorted(saturated.items())))


class ChannelPick:
    """``--channel``: the frames of one channel, and what the log held, for the error when none was that channel's.

    A log that keeps names (candump ``.log``) is picked by the exact name, or by a bare number N as python-can's
    writers spell it (``canN``): ``vcan1`` is not ``can1``, nor ``1`` (each name ending in 1 was one bus before: two
    buses merged without a word, an independent tester's finding). A log that numbers its channels from 1 (ASC, BLF,
    TRC) is picked by the file's number, or by an interface name counted from 0 as SocketCAN does: ``can0`` is the
    file's channel 1, where ``log --channel can0`` wrote it (:func:`radarnode.wire.logfiles.file_channel`, which
    refuses what is neither). A log that keeps no channel (``.csv``) has none to pick."""

    def __init__(self, channel: str | None, fmt: str, option: str = "--channel") -> None:
        from radarnode.wire.logfiles import ONE_BASED_CHANNELS, ascii_number, file_channel
        self.channel = channel
        self.one_based = fmt in ONE_BASED_CHANNELS      # (the refusal's hint on numbering is for these formats)
        number = None if channel is None else file_channel(channel, fmt, option)           # a numbered log's
        # what a frame's channel reads as: a name (exact, or canN for a bare N), or a number as text
        self.names = set() if channel is None else \
            {channel, f"can{channel}"} if ascii_number(channel) else {channel}
        self.number = channel if number is None else str(number)
        self.taken = 0                       # frames of the channel, over every pass
        self.seen: set[str] = set()          # the channels the log's frames came on (a frame without one: none)

    def __call__(self, frames):
        if self.channel is None:
            yield from frames
            return
        for msg in frames:
            ch = msg.channel
            if ch is None:
                continue
            self.seen.add(str(ch))
            if ch in self.names if isinstance(ch, str) else str(ch) == self.number:
                self.taken += 1
                yield msg

    def _held(self) -> str:
        return ", ".join(sorted(self.seen)) if self.seen else "none: this log keeps no channel (a .csv or .db log)"

    def refusal(self) -> str | None:
        """The error where ``--channel`` picked no frame (decode, export: status 1, no output file; an empty decode
        said nothing at first, then warned with status 0), else None."""
        if self.channel is None or self.taken:
            return None
        numbered = "; an ASC, BLF or TRC log numbers its channels from 1, and can0 is its channel 1" \
            if self.one_based else ""
        named = f" (as the log names them{numbered})" if self.seen else ""
        return (f"option --channel: value {self.channel!r} is not allowed: no frame of the log is on it; expected "
                f"one of the channels its frames are on: {self._held()}{named}")


def add_channel_option(p) -> None:
    """``--channel`` of the commands that read a log (decode, export): :class:`ChannelPick`'s."""
    from radarnode.cli import options
    p.add_argument("--channel", default=None, type=options.name("a channel name"),
                   help="only the frames of this channel (as the log names it: can1, or its number 1; an ASC, BLF "
                        "or TRC log numbers its channels from 1, and can0 is its channel 1): a capture of several "
                        "buses (default: every channel)")


class SensorCensus:
    """The radar sensor IDs whose frames a log holds (by the whole-bus DBC's ID plan), and the channels they came on,
    to say which to pick when the one asked for has none, or came on several buses."""

    def __init__(self) -> None:
        from radarnode.wire.busdbc import frame_table
        self._table = frame_table()
        self.present: set[int] = set()
        #: per sensor ID, the channels its frames came on (a capture of two buses, a radar 0 on each)
        self.channels: dict[int, set[str]] = {}

    def note(self, msg) -> None:
        if msg.is_extended_id or msg.is_error_frame or msg.is_remote_frame:
            return
        info = self._table.get(msg.arbitration_id)
        if info is not None and info.sensor_id is not None:
            self.present.add(info.sensor_id)
            self.channels.setdefault(info.sensor_id, set()).add(str(msg.channel))

    def channel_warning(self, wanted: int, option: str) -> str | None:
        """One line when ``wanted``'s frames came on more than one channel (decoded as one bus, a cycle of each radar
        taken for a stray or an orphan of the other's), else None."""
        seen = self.channels.get(wanted, set())
        if len(seen) < 2:
            return None
        names = ", ".join(sorted(seen))
        return (f"warning: frames of sensor {wanted} on {len(seen)} channels ({names}) were decoded as one bus: a "
                f"radar on each?; pick one with {option}")

    def warning(self, wanted: int, option: str, channel: str | None = None) -> str | None:
        """One line when the log (the frames of ``channel``, where ``--channel`` picked one) holds other sensors'
        frames but none of ``wanted``'s, else None."""
        if wanted in self.present or not self.present:
            return None
        ids = ", ".join(str(i) for i in sorted(self.present))
        where = "in the log" if channel is None else f"on channel {channel!r} (option --channel)"
        return (f"warning: no frame of sensor {wanted} {where}; it holds frames of sensor ID "
                f"{ids}{'' if channel is None else ' there'}: pick one with {option}")
