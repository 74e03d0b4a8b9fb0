"""``radarnode image``: the views carry units, the bird's-eye view is to scale and shows the ground truth."""

from __future__ import annotations

from pathlib import Path

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
