"""Forward collision warning (ISO 15623; NHTSA FCW confirmation tests; DESIGN §7).

Time to collision that accounts for the lead's deceleration (and for the lead
coming to a stop first), and the deceleration the ego needs to avoid the
collision. The warning rises when TTC ≤ ``ttc_warn_s`` or the required
deceleration exceeds ``decel_warn_mps2`` for ``on_cycles`` cycles, and falls
only when both have been clear by a margin for ``off_cycles`` cycles
(hysteresis). Only the in-path target counts, so vehicles in other lanes and
roadside objects stay silent.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from radarnode import validate

LEVEL_NONE, LEVEL_PREWARNING, LEVEL_WARNING = 0, 1, 2


def time_to_collision(gap_m: float, ego_speed_mps: float, lead_speed_mps: float, ego_accel_mps2: float = 0.0,
                      lead_accel_mps2: float = 0.0) -> float:
    """Seconds until the ego reaches the lead under constant accelerations; a lead that brakes stops and stays.

    ``inf`` when they never meet.
    """
    if gap_m <= 0:
        return 0.0
    t_stop = lead_speed_mps / -lead_accel_mps2 if lead_accel_mps2 < 0 and lead_speed_mps > 0 else math.inf
    t = _first_root(gap_m, lead_speed_mps - ego_speed_mps, lead_accel_mps2 - ego_accel_mps2)
    if t <= t_stop:
        return t
    # the lead stops first, at gap + v²/(2|a|) ahead of the ego's start
    stop_gap = gap_m + lead_speed_mps ** 2 / (2.0 * -lead_accel_mps2)
    return _first_root(stop_gap, -ego_speed_mps, -ego_accel_mps2)


def _first_root(d: float, v: float, a: float) -> float:
    """Smallest t > 0 with d + v·t + a·t²/2 = 0 (the gap closes)."""
    if abs(a) < 1e-9:
        return d / -v if v < 0 else math.inf
    disc = v * v - 2.0 * a * d
    if disc < 0:
        return math.inf
    roots = [(-v - math.sqrt(disc)) / a, (-v + math.sqrt(disc)) / a]
    pos = [r for r in roots if r > 1e-9]
    return min(pos) if pos else math.inf


def required_deceleration(gap_m: float, ego_speed_mps: float, lead_speed_mps: float,
                          lead_accel_mps2: float = 0.0) -> float:
    """Constant ego deceleration (m/s², negative) that just avoids the collision; 0 when none is needed."""
    if lead_accel_mps2 < 0 and lead_speed_mps > 0:
        # the lead stops: stop behind its stopping point, unless matching its speed earlier suffices
        stop_gap = gap_m + lead_speed_mps ** 2 / (2.0 * -lead_accel_mps2)
        a_stop = -ego_speed_mps ** 2 / (2.0 * max(stop_gap, 0.1))
        return min(0.0, a_stop)
    closing = ego_speed_mps - lead_speed_mps
    if closing <= 0:
        return 0.0
    return min(0.0, lead_accel_mps2 - closing ** 2 / (2.0 * max(gap_m, 0.1)))


@dataclass(frozen=True)
class FcwSettings:
    ttc_warn_s: float = 2.8
    ttc_prewarn_s: float = 4.0
    decel_warn_mps2: float = 4.0
    on_cycles: int = 2
    off_cycles: int = 10
    #: above this ego speed a stationary object never seen moving draws no warning (radarnode.consumer.overhead)
    stationary_max_speed_mps: float = 27.8

    def __post_init__(self) -> None:
        validate.number("ttc_warn_s", self.ttc_warn_s, lo=0.5, hi=10.0)
        validate.number("ttc_prewarn_s", self.ttc_prewarn_s, lo=self.ttc_warn_s, hi=15.0)
        validate.number("decel_warn_mps2", self.decel_warn_mps2, lo=1.0, hi=10.0)
        validate.integer("on_cycles", self.on_cycles, lo=1, hi=20)
        validate.integer("off_cycles", self.off_cycles, lo=1, hi=100)
        validate.number("stationary_max_speed_mps", self.stationary_max_speed_mps, lo=0.0, hi=70.0)


class Fcw:
    """Warning level with hysteresis; :meth:`step` once per cycle."""

    def __init__(self, settings: FcwSettings = FcwSettings()) -> None:
        self.settings = settings
        self.level = LEVEL_NONE
        self._on = 0
        self._off = 0
        self.ttc_s = math.inf
        self.required_decel_mps2 = 0.0

    def step(self, gap_m: float | None, ego_speed_mps: float, lead_speed_mps: float, ego_accel_mps2: float,
             lead_accel_mps2: float) -> int:
        s = self.settings
        if gap_m is None:
            self.ttc_s, self.required_decel_mps2 = math.inf, 0.0
        else:
            self.ttc_s = time_to_collision(gap_m, ego_speed_mps, lead_speed_mps, ego_accel_mps2, lead_accel_mps2)
            self.required_decel_mps2 = required_deceleration(gap_m, ego_speed_mps, lead_speed_mps, lead_accel_mps2)
        danger = self.ttc_s <= s.ttc_warn_s or self.required_decel_mps2 <= -s.decel_warn_mps2
        clear = self.ttc_s > s.ttc_warn_s + 1.0 and self.required_decel_mps2 > -(s.decel_warn_mps2 - 1.0)
        self._on = self._on + 1 if danger else 0
        self._off = self._off + 1 if clear else 0
        if self.level < LEVEL_WARNING and self._on >= s.on_cycles:
            self.level = LEVEL_WARNING
        elif self.level == LEVEL_WARNING and self._off >= s.off_cycles:
            self.level = LEVEL_NONE
        if self.level != LEVEL_WARNING:
            self.level = LEVEL_PREWARNING if self.ttc_s <= s.ttc_prewarn_s else LEVEL_NONE
        return self.level
