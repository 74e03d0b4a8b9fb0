"""What users run: ``radarnode log SCENARIO --fidelity object -o FILE`` end to end (issue 13 item 10).

Each row times the command as a user starts it — a new Python process, imports, model set-up, every cycle
(object list, road boundaries and the cluster list where the scenario asks for them, encoding, the vehicle's
0x300/0x301 frames) and the file written — as the median wall time of ``--runs`` runs. The real-time factor is
the scenario's duration over that time. A first row, ``python -c "import radarnode.cli.main, radarnode.cli.log"``,
is the start-up floor of the command (since 2026-11-28 ``radarnode.cli.main`` alone imports almost nothing: each
command imports its modules when it runs). Then the issue's target case: ``highway_cut_in.yaml --duration 300``, and
last its end: the time from the command's return (``radarnode.cli.program`` raising SystemExit, or in a tree before it
``SystemExit(radarnode.cli.main())``, as ``python -m radarnode`` did) to its process's end, the interpreter's exit.

Run: ``.venv/bin/python benchmarks/log_speed.py [--runs N] [--suffix .blf] [--only SUBSTRING] [--before DIR]``.
Prints a Markdown table. ``--before DIR`` (a tree of another version, e.g. ``git archive REV | tar -x -C DIR``)
times that tree and this one interleaved — before, after, before, after, … — so that both see the same load, and
prints both times and their ratio. The runs use the detection statistic's table cache as a user's do
(``radarnode.radar.tables``; ``RADARNODE_CACHE_DIR=off`` times them computing the tables every run), and the
package's compiled bytecode as an installed package does (each tree is compiled first, and the runs may use it
whatever PYTHONDONTWRITEBYTECODE says: before 2026-11-28 this machine's setting of it made every run recompile
radarnode's sources, 0.1–0.5 s of each figure).
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from radarnode.radar import tables  # noqa: E402
from radarnode.radar.setup import load_scenario  # noqa: E402


#: the runs' environment: Python may keep the modules' bytecode, as an installed package has it (pip compiles it on
#: install). A shell with PYTHONDONTWRITEBYTECODE set would recompile radarnode's sources on every start, some
#: 0.1–0.5 s a run that no user pays (each tree is compiled once before the timing: :func:`compile_tree`)
ENV = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}


def compile_tree(root: Path) -> None:
    """The bytecode of a tree's package, written once, as an installation writes it."""
    subprocess.run([sys.executable, "-m", "compileall", "-q", str(root / "radarnode")], check=True,
                   capture_output=True, env=ENV)


def wall(cmd: list[str], runs: int, roots: tuple[Path, ...] = (ROOT,)) -> list[float]:
    """Median wall time of a command (it must succeed) in each tree of ``roots``, seconds; the runs of the trees
    interleaved. ``python -m radarnode`` imports the tree it is started in (its working directory)."""
    times: list[list[float]] = [[] for _ in roots]
    for _ in range(runs):
        for k, root in enumerate(roots):
            t0 = time.perf_counter()
            subprocess.run(cmd, check=True, capture_output=True, cwd=root, env=ENV)
            times[k].append(time.perf_counter() - t0)
    return [statistics.median(t) for t in times]


#: the command as ``python -m radarnode`` runs it, printing when it returns (its SystemExit) on stderr
ENDING = """
import sys, time
import radarnode.cli as cli
try:
    cli.program() if hasattr(cli, "program") else sys.exit(cli.main())
except SystemExit:
    sys.stderr.write("RETURNED %.6f\\n" % time.time())
    raise
"""


def ending(cmd: list[str], runs: int, roots: tuple[Path, ...]) -> list[float]:
    """Median time from the command's return to its process's end in each tree of ``roots``, seconds (the trees'
    runs interleaved); ``cmd``: the command's arguments after ``radarnode``."""
    times: list[list[float]] = [[] for _ in roots]
    for _ in range(runs):
        for k, root in enumerate(roots):
            done = subprocess.run([sys.executable, "-c", ENDING, *cmd], check=True, capture_output=True, text=True,
                                  cwd=root, env=ENV)
            end = time.time()
            returned = [line for line in done.stderr.splitlines() if line.startswith("RETURNED ")]
            times[k].append(end - float(returned[-1].split()[1]))
    return [statistics.median(t) for t in times]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--suffix", default=".blf")
    ap.add_argument("--only", default="")
    ap.add_argument("--before", type=Path, help="a tree of another version, timed interleaved with this one")
    args = ap.parse_args()
    py = sys.executable
    roots = (ROOT,) if args.before is None else (args.before.resolve(), ROOT)
    for root in roots:
        compile_tree(root)
    start = wall([py, "-c", "import radarnode.cli.main, radarnode.cli.log"], args.runs, roots)
    where = tables.cache_dir()
    print(f"### `radarnode log … --fidelity object -o x{args.suffix}`, median of {args.runs} runs, the package's "
          "bytecode compiled as an installation has it\n")
    print(f"(the detection statistic's table cache: {where}; filled by the first run of each configuration)\n"
          if where is not None else "(the detection statistic's table cache: off (RADARNODE_CACHE_DIR))\n")
    if args.before is None:
        print("| scenario | simulated | cycles | wall time | real-time factor |")
        print("|---|---:|---:|---:|---:|")
        print(f"| (start-up: `import radarnode.cli.main, radarnode.cli.log`) | - | - | {start[0]:.2f} s | - |",
              flush=True)
    else:
        print("| scenario | simulated | cycles | before | after | before/after | real-time factor after |")
        print("|---|---:|---:|---:|---:|---:|---:|")
        print(f"| (start-up: `import radarnode.cli.main, radarnode.cli.log`) | - | - | {start[0]:.2f} s | "
              f"{start[1]:.2f} s | "
              f"{start[0] / start[1]:.2f}× | - |", flush=True)
    cases = [(p, None) for p in sorted((ROOT / "scenarios").glob("*.yaml")) if args.only in p.stem]
    cases.append((ROOT / "scenarios" / "highway_cut_in.yaml", 300.0))
    with tempfile.TemporaryDirectory() as tmp:
        out = str(Path(tmp) / f"x{args.suffix}")
        for path, duration in cases:
            sc = load_scenario(path)
            sim = duration if duration is not None else sc.duration_s
            cmd = [py, "-m", "radarnode", "log", str(path), "--fidelity", "object", "-o", out]
            if duration is not None:
                cmd += ["--duration", str(duration)]
            t = wall(cmd, args.runs, roots)
            name = path.stem + (f" --duration {duration:g}" if duration is not None else "")
            cycles = int(round(sim / sc.period_s))
            if args.before is None:
                print(f"| {name} | {sim:g} s | {cycles} | {t[0]:.2f} s | {sim / t[0]:.0f}× |", flush=True)
            else:
                print(f"| {name} | {sim:g} s | {cycles} | {t[0]:.2f} s | {t[1]:.2f} s | {t[0] / t[1]:.2f}× | "
                      f"{sim / t[1]:.0f}× |", flush=True)
        end = ending(["log", str(ROOT / "scenarios" / "highway_cut_in.yaml"), "--fidelity", "object", "-o", out,
                      "--duration", "300"], args.runs, roots)
        name = "(end of the 300-s log: the command's return to its process's end)"
        if args.before is None:
            print(f"| {name} | - | - | {1e3 * end[0]:.0f} ms | - |", flush=True)
        else:
            print(f"| {name} | - | - | {1e3 * end[0]:.0f} ms | {1e3 * end[1]:.0f} ms | {end[0] / end[1]:.2f}× | - |",
                  flush=True)

if __name__ == "__main__":
    main()
