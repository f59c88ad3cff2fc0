"""The plant's step as a user sets it (gzserver's ~time_step, python -m twil_control.barn
--time_step): said aloud when it is not the world's, gazebo_ros_control's controllers then run
once per step as Gazebo runs them, and /gazebo/get_physics_properties and
set_physics_properties report it and refuse to change it once the plant is built."""

from __future__ import annotations

import logging

import pytest
from support.ros_env import use_packages

from twil_control import PACKAGE_ROOT
from twil_control.barn import many
from twil_control.barn.__main__ import main as barn_main
from twil_control.barn.trial import BarnError
from twil_control.core.messages import msg_class
from twil_control.launch.loader import load_launch
from twil_control.launch.runner import Launch
from twil_control.world.robot_hw_sim import control_update_period

ROBOTS = PACKAGE_ROOT / "tests" / "data" / "robots"
LAUNCH = ROBOTS / "tiny_description" / "launch" / "tiny.launch.yaml"


@pytest.fixture(autouse=True)
def _env(monkeypatch, tmp_path_factory):
    use_packages(monkeypatch, tmp_path_factory, ROBOTS)


@pytest.mark.parametrize(
    ("control_period", "time_step", "runs_every"),
    [
        (0.001, 0.001, 0.001),  # the usual: every step
        (0.001, 0.004, 0.004),  # faster than the step: once per step, the step as the period
        (0.002, 0.001, 0.002),  # a whole number of steps: as asked
        (0.0025, 0.001, 0.003),  # otherwise the first step at least a period after the last run
    ],
)
def test_controllers_run_every_whole_number_of_steps_as_gazebo_ros_control(
    control_period, time_step, runs_every
):
    assert control_update_period(control_period, time_step) == pytest.approx(runs_every, rel=1e-12)


def test_a_4ms_step_is_announced_run_once_per_step_and_reported_by_the_physics_services(caplog):
    plan = load_launch(LAUNCH, {"drive": "ros_control", "ros_control": "true"})
    plan.params.set("/gazebo/time_step", 0.004)
    launch = Launch(plan)
    with caplog.at_level(logging.WARNING):
        launch.build()
        launch.start()
    text = caplog.text
    assert "~time_step 0.004 s: the plant steps every 0.004 s" in text and "asks for 0.001 s" in text
    # tiny.urdf.xacro's controlPeriod is 0.001: gazebo_ros_control's error, then once per step
    assert "(0.001 s) is faster than the simulation period (0.004 s)" in text
    plugin = next(p for n in launch.nodes for p in getattr(n, "plugins", []) if getattr(p, "system", None))
    assert plugin.system.period == 0.004
    cycles: list[float] = []
    inner = plugin.manager.update_realtime
    plugin.manager.update_realtime = lambda t, period, *a: (cycles.append((t, period)), inner(t, period, *a))
    launch.simulator.AdvanceTo(0.2)
    # cycles at t = 0, 4, ..., 196 ms (each reads the step at t), each given the step as its period
    assert len(cycles) == 50
    assert [t for t, _ in cycles] == pytest.approx([0.004 * k for k in range(50)], abs=1e-12)
    assert {period for _, period in cycles} == {0.004}

    call = launch.master.call_service
    got = call("/gazebo/get_physics_properties")
    assert got.success and got.time_step == 0.004 and not got.pause
    assert got.max_update_rate == 0.0  # as fast as it can: Gazebo's 0
    assert (got.gravity.x, got.gravity.y, got.gravity.z) == pytest.approx((0.0, 0.0, -9.81))
    same = call("/gazebo/set_physics_properties", time_step=0.004, max_update_rate=0.0, gravity=got.gravity)
    assert same.success
    other = call("/gazebo/set_physics_properties", time_step=0.001, max_update_rate=0.0)
    assert not other.success
    assert "time_step 0.001 s (running: 0.004 s" in other.status_message
    assert "<max_step_size>" in other.status_message
    vec = msg_class("geometry_msgs/Vector3")
    moon = call("/gazebo/set_physics_properties", time_step=0.004, gravity=vec(x=0.0, y=0.0, z=-1.62))
    assert not moon.success and "gravity (0, 0, -1.62)" in moon.status_message
    launch.shutdown()


def test_barn_time_step_out_of_range_is_refused_before_anything_runs(tmp_path, capsys):
    assert barn_main(["--world_idx", "0", "--time_step", "0.02", "--out", str(tmp_path / "out.txt")]) == 2
    assert "--time_step must be in (0, 0.01] seconds (got 0.02)" in capsys.readouterr().err
    assert not (tmp_path / "out.txt").exists()


def test_barn_records_of_another_time_step_need_another_dir(tmp_path):
    record = tmp_path / "barn.json"
    many._check_same_stack(record, "", 0.004)
    many._check_same_stack(record, "", 0.004)  # the same step: resumed
    with pytest.raises(BarnError, match=r"--time_step 0.004 s; give another --dir for --time_step unset"):
        many._check_same_stack(record, "", None)
