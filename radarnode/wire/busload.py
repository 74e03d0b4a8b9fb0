"""CAN frame lengths on the wire and the bus-load budget of one cycle.

A classical CAN data frame with a standard 11-bit identifier and ``n`` data
bytes has 47 + 8n bits including the 3-bit interframe space; of these, the
34 + 8n bits from start-of-frame to the end of the CRC are subject to bit
stuffing, which adds at most one bit per four after the first:
⌊(34 + 8n − 1)/4⌋. An 8-byte frame is 111 bits, 135 in the worst case.
(Extended identifiers: 67 + 8n bits, 54 + 8n stuffable.)
"""

from __future__ import annotations

import numpy as np


def frame_bits(dlc: int | np.ndarray, extended: bool = False, worst_case: bool = True) -> int | np.ndarray:
    """Bits one data frame occupies on the bus, interframe space included."""
    if isinstance(dlc, int):              # one frame: in Python numbers (several calls a cycle)
        base, stuffable = (67, 54) if extended else (47, 34)
        return base + 8 * dlc + ((stuffable + 8 * dlc - 1) // 4 if worst_case else 0)
    n = np.asarray(dlc)
    base, stuffable = (67, 54) if extended else (47, 34)
    bits = base + 8 * n
    if worst_case:
        bits = bits + (stuffable + 8 * n - 1) // 4
    return bits if isinstance(dlc, np.ndarray) else int(bits)


#: :func:`frame_bits` of a standard-ID data frame by its length (0 … 64 bytes), worst case and without stuffing: a
#: cycle's frames are counted from these (some 15 lookups a cycle instead of calls)
STANDARD_BITS_WORST = tuple(frame_bits(n) for n in range(65))
STANDARD_BITS_NOMINAL = tuple(frame_bits(n, worst_case=False) for n in range(65))


def frame_time_s(dlc: int, bitrate: int, extended: bool = False, worst_case: bool = True) -> float:
    """Time one frame takes on the bus at ``bitrate`` bit/s."""
    return frame_bits(dlc, extended, worst_case) / float(bitrate)


def bus_load(dlcs: list[int] | np.ndarray, bitrate: int, period_s: float, worst_case: bool = True) -> float:
    """Fraction of ``period_s`` the frames with these DLCs occupy at ``bitrate``."""
    bits = int(np.sum(frame_bits(np.asarray(dlcs, dtype=np.int64), False, worst_case)))
    return bits / (bitrate * period_s)
