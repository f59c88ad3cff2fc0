"""A Gazebo world or model file turned into the SDF Drake reads, before Drake sees it (XML only).

Drake 1.51 warns once per element it does not read and crashes on some planes, so
:func:`normalise` rewrites the file span by span (description.xml_spans), keeping every line
where it was: includes inlined, shapes, surfaces and materials in Drake's terms, plugins and
sensors taken out for the plugin host, and what Drake would not read removed and counted
(:meth:`Normalised.summary`). What is read and how: docs/robots.md, "Worlds and SDF models".
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

from ..control.transforms import pose_matrix, pose_of_matrix
from .gazebo_shapes import GROUND_THICKNESS, ShapeRewriter, has_content
from .urdf import DescriptionError, floats
from .xml_spans import Element, SpanFile, start_tag

__all__ = ["GROUND_THICKNESS", "ModelParts", "Normalised", "TopModel", "normalise", "normalise_model"]

DRAKE_NS = "http://drake.mit.edu"
ET.register_namespace("drake", DRAKE_NS)

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


def _open(data: bytes, source: str, folder: Path | None) -> SpanFile:
    """An SDF file to rewrite, with its SDF version (``f.version``)."""
    f = SpanFile(data, source, folder)
    f.version = _version(f.root.attrs.get("version"))
    return f


def _flag(text: str | None) -> bool:
    return (text or "").strip().lower() in ("1", "true")


def _numbers(text: str | None, count: int, what: str, default: tuple) -> tuple[float, ...]:
    return floats(text, count, what, default)


class _Normaliser(ShapeRewriter):
    def __init__(self, source: str) -> None:
        self.result = Normalised(source, b"")
        self.mesh_jobs: list[tuple[Path, tuple, str]] = []  # (mesh file, scale, where it is named)
        self.chain: list[Path] = []
        self.target: tuple[int, int] = (1, 7)

    # -- bookkeeping --------------------------------------------------------------------
    def ignore(self, f: SpanFile, el: Element, name: str | None = None) -> None:
        f.remove(el)
        if has_content(el):
            self.result.ignored[name or el.tag] += 1

    def prune(self, f: SpanFile, el: Element, kind: str) -> list[Element]:
        """Remove and count the children of `el` Drake does not read; return the others."""
        kept = []
        for child in el.children:
            if child.tag.startswith("drake:") or child.tag in _KEEP[kind]:
                kept.append(child)
            else:
                self.ignore(f, child)
        return kept

    # -- files --------------------------------------------------------------------------
    def host(self, f: SpanFile) -> None:
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
        f.replace(root.start, root.tag_end, start_tag("sdf", attrs, root.empty_tag))
        self.result.version = attrs["version"]

    def world(self, f: SpanFile, el: Element) -> None:
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

    def physics(self, f: SpanFile, el: Element) -> None:
        for child in el.children:
            if child.tag == "max_step_size":
                (step,) = _numbers(child.text, 1, f"{f.where(child)}: <max_step_size>", ())
                if not (step > 0 and math.isfinite(step)):
                    raise DescriptionError(f"{f.where(child)}: <max_step_size> {child.text}: must be > 0 s")
                self.result.time_step = step
            elif child.tag == "gravity":  # SDF 1.4 keeps it here
                self.result.gravity = _numbers(child.text, 3, f"{f.where(child)}: <gravity>", ())
            elif has_content(child):
                self.result.ignored[child.tag] += 1
        f.remove(el)

    # -- models -------------------------------------------------------------------------
    def top_model(self, f: SpanFile, el: Element) -> None:
        parts = ModelParts()
        static = self.model(f, el, parts, False)
        name = el.attrs.get("name", "")
        self.result.models.append(TopModel(name, static, el.line, b"", parts, span=(el.start, el.end)))

    def model(
        self, f: SpanFile, el: Element, parts: ModelParts, parent_static: bool, override: bool | None = None
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

    def link(self, f: SpanFile, el: Element, parts: ModelParts, static: bool) -> None:
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

    def joint(self, f: SpanFile, el: Element) -> None:
        self.prune(f, el, "joint")
        kind = el.attrs.get("type", "")
        axis = el.find("axis")
        limit = axis.find("limit") if axis is not None else None
        if kind in ("revolute", "prismatic") and limit is not None:
            lower, upper = limit.findtext("lower"), limit.findtext("upper")
            if lower is not None and upper is not None and lower.strip() == upper.strip():
                # Gazebo holds such a joint at its one position: it is a weld (qbot's original
                # laser mount); a moving joint held by limits alone is stiff for Drake
                f.replace(el.start, el.tag_end, start_tag("joint", {**el.attrs, "type": "fixed"}))
                f.remove(axis)
                self.result.converted["joint with equal limits -> fixed"] += 1
                return
        for a in (el.find("axis"), el.find("axis2")):
            if a is not None:
                self.axis(f, a)

    def axis(self, f: SpanFile, el: Element) -> None:
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

    # -- includes -----------------------------------------------------------------------
    def world_include(self, f: SpanFile, el: Element) -> None:
        found = self.include(f, el, static=False)
        if found is None:
            return
        text, name, static, parts = found
        self.result.models.append(TopModel(name, static, el.line, text, parts))
        f.replace(el.start, el.end, text)

    def nested_include(self, f: SpanFile, el: Element, parts: ModelParts, static: bool) -> None:
        found = self.include(f, el, static)
        if found is None:
            return
        text, name, _, nested = found
        parts.add(nested, name + "::")
        f.replace(el.start, el.end, text)

    def include(self, f: SpanFile, el: Element, static: bool) -> tuple[bytes, str, bool, ModelParts] | None:
        """The model an <include> brings, rewritten, with its name, whether it is static and its
        plugins and sensors; None for an included light (removed and counted)."""
        uri = (el.findtext("uri") or "").strip()
        what = f"{f.where(el)}: <include> {uri!r}"
        path = self.resolve_file(uri, f, what)
        if path.is_dir():
            path = _model_file(path, what)
        if path.resolve() in self.chain:
            raise DescriptionError(f"{what}: includes itself ({' -> '.join(str(p) for p in self.chain)})")
        sub = _open(path.read_bytes(), str(path), path.parent)
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
                top.start, top.tag_end, start_tag("model", {**top.attrs, "name": name}, top.empty_tag)
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
    def _set_child(f: SpanFile, parent: Element, tag: str, text: str) -> None:
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
    return _run(_open(raw, str(path), folder), str(path), None)


def normalise_model(
    data: bytes | str, source: str, folder: Path | None, name: str, pose: tuple[float, ...]
) -> Normalised:
    """An SDF model file for spawn_model -sdf: renamed `name`, its <pose> composed after the
    spawn pose (x y z roll pitch yaw), as gazebo_ros places an SDF model."""
    raw = data.encode() if isinstance(data, str) else data
    return _run(_open(raw, source, folder), source, (name, pose))


def _run(f: SpanFile, source: str, spawn: tuple[str, tuple] | None) -> Normalised:
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
        f.replace(model.start, model.tag_end, start_tag("model", {**model.attrs, "name": name}))
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
    uris = n.convert_meshes()
    result.text = _fill(f.render(), uris)
    for model in result.models:
        if model.parts.any and not model.static:
            from .sdf_robot import describe

            if model.span is not None:
                model.text = f.render(*model.span)
            model.text = _fill(model.text, uris)
            model.robot = describe(model, result.version, source)
    return result


def _fill(text: bytes, uris: dict[bytes, bytes]) -> bytes:
    for placeholder, uri in uris.items():
        text = text.replace(placeholder, uri)
    return text
