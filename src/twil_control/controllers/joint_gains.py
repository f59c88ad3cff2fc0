"""Per-joint gains as controller parameters (Kp, Kd): one number for every joint, or a list of
one per joint; every number finite and >= 0 (control.computed_torque.joint_gains)."""

from __future__ import annotations

import numpy as np

from twil_control.control.computed_torque import joint_gains
from twil_control.core.param_rules import param


def gains_param(default: float):
    """The schema field of a per-joint gain."""
    return param(default, ge=0)


def per_joint(nh, name: str, value, joints: list[str]) -> np.ndarray:
    """The gain of each joint from parameter `name` (under NodeHandle `nh`), already checked by
    its schema field; a list of the wrong length is a ParamError naming where it was set."""
    n = len(joints)
    if isinstance(value, list) and len(value) != n:
        raise nh.param_error(
            name,
            f"must be one number for all {n} joints or a list of {n}, one per joint ({', '.join(joints)})",
        )
    return joint_gains(value, n, name)
