"""An SDF model with plugins as the RobotDescription the Gazebo plugins read (XML only).

The plugins were written for a URDF's ``<gazebo>`` tags (links, joints, a sensor's pose in its
link, joint origins and axes); an SDF model gives the same here, names scoped ``nested::name`` as
Gazebo scopes them, each joint's origin its child link's pose in its parent at zero position, the
floating base the model's canonical link. Plugins and sensors come from the normaliser.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from ..control.transforms import pose_matrix, rpy_from_matrix
from .urdf import (
    DescriptionError,
    GazeboSensor,
    Inertial,
    Joint,
    Link,
    RobotDescription,
    floats,
    gazebo_plugin,
)

__all__ = ["describe"]

_DRAKE_NS = "http://drake.mit.edu"


def _pose(element: ET.Element, what: str) -> np.ndarray:
    return pose_matrix(*floats(element.findtext("pose"), 6, f"{what} <pose>", (0.0,) * 6))


def _in_model_frame(axis: ET.Element, version: tuple[int, int]) -> bool:
    if version >= (1, 7):
        xyz = axis.find("xyz")
        return xyz is not None and xyz.get("expressed_in") == "__model__"
    return (axis.findtext("use_parent_model_frame") or "").strip().lower() in ("1", "true")


def describe(model, version: str, source: str) -> RobotDescription:
    """The RobotDescription of a normalised top-level model (description.gazebo_world.TopModel)."""
    wrapped = f'<sdf version="{version}" xmlns:drake="{_DRAKE_NS}">'.encode() + model.text + b"</sdf>"
    try:
        element = ET.fromstring(wrapped).find("model")
    except ET.ParseError as error:
        raise DescriptionError(f"{source}: model {model.name!r} cannot be read ({error})") from None
    major, minor = (int(v) for v in version.split(".")[:2])
    links: dict[str, Link] = {}
    poses: dict[str, np.ndarray] = {}
    joints: dict[str, Joint] = {}
    _walk(element, "", np.eye(4), links, poses, joints, (major, minor), f"{source}: model {model.name!r}")
    first = element.find("link")
    canonical = element.get("canonical_link") or (first.get("name") if first is not None else None)
    if canonical is None:
        raise DescriptionError(f"{source}: model {model.name!r} has plugins but no <link>")
    description = RobotDescription(model.name, source, links, joints, canonical=canonical)
    description.plugins = [gazebo_plugin(p, None) for p in model.parts.plugins]
    for link, sensor in model.parts.sensors:
        found = GazeboSensor(sensor.get("name", ""), sensor.get("type", ""), link, sensor)
        found.plugins = [gazebo_plugin(p, link) for p in sensor.findall("plugin")]
        description.sensors.append(found)
    return description


def _walk(model: ET.Element, prefix: str, X_TM, links, poses, joints, version, what: str) -> None:
    """Links and joints of `model` (posed X_TM in the top model's frame T) and its nested models."""
    for link in model.findall("link"):
        name = prefix + link.get("name", "")
        poses[name] = X_TM @ _pose(link, f"{what} link {name!r}")
        links[name] = Link(name, _inertial(link.find("inertial"), f"{what} link {name!r}"))
    for nested in model.findall("model"):
        _walk(
            nested,
            prefix + nested.get("name", "") + "::",
            X_TM @ _pose(nested, f"{what} model {nested.get('name')!r}"),
            links,
            poses,
            joints,
            version,
            what,
        )
    for joint in model.findall("joint"):
        name = prefix + joint.get("name", "")
        label = f"{what} joint {name!r}"
        parent = (joint.findtext("parent") or "").strip()
        child = (joint.findtext("child") or "").strip()
        parent = parent if parent == "world" else prefix + parent
        child = prefix + child
        if child not in poses or (parent != "world" and parent not in poses):
            raise DescriptionError(
                f"{label}: names link {child if child not in poses else parent!r}, which the model does not have"
            )
        X_TP = np.eye(4) if parent == "world" else poses[parent]
        X_PC = np.linalg.inv(X_TP) @ poses[child]
        axis_el = joint.find("axis")
        axis = (1.0, 0.0, 0.0)
        effort = velocity = None
        if axis_el is not None:
            vector = np.array(floats(axis_el.findtext("xyz"), 3, f"{label} axis", (0.0, 0.0, 1.0)))
            if not np.linalg.norm(vector) > 0:
                raise DescriptionError(f"{label}: axis {tuple(vector)} has zero length")
            R_TC = poses[child][:3, :3]
            if version == (1, 4) or _in_model_frame(axis_el, version):
                vector = R_TC.T @ (X_TM[:3, :3] @ vector)
            else:  # in the joint frame, posed in the child link
                vector = _pose(joint, label)[:3, :3] @ vector
            axis = tuple(float(v) for v in vector / np.linalg.norm(vector))
            limit = axis_el.find("limit")
            if limit is not None:
                effort = _optional(limit.findtext("effort"), f"{label} effort")
                velocity = _optional(limit.findtext("velocity"), f"{label} velocity")
        joints[name] = Joint(
            name,
            joint.get("type", ""),
            parent,
            child,
            tuple(float(v) for v in X_PC[:3, 3]),
            rpy_from_matrix(X_PC[:3, :3]),
            axis,
            effort if effort is None or effort >= 0 else None,
            velocity if velocity is None or velocity >= 0 else None,
        )


def _optional(text: str | None, what: str) -> float | None:
    return None if text is None or not text.strip() else floats(text, 1, what)[0]


def _inertial(element: ET.Element | None, what: str) -> Inertial | None:
    """SDF's defaults: mass 1 kg, inertia the identity (kg m^2), at the link origin."""
    if element is None:
        return None
    mass = floats(element.findtext("mass"), 1, f"{what} <mass>", (1.0,))[0]
    inertia = element.find("inertia")

    def moment(tag: str, default: float) -> float:
        text = inertia.findtext(tag) if inertia is not None else None
        return floats(text, 1, f"{what} <{tag}>", (default,))[0]

    values = tuple(
        moment(t, d)
        for t, d in (("ixx", 1.0), ("ixy", 0.0), ("ixz", 0.0), ("iyy", 1.0), ("iyz", 0.0), ("izz", 1.0))
    )
    X = _pose(element, f"{what} <inertial>")
    return Inertial(mass, values, tuple(float(v) for v in X[:3, 3]), rpy_from_matrix(X[:3, :3]))
