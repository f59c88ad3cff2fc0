"""move_base's typed parameters (names and defaults of ROS move_base, navfn and the recoveries);
the local planners' are in navigation/local_planner.py and dwa_planner.py, the costmaps' in
costmap_ros."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

from twil_control.errors import InputError

from .move_base_local import LOCAL_PLANNERS

GLOBAL_PLANNERS = {
    "navfn/NavfnROS": "grid",
    "global_planner/GlobalPlanner": "grid",
    "ompl_global_planner/OmplGlobalPlanner": "ompl",
}


@dataclass
class MoveBaseParams:
    ros_package: ClassVar[str] = "move_base"
    base_global_planner: str = "navfn/NavfnROS"
    base_local_planner: str = "base_local_planner/TrajectoryPlannerROS"
    controller_frequency: float = 20.0
    planner_frequency: float = 0.0
    planner_patience: float = 5.0
    controller_patience: float = 15.0
    max_planning_retries: int = -1
    oscillation_timeout: float = 0.0
    oscillation_distance: float = 0.5
    conservative_reset_dist: float = 3.0
    clearing_rotation_allowed: bool = True
    recovery_behavior_enabled: bool = True
    shutdown_costmaps: bool = False
    recovery_behaviors: list[dict] | None = None
    # this package's, not move_base's (off by default, as move_base): re-plan as soon as the global
    # costmap blocks the plan being followed; move_base follows it until the local planner fails,
    # which, with a map still being built, can be at the wall of a room planned through unseen
    replan_when_blocked: bool = False
    # sub-namespaces, read with their own schemas
    global_costmap: dict = field(default_factory=dict)
    local_costmap: dict = field(default_factory=dict)
    TrajectoryPlannerROS: dict = field(default_factory=dict)
    DWAPlannerROS: dict = field(default_factory=dict)
    BacksteppingLocalPlanner: dict = field(default_factory=dict)
    NavfnROS: dict = field(default_factory=dict)
    GlobalPlanner: dict = field(default_factory=dict)
    OmplGlobalPlanner: dict = field(default_factory=dict)
    conservative_reset: dict = field(default_factory=dict)
    aggressive_reset: dict = field(default_factory=dict)
    rotate_recovery: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.base_global_planner not in GLOBAL_PLANNERS:
            raise InputError(
                f"base_global_planner {self.base_global_planner!r} is not available; allowed: "
                f"{', '.join(GLOBAL_PLANNERS)}"
            )
        if self.base_local_planner not in LOCAL_PLANNERS:
            raise InputError(
                f"base_local_planner {self.base_local_planner!r} is not available; allowed: "
                f"{', '.join(LOCAL_PLANNERS)}"
            )
        if not LOCAL_PLANNERS[self.base_local_planner].commands_velocity and self.clearing_rotation_allowed:
            raise InputError(
                "clearing_rotation_allowed must be false with base_local_planner "
                "twil_control/BacksteppingLocalPlanner: the rotate recovery turns in place by velocity, "
                "and the backstepping law takes poses (a pose with the same position is its goal, "
                "where it brakes)"
            )
        if not self.controller_frequency > 0:
            raise InputError(f"controller_frequency must be > 0 Hz (got {self.controller_frequency})")
        for name in (
            "planner_frequency",
            "planner_patience",
            "controller_patience",
            "oscillation_timeout",
            "oscillation_distance",
            "conservative_reset_dist",
        ):
            if getattr(self, name) < 0:
                raise InputError(f"{name} must be >= 0 (got {getattr(self, name)})")


@dataclass
class GridPlannerParams:
    """navfn's (and global_planner's) names; cost_factor and lethal_cost are global_planner's."""

    ros_package: ClassVar[str] = "navfn"

    allow_unknown: bool = True
    default_tolerance: float = 0.0
    visualize_potential: bool = False
    planner_window_x: float = 0.0
    planner_window_y: float = 0.0
    cost_factor: float = 3.0
    lethal_cost: int = 253
    neutral_cost: int = 50
    use_dijkstra: bool = True
    use_grid_path: bool = True
    old_navfn_behavior: bool = False

    def __post_init__(self) -> None:
        if self.cost_factor < 0:
            raise InputError(f"cost_factor must be >= 0 (got {self.cost_factor})")
        if not 1 <= self.lethal_cost <= 254:
            raise InputError(f"lethal_cost must be in 1..254 (got {self.lethal_cost})")


@dataclass
class ClearCostmapParams:
    ros_package: ClassVar[str] = "clear_costmap_recovery"
    reset_distance: float = 3.0
    layer_names: list[str] = field(default_factory=lambda: ["obstacle_layer"])
    affected_maps: str = "both"

    def __post_init__(self) -> None:
        if self.affected_maps not in ("both", "global", "local"):
            raise InputError(f"affected_maps must be one of both, global, local (got {self.affected_maps!r})")


@dataclass
class RotateRecoveryParams:
    ros_package: ClassVar[str] = "rotate_recovery"
    frequency: float = 20.0
    sim_granularity: float = 0.017
    # not in ROS (whose rotation never gives up): a rotation that has not turned a full circle in
    # this many seconds ends, so a robot that cannot turn does not hang move_base
    timeout: float = 60.0
