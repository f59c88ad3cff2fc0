"""env_run-style robot_description commands (Jackal's description.launch) read without a shell:
the configuration file's assignments become the in-process xacro's environment, for that call
only; any other script, file content or command stays refused."""

from __future__ import annotations

import os

import pytest

from twil_control import PACKAGE_ROOT
from twil_control.core import packages
from twil_control.description.env_run import is_env_run_script, read_env_file
from twil_control.description.urdf import parse_urdf
from twil_control.description.xacro_command import XacroError
from twil_control.launch.loader import load_launch
from twil_control.launch.plan import LaunchError

ROS1 = PACKAGE_ROOT / "tests" / "data" / "ros1"
JACKAL = ROS1 / "vendor" / "jackal_description"


@pytest.fixture(autouse=True)
def _env(monkeypatch, tmp_path_factory):
    monkeypatch.setenv("ROS_PACKAGE_PATH", f"{ROS1 / 'vendor'}:{ROS1 / 'stubs'}")
    monkeypatch.delenv("JACKAL_LASER", raising=False)
    packages.set_extra_paths([])


def _links(config: str) -> set[str]:
    plan = load_launch(JACKAL / "launch" / "description.launch", {"config": config})
    return set(parse_urdf(plan.params.get("/robot_description")).links)


def test_jackal_description_launch_builds_robot_description_through_env_run():
    base = _links("base")
    laser = _links("front_laser")  # its file sets JACKAL_LASER=1: the LMS1xx on the front mount
    assert {"base_link", "chassis_link", "imu_link", "front_left_wheel_link"} <= base
    assert laser - base == {"front_laser", "front_laser_mount"}
    assert "JACKAL_LASER" not in os.environ  # the variables were the xacro's, for that call


def test_the_vendored_env_run_is_recognised_and_other_scripts_are_not(tmp_path):
    assert is_env_run_script(JACKAL / "scripts" / "env_run")
    other = tmp_path / "wrapper"
    other.write_text("#!/bin/bash\nF=$1\nshift 1\nset -a\nsource $F\nrm -rf /tmp/x\n$@\n")
    assert not is_env_run_script(other)
    plain = tmp_path / "plain.sh"
    plain.write_text("#!/bin/bash\n$@\n")
    assert not is_env_run_script(plain)


def test_an_env_file_with_anything_but_assignments_is_refused(tmp_path):
    good = tmp_path / "good"
    good.write_text("# a comment\n\nA=1\nexport B=\"two words\"\nC=${A}x\nD='$A'\n")
    assert read_env_file(good) == {"A": "1", "B": "two words", "C": "1x", "D": "$A"}
    bad = tmp_path / "bad"
    bad.write_text("A=1\ntouch /tmp/pwned\n")
    with pytest.raises(XacroError, match=r"bad:2: 'touch /tmp/pwned' is not a KEY=VALUE assignment"):
        read_env_file(bad)
    sneaky = tmp_path / "sneaky"
    sneaky.write_text("A=$(id)\n")
    with pytest.raises(XacroError, match="sneaky:1"):
        read_env_file(sneaky)


def test_a_command_that_is_not_an_env_run_in_front_of_xacro_is_refused(tmp_path):
    script = tmp_path / "run_it"
    script.write_text("#!/bin/bash\n$@\n")
    launch = tmp_path / "l.launch"
    launch.write_text(
        f'<launch><param name="robot_description" command="{script} $(find xacro)/xacro '
        f'{JACKAL}/urdf/jackal.urdf.xacro"/></launch>'
    )
    with pytest.raises(LaunchError, match="'command' runs only xacro"):
        load_launch(launch, {})
    wrapped_other = tmp_path / "l2.launch"
    wrapped_other.write_text(
        f'<launch><param name="robot_description" command="{JACKAL}/scripts/env_run '
        f'{JACKAL}/urdf/configs/base cat /etc/passwd"/></launch>'
    )
    with pytest.raises(LaunchError, match="'command' runs only xacro"):
        load_launch(wrapped_other, {})
