"""2D ray casting of a fan of laser beams against segments and circles (pure numpy + numba).

Per beam, the distance to the nearest intersection ahead of the origin, +inf for none. `cast` is
compiled with angular culling (each shape against the beams inside the angle it subtends), so the
work grows with the actual crossings rather than beams x shapes; tests/support/raycast_reference.py
is its oracle.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from twil_control.errors import InputError

_TWO_PI = 2.0 * math.pi
_EPS = 1e-12


def _as_scene(segments, circles) -> tuple[np.ndarray, np.ndarray]:
    segs = np.ascontiguousarray(np.asarray(segments, dtype=np.float64).reshape(-1, 4))
    circ = np.ascontiguousarray(np.asarray(circles, dtype=np.float64).reshape(-1, 3))
    return segs, circ


def cast(
    x: float, y: float, yaw: float, angle_min: float, angle_increment: float, samples: int, segments, circles
) -> np.ndarray:
    """Ranges (float64, +inf for no hit) of a uniform fan of beams; see the module docstring."""
    if samples < 1 or not angle_increment > 0 or samples * angle_increment > _TWO_PI + angle_increment + 1e-4:
        raise InputError(
            f"a fan needs samples >= 1 and 0 < angle_increment with at most one turn "
            f"(got samples {samples}, angle_increment {angle_increment})"
        )
    segs, circ = _as_scene(segments, circles)
    out = np.full(samples, np.inf)
    _cast_culled(float(x), float(y), float(yaw), float(angle_min), float(angle_increment), segs, circ, out)
    return out


@njit(cache=True)
def _beam_range(i0, i1, n):
    return max(i0, 0), min(i1, n - 1)


@njit(cache=True)
def _ray_segment(ox, oy, dx, dy, ax, ay, bx, by):
    ex, ey = bx - ax, by - ay
    denom = dx * ey - dy * ex
    if abs(denom) < _EPS:
        return math.inf  # parallel: a grazing beam sees the end segments
    wx, wy = ax - ox, ay - oy
    t = (wx * ey - wy * ex) / denom
    s = (wx * dy - wy * dx) / denom
    if t > 0.0 and 0.0 <= s <= 1.0:
        return t
    return math.inf


@njit(cache=True)
def _ray_circle(ox, oy, dx, dy, cx, cy, r):
    fx, fy = ox - cx, oy - cy
    b = fx * dx + fy * dy
    disc = b * b - (fx * fx + fy * fy - r * r)
    if disc < 0.0:
        return math.inf
    sq = math.sqrt(disc)
    t = -b - sq
    if t > 0.0:
        return t
    t = -b + sq  # origin inside the circle: its far side
    return t if t > 0.0 else math.inf


@njit(cache=True)
def _beams_in(lo, hi, angle_min, inc, n):
    """Index ranges of the beams whose angles fall in [lo, hi] (radians, width <= 2 pi), as two
    (start, stop) pairs (the interval and its copy one turn down), one beam of margin each side."""
    lo_n = lo - _TWO_PI * math.floor((lo - angle_min) / _TWO_PI)  # into [angle_min, +2 pi)
    hi_n = lo_n + (hi - lo)
    a0, a1 = _beam_range(
        int(math.floor((lo_n - angle_min) / inc)) - 1, int(math.ceil((hi_n - angle_min) / inc)) + 1, n
    )
    b0, b1 = _beam_range(
        int(math.floor((lo_n - _TWO_PI - angle_min) / inc)) - 1,
        int(math.ceil((hi_n - _TWO_PI - angle_min) / inc)) + 1,
        n,
    )
    return a0, a1, b0, b1


@njit(cache=True)
def _cast_culled(ox, oy, yaw, angle_min, inc, segs, circ, out):
    n = out.shape[0]
    dxs = np.empty(n)
    dys = np.empty(n)
    for i in range(n):
        a = yaw + angle_min + i * inc
        dxs[i] = math.cos(a)
        dys[i] = math.sin(a)
    for k in range(segs.shape[0]):
        ax, ay, bx, by = segs[k, 0], segs[k, 1], segs[k, 2], segs[k, 3]
        # Does the segment pass (nearly) through the origin? Then every beam may meet it.
        ex, ey = bx - ax, by - ay
        ll = ex * ex + ey * ey
        s = 0.0 if ll == 0.0 else min(1.0, max(0.0, ((ox - ax) * ex + (oy - ay) * ey) / ll))
        px, py = ax + s * ex - ox, ay + s * ey - oy
        if px * px + py * py < 1e-18:
            a0, a1, b0, b1 = 0, n - 1, 0, -1
        else:
            pa = math.atan2(ay - oy, ax - ox) - yaw
            delta = math.atan2(by - oy, bx - ox) - yaw - pa
            delta -= _TWO_PI * math.floor((delta + math.pi) / _TWO_PI)  # into [-pi, pi)
            lo, hi = (pa, pa + delta) if delta >= 0.0 else (pa + delta, pa)
            a0, a1, b0, b1 = _beams_in(lo, hi, angle_min, inc, n)
        for i in range(a0, a1 + 1):
            t = _ray_segment(ox, oy, dxs[i], dys[i], ax, ay, bx, by)
            if t < out[i]:
                out[i] = t
        for i in range(b0, b1 + 1):
            t = _ray_segment(ox, oy, dxs[i], dys[i], ax, ay, bx, by)
            if t < out[i]:
                out[i] = t
    for k in range(circ.shape[0]):
        cx, cy, r = circ[k, 0], circ[k, 1], circ[k, 2]
        dist = math.hypot(cx - ox, cy - oy)
        if dist <= r:
            a0, a1, b0, b1 = 0, n - 1, 0, -1
        else:
            centre = math.atan2(cy - oy, cx - ox) - yaw
            half = math.asin(r / dist)
            a0, a1, b0, b1 = _beams_in(centre - half, centre + half, angle_min, inc, n)
        for i in range(a0, a1 + 1):
            t = _ray_circle(ox, oy, dxs[i], dys[i], cx, cy, r)
            if t < out[i]:
                out[i] = t
        for i in range(b0, b1 + 1):
            t = _ray_circle(ox, oy, dxs[i], dys[i], cx, cy, r)
            if t < out[i]:
                out[i] = t
