"""Gazebo's shapes, surfaces and materials as Drake reads them (XML only): the part of the
world normaliser (description.gazebo_world) that rewrites a ``<collision>`` or ``<visual>``.

A ``<plane>`` becomes a thin box whose top face is the plane (pydrake 1.51 can crash when
geometries follow a half-space); a mesh is converted to OBJ (description.meshes) and, on a
moving model's collision, declared convex; ODE's ``<mu>`` becomes Drake's friction; a stock
material script becomes a diffuse colour. `ShapeRewriter` is a part of the normaliser: it uses
the normaliser's ``result``, ``prune`` and ``ignore``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..control.transforms import pose_matrix, pose_of_matrix
from ..core import gazebo_paths, packages
from . import meshes
from .gazebo_materials import gazebo_color
from .urdf import DescriptionError, floats
from .xml_spans import Element, SpanFile, escape, start_tag

__all__ = ["GROUND_MIN_SIDE", "GROUND_THICKNESS", "ShapeRewriter", "has_content"]

#: A <plane> becomes a box this thick (m) whose top face is the plane; pydrake 1.51 can crash
#: when geometries follow a half-space in SceneGraph's broadphase.
GROUND_THICKNESS = 0.1
#: ... at least this long on each side (m): Gazebo's collision plane is unbounded.
GROUND_MIN_SIDE = 100.0
_UNSUPPORTED_SHAPES = ("heightmap", "polyline", "image")


def _placeholder(k: int) -> str:
    return f"@@twil-mesh-{k}@@"


def has_content(el: Element) -> bool:
    """Whether an element says anything: text, attributes, or a child that does (``<contact>
    <ode/></contact>`` says nothing)."""
    return bool(el.text or el.attrs or any(has_content(c) for c in el.children))


class ShapeRewriter:
    def _shape(self, f: SpanFile, el: Element) -> Element | None:
        """The shape element of a collision or visual, or None after removing an element whose
        shape Drake cannot hold (counted by the shape's name)."""
        geometry = el.find("geometry")
        shape = geometry.children[0] if geometry is not None and geometry.children else None
        if shape is not None and shape.tag in _UNSUPPORTED_SHAPES:
            f.remove(el)
            self.result.ignored[f"{el.tag} of {shape.tag}"] += 1
            return None
        return shape

    def collision(self, f: SpanFile, el: Element, static: bool) -> None:
        kept = self.prune(f, el, "collision")
        shape = self._shape(f, el)
        if shape is None:
            return
        if shape.tag == "plane":
            self.plane(f, el, shape, collision=True)
        elif shape.tag == "mesh":
            self.mesh(f, shape, declare_convex=not static)
        surface = next((c for c in kept if c.tag == "surface"), None)
        if surface is not None:
            self.surface(f, el, surface)

    def surface(self, f: SpanFile, collision: Element, el: Element) -> None:
        """ODE's friction as Drake's (one coefficient: ODE's Coulomb friction is static and
        dynamic alike); the rest of <surface> is counted."""
        mu = mu2 = None
        for child in el.children:
            if child.tag == "friction":
                for kind in child.children:
                    if kind.tag == "ode":
                        for c in kind.children:
                            if c.tag == "mu":
                                mu = c
                            elif c.tag == "mu2":
                                mu2 = c
                            elif has_content(c):
                                self.result.ignored[c.tag] += 1
                    elif has_content(kind):
                        self.result.ignored[kind.tag] += 1
            elif has_content(child):
                self.result.ignored[child.tag] += 1
        f.remove(el)
        if mu is None or collision.find("drake:proximity_properties") is not None:
            return
        (value,) = floats(mu.text, 1, f"{f.where(mu)}: <mu>", ())
        if mu2 is not None and floats(mu2.text, 1, f"{f.where(mu2)}: <mu2>", ())[0] != value:
            self.result.ignored["mu2 (friction is isotropic here: mu is used)"] += 1
        v = repr(max(value, 0.0))
        f.insert_into(
            collision,
            f"<drake:proximity_properties><drake:mu_dynamic>{v}</drake:mu_dynamic>"
            f"<drake:mu_static>{v}</drake:mu_static></drake:proximity_properties>",
        )

    def visual(self, f: SpanFile, el: Element) -> None:
        kept = self.prune(f, el, "visual")
        shape = self._shape(f, el)
        if shape is None:
            return
        if shape.tag == "plane":
            self.plane(f, el, shape, collision=False)
        elif shape.tag == "mesh":
            self.mesh(f, shape, declare_convex=False)
        materials = [c for c in kept if c.tag == "material"]
        for extra in materials[1:]:  # SDF holds one; sdformat reads the first
            self.ignore(f, extra, "material (a second one)")
        if materials:
            self.material(f, materials[0])

    def material(self, f: SpanFile, el: Element) -> None:
        kept = self.prune(f, el, "material")
        script = next((c for c in kept if c.tag == "script"), None)
        if script is None:
            return
        f.remove(script)
        if el.find("diffuse") is not None:  # Gazebo applies the script, then the colours given
            return
        name = script.findtext("name", "") or ""
        rgba = gazebo_color(name)
        if rgba is None:
            self.result.ignored[f"material script {name or '(no name)'} (not a stock colour)"] += 1
            return
        f.insert_into(el, f"<diffuse>{' '.join(repr(c) for c in rgba)}</diffuse>")
        self.result.converted["material script -> colour"] += 1

    def plane(self, f: SpanFile, el: Element, shape: Element, collision: bool) -> None:
        what = f"{f.where(shape)}: <plane>"
        normal = np.array(floats(shape.findtext("normal"), 3, f"{what} <normal>", (0.0, 0.0, 1.0)))
        if not np.linalg.norm(normal) > 0:
            raise DescriptionError(f"{what} <normal> has zero length")
        size = floats(shape.findtext("size"), 2, f"{what} <size>", (1.0, 1.0))
        if collision:
            size = tuple(max(s, GROUND_MIN_SIDE) for s in size)
        z = normal / np.linalg.norm(normal)
        x = np.cross([0.0, 1.0, 0.0], z) if abs(z[1]) < 0.9 else np.cross(z, [0.0, 0.0, 1.0])
        x /= np.linalg.norm(x)
        X_PB = np.eye(4)  # the box in the plane's frame: z along the normal, top face on the plane
        X_PB[:3, :3] = np.column_stack([x, np.cross(z, x), z])
        X_PB[:3, 3] = -0.5 * GROUND_THICKNESS * z
        pose_el = el.find("pose")
        given = floats(pose_el.text if pose_el is not None else None, 6, f"{what} pose", (0.0,) * 6)
        pose = " ".join(f"{v:.12g}" for v in pose_of_matrix(pose_matrix(*given) @ X_PB))
        if pose_el is not None:
            f.replace(pose_el.start, pose_el.end, start_tag("pose", pose_el.attrs) + pose + "</pose>")
        else:
            f.insert_into(el, f"<pose>{pose}</pose>")
        f.replace(
            shape.start, shape.end, f"<box><size>{size[0]!r} {size[1]!r} {GROUND_THICKNESS!r}</size></box>"
        )
        self.result.converted[
            f"{'collision' if collision else 'visual'} plane -> {GROUND_THICKNESS} m box"
        ] += 1

    def mesh(self, f: SpanFile, el: Element, declare_convex: bool) -> None:
        """The mesh's URI becomes a placeholder, filled by `convert_meshes` once every mesh of
        the world is known (the conversions run in one child process: description.meshes)."""
        self.prune(f, el, "mesh")
        uri = (el.findtext("uri") or "").strip()
        what = f"{f.where(el)}: <mesh> {uri!r}"
        scale = floats(el.findtext("scale"), 3, f"{what} <scale>", (1.0, 1.0, 1.0))
        self.mesh_jobs.append((self.resolve_file(uri, f, what), scale, what))
        convex = "<drake:declare_convex/>" if declare_convex else ""
        f.replace(
            el.start, el.end, f"<mesh><uri>{_placeholder(len(self.mesh_jobs) - 1)}</uri>{convex}</mesh>"
        )

    def convert_meshes(self) -> dict[bytes, bytes]:
        """Convert every mesh met (description.meshes, one child process for those not cached);
        placeholder -> the converted OBJ's file:// URI."""
        if not self.mesh_jobs:
            return {}
        try:
            converted = meshes.convert_all([(source, scale) for source, scale, _ in self.mesh_jobs])
        except meshes.MeshError as error:
            where = next((what for source, _, what in self.mesh_jobs if str(source) in str(error)), None)
            raise DescriptionError(f"{where or self.result.source}: {error}") from None
        return {
            _placeholder(k).encode(): escape(path.absolute().as_uri()).encode()
            for k, path in enumerate(converted)
        }

    def resolve_file(self, uri: str, f: SpanFile, what: str) -> Path:
        """The file a mesh or include URI names: model:// and package:// as Gazebo and ROS find
        them, file:// and paths from the file's folder, then the resource folders."""
        if uri.startswith(("http://", "https://")):
            raise DescriptionError(
                f"{what}: Gazebo's online model database is not reachable here; put the model on disk"
            )
        if uri.startswith(("model://", "package://")):
            name = uri.split("://", 1)[1]
            try:
                if uri.startswith("model://") and "/" not in name.strip("/"):
                    return gazebo_paths.find_model(name.strip("/"))
                return packages.resolve_url(uri)
            except packages.PackageNotFoundError as error:
                raise DescriptionError(f"{what}: {error}") from None
        rest = uri[len("file://") :] if uri.startswith("file://") else uri
        path = Path(rest).expanduser()
        tried = (
            [path]
            if path.is_absolute()
            else [
                *([f.folder / path] if f.folder is not None else []),
                *(root / path for root in gazebo_paths.resource_folders()),
            ]
        )
        for candidate in tried:
            if candidate.exists():
                return candidate
        raise DescriptionError(f"{what}: not found (tried {', '.join(str(p) for p in tried)})")
