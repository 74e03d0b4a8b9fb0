"""The object and signal levels' cost in instructions, which a shared machine's load does not move (valgrind's callgrind).

This machine's wall-clock times move by ±30 % from one run to the next on some days (a virtual machine on a shared
host): a change of 10–20 % in the object level cannot be told from the load by timing it, alternated or not. The
number of instructions a process executes can: for the same code, inputs and environment it is the same whatever
else the machine runs (``PYTHONHASHSEED=0``, ``OPENBLAS_NUM_THREADS=1``; seen here: two runs agree to a few parts
in 10⁵). Instructions are not seconds (a cache miss or a division costs more than an addition), so this table
says what a change removed, and the wall-clock benchmarks say what a user waits.

Each workload runs twice under callgrind, with a small and a large count of its unit, in a new process each, and
the table prints the difference over the difference of the counts: the imports and the set-up cancel out.

* ``chunk``: ``ObjectModel._chunk`` of 1024 cycles of ``highway_cut_in.yaml`` (the physics, the truth's views,
  the tracker's scan: what the object level computes once for 1024 cycles), per chunk;
* ``object``: the object level as ``benchmarks/fidelity.py --object-only`` times it — a new model, 1024 steps
  of ``highway_cut_in.yaml`` (object list only, the chunk included) — per 1024 cycles;
* ``detection``: the detection level as ``benchmarks/fidelity.py --detection-only`` times it — one model stepped
  through the first 20 and the first 80 cycles of ``highway_cut_in.yaml`` (object list and cluster list) — per frame
  (the difference of the two runs: frames 20–79, the set-up and the first frame's imports cancel out);
* ``log``: ``radarnode log scenarios/highway_cut_in.yaml --fidelity object --duration D -o x.blf`` (issue 13's
  command: object list, cluster list and road boundaries, file written), D = 30 and 150 s, per cycle, for each
  process: the run's own and the road boundaries' (``radarnode.wire.pipeline``);
* ``synth64``, ``synth128``, ``chain64``, ``chain128``: the signal level's two halves, ``synthesize_rd`` and
  ``DspChain.process_rd``, of ``signal_speed.py``'s highway_mimo12 frames at 0, 28 and 70 m/s (complex64 or
  complex128), per frame.

Run: ``python benchmarks/instructions.py [--only chunk,object,log,synth64,...] [--before DIR]`` (DIR: another version's tree,
``git archive REV | tar -x -C DIR``; its rows beside this checkout's and the ratio). Needs ``valgrind`` (Debian's
package); a workload takes 1–3 minutes under it, two run at a time. Prints a Markdown table.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: the workloads: (driver code run with the tree first on sys.path and the count as argv[2], the two counts, the
#: unit's size in counts, what a unit is)
_CHUNK = """
import sys
sys.path.insert(0, sys.argv[1])
import numpy as np
from pathlib import Path
from radarnode.radar.models import make_model
from radarnode.radar.object_model import RuntimeConfig
from radarnode.radar.setup import load_scenario, radar_config
from radarnode.scene.world import Scene
sc = load_scenario(Path(sys.argv[1]) / "scenarios" / "highway_cut_in.yaml")
rc = radar_config(sc)
model = make_model("object", Scene(sc), rc.preset, np.random.default_rng(sc.seed), rc.signal, clusters_wanted=False)
cfg = RuntimeConfig(max_distance_m=rc.preset.max_range_m, clusters=False)
times = np.arange(1024) * sc.period_s
model._chunk(0, times, cfg)                      # the tables and the draws: in both counts
for _ in range(int(sys.argv[2])):
    model._chunk(0, times, cfg)
"""
_OBJECT = """
import sys
sys.path.insert(0, sys.argv[1])
import numpy as np
from pathlib import Path
from radarnode.radar.models import make_model
from radarnode.radar.object_model import RuntimeConfig
from radarnode.radar.setup import load_scenario, radar_config
from radarnode.scene.world import Scene
path = Path(sys.argv[1]) / "scenarios" / "highway_cut_in.yaml"
for _ in range(int(sys.argv[2])):
    sc = load_scenario(path)
    rc = radar_config(sc)
    model = make_model("object", Scene(sc), rc.preset, np.random.default_rng(sc.seed), rc.signal,
                       clusters_wanted=False)
    cfg = RuntimeConfig(max_distance_m=rc.preset.max_range_m, clusters=False)
    model.planned_cycles = 1024
    for k in range(1024):
        model.step(k * sc.period_s, cfg)
"""
_DETECTION = """
import sys
sys.path.insert(0, sys.argv[1])
import numpy as np
from pathlib import Path
from radarnode.radar.models import make_model
from radarnode.radar.object_model import RuntimeConfig
from radarnode.radar.setup import load_scenario, radar_config
from radarnode.scene.world import Scene
sc = load_scenario(Path(sys.argv[1]) / "scenarios" / "highway_cut_in.yaml")
rc = radar_config(sc)
model = make_model("detection", Scene(sc), rc.preset, np.random.default_rng(sc.seed), rc.signal)
cfg = RuntimeConfig(max_distance_m=rc.preset.max_range_m)
for k in range(int(sys.argv[2])):
    model.step(k * sc.period_s, cfg)
"""
_LOG = """
import sys
sys.path.insert(0, sys.argv[1])
from radarnode.cli.main import main
try:
    main(["log", sys.argv[1] + "/scenarios/highway_cut_in.yaml", "--fidelity", "object", "--duration", sys.argv[2],
          "-o", "x.blf"])
except SystemExit as exc:
    if exc.code:
        raise
"""
_SIGNAL = """
import sys
sys.path.insert(0, sys.argv[1])
sys.path.insert(0, sys.argv[1] + "/benchmarks")
import numpy as np
from radarnode.radar.chain import DspChain
from radarnode.radar.signal_model import synthesize_rd
from signal_speed import highway_frames
dtype = np.{dtype}
frames = [highway_frames(ego, 1) for ego in (0.0, 28.0, 70.0)]
chain = DspChain(frames[0][0])
rng = np.random.default_rng(1)
maps = [synthesize_rd(p, s[0], rng, dtype=dtype) for p, s in frames]
chain.process_rd(maps[0])                        # the chain's tables: in both counts
for _ in range(int(sys.argv[2])):
    for (p, s), rd in zip(frames, maps):
        {work}
"""
WORKLOADS = {
    "chunk": (_CHUNK, (1, 4), 1.0, "a 1024-cycle chunk"),
    "object": (_OBJECT, (1, 3), 1.0, "1024 cycles, set-up included"),
    # the detection level as fidelity.py --detection-only times it (object list, cluster list): frames 20–79
    "detection": (_DETECTION, (20, 80), 1.0, "a frame"),
    "log": (_LOG, (30, 150), 1.0 / 0.072, "a cycle"),            # the scenario's 72-ms cycle: counts in seconds
    # the signal level's two halves on highway_mimo12 (signal_speed.py's frames at 0, 28 and 70 m/s): a frame
    "synth64": (_SIGNAL.format(dtype="complex64", work="synthesize_rd(p, s[0], rng, dtype=dtype)"), (1, 3), 3.0,
                "a frame (0/28/70 m/s)"),
    "synth128": (_SIGNAL.format(dtype="complex128", work="synthesize_rd(p, s[0], rng, dtype=dtype)"), (1, 3), 3.0,
                 "a frame (0/28/70 m/s)"),
    "chain64": (_SIGNAL.format(dtype="complex64", work="chain.process_rd(rd)"), (1, 3), 3.0, "a frame (0/28/70 m/s)"),
    "chain128": (_SIGNAL.format(dtype="complex128", work="chain.process_rd(rd)"), (1, 3), 3.0,
                 "a frame (0/28/70 m/s)"),
}


def instructions(tree: Path, code: str, count: int) -> list[int]:
    """Instructions of each process of one run of ``code`` (the main process first, then any it forked)."""
    with tempfile.TemporaryDirectory(prefix="radarnode-ir-") as tmp:
        env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
        env.update(PYTHONHASHSEED="0", OPENBLAS_NUM_THREADS="1", PYTHONPATH="")
        subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={tmp}/cg.%p", sys.executable, "-c",
                        code, str(tree), str(count)], check=True, capture_output=True, cwd=tmp, env=env)
        out = []
        for f in sorted(Path(tmp).glob("cg.*"), key=lambda p: int(p.suffix[1:])):   # pids in order of birth
            for line in f.read_text(errors="replace").splitlines():
                if line.startswith(("summary:", "totals:")):
                    out.append(int(line.split()[1]))
                    break
        return out


def per_unit(tree: Path, name: str) -> list[float]:
    """A workload's instructions per unit, each process."""
    code, (small, large), per, _ = WORKLOADS[name]
    with ThreadPoolExecutor(2) as pool:
        a, b = pool.map(lambda n: instructions(tree, code, n), (small, large))
    if len(a) != len(b):
        raise RuntimeError(f"{name}: {len(a)} and {len(b)} processes in the two runs")
    return [(y - x) / ((large - small) * per) for x, y in zip(a, b)]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", default=",".join(WORKLOADS), help="workloads, comma separated: " + ", ".join(WORKLOADS))
    ap.add_argument("--before", type=Path, help="a tree of another version, measured beside this one")
    args = ap.parse_args()
    if shutil.which("valgrind") is None:
        sys.exit("error: valgrind not found (Debian: apt install valgrind); it counts the instructions")
    names = [n.strip() for n in args.only.split(",") if n.strip()]
    for n in names:
        if n not in WORKLOADS:
            sys.exit(f"error: option --only: value {n!r} is not allowed; expected one of {', '.join(WORKLOADS)}")
    trees = ([args.before.resolve()] if args.before else []) + [ROOT]
    for t in trees:                     # the bytecode as an installation has it (not compiled inside the counts)
        subprocess.run([sys.executable, "-m", "compileall", "-q", str(t / "radarnode")], check=True,
                       capture_output=True)
    print("### Instructions (valgrind --tool=callgrind), PYTHONHASHSEED=0, OPENBLAS_NUM_THREADS=1\n")
    if args.before:
        print(f"| workload | per | process | before ({args.before}) | this tree | this/before |")
        print("|---|---|---|---:|---:|---:|")
    else:
        print("| workload | per | process | instructions |")
        print("|---|---|---|---:|")
    for name in names:
        rows = [per_unit(t, name) for t in trees]
        unit = WORKLOADS[name][3]
        for k in range(len(rows[-1])):
            proc = "the run" if k == 0 else "road boundaries" if name == "log" else f"process {k}"
            if args.before:
                b, a = rows[0][k], rows[1][k]
                print(f"| {name} | {unit} | {proc} | {b / 1e6:.2f} M | {a / 1e6:.2f} M | {a / b:.3f} |", flush=True)
            else:
                print(f"| {name} | {unit} | {proc} | {rows[0][k] / 1e6:.2f} M |", flush=True)


if __name__ == "__main__":
    main()
