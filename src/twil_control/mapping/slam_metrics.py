"""SLAM accuracy figures: the relation-based error of Kummerle et al. (2009) and the absolute
trajectory error after a best rigid alignment. Poses are (n, 3) arrays of (x, y, theta), the
estimate and the reference row for row.

Relation error (Kummerle et al., "On measuring the accuracy of SLAM algorithms", Auton. Robots
2009): for a pair (i, j) the estimated relative motion est_i^-1 est_j is compared with the
reference's ref_i^-1 ref_j; the translational error is the distance between the two relative
translations (m), the rotational error the absolute difference of the relative headings (rad).
It does not depend on the global frame, so drift accumulated before i does not count, only the
error of the relation itself.

Pairs:
- consecutive: (k, k + 1) over the evaluated poses;
- loop-closing: pairs far apart in time but close in space according to the reference: index
  gap >= `min_gap` poses and reference positions within `radius` m (defaults 50 poses, 1 m).
  Their relative motions span a loop, so an estimate that failed to close it (doubled walls)
  shows large errors there even when every consecutive relation is good.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .gmapping.motion import relative_motion, wrap_angle


@dataclass
class RelationError:
    pairs: int
    trans_mean: float   # m
    trans_std: float
    rot_mean: float     # deg
    rot_std: float


def relation_errors(est: np.ndarray, ref: np.ndarray, pairs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(translational m, rotational rad) errors of the relations (i, j) in `pairs` (k, 2)."""
    est, ref, pairs = np.asarray(est, float), np.asarray(ref, float), np.asarray(pairs, np.int64)
    if est.shape != ref.shape or est.ndim != 2 or est.shape[1] != 3:
        raise ValueError(f"estimate {est.shape} and reference {ref.shape} must both be (n, 3)")
    i, j = pairs[:, 0], pairs[:, 1]
    d_est = relative_motion(est[j], est[i])
    d_ref = relative_motion(ref[j], ref[i])
    trans = np.hypot(d_est[:, 0] - d_ref[:, 0], d_est[:, 1] - d_ref[:, 1])
    rot = np.abs(wrap_angle(d_est[:, 2] - d_ref[:, 2]))
    return trans, rot


def consecutive_pairs(n: int) -> np.ndarray:
    return np.stack([np.arange(n - 1), np.arange(1, n)], axis=1)


def loop_pairs(ref: np.ndarray, min_gap: int = 50, radius: float = 1.0) -> np.ndarray:
    """Pairs (i, j), j - i >= min_gap, whose reference positions are within `radius` m."""
    ref = np.asarray(ref, float)
    d = np.hypot(ref[:, None, 0] - ref[None, :, 0], ref[:, None, 1] - ref[None, :, 1])
    i, j = np.nonzero(d <= radius)
    keep = j - i >= min_gap
    return np.stack([i[keep], j[keep]], axis=1)


def summarise(est: np.ndarray, ref: np.ndarray, pairs: np.ndarray) -> RelationError:
    if len(pairs) == 0:
        return RelationError(0, float("nan"), float("nan"), float("nan"), float("nan"))
    trans, rot = relation_errors(est, ref, pairs)
    rot = np.degrees(rot)
    return RelationError(len(pairs), float(trans.mean()), float(trans.std()), float(rot.mean()), float(rot.std()))


def align_rigid(est_xy: np.ndarray, ref_xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(R 2x2, t) minimising sum |R est + t - ref|^2 (Kabsch/Umeyama without scale)."""
    est_xy, ref_xy = np.asarray(est_xy, float), np.asarray(ref_xy, float)
    me, mr = est_xy.mean(0), ref_xy.mean(0)
    u, _, vt = np.linalg.svd((ref_xy - mr).T @ (est_xy - me))
    d = np.sign(np.linalg.det(u @ vt))
    rot = u @ np.diag([1.0, d]) @ vt
    return rot, mr - rot @ me


def ate_rmse(est: np.ndarray, ref: np.ndarray) -> float:
    """Root mean square position error (m) after the best rigid alignment of est onto ref."""
    est, ref = np.asarray(est, float), np.asarray(ref, float)
    rot, t = align_rigid(est[:, :2], ref[:, :2])
    err = est[:, :2] @ rot.T + t - ref[:, :2]
    return float(np.sqrt(np.mean(np.sum(err * err, axis=1))))


@dataclass
class SlamReport:
    consecutive: RelationError
    loops: RelationError
    ate_rmse: float


def evaluate(est: np.ndarray, ref: np.ndarray, min_gap: int = 50, radius: float = 1.0) -> SlamReport:
    """Consecutive and loop-closing relation errors and ATE RMSE of one trajectory."""
    return SlamReport(summarise(est, ref, consecutive_pairs(len(ref))),
                      summarise(est, ref, loop_pairs(ref, min_gap, radius)), ate_rmse(est, ref))
