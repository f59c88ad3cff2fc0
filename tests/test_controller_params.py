"""A controller whose parameters are wrong does not load, and its launch does not start.

Each case edits one line of the WAM's controller configuration (config/wam.yaml) or passes a
bad gain to the cart launch: the controller refuses it naming the parameter, the file:line
where it was set and what is allowed; the spawner, required by default, fails, so the launch
exits 2 with nothing run and no bag. With ``required: false`` on the spawner the launch runs
without the controller, and still exits 1."""

from __future__ import annotations

import re

import pytest
from conftest import read_bag

from twil_control import PACKAGE_ROOT
from twil_control.launch.__main__ import main

WAM_LAUNCH = PACKAGE_ROOT / "launch" / "wam_computed_torque.launch.yaml"
WAM_CONFIG = PACKAGE_ROOT / "config" / "wam.yaml"
CT = "/wam/computed_torque_controller"
SPAWNER_FAILED = "error: required node /wam/controller_spawner failed at t = 0.000 s: Failed to load "


def _wam_launch(tmp_path, old: str, new: str, spawner: str = "") -> tuple[str, int]:
    """The WAM launch reading a copy of config/wam.yaml with line `old` replaced by `new`;
    returns the launch path and the edited line's number."""
    lines = WAM_CONFIG.read_text().splitlines()
    number = lines.index(old) + 1
    lines[number - 1] = new
    config = tmp_path / "wam.yaml"
    config.write_text("\n".join(lines) + "\n")
    text = WAM_LAUNCH.read_text().replace("$(find twil_control)/config/wam.yaml", str(config))
    text = text.replace("name: controller_spawner\n", f"name: controller_spawner\n{spawner}")
    launch = tmp_path / "wam.launch.yaml"
    launch.write_text(text)
    return str(launch), number


@pytest.mark.parametrize(
    "old, new, controller, problem",
    [
        (
            "  kp: 25.0",
            '  kp: "abc"',
            "computed_torque_controller",
            f"parameter '{CT}/kp' must be a number or a list of numbers (got 'abc')",
        ),
        (
            "  kp: 25.0",
            "  kp: -25",
            "computed_torque_controller",
            f"parameter '{CT}/kp' must be a finite number >= 0 (got -25)",
        ),
        (
            "  kp: 25.0",
            "  kp: .nan",
            "computed_torque_controller",
            f"parameter '{CT}/kp' must be a finite number >= 0 (got nan)",
        ),
        (
            "  kp: 25.0",
            "  kp: [25, 25]",
            "computed_torque_controller",
            f"parameter '{CT}/kp' must be one number for all 7 joints or a list of 7, one per joint (wam_joint_1, "
            "wam_joint_2, wam_joint_3, wam_joint_4, wam_joint_5, wam_joint_6, wam_joint_7) (got [25, 25])",
        ),
        (
            "  kd: 10.0",
            "  kd: [10, 10, 10, 10, 10, .inf, 10]",
            "computed_torque_controller",
            f"parameter '{CT}/kd' must hold only finite numbers >= 0 (one is inf) (got [10, 10, 10, 10, 10, inf, 10])",
        ),
        (
            "  kp: 25.0",
            "  kpp: 25.0",
            "computed_torque_controller",
            f"unknown parameter '{CT}/kpp' (did you mean 'kp'?); allowed: joints, kd, kp, model, reference_timeout, "
            "root_link, tip_link, type",
        ),
        (
            "  publish_rate: 100",
            "  publish_rate: -100",
            "joint_state_controller",
            "parameter '/wam/joint_state_controller/publish_rate' must be a finite number > 0 (got -100)",
        ),
    ],
)
def test_bad_controller_parameter_stops_the_launch_before_time(
    tmp_path, capsys, old, new, controller, problem
):
    launch, line = _wam_launch(tmp_path, old, new)
    bag = tmp_path / "out.bag"
    assert main([launch, "--duration", "0.5", "--bag", str(bag), "--quiet"]) == 2
    err = capsys.readouterr().err
    verdict = next(line for line in err.splitlines() if line.startswith("error: "))
    assert verdict == (
        f"{SPAWNER_FAILED}{controller}: Initializing controller '{controller}' failed: "
        f"{tmp_path / 'wam.yaml'}:{line}: {problem}; the launch was not started"
    )
    assert not bag.exists() and not bag.with_name("out.bag.active").exists()


def test_bad_gain_on_the_command_line_names_the_launch_file_line(capsys):
    assert (
        main(
            [
                str(PACKAGE_ROOT / "launch" / "twil_cart_linearizing.launch.yaml"),
                "gamma1:=-1.0",
                "--duration",
                "0.5",
                "--no-bag",
                "--quiet",
            ]
        )
        == 2
    )
    err = capsys.readouterr().err
    assert re.search(
        r"error: required node /twil/ros_control/controller_spawner failed at t = 0\.000 s: "
        r"Failed to load cart_linearizing_controller: .*launch/twil_cart_linearizing\.launch\.yaml:"
        r"\d+: parameter '/twil/ros_control/cart_linearizing_controller/gains/gamma1' must be a "
        r"finite number > 0 \(got -1\.0\); the launch was not started",
        err,
    ), err


def test_a_spawner_that_is_not_required_lets_the_launch_run_without_its_controller(tmp_path, capsys):
    launch, _ = _wam_launch(tmp_path, "  kp: 25.0", "  kp: -25", spawner="            required: false\n")
    bag = tmp_path / "out.bag"
    assert main([launch, "--duration", "0.3", "--bag", str(bag), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert (
        "node /wam/controller_spawner failed at t = 0.000 s: Failed to load computed_torque_controller: "
        in err
        and "the node is not required: the launch goes on without it" in err
    )
    assert "1 node failure while the launch went on" in err
    msgs = read_bag(bag)
    assert len(msgs["/joint_states"]) == 30  # joint_state_controller loaded and ran, 100 Hz
    assert not any(m.effort.any() for _, m in msgs["/joint_states"])  # no controller drives the arm


def test_a_controller_failing_to_load_while_time_runs_stops_the_launch_and_keeps_the_bag(tmp_path, capsys):
    """A spawner waiting for a topic (--wait-for) loads at 0.3 s: its failure then is exit 1,
    with the bag closed and holding what ran."""
    launch, _ = _wam_launch(tmp_path, "  kp: 25.0", "  kp: -25")
    text = (
        open(launch)
        .read()
        .replace(
            'args: "joint_state_controller computed_torque_controller"',
            'args: "--wait-for /go computed_torque_controller"',
        )
    )
    text += """
        - node: {pkg: controller_manager, type: spawner, name: state_spawner, args: joint_state_controller}
        - node:
            pkg: rostopic
            type: timed_pub
            name: go
            params: {topic: /go, type: std_msgs/Bool, messages: [{time: 0.3, msg: {data: true}}]}
"""
    open(launch, "w").write(text)
    bag = tmp_path / "out.bag"
    assert main([launch, "--duration", "1", "--bag", str(bag), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert (
        "required node /wam/controller_spawner failed at t = 0.300 s: Failed to load computed_torque_controller: "
        in err
        and f"parameter '{CT}/kp' must be a finite number >= 0 (got -25)" in err
    )
    assert "stopped at t = 0.300 s" in err
    stamps = [t for t, _ in read_bag(bag)["/joint_states"]]
    assert len(stamps) == 30 and stamps[-1] == 290_000_000  # 100 Hz from 0 to the failure
