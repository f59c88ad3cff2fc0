"""A textbook extended Kalman filter, written for the tests independently of localization/: the
same 15-variable constant-acceleration model (pose, body-frame velocities, accelerations), its
Jacobian by central differences, and the standard predict / update equations with a full
selection matrix H. It fuses odometry twists and IMU messages whose frames are base_link (no
mounting rotation), with robot_localization's conventions: 15-entry update vectors,
differential orientations turned into rates ((C_now + C_before) dt), two_d_mode measuring z,
roll, pitch and their rates and az as 0 (variance 1e-6), initialisation from the first
measurement, variances floored at 1e-9, predict_to_current_time at every tick.
"""

from __future__ import annotations

import math

import numpy as np

N = 15
ANGLES = (3, 4, 5)
TWO_D = (2, 3, 4, 8, 9, 10, 14)
Q_DEFAULT = np.diag(
    [0.05, 0.05, 0.06, 0.03, 0.03, 0.06, 0.025, 0.025, 0.04, 0.01, 0.01, 0.02, 0.01, 0.01, 0.015]
)


def wrap(a: float) -> float:
    return math.atan2(math.sin(a), math.cos(a))


def rotation(roll: float, pitch: float, yaw: float) -> np.ndarray:
    def rx(a):
        return np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])

    def ry(a):
        return np.array([[math.cos(a), 0, math.sin(a)], [0, 1, 0], [-math.sin(a), 0, math.cos(a)]])

    def rz(a):
        return np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])

    return rz(yaw) @ ry(pitch) @ rx(roll)


def euler_of(r: np.ndarray) -> tuple[float, float, float]:
    pitch = math.asin(max(-1.0, min(1.0, -r[2, 0])))
    return math.atan2(r[2, 1], r[2, 2]), pitch, math.atan2(r[1, 0], r[0, 0])


def motion(x: np.ndarray, dt: float) -> np.ndarray:
    """Body velocities and accelerations rotated into the world; Euler rates from body rates."""
    out = x.copy()
    r, p, _ = x[3:6]
    out[0:3] += rotation(*x[3:6]) @ (x[6:9] * dt + 0.5 * x[12:15] * dt * dt)
    euler_rates = np.array(
        [
            [1.0, math.sin(r) * math.tan(p), math.cos(r) * math.tan(p)],
            [0.0, math.cos(r), -math.sin(r)],
            [0.0, math.sin(r) / math.cos(p), math.cos(r) / math.cos(p)],
        ]
    )
    out[3:6] += euler_rates @ x[9:12] * dt
    out[6:9] += x[12:15] * dt
    return out


def jacobian(x: np.ndarray, dt: float, eps: float = 1e-6) -> np.ndarray:
    j = np.zeros((N, N))
    for i in range(N):
        e = np.zeros(N)
        e[i] = eps
        j[:, i] = (motion(x + e, dt) - motion(x - e, dt)) / (2 * eps)
    return j


class ReferenceEkf:
    def __init__(self, q: np.ndarray = Q_DEFAULT, two_d: bool = False) -> None:
        self.q, self.two_d = q, two_d
        self.x, self.p = np.zeros(N), np.eye(N) * 1e-9
        self.t, self.initialized = 0.0, False
        self.previous_orientation: dict[str, tuple[float, np.ndarray, np.ndarray]] = {}

    def predict(self, dt: float) -> None:
        j = jacobian(self.x, dt)
        self.x = motion(self.x, dt)
        for i in ANGLES:
            self.x[i] = wrap(self.x[i])
        self.p = j @ self.p @ j.T + self.q * dt

    def _measurement(self, z: np.ndarray, r: np.ndarray, mask: np.ndarray):
        if self.two_d:
            for i in TWO_D:
                z[i], r[i, i], mask[i] = 0.0, 1e-6, True
        return z, r, mask

    def fuse(self, t: float, z: np.ndarray, r: np.ndarray, mask: np.ndarray) -> None:
        z, r, mask = self._measurement(z, r, mask)
        if not self.initialized:
            self.x[mask] = z[mask]
            both = np.outer(mask, mask)
            self.p[both] = r[both]
            self.initialized, self.t = True, t
            return
        if t > self.t:
            self.predict(t - self.t)
            self.t = t
        idx = np.flatnonzero(mask)
        h = np.zeros((len(idx), N))
        h[np.arange(len(idx)), idx] = 1.0
        rr = r[np.ix_(idx, idx)].copy()
        for k in range(len(idx)):
            rr[k, k] = max(abs(rr[k, k]), 1e-9)
        s = h @ self.p @ h.T + rr
        k_gain = self.p @ h.T @ np.linalg.inv(s)
        y = z[idx] - h @ self.x
        for k, i in enumerate(idx):
            if i in ANGLES:
                y[k] = wrap(y[k])
        self.x = self.x + k_gain @ y
        for i in ANGLES:
            self.x[i] = wrap(self.x[i])
        a = np.eye(N) - k_gain @ h
        self.p = a @ self.p @ a.T + k_gain @ rr @ k_gain.T

    def odometry_twist(self, t: float, twist6: np.ndarray, cov36: np.ndarray, config: np.ndarray) -> None:
        z, r, mask = np.zeros(N), np.zeros((N, N)), np.zeros(N, dtype=bool)
        z[6:12] = twist6
        r[6:12, 6:12] = np.asarray(cov36).reshape(6, 6)
        mask[6:12] = config[6:12]
        self.fuse(t, z, r, mask)

    def imu(self, name: str, t: float, quat, rates, cov, config: np.ndarray, differential: bool) -> None:
        """An IMU in base_link: its orientation (absolute, or differential: rates), then its rates."""
        x, y, zq, w = quat
        r_now = np.array(
            [
                [1 - 2 * (y * y + zq * zq), 2 * (x * y - zq * w), 2 * (x * zq + y * w)],
                [2 * (x * y + zq * w), 1 - 2 * (x * x + zq * zq), 2 * (y * zq - x * w)],
                [2 * (x * zq - y * w), 2 * (y * zq + x * w), 1 - 2 * (x * x + y * y)],
            ]
        )
        c_orientation = np.asarray(cov["orientation"]).reshape(3, 3)
        if config[3:6].any():
            z, r, mask = np.zeros(N), np.zeros((N, N)), np.zeros(N, dtype=bool)
            if differential:
                before = self.previous_orientation.get(name)
                self.previous_orientation[name] = (t, r_now, c_orientation)
                if before is not None and t > before[0]:
                    dt = t - before[0]
                    z[9:12] = np.array(euler_of(before[1].T @ r_now)) / dt
                    r[9:12, 9:12] = (c_orientation + before[2]) * dt
                    mask[9:12] = config[3:6]
                    self.fuse(t, z, r, mask)
            else:
                z[3:6] = euler_of(r_now)
                r[3:6, 3:6] = c_orientation
                mask[3:6] = config[3:6]
                self.fuse(t, z, r, mask)
        if config[9:12].any():
            z, r, mask = np.zeros(N), np.zeros((N, N)), np.zeros(N, dtype=bool)
            z[9:12] = rates
            r[9:12, 9:12] = np.asarray(cov["angular_velocity"]).reshape(3, 3)
            mask[9:12] = config[9:12]
            self.fuse(t, z, r, mask)

    def predict_to(self, t: float) -> None:
        if self.initialized:
            self.predict(t - self.t)
            self.t = t
