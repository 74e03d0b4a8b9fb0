"""``radarnode image``: the views carry units, the bird's-eye view is to scale and shows the ground truth."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"


def test_bird_eye_view_is_to_scale_with_the_ground_truth_beside_the_report():
    pytest.importorskip("matplotlib", reason="radarnode image needs the optional matplotlib")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from radarnode.cli.image import Renderer
    from radarnode.radar.setup import load_scenario

    r = Renderer(load_scenario(SCENARIOS / "point_targets_mimo12.yaml"), 2.5)
    for k in range(5):                                   # the tracker confirms its objects
        frame, bnd = r.step(k * r.scenario.period_s)
    fig = plt.figure(figsize=(22, 6))
    try:
        r.draw(fig, 4 * r.scenario.period_s, frame, bnd)
        rd, ra, bird, persp = [ax for ax in fig.axes if ax.get_title()]
        for ax in (rd, ra, bird, persp):
            assert ax.get_xlabel() and ax.get_ylabel()
            assert any(u in ax.get_xlabel() for u in ("m/s", "°", ", m")) and ", m" in ax.get_ylabel()
        assert bird.get_aspect() == 1.0                 # a metre is a metre both ways
        assert persp.get_aspect() != 1.0                # the perspective view is widened on purpose
        labels = [t.get_text() for t in bird.get_legend().get_texts()]
        assert "ground truth" in labels and "objects" in labels
        # one dashed outline per actor within the view (all eight point reflectors are ahead)
        dashed = [ln for ln in bird.get_lines() if ln.get_linestyle() == "--"]
        assert len(dashed) == int((~r.scene.is_guardrail).sum())
    finally:
        plt.close(fig)


def test_detections_on_the_range_doppler_map_are_within_its_doppler_axis():
    """At 5 s of highway_cut_in the closing speeds exceed the map's ±19 m/s: each detection is drawn at its
    measured (aliased) Doppler, the cell the map shows it in, not its resolved range rate off the map."""
    pytest.importorskip("matplotlib", reason="radarnode image needs the optional matplotlib")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from radarnode.cli.image import Renderer
    from radarnode.radar.setup import load_scenario

    r = Renderer(load_scenario(SCENARIOS / "highway_cut_in.yaml"), 2.5)
    t = 5.0
    frame, bnd = r.step(t)                  # one cycle is enough: the map and detections are of this cycle
    fig = plt.figure(figsize=(22, 6))
    try:
        r.draw(fig, t, frame, bnd)
        rd = next(ax for ax in fig.axes if ax.get_title() == "range–Doppler")
        lo, hi = rd.images[0].get_extent()[:2]
        res = r.preset.speed_resolution_mps
        drawn = rd.collections[0].get_offsets()[:, 0]
        resolved = np.asarray(r.model.info.detections.range_rate_mps)
        assert len(drawn) and (np.abs(resolved) > hi).any()      # some resolved range rates are off the axis
        assert ((drawn >= lo - 1e-9) & (drawn <= hi + res)).all(), (lo, hi, drawn.min(), drawn.max())
        span = (hi - lo) + res
        assert np.allclose(np.mod(drawn - resolved + span / 2, span), span / 2)   # folded by whole spans
    finally:
        plt.close(fig)
