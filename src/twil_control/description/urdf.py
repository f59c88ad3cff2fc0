"""A URDF as ROS 1 tools read it: links, joints, inertials, ``<transmission>``s and the
``<gazebo>`` extensions (per-link properties, model plugins, sensors with their plugins).

Pure: ElementTree only. :func:`parse_urdf` gives a :class:`RobotDescription`; errors are
:class:`DescriptionError` naming the description (file or parameter) and what is wrong.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

from twil_control.errors import TwilControlError

__all__ = [
    "DescriptionError",
    "GazeboPlugin",
    "GazeboSensor",
    "Inertial",
    "Joint",
    "Link",
    "RobotDescription",
    "Transmission",
    "gazebo_plugin",
    "parse_urdf",
    "floats",
]

MOVING_TYPES = ("revolute", "continuous", "prismatic", "floating", "planar")


class DescriptionError(TwilControlError, ValueError):
    """A robot description that cannot be used; the message names it and the element."""


def floats(text: str | None, count: int, what: str, default: tuple = ()) -> tuple[float, ...]:
    """``count`` finite numbers from a space-separated attribute (``default`` when absent)."""
    if text is None or not text.strip():
        if default:
            return default
        raise DescriptionError(f"{what}: missing (expected {count} numbers)")
    try:
        values = tuple(float(v) for v in text.split())
    except ValueError:
        raise DescriptionError(f"{what}: {text!r} is not {count} numbers") from None
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise DescriptionError(f"{what}: {text!r} is not {count} finite numbers")
    return values


@dataclass
class Inertial:
    mass: float
    inertia: tuple[float, float, float, float, float, float]  # ixx ixy ixz iyy iyz izz
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def problem(self) -> str | None:
        """Why this inertia is not physical (None if it is): mass > 0, a positive definite
        inertia matrix whose principal moments satisfy the triangle inequality."""
        import numpy as np

        if not self.mass > 0:
            return f"mass {self.mass} is not > 0"
        ixx, ixy, ixz, iyy, iyz, izz = self.inertia
        moments = np.linalg.eigvalsh(np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]))
        if not moments[0] > 0:
            return f"principal moments {moments.round(12).tolist()} are not all > 0"
        a, b, c = moments
        if a + b < c * (1 - 1e-9):
            return (
                f"principal moments {moments.round(12).tolist()} break the triangle "
                f"inequality (no rigid body has them)"
            )
        return None


@dataclass
class Link:
    name: str
    inertial: Inertial | None = None
    element: ET.Element | None = field(default=None, repr=False)


@dataclass
class Joint:
    name: str
    type: str
    parent: str
    child: str
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)
    axis: tuple[float, float, float] = (1.0, 0.0, 0.0)
    effort: float | None = None  # <limit effort>, None when absent
    velocity: float | None = None

    @property
    def moves(self) -> bool:
        return self.type in MOVING_TYPES

    @property
    def origin_quaternion(self) -> tuple[float, float, float, float]:
        """The <origin> rotation as a quaternion (x, y, z, w)."""
        from twil_control.control.transforms import quat_from_rpy

        return tuple(float(c) for c in quat_from_rpy(*self.rpy))


@dataclass
class Transmission:
    name: str
    type: str
    joint: str
    interfaces: list[str]
    reduction: float = 1.0


@dataclass
class GazeboPlugin:
    name: str
    filename: str
    reference: str | None  # the link of <gazebo reference> or of the sensor, else None
    params: dict[str, str]  # first-level tags -> text (attribute 'value' if no text)
    element: ET.Element = field(repr=False)

    def label(self) -> str:
        where = f" on link {self.reference}" if self.reference else ""
        return f"plugin {self.name!r} ({self.filename}){where}"


@dataclass
class GazeboSensor:
    name: str
    type: str
    link: str
    element: ET.Element = field(repr=False)
    plugins: list[GazeboPlugin] = field(default_factory=list)


@dataclass
class RobotDescription:
    name: str
    source: str
    links: dict[str, Link]
    joints: dict[str, Joint]
    transmissions: list[Transmission] = field(default_factory=list)
    plugins: list[GazeboPlugin] = field(default_factory=list)  # model plugins
    sensors: list[GazeboSensor] = field(default_factory=list)
    link_properties: dict[str, dict[str, str]] = field(default_factory=dict)  # <gazebo reference>
    root_element: ET.Element | None = field(default=None, repr=False)
    canonical: str | None = None  # an SDF model's canonical link (its first), the floating base

    @property
    def root(self) -> str:
        """The link no joint has as its child (URDF has exactly one); an SDF model's canonical
        link."""
        if self.canonical is not None:
            return self.canonical
        children = {j.child for j in self.joints.values()}
        roots = [name for name in self.links if name not in children]
        if len(roots) != 1:
            raise DescriptionError(
                f"{self.source}: a URDF has one root link; found {', '.join(roots) or 'none (a loop)'}"
            )
        return roots[0]

    def parent_joint(self, link: str) -> Joint | None:
        return next((j for j in self.joints.values() if j.child == link), None)

    def joint(self, name: str, what: str) -> Joint:
        if name not in self.joints:
            raise DescriptionError(
                f"{self.source}: {what} names joint {name!r}, which the "
                f"description does not have (joints: {', '.join(self.joints)})"
            )
        return self.joints[name]

    def link(self, name: str, what: str) -> Link:
        if name not in self.links:
            raise DescriptionError(
                f"{self.source}: {what} names link {name!r}, which the "
                f"description does not have (links: {', '.join(self.links)})"
            )
        return self.links[name]

    def welded_group(self, link: str) -> list[str]:
        """``link`` and every link joined to it by fixed joints (one rigid body in motion)."""
        group, todo = [], [link]
        while todo:
            name = todo.pop()
            group.append(name)
            for j in self.joints.values():
                if j.type == "fixed" and j.parent == name and j.child not in group:
                    todo.append(j.child)
                if j.type == "fixed" and j.child == name and j.parent not in group:
                    todo.append(j.parent)
        return group

    def check_inertia(self) -> None:
        """A link with a non-physical inertial, or a moving body with no mass at all, is an error
        naming the link (see docs/robots.md for what Gazebo does instead)."""
        for link in self.links.values():
            if link.inertial is not None and (problem := link.inertial.problem()):
                raise DescriptionError(
                    f"{self.source}: link {link.name!r} has a non-physical "
                    f"<inertial>: {problem}; fix the description"
                )
        moving = [self.root] + [j.child for j in self.joints.values() if j.moves]
        for name in moving:
            group = self.welded_group(name)
            if not any(self.links[n].inertial is not None for n in group):
                joint = self.parent_joint(name)
                how = f"the child of {joint.type} joint {joint.name!r}" if joint else "the root link"
                raise DescriptionError(
                    f"{self.source}: link {name!r} ({how}) moves but has no <inertial>, nor does any "
                    f"link welded to it ({', '.join(group)}): a body without mass cannot be "
                    f"simulated; add an <inertial> (Gazebo drops such links and their joints)"
                )


def _text(element: ET.Element) -> str:
    """A tag's value: its text, or its ``value`` attribute (``<mu1 value="1.0"/>``, Husky's style)."""
    text = (element.text or "").strip()
    return text if text else element.get("value", "").strip()


def _params(element: ET.Element) -> dict[str, str]:
    return {child.tag: _text(child) for child in element if isinstance(child.tag, str)}


def _origin(element: ET.Element | None, what: str) -> tuple[tuple, tuple]:
    if element is None:
        return (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    return (
        floats(element.get("xyz"), 3, f"{what} origin xyz", (0.0, 0.0, 0.0)),
        floats(element.get("rpy"), 3, f"{what} origin rpy", (0.0, 0.0, 0.0)),
    )


def _inertial(element: ET.Element, what: str) -> Inertial:
    mass_el = element.find("mass")
    if mass_el is None or mass_el.get("value") is None:
        raise DescriptionError(f"{what}: <inertial> without <mass value=...>")
    (mass,) = floats(mass_el.get("value"), 1, f"{what} mass")
    inertia_el = element.find("inertia")
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    if inertia_el is None:
        raise DescriptionError(f"{what}: <inertial> without <inertia>")
    inertia = tuple(floats(inertia_el.get(k, "0"), 1, f"{what} inertia {k}")[0] for k in keys)
    xyz, rpy = _origin(element.find("origin"), what)
    return Inertial(mass, inertia, xyz, rpy)


def parse_urdf(text: str, source: str = "robot_description") -> RobotDescription:
    """Parse URDF text (already through xacro) into a :class:`RobotDescription`."""
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise DescriptionError(f"{source}: not valid XML: {exc}") from None
    if root.tag != "robot":
        raise DescriptionError(f"{source}: a URDF's root element is <robot>, got <{root.tag}>")
    name = root.get("name") or ""
    links: dict[str, Link] = {}
    for el in root.findall("link"):
        link_name = el.get("name")
        if not link_name:
            raise DescriptionError(f"{source}: a <link> without a name")
        if link_name in links:
            raise DescriptionError(f"{source}: link {link_name!r} is defined twice")
        inertial = el.find("inertial")
        links[link_name] = Link(
            link_name,
            _inertial(inertial, f"{source}: link {link_name!r}") if inertial is not None else None,
            el,
        )
    joints: dict[str, Joint] = {}
    for el in root.findall("joint"):
        jname, jtype = el.get("name"), el.get("type")
        what = f"{source}: joint {jname!r}"
        parent, child = el.find("parent"), el.find("child")
        if not jname or not jtype or parent is None or child is None:
            raise DescriptionError(f"{what}: a joint needs a name, a type, <parent> and <child>")
        if jname in joints:
            raise DescriptionError(f"{what}: defined twice")
        xyz, rpy = _origin(el.find("origin"), what)
        axis_el = el.find("axis")
        axis = floats(axis_el.get("xyz") if axis_el is not None else None, 3, f"{what} axis", (1.0, 0.0, 0.0))
        norm = math.sqrt(sum(a * a for a in axis))
        if not norm > 0:
            raise DescriptionError(f"{what}: axis {axis} has zero length")
        axis = tuple(a / norm for a in axis)
        limit = el.find("limit")
        effort = velocity = None
        if limit is not None:
            if limit.get("effort") is not None:
                effort = floats(limit.get("effort"), 1, f"{what} limit effort")[0]
            if limit.get("velocity") is not None:
                velocity = floats(limit.get("velocity"), 1, f"{what} limit velocity")[0]
        joints[jname] = Joint(
            jname, jtype, parent.get("link", ""), child.get("link", ""), xyz, rpy, axis, effort, velocity
        )
        for end in (joints[jname].parent, joints[jname].child):
            if end not in links:
                raise DescriptionError(f"{what}: link {end!r} is not defined")
    description = RobotDescription(name, source, links, joints, root_element=root)
    description.transmissions = _transmissions(root, source)
    _gazebo(root, description)
    return description


def _transmissions(root: ET.Element, source: str) -> list[Transmission]:
    found = []
    for el in root.findall("transmission"):
        ttype = _text(el.find("type")) if el.find("type") is not None else el.get("type", "")
        reduction = 1.0
        for actuator in el.findall("actuator"):
            red = actuator.find("mechanicalReduction")
            if red is not None:
                reduction = floats(
                    _text(red), 1, f"{source}: transmission {el.get('name')!r} mechanicalReduction"
                )[0]
        for joint in el.findall("joint"):
            interfaces = [_text(h) for h in joint.findall("hardwareInterface")]
            if not interfaces:  # the older form puts it on the actuator
                interfaces = [
                    _text(h) for a in el.findall("actuator") for h in a.findall("hardwareInterface")
                ]
            found.append(
                Transmission(el.get("name", ""), ttype, joint.get("name", ""), interfaces, reduction)
            )
    return found


def gazebo_plugin(element: ET.Element, reference: str | None) -> GazeboPlugin:
    """A ``<plugin>`` element (of a ``<gazebo>`` tag, a sensor or an SDF model) as read here."""
    return GazeboPlugin(
        element.get("name", ""), element.get("filename", ""), reference, _params(element), element
    )


def _gazebo(root: ET.Element, description: RobotDescription) -> None:
    for el in root.findall("gazebo"):
        reference = el.get("reference")
        for child in el:
            if child.tag == "plugin":
                description.plugins.append(gazebo_plugin(child, reference))
            elif child.tag == "sensor":
                link = reference or ""
                sensor = GazeboSensor(child.get("name", ""), child.get("type", ""), link, child)
                sensor.plugins = [gazebo_plugin(p, link) for p in child.findall("plugin")]
                description.sensors.append(sensor)
            elif reference is not None and isinstance(child.tag, str):
                description.link_properties.setdefault(reference, {})[child.tag] = _text(child)
