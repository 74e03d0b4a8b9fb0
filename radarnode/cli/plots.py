"""Pictures of one ``radarnode report`` run: what the ECU saw and did over time, with its pass/fail limits.

Five panels over the scenario time, one per quantity, each with its unit on the axis:

1. gap to the ``expect.lead`` actor (m), the ``min_gap_m`` limit and, for ACC, the gap the time-gap setting
   asks for at the ego's speed (± ``gap_tolerance`` from ``gap_settle_s``);
2. relative speed of the lead (m/s, negative when closing);
3. constant-speed TTC (s) with the NHTSA limit ``fcw_ttc_min_s`` and the ECU's warning threshold
   ``fcw_ttc_warn_s``, and the TTC at the warning marked;
4. ego speed (m/s) with the ACC set speed;
5. ego acceleration and the ACC request (m/s²) inside the ISO 15622 band for the ego's speed.

Every panel marks the instants: the lead starts braking (brown), FCW warning (red, shaded while it lasts),
the ego starts braking (deceleration or ACC request beyond 1 m/s², blue), the impact (black). The title says pass or FAIL and why. matplotlib is optional
(``radarnode[image]``); it is imported only when ``--plots`` is given.
"""

from __future__ import annotations

import math

import numpy as np

from radarnode.consumer.acc import iso15622_limits
from radarnode.consumer.fcw import LEVEL_WARNING

BRAKING_MPS2 = -1.0          # the ego brakes when its deceleration goes beyond this
TTC_SHOWN_S = 10.0           # TTC above this is off the scale (TTC is infinite while the gap opens)


def _first(mask: np.ndarray, t: np.ndarray) -> float | None:
    idx = np.flatnonzero(mask)
    return float(t[idx[0]]) if idx.size else None


def instants(result) -> dict[str, float | None]:
    """Times (s) of the lead's and the ego's start of braking, the FCW warning and the impact of one run
    (None: did not happen). The lead's acceleration is the ego's plus the change of the relative speed."""
    tr = result.trace
    t = tr["t"]
    lead_braking = None
    if len(t) > 1:
        with np.errstate(invalid="ignore"):
            lead_accel = np.diff(tr["rel_speed"]) / np.diff(t) + tr["accel"][1:]
            lead_braking = _first(lead_accel < BRAKING_MPS2, t[1:])
    return {"lead braking": lead_braking,
            "FCW warning": result.warning_time_s,
            "braking": _first(np.minimum(tr["accel"], tr["request"]) < BRAKING_MPS2, t),
            "impact": result.impact_time_s}


def report_figure(scenario, result, plt=None):
    """The five-panel figure of one run (``simulate`` result); a matplotlib Figure, not yet saved."""
    if plt is None:
        from radarnode.cli.common import require_matplotlib
        plt = require_matplotlib("report_figure")
    tr, e, spec = result.trace, scenario.ecu.expect, scenario.ecu
    t = tr["t"]
    fig, axes = plt.subplots(5, 1, sharex=True, figsize=(10, 12), constrained_layout=True)
    a_gap, a_rel, a_ttc, a_speed, a_acc = axes
    finite = np.isfinite(tr["gap"])
    gap = np.where(finite, tr["gap"], np.nan)
    a_gap.plot(t, gap, color="k", label=f"gap to {e.lead}" if e.lead else "gap")
    if e.min_gap_m is not None:
        a_gap.axhline(e.min_gap_m, color="r", linestyle="--", label=f"limit: min gap {e.min_gap_m} m")
    if e.gap_settle_s is not None:
        want = spec.time_gap_s * tr["speed"]
        after = t >= e.gap_settle_s
        a_gap.fill_between(t, want * (1 - e.gap_tolerance), want * (1 + e.gap_tolerance), where=after,
                           color="g", alpha=0.2,
                           label=f"limit: time gap {spec.time_gap_s} s ± {e.gap_tolerance:.0%} after {e.gap_settle_s} s")
    a_gap.set_ylabel("gap, m")
    if not finite.any():          # an adjacent-lane or no-lead scenario: say so instead of an empty panel
        for ax in (a_gap, a_rel):
            note = f"actor '{e.lead}' never ahead in the ego lane" if e.lead else "no expect.lead actor"
            ax.text(0.5, 0.5, note, transform=ax.transAxes, ha="center", va="center", color="0.4")
    a_rel.plot(t, tr["rel_speed"], color="k", label="lead − ego")
    a_rel.axhline(0.0, color="0.6", linewidth=0.8)
    a_rel.set_ylabel("relative speed, m/s")
    ttc = np.where(np.isfinite(tr["ttc"]), tr["ttc"], np.nan)
    a_ttc.plot(t, ttc, color="k", label="TTC (constant speed)")
    if e.fcw_ttc_min_s is not None:
        a_ttc.axhline(e.fcw_ttc_min_s, color="r", linestyle="--",
                      label=f"limit: warn at TTC ≥ {e.fcw_ttc_min_s} s")
    a_ttc.axhline(spec.fcw_ttc_warn_s, color="tab:orange", linestyle=":",
                  label=f"ECU warning threshold {spec.fcw_ttc_warn_s} s")
    if result.warning_time_s is not None and result.ttc_at_warning_s is not None \
            and math.isfinite(result.ttc_at_warning_s):
        a_ttc.plot([result.warning_time_s], [min(result.ttc_at_warning_s, TTC_SHOWN_S)], "o", color="r",
                   label=f"TTC at warning {result.ttc_at_warning_s:.2f} s")
    a_ttc.set_ylim(0.0, TTC_SHOWN_S)
    if not np.any(ttc <= TTC_SHOWN_S) and finite.any():
        a_ttc.text(0.5, 0.5, f"TTC above {TTC_SHOWN_S:.0f} s throughout", transform=a_ttc.transAxes, ha="center",
                   va="center", color="0.4")
    a_ttc.set_ylabel("TTC, s")
    a_speed.plot(t, tr["speed"], color="k", label="ego speed")
    if spec.acc_enabled:
        a_speed.axhline(spec.set_speed_mps, color="g", linestyle="--", label=f"ACC set speed {spec.set_speed_mps} m/s")
    a_speed.set_ylabel("ego speed, m/s")
    lo, hi = np.array([iso15622_limits(v)[:2] for v in tr["speed"]]).T if len(t) else (np.array([]), np.array([]))
    a_acc.plot(t, tr["accel"], color="k", label="ego acceleration")
    a_acc.plot(t, tr["request"], color="tab:purple", linestyle="--", label="ACC request")
    if spec.closed_loop:
        a_acc.plot(t, lo, color="r", linestyle="--", label="limit: ISO 15622 deceleration / acceleration")
        a_acc.plot(t, hi, color="r", linestyle="--")
    a_acc.set_ylabel("acceleration, m/s²")
    lo_y, hi_y = a_acc.get_ylim()
    a_acc.set_ylim(min(lo_y, -1.0), max(hi_y, 1.0))       # a flat zero line is not blown up to ±0.05
    a_acc.set_xlabel("time, s")
    warn = tr["warning"] == LEVEL_WARNING
    marks = instants(result)
    colours = {"lead braking": "tab:brown", "FCW warning": "r", "braking": "tab:blue", "impact": "k"}
    for ax in axes:
        if warn.any():
            ax.fill_between(t, 0, 1, where=warn, transform=ax.get_xaxis_transform(), color="r", alpha=0.08,
                            step="post")
        for name, when in marks.items():
            if when is not None:
                ax.axvline(when, color=colours[name], linewidth=1.2, linestyle="-.",
                           label=f"{name} at {when:.2f} s" if ax is a_gap else None)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    if len(t):
        a_acc.set_xlim(float(t[0]), float(t[-1]))
    # as the table and the JUnit file: a scenario whose ecu.expect states no criterion did not pass anything
    verdict = ("nothing to check" if not result.checked else "pass" if result.passed
               else "FAIL: " + "; ".join(result.reasons))
    fig.suptitle(f"{scenario.name}, seed {result.seed}: {verdict}", color="k" if result.passed else "r")
    return fig
