"""slam_gmapping's role: occupancy-grid SLAM from a planar laser and odometry (node type
`gmapping/slam_gmapping`). The filter is mapping.gmapping; this file is the ROS glue.

map -> odom is stamped a transform_publish_period ahead, as slam_gmapping does, so a lookup at
the current time succeeds. `processing_latency` models the filter's time on a real robot: scans
go to a worker thread and what they produce takes effect that much simulated time later; the
filter's inputs do not change, so a run stays reproducible, and a slow machine slows it without
changing it (docs/slam.md). Bad input never stops the node: a scan that cannot be used is skipped
with one warning per kind.
"""

from __future__ import annotations

import logging
import math
from collections import deque
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from ..control.transforms import quat_from_yaw, quat_rotate, yaw_from_quat
from ..core.messages import header, msg_class, time_msg, to_sec
from ..core.odometry_msg import pose_msg
from ..core.ros_node import RosNode
from ..core.tf import TfBroadcaster, TfBuffer, TfError, transform_stamped
from ..mapping.gmapping.filter import GMapping, ScanGeometry
from ..mapping.gmapping.gmapping_params import GMappingParams

_WARN = logging.WARNING
MAX_PENDING = 10  # scans (a third of a second at 30 Hz) waiting for odometry before one is dropped


class SlamGMapping(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        p = self.params = self.typed_params(GMappingParams)
        self._rng = self.master.rng(self.fqn)
        self._tf = TfBuffer(self)
        self._tf_out = TfBroadcaster(self)
        self._map_pub = self.create_publisher("map", "nav_msgs/OccupancyGrid", latch=True)
        self._meta_pub = self.create_publisher("map_metadata", "nav_msgs/MapMetaData", latch=True)
        self._entropy_pub = self.create_publisher("~entropy", "std_msgs/Float64")
        self.create_subscription("scan", "sensor_msgs/LaserScan", self._on_scan)
        if p.transform_publish_period > 0:
            self.create_timer(p.transform_publish_period, self._publish_transform)
        self.slam: GMapping | None = None
        self.map_to_odom = np.zeros(3)
        self._n_ranges: int | None = None
        self._laser_frame: str | None = None
        self._laser_count = 0
        self._last_map_time: float | None = None
        self._pending: deque = deque()  # (stamp, ranges) of scans waiting for their odometry
        # with a processing latency, the filter runs on one worker thread, scans in order, and
        # its outputs wait in _in_flight, as (due time, scan time, future), until their time
        self._worker = (
            ThreadPoolExecutor(1, thread_name_prefix="gmapping") if p.processing_latency > 0 else None
        )
        self._in_flight: deque = deque()

    # -- scans -----------------------------------------------------------------------------
    def _on_scan(self, msg) -> None:
        p = self.params
        self._collect(self.now())
        self._laser_count += 1
        if self._laser_count % p.throttle_scans != 0:
            return
        t = to_sec(msg.header.stamp)
        frame = msg.header.frame_id
        if self.slam is None and not self._start(msg, t):
            return
        if frame != self._laser_frame:
            self.log_once(
                _WARN,
                "frame",
                f"scan in frame {frame!r}, not {self._laser_frame!r} of the first "
                f"scan (the filter maps one laser): such scans are skipped",
            )
            return
        ranges = np.asarray(msg.ranges, dtype=float)
        if len(ranges) != self._n_ranges:
            self.log_once(
                _WARN,
                "size",
                f"scan with {len(ranges)} ranges on {self.resolve('scan')}; the "
                f"first scan had {self._n_ranges}: such scans are skipped",
            )
            return
        if np.isnan(ranges).any():
            self.log_once(_WARN, "nan", f"scan from {frame} holds NaN ranges: those beams count as no return")
        with np.errstate(invalid="ignore"):
            no_return = ~np.isfinite(ranges) | (ranges < msg.range_min) | (ranges >= msg.range_max)
        ranges[no_return] = np.inf
        self._pending.append((t, ranges))
        self._drain()

    def _drain(self) -> None:
        """Process the waiting scans, oldest first, as far as odometry is known at their stamps
        (slam_gmapping's tf MessageFilter: a scan waits for its odom -> base transform, which
        may be published after the scan in the same instant). A scan still waiting when
        MAX_PENDING newer ones queue behind it is dropped, with one warning."""
        p = self.params
        while self._pending:
            t, ranges = self._pending[0]
            try:
                pos, quat = self._tf.lookup_transform(p.odom_frame, p.base_frame, t)
            except TfError as error:
                if len(self._pending) <= MAX_PENDING:
                    return
                self._pending.popleft()
                self.log_once(
                    _WARN, "odom", f"no odometry for scan at {t:.3f} s ({error}); such scans are skipped"
                )
                continue
            self._pending.popleft()
            self._process(t, ranges, np.array([pos[0], pos[1], yaw_from_quat(quat)]))

    def _process(self, t: float, ranges: np.ndarray, odom: np.ndarray) -> None:
        if self._worker is None:
            self._apply(t, self._update(t, ranges, odom))
        else:
            self._in_flight.append(
                (t + self.params.processing_latency, t, self._worker.submit(self._update, t, ranges, odom))
            )

    def _update(self, t: float, ranges: np.ndarray, odom: np.ndarray):
        """One scan through the filter (on the worker thread when there is one: this touches
        the filter and nothing else). The outputs it produced, or None if the scan was not used."""
        if not self.slam.process(odom, ranges, t):
            return None
        grid = None
        if self._last_map_time is None or t - self._last_map_time > self.params.map_update_interval:
            grid = self.slam.occupancy()
            self._last_map_time = t
        return self.slam.map_to_odom(), self.slam.entropy, grid

    def _apply(self, t: float, outputs) -> None:
        if outputs is None:
            return
        self.map_to_odom, entropy, grid = outputs
        if entropy > 0.0:
            self._entropy_pub.publish(msg_class("std_msgs/Float64")(data=float(entropy)))
        if grid is not None:
            self._publish_map(t, grid)

    def _collect(self, now: float) -> None:
        """Publish, in scan order, the outputs whose time has come (waiting for the worker if it
        is not done yet)."""
        while self._in_flight and self._in_flight[0][0] <= now + 1e-9:
            _, t, future = self._in_flight.popleft()
            self._apply(t, future.result())

    def shutdown(self) -> None:
        if self._worker is not None:
            self._worker.shutdown(wait=True, cancel_futures=True)

    def _start(self, msg, t: float) -> bool:
        """Build the filter from the first scan: beam directions in the base frame."""
        p = self.params
        try:
            pos, quat = self._tf.lookup_transform(p.base_frame, msg.header.frame_id, t)
        except TfError as error:
            self.log_once(
                _WARN,
                "laser",
                f"no transform {p.base_frame} <- {msg.header.frame_id!r} "
                f"for the scan ({error}); scans are skipped until there is one",
            )
            return False
        n = len(msg.ranges)
        phi = msg.angle_min + msg.angle_increment * np.arange(n)
        dirs = np.array([quat_rotate(quat, (math.cos(a), math.sin(a), 0.0)) for a in phi])
        if np.abs(dirs[:, 2]).max() > 0.05:
            self.log_once(
                _WARN,
                "tilt",
                f"laser frame {msg.header.frame_id!r} is tilted by more than "
                f"3 deg; beams are projected onto the floor plane",
            )
        geometry = ScanGeometry(np.arctan2(dirs[:, 1], dirs[:, 0]), float(pos[0]), float(pos[1]))
        # without a worker the filter matches the particles in numba threads over both cores,
        # the simulation waiting; on the worker it matches them in one thread, beside the
        # simulation's (a second matcher thread would take the simulation's core)
        self.slam = GMapping(p, geometry, self._rng, parallel=self._worker is None)
        self._n_ranges = n
        self._laser_frame = msg.header.frame_id
        self.log.info(
            "gmapping started: %d particles, %d beams from %s, delta %.3f m",
            p.particles,
            n,
            msg.header.frame_id,
            p.delta,
        )
        return True

    # -- outputs ---------------------------------------------------------------------------
    def _publish_transform(self, event) -> None:
        p = self.params
        self._collect(self.now())
        if self._pending:
            self._drain()
        x, y, th = self.map_to_odom
        self._tf_out.send(
            transform_stamped(
                p.map_frame,
                p.odom_frame,
                self.now() + p.transform_publish_period,
                (x, y, 0.0),
                quat_from_yaw(th),
            )
        )

    def _publish_map(self, t: float, grid) -> None:
        rows, cols = grid.data.shape
        info = msg_class("nav_msgs/MapMetaData")(
            map_load_time=time_msg(t),
            resolution=float(grid.resolution),
            width=cols,
            height=rows,
            origin=pose_msg((grid.origin_x, grid.origin_y, 0.0), (0.0, 0.0, 0.0, 1.0)),
        )
        self._map_pub.publish(
            msg_class("nav_msgs/OccupancyGrid")(
                header=header(self.params.map_frame, t), info=info, data=grid.data.reshape(-1).astype(np.int8)
            )
        )
        self._meta_pub.publish(info)
