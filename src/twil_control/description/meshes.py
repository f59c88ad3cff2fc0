"""Meshes of a robot description (STL, DAE, OBJ) converted once to what Drake reads: a
Wavefront OBJ with the URDF's ``scale`` applied, cached by the source file's content and the
scale, so a second run reads the cache.

trimesh reads STL and OBJ, and COLLADA (DAE) through pycollada; a DAE's scene graph is flattened
with its node transforms and unit scale. Colours and textures are not carried over (the
description's ``<material>`` colours the visual). The cache folder is ``$TWIL_MESH_CACHE``, else
``$XDG_CACHE_HOME/twil_control/meshes``, else ``~/.cache/twil_control/meshes``.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

from twil_control.errors import TwilControlError

__all__ = ["MeshError", "SUPPORTED", "cache_dir", "convert"]

SUPPORTED = (".stl", ".dae", ".obj")


class MeshError(TwilControlError, ValueError):
    """A mesh that cannot be read or converted (the message names the file)."""


def cache_dir() -> Path:
    if os.environ.get("TWIL_MESH_CACHE"):
        return Path(os.environ["TWIL_MESH_CACHE"])
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "twil_control" / "meshes"


def convert(source: Path, scale: tuple[float, float, float] = (1.0, 1.0, 1.0)) -> Path:
    """The cached OBJ of ``source`` scaled by ``scale`` (made on first use)."""
    suffix = source.suffix.lower()
    if suffix not in SUPPORTED:
        raise MeshError(
            f"mesh {source}: format {suffix or '(none)'} is not supported; supported: {', '.join(SUPPORTED)}"
        )
    data = source.read_bytes()
    key = hashlib.sha256(data + repr(tuple(float(s) for s in scale)).encode()).hexdigest()[:24]
    target = cache_dir() / f"{source.stem}_{key}.obj"
    if target.is_file():
        return target
    mesh = _load(source)
    mesh.apply_scale(scale)
    target.parent.mkdir(parents=True, exist_ok=True)
    partial = target.with_suffix(f".{os.getpid()}.tmp")
    partial.write_text(
        mesh.export(file_type="obj", include_normals=False, include_color=False, include_texture=False)
    )
    partial.replace(target)  # atomic: a concurrent run never reads half a file
    return target


def _load(source: Path):
    import trimesh

    try:
        loaded = trimesh.load(str(source), force="mesh", process=False)
    except Exception as exc:  # trimesh and pycollada raise many kinds
        raise MeshError(f"mesh {source}: cannot be read ({type(exc).__name__}: {exc})") from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise MeshError(f"mesh {source}: holds no triangles")
    return loaded
