"""AUTOSAR E2E Profile 2 for radarnode's own messages (``dbc/radarnode.dbc``).

Byte 0 is the CRC-8 (polynomial 0x2F, cantools' ``compute_profile2_crc``)
over bytes 1..n−1 followed by the Data ID; the low nibble of byte 1 is the
alive counter, advancing by one per sent frame modulo 16; the Data ID for
counter value c is taken from a 16-entry list, here ``(frame_id + 17·c) mod 256``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from cantools.autosar.end_to_end import compute_profile2_crc


def data_id(frame_id: int, counter: int) -> int:
    """The Data ID of ``frame_id`` for alive-counter value ``counter`` (DataIDList[counter])."""
    return (frame_id + 17 * (counter & 0xF)) & 0xFF


class E2EProtector:
    """Sender side: stamps counter and CRC into payloads, one counter per frame ID."""

    def __init__(self) -> None:
        self._counter: dict[int, int] = {}

    def protect(self, frame_id: int, payload: bytes) -> bytes:
        counter = self._counter.get(frame_id, 0)
        self._counter[frame_id] = (counter + 1) & 0xF
        data = bytearray(payload)
        data[1] = (data[1] & 0xF0) | counter
        data[0] = compute_profile2_crc(bytes(data), data_id(frame_id, counter))
        return bytes(data)


@dataclass
class E2EStats:
    """What the receiver saw: good frames, CRC errors, repeated frames, lost frames (counter gaps)."""

    ok: int = 0
    crc_errors: int = 0
    repeated: int = 0
    lost: int = 0
    last_counter: dict[int, int] = field(default_factory=dict)


class E2EChecker:
    """Receiver side: checks CRC and counter; a frame with a bad CRC is rejected, a repeat is ignored."""

    MAX_DELTA = 15

    def __init__(self) -> None:
        self.stats = E2EStats()

    def check(self, frame_id: int, payload: bytes) -> bool:
        """True when the frame may be used."""
        if len(payload) < 2:
            self.stats.crc_errors += 1
            return False
        counter = payload[1] & 0xF
        if compute_profile2_crc(payload, data_id(frame_id, counter)) != payload[0]:
            self.stats.crc_errors += 1
            return False
        last = self.stats.last_counter.get(frame_id)
        self.stats.last_counter[frame_id] = counter
        if last is not None:
            delta = (counter - last) & 0xF
            if delta == 0:
                self.stats.repeated += 1
                return False
            self.stats.lost += delta - 1
        self.stats.ok += 1
        return True
