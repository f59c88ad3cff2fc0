"""Node types by their launch-file name ``pkg/type`` (what roslaunch finds with rospack).

Built-in types map to ``module:Class`` strings and are imported only when a launch uses them,
so a launch without a simulated world never imports Drake. Packages outside this one add node
types through the entry-point group ``twil_control.nodes`` (name ``pkg/type``, value
``module:Class``). Viewers and GUIs (``rviz``, ``gazebo_ros/gzclient``, ``rqt_*``,
``image_view``) are display nodes (nodes/display.py): known, and run nowhere.
"""

from __future__ import annotations

import importlib
from importlib.metadata import entry_points

from twil_control.errors import TwilControlError

ENTRY_POINT_GROUP = "twil_control.nodes"

BUILTIN = {
    "twil_control/drake_world": "twil_control.gazebo.gzserver:DrakeWorld",
    "gazebo_ros/gzserver": "twil_control.gazebo.gzserver:DrakeWorld",
    "gazebo_ros/gazebo": "twil_control.gazebo.gzserver:DrakeWorld",
    "gazebo_ros/debug": "twil_control.gazebo.gzserver:DrakeWorld",  # gzserver under gdb in ROS
    "gazebo_ros/spawn_model": "twil_control.gazebo.spawn_model:SpawnModel",
    "twil_control/robot_hw_sim": "twil_control.gazebo.robot_hw_sim_node:RobotHWSimNode",
    "twil_control/ground_truth": "twil_control.gazebo.ground_truth:GroundTruth",
    "twil_control/laser": "twil_control.gazebo.laser_node:Laser",
    "map_server/map_server": "twil_control.nodes.map_server:MapServer",
    "map_server/map_saver": "twil_control.nodes.map_saver:MapSaver",
    "twil_control/wheel_odometry": "twil_control.nodes.wheel_odometry:WheelOdometryNode",
    "robot_state_publisher/robot_state_publisher": "twil_control.nodes.robot_state_publisher:RobotStatePublisher",
    "robot_state_publisher/state_publisher": "twil_control.nodes.robot_state_publisher:RobotStatePublisher",
    "joint_state_publisher/joint_state_publisher": "twil_control.nodes.robot_state_publisher:JointStatePublisher",
    "tf/static_transform_publisher": "twil_control.nodes.static_transform_publisher:StaticTransformPublisher",
    "rostopic/timed_pub": "twil_control.nodes.timed_pub:TimedPublisher",
    "rostopic/rostopic": "twil_control.nodes.rostopic:Rostopic",
    "twil_control/cart_reference": "twil_control.nodes.cart_reference:CartReference",
    "twil_control/joint_trajectory_reference": "twil_control.nodes.joint_trajectory_reference:JointTrajectoryReference",
    "twil_control/qbot_cmd_sequence": "twil_control.nodes.qbot_cmd_sequence:QbotCmdSequence",
    "move_base/move_base": "twil_control.nodes.move_base:MoveBase",
    "twil_control/move_base_goals": "twil_control.nodes.move_base_goals:MoveBaseGoals",
    "twil_control/barn_run": "twil_control.nodes.barn_run:BarnRun",
    "twil_control/contact_monitor": "twil_control.gazebo.contact_monitor_node:ContactMonitor",
    "jackal_helper/collision_publisher_node": "twil_control.gazebo.collision_publisher:CollisionPublisher",
    "fake_localization/fake_localization": "twil_control.nodes.fake_localization:FakeLocalization",
    "amcl/amcl": "twil_control.nodes.amcl_node:AmclNode",
    "gmapping/slam_gmapping": "twil_control.nodes.slam_gmapping:SlamGMapping",
    "robot_localization/ekf_localization_node": "twil_control.nodes.ekf_localization:EkfLocalization",
    "robot_localization/ukf_localization_node": "twil_control.nodes.ekf_localization:UkfLocalization",
    "twist_mux/twist_mux": "twil_control.nodes.twist_mux:TwistMux",
    "joy/joy_node": "twil_control.nodes.joystick:JoyNode",
    "teleop_twist_joy/teleop_node": "twil_control.nodes.joystick:TeleopTwistJoy",
    "teleop_twist_keyboard/teleop_twist_keyboard.py": "twil_control.nodes.keyboard_teleop:TeleopTwistKeyboard",
    "turtlebot3_teleop/turtlebot3_teleop_key": "twil_control.nodes.keyboard_teleop:Turtlebot3TeleopKey",
    "interactive_marker_twist_server/marker_server": "twil_control.nodes.marker_server:MarkerServer",
    "controller_manager/spawner": "twil_control.ros_control.nodes:Spawner",
    "controller_manager/controller_manager": "twil_control.ros_control.nodes:ControllerManagerCli",
}


#: Node types that only display: every type of these packages, and of every ``rqt_*`` package.
DISPLAY_PACKAGES = ("rviz", "image_view")
DISPLAY_PACKAGE_PREFIX = "rqt_"
#: Single display types of packages that have other node types.
DISPLAY_TYPES = ("gazebo_ros/gzclient",)
DISPLAY_NODE = "twil_control.nodes.display:DisplayNode"


def is_display(pkg: str, type_: str) -> bool:
    """Whether pkg/type is a viewer or GUI (rviz, gzclient, rqt_*, image_view): a display node."""
    return (
        pkg in DISPLAY_PACKAGES or pkg.startswith(DISPLAY_PACKAGE_PREFIX) or f"{pkg}/{type_}" in DISPLAY_TYPES
    )


class NodeTypeError(TwilControlError, LookupError):
    """No node type of that name."""


def known_types() -> list[str]:
    display = {f"{pkg}/*" for pkg in DISPLAY_PACKAGES} | {f"{DISPLAY_PACKAGE_PREFIX}*/*", *DISPLAY_TYPES}
    return sorted(set(BUILTIN) | display | {ep.name for ep in entry_points(group=ENTRY_POINT_GROUP)})


def unknown_types(specs) -> NodeTypeError | None:
    """One error naming every node of ``specs`` (launch NodeSpecs) whose type is unknown, or None.

    A launch written for ROS can name several packages this workspace does not replicate; the
    user learns them all at once, each with the file and line that names it.
    """
    known = set(known_types())
    missing = [
        spec
        for spec in specs
        if f"{spec.pkg}/{spec.type}" not in known and not is_display(spec.pkg, spec.type)
    ]
    if not missing:
        return None
    lines = "\n".join(
        f"  {spec.pkg}/{spec.type} (node {spec.fqn}, {spec.source or 'no source'})" for spec in missing
    )
    types = sorted({f"{spec.pkg}/{spec.type}" for spec in missing})
    plural = "s" if len(types) > 1 else ""
    return NodeTypeError(
        f"{len(types)} unsupported node type{plural} in this launch:\n{lines}\n"
        f"known types: {', '.join(sorted(known))}"
    )


def _import(target: str):
    module, _, attr = target.partition(":")
    return getattr(importlib.import_module(module), attr)


def get(pkg: str, type_: str):
    """The class of node type pkg/type; unknown types list the known ones."""
    key = f"{pkg}/{type_}"
    if key in BUILTIN:
        return _import(BUILTIN[key])
    for ep in sorted(entry_points(group=ENTRY_POINT_GROUP), key=lambda e: e.name):
        if ep.name == key:
            return ep.load()
    if is_display(pkg, type_):
        return _import(DISPLAY_NODE)
    raise NodeTypeError(f"unknown node type '{key}'; known types: {', '.join(known_types())}")
