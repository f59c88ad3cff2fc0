"""The non-smooth kinematic law eta(e, psi, alpha), eqs. (27)-(28), and its time derivative.

eta is the velocity the platform should have; the backstepping law (37)-(52) makes the actual
velocity u track it, and needs eta_dot. The partial derivatives below are derived by hand and
checked against sympy in tests/test_backstepping.py.

`g` is the gain array of control.gains (BacksteppingGains.vector). Compiled functions of floats
(numba), called from Python and by the cart controller's compiled update alike.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from twil_control.control.angles import sinc, sinc_derivative
from twil_control.control.gains import G1, G2, L2, L3
from twil_control.control.polar import polar_kinematics

__all__ = ["eta", "eta2_partials", "eta_partials", "eta_dot", "eta_dot_nominal"]


@njit(cache=True, nogil=True)
def eta(e, psi, alpha, g):
    """The kinematic law (eta1, eta2), eqs. (27)-(28).

    eta1 = -gamma1 e cos(alpha)                                                        (27)
    eta2 = -gamma2 alpha - gamma1 cos(alpha) sin(alpha)
           + gamma1 (lambda3/lambda2) cos(alpha) (sin(alpha)/alpha) psi                (28)
    sin(alpha)/alpha is a sinc (1 at alpha = 0), so eta is smooth in alpha.
    """
    g1 = g[G1]
    ratio = g[L3] / g[L2]
    c, s = math.cos(alpha), math.sin(alpha)
    return -g1 * e * c, -g[G2] * alpha - g1 * c * s + g1 * ratio * c * sinc(alpha) * psi


@njit(cache=True, nogil=True)
def eta2_partials(psi, alpha, g):
    """(d eta2/dpsi, d eta2/dalpha) of (28); d eta2/de = 0 (see eta_partials)."""
    g1 = g[G1]
    ratio = g[L3] / g[L2]
    c, s = math.cos(alpha), math.sin(alpha)
    sc = sinc(alpha)
    d_cos_sinc = c * sinc_derivative(alpha) - s * sc
    return g1 * ratio * c * sc, -g[G2] - g1 * math.cos(2.0 * alpha) + g1 * ratio * psi * d_cos_sinc


@njit(cache=True, nogil=True)
def eta_partials(e, psi, alpha, g):
    """Jacobian d[eta1, eta2]/d[e, psi, alpha] of the law (27)-(28), shape (2, 3).

    d eta1/de = -gamma1 cos(alpha),  d eta1/dpsi = 0,  d eta1/dalpha = gamma1 e sin(alpha)
    d eta2/de = 0,  d eta2/dpsi = gamma1 (lambda3/lambda2) cos(alpha) sinc(alpha)
    d eta2/dalpha = -gamma2 - gamma1 cos(2 alpha)
                    + gamma1 (lambda3/lambda2) psi [cos(alpha) sinc'(alpha) - sin(alpha) sinc(alpha)]
    with sinc'(alpha) = (cos(alpha) - sinc(alpha))/alpha, taken from its series near 0.
    """
    g1 = g[G1]
    d2_dpsi, d2_dalpha = eta2_partials(psi, alpha, g)
    jac = np.zeros((2, 3))
    jac[0, 0], jac[0, 2] = -g1 * math.cos(alpha), g1 * e * math.sin(alpha)
    jac[1, 1], jac[1, 2] = d2_dpsi, d2_dalpha
    return jac


@njit(cache=True, nogil=True)
def eta_dot(e, psi, alpha, u1, u2, g):
    """d eta/dt along the real platform kinematics (30)-(32) with the actual velocity u.

    This is the eta_dot of (39)-(40): e1 = u1 - eta1 and e2 = u2 - eta2 (37)-(38) are not zero,
    so eta_dot contains them. By the chain rule and (30)-(32),
    eta1_dot = -gamma1 cos^2(alpha) u1 + gamma1 e sin(alpha) (-sin(alpha)/e u1 + u2)
             = -gamma1 u1 + gamma1 e sin(alpha) u2          (written so, the 1/e cancels exactly)
    eta2_dot = d eta2/dpsi * psi_dot + d eta2/dalpha * alpha_dot.
    Requires e > 0 (psi_dot and alpha_dot have 1/e).
    """
    g1 = g[G1]
    d2_dpsi, d2_dalpha = eta2_partials(psi, alpha, g)
    _, psi_dot, alpha_dot = polar_kinematics(e, alpha, u1, u2)
    return -g1 * u1 + g1 * e * math.sin(alpha) * u2, d2_dpsi * psi_dot + d2_dalpha * alpha_dot


@njit(cache=True, nogil=True)
def eta_dot_nominal(e, psi, alpha, g):
    """d eta/dt along the nominal closed loop u = eta, i.e. with e1 = e2 = 0 in (41)-(42).

    This is what the printed (51)-(52) contain (erratum 3 of docs/errata.md). On the nominal
    loop e_dot = -gamma1 e cos^2(alpha), psi_dot = -gamma1 sin(alpha) cos(alpha) and
    alpha_dot = -gamma2 alpha + gamma1 (lambda3/lambda2) cos(alpha) sinc(alpha) psi (42), which
    have no 1/e, so this is defined at e = 0 too.
    """
    g1 = g[G1]
    ratio = g[L3] / g[L2]
    c, s = math.cos(alpha), math.sin(alpha)
    d2_dpsi, d2_dalpha = eta2_partials(psi, alpha, g)
    e_dot = -g1 * e * c * c
    psi_dot = -g1 * s * c
    alpha_dot = -g[G2] * alpha + g1 * ratio * c * sinc(alpha) * psi
    return -g1 * c * e_dot + g1 * e * s * alpha_dot, d2_dpsi * psi_dot + d2_dalpha * alpha_dot
