"""Small scenario builders for tests."""

from __future__ import annotations

from radarnode.radar.setup import parse_scenario


def scenario(actors_yaml: str = "", *, ego: str = "{speed_mps: 20.0}", radar: str = "{preset: ars408_like}",
             road: str = "{lanes: 3, lane_width_m: 3.5, ego_lane: 1}", duration: float = 3.0, seed: int = 1):
    text = f"""
name: test
duration_s: {duration}
seed: {seed}
radar: {radar}
ego: {ego}
road: {road}
actors:
{actors_yaml if actors_yaml.strip() else "  []"}
"""
    if not actors_yaml.strip():
        text = text.replace("actors:\n  []", "actors: []")
    return parse_scenario(text)
