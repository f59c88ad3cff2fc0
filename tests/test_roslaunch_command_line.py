"""The launch command as roslaunch's: `PACKAGE FILE` found in the package, several files in one
graph (an arg goes to every file that declares it; one that none declares, and two nodes of
one name, are errors naming the files), and `name:=value` anywhere on the line."""

from __future__ import annotations

import textwrap

import pytest

from twil_control.core import packages
from twil_control.launch.__main__ import main
from twil_control.launch.command_line import launch_files, split_launch_args
from twil_control.launch.loader import load_launch
from twil_control.launch.plan import LaunchError


def _write(path, text: str):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(textwrap.dedent(text).lstrip())
    return path


@pytest.fixture
def workspace(tmp_path, monkeypatch):
    """A catkin source folder holding the package my_robot_sim, on ROS_PACKAGE_PATH."""
    pkg = tmp_path / "src" / "my_robot_sim"
    _write(pkg / "package.xml", "<package format='2'><name>my_robot_sim</name></package>")
    _write(
        pkg / "launch" / "drive.launch",
        """
        <launch>
          <arg name="speed" default="0.1"/>
          <arg name="topic" default="cmd_vel"/>
          <node pkg="rostopic" type="rostopic" name="drive" args="pub -r 10 /$(arg topic) geometry_msgs/Twist '{linear: {x: $(arg speed)}}'"/>
        </launch>""",
    )
    _write(
        pkg / "launch" / "sensors" / "note.launch",
        """
        <launch>
          <arg name="speed" default="0.5"/>
          <arg name="text" default="hello"/>
          <param name="note_speed" value="$(arg speed)"/>
          <node pkg="rostopic" type="rostopic" name="note" args="pub /note std_msgs/String '$(arg text)'"/>
        </launch>""",
    )
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "src"))
    packages.set_extra_paths([])
    return pkg


def test_package_and_file_resolve_as_roslaunch_finds_them(workspace, tmp_path):
    drive, note = workspace / "launch" / "drive.launch", workspace / "launch" / "sensors" / "note.launch"
    assert launch_files(["my_robot_sim", "drive.launch"]) == [drive]  # by name, anywhere in the package
    assert launch_files(["my_robot_sim", "note.launch"]) == [note]
    assert launch_files(["my_robot_sim", "launch/sensors/note.launch"]) == [note]  # a path inside it
    assert launch_files(["my_robot_sim", "drive.launch", "other.launch"]) == [drive, "other.launch"]
    assert launch_files(["a.launch", "b.launch.yaml"]) == ["a.launch", "b.launch.yaml"]  # files as given
    _write(workspace / "test" / "drive.launch", "<launch/>")
    with pytest.raises(LaunchError) as two:
        launch_files(["my_robot_sim", "drive.launch"])
    assert str(two.value) == (
        f"2 files named 'drive.launch' in package 'my_robot_sim': {drive}, "
        f"{workspace / 'test' / 'drive.launch'}; give the path of one"
    )
    with pytest.raises(LaunchError) as missing:
        launch_files(["my_robot_sim", "nav.launch"])
    assert str(missing.value) == (
        f"no launch file 'nav.launch' in package 'my_robot_sim' ({workspace}), "
        "and 'my_robot_sim' is not a launch file"
    )
    with pytest.raises(LaunchError) as unknown:
        launch_files(["no_such_pkg", "nav.launch"])
    assert str(unknown.value).startswith(
        "'no_such_pkg' is neither a launch file nor a package: package 'no_such_pkg' not found; searched"
    )
    assert str(tmp_path / "src") in str(unknown.value)


def test_name_value_args_stand_anywhere_on_the_line():
    argv = ["speed:=1", "my_robot_sim", "--duration", "1", "topic:=a", "drive.launch", "--no-bag", "x:=a:=b"]
    assert split_launch_args(argv) == (
        ["speed:=1", "topic:=a", "x:=a:=b"],
        ["my_robot_sim", "--duration", "1", "drive.launch", "--no-bag"],
    )


def test_the_command_runs_a_package_file_with_args_before_and_after_the_options(workspace, capsys):
    # issue 35 item 13: `FILE --duration 1 x:=0.5` was refused ("unrecognized arguments")
    argv = ["speed:=0.25", "my_robot_sim", "drive.launch", "--graph", "topic:=robot/cmd_vel"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "  /robot/cmd_vel [geometry_msgs/Twist]\n    publisher:  /drive" in out
    assert (
        main([str(workspace / "launch" / "drive.launch"), "--duration", "0.2", "--no-bag", "speed:=2"]) == 0
    )


def test_several_files_make_one_graph_and_each_arg_goes_to_every_file_declaring_it(workspace):
    drive, note = workspace / "launch" / "drive.launch", workspace / "launch" / "sensors" / "note.launch"
    plan = load_launch([drive, note], {"speed": "0.3", "text": "hi", "topic": "base/cmd_vel"})
    assert [spec.fqn for spec in plan.nodes] == ["/drive", "/note"]
    assert plan.nodes[0].args[3] == "/base/cmd_vel" and plan.nodes[0].args[-1] == "{linear: {x: 0.3}}"
    assert plan.nodes[1].args[-1] == "hi" and plan.params.get("/note_speed") == 0.3
    assert plan.files == [drive, note]
    # an arg one file declares leaves the other's default alone
    plan = load_launch([drive, note], {"text": "only"})
    assert plan.nodes[0].args[-1] == "{linear: {x: 0.1}}" and plan.params.get("/note_speed") == 0.5


def test_an_arg_no_file_declares_is_an_error_listing_each_files_args(workspace):
    drive, note = workspace / "launch" / "drive.launch", workspace / "launch" / "sensors" / "note.launch"
    with pytest.raises(LaunchError) as err:
        load_launch([drive, note], {"sped": "1", "text": "x"})
    assert str(err.value) == (
        f"unknown arg 'sped': no file of this launch declares it; declared args: "
        f"{drive}: speed, topic; {note}: speed, text"
    )


def test_two_nodes_of_one_name_in_two_files_is_an_error_naming_both(workspace, tmp_path):
    drive = workspace / "launch" / "drive.launch"
    again = _write(
        tmp_path / "mine.launch",
        """
        <launch>
          <node pkg="rostopic" type="rostopic" name="drive" args="pub /x std_msgs/Bool true"/>
        </launch>""",
    )
    with pytest.raises(LaunchError) as err:
        load_launch([drive, again])
    assert str(err.value) == (
        f"{again}:2:3: duplicate node name '/drive' (first declared at {drive}:4:3); roslaunch requires "
        f"unique node names: change 'name' or 'ns'"
    )


def test_the_command_takes_several_files_and_exits_2_naming_an_undeclared_arg(workspace, capsys, tmp_path):
    drive, note = workspace / "launch" / "drive.launch", workspace / "launch" / "sensors" / "note.launch"
    assert main([str(drive), str(note), "--graph", "text:=x"]) == 0
    out = capsys.readouterr().out
    assert "  /drive\n  /note\n" in out and "  /note [std_msgs/String]" in out
    assert main([str(drive), "--no-bag", str(note), "--duration", "0.1", "nope:=1"]) == 2
    assert "error: unknown arg 'nope': no file of this launch declares it" in capsys.readouterr().err
