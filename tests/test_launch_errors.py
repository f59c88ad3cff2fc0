"""Bad input to `python -m twil_control.launch`: one clear message, exit 2, no traceback, no bag."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from twil_control import PACKAGE_ROOT
from twil_control.launch.__main__ import main
from twil_control.launch.plan import LaunchError

TWIL_SIM = PACKAGE_ROOT / "launch/twil_sim.launch.yaml"


def _launch(tmp_path: Path, body: str, config: str | None = None) -> Path:
    if config is not None:
        (tmp_path / "params.yaml").write_text(textwrap.dedent(config))
    path = tmp_path / "bad.launch.yaml"
    path.write_text(textwrap.dedent(body))
    return path


def _fails(capsys, tmp_path: Path, argv: list[str], *expected: str) -> str:
    bag = tmp_path / "out.bag"
    assert main(argv + ["--bag", str(bag), "--duration", "0.1"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    for text in expected:
        assert text in err, err
    assert not bag.exists() and not Path(str(bag) + ".active").exists()
    return err


WORLD_NODE = """
launch:
  - arg: {name: world, default: "$(find twil_control)/sim/worlds/default.sdf"}
  - node: {pkg: twil_control, type: drake_world, name: drake_world, params: {world: "$(arg world)"}}
  - node: {pkg: gazebo_ros, type: spawn_model, name: spawn, args: "-file twil -model twil"}
"""


def test_missing_launch_file(capsys, tmp_path):
    _fails(capsys, tmp_path, [str(tmp_path / "nope.launch.yaml")], "nope.launch.yaml", "not found")


def test_yaml_syntax_error_names_file_and_line(capsys, tmp_path):
    path = _launch(tmp_path, "launch:\n  - arg: {name: x, default: 1\n  - node: [\n")
    err = _fails(capsys, tmp_path, [str(path)], "bad.launch.yaml:")
    assert "syntax" in err.lower()


def test_unknown_arg_on_the_command_line_lists_declared_args(capsys, tmp_path):
    _fails(capsys, tmp_path, [str(TWIL_SIM), "wrld:=foo.sdf"], "wrld", "world", "yaw")


def test_malformed_command_line_arg(capsys, tmp_path):
    _fails(capsys, tmp_path, [str(TWIL_SIM), "world=foo.sdf"], "world=foo.sdf", "name:=value")


def test_unknown_parameter_key_names_file_key_and_allowed(capsys, tmp_path):
    path = _launch(
        tmp_path,
        WORLD_NODE.replace(
            'params: {world: "$(arg world)"}', 'params: {world: "$(arg world)", time_stp: 0.001}'
        ),
    )
    _fails(capsys, tmp_path, [str(path)], "time_stp", "time_step", "bad.launch.yaml")


def test_wrong_parameter_type(capsys, tmp_path):
    path = _launch(
        tmp_path,
        WORLD_NODE.replace(
            'params: {world: "$(arg world)"}', 'params: {world: "$(arg world)", time_step: fast}'
        ),
    )
    _fails(capsys, tmp_path, [str(path)], "time_step", "fast")


def test_wrong_type_in_a_rosparam_file_names_that_file(capsys, tmp_path):
    path = _launch(
        tmp_path,
        WORLD_NODE
        + f"""
  - rosparam: {{file: "{tmp_path / "params.yaml"}", ns: /twil/ros_control}}
  - node: {{pkg: twil_control, type: robot_hw_sim, name: gazebo_ros_control, ns: /twil/ros_control}}
""",
        config="""
gazebo_ros_control:
  model: twil
  control_period: "one millisecond"
  joints: {left_wheel_joint: {interfaces: [effort]}}
""",
    )
    _fails(capsys, tmp_path, [str(path)], "params.yaml", "control_period")


def test_missing_world_file(capsys, tmp_path):
    _fails(capsys, tmp_path, [str(TWIL_SIM), f"world:={tmp_path / 'no_world.sdf'}"], "no_world.sdf")


def test_missing_model_file(capsys, tmp_path):
    path = _launch(tmp_path, WORLD_NODE.replace("-file twil ", f"-file {tmp_path / 'robot.urdf'} "))
    _fails(capsys, tmp_path, [str(path)], "robot.urdf")


def test_unknown_node_type_lists_known_types(capsys, tmp_path):
    path = _launch(tmp_path, WORLD_NODE + "  - node: {pkg: twil_control, type: teleport, name: t}\n")
    _fails(capsys, tmp_path, [str(path)], "twil_control/teleport", "twil_control/drake_world")


def test_python_object_tags_are_refused(capsys, tmp_path):
    path = _launch(
        tmp_path, 'launch:\n  - arg: {name: x, default: !!python/object/apply:os.system ["echo hi"]}\n'
    )
    _fails(capsys, tmp_path, [str(path)], "bad.launch.yaml")


def test_eval_outside_the_whitelist_is_refused(capsys, tmp_path):
    path = _launch(tmp_path, "launch:\n  - arg: {name: x, default: \"$(eval open('/etc/passwd'))\"}\n")
    _fails(
        capsys,
        tmp_path,
        [str(path)],
        "bad.launch.yaml:2:",
        "$(eval open('/etc/passwd'))",
        "calling 'open' is not allowed",
    )


def test_existing_bag_is_never_overwritten(capsys, tmp_path):
    bag = tmp_path / "out.bag"
    bag.write_bytes(b"precious")
    assert main([str(TWIL_SIM), "--bag", str(bag), "--duration", "0.1"]) == 2
    assert "never overwritten" in capsys.readouterr().err
    assert bag.read_bytes() == b"precious"


def test_debug_shows_the_traceback(tmp_path):
    with pytest.raises(LaunchError, match="nope.launch.yaml"):
        main([str(tmp_path / "nope.launch.yaml"), "--debug"])


@pytest.mark.parametrize("rate", ["0", "-1", "nan", "61"])
def test_view_rate_outside_its_range_is_refused(capsys, tmp_path, rate):
    _fails(
        capsys,
        tmp_path,
        [str(TWIL_SIM), "--view", "--view-rate", rate],
        "--view-rate must be in (0, 60] frames per second",
        f"(got {float(rate)})",
    )


def test_unsupported_node_types_of_an_xml_launch_are_all_named_before_anything_runs(capsys, tmp_path):
    path = tmp_path / "user.launch"
    path.write_text(
        '<launch>\n  <node pkg="cartographer_ros" type="cartographer_node" name="cartographer"/>\n'
        '  <node pkg="move_base" type="move_base" name="move_base"/>\n'
        '  <node pkg="hector_mapping" type="hector_mapping" name="hector"/>\n</launch>\n'
    )
    err = _fails(
        capsys,
        tmp_path,
        [str(path)],
        "2 unsupported node types in this launch:",
        f"cartographer_ros/cartographer_node (node /cartographer, {path}:2:3)",
        f"hector_mapping/hector_mapping (node /hector, {path}:4:3)",
        "known types: ",
    )
    assert "move_base/move_base (node" not in err
