"""The odometry motion model of gmapping: sampling particle poses from an odometry increment.

The noise formulas are gmapping's code's (MotionModel::drawFromMotion), where srt and str are the
other way round from the ROS wiki's description: a launch file tuned against gmapping means the
same here (docs/slam.md).
"""

from __future__ import annotations

import numpy as np


def wrap_angle(a):
    """Angles into [-pi, pi)."""
    return (np.asarray(a) + np.pi) % (2.0 * np.pi) - np.pi


def relative_motion(new, old) -> np.ndarray:
    """The motion from pose `old` to pose `new` expressed in `old`'s frame (old^-1 * new)."""
    new, old = np.asarray(new, float), np.asarray(old, float)
    c, s = np.cos(old[..., 2]), np.sin(old[..., 2])
    dx, dy = new[..., 0] - old[..., 0], new[..., 1] - old[..., 1]
    return np.stack([c * dx + s * dy, -s * dx + c * dy, wrap_angle(new[..., 2] - old[..., 2])], axis=-1)


def compose(pose, delta) -> np.ndarray:
    """pose * delta: apply a motion given in the pose's frame (rows broadcast)."""
    pose, delta = np.asarray(pose, float), np.asarray(delta, float)
    c, s = np.cos(pose[..., 2]), np.sin(pose[..., 2])
    return np.stack(
        [
            pose[..., 0] + c * delta[..., 0] - s * delta[..., 1],
            pose[..., 1] + s * delta[..., 0] + c * delta[..., 1],
            wrap_angle(pose[..., 2] + delta[..., 2]),
        ],
        axis=-1,
    )


def noise_sigmas(delta, srr: float, srt: float, str_: float, stt: float) -> np.ndarray:
    """Standard deviations (x, y, theta) of the noise added to a relative motion `delta`."""
    dx, dy, dth = (np.abs(np.asarray(delta, float)[..., i]) for i in range(3))
    sxy = 0.3 * srr
    return np.stack(
        [
            srr * dx + str_ * dth + sxy * dy,
            srr * dy + str_ * dth + sxy * dx,
            stt * dth + srt * np.hypot(dx, dy),
        ],
        axis=-1,
    )


def noisy_motion(
    delta, srr: float, srt: float, str_: float, stt: float, rng: np.random.Generator, n: int | None = None
) -> np.ndarray:
    """`n` noisy copies (or one, n=None) of the relative motion `delta`."""
    delta = np.asarray(delta, float)
    sig = noise_sigmas(delta, srr, srt, str_, stt)
    shape = (3,) if n is None else (n, 3)
    out = delta + sig * rng.standard_normal(shape)
    out[..., 2] = wrap_angle(out[..., 2])
    return out


def sample_motion(
    poses, odom_new, odom_old, srr: float, srt: float, str_: float, stt: float, rng: np.random.Generator
) -> np.ndarray:
    """Every particle moved by the odometry increment odom_old -> odom_new, each with its own
    noise draw (the particles' proposal before scan matching)."""
    poses = np.asarray(poses, float)
    delta = relative_motion(odom_new, odom_old)
    return compose(poses, noisy_motion(delta, srr, srt, str_, stt, rng, len(poses)))
