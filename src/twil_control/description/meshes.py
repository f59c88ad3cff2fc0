"""Meshes of a robot description (STL, DAE, OBJ) converted once to what Drake reads: a Wavefront
OBJ with the URDF's ``scale`` applied, cached by the source's content and the scale.

The conversion runs in a child process under core.limited's limits, so a mesh that would take the
machine is one error; the cache only ever holds whole, successful conversions. Formats, limits
and the cache folder: docs/robots.md, "The files it reads".
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

from twil_control.core import limited
from twil_control.errors import TwilControlError

__all__ = ["MeshError", "SUPPORTED", "cache_dir", "convert", "convert_all"]

SUPPORTED = (".stl", ".dae", ".obj")

#: Part of every cache key: a change to what a conversion does makes new cache files.
_CONVERSION = b"units-in-metres"


class MeshError(TwilControlError, ValueError):
    """A mesh that cannot be read or converted (the message names the file)."""


class MeshLimitError(MeshError, limited.LimitError):
    """A mesh over a size limit, or whose conversion went past the child's memory or time limit."""


def cache_dir() -> Path:
    if os.environ.get("TWIL_MESH_CACHE"):
        return Path(os.environ["TWIL_MESH_CACHE"])
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "twil_control" / "meshes"


def convert(source: Path, scale: tuple[float, float, float] = (1.0, 1.0, 1.0)) -> Path:
    """The cached OBJ of ``source`` scaled by ``scale`` (made on first use)."""
    return convert_all([(source, scale)])[0]


def convert_all(jobs: list[tuple[Path, tuple[float, float, float]]]) -> list[Path]:
    """The cached OBJ of each (source, scale); those not cached yet are made in one child process."""
    limits = limited.LIMITS
    targets, todo = [], []
    for source, scale in jobs:
        suffix = source.suffix.lower()
        if suffix not in SUPPORTED:
            raise MeshError(
                f"mesh {source}: format {suffix or '(none)'} is not supported; supported: {', '.join(SUPPORTED)}"
            )
        size = source.stat().st_size
        if size > limits.mesh_bytes:
            raise MeshLimitError(
                f"mesh {source}: {size / 2**20:.1f} MiB is more than the {limited.size_text(limits.mesh_bytes)} "
                "allowed; raise the limit with --max-mesh-size SIZE"
            )
        data = source.read_bytes()
        key = hashlib.sha256(data + repr(tuple(float(s) for s in scale)).encode() + _CONVERSION).hexdigest()[
            :24
        ]
        target = cache_dir() / f"{source.stem}_{key}.obj"
        targets.append(target)
        if not target.is_file() and (str(source), tuple(scale), str(target)) not in todo:
            todo.append((str(source), tuple(float(s) for s in scale), str(target)))
    if todo:
        cache_dir().mkdir(parents=True, exist_ok=True)
        try:
            errors = limited.call(
                "twil_control.description.meshes:convert_in_child",
                (todo, limits.mesh_triangles),
                "mesh conversion",
            )
        except limited.LimitError as error:
            for _, _, target in todo:  # a child stopped while writing leaves its partial file
                for partial in Path(target).parent.glob(f"{Path(target).stem}.*.tmp"):
                    partial.unlink(missing_ok=True)
            culprit = todo[int(error.last_note)][0] if error.last_note is not None else todo[0][0]
            raise MeshLimitError(str(error).replace("mesh conversion", f"mesh {culprit}", 1)) from None
        for error in errors:
            if error is not None:
                raise error
    return targets


def convert_in_child(todo: list[tuple[str, tuple, str]], max_triangles: int) -> list[MeshError | None]:
    """Convert each (source, scale, target) (in the child process); an error or None for each."""
    out: list[MeshError | None] = []
    for i, (source, scale, target) in enumerate(todo):
        limited.note(str(i))
        try:
            _convert_one(Path(source), scale, Path(target), max_triangles)
            out.append(None)
        except MeshError as error:
            out.append(error)
    return out


def _convert_one(source: Path, scale: tuple, target: Path, max_triangles: int) -> None:
    mesh = _load(source)
    mesh.update_faces(mesh.nondegenerate_faces(height=1e-12))
    mesh.remove_unreferenced_vertices()
    if len(mesh.faces) == 0:
        raise MeshError(f"mesh {source}: holds no triangles of non-zero area")
    if len(mesh.faces) > max_triangles:
        raise MeshLimitError(
            f"mesh {source}: {len(mesh.faces)} triangles are more than the {max_triangles} allowed; "
            "raise the limit with --max-mesh-triangles N"
        )
    mesh.apply_scale(scale)
    partial = target.with_suffix(f".{os.getpid()}.tmp")
    try:
        partial.write_text(
            mesh.export(file_type="obj", include_normals=False, include_color=False, include_texture=False)
        )
        partial.replace(target)  # atomic: a concurrent run never reads half a file
    finally:
        partial.unlink(missing_ok=True)  # a failed or stopped conversion leaves nothing in the cache


def _load(source: Path):
    import trimesh

    try:
        loaded = trimesh.load(str(source), force="mesh", process=False)
    except MemoryError:
        raise
    except Exception as exc:  # trimesh and pycollada raise many kinds
        raise MeshError(f"mesh {source}: cannot be read ({type(exc).__name__}: {exc})") from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise MeshError(f"mesh {source}: holds no triangles")
    if loaded.units not in (None, "meters", "meter", "m"):  # a COLLADA <unit meter="0.0254"/>
        loaded.convert_units("meters")
    return loaded
