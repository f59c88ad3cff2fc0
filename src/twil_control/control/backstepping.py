"""Backstepping control of the TWIL platform, eqs. (37)-(52), as corrected in docs/errata.md.

Backstepping makes the platform's velocity u track the kinematic law eta (27)-(28) through the
input v = u_dot of the cascade (30)-(34). `law="corrected"` (default) keeps (48) exact at every
state with e > 0; `law="printed"` runs (51)-(52) as printed, for comparison. Near the goal, or
where the law overflows, the command is the brake of erratum 4, so it is finite for every
finite input. The equations are compiled functions of floats and the gain array (numba), which
the cart controller's compiled update composes; `control_law` and `BacksteppingLaw` check
their arguments and call them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, fields

import numpy as np
from numba import njit

from twil_control.control.angles import sinc, sinc_derivative
from twil_control.control.gains import (
    G1,
    G2,
    G4,
    G5,
    GAIN_NAMES,
    L1,
    L2,
    L3,
    L4,
    L5,
    BacksteppingGains,
    validate_gains,
)
from twil_control.control.kinematic_law import eta, eta_dot
from twil_control.control.polar import as_pose, error_coordinates, polar_kinematics
from twil_control.errors import InputError

__all__ = [
    "BacksteppingLaw",
    "GAIN_NAMES",
    "LAWS",
    "CORRECTED",
    "PRINTED",
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
    "command",
    "control_law",
    "lyapunov_v1",
    "lyapunov_v1_dot_predicted",
    "lyapunov_v1_dot",
    "lyapunov_v1_dot_actual",
    "backstepping_state",
    "closed_loop_rhs",
]

LAWS = ("corrected", "printed")
CORRECTED, PRINTED = 0, 1  # `command`'s law codes, in LAWS order
DEFAULT_GOAL_TOLERANCE = 1e-3  # m; the controller node passes its own from the parameters
# Even with goal_tolerance = 0 the law is not evaluated below this distance: psi and alpha come
# from atan2 of a vector whose length is near rounding noise, and 1/e would reach 1e9 and more.
_MIN_DISTANCE = 1e-9  # m
_FLOAT_MAX = np.finfo(np.float64).max


@njit(cache=True, nogil=True)
def tracking_errors(e, psi, alpha, u1, u2, g):
    """(e1, e2) = u - eta, eqs. (37)-(38)."""
    eta1, eta2 = eta(e, psi, alpha, g)
    return u1 - eta1, u2 - eta2


@njit(cache=True, nogil=True)
def v_bar(e, psi, alpha, e1, e2, g):
    """(v_bar1, v_bar2) of (46)-(47) with erratum 1 (the e in the lambda1 term).

    v_bar1 = -gamma4 e1 - (lambda1/lambda4) e cos(alpha)
             + (lambda2/lambda4) alpha sin(alpha)/e - (lambda3/lambda4) psi sin(alpha)/e   (46)
    v_bar2 = -gamma5 e2 - (lambda2/lambda5) alpha                                           (47)
    Requires e > 0.
    """
    l4 = g[L4]
    s_over_e = math.sin(alpha) / e
    vb1 = (
        -g[G4] * e1
        - g[L1] / l4 * e * math.cos(alpha)
        + g[L2] / l4 * alpha * s_over_e
        - g[L3] / l4 * psi * s_over_e
    )
    return vb1, -g[G5] * e2 - g[L2] / g[L5] * alpha


@njit(cache=True, nogil=True)
def corrected_command(e, psi, alpha, u1, u2, g):
    """v = v_bar + eta_dot, the inverse of the definitions (39)-(40) (errata 1-3).

    v_bar from (46)-(47) with erratum 1, eta_dot along (30)-(34) with the actual u. Requires e > 0.
    """
    e1, e2 = tracking_errors(e, psi, alpha, u1, u2, g)
    vb1, vb2 = v_bar(e, psi, alpha, e1, e2, g)
    eta1_dot, eta2_dot = eta_dot(e, psi, alpha, u1, u2, g)
    return vb1 + eta1_dot, vb2 + eta2_dot


@njit(cache=True, nogil=True)
def printed_command(e, psi, alpha, u1, u2, g):
    """v of (51)-(52) exactly as printed, term by term in the printed order.

    Kept for comparison; it is not the law the derivation needs (docs/errata.md): (51) has
    -(lambda1/lambda4) cos(alpha) without e (erratum 1) and omits the -(lambda3/lambda4) psi
    sin(alpha)/e term of (46) (erratum 1b); the remaining terms are v_bar - eta_dot with eta_dot
    along the nominal loop u = eta (errata 2-3). Quotients of powers of sin(alpha) by powers of
    alpha are evaluated with sinc so the expression is defined at alpha = 0:
    sin^2/alpha = sin sinc, sin^3/alpha = sin^2 sinc, sin^3/alpha^2 = sin sinc^2, and the pair
    -cos^3 sin/alpha^2 + cos^2 sin^2/alpha^3 = -cos^2 sinc sinc'. Requires e > 0.
    """
    g1, g2 = g[G1], g[G2]
    l2, l4 = g[L2], g[L4]
    L = g[L3] / l2
    c, s = math.cos(alpha), math.sin(alpha)
    sc, dsc = sinc(alpha), sinc_derivative(alpha)
    e1, e2 = tracking_errors(e, psi, alpha, u1, u2, g)
    v1 = (
        -g[G4] * e1
        - g[L1] / l4 * c
        + l2 / l4 * alpha * s / e
        - g1 * g1 * e * c**3
        + g1 * g2 * e * alpha * s
        - g1 * g1 * L * e * c * s * sc * psi
    )
    v2 = (
        -g[G5] * e2
        - l2 / g[L5] * alpha
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
    return v1, v2


@njit(cache=True, nogil=True)
def braking_command(u1, u2, g):
    """v = -(gamma4 u1, gamma5 u2): stop at the goal (erratum 4), finite for every finite u.

    u then decays as exp(-gamma4 t), exp(-gamma5 t); the platform rolls at most |u1|/gamma4
    further. Products that overflow are clipped to the largest float.
    """
    v1, v2 = -g[G4] * u1, -g[G5] * u2
    return min(max(v1, -_FLOAT_MAX), _FLOAT_MAX), min(max(v2, -_FLOAT_MAX), _FLOAT_MAX)


@njit(cache=True, nogil=True)
def command(law, x, y, th, xr, yr, thr, u1, u2, g, tolerance):
    """The platform input (v1, v2) for the pose (x, y, th) -> (xr, yr, thr) at velocity
    (u1, u2): (18)-(22), then the law `law` (CORRECTED or PRINTED), or the brake within
    `tolerance` (m, > 0) of the goal and wherever the law is not finite in floating point
    (poses near 1e308 apart). Arguments finite (checked by the callers)."""
    e, psi, alpha = error_coordinates(x, y, th, xr, yr, thr)
    if math.isfinite(e) and e > tolerance:
        if law == PRINTED:
            v1, v2 = printed_command(e, psi, alpha, u1, u2, g)
        else:
            v1, v2 = corrected_command(e, psi, alpha, u1, u2, g)
        if math.isfinite(v1) and math.isfinite(v2):
            return v1, v2
    return braking_command(u1, u2, g)


def _velocity2(velocity) -> tuple[float, float]:
    if len(velocity) != 2:
        raise InputError(f"velocity must be (u1, u2), got {len(velocity)} values")
    u1, u2 = float(velocity[0]), float(velocity[1])
    if not (math.isfinite(u1) and math.isfinite(u2)):
        raise InputError(f"velocity must be finite, got {tuple(velocity)}")
    return u1, u2


class BacksteppingLaw:
    """The platform input v = u_dot = [v1, v2] for pose -> pose_ref, eqs. (18)-(22), (27)-(52),
    with the gains, law and goal tolerance checked once (for a loop; `control_law` is one call).

    law: "corrected" (v = v_bar + eta_dot, errata 1-3) or "printed" ((51)-(52) as printed).
    goal_tolerance (m, >= 0): for e <= max(goal_tolerance, 1e-9 m) the command is the brake
    of `braking_command` (erratum 4), as it is if the law overflows floating point.
    Feed v to the feedback linearisation (9) (platform_model.feedback_linearization).
    A pose or velocity that is not finite is refused with ValueError."""

    def __init__(
        self,
        gains: Mapping[str, float],
        *,
        law: str = "corrected",
        goal_tolerance: float = DEFAULT_GOAL_TOLERANCE,
    ) -> None:
        if law not in LAWS:
            raise InputError(f"law must be one of {LAWS}, got {law!r}")
        tolerance = float(goal_tolerance)
        if not (math.isfinite(tolerance) and tolerance >= 0.0):
            raise InputError(f"goal_tolerance must be finite and >= 0, got {goal_tolerance!r}")
        self.gains = validate_gains(gains)
        self.law = LAWS.index(law)
        self.tolerance = max(tolerance, _MIN_DISTANCE)  # the brake below it (erratum 4)

    def __call__(self, pose, pose_ref, velocity) -> np.ndarray:
        """pose, pose_ref: (x, y, theta) of the axle midpoint; velocity: (u1, u2)."""
        x, y, th = as_pose(pose, "pose")
        xr, yr, thr = as_pose(pose_ref, "pose_ref")
        u1, u2 = _velocity2(velocity)
        return np.array(command(self.law, x, y, th, xr, yr, thr, u1, u2, self.gains.vector, self.tolerance))


def control_law(
    pose,
    pose_ref,
    velocity,
    gains: Mapping[str, float],
    *,
    law: str = "corrected",
    goal_tolerance: float = DEFAULT_GOAL_TOLERANCE,
) -> np.ndarray:
    """BacksteppingLaw(gains, law=law, goal_tolerance=goal_tolerance)(pose, pose_ref, velocity)."""
    return BacksteppingLaw(gains, law=law, goal_tolerance=goal_tolerance)(pose, pose_ref, velocity)


@njit(cache=True, nogil=True)
def lyapunov_v1(e, psi, alpha, e1, e2, g):
    """V1 = 1/2 (lambda1 e^2 + lambda2 alpha^2 + lambda3 psi^2 + lambda4 e1^2 + lambda5 e2^2), eq. (43)."""
    return 0.5 * (
        g[L1] * e * e + g[L2] * alpha * alpha + g[L3] * psi * psi + g[L4] * e1 * e1 + g[L5] * e2 * e2
    )


@njit(cache=True, nogil=True)
def lyapunov_v1_dot_predicted(e, alpha, e1, e2, g):
    """The right-hand side of (48): -g1 l1 e^2 cos^2(alpha) - g2 l2 alpha^2 - g4 l4 e1^2 - g5 l5 e2^2."""
    ec = e * math.cos(alpha)
    return -(
        g[G1] * g[L1] * ec * ec
        + g[G2] * g[L2] * alpha * alpha
        + g[G4] * g[L4] * e1 * e1
        + g[G5] * g[L5] * e2 * e2
    )


@njit(cache=True, nogil=True)
def lyapunov_v1_dot(e, psi, alpha, u1, u2, v1, v2, g):
    """dV1/dt along the real dynamics (30)-(34) for the input v, by (44) with (37)-(40):
    l1 e e_dot + l2 alpha alpha_dot + l3 psi psi_dot + l4 e1 (v1 - eta1_dot)
    + l5 e2 (v2 - eta2_dot), eta_dot along (30)-(32) with the actual u. Requires e > 0."""
    e_dot, psi_dot, alpha_dot = polar_kinematics(e, alpha, u1, u2)
    e1, e2 = tracking_errors(e, psi, alpha, u1, u2, g)
    eta1_dot, eta2_dot = eta_dot(e, psi, alpha, u1, u2, g)
    return (
        g[L1] * e * e_dot
        + g[L2] * alpha * alpha_dot
        + g[L3] * psi * psi_dot
        + g[L4] * e1 * (v1 - eta1_dot)
        + g[L5] * e2 * (v2 - eta2_dot)
    )


def lyapunov_v1_dot_actual(pose, pose_ref, velocity, v, gains: Mapping[str, float]) -> float:
    """`lyapunov_v1_dot` at pose -> pose_ref (checked): equals lyapunov_v1_dot_predicted when v
    is the corrected law."""
    g = validate_gains(gains).vector
    u1, u2 = _velocity2(velocity)
    e, psi, alpha = error_coordinates(*as_pose(pose, "pose"), *as_pose(pose_ref, "pose_ref"))
    return float(lyapunov_v1_dot(e, psi, alpha, u1, u2, float(v[0]), float(v[1]), g))


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
    g = validate_gains(gains).vector
    u1, u2 = _velocity2(velocity)
    e, psi, alpha = error_coordinates(*as_pose(pose, "pose"), *as_pose(pose_ref, "pose_ref"))
    eta1, eta2 = eta(e, psi, alpha, g)
    e1, e2 = u1 - eta1, u2 - eta2
    return BacksteppingState(
        e=e,
        psi=psi,
        alpha=alpha,
        eta1=eta1,
        eta2=eta2,
        e1=e1,
        e2=e2,
        V1=lyapunov_v1(e, psi, alpha, e1, e2, g),
        V1dot_pred=lyapunov_v1_dot_predicted(e, alpha, e1, e2, g),
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
