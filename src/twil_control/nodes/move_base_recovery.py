"""move_base's recovery behaviours, each behind one interface (nav_core::RecoveryBehavior) and
chosen by its plugin type from RECOVERY_BEHAVIORS, as ~recovery_behaviors names them."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np

from ..core.tf import TfError
from ..navigation.local_planner import SamplingPlanner
from .move_base_local import VelocityPlanner
from .move_base_params import ClearCostmapParams, RotateRecoveryParams

if TYPE_CHECKING:
    from .move_base import MoveBase


class RecoveryBehavior(Protocol):
    """One recovery behaviour of a move_base, run once per control cycle while it lasts."""

    name: str

    def run(self, nav: MoveBase, now: float, period: float) -> bool:
        """One control cycle of the behaviour; False when it is over."""
        ...

    def reset(self) -> None:
        """Forget a run in progress (a new goal)."""
        ...


class ClearCostmapRecovery:
    """clear_costmap_recovery: the costmaps forget what lies beyond reset_distance, at once."""

    def __init__(self, name: str, cfg: ClearCostmapParams) -> None:
        self.name, self.cfg = name, cfg

    @classmethod
    def load(cls, nav: MoveBase, name: str) -> ClearCostmapRecovery:
        p, cfg = nav.params, nav.typed_params(ClearCostmapParams, f"~{name}")
        if name == "conservative_reset" and "reset_distance" not in p.conservative_reset:
            cfg.reset_distance = p.conservative_reset_dist
        if name == "aggressive_reset" and "reset_distance" not in p.aggressive_reset:
            cfg.reset_distance = 4 * nav.local_costmap.costmap.circumscribed_radius
        return cls(name, cfg)

    def run(self, nav: MoveBase, now: float, period: float) -> bool:
        cfg = self.cfg
        nav.log.info("recovery %s: clearing the costmaps beyond %.2f m", self.name, cfg.reset_distance)
        for which, cmap in (("global", nav.global_costmap), ("local", nav.local_costmap)):
            if cfg.affected_maps in (which, "both"):
                try:
                    x, y, _ = cmap.robot_pose()
                except TfError:
                    continue
                cmap.costmap.reset_beyond(x, y, cfg.reset_distance)
                cmap.update()
        return False

    def reset(self) -> None:
        pass


@dataclass
class Rotation:
    """A rotate recovery in progress."""

    start: float
    last_yaw: float
    turned: float = 0.0


class RotateRecovery:
    """rotate_recovery: a full turn in place, stopped where the footprint would hit something."""

    def __init__(self, name: str, cfg: RotateRecoveryParams, planner: SamplingPlanner) -> None:
        self.name, self.cfg = name, cfg
        self.planner = planner  # the local planner's, whose footprint check stops the turn
        self.rotation: Rotation | None = None

    @classmethod
    def load(cls, nav: MoveBase, name: str) -> RotateRecovery | None:
        cfg = nav.typed_params(RotateRecoveryParams, f"~{name}")
        local = nav.local
        if not (nav.params.clearing_rotation_allowed and isinstance(local, VelocityPlanner)):
            return None
        return cls(name, cfg, local.planner)

    def reset(self) -> None:
        self.rotation = None

    def run(self, nav: MoveBase, now: float, period: float) -> bool:
        cfg = self.cfg
        try:
            x, y, yaw = nav.local_costmap.robot_pose()
        except TfError:
            return False
        # rotate_recovery stops where the footprint would hit something within the next
        # sim_granularity-spaced headings up to a quarter turn ahead
        ahead = yaw + np.arange(0.0, math.pi / 2, cfg.sim_granularity)
        if (
            nav.local_costmap.costmap.updated
            and not self.planner.checker(nav.local_costmap.costmap.master).trajectories(
                np.column_stack([np.full(len(ahead), x), np.full(len(ahead), y), ahead])[None]
            )[0][0]
        ):
            nav.log.info("recovery: rotation stopped, the footprint would hit an obstacle")
            nav.publish_cmd(0.0, 0.0)
            self.rotation = None
            return False
        if self.rotation is None:
            nav.log.info("recovery: rotating in place")
            self.rotation = Rotation(now, yaw)
        r = self.rotation
        r.turned += abs(math.remainder(yaw - r.last_yaw, 2 * math.pi))
        r.last_yaw = yaw
        left = 2 * math.pi - r.turned
        tp = nav.traj_params
        if left <= tp.yaw_goal_tolerance or now - r.start > cfg.timeout:
            nav.publish_cmd(0.0, 0.0)
            self.rotation = None
            return False
        w = min(tp.max_vel_theta, max(tp.min_in_place_vel_theta, math.sqrt(2 * tp.acc_lim_theta * left)))
        w = min(w, nav.velocity[1] + tp.acc_lim_theta * period)
        nav.publish_cmd(0.0, w)
        return True


#: plugin type -> the behaviour built from its ~name parameters (None: not run, e.g. a rotation
#: with clearing_rotation_allowed false)
RECOVERY_BEHAVIORS: dict[str, Callable[[MoveBase, str], RecoveryBehavior | None]] = {
    "clear_costmap_recovery/ClearCostmapRecovery": ClearCostmapRecovery.load,
    "rotate_recovery/RotateRecovery": RotateRecovery.load,
}
