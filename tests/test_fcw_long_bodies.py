"""FCW's cleared-path rule judges a body by all its pieces (radarnode/consumer/ecu.py, ``body_extent`` and
``body_clears``): a long vehicle crossing is several tracks at the detection and signal levels, each reported 5–9 m
long, and its front pieces cleared the path on their own extent while its tail was still to come (an independent
tester: the ego hit a 16.5-m truck's rear part unwarned in 6 of 8 seeds at the detection level)."""
import numpy as np
import pytest

from helpers import scenario
from radarnode.consumer.ecu import (CLEAR_BODY_DEPTH_M, CLEAR_BODY_GAP_M, CLEAR_BODY_SPEED_MPS, body_clears,
                                    body_extent)

#: two pieces crossing to the right (negative across) at 15 m/s, 20 m ahead: the front one at −3 m from the centre
#: line, the trailing one ``gap`` behind it
W = -15.0


def _pair(gap=4.5, dw=0.0, dalong=0.0, dahead=0.0):
    offset = np.array([-3.0, -3.0 + gap])
    across = np.array([W, W + dw])
    along = np.array([0.0, dalong])
    ahead = np.array([20.0, 20.0 + dahead])
    return offset, across, along, ahead


def test_a_piece_does_not_clear_while_a_piece_trailing_it_has_not():
    offset, across, along, ahead = _pair()
    assert list(body_clears(np.array([True, False]), offset, across, along, ahead)) == [False, False]
    assert list(body_clears(np.array([True, True]), offset, across, along, ahead)) == [True, True]
    # the trailing piece is not held back by a piece ahead of it that has not cleared
    assert list(body_clears(np.array([False, True]), offset, across, along, ahead)) == [False, True]


@pytest.mark.parametrize("factor, joined", [(0.99, True), (1.0, True), (1.01, False), (2.0, False)])
@pytest.mark.parametrize("what", ["speed", "along", "depth", "gap"])
def test_pieces_are_one_body_only_within_each_limit(factor, joined, what):
    """Just below and at each limit one body, just above and at twice it two (the trailing piece uncleared holds the
    front one back only when they are one body)."""
    kw = {"speed": {"dw": factor * CLEAR_BODY_SPEED_MPS}, "along": {"dalong": factor * CLEAR_BODY_SPEED_MPS},
          "depth": {"dahead": factor * CLEAR_BODY_DEPTH_M}, "gap": {"gap": factor * CLEAR_BODY_GAP_M}}[what]
    offset, across, along, ahead = _pair(**kw)
    front_clears = body_clears(np.array([True, False]), offset, across, along, ahead)[0]
    assert front_clears == (not joined)


def test_pieces_moving_opposite_ways_or_standing_are_not_one_body():
    offset, across, along, ahead = _pair()
    assert body_clears(np.array([True, False]), offset, np.array([W, -W]), along, ahead)[0]
    assert body_clears(np.array([True, False]), offset, np.array([W, 0.0]), along, ahead)[0]


def test_a_piece_extent_is_at_least_its_body_span_plus_its_largest_piece():
    offset, across, along, ahead = _pair(gap=4.5)
    extent = body_extent(np.array([5.0, 5.6]), offset, across, along, ahead)
    assert np.allclose(extent, [4.5 + 5.6, 4.5 + 5.6])
    # a piece alone keeps its own, and so do pieces of two bodies
    assert np.allclose(body_extent(np.array([5.0]), offset[:1], across[:1], along[:1], ahead[:1]), [5.0])
    far = _pair(gap=2.0 * CLEAR_BODY_GAP_M)
    assert np.allclose(body_extent(np.array([5.0, 5.6]), *far), [5.0, 5.6])


@pytest.mark.parametrize("seed", [2, 3, 4, 5])
def test_a_long_truck_crossing_into_the_ego_is_warned_for_at_the_detection_level(seed):
    """The tester's scene: a 16.5-m truck crosses from the left at 15 m/s, the ego at 15 m/s (not braking) hits its
    rear part at 4.0 s, 1.2 m of the ego's width. Before the body rule these seeds drew no warning; the code before the
    cleared-path rule (53ccc36) warned at 3.12–3.33 s in them, as now."""
    from radarnode.consumer.evaluate import simulate
    sc = scenario("  - {id: x, class: truck, length_m: 16.5, x_m: 64.95, y_m: 52.05, speed_mps: 15.0, "
                  "heading_deg: -90.0}",
                  ego="{speed_mps: 15.0}", road="{lanes: 2, lane_width_m: 3.5, ego_lane: 0}", duration=4.3,
                  seed=seed, extra="ecu: {acc_enabled: false, expect: {lead: x}}")
    res = simulate(sc, fidelity="detection")
    assert res.collisions.get("x") == pytest.approx(4.0, abs=0.05)
    assert res.warning_time_s is not None and res.warning_time_s <= 3.4
    assert res.warned_for == "x"
