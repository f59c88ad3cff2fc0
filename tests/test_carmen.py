"""CARMEN logs: parsing, bad files, the bag round trip, and (slow) the SLAM on the real logs."""

from __future__ import annotations

import gzip
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import read_bag
from rosbags.rosbag1 import Reader

from twil_control import PACKAGE_ROOT
from twil_control.core.messages import deserialize, to_sec
from twil_control.core.node import Master, Node
from twil_control.core.tf import TF_TYPE
from twil_control.launch.node_types import get
from twil_control.mapping import carmen, slam_metrics
from twil_control.mapping.gmapping import offline
from twil_control.mapping.gmapping.filter import ScanGeometry
from twil_control.mapping.gmapping.gmapping_params import GMappingParams
from twil_control.tools import carmen_to_bag as carmen_tool

DATA = PACKAGE_ROOT / "data/carmen"


def write_log(path: Path, n_scans: int = 6, beams: int = 5, extra: str = "") -> np.ndarray:
    poses = np.array([[0.1 * k, 0.05 * k, 0.02 * k] for k in range(n_scans)])
    lines = [
        "# message formats defined: PARAM SYNC ODOM FLASER",
        "PARAM robot_frontlaser_offset 0.25 nohost 0",
    ]
    for k, (x, y, th) in enumerate(poses):
        ranges = " ".join(f"{1.0 + 0.1 * i + 0.01 * k:.3f}" for i in range(beams))
        lines.append(f"ODOM {x} {y} {th} 0 0 0 {k:.3f} host {k:.3f}")
        lines.append(f"FLASER {beams} {ranges} {x} {y} {th} {x} {y} {th} {1.0 + k:.3f} host {1.0 + k:.3f}")
        lines.append("NEFF 12.5")
    text = "\n".join(lines) + "\n" + extra
    with gzip.open(path, "wt") as fh:
        fh.write(text)
    return poses


def test_read_log_gives_scans_poses_params(tmp_path):
    poses = write_log(tmp_path / "a.log.gz")
    log = carmen.read_log(tmp_path / "a.log.gz")
    assert log.ranges.shape == (6, 5) and log.n_beams == 5
    np.testing.assert_allclose(log.poses, poses)
    np.testing.assert_allclose(log.ranges[2], [1.02, 1.12, 1.22, 1.32, 1.42])
    np.testing.assert_allclose(log.times, 1.0 + np.arange(6))
    assert log.laser_offset == 0.25
    np.testing.assert_allclose(np.diff(log.beam_angles()), math.pi / 5)


@pytest.mark.parametrize(
    "line, message",
    [
        ("FLASER 5 1 2 3", r":21: FLASER with 5 ranges needs 16 fields"),
        ("FLASER x 1 2", r":21: FLASER must be followed by the number of ranges"),
        ("FLASER 3 1 2 3 0 0 0 0 0 0 1.0 host 1.0", r":21: FLASER has 3 ranges; earlier scans had 5"),
        ("FLASER 5 1 2 abc 4 5 0 0 0 0 0 0 9.0 host 9.0", r":21: FLASER fields must be numbers"),
        ("FLASER 5 1 2 -3 4 5 0 0 0 0 0 0 9.0 host 9.0", r":21: FLASER has a negative range"),
        ("PARAM lonely", r":21: PARAM needs"),
    ],
)
def test_bad_lines_name_the_line_and_what_was_expected(tmp_path, line, message):
    write_log(tmp_path / "bad.log.gz", extra=line + "\n")
    with pytest.raises(carmen.CarmenFormatError, match=message):
        carmen.read_log(tmp_path / "bad.log.gz")


def test_a_file_without_scans_or_missing_is_an_error(tmp_path):
    (tmp_path / "empty.log").write_text("# nothing\nODOM 0 0 0 0 0 0 0 h 0\n")
    with pytest.raises(carmen.CarmenFormatError, match="no FLASER records"):
        carmen.read_log(tmp_path / "empty.log")
    with pytest.raises(carmen.CarmenFormatError, match="no such file"):
        carmen.read_log(tmp_path / "missing.log")
    assert carmen_tool.main([str(tmp_path / "empty.log"), "-o", str(tmp_path / "x.bag")]) == 2


def test_backwards_stamps_are_nudged_forward():
    np.testing.assert_allclose(carmen.monotonic_times(np.array([1.0, 2.0, 1.5, 3.0])), [1.0, 2.0, 2.001, 3.0])


def test_odometry_without_noise_is_the_corrected_path_and_noise_is_seeded():
    poses = np.array([[0.0, 0.0, 0.0], [0.5, 0.1, 0.2], [1.0, 0.3, 0.5], [1.2, 0.9, 1.4]])
    np.testing.assert_allclose(carmen.synthesise_odometry(poses, (0, 0, 0, 0)), poses, atol=1e-12)
    a = carmen.synthesise_odometry(poses, (0.1, 0.1, 0.1, 0.1), seed=4)
    b = carmen.synthesise_odometry(poses, (0.1, 0.1, 0.1, 0.1), seed=4)
    c = carmen.synthesise_odometry(poses, (0.1, 0.1, 0.1, 0.1), seed=5)
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)


def test_bag_round_trip(tmp_path):
    poses = write_log(tmp_path / "a.log.gz")
    out = tmp_path / "a.bag"
    assert (
        carmen_tool.main(
            [str(tmp_path / "a.log.gz"), "-o", str(out), "--noise", "0.1", "0.1", "0.1", "0.1", "--seed", "3"]
        )
        == 0
    )
    bag = read_bag(out)
    assert {t: len(v) for t, v in bag.items()} == {
        "/tf_static": 1,
        "/tf": 6,
        "/odom": 6,
        "/ground_truth/odom": 6,
        "/scan": 6,
    }
    scans = [m for _, m in bag["/scan"]]
    assert scans[0].header.frame_id == "base_laser"
    np.testing.assert_allclose(scans[4].ranges, [1.04, 1.14, 1.24, 1.34, 1.44], rtol=1e-6)
    assert math.isclose(scans[0].angle_min, -math.pi / 2, rel_tol=1e-6) and math.isclose(
        scans[0].angle_increment, math.pi / 5, rel_tol=1e-6
    )
    truth = np.array([[m.pose.pose.position.x, m.pose.pose.position.y] for _, m in bag["/ground_truth/odom"]])
    np.testing.assert_allclose(truth, poses[:, :2])
    static = bag["/tf_static"][0][1].transforms[0]
    assert (static.header.frame_id, static.child_frame_id, static.transform.translation.x) == (
        "base_link",
        "base_laser",
        0.25,
    )
    odom = [m for _, m in bag["/odom"]]
    assert (odom[0].header.frame_id, odom[0].child_frame_id) == ("odom", "base_link")
    expected = carmen.synthesise_odometry(poses, (0.1, 0.1, 0.1, 0.1), seed=3)
    np.testing.assert_allclose([o.pose.pose.position.x for o in odom], expected[:, 0])
    assert [to_sec(s.header.stamp) for s in scans] == pytest.approx(1.0 + np.arange(6))
    # never overwrite
    assert carmen_tool.main([str(tmp_path / "a.log.gz"), "-o", str(out)]) == 2


def test_the_real_logs_parse():
    for name, scans, max_range in (("intel", 910, 81.83), ("aces", 440, 50.0)):
        log = carmen.read_log(DATA / f"{name}-corrected.log.gz")
        assert log.ranges.shape == (scans, 180)
        assert math.isclose(log.range_max, max_range)


def run_slam_on_log(
    name: str, n: int, particles: int, delta: float, noise=carmen.DEFAULT_NOISE, seed: int = 0
):
    log = carmen.read_log(DATA / f"{name}-corrected.log.gz")
    odom = carmen.synthesise_odometry(log.poses, noise, seed)
    params = GMappingParams(
        particles=particles,
        delta=delta,
        maxUrange=25.0,
        maxRange=log.range_max - 0.01,
        linearUpdate=0.0,
        angularUpdate=0.0,
        xmin=-5,
        ymin=-5,
        xmax=5,
        ymax=5,
    )
    run = offline.run(
        log.ranges[:n],
        odom[:n],
        log.times[:n],
        ScanGeometry(log.beam_angles(), log.laser_offset, 0.0),
        params,
        seed=seed + 1,
    )
    ref = log.poses[run.scan_index]
    return slam_metrics.evaluate(run.poses, ref), slam_metrics.evaluate(odom[run.scan_index], ref)


@pytest.mark.slow
def test_slam_on_the_first_300_intel_scans_matches_the_published_order_of_magnitude():
    slam, odo = run_slam_on_log("intel", 300, particles=30, delta=0.05)
    assert slam.consecutive.trans_mean < 0.06 and slam.consecutive.rot_mean < 1.0
    assert slam.loops.pairs > 100 and slam.loops.trans_mean < 0.15 and slam.loops.rot_mean < 1.5
    assert odo.loops.trans_mean > 2.0  # the odometry alone does not close the loops
    assert slam.ate_rmse < 0.25 and slam.ate_rmse < 0.1 * odo.ate_rmse


@pytest.mark.slow
def test_the_node_on_an_intel_bag_tracks_the_ground_truth(tmp_path):
    """The first 120 Intel scans through the importer, the bag and the node on the bus."""
    log = carmen.read_log(DATA / "intel-corrected.log.gz")
    log.times, log.ranges, log.poses = log.times[:120], log.ranges[:120], log.poses[:120]
    carmen_tool.write_bag(log, tmp_path / "intel.bag")
    master = Master()
    master.params.set(
        "/slam_gmapping",
        dict(
            particles=30,
            delta=0.05,
            maxUrange=25.0,
            maxRange=81.0,
            linearUpdate=0.0,
            angularUpdate=0.0,
            xmin=-5.0,
            ymin=-5.0,
            xmax=5.0,
            ymax=5.0,
        ),
    )
    node = get("gmapping", "slam_gmapping")(master, "slam_gmapping", "/", {})
    feeder = Node(master, "player")
    pubs = {}
    types = {"/tf": TF_TYPE, "/tf_static": TF_TYPE, "/scan": "sensor_msgs/LaserScan"}
    with Reader(tmp_path / "intel.bag") as reader:  # bag order: time, then write order (tf first)
        events = [
            (t, c.topic, deserialize(raw, c.msgtype)) for c, t, raw in reader.messages() if c.topic in types
        ]
    for t, topic, msg in events:
        if topic not in pubs:
            pubs[topic] = feeder.create_publisher(topic, types[topic], latch=topic == "/tf_static")
        master.clock.set(max(master.clock.now(), t * 1e-9))
        pubs[topic].publish(msg)
    assert node.slam.count == 120
    scans, poses = node.slam.trajectory()
    report = slam_metrics.evaluate(poses, log.poses[scans])
    assert report.consecutive.trans_mean < 0.06 and report.consecutive.rot_mean < 1.0
    assert report.ate_rmse < 0.15
