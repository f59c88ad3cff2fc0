"""Drawing ROS messages into a Meshcat scene, one scene path per layer so each layer has its own
visibility toggle in Meshcat's scene tree (rviz's displays).

Every layer lives at /view/<layer>; its pose in the Drake world is set on that path (the frame
the message is expressed in, placed in the world by the view's tf anchoring), and its geometry
below it, expressed in the message's frame.
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import cv2
import numpy as np
from pydrake.geometry import Box, Cylinder, Mesh, MeshcatCone, Rgba
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix
from pydrake.perception import BaseField, Fields, PointCloud

from twil_control.errors import InputError

from .grid_image import grid_rgba

ROOT = "/view"
LAYERS = (
    "map",
    "global_costmap",
    "local_costmap",
    "scan",
    "global_plan",
    "local_plan",
    "goal",
    "cart_reference",
    "robot",
)
HEIGHTS = {"map": 0.002, "global_costmap": 0.004, "local_costmap": 0.006}  # m: no z-fighting


def layer_path(layer: str) -> str:
    if layer not in LAYERS:
        raise InputError(f"unknown view layer {layer!r} (layers: {', '.join(LAYERS)})")
    return f"{ROOT}/{layer}"


def pose_transform(translation, quaternion_xyzw) -> RigidTransform:
    from pydrake.common.eigen_geometry import Quaternion

    x, y, z, w = (float(v) for v in quaternion_xyzw)
    n = math.sqrt(x * x + y * y + z * z + w * w) or 1.0
    return RigidTransform(Quaternion(w / n, x / n, y / n, z / n), np.asarray(translation, float))


class Scene:
    """The view's layers in one Meshcat; texture files go to a private temporary directory."""

    def __init__(self, meshcat) -> None:
        self.meshcat = meshcat
        self._tmp = tempfile.TemporaryDirectory(prefix="twil_view_")
        self._serial = 0
        self._arrows: set[str] = set()
        self.placed: dict[str, RigidTransform] = {}  # layer -> the last pose sent to Meshcat

    def close(self) -> None:
        self._tmp.cleanup()

    def place(
        self, layer: str, X_world_frame: RigidTransform, time_in_recording: float | None = None
    ) -> None:
        self.meshcat.SetTransform(layer_path(layer), X_world_frame, time_in_recording)
        self.placed[layer] = X_world_frame

    # -- grids as textured planes ------------------------------------------------------------
    def grid(self, layer: str, msg, scheme: str) -> None:
        """An OccupancyGrid as a textured plane at its origin (in the message's frame)."""
        info = msg.info
        w, h, res = int(info.width), int(info.height), float(info.resolution)
        if w == 0 or h == 0:
            return
        self._serial += 1
        stem = Path(self._tmp.name) / f"{layer}_{self._serial}"
        cv2.imwrite(
            str(stem.with_suffix(".png")),
            cv2.cvtColor(grid_rgba(msg.data, w, h, scheme), cv2.COLOR_RGBA2BGRA),
        )
        # `d` below 1 makes three.js treat the material as transparent, so a costmap's alpha counts.
        # The map stays opaque: drawn in the opaque pass, before the costmaps, a costmap's clear
        # cells (which still write depth) cannot hide it.
        d = "1" if scheme == "map" else "0.999"
        stem.with_suffix(".mtl").write_text(
            f"newmtl grid\nKa 1 1 1\nKd 1 1 1\nd {d}\nmap_Kd {stem.name}.png\n"
        )
        W, H = w * res, h * res
        stem.with_suffix(".obj").write_text(
            f"mtllib {stem.name}.mtl\nv 0 0 0\nv {W} 0 0\nv {W} {H} 0\nv 0 {H} 0\n"
            "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nusemtl grid\nf 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n"
        )
        o = info.origin
        X_frame_origin = pose_transform(
            (o.position.x, o.position.y, o.position.z + HEIGHTS.get(layer, 0.0)),
            (o.orientation.x, o.orientation.y, o.orientation.z, o.orientation.w),
        )
        path = layer_path(layer) + "/grid"
        self.meshcat.SetObject(path, Mesh(str(stem.with_suffix(".obj"))))
        self.meshcat.SetTransform(path, X_frame_origin)
        for old in Path(self._tmp.name).glob(f"{layer}_*"):  # Meshcat has read them; keep only the newest
            if not old.name.startswith(f"{stem.name}."):
                old.unlink(missing_ok=True)

    # -- points and lines -----------------------------------------------------------------------
    def points(self, layer: str, xyz: np.ndarray, rgba: Rgba, size: float = 0.04) -> None:
        cloud = PointCloud(xyz.shape[1], Fields(BaseField.kXYZs))
        cloud.mutable_xyzs()[:] = xyz
        self.meshcat.SetObject(layer_path(layer) + "/points", cloud, size, rgba)

    def line(self, layer: str, xyz: np.ndarray, rgba: Rgba, width: float = 3.0) -> None:
        if xyz.shape[1] < 2:
            self.meshcat.Delete(layer_path(layer) + "/line")
            return
        self.meshcat.SetLine(layer_path(layer) + "/line", xyz, width, rgba)

    # -- markers ---------------------------------------------------------------------------------
    def arrow(self, layer: str, rgba: Rgba, length: float = 0.6, radius: float = 0.025) -> None:
        """An arrow along the layer frame's +x, drawn once; move it with `place`."""
        if layer in self._arrows:
            return
        self._arrows.add(layer)
        base = layer_path(layer)
        along_x = RotationMatrix.MakeYRotation(math.pi / 2)
        shaft = 0.7 * length
        self.meshcat.SetObject(base + "/shaft", Cylinder(radius, shaft), rgba)
        self.meshcat.SetTransform(base + "/shaft", RigidTransform(along_x, [shaft / 2, 0, 0.05]))
        self.meshcat.SetObject(base + "/head", MeshcatCone(length - shaft, 2.5 * radius, 2.5 * radius), rgba)
        # MeshcatCone's apex is at its origin and it opens along +z: turn it to open along -x.
        self.meshcat.SetTransform(
            base + "/head", RigidTransform(RotationMatrix.MakeYRotation(-math.pi / 2), [length, 0, 0.05])
        )

    def box(self, layer: str, size, rgba: Rgba, z: float) -> None:
        self.meshcat.SetObject(layer_path(layer) + "/box", Box(*size), rgba)
        self.meshcat.SetTransform(layer_path(layer) + "/box", RigidTransform([0, 0, z]))

    def visible(self, layer: str, on: bool) -> None:
        self.meshcat.SetProperty(layer_path(layer), "visible", on)


def planar(x: float, y: float, yaw: float, z: float = 0.0) -> RigidTransform:
    return RigidTransform(RollPitchYaw(0, 0, yaw), [x, y, z])
