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


def figures(summary: dict, plt) -> dict:
    """File name → matplotlib Figure (not yet saved)."""
    out = {}
    names = summary.get("estimators", [])
    ours, theirs = _split(names)
    if "snr" in summary:
        s = summary["snr"]
        x = s["snr_db"]
        fig, axes = plt.subplots(1, 2, figsize=(13, 5), sharey=True, constrained_layout=True)
        for ax, group in zip(axes, (ours, theirs)):
            for n in group:
                _curve(ax, x, [c["p"] for c in s["metrics"][n]], n)
            ax.set_xlabel("SNR per element, dB")
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=7)
        axes[0].set_ylabel("P(correct number of targets)")
        fig.suptitle(f"seed 001 eq. 11, one target at {s['azimuth_deg']:g}°")
        out["montecarlo_p_correct.png"] = fig
        for key, fname, label in (("rmse_deg", "montecarlo_rmse.png", "RMSE (eq. 12), °"),
                                  ("bias_deg", "montecarlo_bias.png", "bias (eq. 13), °")):
            fig, axes = plt.subplots(1, 2, figsize=(13, 5), sharey=True, constrained_layout=True)
            for ax, group in zip(axes, (ours, theirs)):
                for n in group:
                    _curve(ax, x, [c[key] for c in s["metrics"][n]], n)
                if key == "rmse_deg":
                    for k, style in (("srr1", ":"), ("srr2", "--"), ("both", "-")):
                        ax.plot(x, s["crb_deg"][k], color="black", linestyle=style, linewidth=1.0,
                                label=f"CRB {k}")
                    ax.axhline(0.1, color="grey", linewidth=0.8)
                ax.set_yscale("log")
                ax.set_xlabel("SNR per element, dB")
                ax.grid(True, which="both", alpha=0.3)
                ax.legend(fontsize=7)
            axes[0].set_ylabel(label)
            fig.suptitle(f"seed 001, one target at {s['azimuth_deg']:g}°; shown where p > 0.8")
            out[fname] = fig
    if "resolution" in summary:
        r = summary["resolution"]
        fig, axes = plt.subplots(1, 2, figsize=(13, 5), sharey=True, constrained_layout=True)
        for ax, group in zip(axes, (ours, theirs)):
            for n in group:
                _curve(ax, r["separation_deg"], r["probability"][n], n)
            ax.set_xlabel("separation, °")
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=7)
        axes[0].set_ylabel("P(resolved)")
        fig.suptitle(f"two targets around {r['centre_deg']:g}° at {r['snr_db']:g} dB")
        out["montecarlo_resolution.png"] = fig
    return out
