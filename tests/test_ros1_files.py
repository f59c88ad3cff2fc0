"""A ROS 1 user's own files, as they are: the qbot report's Listing 2 (gmapping launch) and Listing 3
(move_base node) parsed out of the report's text and run as printed, included from a launch that
brings up the simulated qbot; the original move_base parameter files loaded unmodified, with a
warning at load for every value the simulated qbot cannot live with (and none for the
project's own files)."""

from __future__ import annotations

import logging
import re
import shutil
from pathlib import Path

import pytest

from twil_control import PACKAGE_ROOT
from twil_control.launch.loader import load_launch
from twil_control.launch.plan import LaunchError
from twil_control.launch.runner import Launch, RunOptions, run

DATA = PACKAGE_ROOT / "tests/data/ros1"


def report_listings() -> dict[int, str]:
    """The qbot report's fenced code blocks by the number of the "Listing N:" caption after them."""
    parts = (DATA / "qbot_report.txt").read_text(encoding="utf-8").split("```")
    listings = {}
    for k in range(1, len(parts) - 1, 2):
        caption = re.match(r"\s*Listing (\d+):", parts[k + 1])
        if caption:
            listings[int(caption.group(1))] = parts[k]
    return listings


def write_listings(directory: Path) -> None:
    """Listing 2 without its "[...]" line, Listing 3 inside a <launch>, as a user would save them."""
    listings = report_listings()
    (directory / "gmapping.launch").write_text(
        "".join(line for line in listings[2].splitlines(keepends=True) if line.strip() != "[...]")
    )
    (directory / "move_base.launch").write_text("<launch>\n" + listings[3] + "</launch>\n")


@pytest.fixture
def listings_dir(tmp_path, monkeypatch):
    """A user's package directory: the top-level launch, the two listings and params/, run from
    there (roslaunch resolves the listing's "params/..." from the working directory)."""
    shutil.copytree(DATA / "params", tmp_path / "params")
    shutil.copy(DATA / "qbot_report.launch", tmp_path)
    write_listings(tmp_path)
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_the_listings_are_the_reports_text():
    listings = report_listings()
    assert (
        '<node pkg="gmapping" type="slam_gmapping" name="slam_gmapping" output="screen">' in listings[2]
        and "[...]" in listings[2]
    )
    assert listings[3].count('<rosparam file="params/') == 5
    assert '<remap from="/cmd_vel" to="/qbot/cmd_vel" />' in listings[3]


def test_listing_2_with_its_elision_line_is_refused_naming_the_inline_yaml_lines(tmp_path):
    path = tmp_path / "gmapping.launch"
    path.write_text(report_listings()[2])
    with pytest.raises(LaunchError) as err:
        load_launch(path)
    # "[...]" (line 11) starts a key that never gets its ':' before </rosparam> (line 12)
    assert str(err.value).startswith(f"{path}:12:5: YAML syntax error: could not find expected ':'")
    assert str(err.value).endswith(f"(loaded by {path}:6:5)")


def test_the_listings_load_as_printed(listings_dir):
    plan = load_launch(listings_dir / "qbot_report.launch", {"goal": "1.3 0.8 0"})
    node = plan.node("/slam_gmapping")
    assert node.remappings == {"/scan": "/qbot/laser/scan"} and node.output == "screen"
    listing = {"odom_frame": "odom", "map_update_interval": 1.0, "maxUrange": 10.0, "base_frame": "base_link"}
    assert (
        load_launch(listings_dir / "qbot_report.launch", {"elided": "false"}).params.get("/slam_gmapping")
        == listing
    )
    # what "[...]" elides: the original launch's other values, which the listing's override
    gmapping = plan.params.get("/slam_gmapping")
    assert {key: gmapping[key] for key in listing} == listing
    assert (gmapping["particles"], gmapping["xmin"], gmapping["delta"]) == (80, -5.0, 0.025)
    assert plan.node("/hokuyo_link_broadcaster").args == "0 0 0.08 0 0 0 1 base_link base_laser 100".split()
    move_base = plan.node("/move_base")
    assert move_base.remappings == {"/cmd_vel": "/qbot/cmd_vel"} and not move_base.respawn
    params = plan.params
    # the original values, unmodified, from the listing's relative paths
    assert params.get("/move_base/TrajectoryPlannerROS/min_vel_theta") == 0.5
    assert (
        params.source_of("/move_base/TrajectoryPlannerROS/min_vel_theta")
        == f"{listings_dir}/params/base_local_planner.yaml:5"
    )
    for costmap in ("global_costmap", "local_costmap"):
        assert params.get(f"/move_base/{costmap}/inflation_radius") == 0.3
        assert params.get(f"/move_base/{costmap}/footprint") == [
            [0.25, 0.15],
            [-0.25, 0.15],
            [-0.25, -0.15],
            [0.25, -0.15],
        ]
    assert params.get("/move_base/local_costmap/rolling_window") is True
    assert params.get("/move_base/global_costmap/static_map") is True


#: (parameter, what its warning must say) for each value of the original files (and defaults)
#: that the simulated qbot cannot live with
EXPECTED_WARNINGS = [
    ("TrajectoryPlannerROS/min_vel_theta = 0.5 (", "never turns right", "uses -2.0"),
    ("TrajectoryPlannerROS/max_vel_x = 0.5 (", "limits linear speed to 0.45 m/s", "uses 0.45"),
    ("TrajectoryPlannerROS/min_in_place_vel_theta = 0.0 (", "slow in-place turns", "uses 1.0"),
    ("TrajectoryPlannerROS/rotate_to_heading_threshold = 0.0 (not set", "arcs", "uses 0.15"),
    ("TrajectoryPlannerROS/dwa = True (not set", "one control period", "uses False"),
    (
        "global_costmap/footprint = [[0.25, 0.15],",
        "wheels reach +-0.305 x +-0.199 m",
        "uses [[0.305, 0.199],",
    ),
    ("global_costmap/inflation_radius = 0.3 (", "0.364 m", "uses 0.55"),
    ("local_costmap/footprint = [[0.25, 0.15],", "wheels", "uses [[0.305"),
    ("local_costmap/inflation_radius = 0.3 (", "neither turn nor pass", "uses 0.55"),
    ("oscillation_timeout = 0.0 (not set", "never notices a robot that is stuck", "uses 30.0"),
]


def _move_base_warnings(plan, caplog) -> list[str]:
    with caplog.at_level(logging.WARNING, logger="twil_control.node.move_base"):
        Launch(plan)
    return [r.getMessage() for r in caplog.records if r.name == "twil_control.node.move_base"]


def test_original_move_base_files_warn_once_per_value_the_qbot_cannot_live_with(listings_dir, caplog):
    warnings = _move_base_warnings(load_launch(listings_dir / "qbot_report.launch"), caplog)
    assert len(warnings) == len(EXPECTED_WARNINGS)
    for warning, (head, *says) in zip(warnings, EXPECTED_WARNINGS):
        assert warning.startswith(f"/move_base/{head}"), warning
        for text in says:
            assert text in warning, warning
    assert f"({listings_dir}/params/base_local_planner.yaml:5): " in warnings[0]
    assert f"({listings_dir}/params/costmap_common.yaml:4): " in warnings[6]


def test_the_projects_own_navigation_files_give_no_such_warning(caplog):
    plan = load_launch(PACKAGE_ROOT / "launch/qbot_navigation.launch")
    assert _move_base_warnings(plan, caplog) == []


@pytest.mark.slow
def test_the_listings_run_as_printed_on_the_simulated_qbot(listings_dir):
    from conftest import read_bag

    bag = listings_dir / "qbot_report.bag"
    plan = load_launch(listings_dir / "qbot_report.launch", {"goal": "1.3 0.8 0"})
    result = run(plan, RunOptions(duration=4.0, bag=bag, seed=1))
    assert result.error is None
    msgs = read_bag(bag)
    # Listing 2: its static transform, and gmapping's map and map -> odom from the robot's scans
    static = [tr for _, m in msgs["/tf_static"] for tr in m.transforms if tr.child_frame_id == "base_laser"]
    assert static[-1].header.frame_id == "base_link"
    assert abs(static[-1].transform.translation.z - 0.08) < 1e-12
    assert len(msgs["/map"]) >= 1 and msgs["/map"][0][1].info.resolution == pytest.approx(0.025)
    assert any(
        tr.header.frame_id == "map" and tr.child_frame_id == "odom"
        for _, m in msgs["/tf"]
        for tr in m.transforms
    )
    # Listing 3: move_base takes the goal and drives the qbot through /qbot/cmd_vel
    commands = [m for _, m in msgs["/qbot/cmd_vel"]]
    assert len(commands) >= 20 and max(abs(c.linear.x) + abs(c.angular.z) for c in commands) > 0.1
    start, end = (msgs["/qbot/ground_truth/odom"][k][1].pose.pose.position for k in (0, -1))
    assert ((end.x - start.x) ** 2 + (end.y - start.y) ** 2) ** 0.5 > 0.1
