"""Vectorised DBC encoding: many frames of one message in one numpy pass.

cantools encodes one frame per call (about 5 µs each here, 30 µs with
``strict=True``); a 100-object cycle with quality and extended information is
300 frames. :class:`MessageCodec` compiles a cantools message once into shifts
and masks and encodes all objects of a group at once. Values outside a
signal's [minimum, maximum] are saturated to the range first and counted per
signal (cantools would raise on a raw overflow). The byte layout is checked
against cantools in the tests, for every message of the DBC.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import numpy as np

from radarnode.errors import WireError

_SCALARS = (int, float, np.generic)     # what :meth:`MessageCodec.encode` encodes as one frame in Python numbers
_NUMBERS = (int, float, np.integer, np.floating, np.bool_)      # a column's one value, for every frame (_encode_few)
#: at most this many values (frames × signals) are encoded frame by frame in Python numbers (_encode_few): numpy's
#: dozen calls on a group's arrays cost about 16–20 µs whatever its size, a frame of 7 signals in Python about 4 µs
FEW_VALUES = 21


@dataclass(frozen=True)
class _Field:
    name: str
    shift: int
    bits: int
    scale: float
    offset: float
    minimum: float
    maximum: float


class MessageCodec:
    """Encoder/decoder of one (non-multiplexed, Motorola) message, vectorised over frames.

    Parameters
    ----------
    message : cantools.database.can.Message
    saturated : collections.Counter, optional
        Shared counter of saturated values, keyed by signal name.
    """

    def __init__(self, message, saturated: Counter | None = None) -> None:
        if message.is_multiplexed():
            raise WireError(f"message {message.name}: multiplexed messages are encoded with cantools, not here")
        self.name = message.name
        self.frame_id = message.frame_id
        self.length = message.length
        self.saturated = saturated if saturated is not None else Counter()
        fields = []
        for sig in message.signals:
            if sig.byte_order != "big_endian" or sig.is_signed or sig.is_float:
                raise WireError(f"signal {sig.name} of {message.name}: only unsigned Motorola integer signals "
                                f"are supported (got {sig.byte_order}, signed={sig.is_signed})")
            msb = (sig.start // 8) * 8 + (7 - sig.start % 8)   # bit index from the left of the 64-bit word
            shift = 63 - (msb + sig.length - 1)
            raw_max = (1 << sig.length) - 1
            lo = sig.minimum if sig.minimum is not None else sig.offset
            hi = sig.maximum if sig.maximum is not None else sig.offset + sig.scale * raw_max
            if round((hi - sig.offset) / sig.scale) > raw_max or round((lo - sig.offset) / sig.scale) < 0:
                raise WireError(f"signal {sig.name} of {message.name}: range [{lo}, {hi}] does not fit "
                                f"{sig.length} bits with scale {sig.scale} and offset {sig.offset}")
            fields.append(_Field(sig.name, shift, sig.length, float(sig.scale), float(sig.offset), float(lo),
                                 float(hi)))
        self.fields = tuple(fields)
        self.signal_names = tuple(f.name for f in fields)
        # the fields as columns, so that a whole group is encoded in a few array operations
        col = lambda attr: np.array([getattr(f, attr) for f in fields], dtype=np.float64)[:, None]
        self._lo, self._hi, self._scale, self._offset = col("minimum"), col("maximum"), col("scale"), col("offset")
        self._tol = 1e-6 * self._scale
        self._mask = np.array([(1 << f.bits) - 1 for f in fields], dtype=np.uint64)[:, None]
        self._shift = np.array([f.shift for f in fields], dtype=np.uint64)[:, None]
        # each field for one frame in Python numbers (:meth:`_encode_one`): its limits, where saturation starts (a
        # millionth of an LSB beyond them), offset, scale, mask and shift
        self._scalar = tuple((f.name, f.minimum, f.maximum, f.minimum - 1e-6 * f.scale, f.maximum + 1e-6 * f.scale,
                              f.offset, f.scale, (1 << f.bits) - 1, f.shift) for f in fields)

    def encode(self, values: dict[str, np.ndarray | float]) -> np.ndarray:
        """Encode physical values to frame payloads.

        Parameters
        ----------
        values : dict
            Signal name -> scalar or array of shape (n,); every signal of the
            message must be present.

        Returns
        -------
        numpy.ndarray of uint8, shape (n, length)
        """
        try:
            cols = [values[name] for name in self.signal_names]
        except KeyError:
            missing = [name for name in self.signal_names if name not in values]
            raise WireError(f"message {self.name}: no value for signal(s) {', '.join(missing)}") from None
        for c in cols:
            if not (isinstance(c, _SCALARS) or (isinstance(c, np.ndarray) and c.ndim == 0)):
                break
        else:
            return self._encode_one(cols)
        n = max([np.size(c) for c in cols] + [1])
        if n * len(cols) <= FEW_VALUES:
            few = self._encode_few(cols, n)
            if few is not None:
                return few
        v = np.empty((len(cols), n), dtype=np.float64)
        for row, c in zip(v, cols):                       # one row per signal (a dozen), not per frame
            row[...] = c
        if np.isnan(v).any():
            f = self.fields[int(np.flatnonzero(np.isnan(v).any(axis=1))[0])]
            raise WireError(f"message {self.name}: signal {f.name} got NaN; expected a number in "
                            f"[{f.minimum:g}, {f.maximum:g}]")
        # a value within a millionth of an LSB of a limit is the limit (float round-off), not saturation
        out = (v < self._lo - self._tol) | (v > self._hi + self._tol)
        if out.any():
            for k in np.flatnonzero(out.any(axis=1)):
                self.saturated[self.fields[k].name] += int(out[k].sum())
        np.clip(v, self._lo, self._hi, out=v)
        # same arithmetic as cantools: round((value - offset) / scale), ties to even
        v -= self._offset
        v /= self._scale
        raw = np.rint(v).astype(np.uint64)
        raw &= self._mask
        raw <<= self._shift
        word = np.bitwise_or.reduce(raw, axis=0)
        return word.astype(">u8").view(np.uint8).reshape(n, 8)[:, : self.length]

    def _encode_few(self, cols: list, n: int) -> np.ndarray | None:
        """:meth:`encode` of a few frames (a cycle's one or two objects) one by one in Python numbers
        (:meth:`encode_values`, the same arithmetic, bit for bit) instead of a dozen array operations at numpy's
        per-call cost; None — encode's own arrays then — where a column is not a number or a 1-D numeric array of
        the n values, or a value is NaN (so that the error names the field encode's check names)."""
        lists = []
        for c in cols:
            if type(c) is np.ndarray:
                if c.ndim == 1 and c.size == n and c.dtype.kind in "fiub":
                    lists.append(c.tolist())
                elif c.ndim == 0 and c.dtype.kind in "fiub":
                    lists.append([c.item()] * n)
                else:
                    return None
            elif isinstance(c, _NUMBERS):
                lists.append([c] * n)
            else:
                return None
        rows = list(zip(*lists))
        for row in rows:
            for x in row:
                if x != x:
                    return None
        counted: Counter = Counter()
        payload = bytearray().join([self._frame(row, counted) for row in rows])
        for name in self.signal_names:        # the counts in encode's order: field by field, not frame by frame
            if counted[name]:
                self.saturated[name] += counted[name]
        return np.frombuffer(payload, dtype=np.uint8).reshape(n, self.length)

    def _encode_one(self, cols: list) -> np.ndarray:
        """One frame from scalars (a header, a status, a boundary: several a cycle), in Python numbers: the same
        arithmetic as :meth:`encode`'s columns — clip, minus offset, over scale, round half to even — without
        numpy's per-call cost for a dozen one-element arrays."""
        return np.frombuffer(bytearray(self.encode_values(cols)), dtype=np.uint8).reshape(1, self.length)

    def encode_values(self, values) -> bytes:
        """One frame's payload from its signals' physical values in the message's signal order
        (:attr:`signal_names`), as :meth:`encode` makes it for scalars (saturation counted, NaN refused)."""
        return self._frame(values, self.saturated)

    def _frame(self, values, saturated: Counter) -> bytes:
        """:meth:`encode_values`, its saturated values counted in ``saturated``."""
        values = [float(c) for c in values]
        if len(values) != len(self.fields):
            raise WireError(f"message {self.name}: {len(values)} values for {len(self.fields)} signals")
        for (name, lo, hi, *_), v in zip(self._scalar, values):     # (nothing counted for a frame refused)
            if v != v:
                raise WireError(f"message {self.name}: signal {name} got NaN; expected a number in [{lo:g}, {hi:g}]")
        word = 0
        for (name, lo, hi, below, above, offset, scale, mask, shift), v in zip(self._scalar, values):
            if v < below or v > above:
                saturated[name] += 1
            v = lo if v < lo else hi if v > hi else v
            word |= (round((v - offset) / scale) & mask) << shift
        return word.to_bytes(8, "big")[: self.length]

    def as_sent(self, name: str, value: np.ndarray) -> np.ndarray:
        """Signal ``name``'s physical values as a receiver decodes them: clipped to its range and rounded to its
        grid, the arithmetic of :meth:`encode` (without counting saturation) and of the decoder."""
        f = self.fields[self.signal_names.index(name)]
        raw = np.rint((np.clip(np.asarray(value, dtype=np.float64), f.minimum, f.maximum) - f.offset) / f.scale)
        return raw * f.scale + f.offset

    def decode(self, payload: np.ndarray) -> dict[str, np.ndarray]:
        """Decode payloads of shape (n, length) (uint8) back to physical values."""
        payload = np.asarray(payload, dtype=np.uint8)
        buf = np.zeros((payload.shape[0], 8), dtype=np.uint8)
        buf[:, : payload.shape[1]] = payload
        word = buf.view(">u8").reshape(-1).astype(np.uint64)
        out = {}
        for f in self.fields:
            raw = (word >> np.uint64(f.shift)) & np.uint64((1 << f.bits) - 1)
            out[f.name] = raw.astype(np.float64) * f.scale + f.offset
        return out
