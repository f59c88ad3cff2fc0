"""The non-smooth kinematic law eta(e, psi, alpha), eqs. (27)-(28), and its time derivative.

eta is the velocity the platform should have; the backstepping law (37)-(52) makes the actual
velocity u track it, and needs eta_dot. The partial derivatives below are derived by hand and
checked against sympy in tests/test_backstepping.py.

`gains` is any mapping with the keys gamma1, gamma2, lambda2 and lambda3 (a
twil_control.control.backstepping.BacksteppingGains, or a plain dict). Scalar math (the
controller evaluates this at 1 kHz, and numpy on scalars costs microseconds a call).
"""
from __future__ import annotations

import math
from typing import Mapping

import numpy as np

from twil_control.control.angles import sinc, sinc_derivative
from twil_control.control.polar import polar_kinematics

__all__ = ["eta", "eta_tuple", "eta_partials", "eta_dot", "eta_dot_tuple", "eta_dot_nominal"]


def eta(e: float, psi: float, alpha: float, gains: Mapping[str, float]) -> np.ndarray:
    """The kinematic law [eta1, eta2], eqs. (27)-(28).

    eta1 = -gamma1 e cos(alpha)                                                        (27)
    eta2 = -gamma2 alpha - gamma1 cos(alpha) sin(alpha)
           + gamma1 (lambda3/lambda2) cos(alpha) (sin(alpha)/alpha) psi                (28)
    sin(alpha)/alpha is a sinc (1 at alpha = 0), so eta is smooth in alpha.
    """
    return np.array(eta_tuple(e, psi, alpha, gains))


def eta_tuple(e: float, psi: float, alpha: float, gains: Mapping[str, float]) -> tuple[float, float]:
    """eta of (27)-(28) as a tuple of floats (no array: for the 1 kHz loop)."""
    g1 = gains["gamma1"]
    ratio = gains["lambda3"] / gains["lambda2"]
    c, s = math.cos(alpha), math.sin(alpha)
    return -g1 * e * c, -gains["gamma2"] * alpha - g1 * c * s + g1 * ratio * c * sinc(alpha) * psi


def _eta2_partials(psi: float, alpha: float, gains: Mapping[str, float]) -> tuple[float, float]:
    # (d eta2/dpsi, d eta2/dalpha); d eta2/de = 0. See eta_partials.
    g1 = gains["gamma1"]
    ratio = gains["lambda3"] / gains["lambda2"]
    c, s = math.cos(alpha), math.sin(alpha)
    sc = sinc(alpha)
    d_cos_sinc = c * sinc_derivative(alpha) - s * sc
    return (
        g1 * ratio * c * sc,
        -gains["gamma2"] - g1 * math.cos(2.0 * alpha) + g1 * ratio * psi * d_cos_sinc,
    )


def eta_partials(e: float, psi: float, alpha: float, gains: Mapping[str, float]) -> np.ndarray:
    """Jacobian d[eta1, eta2]/d[e, psi, alpha] of the law (27)-(28), shape (2, 3).

    d eta1/de = -gamma1 cos(alpha),  d eta1/dpsi = 0,  d eta1/dalpha = gamma1 e sin(alpha)
    d eta2/de = 0,  d eta2/dpsi = gamma1 (lambda3/lambda2) cos(alpha) sinc(alpha)
    d eta2/dalpha = -gamma2 - gamma1 cos(2 alpha)
                    + gamma1 (lambda3/lambda2) psi [cos(alpha) sinc'(alpha) - sin(alpha) sinc(alpha)]
    with sinc'(alpha) = (cos(alpha) - sinc(alpha))/alpha, taken from its series near 0.
    """
    g1 = gains["gamma1"]
    d2_dpsi, d2_dalpha = _eta2_partials(psi, alpha, gains)
    return np.array([[-g1 * math.cos(alpha), 0.0, g1 * e * math.sin(alpha)], [0.0, d2_dpsi, d2_dalpha]])


def eta_dot(e: float, psi: float, alpha: float, u, gains: Mapping[str, float]) -> np.ndarray:
    """d eta/dt along the real platform kinematics (30)-(32) with the actual velocity u.

    This is the eta_dot of (39)-(40): e1 = u1 - eta1 and e2 = u2 - eta2 (37)-(38) are not zero,
    so eta_dot contains them. By the chain rule and (30)-(32),
    eta1_dot = -gamma1 cos^2(alpha) u1 + gamma1 e sin(alpha) (-sin(alpha)/e u1 + u2)
             = -gamma1 u1 + gamma1 e sin(alpha) u2          (written so, the 1/e cancels exactly)
    eta2_dot = d eta2/dpsi * psi_dot + d eta2/dalpha * alpha_dot.
    Requires e > 0 (psi_dot and alpha_dot have 1/e).
    """
    return np.array(eta_dot_tuple(e, psi, alpha, u, gains))


def eta_dot_tuple(e: float, psi: float, alpha: float, u, gains: Mapping[str, float]) -> tuple[float, float]:
    """eta_dot of (30)-(32) with the actual u, as a tuple of floats (see eta_dot)."""
    u1, u2 = float(u[0]), float(u[1])
    g1 = gains["gamma1"]
    d2_dpsi, d2_dalpha = _eta2_partials(psi, alpha, gains)
    _, psi_dot, alpha_dot = polar_kinematics(e, alpha, (u1, u2))
    return -g1 * u1 + g1 * e * math.sin(alpha) * u2, d2_dpsi * psi_dot + d2_dalpha * alpha_dot


def eta_dot_nominal(e: float, psi: float, alpha: float, gains: Mapping[str, float]) -> np.ndarray:
    """d eta/dt along the nominal closed loop u = eta, i.e. with e1 = e2 = 0 in (41)-(42).

    This is what the printed (51)-(52) contain (erratum 3 of docs/errata.md). On the nominal
    loop e_dot = -gamma1 e cos^2(alpha), psi_dot = -gamma1 sin(alpha) cos(alpha) and
    alpha_dot = -gamma2 alpha + gamma1 (lambda3/lambda2) cos(alpha) sinc(alpha) psi (42), which
    have no 1/e, so this is defined at e = 0 too.
    """
    g1 = gains["gamma1"]
    ratio = gains["lambda3"] / gains["lambda2"]
    c, s = math.cos(alpha), math.sin(alpha)
    d2_dpsi, d2_dalpha = _eta2_partials(psi, alpha, gains)
    e_dot = -g1 * e * c * c
    psi_dot = -g1 * s * c
    alpha_dot = -gains["gamma2"] * alpha + g1 * ratio * c * sinc(alpha) * psi
    eta1_dot = -g1 * c * e_dot + g1 * e * s * alpha_dot
    return np.array([eta1_dot, d2_dpsi * psi_dot + d2_dalpha * alpha_dot])
