"""robot_localization's ekf_localization_node and ukf_localization_node: a Kalman filter over
the 15-variable state fusing odometry, pose, twist and IMU topics (localization/).

As robot_localization's RosFilter: each message becomes a measurement queued by its stamp, and
every 1/frequency s the queue up to now is fused in time order, so the result does not depend on
when messages arrive. Parameters, topics and differences: docs/ros1.md, "A robot's bring-up".
"""

from __future__ import annotations

import heapq
import itertools
import logging
from typing import ClassVar

import numpy as np

from ..core import names
from ..core.messages import header, msg_class, to_sec
from ..core.odometry_msg import odometry_msg
from ..core.params import ParamError, source_prefix
from ..core.ros_node import RosNode
from ..core.tf import TfBroadcaster, TfBuffer, TfError, transform_stamped
from ..localization import kalman_measurements as km
from ..localization.kalman_filter import ControlConfig, StateEstimator
from ..localization.kalman_state import (
    ACCEL,
    DEFAULT_INITIAL_COVARIANCE,
    DEFAULT_PROCESS_NOISE,
    NAMES,
    STATE_SIZE,
    VROLL,
    matrix_from_quat,
    quat_from_matrix,
    quat_from_rpy,
)
from ..localization.ukf import UkfWeights
from . import ekf_params
from .ekf_params import FilterParams, SensorParams


def _cov(values, n: int) -> np.ndarray:
    return np.asarray(values, dtype=float).reshape(n, n)


def _vec(v) -> np.ndarray:
    return np.array([v.x, v.y, v.z], dtype=float)


class EkfLocalization(RosNode):
    kind: ClassVar[str] = "ekf"

    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        p = self.params = self.typed_params(FilterParams)
        server, private = self.master.params, names.resolve("~", self.namespace, self.name)
        self._check_frames()
        self.world_frame = p.world_frame or p.odom_frame
        self.base_output = p.base_link_frame_output or p.base_link_frame
        sensors, _ = ekf_params.read_sensors(server, private, self.log.warning)
        self.filter = StateEstimator(
            kind=self.kind,
            process_noise=ekf_params.matrix(
                server,
                f"{private}/process_noise_covariance",
                p.process_noise_covariance,
                DEFAULT_PROCESS_NOISE,
            ),
            sensor_timeout=p.sensor_timeout if p.sensor_timeout is not None else 1.0 / p.frequency,
            dynamic_process_noise=p.dynamic_process_noise_covariance,
            ukf_weights=UkfWeights.of(p.alpha, p.kappa, p.beta) if self.kind == "ukf" else None,
        )
        self.filter.covariance = ekf_params.matrix(
            server,
            f"{private}/initial_estimate_covariance",
            p.initial_estimate_covariance,
            DEFAULT_INITIAL_COVARIANCE,
        )
        if p.initial_state is not None:
            if len(p.initial_state) != STATE_SIZE:
                raise ParamError(
                    f"{source_prefix(server.source_of(private + '/initial_state'))}parameter "
                    f"{private + '/initial_state'!r} must have {STATE_SIZE} entries (got {len(p.initial_state)})"
                )
            self.filter.state = np.array(p.initial_state, dtype=float)
        self.filter.last_measurement_time = self.now()
        self.filter.control = self._control_config(server, private, sensors)
        self.silent_tf = bool(self.get_param("/silent_tf_failure", False))
        self.tf = TfBuffer(self)
        self._br = TfBroadcaster(self)
        self._queue: list = []
        self._seq = itertools.count()
        self._last_times: dict[str, float] = {}
        self._memory: dict[str, km.PoseSensorMemory] = {}
        self._last_set_pose = 0.0
        self._last_published: float | None = None
        self._angular_accel = np.zeros(3)
        self._last_rates = np.zeros(3)
        self._last_diff_time = 0.0
        self.enabled = not p.disabled_at_startup
        self.toggled_on = True
        self._pub = self.create_publisher("odometry/filtered", "nav_msgs/Odometry")
        self._accel_pub = (
            self.create_publisher("accel/filtered", "geometry_msgs/AccelWithCovarianceStamped")
            if p.publish_acceleration
            else None
        )
        for sensor in sensors:
            self._subscribe(sensor)
        self._diagnose(sensors)
        self.create_subscription("set_pose", "geometry_msgs/PoseWithCovarianceStamped", self.set_pose)
        self.master.advertise_service(self.resolve("set_pose"), self.fqn, self.set_pose)
        self.master.advertise_service(self.resolve("~enable"), self.fqn, self._enable)
        self.master.advertise_service(self.resolve("~toggle"), self.fqn, self._toggle)
        self.create_timer(1.0 / p.frequency, self._update)

    # -- set-up --------------------------------------------------------------------
    def _check_frames(self) -> None:
        p = self.params
        output = p.base_link_frame_output or p.base_link_frame
        pairs = (
            (p.map_frame, p.odom_frame),
            (p.odom_frame, p.base_link_frame),
            (p.map_frame, p.base_link_frame),
        )
        if any(a == b for a, b in pairs) or output in (p.map_frame, p.odom_frame):
            raise ParamError(
                f"node {self.fqn}: map_frame {p.map_frame!r}, odom_frame {p.odom_frame!r} and "
                f"base_link_frame {p.base_link_frame!r} must be unique, and base_link_frame_output "
                f"{output!r} must be neither map_frame nor odom_frame (robot_localization's frames)"
            )
        world = p.world_frame or p.odom_frame
        if world not in (p.map_frame, p.odom_frame):
            raise ParamError(
                f"node {self.fqn}: world_frame {world!r} must be map_frame ({p.map_frame!r}) or "
                f"odom_frame ({p.odom_frame!r})"
            )
        if p.tf_prefix:
            self.log.warning("tf_prefix %r has no effect: frames are used as given (tf2)", p.tf_prefix)

    def _control_config(self, server, private: str, sensors: list[SensorParams]) -> ControlConfig | None:
        p = self.params
        if not p.use_control:
            return None
        if p.control_config is None or len(p.control_config) != 6:
            self.log.error(
                "use_control is set to true, but control_config is missing or not 6 entries. "
                "No control term will be used."
            )
            return None
        update = np.array(p.control_config, dtype=bool)
        for sensor in sensors:  # an IMU measuring an acceleration disables its control input
            if sensor.kind == "imu":
                for i in range(3):
                    if update[i] and sensor.config[12 + i]:
                        self.log.warning(
                            "%s acceleration is being measured from IMU; %s velocity control input is "
                            "disabled",
                            "XYZ"[i],
                            "XYZ"[i],
                        )
                        update[i] = False
        if not update.any():
            self.log.error(
                "use_control is set to true, but control_config has only false values. "
                "No control term will be used."
            )
            return None
        accel_limits = ekf_params.six(server, f"{private}/acceleration_limits", p.acceleration_limits, 1.0)
        accel_gains = ekf_params.six(server, f"{private}/acceleration_gains", p.acceleration_gains, 1.0)
        decel_limits = (
            ekf_params.six(server, f"{private}/deceleration_limits", p.deceleration_limits, 1.0)
            if p.deceleration_limits is not None
            else accel_limits
        )
        decel_gains = (
            ekf_params.six(server, f"{private}/deceleration_gains", p.deceleration_gains, 1.0)
            if p.deceleration_gains is not None
            else accel_gains
        )
        timeout = p.control_timeout if p.control_timeout is not None else self.filter.sensor_timeout
        msgtype = "geometry_msgs/TwistStamped" if p.stamped_control else "geometry_msgs/Twist"
        self.create_subscription("cmd_vel", msgtype, self._on_control)
        return ControlConfig(update, timeout, accel_limits, accel_gains, decel_limits, decel_gains)

    def _subscribe(self, s: SensorParams) -> None:
        pose_cfg, twist_cfg, accel_cfg = (np.zeros(STATE_SIZE, dtype=bool) for _ in range(3))
        if s.kind in ("odom", "pose"):
            pose_cfg[:6] = s.config[:6]
        if s.kind in ("odom", "twist"):
            twist_cfg[6:12] = s.config[6:12]
        if s.kind == "imu":
            pose_cfg[3:6] = s.config[3:6]
            twist_cfg[9:12] = s.config[9:12]
            accel_cfg[12:15] = s.config[12:15]
            if s.config[0:3].any():
                self.log.warning(
                    "Some position entries in parameter %s_config are listed true, but "
                    "sensor_msgs/Imu contains no information about position",
                    s.name,
                )
            if s.config[6:9].any():
                self.log.warning(
                    "Some linear velocity entries in parameter %s_config are listed true, but "
                    "an sensor_msgs/Imu contains no information about linear velocities",
                    s.name,
                )
        s.parts = (pose_cfg, twist_cfg, accel_cfg)
        if not (pose_cfg.any() or twist_cfg.any() or accel_cfg.any()):
            self.log.warning(
                "%s is listed as an input topic, but all its update variables are false", s.topic
            )
            return
        callback, msgtype = {
            "odom": (self._on_odometry, "nav_msgs/Odometry"),
            "pose": (self._on_pose, "geometry_msgs/PoseWithCovarianceStamped"),
            "twist": (self._on_twist, "geometry_msgs/TwistWithCovarianceStamped"),
            "imu": (self._on_imu, "sensor_msgs/Imu"),
        }[s.kind]
        self.create_subscription(s.topic, msgtype, lambda msg, s=s: callback(msg, s))

    def _diagnose(self, sensors: list[SensorParams]) -> None:
        """robot_localization's configuration diagnostics, as warnings at start."""
        if not self.params.print_diagnostics:
            return
        absolute, rates = np.zeros(6, dtype=int), np.zeros(6, dtype=int)
        for s in sensors:
            pose, twist, _ = s.parts
            if s.differential:
                rates += pose[:6]
            else:
                absolute += pose[:6]
            rates += twist[6:12]
        for i in range(6):
            if absolute[i] > 1:
                self.log.warning(
                    "%d absolute pose inputs detected for %s. This may result in oscillations.",
                    absolute[i],
                    NAMES[i],
                )
            elif absolute[i] == 0 and rates[i] == 0 and not (self.params.two_d_mode and i in (2, 3, 4)):
                self.log.warning(
                    "Neither %s nor its velocity is being measured. This will result in "
                    "unbounded error growth and erratic filter behavior.",
                    NAMES[i],
                )

    # -- transforms ----------------------------------------------------------------
    def _lookup(self, target: str, source: str, t: float) -> km.Transform | None:
        """`source` in `target` at `t`, else the latest, else None (lookupTransformSafe)."""
        if target == source:
            return km.IDENTITY
        try:
            p, q = self.tf.lookup_transform(target, source, t)
        except TfError:
            try:
                p, q = self.tf.lookup_transform(target, source)
            except TfError as exc:
                if not self.silent_tf:
                    self.log_once(
                        logging.WARNING,
                        f"tf {source} {target}",
                        f"Could not obtain transform from {source} to {target}: {exc}",
                    )
                return None
        return matrix_from_quat(q), np.asarray(p, dtype=float)

    # -- callbacks -----------------------------------------------------------------
    def _fresh(self, key: str, stamp: float) -> float | None:
        """The time since `key`'s previous message, or None when the message is to be ignored."""
        if stamp <= self._last_set_pose:
            return None
        last = self._last_times.setdefault(key, stamp)
        if stamp < last:
            self.log_once(
                logging.WARNING,
                f"old {key}",
                f"The {key} message has a timestamp before that of the previous message received, "
                f"this message will be ignored.",
            )
            return None
        return stamp - last

    def _enqueue(self, m: km.Measurement) -> None:
        heapq.heappush(self._queue, (m.time, next(self._seq), m))

    def _pose(self, key, s: SensorParams, stamp, *pose) -> None:
        """A pose measurement (the rest of _prepare_pose's arguments in `pose`), once fresh; its
        stamp becomes the sensor's last even when the measurement is refused."""
        dt = self._fresh(key, stamp)
        if dt is None:
            return
        try:
            self._prepare_pose(key, s, stamp, *pose, dt)
        finally:
            self._last_times[key] = stamp

    def _prepare_pose(
        self,
        key,
        s,
        stamp,
        frame,
        position,
        orientation,
        cov36,
        config,
        target_frame,
        source_frame,
        imu,
        threshold,
        dt,
    ) -> None:
        p = self.params
        q = np.array([orientation.x, orientation.y, orientation.z, orientation.w], dtype=float)
        norm = float(np.linalg.norm(q))
        if norm == 0.0:
            q = np.array([0.0, 0.0, 0.0, 1.0])
            if config[3:6].any():
                self.log_once(
                    logging.WARNING,
                    f"quat {key}",
                    f"The {key} message contains an invalid "
                    f"orientation quaternion, but its configuration is such that orientation data is "
                    f"being used. Correcting...",
                )
        elif abs(norm - 1.0) > 0.01:
            self.log_once(
                logging.WARNING,
                "normalize",
                "An input was not normalized, this should NOT happen, but will normalize.",
            )
            q = q / norm
        else:
            q = q / norm
        pose_frame = target_frame if (s.differential and not imu) else frame
        target = self._lookup(target_frame, pose_frame, stamp)
        if target is None:
            return
        source = None
        if source_frame != p.base_link_frame:
            source = self._lookup(source_frame, p.base_link_frame, stamp)
        twist_frame = km.IDENTITY
        if s.differential and source_frame != p.base_link_frame:
            twist_frame = self._lookup(p.base_link_frame, source_frame, stamp) or km.IDENTITY
        m = km.Measurement(key, stamp, rejection_threshold=threshold)
        memory = self._memory.setdefault(key, km.PoseSensorMemory())
        ok = km.prepare_pose(
            m,
            (matrix_from_quat(q), np.array([position.x, position.y, position.z], dtype=float)),
            _cov(cov36, 6),
            config,
            target,
            source,
            memory,
            dt,
            s.differential,
            s.relative,
            imu,
            self.filter.state,
            p.two_d_mode,
            twist_frame,
        )
        if ok:
            self._enqueue(m)

    def _twist(self, key, stamp, frame, linear, angular, cov36, config, threshold) -> None:
        if self._fresh(key, stamp) is None:
            return
        self._last_times[key] = stamp
        target = self._lookup(self.params.base_link_frame, frame or self.params.base_link_frame, stamp)
        if target is None:
            return
        m = km.Measurement(key, stamp, rejection_threshold=threshold)
        km.prepare_twist(
            m, linear, angular, _cov(cov36, 6), config, target, self.filter.state, self.params.two_d_mode
        )
        self._enqueue(m)

    def _on_odometry(self, msg, s: SensorParams) -> None:
        stamp = to_sec(msg.header.stamp)
        pose_cfg, twist_cfg, _ = s.parts
        if pose_cfg.any():
            source = msg.child_frame_id if s.pose_use_child_frame else self.params.base_link_frame
            pose = msg.pose.pose
            self._pose(
                f"{s.name}_pose",
                s,
                stamp,
                msg.header.frame_id,
                pose.position,
                pose.orientation,
                msg.pose.covariance,
                pose_cfg,
                self.world_frame,
                source,
                False,
                s.threshold("pose"),
            )
        if twist_cfg.any():
            twist = msg.twist.twist
            self._twist(
                f"{s.name}_twist",
                stamp,
                msg.child_frame_id,
                _vec(twist.linear),
                _vec(twist.angular),
                msg.twist.covariance,
                twist_cfg,
                s.threshold("twist"),
            )

    def _on_pose(self, msg, s: SensorParams) -> None:
        pose = msg.pose.pose
        self._pose(
            s.name,
            s,
            to_sec(msg.header.stamp),
            msg.header.frame_id,
            pose.position,
            pose.orientation,
            msg.pose.covariance,
            s.parts[0],
            self.world_frame,
            self.params.base_link_frame,
            False,
            s.threshold("pose"),
        )

    def _on_twist(self, msg, s: SensorParams) -> None:
        twist = msg.twist.twist
        self._twist(
            s.name,
            to_sec(msg.header.stamp),
            msg.header.frame_id,
            _vec(twist.linear),
            _vec(twist.angular),
            msg.twist.covariance,
            s.parts[1],
            s.threshold("twist"),
        )

    def _on_imu(self, msg, s: SensorParams) -> None:
        stamp = to_sec(msg.header.stamp)
        if stamp <= self._last_set_pose:
            return
        pose_cfg, twist_cfg, accel_cfg = s.parts
        base = self.params.base_link_frame
        if pose_cfg.any() and abs(msg.orientation_covariance[0] + 1.0) >= 1e-9:
            cov = np.zeros((6, 6))
            cov[3:, 3:] = _cov(msg.orientation_covariance, 3)
            zero = msg_class("geometry_msgs/Point")(x=0.0, y=0.0, z=0.0)
            self._pose(
                f"{s.name}_pose",
                s,
                stamp,
                msg.header.frame_id,
                zero,
                msg.orientation,
                cov.reshape(36),
                pose_cfg,
                base,
                base,
                True,
                s.threshold("pose"),
            )
        if twist_cfg.any() and abs(msg.angular_velocity_covariance[0] + 1.0) >= 1e-9:
            cov = np.zeros((6, 6))
            cov[3:, 3:] = _cov(msg.angular_velocity_covariance, 3)
            self._twist(
                f"{s.name}_twist",
                stamp,
                msg.header.frame_id,
                np.zeros(3),
                _vec(msg.angular_velocity),
                cov.reshape(36),
                twist_cfg,
                s.threshold("twist"),
            )
        if accel_cfg.any() and abs(msg.linear_acceleration_covariance[0] + 1.0) >= 1e-9:
            self._acceleration(msg, s, stamp, accel_cfg)

    def _acceleration(self, msg, s: SensorParams, stamp: float, config) -> None:
        key = f"{s.name}_acceleration"
        if self._fresh(key, stamp) is None:
            return
        self._last_times[key] = stamp
        target = self._lookup(
            self.params.base_link_frame, msg.header.frame_id or self.params.base_link_frame, stamp
        )
        if target is None:
            return
        attitude = None
        if abs(msg.orientation_covariance[0] + 1.0) >= 1e-9:
            o = msg.orientation
            q = np.array([o.x, o.y, o.z, o.w], dtype=float)
            attitude = matrix_from_quat(q / (np.linalg.norm(q) or 1.0))
        m = km.Measurement(key, stamp, rejection_threshold=s.threshold("acceleration"))
        km.prepare_acceleration(
            m,
            _vec(msg.linear_acceleration),
            _cov(msg.linear_acceleration_covariance, 3),
            config,
            target,
            self.filter.state,
            self._angular_accel,
            self.params.gravitational_acceleration if s.remove_gravitational_acceleration else None,
            attitude,
            s.relative,
            self.params.two_d_mode,
        )
        self._enqueue(m)

    def _on_control(self, msg) -> None:
        if self.params.stamped_control:
            if msg.header.frame_id not in ("", self.params.base_link_frame):
                self.log_once(
                    logging.WARNING,
                    "control frame",
                    "Commanded velocities must be given in the "
                    f"robot's body frame ({self.params.base_link_frame}). Message frame was "
                    f"{msg.header.frame_id}",
                )
                return
            t, twist = to_sec(msg.header.stamp), msg.twist
        else:
            t, twist = self.now(), msg
        self.filter.set_control(np.concatenate([_vec(twist.linear), _vec(twist.angular)]), t)

    def set_pose(self, msg) -> None:
        """Reset the estimate to a pose (the set_pose topic and service)."""
        self.log.info("Received set_pose request")
        self._memory.clear()
        self._queue.clear()
        self._last_set_pose = to_sec(msg.header.stamp)
        m = km.Measurement("setPose", self._last_set_pose)
        m.covariance[:] = np.eye(STATE_SIZE) * 1e-6
        pose = msg.pose.pose
        o = pose.orientation
        q = np.array([o.x, o.y, o.z, o.w], dtype=float)
        q = q / np.linalg.norm(q) if np.linalg.norm(q) > 0 else np.array([0.0, 0.0, 0.0, 1.0])
        target = self._lookup(self.world_frame, msg.header.frame_id or self.world_frame, self._last_set_pose)
        km.prepare_pose(
            m,
            (matrix_from_quat(q), np.array([pose.position.x, pose.position.y, pose.position.z])),
            _cov(msg.pose.covariance, 6),
            np.ones(STATE_SIZE, dtype=bool),
            target or km.IDENTITY,
            None,
            km.PoseSensorMemory(),
            0.0,
            False,
            False,
            False,
            self.filter.state,
            self.params.two_d_mode,
        )
        self.filter.state = m.z.copy()
        self.filter.covariance = m.covariance.copy()
        self.filter.last_measurement_time = self.now()

    def _enable(self, *_):
        if self.enabled:
            self.log.warning(
                "Asking for enabling filter service, but the filter was already enabled! "
                "Use param disabled_at_startup."
            )
        self.enabled = True
        return True

    def _toggle(self, on: bool = True):
        if on == self.toggled_on:
            self.log.warning(
                "Service was called to toggle filter processing but state was already as requested."
            )
            return False
        self.log.info("Toggling filter measurement filtering to %s.", "On" if on else "Off")
        self.toggled_on = on
        return True

    # -- the periodic update -------------------------------------------------------
    def _integrate(self, now: float) -> None:
        f = self.filter
        predict_now = self.params.predict_to_current_time
        if self._queue:
            while self._queue and self._queue[0][0] <= now:
                f.process_measurement(heapq.heappop(self._queue)[2])
        elif f.initialized and now - f.last_measurement_time >= f.sensor_timeout:
            predict_now = True
        if f.initialized and predict_now:
            f.predict_to(now)

    def _differentiate(self, now: float) -> None:
        f = self.filter
        if not f.initialized:
            return
        dt = now - self._last_diff_time
        rates = f.state[VROLL : VROLL + 3].copy()
        if dt > 0:
            self._angular_accel = (rates - self._last_rates) / dt
        self._last_rates, self._last_diff_time = rates, now

    def _update(self, _event) -> None:
        if not self.enabled:
            self.log_once(
                logging.INFO,
                "disabled",
                f"Filter is disabled. To enable it call the {self.resolve('~enable')} service",
            )
            return
        now = self.now()
        if self.toggled_on:
            self._integrate(now)
            self._differentiate(now)
        else:
            self._queue.clear()
            if self.filter.initialized:
                self.filter.last_measurement_time = now
        if not self.filter.initialized:
            return
        self._publish()

    def _publish(self) -> None:
        p, f = self.params, self.filter
        x, cov = f.state, f.covariance
        if not np.all(np.isfinite(x)):
            self.log_once(
                logging.ERROR,
                "nan",
                "Critical Error, NaNs were detected in the output state of the "
                "filter. This was likely due to poorly conditioned process, noise, or sensor covariances.",
            )
        stamp = f.last_measurement_time
        corrected = (
            not p.permit_corrected_publication
            and self._last_published is not None
            and (self._last_published >= stamp)
        )
        q = quat_from_rpy(x[3], x[4], x[5])
        if p.publish_tf and not corrected:
            self._send_tf(stamp + p.transform_time_offset, x[:3], q)
        if not corrected:
            self._pub.publish(
                odometry_msg(
                    stamp,
                    self.world_frame,
                    self.base_output,
                    x[:3],
                    q,
                    x[6:9],
                    x[9:12],
                    cov[:6, :6].reshape(36),
                    cov[6:12, 6:12].reshape(36),
                )
            )
            if self._accel_pub is not None:
                self._publish_accel(stamp)
        self._last_published = stamp

    def _send_tf(self, t: float, position, q) -> None:
        p = self.params
        if p.invert_tf or self.world_frame == p.odom_frame:
            rot = matrix_from_quat(q)
            if p.invert_tf:
                inv = km.inverse((rot, np.asarray(position)))
                self._br.send(
                    transform_stamped(self.base_output, self.world_frame, t, inv[1], quat_from_matrix(inv[0]))
                )
            else:
                self._br.send(transform_stamped(self.world_frame, self.base_output, t, position, q))
            return
        base_odom = self._lookup(p.base_link_frame, p.odom_frame, t - p.transform_time_offset)
        if base_odom is None:
            self.log_once(
                logging.ERROR,
                "map odom",
                f"Could not obtain transform from {p.odom_frame}->{p.base_link_frame}",
            )
            return
        map_odom = km.compose((matrix_from_quat(q), np.asarray(position, dtype=float)), base_odom)
        self._br.send(
            transform_stamped(p.map_frame, p.odom_frame, t, map_odom[1], quat_from_matrix(map_odom[0]))
        )

    def _publish_accel(self, stamp: float) -> None:
        vec = msg_class("geometry_msgs/Vector3")
        cov = np.zeros((6, 6))
        cov[:3, :3] = self.filter.covariance[ACCEL, ACCEL]
        a = self.filter.state[ACCEL]
        w = self._angular_accel
        self._accel_pub.publish(
            msg_class("geometry_msgs/AccelWithCovarianceStamped")(
                header=header(self.base_output, stamp),
                accel=msg_class("geometry_msgs/AccelWithCovariance")(
                    accel=msg_class("geometry_msgs/Accel")(
                        linear=vec(x=float(a[0]), y=float(a[1]), z=float(a[2])),
                        angular=vec(x=float(w[0]), y=float(w[1]), z=float(w[2])),
                    ),
                    covariance=cov.reshape(36),
                ),
            )
        )


class UkfLocalization(EkfLocalization):
    kind: ClassVar[str] = "ukf"
