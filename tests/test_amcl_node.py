"""The amcl node on the in-process bus, fed a synthetic room (tests/support/amcl_fakes.py): scans ray-cast
at the true pose, drifting odometry on /tf, the map from a static_map service. Pinned down:
tracking from a wrong start, global localisation, /initialpose resetting the filter, the outputs'
frames and stamps, amcl's parameter names, map topic handling, and the same seed giving the same
estimates."""

from __future__ import annotations

import dataclasses
import logging
import math

import numpy as np
import pytest
from support.amcl_fakes import Harness, pose_error
from test_gmapping import loop_path, noisy_odometry

from twil_control.core.messages import to_sec
from twil_control.localization.amcl_params import AmclParams
from twil_control.nodes.map_msg import occupancy_grid_msg

pytestmark = pytest.mark.kernels

TRUTH = loop_path()
ODOM = noisy_odometry(TRUTH, (0.05, 0.15, 0.05, 0.15), seed=5)
# the filter's particles and beams kept small for time; started at the truth unless a test says otherwise
FAST = {
    "laser_max_beams": 30,
    "max_particles": 2000,
    "initial_pose_x": TRUTH[0][0],
    "initial_pose_y": TRUTH[0][1],
}
FAST["initial_pose_a"] = TRUTH[0][2]


def _run(h: Harness, scans: int, start: int = 0) -> np.ndarray:
    """Feed scans start..start+scans; the robot's map pose errors (m, rad) at each."""
    errs = []
    for k in range(start, start + scans):
        h.step(TRUTH[k], ODOM[k])
        errs.append(pose_error(h.robot_pose(ODOM[k]), TRUTH[k]) if h.map_tf else (math.inf, math.inf))
    return np.array(errs)


def test_tracks_the_robot_from_a_start_0_36_m_and_0_2_rad_off():
    x, y, a = TRUTH[0]
    h = Harness({**FAST, "initial_pose_x": x + 0.3, "initial_pose_y": y - 0.2, "initial_pose_a": a + 0.2})
    errs = _run(h, 250)
    assert errs[0][0] == pytest.approx(0.36, abs=0.05)  # the first estimate: the initial belief
    late = errs[150:]  # 15 s on: the odometry alone is off by 0.2-0.5 m by then
    assert late[:, 0].max() < 0.12 and late[:, 0].mean() < 0.06
    assert late[:, 1].max() < 0.15 and late[:, 1].mean() < 0.07
    odom_err = np.hypot(*(ODOM[249, :2] - TRUTH[249, :2] - (ODOM[0, :2] - TRUTH[0, :2])))
    assert odom_err > 0.15  # the drift the filter corrected


def test_global_localization_spreads_the_particles_and_converges():
    h = Harness(FAST, seed=2)
    _run(h, 1)
    h.master.call_service("/global_localization")
    _run(h, 1)
    spread = np.array([[p.position.x, p.position.y] for p in h.clouds[-1].poses])
    assert len(spread) == 2000 and np.ptp(spread[:, 0]) > 6.0 and np.ptp(spread[:, 1]) > 4.0
    errs = _run(h, 250, start=2)
    assert errs[-50:, 0].max() < 0.15 and errs[-50:, 1].max() < 0.15


def test_initialpose_resets_the_filter_around_the_given_pose():
    h = Harness(FAST)
    _run(h, 30)
    before = len(h.poses)
    x, y, a = TRUTH[29]
    h.send_initial_pose(x + 1.0, y - 0.5, a + 0.4, sd_xy=0.05, sd_yaw=0.02)
    _run(h, 1, start=30)  # the first scan after a reset publishes the estimate
    assert len(h.poses) == before + 1
    p = h.poses[-1].pose.pose
    est = (p.position.x, p.position.y, 2 * math.atan2(p.orientation.z, p.orientation.w))
    # the new belief: the given pose, moved by the odometry of the scan since (under 5 cm)
    assert pose_error(est, (x + 1.0, y - 0.5, a + 0.4))[0] < 0.1
    assert pose_error(est, (x + 1.0, y - 0.5, a + 0.4))[1] < 0.05
    cloud = np.array([[q.position.x, q.position.y] for q in h.clouds[-1].poses])
    assert cloud.std(axis=0).max() < 0.1


def test_initialpose_in_another_frame_is_ignored_with_a_warning(caplog):
    h = Harness(FAST)
    _run(h, 5)
    count = len(h.poses)
    with caplog.at_level(logging.WARNING):
        h.send_initial_pose(1.0, 1.0, 0.0, frame="odom")
    assert any('Ignoring initial pose in frame "odom"' in r.getMessage() for r in caplog.records)
    _run(h, 1, start=5)
    assert len(h.poses) == count  # no reset: no new estimate without motion


def test_outputs_frames_stamps_and_transform_tolerance():
    h = Harness({**FAST, "transform_tolerance": 0.3})
    _run(h, 40)
    pose = h.poses[-1]
    assert pose.header.frame_id == "map"
    cov = np.asarray(pose.pose.covariance).reshape(6, 6)
    assert cov[0, 0] > 0 and cov[1, 1] > 0 and cov[5, 5] > 0 and cov[2, 2] == 0.0
    stamps = [to_sec(tf.header.stamp) for tf in h.map_tf]
    assert len(stamps) == 40  # every scan re-sends map -> odom
    assert stamps[-1] == pytest.approx(h.t + 0.3)  # the last scan's stamp + transform_tolerance
    assert h.map_tf[-1].child_frame_id == "odom"
    cloud = h.clouds[-1]
    assert cloud.header.frame_id == "map" and len(cloud.poses) == len(h.node.filter.pf.poses) >= 100


def test_every_amcl_parameter_name_is_taken_and_an_unknown_one_is_one_warning(caplog):
    names = [f.name for f in dataclasses.fields(AmclParams)]
    defaults = AmclParams()
    params = {n: getattr(defaults, n) for n in names}
    params.update(FAST)
    params.update(
        laser_model_type="beam", odom_model_type="omni-corrected", laser_max_beams=20, max_particles=500
    )
    with caplog.at_level(logging.WARNING):
        h = Harness({**params, "laser_z_hits": 0.3})
    assert h.node.params.laser_model_type == "beam" and h.node.params.odom_model_type == "omni-corrected"
    warnings = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert len(warnings) == 1 and "laser_z_hits" in warnings[0] and "laser_z_hit" in warnings[0]
    _run(h, 20)  # the beam model and the omni model run
    assert pose_error(h.robot_pose(ODOM[19]), TRUTH[19])[0] < 0.15


def test_unknown_model_types_fall_back_to_amcl_s_defaults_with_a_warning(caplog):
    with caplog.at_level(logging.WARNING):
        h = Harness({"laser_model_type": "lidar", "odom_model_type": "tank"})
    assert (h.node.params.laser_model_type, h.node.params.odom_model_type) == ("likelihood_field", "diff")
    text = " ".join(r.getMessage() for r in caplog.records)
    assert 'Unknown laser model type "lidar"' in text and 'Unknown odom model type "tank"' in text


def test_map_topic_and_first_map_only():
    for first_only, expected_width in ((False, 90), (True, 180)):
        h = Harness({**FAST, "use_map_topic": True, "first_map_only": first_only}, map_service=False)
        pub = h.feeder.create_publisher("/map", "nav_msgs/OccupancyGrid")
        assert h.node.filter is None  # no map yet: scans wait
        _run(h, 1)
        grid = h.map_message()
        pub.publish(grid)
        assert h.node.filter.map.width == 180
        half = occupancy_grid_msg(_half(grid), "map", 0.0)
        pub.publish(half)
        assert h.node.filter.map.width == expected_width


def _half(msg):
    from twil_control.nodes.map_msg import map_from_msg

    m = map_from_msg(msg)
    m.data = m.data[:, :90].copy()
    return m


def test_the_map_service_is_asked_again_until_it_answers(caplog):
    h = Harness(FAST, map_service=False)
    with caplog.at_level(logging.WARNING):
        _run(h, 2)
    assert h.node.filter is None
    assert sum("Request for map failed" in r.getMessage() for r in caplog.records) == 1
    h.master.advertise_service("/static_map", "/map_server", h.map_message)
    _run(h, 1, start=2)
    assert h.node.filter is not None and h.poses


def test_the_same_seed_gives_the_same_estimates_and_another_seed_others():
    def estimates(seed):
        h = Harness({**FAST, "initial_pose_x": TRUTH[0][0] + 0.3}, seed=seed)
        _run(h, 60)
        return [(p.pose.pose.position.x, p.pose.pose.position.y) for p in h.poses]

    a = estimates(4)
    assert a == estimates(4)
    assert a != estimates(5)


def test_the_estimate_is_saved_to_the_parameter_server():
    h = Harness({**FAST, "save_pose_rate": 2.0})
    _run(h, 40)
    x, y = h.master.params.get("/amcl/initial_pose_x"), h.master.params.get("/amcl/initial_pose_y")
    assert math.hypot(x - TRUTH[39][0], y - TRUTH[39][1]) < 0.15
    assert 0 < h.master.params.get("/amcl/initial_cov_xx") < 0.25


def test_the_navigation_launch_localises_with_amcl_on_request():
    from twil_control import PACKAGE_ROOT
    from twil_control.launch.loader import load_launch

    launch = PACKAGE_ROOT / "launch/qbot_navigation.launch.yaml"
    base = {"slam": "false", "map": "/tmp/house.yaml"}
    plan = load_launch(launch, {**base, "localization": "amcl", "amcl_x": "0.3", "yaw": "1.0"})
    types = {f"{n.pkg}/{n.type}" for n in plan.nodes}
    assert "amcl/amcl" in types and "fake_localization/fake_localization" not in types
    p = plan.params
    assert (p.get("/amcl/initial_pose_x"), p.get("/amcl/initial_pose_y"), p.get("/amcl/initial_pose_a")) == (
        0.3,
        0.0,
        1.0,
    )  # amcl_x given; y and yaw from the spawn pose
    assert p.get("/amcl/laser_max_beams") == 60  # config/amcl.yaml
    assert p.get("/qbot/wheel_odometry/wheel_separation") == 1.06  # the skid-steer's effective track
    plain = load_launch(launch, base)
    assert "fake_localization/fake_localization" in {f"{n.pkg}/{n.type}" for n in plain.nodes}
    assert plain.params.get("/qbot/wheel_odometry/wheel_separation") == 0.36
