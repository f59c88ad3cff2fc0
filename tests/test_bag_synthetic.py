"""Mapping and navigation analyses on bags written here with the ROS interfaces those runs
use (nav_msgs/OccupancyGrid on /map, tf2_msgs/TFMessage on /tf, actionlib_msgs/GoalStatusArray
on /move_base/status, geometry_msgs/PoseStamped on /move_base_simple/goal, ground-truth
nav_msgs/Odometry), built so the expected figures are known by construction."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import write_bag as _write

from twil_control.bag.__main__ import main
from twil_control.bag.analyze import analyze_bag
from twil_control.core import messages
from twil_control.mapping.map_io import OccupancyMap, write_map

C = messages.msg_class
RES = 0.05


def _quat(yaw):
    return C("geometry_msgs/Quaternion")(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))


def _pose(x, y, yaw):
    return C("geometry_msgs/Pose")(position=C("geometry_msgs/Point")(x=x, y=y, z=0.0), orientation=_quat(yaw))


def _odom(t, x, y, yaw):
    v3 = C("geometry_msgs/Vector3")(x=0.0, y=0.0, z=0.0)
    return C("nav_msgs/Odometry")(
        header=messages.header("world", t),
        child_frame_id="base_link_ground_truth",
        pose=C("geometry_msgs/PoseWithCovariance")(pose=_pose(x, y, yaw), covariance=np.zeros(36)),
        twist=C("geometry_msgs/TwistWithCovariance")(
            twist=C("geometry_msgs/Twist")(linear=v3, angular=v3), covariance=np.zeros(36)
        ),
    )


def _tf(t, parent, child, x, y, yaw):
    return C("geometry_msgs/TransformStamped")(
        header=messages.header(parent, t),
        child_frame_id=child,
        transform=C("geometry_msgs/Transform")(
            translation=C("geometry_msgs/Vector3")(x=x, y=y, z=0.0), rotation=_quat(yaw)
        ),
    )


def _grid(t, data, origin):
    info = C("nav_msgs/MapMetaData")(
        map_load_time=messages.time_msg(t),
        resolution=RES,
        width=data.shape[1],
        height=data.shape[0],
        origin=_pose(origin[0], origin[1], 0.0),
    )
    return C("nav_msgs/OccupancyGrid")(
        header=messages.header("map", t), info=info, data=data.astype(np.int8).ravel()
    )


def _compose(a, b):
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], a[2] + b[2])


def _inverse(a):
    c, s = math.cos(a[2]), math.sin(a[2])
    return (-c * a[0] - s * a[1], s * a[0] - c * a[1], -a[2])


@pytest.fixture
def mapping_case(tmp_path):
    """World map: isolated occupied cells on a 4-cell lattice. The robot starts at S in the
    world; the map frame starts at S (gmapping's convention). The recorded map holds every
    ground-truth cell but `removed`, each moved by one cell (within tolerance), plus `false`
    cells 2 cells from any true one. The estimate drifts by 0.02 t m along the map's x."""
    rng = np.random.default_rng(7)
    gt = np.zeros((64, 64), np.int8)
    lattice = [(r, c) for r in range(2, 62, 4) for c in range(2, 62, 4)]
    chosen = [lattice[i] for i in rng.choice(len(lattice), 60, replace=False)]
    for r, c in chosen:
        gt[r, c] = 100
    gt_origin = (-1.6, -1.6, 0.0)
    yaml_path, _ = write_map(OccupancyMap(gt, RES, gt_origin), tmp_path / "world")
    S = (0.5, -0.3, 0.0)  # whole cells: 10 and -6
    map_origin = (gt_origin[0] - S[0], gt_origin[1] - S[1])
    rec = np.full((64, 64), -1, np.int8)
    rec[:, :] = 0
    removed, false = 9, 4
    for r, c in chosen[removed:]:
        rec[r, c + 1] = 100
    extra = [(r + 2, c + 2) for r, c in lattice if gt[r, c] == 0][:false]
    for r, c in extra:
        rec[r, c] = 100
    ts = np.arange(0, 10.0, 0.1)
    M = (0.1, 0.05, 0.02)  # map -> odom (constant here)
    gt_msgs, tf_msgs = [], []
    for t in ts:
        world = (0.5 + 0.8 * math.sin(0.3 * t), -0.3 + 0.8 * (1 - math.cos(0.3 * t)), 0.3 * t)
        est = _compose(_inverse(S), world)
        est = (est[0] + 0.02 * t, est[1], est[2])  # the estimate's drift (map frame)
        odom_base = _compose(_inverse(M), est)
        gt_msgs.append((t, _odom(t, *world)))
        tf_msgs.append(
            (
                t,
                C("tf2_msgs/TFMessage")(
                    transforms=[_tf(t, "map", "odom", *M), _tf(t, "odom", "base_link", *odom_base)]
                ),
            )
        )
    bag = _write(
        tmp_path / "mapping.bag",
        {"/map": [(9.0, _grid(9.0, rec, map_origin))], "/tf": tf_msgs, "/qbot/ground_truth/odom": gt_msgs},
    )
    return {"bag": bag, "map": yaml_path, "n": len(chosen), "removed": removed, "false": false, "ts": ts}


def test_mapping_trajectory_error_and_map_precision_recall(mapping_case):
    m = analyze_bag(mapping_case["bag"], ground_truth_map=mapping_case["map"])["mapping"]
    drift = 0.02 * mapping_case["ts"]
    assert m["trajectory_rmse_m"] == pytest.approx(np.sqrt(np.mean(drift**2)), rel=1e-6)
    assert m["trajectory_final_error_m"] == pytest.approx(drift[-1], rel=1e-6)
    assert m["yaw_rmse_deg"] == pytest.approx(0.0, abs=1e-6)
    n, k, f = mapping_case["n"], mapping_case["removed"], mapping_case["false"]
    assert m["map_precision"] == pytest.approx((n - k) / (n - k + f))
    assert m["map_recall"] == pytest.approx((n - k) / n)
    assert m["map_occupied_cells"] == n - k + f and m["map_reference_occupied_cells"] == n


def test_mapping_report_and_a_bad_ground_truth_map(mapping_case, tmp_path, capsys):
    out = tmp_path / "r.html"
    assert (
        main(
            [
                "analyze",
                str(mapping_case["bag"]),
                "--ground-truth-map",
                str(mapping_case["map"]),
                "-o",
                str(out),
            ]
        )
        == 0
    )
    assert out.read_text().count("data:image/png;base64,") == 2
    bad = tmp_path / "bad.yaml"
    bad.write_text("image: nowhere.pgm\nresolution: 0.05\n")
    assert main(["analyze", str(mapping_case["bag"]), "--ground-truth-map", str(bad)]) == 2
    assert "ground-truth map" in capsys.readouterr().err


def _status(t, entries):
    return C("actionlib_msgs/GoalStatusArray")(
        header=messages.header("", t),
        status_list=[
            C("actionlib_msgs/GoalStatus")(
                goal_id=C("actionlib_msgs/GoalID")(stamp=messages.time_msg(0.0), id=gid), status=st, text=""
            )
            for gid, st in entries
        ],
    )


@pytest.fixture
def navigation_case(tmp_path):
    """Goal 1 (2, 0) at 1 s: driven straight, SUCCEEDED at 6 s. Goal 2 (2, 2) at 10 s: moves
    to (2, 1.2), ABORTED at 14 s. A wall cell at (1.025, 0.625)."""
    ts = np.round(np.arange(0, 16.0001, 0.1), 6)

    def pos(t):
        if t < 1:
            return 0.0, 0.0
        if t < 6:
            return 2.0 * (t - 1) / 5, 0.0
        if t < 10:
            return 2.0, 0.0
        return 2.0, 1.2 * min(t - 10, 4) / 4

    gt = [(t, _odom(t, *pos(t), 0.0)) for t in ts]
    status = []
    for t in np.round(np.arange(0, 16.0001, 0.2), 6):
        entries = []
        if t >= 1.2:
            entries.append(("g1", 1 if t < 6 else 3))
        if t >= 10.2:
            entries.append(("g2", 1 if t < 14 else 4))
        status.append((t, _status(t, entries)))
    goal = lambda t, x, y: C("geometry_msgs/PoseStamped")(
        header=messages.header("map", t), pose=_pose(x, y, 0.0)
    )  # noqa: E731
    wall = np.zeros((80, 80), np.int8)
    wall[12, 20] = 100  # centre (1.025, 0.625) with origin (0, 0)
    yaml_path, _ = write_map(OccupancyMap(wall, RES, (0.0, 0.0, 0.0)), tmp_path / "nav_map")
    bag = _write(
        tmp_path / "nav.bag",
        {
            "/move_base/status": status,
            "/qbot/ground_truth/odom": gt,
            "/move_base_simple/goal": [(1.0, goal(1.0, 2.0, 0.0)), (10.0, goal(10.0, 2.0, 2.0))],
        },
    )
    return {"bag": bag, "map": yaml_path, "pos": pos, "ts": ts}


def test_navigation_per_goal_status_time_path_and_clearance(navigation_case):
    m = analyze_bag(navigation_case["bag"], ground_truth_map=navigation_case["map"])["navigation"]
    assert m["goals"] == 2 and m["succeeded"] == 1
    g1, g2 = m["per_goal"]
    assert (g1["status"], g2["status"]) == ("SUCCEEDED", "ABORTED")
    assert g1["time_s"] == pytest.approx(5.0) and g2["time_s"] == pytest.approx(4.0)
    assert g1["path_length_m"] == pytest.approx(2.0, abs=1e-9)
    assert g2["path_length_m"] == pytest.approx(1.2, abs=1e-9)
    assert g1["final_distance_m"] == pytest.approx(0.0, abs=1e-9)
    assert g2["final_distance_m"] == pytest.approx(0.8, abs=1e-9)
    # clearance: from the centre of the cell under the base to the wall cell's centre
    pos = navigation_case["pos"]
    for g, (t0, t1) in ((g1, (1.0, 6.0)), (g2, (10.0, 14.0))):
        pts = np.array([pos(t) for t in navigation_case["ts"] if t0 <= t <= t1])
        centres = (np.floor(pts / RES) + 0.5) * RES
        expected = np.hypot(centres[:, 0] - 1.025, centres[:, 1] - 0.625).min()
        assert g["min_clearance_m"] == pytest.approx(expected, abs=1e-9)


def test_navigation_text_output_lists_the_goals(navigation_case, capsys):
    assert main(["analyze", str(navigation_case["bag"])]) == 0
    out = capsys.readouterr().out
    assert "[navigation]" in out and "SUCCEEDED" in out and "ABORTED" in out
