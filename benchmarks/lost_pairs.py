"""Lost-header pairs: every cycle's next header lost together with one list frame of the cycle, on a capture.

For each cycle k of the log and each of its list frames (0x60B–0x60E), the stream of cycles k−5 … k+2 is fed to a
fresh consumer with that frame and the header of cycle k+1 left out. A standing sensor repeats its frames, so the
next cycle's frames can fill cycle k's lost place; the consumer must drop cycle k rather than deliver it mixed.
Counted: pairs in which some delivered cycle differs from what a clean assembly of the whole log delivers under that
MeasCounter (*wrong*); pairs in which cycle k was delivered all the same with the content it was sent with (*k as
sent*: the next cycle's frame for its place was identical); cycles of the window other than k and k+1 that a clean
assembly of the window delivers and this one did not (*other cycles lost*).

Run: ``python benchmarks/lost_pairs.py`` (the public ARS 408 capture in ``../shared``; about 4 minutes),
``--log FILE`` for another log, ``--cycles N`` for its first N cycles only, ``--tree DIR`` to measure the consumer of
another source tree (say ``git archive COMMIT | tar -x -C DIR``). Prints a Markdown table.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CAPTURE = ROOT.parent / "shared" / "reference" / "ars408" / "candump-ars408-parked.log"
LIST_IDS = (0x60B, 0x60C, 0x60D, 0x60E)
HEADER = 0x60A


def _as_sent(a, b, names) -> bool:
    """Whether two delivered object cycles hold the same objects, every column equal (NaN equal to NaN)."""
    import numpy as np
    if (a.has_quality, a.has_extended, a.has_warning, len(a.objects)) != \
            (b.has_quality, b.has_extended, b.has_warning, len(b.objects)):
        return False
    oa, ob = a.objects.take(np.argsort(a.objects.id)), b.objects.take(np.argsort(b.objects.id))
    return all(np.array_equal(getattr(oa, f), getattr(ob, f), equal_nan=True) for f in names)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--log", default=str(CAPTURE), help="the log (default: the public ARS 408 capture)")
    ap.add_argument("--cycles", type=int, default=0, help="only the first N cycles (0: all)")
    ap.add_argument("--tree", default=str(ROOT), help="the source tree whose consumer is measured")
    args = ap.parse_args(argv)
    if not Path(args.log).is_file():
        print(f"error: {args.log!r} not found (the public capture lives in ../shared/reference/ars408)",
              file=sys.stderr)
        return 2
    sys.path.insert(0, str(Path(args.tree).resolve()))
    import can

    from radarnode.consumer.assembler import CycleAssembler
    from radarnode.perception.types import ObjectList
    from radarnode.wire.dbc import load_database

    names = list(ObjectList.__dataclass_fields__)
    db = load_database()
    msgs = list(can.LogReader(args.log))
    truth = {c.meas_counter: c for c in CycleAssembler().feed(msgs)}
    heads = [i for i, m in enumerate(msgs) if m.arbitration_id == HEADER]
    n = len(heads) - 2 if not args.cycles else min(len(heads) - 2, args.cycles)
    pairs = wrong = k_as_sent = others_lost = 0
    start = time.perf_counter()
    for j in range(5, n):
        k0, k1 = heads[j], heads[j + 1]
        ck = db.decode_message(HEADER, msgs[k0].data)["Obj_MeasCounter"]
        ck1 = db.decode_message(HEADER, msgs[k1].data)["Obj_MeasCounter"]
        lo, hi = heads[j - 5], heads[j + 2] if j + 3 >= len(heads) else heads[j + 3]
        clean = {c.meas_counter for c in CycleAssembler().feed(msgs[lo:hi])}
        for lost in (i for i in range(k0 + 1, k1) if msgs[i].arbitration_id in LIST_IDS):
            got = list(CycleAssembler().feed(msgs[lo:lost] + msgs[lost + 1:k1] + msgs[k1 + 1:hi]))
            bad = {c.meas_counter for c in got
                   if c.meas_counter not in truth or not _as_sent(c, truth[c.meas_counter], names)}
            right = {c.meas_counter for c in got} - bad
            pairs += 1
            wrong += bool(bad)
            k_as_sent += ck in right
            others_lost += len(clean - {ck, ck1} - right)
    print(f"| log | tree | pairs | wrong | k as sent | other cycles lost | s |\n|---|---|---:|---:|---:|---:|---:|\n"
          f"| {Path(args.log).name} | {Path(args.tree).name} | {pairs} | {wrong} | {k_as_sent} | {others_lost} | "
          f"{time.perf_counter() - start:.0f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
