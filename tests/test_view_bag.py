"""`bag play --view`: a short bag played fast into the view leaves the Meshcat scene with every
layer at its path, posed from the bag's /tf (no browser needed), and grid images are right."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import write_bag

from twil_control.control.transforms import quat_from_yaw
from twil_control.core.messages import header, msg_class
from twil_control.core.tf import TF_TYPE, transform_stamped
from twil_control.view.grid_image import grid_rgba

pytestmark = pytest.mark.usefixtures("meshcat_freed_here")  # conftest: Meshcat is thread-bound


def _tf(*transforms):
    return msg_class(TF_TYPE)(transforms=list(transforms))


def _grid(t: float, frame: str):
    info = msg_class("nav_msgs/MapMetaData")(
        map_load_time=header("", t).stamp,
        resolution=0.1,
        width=4,
        height=3,
        origin=msg_class("geometry_msgs/Pose")(
            position=msg_class("geometry_msgs/Point")(x=-1.0, y=-2.0, z=0.0),
            orientation=msg_class("geometry_msgs/Quaternion")(x=0.0, y=0.0, z=0.0, w=1.0),
        ),
    )
    data = np.array([0, 0, 100, -1, 0, 50, 100, 0, 99, 0, 0, 0], np.int8)
    return msg_class("nav_msgs/OccupancyGrid")(header=header(frame, t), info=info, data=data)


def _pose(frame, t, x, y, yaw):
    q = quat_from_yaw(yaw)
    return msg_class("geometry_msgs/PoseStamped")(
        header=header(frame, t),
        pose=msg_class("geometry_msgs/Pose")(
            position=msg_class("geometry_msgs/Point")(x=x, y=y, z=0.0),
            orientation=msg_class("geometry_msgs/Quaternion")(x=q[0], y=q[1], z=q[2], w=q[3]),
        ),
    )


@pytest.fixture
def nav_bag(tmp_path):
    """2 s of a robot driving along x at 0.5 m/s and turning at 0.2 rad/s: truth, localisation
    (map -> odom offset 0.3 m, odom -> base_link the rest), a laser 0.1 m ahead, map, scan, plan."""
    tf, scans = [], []
    for k in range(21):
        t = 0.1 * k
        x, yaw = 0.5 * t, 0.2 * t
        tf.append(
            (
                t,
                _tf(
                    transform_stamped(
                        "world", "base_link_ground_truth", t, (x, 0.0, 0.0), quat_from_yaw(yaw)
                    ),
                    transform_stamped("map", "odom", t, (0.3, 0.0, 0.0), quat_from_yaw(0.0)),
                    transform_stamped("odom", "base_link", t, (x - 0.3, 0.0, 0.0), quat_from_yaw(yaw)),
                ),
            )
        )
        scans.append(
            (
                t,
                msg_class("sensor_msgs/LaserScan")(
                    header=header("base_laser", t),
                    angle_min=-0.5,
                    angle_max=0.5,
                    angle_increment=0.5,
                    time_increment=0.0,
                    scan_time=0.1,
                    range_min=0.1,
                    range_max=5.0,
                    ranges=np.array([1.0, math.inf, 2.0], np.float32),
                    intensities=np.array([], np.float32),
                ),
            )
        )
    static = [
        (0.0, _tf(transform_stamped("base_link", "base_laser", 0.0, (0.1, 0.0, 0.2), quat_from_yaw(0.0))))
    ]
    plan = msg_class("nav_msgs/Path")(
        header=header("map", 0.5), poses=[_pose("map", 0.5, 0.1 * i, 0.0, 0.0) for i in range(10)]
    )
    return write_bag(
        tmp_path / "nav.bag",
        {
            "/tf": tf,
            "/tf_static": static,
            "/map": [(0.0, _grid(0.0, "map"))],
            "/qbot/laser/scan": scans,
            "/move_base/NavfnROS/plan": [(0.5, plan)],
            "/move_base_simple/goal": [(0.4, _pose("map", 0.4, 1.0, 0.0, 0.5))],
        },
    )


def test_bag_play_into_the_view_poses_every_layer_from_tf(nav_bag, tmp_path):
    from support.view_replay import play_with_view

    from twil_control.view.view_node import ViewOptions

    html = tmp_path / "replay.html"
    view, stats = play_with_view(nav_bag, ViewOptions(serve=False, save_html=html), rate=0.0)
    try:
        assert stats.messages == 21 + 1 + 1 + 21 + 1 + 1
        m = view.meshcat
        for path in (
            "/view/map/grid",
            "/view/scan/points",
            "/view/global_plan/line",
            "/view/goal/head",
            "/view/robot/box",
        ):
            assert m.HasPath(path), path
        placed = view.scene.placed
        # The robot stand-in at the last truth: x = 1.0 m, yaw = 0.4 rad.
        X = placed["robot"]
        assert X.translation() == pytest.approx([1.0, 0.0, 0.0], abs=1e-9)
        assert X.rotation().ToRollPitchYaw().yaw_angle() == pytest.approx(0.4, abs=1e-9)
        # The laser 0.1 m ahead of the truth, 0.2 m up.
        assert placed["scan"].translation() == pytest.approx(
            [1.0 + 0.1 * math.cos(0.4), 0.1 * math.sin(0.4), 0.2], abs=1e-9
        )
        # Localisation agrees with the truth here, so the map frame is the world (to rounding).
        assert placed["map"].GetAsMatrix4() == pytest.approx(np.eye(4), abs=1e-9)
        # The goal arrow at (1, 0) in map, heading 0.5 rad.
        assert placed["goal"].translation() == pytest.approx([1.0, 0.0, 0.0], abs=1e-9)
        assert placed["goal"].rotation().ToRollPitchYaw().yaw_angle() == pytest.approx(0.5, abs=1e-9)
    finally:
        view.shutdown()
    assert html.stat().st_size > 1_000_000 and "base64" in html.read_text()[:10_000_000]


def test_grid_images_follow_rvizs_colour_schemes():
    data = [0, 100, -1, 50, 99, 1]  # 3 x 2 grid, row 0 at the origin
    img = grid_rgba(data, 3, 2, "map")
    # Image row 0 is the grid's last row (top of the picture).
    assert img[1, :3, :3].tolist() == [[190, 215, 255], [0, 0, 0], [128, 128, 128]]  # free, occupied, unknown
    assert img[0, 0, :3].tolist() == [95, 108, 128]  # 50: half way to black
    assert (img[..., 3] == 255).all()
    cost = grid_rgba(data, 3, 2, "costmap")
    assert cost[1, 0, 3] == 0 and cost[1, 2, 3] == 0  # free and unknown: transparent
    assert tuple(cost[1, 1]) == (160, 0, 200, 220)  # lethal: purple
    assert tuple(cost[0, 1]) == (0, 255, 255, 200)  # inscribed: cyan
    assert tuple(cost[0, 2]) == (0, 0, 255, 160)  # cost 1: the blue end of the ramp
    with pytest.raises(ValueError, match="6 cells, not width x height = 4 x 2"):
        grid_rgba(data, 4, 2, "map")
    with pytest.raises(ValueError, match="one of map, costmap"):
        grid_rgba(data, 3, 2, "heat")


def test_bag_play_save_html_never_overwrites_unless_forced(nav_bag, tmp_path, capsys):
    from twil_control.bag.__main__ import main

    html = tmp_path / "replay.html"
    html.write_text("precious")
    argv = ["play", str(nav_bag), "--rate", "0", "--save-html", str(html)]
    assert main(argv) == 2
    assert "--save-html" in capsys.readouterr().err and html.read_text() == "precious"
    assert main(argv + ["--force"]) == 0
    assert html.stat().st_size > 100_000 and "<html" in html.read_text()[:2000].lower()


def test_a_recording_file_that_appears_during_the_run_is_not_replaced(nav_bag, tmp_path, caplog):
    from support.view_replay import play_with_view

    from twil_control.view.view_node import ViewOptions

    html = tmp_path / "replay.html"
    view, _ = play_with_view(nav_bag, ViewOptions(serve=False, save_html=html), rate=0.0)
    html.write_text("precious")  # appeared after the start's check, before the save
    view.shutdown()
    assert html.read_text() == "precious"
    assert "appeared during the run and is never overwritten" in caplog.text
