"""Pictures of one ``radarnode montecarlo`` run (PNG, matplotlib imported only for ``--plots``).

* ``montecarlo_p_correct.png`` — probability of the correct number of targets against SNR (seed 001 fig. 6);
* ``montecarlo_rmse.png`` — RMSE (eq. 12) against SNR, log scale, with the stochastic Cramér–Rao bound of each
  radar and of both arrays together, and seed 001's 0.1° level (fig. 7a); left: seed 001's estimators, right:
  the subspace estimators;
* ``montecarlo_bias.png`` — bias (eq. 13) against SNR (fig. 7b);
* ``montecarlo_resolution.png`` — probability of resolving two targets against their separation.
"""

from __future__ import annotations

SEED001 = ("lcacm", "lcacm_sine", "lcacm_scan", "circles", "bs_srr1", "bs_srr2", "capon_srr1", "capon_srr2")


def _split(names):
    return [n for n in names if n in SEED001], [n for n in names if n not in SEED001]


def _curve(ax, x, values, name, **kw):
    xs = [a for a, v in zip(x, values) if v is not None]
    ys = [v for v in values if v is not None]
    if xs:
        ax.plot(xs, ys, marker=".", label=name, **kw)


def _panels(plt, groups, x, values_of, xlabel, ylabel, title, extra=None, log=False):
    """Two panels side by side (seed 001's estimators, the subspace ones): one curve per estimator."""
    fig, axes = plt.subplots(1, 2, figsize=(13, 5), sharey=True, constrained_layout=True)
    for ax, group in zip(axes, groups):
        for n in group:
            _curve(ax, x, values_of(n), n)
        if extra is not None:
            extra(ax)
        if log:
            ax.set_yscale("log")
        ax.set_xlabel(xlabel)
        ax.grid(True, which="both" if log else "major", alpha=0.3)
        ax.legend(fontsize=7)
    axes[0].set_ylabel(ylabel)
    fig.suptitle(title)
    return fig


def figures(summary: dict, plt) -> dict:
    """File name → matplotlib Figure (not yet saved)."""
    out = {}
    groups = _split(summary.get("estimators", []))
    if "snr" in summary:
        s = summary["snr"]
        x, snr = s["snr_db"], "SNR per element, dB"

        def crb(ax):
            for k, style in (("srr1", ":"), ("srr2", "--"), ("both", "-")):
                ax.plot(x, s["crb_deg"][k], color="black", linestyle=style, linewidth=1.0, label=f"CRB {k}")
            ax.axhline(0.1, color="grey", linewidth=0.8)

        out["montecarlo_p_correct.png"] = _panels(
            plt, groups, x, lambda n: [c["p"] for c in s["metrics"][n]], snr, "P(correct number of targets)",
            f"seed 001 eq. 11, one target at {s['azimuth_deg']:g}°")
        for key, fname, label in (("rmse_deg", "montecarlo_rmse.png", "RMSE (eq. 12), °"),
                                  ("bias_deg", "montecarlo_bias.png", "bias (eq. 13), °")):
            out[fname] = _panels(plt, groups, x, lambda n, key=key: [c[key] for c in s["metrics"][n]], snr, label,
                                 f"seed 001, one target at {s['azimuth_deg']:g}°; shown where p > 0.8",
                                 extra=crb if key == "rmse_deg" else None, log=True)
    if "resolution" in summary:
        r = summary["resolution"]
        out["montecarlo_resolution.png"] = _panels(
            plt, groups, r["separation_deg"], lambda n: r["probability"][n], "separation, °", "P(resolved)",
            f"two targets around {r['centre_deg']:g}° at {r['snr_db']:g} dB")
    return out
