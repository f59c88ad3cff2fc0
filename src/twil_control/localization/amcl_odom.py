"""amcl's odometry motion models (AMCLOdom::UpdateAction): every particle moved by the odometry
increment since the last filter update, each with its own noise draw.

`diff` and `omni` pass alpha-weighted variances where a standard deviation belongs, as amcl's
originals do; the `-corrected` models take their square roots, kept as separate models so tuned
parameters keep their meaning. The formulas: docs/localization.md. Headings are not wrapped, as
in amcl.
"""

from __future__ import annotations

import math

import numpy as np

from twil_control.errors import InputError

MODELS = ("diff", "omni", "diff-corrected", "omni-corrected")


def angle_diff(a: float, b: float) -> float:
    """The shortest signed angle from b to a, in [-pi, pi] (amcl's angle_diff), of two numbers."""
    d = math.atan2(math.sin(a), math.cos(a)) - math.atan2(math.sin(b), math.cos(b))
    if d > math.pi:
        return d - 2 * math.pi
    if d < -math.pi:
        return d + 2 * math.pi
    return d


def wrapped_difference(a: float, b: np.ndarray) -> np.ndarray:
    """angle_diff(a, b) for an array b: a - b into [-pi, pi)."""
    return np.remainder(a - b + math.pi, 2 * math.pi) - math.pi


def _folded(rot: float) -> float:
    """min(|rot - 0|, |rot - pi|): a rotation's distance from straight ahead or straight back."""
    return min(abs(angle_diff(rot, 0.0)), abs(angle_diff(rot, math.pi)))


def diff_increments(delta, odom_yaw_old: float) -> tuple[float, float, float]:
    """(rot1, trans, rot2) of an odom-frame increment, as amcl's diff models split it."""
    dx, dy, dyaw = (float(v) for v in delta)
    trans = math.hypot(dx, dy)
    rot1 = 0.0 if trans < 0.01 else angle_diff(math.atan2(dy, dx), odom_yaw_old)
    rot2 = angle_diff(dyaw, rot1)
    return rot1, trans, rot2


def diff_sigmas(delta, odom_yaw_old: float, alphas, corrected: bool) -> tuple[float, float, float]:
    """The standard deviations amcl draws (rot1, trans, rot2) noise with."""
    a1, a2, a3, a4 = alphas[:4]
    rot1, trans, rot2 = diff_increments(delta, odom_yaw_old)
    r1, r2 = _folded(rot1), _folded(rot2)
    s1 = a1 * r1 * r1 + a2 * trans * trans
    s2 = a3 * trans * trans + a4 * (r1 * r1 + r2 * r2)
    s3 = a1 * r2 * r2 + a2 * trans * trans
    return (math.sqrt(s1), math.sqrt(s2), math.sqrt(s3)) if corrected else (s1, s2, s3)


def omni_sigmas(delta, alphas, corrected: bool) -> tuple[float, float, float]:
    """The standard deviations amcl draws (trans, rot, strafe) noise with."""
    a1, a2, a3, a4, a5 = alphas
    trans2 = float(delta[0]) ** 2 + float(delta[1]) ** 2
    rot2 = float(delta[2]) ** 2
    if corrected:
        return (
            math.sqrt(a3 * trans2 + a4 * rot2),
            math.sqrt(a1 * rot2 + a2 * trans2),
            math.sqrt(a4 * rot2 + a5 * trans2),
        )
    return (a3 * trans2 + a1 * rot2, a4 * rot2 + a2 * trans2, a1 * rot2 + a5 * trans2)


def sample_motion(poses: np.ndarray, model: str, delta, odom_pose, alphas, rng: np.random.Generator) -> None:
    """Move `poses` ((n, 3), in place) by the increment `delta` under `model` (MODELS)."""
    n = len(poses)
    if n == 0:
        return
    delta = np.asarray(delta, dtype=float)
    old_yaw = float(odom_pose[2]) - float(delta[2])
    noise = rng.standard_normal((n, 3))
    if model in ("diff", "diff-corrected"):
        rot1, trans, rot2 = diff_increments(delta, old_yaw)
        s1, st, s2 = diff_sigmas(delta, old_yaw, alphas, model == "diff-corrected")
        rot1_hat = wrapped_difference(rot1, s1 * noise[:, 0])
        trans_hat = trans - st * noise[:, 1]
        rot2_hat = wrapped_difference(rot2, s2 * noise[:, 2])
        heading = poses[:, 2] + rot1_hat
        poses[:, 0] += trans_hat * np.cos(heading)
        poses[:, 1] += trans_hat * np.sin(heading)
        poses[:, 2] += rot1_hat + rot2_hat
    elif model in ("omni", "omni-corrected"):
        trans = math.hypot(delta[0], delta[1])
        st, sr, ss = omni_sigmas(delta, alphas, model == "omni-corrected")
        bearing = angle_diff(math.atan2(delta[1], delta[0]), old_yaw) + poses[:, 2]
        cb, sb = np.cos(bearing), np.sin(bearing)
        trans_hat = trans + st * noise[:, 0]
        strafe_hat = ss * noise[:, 2]
        poses[:, 0] += trans_hat * cb + strafe_hat * sb
        poses[:, 1] += trans_hat * sb - strafe_hat * cb
        poses[:, 2] += delta[2] + sr * noise[:, 1]
    else:
        raise InputError(f"odometry model {model!r} is not one of {', '.join(MODELS)}")
