"""The simulated planar laser's Drake side: each scan, the sensor's world pose and the scene
cut at its height (world.laser_scene); the ray casting and the message are the node's.

The scan plane is horizontal through the sensor frame's origin, at the frame's heading (the
yaw of its x axis); the sensor's small roll and pitch are ignored (a robot on a flat floor tilts
its laser by well under a degree; a tilted plane would see the floor), but a sensor mounted
upside down (its z axis pointing down: Husky's LMS1xx on its tower) sweeps the other way round,
as Gazebo's ray sensor in that frame does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.geometry import QueryObject
from pydrake.systems.framework import EventStatus, LeafSystem

from .laser_scene import LaserScene


@dataclass
class ScanInput:
    """What one scan is cast from: the sensor's pose in the world and the 2D scene."""

    t: float
    x: float
    y: float
    z: float
    yaw: float
    segments: np.ndarray  # (N, 4) [x0, y0, x1, y1]
    circles: np.ndarray  # (M, 3) [cx, cy, r]
    upside_down: bool = False  # the sensor's z axis points down: its angles turn clockwise


class LaserScanner(LeafSystem):
    """Calls report(ScanInput) every `period` seconds of simulated time, from t = 0.

    `sensor_body` is the plant body whose frame is the scan's; geometry of `exclude` (model
    instances, normally the robot carrying the sensor) is not seen.
    """

    def __init__(self, sim, sensor_body, exclude, period: float, report, clock, offset=None) -> None:
        super().__init__()
        # the sensor's pose in the body (a Gazebo sensor's <pose>: x y z roll pitch yaw), if any
        self._offset = None
        if offset is not None and any(offset):
            from pydrake.math import RigidTransform, RollPitchYaw

            self._offset = RigidTransform(RollPitchYaw(*offset[3:]), list(offset[:3]))
        self.scene = LaserScene(
            sim.plant,
            sim.scene_graph.model_inspector(),
            exclude,
            extra=[(gid, s.shape) for gid, s in sim.windowed_shapes],
        )
        # The sensor's pose comes from the query object (the scene graph's copy of the plant's
        # body poses, bit for bit): the plant's body-pose port would hand Python every body of
        # the world at every scan.
        self._frame = sim.plant.GetBodyFrameIdOrThrow(sensor_body.index())
        self._report = report
        self._clock = clock
        self._query = self.DeclareAbstractInputPort("query", AbstractValue.Make(QueryObject()))
        self.DeclarePeriodicPublishEvent(period, 0.0, self._on_tick)

    def connect(self, sim) -> None:
        sim.builder.Connect(sim.scene_graph.get_query_output_port(), self._query)

    def scan_input(self, context) -> ScanInput:
        """The sensor pose and the scene at this context's time (also used by tests)."""
        query = self._query.Eval(context)
        X_WS = query.GetPoseInWorld(self._frame)
        if self._offset is not None:
            X_WS = X_WS @ self._offset
        R, p = X_WS.rotation().matrix(), X_WS.translation()
        segments, circles = self.scene.arrays(query, float(p[2]))
        return ScanInput(
            context.get_time(),
            float(p[0]),
            float(p[1]),
            float(p[2]),
            math.atan2(R[1, 0], R[0, 0]),
            segments,
            circles,
            bool(R[2, 2] < 0.0),
        )

    def _on_tick(self, context) -> EventStatus:
        self._clock.set(context.get_time())
        self._report(self.scan_input(context))
        return EventStatus.Succeeded()


def mount_transform(plant, parent_body, child_body) -> tuple[np.ndarray, np.ndarray]:
    """(translation, quaternion xyzw) of child_body's frame in parent_body's, from the plant's
    default context: for bodies welded together (a sensor mount) it is the description's fixed
    chain, e.g. base_link -> hokuyo_link -> base_laser in the qbot URDF."""
    context = plant.CreateDefaultContext()
    X = plant.CalcRelativeTransform(context, parent_body.body_frame(), child_body.body_frame())
    q = X.rotation().ToQuaternion()
    return np.array(X.translation()), np.array([q.x(), q.y(), q.z(), q.w()])
