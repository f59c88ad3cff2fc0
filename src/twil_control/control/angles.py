"""Angle helpers shared by the platform laws: wrapping and the sinc function.

The polar coordinates (20)-(22) are angles and must be wrapped to (-pi, pi]; the kinematic law
(28) contains sin(alpha)/alpha, which is a sinc and equals 1 at alpha = 0. Its derivative is
needed by the backstepping law (49)-(52) and is evaluated by a series near 0, where the closed
form cancels catastrophically.

Each function is compiled (numba) for floats: the Python API and the compiled control kernels
call the same functions.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["wrap_angle", "sinc", "sinc_derivative"]

_TWO_PI = 2.0 * math.pi

# Below this |x| the Taylor series of sin(x)/x is used: the first omitted term, x**6/5040, is
# then below 3e-28, far under one ulp of the value 1.
_SINC_SERIES_LIMIT = 1e-4
# Below this |x| the derivative of sinc is taken from its series. The closed form
# (x cos x - sin x)/x**2 loses about log10(3/x**2) digits to cancellation; at 0.5 it still has
# 15 good digits, and the series truncated after x**13 is exact to 1e-18 there.
_DSINC_SERIES_LIMIT = 0.5
# d/dx sum_k (-1)^k x^(2k)/(2k+1)! = sum_{k>=1} (-1)^k 2k x^(2k-1)/(2k+1)!, k = 1..7
_DSINC_COEFFS = tuple((-1) ** k * 2 * k / math.factorial(2 * k + 1) for k in range(1, 8))


@njit(cache=True, nogil=True)
def wrap_angle(a):
    """An angle (rad) wrapped to (-pi, pi], as the polar coordinates (21)-(22) need: pi stays pi
    and -pi becomes pi."""
    wrapped = np.fmod(a + math.pi, _TWO_PI)  # C fmod (numba has no math.fmod)
    if wrapped < 0.0:
        wrapped += _TWO_PI
    # fmod puts a = -pi (and pi) at 0, i.e. at -pi after the shift back; (-pi, pi] wants +pi.
    result = wrapped - math.pi
    return math.pi if result <= -math.pi else result


@njit(cache=True, nogil=True)
def sinc(x):
    """sin(x)/x with value 1 at x = 0: the sin(alpha)/alpha factor of the kinematic law (28).

    Uses the Taylor series for |x| < 1e-4, so the result is accurate to one ulp near 0.
    Unnormalised (numpy's np.sinc is sin(pi x)/(pi x)).
    """
    if abs(x) < _SINC_SERIES_LIMIT:
        x2 = x * x
        return 1.0 - x2 / 6.0 * (1.0 - x2 / 20.0)
    return math.sin(x) / x


@njit(cache=True, nogil=True)
def sinc_derivative(x):
    """d/dx [sin(x)/x] = (cos x - sin(x)/x)/x, with value 0 at x = 0.

    Needed for d(eta2)/d(alpha) of the kinematic law (28) inside the backstepping law (49)-(52),
    and for the printed (52), whose terms cos^2 sin^2/alpha^3 - cos^3 sin/alpha^2 combine into
    -cos^2(alpha) sinc(alpha) sinc'(alpha). Series (to x**13, Horner in x**2) for |x| < 0.5.
    """
    if abs(x) < _DSINC_SERIES_LIMIT:
        x2 = x * x
        acc = 0.0
        for k in range(len(_DSINC_COEFFS) - 1, -1, -1):
            acc = acc * x2 + _DSINC_COEFFS[k]
        return acc * x
    return (math.cos(x) - math.sin(x) / x) / x
