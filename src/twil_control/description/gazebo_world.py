"""A Gazebo world or model file turned into the SDF Drake reads, before Drake sees it (XML only).

Gazebo reads SDF 1.4 to 1.7, resolves ``<include>``s, draws ``Gazebo/<Colour>`` scripts and
keeps a saved world's ``<state>``, ``<gui>``, lights and world plugins; Drake 1.51 warns once per
element it does not read and crashes on some planes. :func:`normalise` rewrites the file's
bytes span by span (description.xml_spans), so what it leaves alone keeps its line: includes
inlined (``model://`` through core.gazebo_paths; ``<name>``, ``<pose>``, ``<static>`` kept),
planes as thin boxes, material scripts as colours, ODE friction as Drake's, meshes converted to
OBJ (description.meshes; a moving model's collision mesh declared convex), a revolute or
prismatic joint whose limits are equal made fixed, model ``<plugin>``s and link ``<sensor>``s
taken out for the plugin host, ``<physics>`` and ``<gravity>`` read. Everything else Drake
would not read is removed and counted by element name (:meth:`Normalised.summary`).
"""

from __future__ import annotations

import bisect
import math
import xml.etree.ElementTree as ET
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..control.transforms import pose_matrix, pose_of_matrix
from ..core import gazebo_paths, packages
from . import meshes
from .gazebo_materials import gazebo_color
from .urdf import DescriptionError, floats
from .xml_spans import Element, read_tree

__all__ = ["GROUND_THICKNESS", "ModelParts", "Normalised", "TopModel", "normalise", "normalise_model"]

DRAKE_NS = "http://drake.mit.edu"
ET.register_namespace("drake", DRAKE_NS)

#: A <plane> becomes a box this thick (m) whose top face is the plane; pydrake 1.51 can crash
#: when geometries follow a half-space in SceneGraph's broadphase.
GROUND_THICKNESS = 0.1
#: ... at least this long on each side (m): Gazebo's collision plane is unbounded.
GROUND_MIN_SIDE = 100.0

#: Children Drake reads (or this module turns into what Drake reads), per parent element;
#: ``drake:`` elements are always kept. Any other child is removed and counted.
_KEEP = {
    "world": {"model", "include", "frame", "joint", "physics", "gravity"},
    "model": {"static", "pose", "link", "joint", "model", "frame", "include", "plugin"},
    "link": {"pose", "inertial", "collision", "visual", "frame", "sensor"},
    "collision": {"pose", "geometry", "surface"},
    "visual": {"pose", "geometry", "material", "transparency"},
    "material": {"diffuse", "ambient", "specular", "emissive", "script"},
    "joint": {"parent", "child", "pose", "axis", "axis2"},
    "mesh": {"uri", "scale"},
}
_UNSUPPORTED_SHAPES = ("heightmap", "polyline", "image")


def _version(text: str | None) -> tuple[int, int]:
    try:
        major, minor = (text or "1.7").strip().split(".")[:2]
        return int(major), int(minor)
    except ValueError:
        return (1, 7)


@dataclass
class ModelParts:
    """What a model holds for the plugin host: its ``<plugin>``s and its sensors (each with
    the scoped name of its link, ``nested::link`` for a sensor of a nested model)."""

    plugins: list[ET.Element] = field(default_factory=list)
    sensors: list[tuple[str, ET.Element]] = field(default_factory=list)

    def add(self, other: ModelParts, prefix: str) -> None:
        self.plugins += other.plugins
        self.sensors += [(prefix + link, sensor) for link, sensor in other.sensors]

    @property
    def any(self) -> bool:
        return bool(self.plugins or any(s.find("plugin") is not None for _, s in self.sensors))


@dataclass
class TopModel:
    """A model at the top of the world (or the model file): its name, whether it is static,
    where it starts in the user's file, its normalised text and its plugins and sensors."""

    name: str
    static: bool
    line: int
    text: bytes
    parts: ModelParts
    robot: object = None  # description.urdf.RobotDescription for a model with plugins
    span: tuple[int, int] | None = None  # where it is in the file being rewritten


@dataclass
class Normalised:
    source: str  # the user's file, as messages name it
    text: bytes  # what Drake reads
    version: str = "1.7"
    time_step: float | None = None  # <physics><max_step_size>
    gravity: tuple[float, float, float] | None = None
    ignored: Counter = field(default_factory=Counter)  # element name -> how many were removed
    converted: Counter = field(default_factory=Counter)  # what was turned into Drake's terms
    models: list[TopModel] = field(default_factory=list)

    def summary(self) -> str | None:
        """One line: the elements without meaning here, by name with their counts."""
        if not self.ignored:
            return None
        listed = ", ".join(f"{name} {count}" for name, count in sorted(self.ignored.items()))
        total = sum(self.ignored.values())
        return (
            f"{self.source}: {total} Gazebo element{'s' if total != 1 else ''} without meaning in "
            f"this simulation, ignored (element count): {listed}"
        )


def _newlines(data: bytes, start: int, end: int) -> bytes:
    return b"\n" * data.count(b"\n", start, end)


def _esc(value: str) -> str:
    return value.replace("&", "&amp;").replace("<", "&lt;").replace('"', "&quot;")


def _start_tag(tag: str, attrs: dict[str, str], empty: bool = False) -> str:
    inner = "".join(f' {k}="{_esc(v)}"' for k, v in attrs.items())
    return f"<{tag}{inner}{'/' if empty else ''}>"


class _File:
    """One file being rewritten: its bytes, its tree and the edits (spans replaced)."""

    def __init__(self, data: bytes, source: str, folder: Path | None) -> None:
        self.data, self.source, self.folder = data, source, folder
        self.root = read_tree(data, source)
        self.version = _version(self.root.attrs.get("version"))
        self.edits: list[tuple[int, int, int, bytes]] = []
        self._sorted: list | None = None

    def where(self, el: Element) -> str:
        return f"{self.source}:{el.line}"

    def replace(self, start: int, end: int, text: str | bytes) -> None:
        raw = text.encode() if isinstance(text, str) else text
        self.edits.append((start, end, len(self.edits), raw.replace(b"\n", b" ")))

    def remove(self, el: Element) -> None:
        self.replace(el.start, el.end, b"")

    def insert_into(self, el: Element, text: str) -> None:
        """Insert `text` as the first content of `el` (an element with an end tag)."""
        self.replace(el.tag_end, el.tag_end, text)

    def slice(self, el: Element) -> bytes:
        return self.data[el.start : el.end]

    def render(self, start: int = 0, end: int | None = None) -> bytes:
        """The span [start, end) with the edits inside it applied; every replaced span keeps
        its newlines, so the text after it keeps its lines."""
        end = len(self.data) if end is None else end
        if self._sorted is None or len(self._sorted) != len(self.edits):
            self._sorted = sorted(self.edits)
        edits = self._sorted[bisect.bisect_left(self._sorted, (start,)) :]
        out, at = [], start
        for s, e, _, text in edits:
            if s >= end or e > end:
                break
            if s < at:  # nested in a span already replaced (never planned; kept safe)
                continue
            out += [self.data[at:s], text, _newlines(self.data, s, e)]
            at = e
        out.append(self.data[at:end])
        return b"".join(out)

    def element(self, el: Element) -> ET.Element:
        """`el` (with its original text) as an ElementTree element."""
        wrapped = b'<w xmlns:drake="' + DRAKE_NS.encode() + b'">' + self.slice(el) + b"</w>"
        try:
            return ET.fromstring(wrapped)[0]
        except ET.ParseError as error:
            raise DescriptionError(f"{self.where(el)}: <{el.tag}> cannot be read ({error})") from None


def _flag(text: str | None) -> bool:
    return (text or "").strip().lower() in ("1", "true")


def _has_content(el: Element) -> bool:
    """Whether an element says anything: text, attributes, or a child that does (``<contact>
    <ode/></contact>`` says nothing)."""
    return bool(el.text or el.attrs or any(_has_content(c) for c in el.children))


def _numbers(text: str | None, count: int, what: str, default: tuple) -> tuple[float, ...]:
    return floats(text, count, what, default)


class _Normaliser:
    def __init__(self, source: str) -> None:
        self.result = Normalised(source, b"")
        self.chain: list[Path] = []
        self.target: tuple[int, int] = (1, 7)

    # -- bookkeeping --------------------------------------------------------------------
    def ignore(self, f: _File, el: Element, name: str | None = None) -> None:
        f.remove(el)
        if _has_content(el):
            self.result.ignored[name or el.tag] += 1

    def prune(self, f: _File, el: Element, kind: str) -> list[Element]:
        """Remove and count the children of `el` Drake does not read; return the others."""
        kept = []
        for child in el.children:
            if child.tag.startswith("drake:") or child.tag in _KEEP[kind]:
                kept.append(child)
            else:
                self.ignore(f, child)
        return kept

    # -- files --------------------------------------------------------------------------
    def host(self, f: _File) -> None:
        root = f.root
        if root.tag != "sdf":
            raise DescriptionError(f"{f.where(root)}: an SDF file's root element is <sdf>, not <{root.tag}>")
        if f.version < (1, 4):
            raise DescriptionError(
                f"{f.where(root)}: SDF version {root.attrs.get('version')}: 1.4 or later is read"
            )
        self.target = max(f.version, (1, 5))
        attrs = dict(root.attrs)
        attrs["version"] = f"{self.target[0]}.{self.target[1]}"
        attrs.setdefault("xmlns:drake", DRAKE_NS)
        f.replace(root.start, root.tag_end, _start_tag("sdf", attrs, root.empty_tag))
        self.result.version = attrs["version"]

    def world(self, f: _File, el: Element) -> None:
        physics = [c for c in el.children if c.tag == "physics"]
        chosen = next((p for p in physics if p.attrs.get("default", "").lower() in ("1", "true")), None)
        if physics:
            self.physics(f, chosen or physics[0])
            for p in physics:
                if p is not (chosen or physics[0]):
                    self.ignore(f, p)
        for child in self.prune(f, el, "world"):
            if child.tag == "model":
                self.top_model(f, child)
            elif child.tag == "include":
                self.world_include(f, child)
            elif child.tag == "gravity":
                self.result.gravity = _numbers(child.text, 3, f"{f.where(child)}: <gravity>", ())
                f.remove(child)

    def physics(self, f: _File, el: Element) -> None:
        for child in el.children:
            if child.tag == "max_step_size":
                (step,) = _numbers(child.text, 1, f"{f.where(child)}: <max_step_size>", ())
                if not (step > 0 and math.isfinite(step)):
                    raise DescriptionError(f"{f.where(child)}: <max_step_size> {child.text}: must be > 0 s")
                self.result.time_step = step
            elif child.tag == "gravity":  # SDF 1.4 keeps it here
                self.result.gravity = _numbers(child.text, 3, f"{f.where(child)}: <gravity>", ())
            elif _has_content(child):
                self.result.ignored[child.tag] += 1
        f.remove(el)

    # -- models -------------------------------------------------------------------------
    def top_model(self, f: _File, el: Element) -> None:
        parts = ModelParts()
        static = self.model(f, el, parts, False)
        name = el.attrs.get("name", "")
        self.result.models.append(TopModel(name, static, el.line, b"", parts, span=(el.start, el.end)))

    def model(
        self, f: _File, el: Element, parts: ModelParts, parent_static: bool, override: bool | None = None
    ) -> bool:
        """Rewrite a <model> in place (its plugins and sensors into `parts`); whether it is
        static (an including <static> overrides the file's)."""
        own = _flag(el.findtext("static")) if override is None else override
        static = parent_static or own
        for child in self.prune(f, el, "model"):
            if child.tag == "link":
                self.link(f, child, parts, static)
            elif child.tag == "joint":
                self.joint(f, child)
            elif child.tag == "model":
                nested = ModelParts()
                self.model(f, child, nested, static)
                parts.add(nested, child.attrs.get("name", "") + "::")
            elif child.tag == "include":
                self.nested_include(f, child, parts, static)
            elif child.tag == "plugin":
                if static:
                    self.ignore(f, child)
                else:
                    parts.plugins.append(f.element(child))
                    f.remove(child)
        return static

    def link(self, f: _File, el: Element, parts: ModelParts, static: bool) -> None:
        for child in self.prune(f, el, "link"):
            if child.tag == "collision":
                self.collision(f, child, static)
            elif child.tag == "visual":
                self.visual(f, child)
            elif child.tag == "sensor":
                if static:
                    self.ignore(f, child)
                else:
                    parts.sensors.append((el.attrs.get("name", ""), f.element(child)))
                    f.remove(child)

    def joint(self, f: _File, el: Element) -> None:
        self.prune(f, el, "joint")
        kind = el.attrs.get("type", "")
        axis = el.find("axis")
        limit = axis.find("limit") if axis is not None else None
        if kind in ("revolute", "prismatic") and limit is not None:
            lower, upper = limit.findtext("lower"), limit.findtext("upper")
            if lower is not None and upper is not None and lower.strip() == upper.strip():
                # Gazebo holds such a joint at its one position: it is a weld (the seed's
                # laser mount); a moving joint held by limits alone is stiff for Drake
                f.replace(el.start, el.tag_end, _start_tag("joint", {**el.attrs, "type": "fixed"}))
                f.remove(axis)
                self.result.converted["joint with equal limits -> fixed"] += 1
                return
        for a in (el.find("axis"), el.find("axis2")):
            if a is not None:
                self.axis(f, a)

    def axis(self, f: _File, el: Element) -> None:
        """Express the axis as the document's SDF version reads it (a model included from a
        file of another version keeps the axis it had there)."""
        xyz = el.find("xyz")
        upmf = el.find("use_parent_model_frame")
        in_model = (
            f.version == (1, 4)
            or (f.version < (1, 7) and upmf is not None and upmf.text.lower() in ("1", "true"))
            or (f.version >= (1, 7) and xyz is not None and xyz.attrs.get("expressed_in") == "__model__")
        )
        if (f.version >= (1, 7)) == (self.target >= (1, 7)) and f.version != (1, 4):
            return
        vector = xyz.text if xyz is not None else "0 0 1"
        if self.target >= (1, 7):
            xyz_text = f'<xyz expressed_in="__model__">{vector}</xyz>' if in_model else f"<xyz>{vector}</xyz>"
            upmf_text = ""
        else:
            xyz_text, upmf_text = (
                f"<xyz>{vector}</xyz>",
                (f"<use_parent_model_frame>{'true' if in_model else 'false'}</use_parent_model_frame>"),
            )
        if xyz is not None:
            f.replace(xyz.start, xyz.end, xyz_text + upmf_text)
        else:
            f.insert_into(el, xyz_text + upmf_text)
        if upmf is not None:
            f.remove(upmf)

    # -- geometry -----------------------------------------------------------------------
    def _shape(self, f: _File, el: Element) -> Element | None:
        """The shape element of a collision or visual, or None after removing an element whose
        shape Drake cannot hold (counted by the shape's name)."""
        geometry = el.find("geometry")
        shape = geometry.children[0] if geometry is not None and geometry.children else None
        if shape is not None and shape.tag in _UNSUPPORTED_SHAPES:
            f.remove(el)
            self.result.ignored[f"{el.tag} of {shape.tag}"] += 1
            return None
        return shape

    def collision(self, f: _File, el: Element, static: bool) -> None:
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

    def surface(self, f: _File, collision: Element, el: Element) -> None:
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
                            elif _has_content(c):
                                self.result.ignored[c.tag] += 1
                    elif _has_content(kind):
                        self.result.ignored[kind.tag] += 1
            elif _has_content(child):
                self.result.ignored[child.tag] += 1
        f.remove(el)
        if mu is None or collision.find("drake:proximity_properties") is not None:
            return
        (value,) = _numbers(mu.text, 1, f"{f.where(mu)}: <mu>", ())
        if mu2 is not None and _numbers(mu2.text, 1, f"{f.where(mu2)}: <mu2>", ())[0] != value:
            self.result.ignored["mu2 (friction is isotropic here: mu is used)"] += 1
        v = repr(max(value, 0.0))
        f.insert_into(
            collision,
            f"<drake:proximity_properties><drake:mu_dynamic>{v}</drake:mu_dynamic>"
            f"<drake:mu_static>{v}</drake:mu_static></drake:proximity_properties>",
        )

    def visual(self, f: _File, el: Element) -> None:
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

    def material(self, f: _File, el: Element) -> None:
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

    def plane(self, f: _File, el: Element, shape: Element, collision: bool) -> None:
        what = f"{f.where(shape)}: <plane>"
        normal = np.array(_numbers(shape.findtext("normal"), 3, f"{what} <normal>", (0.0, 0.0, 1.0)))
        if not np.linalg.norm(normal) > 0:
            raise DescriptionError(f"{what} <normal> has zero length")
        size = _numbers(shape.findtext("size"), 2, f"{what} <size>", (1.0, 1.0))
        if collision:
            size = tuple(max(s, GROUND_MIN_SIDE) for s in size)
        z = normal / np.linalg.norm(normal)
        x = np.cross([0.0, 1.0, 0.0], z) if abs(z[1]) < 0.9 else np.cross(z, [0.0, 0.0, 1.0])
        x /= np.linalg.norm(x)
        X_PB = np.eye(4)  # the box in the plane's frame: z along the normal, top face on the plane
        X_PB[:3, :3] = np.column_stack([x, np.cross(z, x), z])
        X_PB[:3, 3] = -0.5 * GROUND_THICKNESS * z
        pose_el = el.find("pose")
        given = _numbers(pose_el.text if pose_el is not None else None, 6, f"{what} pose", (0.0,) * 6)
        pose = " ".join(f"{v:.12g}" for v in pose_of_matrix(pose_matrix(*given) @ X_PB))
        if pose_el is not None:
            f.replace(pose_el.start, pose_el.end, _start_tag("pose", pose_el.attrs) + pose + "</pose>")
        else:
            f.insert_into(el, f"<pose>{pose}</pose>")
        f.replace(
            shape.start, shape.end, f"<box><size>{size[0]!r} {size[1]!r} {GROUND_THICKNESS!r}</size></box>"
        )
        self.result.converted[
            f"{'collision' if collision else 'visual'} plane -> {GROUND_THICKNESS} m box"
        ] += 1

    def mesh(self, f: _File, el: Element, declare_convex: bool) -> None:
        self.prune(f, el, "mesh")
        uri = (el.findtext("uri") or "").strip()
        what = f"{f.where(el)}: <mesh> {uri!r}"
        scale = _numbers(el.findtext("scale"), 3, f"{what} <scale>", (1.0, 1.0, 1.0))
        try:
            converted = meshes.convert(self.resolve_file(uri, f, what), scale)
        except meshes.MeshError as error:
            raise DescriptionError(f"{what}: {error}") from None
        convex = "<drake:declare_convex/>" if declare_convex else ""
        f.replace(el.start, el.end, f"<mesh><uri>{_esc(converted.absolute().as_uri())}</uri>{convex}</mesh>")

    def resolve_file(self, uri: str, f: _File, what: str) -> Path:
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

    # -- includes -----------------------------------------------------------------------
    def world_include(self, f: _File, el: Element) -> None:
        found = self.include(f, el, static=False)
        if found is None:
            return
        text, name, static, parts = found
        self.result.models.append(TopModel(name, static, el.line, text, parts))
        f.replace(el.start, el.end, text)

    def nested_include(self, f: _File, el: Element, parts: ModelParts, static: bool) -> None:
        found = self.include(f, el, static)
        if found is None:
            return
        text, name, _, nested = found
        parts.add(nested, name + "::")
        f.replace(el.start, el.end, text)

    def include(self, f: _File, el: Element, static: bool) -> tuple[bytes, str, bool, ModelParts] | None:
        """The model an <include> brings, rewritten, with its name, whether it is static and its
        plugins and sensors; None for an included light (removed and counted)."""
        uri = (el.findtext("uri") or "").strip()
        what = f"{f.where(el)}: <include> {uri!r}"
        path = self.resolve_file(uri, f, what)
        if path.is_dir():
            path = _model_file(path, what)
        if path.resolve() in self.chain:
            raise DescriptionError(f"{what}: includes itself ({' -> '.join(str(p) for p in self.chain)})")
        sub = _File(path.read_bytes(), str(path), path.parent)
        if sub.root.tag != "sdf" or not sub.root.children:
            raise DescriptionError(f"{what}: {path} holds no <model> inside <sdf>")
        top = sub.root.children[0]
        if top.tag != "model":
            self.result.ignored[top.tag] += 1
            f.remove(el)
            return None
        self.chain.append(path.resolve())
        try:
            parts = ModelParts()
            given = el.findtext("static")
            override = None if given is None else _flag(given)
            is_static = self.model(sub, top, parts, static, override)
            if override is not None and override != _flag(top.findtext("static")):
                self._set_child(sub, top, "static", f"<static>{'true' if override else 'false'}</static>")
            name = (el.findtext("name") or "").strip() or top.attrs.get("name", "")
            sub.replace(
                top.start, top.tag_end, _start_tag("model", {**top.attrs, "name": name}, top.empty_tag)
            )
            pose = el.find("pose")
            if pose is not None:
                self._set_child(sub, top, "pose", f.slice(pose).decode())
            for plugin in el.findall("plugin"):
                parts.plugins.append(f.element(plugin))
            return sub.render(top.start, top.end), name, is_static, parts
        finally:
            self.chain.pop()

    @staticmethod
    def _set_child(f: _File, parent: Element, tag: str, text: str) -> None:
        old = parent.find(tag)
        if old is not None:
            f.replace(old.start, old.end, text)
        else:
            f.insert_into(parent, text)


def _model_file(folder: Path, what: str) -> Path:
    """The SDF file of a model folder, as Gazebo picks it from model.config: the highest
    ``<sdf version>`` up to 1.7 (Gazebo 11's), else the highest; model.sdf without a config."""
    config = folder / "model.config"
    if not config.is_file():
        if (folder / "model.sdf").is_file():
            return folder / "model.sdf"
        raise DescriptionError(f"{what}: {folder} holds no model.config")
    try:
        root = ET.fromstring(config.read_bytes())
    except ET.ParseError as error:
        raise DescriptionError(f"{what}: {config} is not valid XML ({error})") from None
    entries = [
        (_version(e.get("version")), (e.text or "").strip())
        for e in root.iter("sdf")
        if (e.text or "").strip()
    ]
    if not entries:
        return folder / "model.sdf"
    supported = [e for e in entries if e[0] <= (1, 7)] or entries
    return folder / max(supported)[1]


def normalise(path: str | Path, data: bytes | None = None) -> Normalised:
    """The world (or model) file at `path` as Drake should read it; `data`, when given, is its
    content (a file that can be read once, such as /dev/stdin)."""
    path = Path(path)
    raw = path.read_bytes() if data is None else data
    folder = path.parent if str(path) else None
    return _run(_File(raw, str(path), folder), str(path), None)


def normalise_model(
    data: bytes | str, source: str, folder: Path | None, name: str, pose: tuple[float, ...]
) -> Normalised:
    """An SDF model file for spawn_model -sdf: renamed `name`, its <pose> composed after the
    spawn pose (x y z roll pitch yaw), as gazebo_ros places an SDF model."""
    raw = data.encode() if isinstance(data, str) else data
    return _run(_File(raw, source, folder), source, (name, pose))


def _run(f: _File, source: str, spawn: tuple[str, tuple] | None) -> Normalised:
    n = _Normaliser(source)
    n.host(f)
    if f.folder is not None and Path(source).is_file():
        n.chain.append(Path(source).resolve())
    root = f.root
    if spawn is not None:
        model = root.find("model")
        if model is None:
            raise DescriptionError(f"{source}: an SDF model file is <sdf><model>...</model></sdf>")
        for other in root.children:
            if other is not model:
                n.ignore(f, other)
        name, spawn_pose = spawn
        given = model.find("pose")
        in_file = _numbers(
            given.text if given is not None else None, 6, f"{source}: model <pose>", (0.0,) * 6
        )
        placed = " ".join(
            f"{v:.12g}" for v in pose_of_matrix(pose_matrix(*spawn_pose) @ pose_matrix(*in_file))
        )
        f.replace(model.start, model.tag_end, _start_tag("model", {**model.attrs, "name": name}))
        n._set_child(f, model, "pose", f"<pose>{placed}</pose>")
        n.top_model(f, model)
    else:
        for child in root.children:
            if child.tag == "world":
                n.world(f, child)
            elif child.tag == "model":
                n.top_model(f, child)
            else:
                n.ignore(f, child)
    result = n.result
    result.text = f.render()
    for model in result.models:
        if model.parts.any and not model.static:
            from .sdf_robot import describe

            if model.span is not None:
                model.text = f.render(*model.span)
            model.robot = describe(model, result.version, source)
    return result
