"""The state estimate and its bookkeeping, shared by the EKF and the UKF (FilterBase).

The first measurement initialises what it measures; each later one is preceded by a prediction
over the time since the last (none for an older one, which corrects the estimate as it is), and
the control term turns commanded velocities into accelerations (docs/localization.md).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import ekf, ukf
from .kalman_measurements import Measurement
from .kalman_state import (
    AX,
    DEFAULT_INITIAL_COVARIANCE,
    DEFAULT_PROCESS_NOISE,
    STATE_SIZE,
    VROLL,
    VX,
    control_acceleration,
    dynamic_process_noise,
)


@dataclass
class ControlConfig:
    """use_control's settings, per twist variable (vx, vy, vz, vroll, vpitch, vyaw)."""

    update: np.ndarray  # 6 booleans: control_config
    timeout: float
    acceleration_limits: np.ndarray
    acceleration_gains: np.ndarray
    deceleration_limits: np.ndarray
    deceleration_gains: np.ndarray


@dataclass
class StateEstimator:
    """x, P and what the next step needs; `kind` is "ekf" or "ukf"."""

    kind: str = "ekf"
    process_noise: np.ndarray = field(default_factory=lambda: DEFAULT_PROCESS_NOISE.copy())
    sensor_timeout: float = 1.0 / 30.0
    dynamic_process_noise: bool = False
    control: ControlConfig | None = None
    ukf_weights: ukf.UkfWeights | None = None
    state: np.ndarray = field(default_factory=lambda: np.zeros(STATE_SIZE))
    covariance: np.ndarray = field(default_factory=lambda: DEFAULT_INITIAL_COVARIANCE.copy())
    initialized: bool = False
    last_measurement_time: float = 0.0
    latest_control: np.ndarray = field(default_factory=lambda: np.zeros(6))
    latest_control_time: float = 0.0
    _sigma: np.ndarray | None = None  # the UKF's points since the last prediction (uncorrected)

    def __post_init__(self) -> None:
        if self.kind == "ukf" and self.ukf_weights is None:
            self.ukf_weights = ukf.UkfWeights.of()

    def _weights(self) -> ukf.UkfWeights:
        assert self.ukf_weights is not None  # set in __post_init__ for a UKF
        return self.ukf_weights

    def set_control(self, command: np.ndarray, t: float) -> None:
        self.latest_control, self.latest_control_time = np.asarray(command, dtype=float), t

    def _apply_control(self, reference_time: float, dt: float) -> None:
        c = self.control
        if c is None:
            return
        timed_out = abs(reference_time - self.latest_control_time) >= c.timeout
        accel = np.zeros(6)
        for i in np.flatnonzero(c.update):
            command = 0.0 if timed_out else float(self.latest_control[i])
            accel[i] = control_acceleration(
                float(self.state[VX + i]),
                command,
                float(c.acceleration_limits[i]),
                float(c.acceleration_gains[i]),
                float(c.deceleration_limits[i]),
                float(c.deceleration_gains[i]),
            )
        self.state[VROLL : VROLL + 3] += accel[3:] * dt
        for i in range(3):
            if c.update[i]:
                self.state[AX + i] = accel[i]

    def predict(self, reference_time: float, dt: float) -> None:
        """Project the estimate `dt` seconds forward (the caller moves last_measurement_time)."""
        self.state = self.state.copy()
        self._apply_control(reference_time, dt)
        q = (
            dynamic_process_noise(self.process_noise, self.state)
            if self.dynamic_process_noise
            else self.process_noise
        )
        if self.kind == "ukf":
            self.state, self.covariance, self._sigma = ukf.predict(
                self.state, self.covariance, dt, q, self._weights()
            )
        else:
            self.state, self.covariance = ekf.predict(self.state, self.covariance, dt, q)

    def correct(self, m: Measurement) -> bool:
        if self.kind == "ukf":
            points = self._sigma
            if points is None:
                points = ukf.sigma_points(self.state, self.covariance, self._weights())
            self.state, self.covariance, accepted = ukf.correct(
                self.state,
                self.covariance,
                points,
                m.z,
                m.covariance,
                m.update,
                self._weights(),
                m.rejection_threshold,
            )
            if accepted:
                self._sigma = None
            return accepted
        self.state, self.covariance, accepted = ekf.correct(
            self.state, self.covariance, m.z, m.covariance, m.update, m.rejection_threshold
        )
        return accepted

    def process_measurement(self, m: Measurement) -> None:
        """Predict to the measurement's time (if later) and correct, or initialise with it."""
        delta = 0.0
        if self.initialized:
            delta = m.time - self.last_measurement_time
            if delta > 0:
                if delta > 100000.0:  # a bag replayed from far away: FilterBase::validateDelta
                    delta = 0.01
                self.predict(m.time, delta)
            self.correct(m)
        else:
            self.state = self.state.copy()
            self.state[m.update] = m.z[m.update]
            both = np.outer(m.update, m.update)
            self.covariance = np.where(both, m.covariance, self.covariance)
            self.initialized = True
        if delta >= 0.0:
            self.last_measurement_time = m.time

    def predict_to(self, t: float) -> None:
        """Predict to time `t` and make it the last measurement time (predict_to_current_time)."""
        delta = t - self.last_measurement_time
        if delta > 100000.0:
            delta = 0.01
        self.predict(t, delta)
        self.last_measurement_time += delta
