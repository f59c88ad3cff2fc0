"""Pure signal and planar-geometry helpers for the bag analyses (numpy only).

Poses are planar (x, y, yaw) arrays of shape (N, 3); times are float seconds.
"""

from __future__ import annotations

import numpy as np


def wrap(a):
    """Angles to (-pi, pi]."""
    a = np.asarray(a, dtype=float)
    return np.pi - np.mod(np.pi - a, 2 * np.pi)


def yaw_from_quaternion(x, y, z, w):
    """Yaw (rotation about z) of quaternions, REP 103 (ZYX convention)."""
    return np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def compose(a, b):
    """a ⊕ b for planar poses (broadcasts): the pose b given in frame a."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    return np.stack(
        [
            a[..., 0] + c * b[..., 0] - s * b[..., 1],
            a[..., 1] + s * b[..., 0] + c * b[..., 1],
            wrap(a[..., 2] + b[..., 2]),
        ],
        axis=-1,
    )


def inverse(a):
    """⊖a: the pose whose composition with a is the identity."""
    a = np.asarray(a, float)
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    return np.stack(
        [-c * a[..., 0] - s * a[..., 1], s * a[..., 0] - c * a[..., 1], wrap(-a[..., 2])], axis=-1
    )


def interp_poses(t_query, t, poses):
    """Linear interpolation of poses at t_query (yaw unwrapped first), clamped at the ends."""
    t_query = np.asarray(t_query, float)
    yaw = np.unwrap(poses[:, 2])
    return np.stack(
        [
            np.interp(t_query, t, poses[:, 0]),
            np.interp(t_query, t, poses[:, 1]),
            wrap(np.interp(t_query, t, yaw)),
        ],
        axis=-1,
    )


def path_length(x, y) -> float:
    return float(np.sum(np.hypot(np.diff(x), np.diff(y)))) if len(x) > 1 else 0.0


def settle_time(t, ok):
    """The first time from which ok holds to the end of the series; None if it never does
    (or does not hold at the end)."""
    ok = np.asarray(ok, bool)
    if len(ok) == 0 or not ok[-1]:
        return None
    bad = np.nonzero(~ok)[0]
    return float(t[0] if len(bad) == 0 else t[bad[-1] + 1])


def max_rise(v) -> float:
    """Largest increase of a series over its running minimum (0 for a non-increasing one)."""
    v = np.asarray(v, float)
    return float((v - np.minimum.accumulate(v)).max()) if len(v) else 0.0


def rms(v, axis=None):
    v = np.asarray(v, float)
    return np.sqrt(np.mean(v * v, axis=axis))


def align_start(t_a, poses_a, t_b, poses_b):
    """Transform T (planar) that maps frame A onto frame B at the first time both have data:
    T ⊕ pose_a(t0) = pose_b(t0). Used to express odometry (starting at zero in its own frame)
    in the ground truth's world frame."""
    t0 = max(t_a[0], t_b[0])
    pa = interp_poses([t0], t_a, poses_a)[0]
    pb = interp_poses([t0], t_b, poses_b)[0]
    return compose(pb, inverse(pa))
