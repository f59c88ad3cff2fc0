"""Warnings at load about move_base parameters that are valid ROS but that the robot move_base
drives cannot live with: which parameter (and the file:line that set it), why, and what this
project's own configuration uses instead. The values are used as ROS would use them: a user's
file that ran on a real robot loads unmodified, and its effect shows in the run.

The robot is the one move_base's cmd_vel reaches: the ros_control controller whose
``cmd_vel_topic`` parameter names that topic. Its velocity limits bound max_vel_x and
max_vel_theta; when it is the simulated qbot's skid-steer drive, the qbot's known needs (from
config/ and the README's qbot section) apply too.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np

from twil_control import PACKAGE_ROOT
from twil_control.core import names
from twil_control.core.yaml_io import load_yaml
from twil_control.navigation.footprint import parse_footprint, radii

SKID_STEER = "twil_control/SkidSteerPwmController"
PLANNER_FILE = "config/base_local_planner_params.yaml"
COSTMAP_FILE = "config/costmap_common_params.yaml"
MOVE_BASE_FILE = "config/move_base_params.yaml"


@dataclass(frozen=True)
class Drive:
    """The controller move_base's cmd_vel reaches."""

    namespace: str
    type: str
    max_linear: float | None
    max_angular: float | None


def find_drive(server, cmd_vel_topic: str) -> Drive | None:
    """The controller (namespace and type) whose cmd_vel_topic is ``cmd_vel_topic``, if any."""
    for name in server.names():
        if names.basename(name) != "cmd_vel_topic" or server.get(name) != cmd_vel_topic:
            continue
        ns = names.namespace_of(name)
        config = server.get(ns)

        def limit(axis: str, direction: str) -> float | None:
            block = config.get(axis, {}).get(direction, {})
            if isinstance(block, dict) and block.get("has_velocity_limits"):
                return float(block.get("max_velocity"))
            return None

        return Drive(ns, str(config.get("type", "")), limit("linear", "x"), limit("angular", "z"))
    return None


def _project(file: str, *keys: str) -> Any:
    data = load_yaml(PACKAGE_ROOT / file)
    for key in keys:
        data = data[key]
    return data


def advice(node, move_base_params, planner_ns: str, local, costmaps) -> list[str]:
    """The warnings for move_base ``node``: its typed params, its local planner's namespace
    (TrajectoryPlannerROS or DWAPlannerROS) and typed params, and its (global, local) CostmapSetups."""
    server = node.master.params
    drive = find_drive(server, node.resolve("cmd_vel"))
    out: list[str] = []
    dwa = planner_ns == "DWAPlannerROS"

    def warn(param: str, value: Any, why: str, instead: str) -> None:
        full = names.join(node.fqn, param)
        source = server.source_of(full)
        where = f" ({source})" if source else " (not set: the default)"
        out.append(f"{full} = {value}{where}: {why}; {instead}")

    planner = planner_ns + "/"
    tp = _project(PLANNER_FILE, "TrajectoryPlannerROS")
    if not dwa and local.min_vel_theta > 0:
        warn(
            planner + "min_vel_theta",
            local.min_vel_theta,
            "TrajectoryPlanner samples rotational velocities in [min_vel_theta, max_vel_theta] "
            "(min_vel_theta is the right-turn limit, default -1.0), so the robot never turns "
            "right: it turns left the long way round",
            f"{PLANNER_FILE} uses {tp['min_vel_theta']}",
        )
    if drive is None:
        return out
    if drive.max_linear is not None and local.max_vel_x > drive.max_linear + 1e-9:
        warn(
            planner + "max_vel_x",
            local.max_vel_x,
            f"the drive {drive.namespace} limits linear speed to {drive.max_linear} m/s, so the "
            f"rollouts at faster speeds predict motion the robot does not make",
            f"{PLANNER_FILE} uses {tp['max_vel_x']}",
        )
    if drive.max_angular is not None and local.max_vel_theta > drive.max_angular + 1e-9:
        warn(
            planner + "max_vel_theta",
            local.max_vel_theta,
            f"the drive {drive.namespace} limits the turn rate to {drive.max_angular} rad/s",
            f"{PLANNER_FILE} uses {tp['max_vel_theta']}",
        )
    if drive.type != SKID_STEER:
        return out
    qbot = "qbot's skid-steer wheels scrub sideways when it turns"
    in_place = "min_vel_theta" if dwa else "min_in_place_vel_theta"
    if local.min_turn_in_place < tp["min_in_place_vel_theta"]:
        warn(
            planner + in_place,
            getattr(local, in_place),
            f"{qbot}: commanded to turn in place below about 1 rad/s it turns at a fraction of "
            f"the command or not at all, so slow in-place turns never finish",
            f"{PLANNER_FILE} uses {'TrajectoryPlannerROS with min_in_place_vel_theta ' if dwa else ''}"
            f"{tp['min_in_place_vel_theta']}",
        )
    if not dwa and local.rotate_to_heading_threshold <= 0:
        warn(
            planner + "rotate_to_heading_threshold",
            local.rotate_to_heading_threshold,
            f"{qbot}, and gentle arcs barely turn it, so it does not follow a plan that bends "
            f"unless it first turns in place towards it (a parameter of this package, not of "
            f"TrajectoryPlanner)",
            f"{PLANNER_FILE} uses {tp['rotate_to_heading_threshold']}",
        )
    window = "use_dwa" if dwa else "dwa"
    if getattr(local, window):
        warn(
            planner + window,
            getattr(local, window),
            "DWA samples only what one control period's acceleration reaches, so a turn qbot "
            "has started can only be continued, not reconsidered",
            f"{PLANNER_FILE} uses {'TrajectoryPlannerROS with dwa ' if dwa else ''}{tp['dwa']}",
        )
    common = _project(COSTMAP_FILE)
    robot = parse_footprint(common["footprint"])
    _, robot_radius = radii(robot)
    for label, setup in zip(("global_costmap", "local_costmap"), costmaps):
        fp = setup.footprint
        if not _covers(fp, robot):
            shown = setup.params.footprint  # as written (the polygon used is padded)
            extent = np.abs(robot).max(axis=0)
            warn(
                f"{label}/footprint",
                shown,
                f"it leaves out part of the robot: qbot's wheels reach +-{extent[0]:g} x "
                f"+-{extent[1]:g} m, so plans pass where the wheels hit",
                f"{COSTMAP_FILE} uses {common['footprint']}",
            )
        radius = setup.layers.inflation_radius
        if setup.layers.inflation and radius < robot_radius - 1e-9:
            warn(
                f"{label}/inflation_radius",
                radius,
                f"below the radius qbot sweeps when it turns in place ({robot_radius:.3f} m), so "
                f"plans hug walls and corners where it can neither turn nor pass",
                f"{COSTMAP_FILE} uses {common['inflation_radius']}",
            )
    timeout = _project(MOVE_BASE_FILE, "oscillation_timeout")
    if move_base_params.oscillation_timeout == 0 and timeout > 0:
        warn(
            "oscillation_timeout",
            move_base_params.oscillation_timeout,
            "0 never notices a robot that is stuck while its local planner keeps finding tiny "
            "valid commands (a qbot turning too slowly to turn), so a goal can hang forever",
            f"{MOVE_BASE_FILE} uses {timeout}",
        )
    return out


def _covers(polygon: np.ndarray, robot: np.ndarray) -> bool:
    """Whether ``polygon`` contains every vertex of ``robot`` (within 1 mm)."""
    contour = polygon.astype(np.float32).reshape(-1, 1, 2)
    return all(cv2.pointPolygonTest(contour, (float(x), float(y)), True) >= -1e-3 for x, y in robot)
