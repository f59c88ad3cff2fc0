"""The gains of the platform laws (27)-(28), (43) and (46)-(47), checked once.

The compiled equations take the gains as one float array `g` in GAIN_NAMES order (numba cannot
read a mapping); G1 .. L5 are its indices. `validate_gains` checks a mapping of them and
`BacksteppingGains.vector` is that array.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field

import numpy as np

from twil_control.errors import InputError

__all__ = [
    "GAIN_NAMES",
    "G1",
    "G2",
    "G4",
    "G5",
    "L1",
    "L2",
    "L3",
    "L4",
    "L5",
    "BacksteppingGains",
    "validate_gains",
]

GAIN_NAMES = ("gamma1", "gamma2", "gamma4", "gamma5", "lambda1", "lambda2", "lambda3", "lambda4", "lambda5")
G1, G2, G4, G5, L1, L2, L3, L4, L5 = range(9)


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
    vector: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        vector = np.array([getattr(self, k) for k in GAIN_NAMES], dtype=float)
        vector.flags.writeable = False
        object.__setattr__(self, "vector", vector)

    def __getitem__(self, key: str) -> float:
        if key not in GAIN_NAMES:
            raise KeyError(key)
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
        raise InputError(f"unknown backstepping gains {unknown}; allowed: {list(GAIN_NAMES)}")
    values = {}
    for key in GAIN_NAMES:
        try:
            value = float(gains[key])
        except (TypeError, ValueError) as err:
            raise InputError(f"backstepping gain {key}={gains[key]!r} is not a number") from err
        if not (math.isfinite(value) and value > 0.0):
            raise InputError(f"backstepping gain {key}={value} must be finite and > 0")
        values[key] = value
    return BacksteppingGains(**values)
