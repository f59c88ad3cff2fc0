"""The oracle of mapping.raycast.cast: every beam against every shape, vectorised in numpy (no
culling), at any beam angles."""

from __future__ import annotations

import numpy as np

from twil_control.mapping.raycast import _EPS, _as_scene


def cast_numpy(x: float, y: float, yaw: float, angles, segments, circles) -> np.ndarray:
    """Ranges of beams at `angles` (radians from the heading `yaw`): every beam against every
    shape with numpy broadcasting (the oracle)."""
    segs, circ = _as_scene(segments, circles)
    a = yaw + np.asarray(angles, dtype=np.float64)
    dx, dy = np.cos(a)[:, None], np.sin(a)[:, None]
    best = np.full(a.shape, np.inf)
    if len(segs):
        ex, ey = segs[:, 2] - segs[:, 0], segs[:, 3] - segs[:, 1]
        wx, wy = segs[:, 0] - x, segs[:, 1] - y
        denom = dx * ey - dy * ex
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (wx * ey - wy * ex) / denom
            s = (wx * dy - wy * dx) / denom
        hit = (np.abs(denom) >= _EPS) & (t > 0) & (s >= 0) & (s <= 1)
        best = np.minimum(best, np.where(hit, t, np.inf).min(axis=1))
    if len(circ):
        fx, fy, r = x - circ[:, 0], y - circ[:, 1], circ[:, 2]
        b = fx * dx + fy * dy
        disc = b * b - (fx * fx + fy * fy - r * r)
        sq = np.sqrt(np.maximum(disc, 0.0))
        near, far = -b - sq, -b + sq
        t = np.where(near > 0, near, np.where(far > 0, far, np.inf))
        best = np.minimum(best, np.where(disc >= 0, t, np.inf).min(axis=1))
    return best
