"""Motion models shared by the radar's own tracker and the consumer ECU's: state transition and process noise."""

from __future__ import annotations

import numpy as np

from radarnode.errors import ConfigError


def transition(model: str, dt: float, q: float) -> tuple[np.ndarray, np.ndarray]:
    """State transition F and process noise Q (white acceleration for CV, white jerk for CA), 2-D."""
    if model == "cv":
        f1 = np.array([[1.0, dt], [0.0, 1.0]])
        q1 = q * np.array([[dt ** 4 / 4, dt ** 3 / 2], [dt ** 3 / 2, dt ** 2]])
        order = [0, 2]                                # x, vx ; y, vy
    elif model == "ca":
        f1 = np.array([[1.0, dt, dt * dt / 2], [0.0, 1.0, dt], [0.0, 0.0, 1.0]])
        q1 = q * np.array([[dt ** 5 / 20, dt ** 4 / 8, dt ** 3 / 6], [dt ** 4 / 8, dt ** 3 / 3, dt ** 2 / 2],
                           [dt ** 3 / 6, dt ** 2 / 2, dt]])
        order = [0, 2, 4]
    else:
        raise ConfigError(f"motion model: value {model!r} is not allowed; expected 'cv' or 'ca'")
    n = 2 * len(order)
    f, qq = np.zeros((n, n)), np.zeros((n, n))
    for axis in range(2):
        idx = [o + axis for o in order]
        f[np.ix_(idx, idx)] = f1
        qq[np.ix_(idx, idx)] = q1
    return f, qq
