"""Backstepping control of the TWIL platform, eqs. (37)-(52), as corrected in docs/errata.md.

The platform is the cascade (30)-(34): pose error (e, psi, alpha) driven by the velocity
u = (u1, u2), and u driven by the input v = u_dot (after the feedback linearisation (9)).
The kinematic law eta (27)-(28) is what u should be; backstepping makes u track eta.

Two laws are offered, selected by `law=`:
- "corrected" (default): v = v_bar + eta_dot, v_bar from (46)-(47) with the e of erratum 1,
  eta_dot along the real dynamics (30)-(34) with the actual u. With it
  V1_dot = -g1 l1 e^2 cos^2(alpha) - g2 l2 alpha^2 - g4 l4 e1^2 - g5 l5 e2^2   (48)
  holds exactly (to rounding) at every state with e > 0.
- "printed": (51)-(52) term by term as printed, for comparison (errata 1-3 and 1b).

Near the goal the 1/e of v_bar1 is singular (erratum 4). When e is below `goal_tolerance`, or
if the law cannot be evaluated in floating point, the command is the brake v = -(gamma4 u1,
gamma5 u2): the velocity decays exponentially to zero with the rates of the e1, e2 loops, and
the platform stops within |u1|/gamma4 metres. The command is finite for every finite input.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields
from typing import Iterator, Mapping

import numpy as np

from twil_control.control.angles import sinc, sinc_derivative
from twil_control.control.kinematic_law import eta_dot_tuple, eta_tuple
from twil_control.control.polar import as_pose, error_coordinates, error_coordinates_unchecked, polar_kinematics

__all__ = [
    "BacksteppingLaw",
    "GAIN_NAMES",
    "LAWS",
    "DEFAULT_GOAL_TOLERANCE",
    "BacksteppingGains",
    "BacksteppingState",
    "STATE_FIELDS",
    "validate_gains",
    "tracking_errors",
    "v_bar",
    "corrected_command",
    "printed_command",
    "braking_command",
    "control_law",
    "lyapunov_v1",
    "lyapunov_v1_dot_predicted",
    "lyapunov_v1_dot_actual",
    "backstepping_state",
    "closed_loop_rhs",
]

GAIN_NAMES = ("gamma1", "gamma2", "gamma4", "gamma5", "lambda1", "lambda2", "lambda3", "lambda4", "lambda5")
LAWS = ("corrected", "printed")
DEFAULT_GOAL_TOLERANCE = 1e-3  # m; the controller node passes its own from the parameters
# Even with goal_tolerance = 0 the law is not evaluated below this distance: psi and alpha come
# from atan2 of a vector whose length is near rounding noise, and 1/e would reach 1e9 and more.
_MIN_DISTANCE = 1e-9  # m
_FLOAT_MAX = np.finfo(float).max


@dataclass(frozen=True)
class BacksteppingGains(Mapping):
    """The positive gains of (27)-(28), (43) and (46)-(47). There is no gamma3 in the paper."""

    gamma1: float
    gamma2: float
    gamma4: float
    gamma5: float
    lambda1: float
    lambda2: float
    lambda3: float
    lambda4: float
    lambda5: float

    def __getitem__(self, key: str) -> float:
        # The instance dict holds exactly the fields; an unknown key raises KeyError.
        return self.__dict__[key]

    def __iter__(self) -> Iterator[str]:
        return iter(GAIN_NAMES)

    def __len__(self) -> int:
        return len(GAIN_NAMES)


def validate_gains(gains: Mapping[str, float]) -> BacksteppingGains:
    """Check the gains of (27)-(28), (43), (46)-(47): exactly the keys of GAIN_NAMES, finite, > 0.

    Raises KeyError naming the missing keys, ValueError naming unknown keys or bad values.
    """
    if isinstance(gains, BacksteppingGains):
        return gains
    keys = set(gains)
    missing = [k for k in GAIN_NAMES if k not in keys]
    if missing:
        raise KeyError(f"backstepping gains missing {missing}; required: {list(GAIN_NAMES)}")
    unknown = sorted(keys - set(GAIN_NAMES))
    if unknown:
        raise ValueError(f"unknown backstepping gains {unknown}; allowed: {list(GAIN_NAMES)}")
    values = {}
    for key in GAIN_NAMES:
        try:
            value = float(gains[key])
        except (TypeError, ValueError) as err:
            raise ValueError(f"backstepping gain {key}={gains[key]!r} is not a number") from err
        if not (math.isfinite(value) and value > 0.0):
            raise ValueError(f"backstepping gain {key}={value} must be finite and > 0")
        values[key] = value
    return BacksteppingGains(**values)


def tracking_errors(e: float, psi: float, alpha: float, u, gains: Mapping[str, float]) -> tuple[float, float]:
    """(e1, e2) = u - eta, eqs. (37)-(38)."""
    eta1, eta2 = eta_tuple(e, psi, alpha, gains)
    return float(u[0]) - eta1, float(u[1]) - eta2


def v_bar(e: float, psi: float, alpha: float, e1: float, e2: float, gains: Mapping[str, float]) -> np.ndarray:
    """[v_bar1, v_bar2] of (46)-(47) with erratum 1 (the e in the lambda1 term).

    v_bar1 = -gamma4 e1 - (lambda1/lambda4) e cos(alpha)
             + (lambda2/lambda4) alpha sin(alpha)/e - (lambda3/lambda4) psi sin(alpha)/e   (46)
    v_bar2 = -gamma5 e2 - (lambda2/lambda5) alpha                                           (47)
    Requires e > 0.
    """
    return np.array(_v_bar_tuple(e, psi, alpha, e1, e2, gains))


def _v_bar_tuple(e: float, psi: float, alpha: float, e1: float, e2: float, gains) -> tuple[float, float]:
    l4 = gains["lambda4"]
    s_over_e = math.sin(alpha) / e
    vb1 = (
        -gains["gamma4"] * e1
        - gains["lambda1"] / l4 * e * math.cos(alpha)
        + gains["lambda2"] / l4 * alpha * s_over_e
        - gains["lambda3"] / l4 * psi * s_over_e
    )
    return vb1, -gains["gamma5"] * e2 - gains["lambda2"] / gains["lambda5"] * alpha


def corrected_command(e: float, psi: float, alpha: float, u, gains: Mapping[str, float]) -> np.ndarray:
    """v = v_bar + eta_dot, the inverse of the definitions (39)-(40) (errata 1-3).

    v_bar from (46)-(47) with erratum 1, eta_dot along (30)-(34) with the actual u. Requires e > 0.
    """
    e1, e2 = tracking_errors(e, psi, alpha, u, gains)
    vb1, vb2 = _v_bar_tuple(e, psi, alpha, e1, e2, gains)
    eta1_dot, eta2_dot = eta_dot_tuple(e, psi, alpha, u, gains)
    return np.array([vb1 + eta1_dot, vb2 + eta2_dot])


def printed_command(e: float, psi: float, alpha: float, u, gains: Mapping[str, float]) -> np.ndarray:
    """v of (51)-(52) exactly as printed, term by term in the printed order.

    Kept for comparison; it is not the law the derivation needs (docs/errata.md): (51) has
    -(lambda1/lambda4) cos(alpha) without e (erratum 1) and omits the -(lambda3/lambda4) psi
    sin(alpha)/e term of (46) (erratum 1b); the remaining terms are v_bar - eta_dot with eta_dot
    along the nominal loop u = eta (errata 2-3). Quotients of powers of sin(alpha) by powers of
    alpha are evaluated with sinc so the expression is defined at alpha = 0:
    sin^2/alpha = sin sinc, sin^3/alpha = sin^2 sinc, sin^3/alpha^2 = sin sinc^2, and the pair
    -cos^3 sin/alpha^2 + cos^2 sin^2/alpha^3 = -cos^2 sinc sinc'. Requires e > 0.
    """
    g1, g2 = gains["gamma1"], gains["gamma2"]
    l2, l3, l4 = gains["lambda2"], gains["lambda3"], gains["lambda4"]
    L = l3 / l2
    c, s = math.cos(alpha), math.sin(alpha)
    sc, dsc = sinc(alpha), sinc_derivative(alpha)
    e1, e2 = tracking_errors(e, psi, alpha, u, gains)
    v1 = (
        -gains["gamma4"] * e1
        - gains["lambda1"] / l4 * c
        + l2 / l4 * alpha * s / e
        - g1 * g1 * e * c**3
        + g1 * g2 * e * alpha * s
        - g1 * g1 * L * e * c * s * sc * psi
    )
    v2 = (
        -gains["gamma5"] * e2
        - l2 / gains["lambda5"] * alpha
        - g2 * g2 * alpha
        + g1 * g2 * alpha * s * s
        - g1 * g1 * L * c * s * s * sc * psi
        - g1 * g2 * alpha * c * c
        + g1 * g1 * L * c**3 * sc * psi
        - g1 * g2 * L * s * s * psi
        + g1 * g1 * L * L * c * s * sc * sc * psi * psi
        + g1 * g2 * L * c * c * psi
        - g1 * g1 * L * L * c * c * sc * dsc * psi * psi
        + g1 * g1 * L * c * c * s * sc
    )
    return np.array([v1, v2])


def braking_command(velocity, gains: Mapping[str, float]) -> np.ndarray:
    """v = -(gamma4 u1, gamma5 u2): stop at the goal (erratum 4), finite for every finite u.

    u then decays as exp(-gamma4 t), exp(-gamma5 t); the platform rolls at most |u1|/gamma4
    further. Products that overflow are clipped to the largest float.
    """
    # Python float products overflow to inf silently; clip brings them back to finite.
    brake = np.array([-gains["gamma4"] * float(velocity[0]), -gains["gamma5"] * float(velocity[1])])
    return np.clip(brake, -_FLOAT_MAX, _FLOAT_MAX)


_LAW_FUNCTIONS = {"corrected": corrected_command, "printed": printed_command}


def _velocity2(velocity) -> tuple[float, float]:
    if len(velocity) != 2:
        raise ValueError(f"velocity must be (u1, u2), got {len(velocity)} values")
    u1, u2 = float(velocity[0]), float(velocity[1])
    if not (math.isfinite(u1) and math.isfinite(u2)):
        raise ValueError(f"velocity must be finite, got {tuple(velocity)}")
    return u1, u2


def control_law(
    pose,
    pose_ref,
    velocity,
    gains: Mapping[str, float],
    *,
    law: str = "corrected",
    goal_tolerance: float = DEFAULT_GOAL_TOLERANCE,
) -> np.ndarray:
    """The platform input v = u_dot = [v1, v2] for pose -> pose_ref, eqs. (18)-(22), (27)-(52).

    pose, pose_ref: (x, y, theta) of the axle midpoint; velocity: (u1, u2) = (linear, angular).
    law: "corrected" (v = v_bar + eta_dot, errata 1-3) or "printed" ((51)-(52) as printed).
    goal_tolerance (m, >= 0): for e <= max(goal_tolerance, 1e-9 m) the command is the brake
    of `braking_command` (erratum 4), as it is if the law overflows floating point.
    Feed v to the feedback linearisation (9) (platform_model.feedback_linearization).
    """
    if law not in _LAW_FUNCTIONS:
        raise ValueError(f"law must be one of {LAWS}, got {law!r}")
    tolerance = float(goal_tolerance)
    if not (math.isfinite(tolerance) and tolerance >= 0.0):
        raise ValueError(f"goal_tolerance must be finite and >= 0, got {goal_tolerance!r}")
    checked = validate_gains(gains)
    u = _velocity2(velocity)
    pose, pose_ref = as_pose(pose, "pose"), as_pose(pose_ref, "pose_ref")
    return _checked_command(pose, pose_ref, u, checked, _LAW_FUNCTIONS[law], max(tolerance, _MIN_DISTANCE))


def _checked_command(pose, pose_ref, u, gains, law_function, tolerance: float) -> np.ndarray:
    """control_law once its arguments are validated (finite floats, checked gains)."""
    try:
        e, psi, alpha = error_coordinates_unchecked(pose, pose_ref)
        if not (math.isfinite(e) and e > tolerance):
            return braking_command(u, gains)
        # Plain float arithmetic: overflow gives inf (or nan from inf - inf), without warnings.
        command = law_function(e, psi, alpha, u, gains)
    except (OverflowError, ValueError):
        # The arguments are validated, so these come from floating point: math.fmod or
        # math.cos of an angle that overflowed (poses near 1e308 apart), or ** overflowing.
        return braking_command(u, gains)
    if not (math.isfinite(command[0]) and math.isfinite(command[1])):
        return braking_command(u, gains)
    return command


class BacksteppingLaw:
    """control_law with its gains, law and goal tolerance checked once, for a 1 kHz loop (the
    checks cost more than the law). Same result as control_law (tested); a pose or velocity
    that is not finite is still refused with ValueError."""

    def __init__(self, gains: Mapping[str, float], *, law: str = "corrected",
                 goal_tolerance: float = DEFAULT_GOAL_TOLERANCE) -> None:
        if law not in _LAW_FUNCTIONS:
            raise ValueError(f"law must be one of {LAWS}, got {law!r}")
        tolerance = float(goal_tolerance)
        if not (math.isfinite(tolerance) and tolerance >= 0.0):
            raise ValueError(f"goal_tolerance must be finite and >= 0, got {goal_tolerance!r}")
        self.gains = validate_gains(gains)
        self._function = _LAW_FUNCTIONS[law]
        self.tolerance = max(tolerance, _MIN_DISTANCE)  # the brake below it (erratum 4)

    def __call__(self, pose, pose_ref, velocity) -> np.ndarray:
        x, y, th = pose
        xr, yr, thr = pose_ref
        u1, u2 = velocity
        if not math.isfinite(x + y + th + xr + yr + thr + u1 + u2):  # one test for all eight
            pose, pose_ref, u = as_pose(pose, "pose"), as_pose(pose_ref, "pose_ref"), _velocity2(velocity)
        return _checked_command((x, y, th), (xr, yr, thr), (u1, u2), self.gains, self._function, self.tolerance)


def lyapunov_v1(e: float, psi: float, alpha: float, e1: float, e2: float, gains: Mapping[str, float]) -> float:
    """V1 = 1/2 (lambda1 e^2 + lambda2 alpha^2 + lambda3 psi^2 + lambda4 e1^2 + lambda5 e2^2), eq. (43)."""
    return 0.5 * (
        gains["lambda1"] * e * e
        + gains["lambda2"] * alpha * alpha
        + gains["lambda3"] * psi * psi
        + gains["lambda4"] * e1 * e1
        + gains["lambda5"] * e2 * e2
    )


def lyapunov_v1_dot_predicted(e: float, alpha: float, e1: float, e2: float, gains: Mapping[str, float]) -> float:
    """The right-hand side of (48): -g1 l1 e^2 cos^2(alpha) - g2 l2 alpha^2 - g4 l4 e1^2 - g5 l5 e2^2."""
    return -(
        gains["gamma1"] * gains["lambda1"] * (e * math.cos(alpha)) ** 2
        + gains["gamma2"] * gains["lambda2"] * alpha * alpha
        + gains["gamma4"] * gains["lambda4"] * e1 * e1
        + gains["gamma5"] * gains["lambda5"] * e2 * e2
    )


def lyapunov_v1_dot_actual(pose, pose_ref, velocity, v, gains: Mapping[str, float]) -> float:
    """dV1/dt along the real dynamics (30)-(34) for the input v, by (44) with (37)-(40).

    V1_dot = l1 e e_dot + l2 alpha alpha_dot + l3 psi psi_dot + l4 e1 (v1 - eta1_dot)
             + l5 e2 (v2 - eta2_dot), eta_dot along (30)-(32) with the actual u. Requires e > 0.
    Equals lyapunov_v1_dot_predicted when v is the corrected law.
    """
    checked = validate_gains(gains)
    u = _velocity2(velocity)
    e, psi, alpha = error_coordinates(pose, pose_ref)
    e_dot, psi_dot, alpha_dot = polar_kinematics(e, alpha, u)
    e1, e2 = tracking_errors(e, psi, alpha, u, checked)
    eta1_dot, eta2_dot = eta_dot_tuple(e, psi, alpha, u, checked)
    return (
        checked.lambda1 * e * e_dot
        + checked.lambda2 * alpha * alpha_dot
        + checked.lambda3 * psi * psi_dot
        + checked.lambda4 * e1 * (float(v[0]) - eta1_dot)
        + checked.lambda5 * e2 * (float(v[1]) - eta2_dot)
    )


@dataclass(frozen=True)
class BacksteppingState:
    """The controller's internal quantities, for a status topic: (20)-(22), (27)-(28), (37)-(38), (43), (48)."""

    e: float
    psi: float
    alpha: float
    eta1: float
    eta2: float
    e1: float
    e2: float
    V1: float
    V1dot_pred: float

    def as_dict(self) -> dict[str, float]:
        return asdict(self)


def backstepping_state(pose, pose_ref, velocity, gains: Mapping[str, float]) -> BacksteppingState:
    """e, psi, alpha (20)-(22), eta (27)-(28), e1, e2 (37)-(38), V1 (43) and the bound (48)."""
    checked = validate_gains(gains)
    u = _velocity2(velocity)
    e, psi, alpha = error_coordinates(pose, pose_ref)
    eta1, eta2 = eta_tuple(e, psi, alpha, checked)
    e1, e2 = u[0] - eta1, u[1] - eta2
    return BacksteppingState(
        e=e,
        psi=psi,
        alpha=alpha,
        eta1=float(eta1),
        eta2=float(eta2),
        e1=float(e1),
        e2=float(e2),
        V1=lyapunov_v1(e, psi, alpha, e1, e2, checked),
        V1dot_pred=lyapunov_v1_dot_predicted(e, alpha, e1, e2, checked),
    )


STATE_FIELDS = tuple(f.name for f in fields(BacksteppingState))


def closed_loop_rhs(
    t: float,
    state,
    pose_ref,
    gains: Mapping[str, float],
    law: str = "corrected",
    goal_tolerance: float = DEFAULT_GOAL_TOLERANCE,
) -> np.ndarray:
    """Right-hand side of the ideal closed loop (11)-(12) with u_dot = v = control_law(...).

    state = (x, y, theta, u1, u2). For scipy.integrate.solve_ivp; t is unused (the law is
    time-invariant). Pass validated BacksteppingGains to skip re-validation at every call.
    """
    x, y, theta, u1, u2 = (float(s) for s in state)
    v = control_law((x, y, theta), pose_ref, (u1, u2), gains, law=law, goal_tolerance=goal_tolerance)
    return np.array([u1 * math.cos(theta), u1 * math.sin(theta), u2, v[0], v[1]])
