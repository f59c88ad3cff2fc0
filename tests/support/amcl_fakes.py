"""A synthetic world for amcl's tests: test_gmapping's room (segments) as an occupancy grid, scans
ray-cast in it, odometry with drift, and the amcl node on the in-process bus fed with them."""

from __future__ import annotations

import math

import numpy as np
from test_gmapping import LASER_ANGLES, cast, room_segments

from twil_control.control.transforms import quat_from_yaw
from twil_control.core.messages import header, msg_class
from twil_control.core.node import Master, Node
from twil_control.core.tf import TF_TYPE, transform_stamped
from twil_control.launch.node_types import get
from twil_control.localization.amcl_map import AmclMap
from twil_control.mapping.map_io import OccupancyMap
from twil_control.nodes.map_msg import occupancy_grid_msg

RES = 0.05
ORIGIN = (-4.5, -3.5)
SIZE = (180, 140)  # columns, rows: 9 x 7 m around the 8 x 6 m room


def room_grid() -> OccupancyMap:
    """The room's walls and boxes as a grid: a cell is occupied when a segment passes through it
    (segments sampled every res / 8), free otherwise."""
    data = np.zeros((SIZE[1], SIZE[0]), np.int8)
    for x0, y0, x1, y1 in room_segments():
        n = int(math.ceil(math.hypot(x1 - x0, y1 - y0) / (RES / 8))) + 1
        s = np.linspace(0.0, 1.0, n)
        cols = np.floor((x0 + s * (x1 - x0) - ORIGIN[0]) / RES).astype(int)
        rows = np.floor((y0 + s * (y1 - y0) - ORIGIN[1]) / RES).astype(int)
        data[rows, cols] = 100
    return OccupancyMap(data, RES, (ORIGIN[0], ORIGIN[1], 0.0))


def room_map() -> AmclMap:
    g = room_grid()
    return AmclMap.from_occupancy(g.data, g.resolution, g.origin[0], g.origin[1])


def scan_msg(t: float, ranges, frame: str = "base_laser"):
    inc = float(LASER_ANGLES[1] - LASER_ANGLES[0])
    return msg_class("sensor_msgs/LaserScan")(
        header=header(frame, t),
        angle_min=float(LASER_ANGLES[0]),
        angle_max=float(LASER_ANGLES[-1]),
        angle_increment=inc,
        time_increment=0.0,
        scan_time=0.1,
        range_min=0.08,
        range_max=10.0,
        ranges=np.asarray(ranges, np.float32),
        intensities=np.zeros(0, np.float32),
    )


def room_scan(pose) -> np.ndarray:
    """Ranges at the robot's pose (the laser at its centre), inf beyond 10 m (REP 117)."""
    return cast(room_segments(), pose, LASER_ANGLES)


class Harness:
    """The amcl node with `params` under /amcl, a static_map service serving the room, and a
    feeder publishing odom -> base_link on /tf and scans on /scan."""

    def __init__(self, params: dict | None = None, seed: int = 0, map_service: bool = True) -> None:
        self.master = Master()
        self.master.seed = seed
        self.master.params.set("/amcl", dict(params or {}))
        if map_service:
            self.master.advertise_service("/static_map", "/map_server", self.map_message)
        self.node = get("amcl", "amcl")(self.master, "amcl", "/")
        self.feeder = Node(self.master, "feeder")
        self.tf = self.feeder.create_publisher("/tf", TF_TYPE)
        self.scan = self.feeder.create_publisher("/scan", "sensor_msgs/LaserScan")
        self.initialpose = self.feeder.create_publisher(
            "/initialpose", "geometry_msgs/PoseWithCovarianceStamped"
        )
        static = self.feeder.create_publisher("/tf_static", TF_TYPE, latch=True)
        static.publish(
            msg_class(TF_TYPE)(
                transforms=[transform_stamped("base_link", "base_laser", 0.0, (0, 0, 0.1), (0, 0, 0, 1))]
            )
        )
        self.poses: list = []  # /amcl_pose messages
        self.map_tf: list = []  # map -> odom transforms
        self.clouds: list = []
        self.feeder.create_subscription(
            "/amcl_pose", "geometry_msgs/PoseWithCovarianceStamped", self.poses.append
        )
        self.feeder.create_subscription("/particlecloud", "geometry_msgs/PoseArray", self.clouds.append)
        self.feeder.create_subscription(
            "/tf",
            TF_TYPE,
            lambda m: self.map_tf.extend(tf for tf in m.transforms if tf.header.frame_id == "map"),
        )
        self.node.on_start()
        self.t = 0.0

    def map_message(self):
        return occupancy_grid_msg(room_grid(), "map", 0.0)

    def step(self, truth, odom, rate: float = 10.0) -> None:
        """One scan period: odometry at the new time, then the scan taken at the true pose."""
        self.t += 1.0 / rate
        self.master.spin_until(self.t)
        self.tf.publish(
            msg_class(TF_TYPE)(
                transforms=[
                    transform_stamped(
                        "odom", "base_link", self.t, (odom[0], odom[1], 0.0), quat_from_yaw(odom[2])
                    )
                ]
            )
        )
        self.scan.publish(scan_msg(self.t, room_scan(truth)))

    def run(self, truth, odom, rate: float = 10.0) -> None:
        for k in range(len(truth)):
            self.step(truth[k], odom[k], rate)

    def robot_pose(self, odom) -> np.ndarray:
        """The robot's pose in the map: the latest map -> odom composed with `odom`."""
        tf = self.map_tf[-1].transform
        yaw = 2.0 * math.atan2(tf.rotation.z, tf.rotation.w)
        c, s = math.cos(yaw), math.sin(yaw)
        return np.array(
            [
                tf.translation.x + c * odom[0] - s * odom[1],
                tf.translation.y + s * odom[0] + c * odom[1],
                math.atan2(math.sin(yaw + odom[2]), math.cos(yaw + odom[2])),
            ]
        )

    def send_initial_pose(
        self, x: float, y: float, yaw: float, sd_xy: float = 0.2, sd_yaw: float = 0.2, frame: str = "map"
    ) -> None:
        cov = np.zeros(36)
        cov[0] = cov[7] = sd_xy**2
        cov[35] = sd_yaw**2
        self.initialpose.publish(
            msg_class("geometry_msgs/PoseWithCovarianceStamped")(
                header=header(frame, self.t),
                pose=msg_class("geometry_msgs/PoseWithCovariance")(
                    pose=msg_class("geometry_msgs/Pose")(
                        position=msg_class("geometry_msgs/Point")(x=x, y=y, z=0.0),
                        orientation=msg_class("geometry_msgs/Quaternion")(
                            x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)
                        ),
                    ),
                    covariance=cov,
                ),
            )
        )


def pose_error(estimate, truth) -> tuple[float, float]:
    """(position error m, heading error rad)."""
    d = float(np.hypot(estimate[0] - truth[0], estimate[1] - truth[1]))
    return d, abs(math.remainder(float(estimate[2]) - float(truth[2]), 2 * math.pi))
