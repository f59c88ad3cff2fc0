"""move_base's local planners, each behind one interface (nav_core::BaseLocalPlanner) and chosen by
its plugin name from LOCAL_PLANNERS, as ~base_local_planner names it: base_local_planner's and
dwa_local_planner's sampling planners (a Twist on cmd_vel), or the TWIL platform's waypoint
follower (a pose reference for the cart_linearizing_controller's backstepping law)."""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

import numpy as np

from ..core.tf import TfError
from ..navigation.backstepping_planner import BacksteppingPlannerParams, WaypointFollower
from ..navigation.dwa_planner import DWAParams, DWAPlanner
from ..navigation.local_planner import LocalController, LocalPlannerError, SamplingPlanner, TrajectoryPlanner
from .cart_command_output import CartCommandOutput

if TYPE_CHECKING:
    from .move_base import MoveBase


@dataclass
class LocalStep:
    """One control cycle's outcome: the goal is reached, or a command was sent (valid), with the
    local plan to show on ~<ns>/local_plan."""

    goal_reached: bool = False
    valid: bool = False
    path: np.ndarray | None = None


class LocalPlanner(Protocol):
    """What move_base asks of its local planner."""

    #: its parameter namespace (~<ns>/...), where it also publishes local_plan
    ns: str
    #: its parameters (move_base's advice reads them)
    params: Any
    #: whether it commands velocities (cmd_vel), which a rotate recovery needs
    commands_velocity: ClassVar[bool]

    def prunes_plan(self) -> bool:
        """Whether the plan behind the robot is dropped before each cycle."""
        ...

    def compute(self, nav: MoveBase, pose, plan: np.ndarray, period: float) -> LocalStep:
        """One control cycle at `pose` along `plan` (both in the local costmap's frame); sends
        the command when it has a valid one."""
        ...

    def stop(self, nav: MoveBase) -> None:
        """Stop the robot (a zero Twist, or hold the pose)."""
        ...

    def reset(self) -> None:
        """A new goal."""
        ...

    def new_plan(self) -> None:
        """A new global plan."""
        ...


class VelocityPlanner:
    """TrajectoryPlannerROS or DWAPlannerROS: LocalController around a sampling planner."""

    commands_velocity: ClassVar[bool] = True

    def __init__(self, ns: str, params: Any, planner: SamplingPlanner) -> None:
        self.ns, self.params, self.planner = ns, params, planner
        self.controller = LocalController(planner)

    def prunes_plan(self) -> bool:
        return self.params.prune_plan

    def compute(self, nav: MoveBase, pose, plan: np.ndarray, period: float) -> LocalStep:
        costmap = nav.local_costmap.costmap.master
        try:
            out = self.controller.compute(costmap, pose, nav.velocity, plan, period)
        except LocalPlannerError as exc:
            nav.log_once(logging.WARNING, "local-plan", f"local planner: {exc}")
            return LocalStep()
        if out.goal_reached:
            return LocalStep(goal_reached=True)
        if out.valid:
            nav.publish_cmd(*out.cmd)
        return LocalStep(valid=out.valid, path=out.trajectory)

    def stop(self, nav: MoveBase) -> None:
        nav.publish_cmd(0.0, 0.0)

    def reset(self) -> None:
        self.controller.reset()

    def new_plan(self) -> None:
        self.planner.new_plan()


class TrajectoryPlannerROS(VelocityPlanner):
    @classmethod
    def load(cls, nav: MoveBase) -> TrajectoryPlannerROS:
        cells = nav.local_costmap.costmap.cells
        planner = TrajectoryPlanner(nav.traj_params, cells, nav.sim_period(nav.traj_params))
        return cls("TrajectoryPlannerROS", nav.traj_params, planner)


class DWAPlannerROS(VelocityPlanner):
    @classmethod
    def load(cls, nav: MoveBase) -> DWAPlannerROS:
        params = nav.typed_params(DWAParams, "~DWAPlannerROS")
        planner = DWAPlanner(params, nav.local_costmap.costmap.cells, nav.sim_period(params))
        return cls("DWAPlannerROS", params, planner)


class BacksteppingLocalPlanner:
    """The TWIL platform's waypoint follower: the cart controller's reference pose, no cmd_vel."""

    commands_velocity: ClassVar[bool] = False

    def __init__(self, traj_params: Any, params: BacksteppingPlannerParams, cart: CartCommandOutput) -> None:
        # what move_base's advice reads is TrajectoryPlannerROS's (the rotate recovery's, unused here)
        self.ns, self.params = "TrajectoryPlannerROS", traj_params
        self.follower, self.cart = WaypointFollower(params), cart

    @classmethod
    def load(cls, nav: MoveBase) -> BacksteppingLocalPlanner:
        params = nav.typed_params(BacksteppingPlannerParams, "~BacksteppingLocalPlanner")
        return cls(nav.traj_params, params, CartCommandOutput(nav, params, nav.tf))

    def prunes_plan(self) -> bool:
        return True

    def compute(self, nav: MoveBase, pose, plan: np.ndarray, period: float) -> LocalStep:
        lc = nav.local_costmap
        ref = self.follower.compute(lc.costmap.master, pose, plan)
        if ref.goal_reached:
            return LocalStep(goal_reached=True)
        if ref.pose is not None:
            self.cart.send(ref.pose, lc.params.global_frame)
            return LocalStep(valid=True, path=np.array([pose, ref.pose]))
        nav.log_once(
            logging.WARNING,
            "no-waypoint",
            "BacksteppingLocalPlanner: no waypoint of the plan is "
            "reachable in a straight line clear of the inscribed zone",
        )
        return LocalStep()

    def stop(self, nav: MoveBase) -> None:
        frame = nav.local_costmap.params.global_frame
        try:
            self.cart.stop(nav.local_costmap.robot_pose(), frame)
        except TfError as exc:
            nav.log_once(
                logging.WARNING, "no-stop-pose", f"cannot hold the platform: no pose in {frame}: {exc}"
            )

    def reset(self) -> None:
        self.follower.reset()
        self.cart.latch_arm()

    def new_plan(self) -> None:
        pass


#: ~base_local_planner -> the planner's class (its load(move_base) reads its parameters)
LOCAL_PLANNERS: dict[str, type[TrajectoryPlannerROS | DWAPlannerROS | BacksteppingLocalPlanner]] = {
    "base_local_planner/TrajectoryPlannerROS": TrajectoryPlannerROS,
    "dwa_local_planner/DWAPlannerROS": DWAPlannerROS,
    "twil_control/BacksteppingLocalPlanner": BacksteppingLocalPlanner,
}
