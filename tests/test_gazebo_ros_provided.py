"""gazebo_ros without ROS: `$(find gazebo_ros)` names the package this project provides (a user's
own gazebo_ros wins), its empty_world.launch takes the noetic original's arguments and hands
each to the node it belongs to, and a launch file written as TurtleBot3's are (include
empty_world.launch with world_name, spawn_model -urdf -param robot_description) runs with a
world of its own package given as an .sdf path."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest
from conftest import read_bag
from support.ros_env import use_packages

from twil_control import PACKAGE_ROOT
from twil_control.core import packages
from twil_control.launch.command_line import launch_files
from twil_control.launch.launch_file import declarations, read_launch
from twil_control.launch.loader import load_launch
from twil_control.launch.runner import Launch, RunOptions, run

ROS1 = PACKAGE_ROOT / "tests" / "data" / "ros1"
PROVIDED = PACKAGE_ROOT / "src" / "twil_control" / "share" / "gazebo_ros"
EMPTY_WORLD = PROVIDED / "launch" / "empty_world.launch"

#: every arg of gazebo_ros's noetic empty_world.launch, with its default there
ORIGINAL_ARGS = {
    "paused": "false",
    "use_sim_time": "true",
    "extra_gazebo_args": "",
    "gui": "true",
    "recording": "false",
    "headless": "false",
    "debug": "false",
    "physics": "ode",
    "verbose": "false",
    "output": "screen",
    "world_name": "worlds/empty.world",
    "respawn_gazebo": "false",
    "use_clock_frequency": "false",
    "pub_clock_frequency": "100",
    "enable_ros_network": "true",
    "server_required": "false",
    "gui_required": "false",
}


@pytest.fixture(autouse=True)
def _env(monkeypatch, tmp_path_factory):
    use_packages(monkeypatch, tmp_path_factory, ROS1 / "vendor", ROS1 / "tb3_style_gazebo", ROS1 / "stubs")


def test_find_gazebo_ros_is_the_provided_package_unless_the_user_has_one(tmp_path, monkeypatch):
    assert packages.find("gazebo_ros") == PROVIDED
    own = tmp_path / "ws" / "gazebo_ros"
    (own / "launch").mkdir(parents=True)
    (own / "package.xml").write_text("<package format='2'><name>gazebo_ros</name></package>")
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "ws"))
    assert packages.find("gazebo_ros") == own  # ROS_PACKAGE_PATH before the provided packages
    monkeypatch.setenv("ROS_PACKAGE_PATH", "")
    packages.set_extra_paths([tmp_path / "ws"])
    assert packages.find("gazebo_ros") == own  # and --package-path


def test_empty_world_launch_declares_the_original_arguments_with_their_defaults():
    data, lines, _ = read_launch(EMPTY_WORLD, None)
    declared = {
        name: decl.default
        for name, decl in declarations(data["launch"], ("launch",), lines).items()
        if decl.value is None  # the overridable ones; 'value' args are the file's own
    }
    assert declared == ORIGINAL_ARGS


def _nodes(**args):
    plan = load_launch(EMPTY_WORLD, {k: str(v) for k, v in args.items()})
    return plan, {spec.fqn: spec for spec in plan.nodes}


def test_empty_world_arguments_reach_the_server_and_client_nodes():
    plan, nodes = _nodes(world_name="/data/my.sdf")
    server = nodes["/gazebo"]
    assert (server.pkg, server.type, server.args) == ("gazebo_ros", "gzserver", ["-e", "ode", "/data/my.sdf"])
    assert (server.required, server.respawn, server.output) == (False, False, "screen")
    gui = nodes["/gazebo_gui"]
    assert (gui.type, gui.args, gui.required) == ("gzclient", [], False)
    assert plan.params.get("/use_sim_time") is True and plan.params.get("/gazebo") == {
        "enable_ros_network": True
    }

    plan, nodes = _nodes(
        world_name="w.world", paused="true", recording="true", verbose="true", physics="bullet",
        extra_gazebo_args="--seed 3", debug="true", gui="false", server_required="true",
        respawn_gazebo="true", output="log", use_clock_frequency="true", pub_clock_frequency="250",
        enable_ros_network="false", use_sim_time="false",
    )  # fmt: skip
    server = nodes["/gazebo"]
    assert server.type == "debug"  # the server under gdb in ROS: the same simulator here
    assert server.args == ["-u", "-r", "--verbose", "-e", "bullet", "--seed", "3", "w.world"]  # world last
    assert (server.required, server.respawn, server.output) == (True, True, "log")
    assert "/gazebo_gui" not in nodes
    assert plan.params.get("/gazebo") == {"pub_clock_frequency": 250, "enable_ros_network": False}
    assert plan.params.get("/use_sim_time") is False
    _, nodes = _nodes(verbose="true", gui_required="true")
    assert (nodes["/gazebo_gui"].args, nodes["/gazebo_gui"].required) == (["--verbose"], True)


def test_the_provided_node_types_build_without_drake_and_gzclient_only_displays():
    plan = load_launch(
        EMPTY_WORLD, {"world_name": str(PACKAGE_ROOT / "sim/worlds/default.sdf"), "debug": "true"}
    )
    launch = Launch(plan)
    server, gui = launch.nodes
    assert type(server).__name__ == "DrakeWorld" and server.params.world.endswith("default.sdf")
    assert server.params.enable_ros_network is True and getattr(gui, "displays_only", False)


@pytest.mark.slow
def test_a_turtlebot3_style_launch_runs_its_own_world_through_empty_world_launch(tmp_path, caplog):
    (path,) = launch_files(["tb3_style_gazebo", "burger_walls.launch"])
    assert path == ROS1 / "tb3_style_gazebo" / "launch" / "burger_walls.launch"
    plan = load_launch(path, {"model": "burger", "x_pos": "0.2", "y_pos": "-0.1"})
    world = ROS1 / "tb3_style_gazebo" / "worlds" / "two_walls.sdf"
    assert plan.node("/gazebo").args[-1] == str(world)  # world_name, the server's last arg
    assert [f.name for f in plan.files] == ["burger_walls.launch", "empty_world.launch"]
    with caplog.at_level(logging.INFO, logger="twil_control.launch"):
        result = run(plan, RunOptions(duration=1.0, bag=tmp_path / "run.bag"))
    assert not result.failed  # gui:=true's gzclient did not stop the headless run
    assert "node /gazebo_gui (gazebo_ros/gzclient, " in caplog.text
    bag = read_bag(result.bag)
    _, states = bag["/gazebo/model_states"][-1]
    pose = states.pose[list(states.name).index("turtlebot3_burger")]
    assert (pose.position.x, pose.position.y) == pytest.approx((0.2, -0.1), abs=0.01)
    # the world's walls, seen by the burger's LDS (base_scan 0.032 m behind base_link): wall_x's
    # face at x = 1.5 m straight ahead, wall_y's at y = -1.0 m to the right; the LDS adds
    # Gaussian noise (0.01 m) and reports ranges in 0.015 m steps
    _, scan = bag["/scan"][-1]
    angles = scan.angle_min + np.arange(len(scan.ranges)) * scan.angle_increment
    ranges = np.asarray(scan.ranges)

    def at(angle: float) -> float:
        return float(ranges[np.argmin(np.abs(np.angle(np.exp(1j * (angles - angle)))))])

    assert at(0.0) == pytest.approx(1.5 - (0.2 - 0.032), abs=0.04)
    assert at(-math.pi / 2) == pytest.approx(1.0 - 0.1, abs=0.04)
    assert math.isinf(at(math.pi / 2)) or at(math.pi / 2) > 3.4  # nothing on the left within range
