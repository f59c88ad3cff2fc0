"""amcl's role (node type `amcl/amcl`): Monte Carlo localisation of a robot with a planar laser
on a known map. The filter is localization.amcl_filter; this file is the ROS glue.

amcl's parameter names, defaults and topics, its map from the topic or the `static_map`
service, each scan waiting for its odometry as amcl's tf message filter waits. The estimate is
saved back to ~initial_pose_* at save_pose_rate, as amcl does, so a restart keeps it. The
filter's random stream is the launch's (--seed): the same launch and seed give the same bag.
What differs from amcl: docs/ros1.md, "amcl".
"""

from __future__ import annotations

import logging
import math
from collections import deque
from dataclasses import dataclass, replace

import numpy as np

from twil_control.errors import InputError

from ..control.transforms import qmul, quat_from_yaw, yaw_from_quat
from ..core.messages import header, msg_class, to_sec
from ..core.ros_node import RosNode
from ..core.tf import TfBroadcaster, TfBuffer, TfError, transform_stamped
from ..localization.amcl_filter import Amcl, Scan, map_to_odom
from ..localization.amcl_map import AmclMap
from ..localization.amcl_params import LASER_MODELS, ODOM_MODELS, AmclParams

_WARN = logging.WARNING
MAX_PENDING = 10  # scans waiting for their odometry before the oldest is dropped
DRAIN_PERIOD = 0.02  # s: how often scans waiting for their odometry are retried
LASER_CHECK_INTERVAL = 15.0  # s without a scan before amcl warns


@dataclass
class EmptyResponse:
    """std_srvs/Empty's response."""


@dataclass
class SetMapResponse:
    success: bool = False


def _planar(pos, quat) -> np.ndarray:
    return np.array([float(pos[0]), float(pos[1]), yaw_from_quat(quat)])


class AmclNode(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        self.params = self._checked(self.typed_params(AmclParams))
        self._rng = self.master.rng(self.fqn)
        self._tf = TfBuffer(self)
        self._tf_out = TfBroadcaster(self)
        self._pose_pub = self.create_publisher(
            "amcl_pose", "geometry_msgs/PoseWithCovarianceStamped", latch=True
        )
        self._cloud_pub = self.create_publisher("particlecloud", "geometry_msgs/PoseArray", latch=True)
        self.create_subscription("scan", "sensor_msgs/LaserScan", self._on_scan)
        self.create_subscription(
            "initialpose", "geometry_msgs/PoseWithCovarianceStamped", self._on_initial_pose
        )
        if self.params.use_map_topic:
            self.create_subscription("map", "nav_msgs/OccupancyGrid", self._on_map)
        for name, handler in (
            ("global_localization", self.global_localization),
            ("request_nomotion_update", self.request_nomotion_update),
            ("set_map", self.set_map),
        ):
            self.master.advertise_service(self.resolve(name), self.fqn, handler)
        self.create_timer(DRAIN_PERIOD, lambda event: self._drain())
        self.create_timer(LASER_CHECK_INTERVAL, self._check_laser)
        self.filter: Amcl | None = None
        self._first_map_received = False
        self._initial_hyp: tuple[np.ndarray, np.ndarray] | None = None
        self._lasers: dict[str, tuple[float, float, float, float]] = {}  # frame -> x, y, angle_min, inc
        self._pending: deque = deque()  # scans waiting for their odometry
        self._latest_tf: np.ndarray | None = None  # map -> odom (x, y, yaw)
        self._sent_first_transform = False
        self._last_scan_time = 0.0
        self._last_save = -math.inf
        self.last_estimate = None  # the last published estimate (localization.amcl_filter.Estimate)

    def _checked(self, p: AmclParams) -> AmclParams:
        """amcl's own fallbacks for values it warns about rather than refuses."""
        if p.laser_model_type not in LASER_MODELS:
            self.log.warning(
                'Unknown laser model type "%s"; defaulting to likelihood_field model', p.laser_model_type
            )
            p = replace(p, laser_model_type="likelihood_field")
        if p.odom_model_type not in ODOM_MODELS:
            self.log.warning('Unknown odom model type "%s"; defaulting to diff model', p.odom_model_type)
            p = replace(p, odom_model_type="diff")
        if p.min_particles > p.max_particles:
            self.log.warning(
                "min_particles %d > max_particles %d: the filter keeps at most max_particles",
                p.min_particles,
                p.max_particles,
            )
        return p

    def on_start(self) -> None:
        if not self.params.use_map_topic:
            self._request_map(quiet=True)

    # -- the map -----------------------------------------------------------------------------
    def _request_map(self, quiet: bool = False) -> bool:
        try:
            msg = self.master.call_service(self.resolve("static_map"))
        except Exception as error:  # noqa: BLE001 - amcl retries whatever the failure
            if not quiet:
                self.log_once(_WARN, "static_map", f"Request for map failed; trying again... ({error})")
            return False
        self._handle_map(msg)
        return True

    def _on_map(self, msg) -> None:
        if self.params.first_map_only and self._first_map_received:
            return
        self._handle_map(msg)
        self._first_map_received = True

    def _handle_map(self, msg) -> None:
        info = msg.info
        self.log.info("Received a %d X %d map @ %.3f m/pix", info.width, info.height, info.resolution)
        if msg.header.frame_id != self.params.global_frame_id:
            self.log.warning(
                "Frame_id of map received:'%s' doesn't match global_frame_id:'%s'. This could cause "
                "issues with reading published topics",
                msg.header.frame_id,
                self.params.global_frame_id,
            )
        data = np.asarray(msg.data, dtype=np.int8).reshape(info.height, info.width)
        grid = AmclMap.from_occupancy(data, info.resolution, info.origin.position.x, info.origin.position.y)
        self.params = self._pose_from_server(self.params)
        self.filter = Amcl(self.params, grid, self._rng)
        self._lasers.clear()
        self._apply_initial_pose()

    def _pose_from_server(self, p: AmclParams) -> AmclParams:
        """~initial_pose_* and ~initial_cov_* as they are now on the parameter server (saved
        estimates included), NaN ignored with a warning as amcl does."""
        values = {}
        for name in (
            "initial_pose_x",
            "initial_pose_y",
            "initial_pose_a",
            "initial_cov_xx",
            "initial_cov_yy",
            "initial_cov_aa",
        ):
            value = self.get_param("~" + name, getattr(p, name))
            if isinstance(value, (int, float)) and not isinstance(value, bool) and not math.isnan(value):
                values[name] = float(value)
            else:
                self.log.warning("ignoring %r in %s", value, name)
        return replace(p, **values)

    # -- services ----------------------------------------------------------------------------
    def global_localization(self) -> EmptyResponse:
        if self.filter is not None:
            self.log.info("Initializing with uniform distribution")
            self.filter.global_localization()
            self.log.info("Global initialisation done!")
        return EmptyResponse()

    def request_nomotion_update(self) -> EmptyResponse:
        if self.filter is not None:
            self.filter.request_nomotion_update()
        return EmptyResponse()

    def set_map(self, map=None, initial_pose=None) -> SetMapResponse:  # nav_msgs/SetMap's fields
        if map is None or initial_pose is None:
            raise InputError("set_map needs a map (nav_msgs/OccupancyGrid) and an initial_pose")
        self._handle_map(map)
        self._handle_initial_pose(initial_pose)
        if self.params.force_update_after_set_map and self.filter is not None:
            self.filter.request_nomotion_update()
        return SetMapResponse(True)

    # -- the initial pose --------------------------------------------------------------------
    def _on_initial_pose(self, msg) -> None:
        self._handle_initial_pose(msg)
        if self.params.force_update_after_initialpose and self.filter is not None:
            self.filter.request_nomotion_update()

    def _handle_initial_pose(self, msg) -> None:
        p = self.params
        frame = msg.header.frame_id.lstrip("/")
        if frame == "":
            self.log.warning(
                "Received initial pose with empty frame_id.  You should always supply a frame_id."
            )
        elif frame != p.global_frame_id:
            self.log.warning(
                'Ignoring initial pose in frame "%s"; initial poses must be in the global frame, "%s"',
                frame,
                p.global_frame_id,
            )
            return
        # the robot's motion (in its own frame) between the message's stamp and now
        moved = np.zeros(3)
        try:
            then = _planar(
                *self._tf.lookup_transform(p.odom_frame_id, p.base_frame_id, to_sec(msg.header.stamp))
            )
            now = _planar(*self._tf.lookup_transform(p.odom_frame_id, p.base_frame_id))
            moved = map_to_odom(np.zeros(3), then)  # then^-1
            moved = _compose(moved, now)
        except TfError as error:
            if self._sent_first_transform:
                self.log.warning("Failed to transform initial pose in time (%s)", error)
        pose = msg.pose.pose
        old = _planar((pose.position.x, pose.position.y), _quat(pose.orientation))
        new = _compose(old, moved)
        self.log.info("Setting pose (%.6f): %.3f %.3f %.3f", self.now(), *new)
        c = np.asarray(msg.pose.covariance, dtype=float)
        cov = np.array([[c[0], c[1], 0.0], [c[6], c[7], 0.0], [0.0, 0.0, c[35]]])
        self._initial_hyp = (new, cov)
        self._apply_initial_pose()

    def _apply_initial_pose(self) -> None:
        if self._initial_hyp is not None and self.filter is not None:
            self.filter.set_pose(*self._initial_hyp)
            self._initial_hyp = None

    # -- scans -------------------------------------------------------------------------------
    def _check_laser(self, event) -> None:
        waited = self.now() - self._last_scan_time
        if waited > LASER_CHECK_INTERVAL:
            self.log.warning(
                "No laser scan received (and thus no pose updates have been published) for %f seconds.  "
                "Verify that data is being published on the %s topic.",
                waited,
                self.resolve("scan"),
            )

    def _on_scan(self, msg) -> None:
        self._last_scan_time = self.now()
        if self.filter is None and not self.params.use_map_topic:
            self._request_map()  # amcl asks static_map until it answers
        if self.filter is None:
            return  # no map yet: amcl drops scans until it has one
        self._pending.append(msg)
        self._drain()

    def _drain(self) -> None:
        """Process the waiting scans, oldest first, as far as odometry is known at their stamps;
        a scan still waiting when MAX_PENDING newer ones queue behind it is dropped (warned once)."""
        p = self.params
        while self._pending:
            msg = self._pending[0]
            t = to_sec(msg.header.stamp)
            try:
                odom = _planar(*self._tf.lookup_transform(p.odom_frame_id, p.base_frame_id, t))
            except TfError as error:
                if len(self._pending) <= MAX_PENDING:
                    return
                self._pending.popleft()
                self.log_once(_WARN, "odom", f"Failed to compute odom pose, skipping scan ({error})")
                continue
            self._pending.popleft()
            self._process(msg, t, odom)

    def _laser(self, msg, t: float) -> tuple[float, float, float, float] | None:
        """The laser's (x, y) on the robot and its angle_min and angle_increment in the robot's
        frame, looked up once per laser frame."""
        frame = msg.header.frame_id.lstrip("/")
        if frame not in self._lasers:
            try:
                pos, quat = self._tf.lookup_transform(self.params.base_frame_id, frame)
            except TfError as error:
                self.log_once(
                    logging.ERROR,
                    "laser",
                    f"Couldn't transform from {frame} to {self.params.base_frame_id} ({error})",
                )
                return None
            angle_min = yaw_from_quat(qmul(quat, quat_from_yaw(msg.angle_min)))
            second = yaw_from_quat(qmul(quat, quat_from_yaw(msg.angle_min + msg.angle_increment)))
            increment = math.fmod(second - angle_min + 5 * math.pi, 2 * math.pi) - math.pi
            self._lasers[frame] = (float(pos[0]), float(pos[1]), angle_min, increment)
        return self._lasers[frame]

    def _process(self, msg, t: float, odom: np.ndarray) -> None:
        p = self.params
        laser = self._laser(msg, t)
        if laser is None:
            return
        x, y, angle_min, increment = laser
        scan = Scan(
            np.asarray(msg.ranges, dtype=np.float32), msg.range_min, msg.range_max, angle_min, increment, x, y
        )
        step = self.filter.process(odom, scan, msg.header.frame_id.lstrip("/"))
        if step.skipped:
            self.log_once(logging.ERROR, "ranges", f"{step.skipped}: such scans are ignored")
            return
        if step.updated:
            self._publish_cloud()
        if step.estimate is not None:
            self._publish_estimate(step.estimate, t)
            self._latest_tf = map_to_odom(step.estimate.pose, odom)
            self._send_transform(t)
            self._sent_first_transform = True
        elif self._latest_tf is not None:
            self._send_transform(t)
            if p.save_pose_rate > 0 and self.now() - self._last_save >= 1.0 / p.save_pose_rate:
                self._save_pose(odom)
                self._last_save = self.now()

    # -- outputs -----------------------------------------------------------------------------
    def _send_transform(self, t: float) -> None:
        p = self.params
        if not p.tf_broadcast:
            return
        x, y, yaw = self._latest_tf
        self._tf_out.send(
            transform_stamped(
                p.global_frame_id, p.odom_frame_id, t + p.transform_tolerance, (x, y, 0.0), quat_from_yaw(yaw)
            )
        )

    def _publish_estimate(self, estimate, t: float) -> None:
        x, y, yaw = estimate.pose
        msg = msg_class("geometry_msgs/PoseWithCovarianceStamped")(
            header=header(self.params.global_frame_id, t),
            pose=msg_class("geometry_msgs/PoseWithCovariance")(
                pose=_pose(x, y, yaw), covariance=np.asarray(estimate.covariance, dtype=float)
            ),
        )
        self._pose_pub.publish(msg)
        self.last_estimate = estimate

    def _publish_cloud(self) -> None:
        poses = self.filter.pf.poses
        half = 0.5 * poses[:, 2]
        s, c = np.sin(half), np.cos(half)
        pose, point, quat = (
            msg_class(n) for n in ("geometry_msgs/Pose", "geometry_msgs/Point", "geometry_msgs/Quaternion")
        )
        items = [
            pose(point(px, py, 0.0), quat(0.0, 0.0, sz, cw))
            for px, py, sz, cw in zip(poses[:, 0].tolist(), poses[:, 1].tolist(), s.tolist(), c.tolist())
        ]
        self._cloud_pub.publish(
            msg_class("geometry_msgs/PoseArray")(
                header=header(self.params.global_frame_id, self.now()), poses=items
            )
        )

    def _save_pose(self, odom: np.ndarray) -> None:
        """The pose the latest map -> odom gives the robot, and the last estimate's covariance,
        into ~initial_pose_* and ~initial_cov_* (amcl's savePoseToServer)."""
        x, y, yaw = _compose(self._latest_tf, odom)
        values = {"initial_pose_x": x, "initial_pose_y": y, "initial_pose_a": yaw}
        if self.last_estimate is not None:
            cov = self.last_estimate.covariance
            values.update(initial_cov_xx=cov[0], initial_cov_yy=cov[7], initial_cov_aa=cov[35])
        for name, value in values.items():
            self.master.params.set(self.resolve("~" + name), float(value))


def _quat(q) -> tuple[float, float, float, float]:
    return (q.x, q.y, q.z, q.w)


def _compose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Planar a * b."""
    c, s = math.cos(a[2]), math.sin(a[2])
    yaw = a[2] + b[2]
    return np.array(
        [a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], math.atan2(math.sin(yaw), math.cos(yaw))]
    )


def _pose(x: float, y: float, yaw: float):
    return msg_class("geometry_msgs/Pose")(
        position=msg_class("geometry_msgs/Point")(x=float(x), y=float(y), z=0.0),
        orientation=msg_class("geometry_msgs/Quaternion")(
            x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)
        ),
    )
