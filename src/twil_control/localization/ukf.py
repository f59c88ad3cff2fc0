"""robot_localization's unscented Kalman filter on the EKF's motion model (Ukf).

Sigma points: the state and the state plus and minus each column of the lower Cholesky factor
of (n + lambda) P, lambda = alpha^2 (n + kappa) - n, n = 15; mean weights lambda / (n + lambda)
and 1 / (2 (n + lambda)), the first covariance weight plus 1 - alpha^2 + beta. Prediction moves
every point through the motion model (ekf.transfer_function), averages the Euler angles on the
circle, and adds Q dt. Correction of the measured subset: K = P_xz (P_zz + R)^-1,
P -= K P_zz K^T, with the sigma points drawn again when a correction follows a correction.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .ekf import measured_indices, transfer_function
from .kalman_state import ANGLES, STATE_SIZE, normalize_angle, wrap_state_angles

_ANGLE_MASK = np.zeros(STATE_SIZE, dtype=bool)
_ANGLE_MASK[list(ANGLES)] = True
_wrap = np.vectorize(normalize_angle, otypes=[float])


@dataclass(frozen=True)
class UkfWeights:
    lam: float
    state: np.ndarray  # (2n + 1,)
    covariance: np.ndarray  # (2n + 1,)

    @classmethod
    def of(cls, alpha: float = 0.001, kappa: float = 0.0, beta: float = 2.0) -> UkfWeights:
        n = STATE_SIZE
        lam = alpha * alpha * (n + kappa) - n
        ws = np.full(2 * n + 1, 1.0 / (2.0 * (n + lam)))
        ws[0] = lam / (n + lam)
        wc = ws.copy()
        wc[0] += 1.0 - alpha * alpha + beta
        return cls(lam, ws, wc)


def sigma_points(state: np.ndarray, covariance: np.ndarray, weights: UkfWeights) -> np.ndarray:
    """(2n + 1, n) sigma points of (state, covariance)."""
    root = np.linalg.cholesky((STATE_SIZE + weights.lam) * covariance)
    return np.vstack([state, state + root.T, state - root.T])


def _circular_mean(values: np.ndarray, weights: np.ndarray) -> float:
    return math.atan2(float(weights @ np.sin(values)), float(weights @ np.cos(values)))


def predict(
    state: np.ndarray, covariance: np.ndarray, dt: float, process_noise: np.ndarray, weights: UkfWeights
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x, P, projected sigma points) after `dt` seconds."""
    points = sigma_points(state, covariance, weights)
    moved = np.array([transfer_function(p, dt) @ p for p in points])
    x = weights.state @ moved
    for i in ANGLES:
        x[i] = _circular_mean(moved[:, i], weights.state)
    diff = moved - x
    diff[:, _ANGLE_MASK] = _wrap(diff[:, _ANGLE_MASK])
    p = (weights.covariance[:, None] * diff).T @ diff + dt * process_noise
    wrap_state_angles(x)
    return x, p, moved


def correct(
    state: np.ndarray,
    covariance: np.ndarray,
    points: np.ndarray,
    measurement: np.ndarray,
    measurement_covariance: np.ndarray,
    update: np.ndarray,
    weights: UkfWeights,
    rejection_threshold: float = math.inf,
) -> tuple[np.ndarray, np.ndarray, bool]:
    """(x, P, accepted) after fusing the selected entries of a measurement, from the sigma
    points `points` (the prediction's, or sigma_points of the current estimate)."""
    idx = measured_indices(measurement, update)
    if idx.size == 0:
        return state, covariance, False
    r = measurement_covariance[np.ix_(idx, idx)].copy()
    np.fill_diagonal(r, np.maximum(np.abs(np.diag(r)), 1e-9))
    z_points = points[:, idx]
    z_hat = weights.state @ z_points
    angles = _ANGLE_MASK[idx]
    for k in np.flatnonzero(angles):
        z_hat[k] = _circular_mean(z_points[:, k], weights.state)
    dz = z_points - z_hat
    dx = points - state
    if angles.any():
        dz[:, angles] = _wrap(dz[:, angles])
    dx[:, _ANGLE_MASK] = _wrap(dx[:, _ANGLE_MASK])
    p_zz = (weights.covariance[:, None] * dz).T @ dz
    p_xz = (weights.covariance[:, None] * dx).T @ dz
    s_inv = np.linalg.inv(p_zz + r)
    gain = p_xz @ s_inv
    innovation = measurement[idx] - z_hat
    if angles.any():
        innovation[angles] = _wrap(innovation[angles])
    if float(innovation @ s_inv @ innovation) >= rejection_threshold * rejection_threshold:
        return state, covariance, False
    x = state + gain @ innovation
    p = covariance - gain @ p_zz @ gain.T
    wrap_state_angles(x)
    return x, p, True
