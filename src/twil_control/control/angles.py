"""Angle helpers shared by the platform laws: wrapping and the sinc function.

The polar coordinates (20)-(22) are angles and must be wrapped to (-pi, pi]; the kinematic law
(28) contains sin(alpha)/alpha, which is a sinc and equals 1 at alpha = 0. Its derivative is
needed by the backstepping law (49)-(52) and is evaluated by a series near 0, where the closed
form cancels catastrophically.

Every function accepts a float or an array. A float in gives a float out (the controller calls
these at 1 kHz, and numpy scalars are slow), an array in gives an array out.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["wrap_angle", "sinc", "sinc_derivative"]

_TWO_PI = 2.0 * math.pi

# Below this |x| the Taylor series of sin(x)/x is used: the first omitted term, x**6/5040, is
# then below 3e-28, far under one ulp of the value 1.
_SINC_SERIES_LIMIT = 1e-4
# Below this |x| the derivative of sinc is taken from its series. The closed form
# (x cos x - sin x)/x**2 loses about log10(3/x**2) digits to cancellation; at 0.5 it still has
# 15 good digits, and the series truncated after x**13 is exact to 1e-18 there.
_DSINC_SERIES_LIMIT = 0.5


def _wrap_scalar(a: float) -> float:
    wrapped = math.fmod(a + math.pi, _TWO_PI)
    if wrapped < 0.0:
        wrapped += _TWO_PI
    # fmod puts a = -pi (and pi) at 0, i.e. at -pi after the shift back; (-pi, pi] wants +pi.
    result = wrapped - math.pi
    return math.pi if result <= -math.pi else result


def wrap_angle(a):
    """Wrap an angle (rad) to the interval (-pi, pi], as the polar coordinates (21)-(22) need.

    pi stays pi and -pi becomes pi. Vectorised: arrays are wrapped element by element.
    """
    if isinstance(a, (float, int)) and not isinstance(a, bool):
        return _wrap_scalar(float(a))
    arr = np.asarray(a, dtype=float)
    wrapped = np.mod(arr + np.pi, _TWO_PI) - np.pi
    wrapped = np.where(wrapped <= -np.pi, np.pi, wrapped)
    return wrapped if wrapped.ndim else float(wrapped)


def _sinc_scalar(x: float) -> float:
    if abs(x) < _SINC_SERIES_LIMIT:
        x2 = x * x
        return 1.0 - x2 / 6.0 * (1.0 - x2 / 20.0)
    return math.sin(x) / x


def sinc(x):
    """sin(x)/x with value 1 at x = 0: the sin(alpha)/alpha factor of the kinematic law (28).

    Uses the Taylor series for |x| < 1e-4, so the result is accurate to one ulp near 0.
    Unnormalised (numpy's np.sinc is sin(pi x)/(pi x)). Vectorised.
    """
    if isinstance(x, (float, int)) and not isinstance(x, bool):
        return _sinc_scalar(float(x))
    arr = np.asarray(x, dtype=float)
    small = np.abs(arr) < _SINC_SERIES_LIMIT
    safe = np.where(small, 1.0, arr)
    x2 = arr * arr
    result = np.where(small, 1.0 - x2 / 6.0 * (1.0 - x2 / 20.0), np.sin(safe) / safe)
    return result if result.ndim else float(result)


# d/dx sum_k (-1)^k x^(2k)/(2k+1)! = sum_{k>=1} (-1)^k 2k x^(2k-1)/(2k+1)!
_DSINC_COEFFS = tuple((-1) ** k * 2 * k / math.factorial(2 * k + 1) for k in range(1, 8))


def _dsinc_series(x, x2):
    # Horner in x**2, highest power first.
    acc = 0.0 * x2
    for coeff in reversed(_DSINC_COEFFS):
        acc = acc * x2 + coeff
    return acc * x


def _sinc_derivative_scalar(x: float) -> float:
    if abs(x) < _DSINC_SERIES_LIMIT:
        return _dsinc_series(x, x * x)
    return (math.cos(x) - math.sin(x) / x) / x


def sinc_derivative(x):
    """d/dx [sin(x)/x] = (cos x - sin(x)/x)/x, with value 0 at x = 0.

    Needed for d(eta2)/d(alpha) of the kinematic law (28) inside the backstepping law (49)-(52),
    and for the printed (52), whose terms cos^2 sin^2/alpha^3 - cos^3 sin/alpha^2 combine into
    -cos^2(alpha) sinc(alpha) sinc'(alpha). Series (to x**13) for |x| < 0.5. Vectorised.
    """
    if isinstance(x, (float, int)) and not isinstance(x, bool):
        return _sinc_derivative_scalar(float(x))
    arr = np.asarray(x, dtype=float)
    small = np.abs(arr) < _DSINC_SERIES_LIMIT
    safe = np.where(small, 1.0, arr)
    closed = (np.cos(safe) - np.sin(safe) / safe) / safe
    result = np.where(small, _dsinc_series(arr, arr * arr), closed)
    return result if result.ndim else float(result)
