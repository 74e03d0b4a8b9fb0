"""AUTOSAR E2E Profile 2 for radarnode's own messages (``dbc/radarnode.dbc``).

Byte 0 is the CRC-8 (polynomial 0x2F, cantools' ``compute_profile2_crc``)
over bytes 1..n−1 followed by the Data ID; the low nibble of byte 1 is the
alive counter, advancing by one per sent frame modulo 16; the Data ID for
counter value c is taken from a 16-entry list, here ``(key + 17·c) mod 256``.
The key names the message and the sensor (:func:`radarnode.wire.ids.e2e_key`),
not the CAN ID, so a frame of another sensor or message fails the check.
"""

from __future__ import annotations

from dataclasses import dataclass, field


def _crc8_table(poly: int) -> tuple[int, ...]:
    table = []
    for byte in range(256):
        crc = byte
        for _ in range(8):
            crc = ((crc << 1) ^ poly) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
        table.append(crc)
    return tuple(table)


_CRC8_0X2F = _crc8_table(0x2F)


def profile2_crc(payload: bytes, data_id: int) -> int:
    """``compute_profile2_crc(payload, data_id)``: CRC-8/AUTOSAR (polynomial 0x2F, init and final XOR 0xFF, not
    reflected) over bytes 1..n−1 and the Data ID, by table (twice a cycle for the boundaries: a tenth of
    crccheck's cost)."""
    crc = 0xFF
    for b in payload[1:]:
        crc = _CRC8_0X2F[crc ^ b]
    return _CRC8_0X2F[crc ^ (data_id & 0xFF)] ^ 0xFF


def data_id(key: int, counter: int) -> int:
    """The Data ID of the message with E2E key ``key`` for alive-counter value ``counter`` (DataIDList[counter])."""
    return (key + 17 * (counter & 0xF)) & 0xFF


class E2EProtector:
    """Sender side: stamps counter and CRC into payloads, one counter per E2E key (message and sensor)."""

    def __init__(self) -> None:
        self._counter: dict[int, int] = {}

    def protect(self, key: int, payload: bytes) -> bytes:
        counter = self._counter.get(key, 0)
        self._counter[key] = (counter + 1) & 0xF
        data = bytearray(payload)
        data[1] = (data[1] & 0xF0) | counter
        data[0] = profile2_crc(data, data_id(key, counter))
        return bytes(data)


@dataclass
class E2EStats:
    """What the receiver saw: good frames, CRC errors, repeated frames, frames out of sequence (refused), frames
    lost (counter gaps), and the frames counted lost that came later after all (``late``: out of order, refused,
    counted in ``wrong_sequence`` too)."""

    ok: int = 0
    crc_errors: int = 0
    repeated: int = 0
    wrong_sequence: int = 0
    lost: int = 0
    late: int = 0
    last_counter: dict[int, int] = field(default_factory=dict)


class E2EChecker:
    """Receiver side: checks CRC and counter (AUTOSAR Profile 2's sequence check with MaxDeltaCounter
    ``MAX_DELTA``).

    A frame is used when its CRC holds and its counter advances by 1 … MAX_DELTA from the last one used (the frames
    in between are counted lost). Any other counter is refused (``wrong_sequence``): on a 4-bit counter a frame from
    the past looks like one from the future, and a late frame taken as the current one put an older road boundary in
    place of the newest. Of the refused frames,

    - one whose counter was counted lost is late (moved from ``lost`` to ``late``), a frame overtaken on the way;
    - one whose counter is among the last ``RECENT`` used is an old frame sent again, unless it continues a run
      begun by one that is not;
    - the rest may be a stream that really jumped (the sender restarted, a long outage): ``SYNC_FRAMES`` of them in
      counter order take it up again, as Profile 2's re-synchronisation does. A late frame never begins or continues
      such a run, nor does an old frame sent again begin one, so a delayed burst or a replay of the last RECENT frames
      cannot take the place of the newest. (Two frames older than that, sent again in order, are indistinguishable
      from a restarted sender on a 4-bit counter: they are taken up.)
    """

    MAX_DELTA = 4            # up to 3 frames lost in a row (3 radar cycles of a message sent once a cycle)
    RECENT = 8               # counters used last, whose return is a repeat of an old frame
    SYNC_FRAMES = 2          # frames in counter order, neither late nor repeated, that take up a jumped stream
    _FORGET = 12             # frames counted lost are recognised as late for this many counter steps

    def __init__(self) -> None:
        self.stats = E2EStats()
        self._recent: dict[int, list[int]] = {}           # per key: the counters used last, oldest first
        self._skipped: dict[int, dict[int, int]] = {}     # per key: counter counted lost → counter steps left
        self._run: dict[int, tuple[int, int]] = {}        # per key: (last refused counter of a run, its length)

    def check(self, key: int, payload: bytes) -> bool:
        """True when the frame may be used; ``key`` is the E2E key of the message expected on its ID."""
        if len(payload) < 2:
            self.stats.crc_errors += 1
            return False
        counter = payload[1] & 0xF
        if profile2_crc(payload, data_id(key, counter)) != payload[0]:
            self.stats.crc_errors += 1
            return False
        last = self.stats.last_counter.get(key)
        skipped = self._skipped.setdefault(key, {})
        recent = self._recent.setdefault(key, [])
        if last is not None:
            delta = (counter - last) & 0xF
            if delta == 0:
                self.stats.repeated += 1
                return False
            if delta > self.MAX_DELTA:
                if not self._takes_up(key, counter, skipped, recent):
                    self.stats.wrong_sequence += 1
                    return False
                recent.clear()
                skipped.clear()
                delta = 1                                   # what the jump skipped is unknowable
            for c in list(skipped):                         # forget what is too old to come late
                skipped[c] -= delta
                if skipped[c] <= 0:
                    del skipped[c]
            for k in range(1, delta):
                skipped[(last + k) & 0xF] = self._FORGET
            self.stats.lost += delta - 1
        self._run.pop(key, None)
        recent.append(counter)
        del recent[:-self.RECENT]
        self.stats.last_counter[key] = counter
        self.stats.ok += 1
        return True

    def _takes_up(self, key: int, counter: int, skipped: dict[int, int], recent: list[int]) -> bool:
        """Whether a frame out of sequence takes up a jumped stream (the class docstring): a late frame (moved from
        ``lost`` to ``late``) and an old frame sent again never do; the rest count towards SYNC_FRAMES in a row."""
        if counter in skipped:                              # counted lost, came late
            del skipped[counter]
            self.stats.lost -= 1
            self.stats.late += 1
            return False
        prev, length = self._run.get(key, (None, 0))
        continues = prev is not None and (counter - prev) & 0xF == 1
        if counter in recent and not continues:             # an old frame sent again
            return False
        length = length + 1 if continues else 1
        self._run[key] = (counter, length)
        return length >= self.SYNC_FRAMES
