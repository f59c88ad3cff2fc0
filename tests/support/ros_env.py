"""The environment a test of a user's ROS packages runs in: which packages ``$(find)`` sees, and a
mesh cache of the session's own (never the user's ~/.cache)."""

from __future__ import annotations

import os

from twil_control.core import packages

GAZEBO_PATHS = ("GAZEBO_MODEL_PATH", "GAZEBO_RESOURCE_PATH")


def use_packages(monkeypatch, tmp_path_factory, *roots, without_gazebo_paths: bool = False) -> None:
    """ROS_PACKAGE_PATH = `roots` (in order), the session's mesh cache, no extra package paths;
    with `without_gazebo_paths`, no GAZEBO_MODEL_PATH or GAZEBO_RESOURCE_PATH from the caller's
    shell."""
    if without_gazebo_paths:
        for var in GAZEBO_PATHS:
            monkeypatch.delenv(var, raising=False)
    monkeypatch.setenv("ROS_PACKAGE_PATH", os.pathsep.join(str(r) for r in roots))
    monkeypatch.setenv("TWIL_MESH_CACHE", str(tmp_path_factory.getbasetemp() / "meshes"))
    packages.set_extra_paths([])
