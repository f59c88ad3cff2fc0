#!/usr/bin/env python3
"""Symbolic proof of the errata of the backstepping law (docs/errata.md), with sympy.

Run:  python docs/scripts/check_errata_symbolic.py     (prints PASS/FAIL lines, exit 1 on FAIL)
Tests import `run_checks()` from this file (tests/test_backstepping.py).

Every check derives dV1/dt of (43)-(44) along the model (30)-(34) for some input v and compares
it with the bound (48). "PASS" means the statement in the check's name was proven: for the
corrected law the residual simplifies to 0; for an erratum the printed expression is shown to
differ, with the exact difference.
"""

from __future__ import annotations

import random
import sys
from dataclasses import dataclass
from pathlib import Path

import sympy as sp

e, psi, alpha = sp.symbols("e psi alpha", real=True)
u1, u2 = sp.symbols("u1 u2", real=True)
g1, g2, g4, g5 = sp.symbols("gamma1 gamma2 gamma4 gamma5", positive=True)
l1, l2, l3, l4, l5 = sp.symbols("lambda1 lambda2 lambda3 lambda4 lambda5", positive=True)
GAINS = dict(
    gamma1=g1, gamma2=g2, gamma4=g4, gamma5=g5, lambda1=l1, lambda2=l2, lambda3=l3, lambda4=l4, lambda5=l5
)
c, s = sp.cos(alpha), sp.sin(alpha)
L = l3 / l2

# Kinematic law (27)-(28) and tracking errors (37)-(38).
eta1 = -g1 * e * c
eta2 = -g2 * alpha - g1 * c * s + g1 * L * c * s / alpha * psi
e1, e2 = u1 - eta1, u2 - eta2

# Model (30)-(32) with the actual u, and the nominal loop u = eta of (42) (e1 = e2 = 0).
RATES = {e: c * u1, psi: s / e * u1, alpha: -s / e * u1 + u2}
NOMINAL = {x: r.subs({u1: eta1, u2: eta2}, simultaneous=True) for x, r in RATES.items()}


def time_derivative(expr, rates):
    """d expr/dt by the chain rule over (e, psi, alpha) with the given rates."""
    return sum(sp.diff(expr, x) * r for x, r in rates.items())


eta1_dot = time_derivative(eta1, RATES)  # along (30)-(34): contains e1, e2
eta2_dot = time_derivative(eta2, RATES)
eta1_dot_nominal = time_derivative(eta1, NOMINAL)  # along u = eta
eta2_dot_nominal = time_derivative(eta2, NOMINAL)

V1 = (l1 * e**2 + l2 * alpha**2 + l3 * psi**2 + l4 * e1**2 + l5 * e2**2) / 2  # (43)
PREDICTED = -g1 * l1 * e**2 * c**2 - g2 * l2 * alpha**2 - g4 * l4 * e1**2 - g5 * l5 * e2**2  # (48)

# v_bar of (46)-(47): as needed (with e, erratum 1) and as printed in (46).
v_bar1 = -g4 * e1 - l1 / l4 * e * c + l2 / l4 * alpha * s / e - l3 / l4 * psi * s / e
v_bar1_printed_46 = -g4 * e1 - l1 / l4 * c + l2 / l4 * alpha * s / e - l3 / l4 * psi * s / e
v_bar2 = -g5 * e2 - l2 / l5 * alpha

# (51)-(52) transcribed term by term from the paper.
V1_PRINTED_51 = (
    -g4 * e1
    - l1 / l4 * c
    + l2 / l4 * alpha * s / e
    - g1**2 * e * c**3
    + g1 * g2 * e * alpha * s
    - g1**2 * L * e * c * s**2 / alpha * psi
)
V2_PRINTED_52 = (
    -g5 * e2
    - l2 / l5 * alpha
    - g2**2 * alpha
    + g1 * g2 * alpha * s**2
    - g1**2 * L * c * s**3 / alpha * psi
    - g1 * g2 * alpha * c**2
    + g1**2 * L * c**3 * s / alpha * psi
    - g1 * g2 * L * s**2 * psi
    + g1**2 * L**2 * c * s**3 / alpha**2 * psi**2
    + g1 * g2 * L * c**2 * psi
    - g1**2 * L**2 * c**3 * s / alpha**2 * psi**2
    + g1**2 * L**2 * c**2 * s**2 / alpha**3 * psi**2
    + g1**2 * L * c**2 * s**2 / alpha
)


def v1_dot(v1, v2):
    """dV1/dt along (30)-(34) with u_dot = v, by (44)."""
    return time_derivative(V1, RATES) + sp.diff(V1, u1) * v1 + sp.diff(V1, u2) * v2


def is_zero(expr) -> bool:
    """Exact zero test: expand as a polynomial in sin, cos and the symbols, then simplify."""
    expanded = sp.expand(expr)
    return expanded == 0 or sp.simplify(expanded) == 0


def numeric_value(expr, seed=0) -> float:
    """expr at a random point (all gains and e positive, alpha away from 0)."""
    rng = random.Random(seed)
    point = {x: rng.uniform(0.2, 2.0) for x in (e, *GAINS.values())}
    point |= {
        psi: rng.uniform(-2, 2),
        alpha: rng.uniform(0.3, 2.5),
        u1: rng.uniform(-1, 1),
        u2: rng.uniform(-1, 1),
    }
    return float(expr.subs(point).evalf())


@dataclass
class Check:
    name: str
    passed: bool
    detail: str


def _check_corrected_law():
    residual = v1_dot(v_bar1 + eta1_dot, v_bar2 + eta2_dot) - PREDICTED
    return Check(
        "corrected law v = v_bar + eta_dot gives V1_dot = (48) exactly",
        is_zero(residual),
        "residual simplifies to 0",
    )


def _check_kinematic_law_29():
    V = (l1 * e**2 + l2 * alpha**2 + l3 * psi**2) / 2
    residual = time_derivative(V, NOMINAL) - (-g1 * l1 * e**2 * c**2 - g2 * l2 * alpha**2)
    return Check(
        "(27)-(28) give (29) on the kinematic model (25)", is_zero(residual), "residual simplifies to 0"
    )


def _check_erratum_1():
    residual = v1_dot(v_bar1_printed_46 + eta1_dot, v_bar2 + eta2_dot) - PREDICTED
    expected = l1 * (e - 1) * c * e1
    proven = is_zero(residual - expected) and numeric_value(residual) != 0.0
    return Check(
        "erratum 1: (46) without e leaves V1_dot - (48) = lambda1 (e - 1) cos(alpha) e1",
        proven,
        "sign-indefinite (changes sign with e1 and at e = 1), so V1_dot is not <= 0",
    )


def _check_erratum_2():
    residual = v1_dot(v_bar1 - eta1_dot, v_bar2 - eta2_dot) - PREDICTED
    expected = -2 * (l4 * e1 * eta1_dot + l5 * e2 * eta2_dot)
    proven = is_zero(residual - expected) and numeric_value(residual) != 0.0
    return Check(
        "erratum 2: v = v_bar - eta_dot (49)-(50) leaves V1_dot - (48) = -2 (l4 e1 eta1_dot + l5 e2 eta2_dot)",
        proven,
        "the definitions (39)-(40) invert to v = v_bar + eta_dot",
    )


def _check_erratum_3():
    tail1 = V1_PRINTED_51 - (-g4 * e1 - l1 / l4 * c + l2 / l4 * alpha * s / e)
    tail2 = V2_PRINTED_52 - v_bar2
    nominal = is_zero(tail1 + eta1_dot_nominal) and is_zero(tail2 + eta2_dot_nominal)
    missing = sp.expand(eta1_dot - eta1_dot_nominal), sp.expand(eta2_dot - eta2_dot_nominal)
    differs = numeric_value(missing[0]) != 0.0 and numeric_value(missing[1]) != 0.0
    return Check(
        "erratum 3: the eta terms of (51)-(52) are -eta_dot along u = eta, without the e1, e2 parts",
        nominal and differs,
        "printed tails + eta_dot|u=eta simplify to 0; eta_dot - eta_dot|u=eta is non-zero",
    )


def _check_erratum_1b():
    printed_v_bar1_in_51 = V1_PRINTED_51 + eta1_dot_nominal
    difference = sp.simplify(printed_v_bar1_in_51 - v_bar1_printed_46)
    expected = l3 / l4 * psi * s / e
    return Check(
        "erratum 1b: (51) also drops the -(lambda3/lambda4) psi sin(alpha)/e term of (46)",
        is_zero(difference - expected),
        f"(51) - [(46) - eta1_dot|u=eta] = {difference}",
    )


def _check_printed_law_fails():
    residual = v1_dot(V1_PRINTED_51, V2_PRINTED_52) - PREDICTED
    value = numeric_value(residual)
    # At the goal (e -> 0, alpha = psi = 0, u = 0) the printed v1 is -lambda1/lambda4, not 0.
    at_goal = sp.limit(V1_PRINTED_51.subs({psi: 0, u1: 0, u2: 0}).subs(alpha, 0), e, 0)
    return Check(
        "printed law (51)-(52) violates (48), and the goal is not an equilibrium",
        value != 0.0 and sp.simplify(at_goal + l1 / l4) == 0,
        f"residual at a random state = {value:.4g}; printed v1 at the goal = {at_goal}",
    )


def _check_implementation():
    """The package's laws equal the sympy expressions above at random states."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "src"))
    from twil_control.control.backstepping import corrected_command, printed_command
    from twil_control.control.gains import validate_gains

    symbols = (e, psi, alpha, u1, u2, *GAINS.values())
    corrected = sp.lambdify(symbols, [v_bar1 + eta1_dot, v_bar2 + eta2_dot], "math")
    printed = sp.lambdify(symbols, [V1_PRINTED_51, V2_PRINTED_52], "math")
    worst = 0.0
    for seed in range(200):
        rng = random.Random(seed)
        gains = {k: rng.uniform(0.2, 3.0) for k in GAINS}
        # |alpha| >= 0.1: the transcribed expressions divide by powers of alpha.
        state = (
            rng.uniform(0.05, 3),
            rng.uniform(-3, 3),
            rng.choice((-1, 1)) * rng.uniform(0.1, 3),
            rng.uniform(-1, 1),
            rng.uniform(-1, 1),
        )
        values = (*state, *gains.values())
        args = (*state, validate_gains(gains).vector)
        for got, want in (
            (corrected_command(*args), corrected(*values)),
            (printed_command(*args), printed(*values)),
        ):
            for g, w in zip(got, want):
                worst = max(worst, abs(g - w) / max(1.0, abs(w)))
    return Check(
        "twil_control's corrected and printed laws equal these expressions",
        worst < 1e-10,
        f"worst relative difference {worst:.1e}",
    )


CHECKS = (
    _check_kinematic_law_29,
    _check_corrected_law,
    _check_erratum_1,
    _check_erratum_1b,
    _check_erratum_2,
    _check_erratum_3,
    _check_printed_law_fails,
    _check_implementation,
)


def run_checks() -> list[Check]:
    """Run every check; each returns Check(name, passed, detail)."""
    return [check() for check in CHECKS]


def main() -> int:
    results = run_checks()
    for result in results:
        print(f"{'PASS' if result.passed else 'FAIL'}  {result.name}\n      {result.detail}")
    return 0 if all(r.passed for r in results) else 1


if __name__ == "__main__":
    sys.exit(main())
