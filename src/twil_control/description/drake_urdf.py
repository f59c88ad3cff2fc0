"""A user's URDF rewritten into what Drake's parser reads, with the ``<gazebo reference>``
properties mapped to Drake's (pure XML work, no Drake import).

Meshes are resolved and converted to cached OBJs (collision meshes declared convex: Drake's point
contact uses the hull); ``mu1``, ``kp`` and ``material`` map to Drake's friction, stiffness and
colour, the rest is warned about once per link; ``<gazebo>`` and unsupported ``<transmission>``
elements are removed, and a SimpleTransmission is added for each joint a drive plugin turns, so
Drake gives it an actuator (docs/robots.md).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from twil_control.core import packages

from . import meshes
from .gazebo_materials import GAZEBO_COLORS
from .urdf import DescriptionError, RobotDescription, floats

__all__ = ["GAZEBO_COLORS", "self_collides", "urdf_for_drake"]

DRAKE_NS = "http://drake.mit.edu"
ET.register_namespace("drake", DRAKE_NS)

#: <gazebo reference> tags mapped to Drake (the rest have no equivalent and are warned);
#: selfCollide is read by self_collides().
MAPPED_LINK_TAGS = ("mu1", "mu2", "kp", "material", "selfCollide")


def self_collides(description: RobotDescription) -> bool:
    """Whether a link of the robot asks Gazebo to collide it with the robot's other links
    (``<selfCollide>true</selfCollide>``); without one, Gazebo collides none of them."""
    return any(
        str(props.get("selfCollide", "")).strip().lower() in ("1", "true")
        for props in description.link_properties.values()
    )


def _drake(tag: str) -> str:
    return f"{{{DRAKE_NS}}}{tag}"


def urdf_for_drake(
    description: RobotDescription,
    model_name: str,
    base_dir: Path | None,
    actuated_joints: tuple[str, ...] = (),
) -> tuple[str, list[str]]:
    """(URDF text for Drake's parser, warnings). The robot is renamed ``model_name`` (Drake's
    model instance name, as spawn_model's -model names Gazebo's model); ``base_dir`` resolves
    relative mesh paths; ``actuated_joints`` get a SimpleTransmission unless they have one."""
    root = description.root_element
    if root is None:
        raise DescriptionError(f"{description.source}: no XML to rewrite")
    root = ET.fromstring(ET.tostring(root))  # a copy: the description stays as read
    root.set("name", model_name)
    _resolve_meshes(root, description, base_dir)
    warnings = _map_gazebo_references(root, description)
    for el in root.findall("gazebo"):
        root.remove(el)
    kept = _keep_simple_transmissions(root, description.source, warnings)
    for joint in actuated_joints:
        if joint not in kept:
            _add_transmission(root, joint)
    return ET.tostring(root, encoding="unicode"), warnings


def _resolve_meshes(root: ET.Element, description: RobotDescription, base_dir: Path | None) -> None:
    """Every visual and collision mesh first, then one conversion of those not cached yet."""
    jobs = []
    for link in root.findall("link"):
        for role in ("visual", "collision"):
            for geometry in link.findall(f"{role}/geometry"):
                mesh = geometry.find("mesh")
                if mesh is not None:
                    jobs.append(_mesh_job(mesh, role, link.get("name"), description, base_dir))
    _convert_meshes(jobs)


def _map_gazebo_references(root: ET.Element, description: RobotDescription) -> list[str]:
    """Apply each ``<gazebo reference>``'s properties to its link; the warnings for what
    names no link, what sits on a joint and the tags with no Drake equivalent."""
    warnings: list[str] = []
    unmapped: dict[str, list[str]] = {}
    for name, props in description.link_properties.items():
        link = root.find(f"link[@name='{name}']")
        if link is None:
            warnings += _reference_without_link(description, name, props)
            continue
        warnings += _link_properties(link, props, description.source)
        for tag in sorted(props):
            if tag not in MAPPED_LINK_TAGS:
                unmapped.setdefault(tag, []).append(name)
    if unmapped:
        listed = "; ".join(f"{tag} ({', '.join(links)})" for tag, links in unmapped.items())
        warnings.append(
            f"{description.source}: <gazebo reference> tags with no Drake equivalent "
            f"are ignored: {listed} (mapped: {', '.join(MAPPED_LINK_TAGS)}; see "
            f"docs/robots.md)"
        )
    return warnings


def _reference_without_link(description: RobotDescription, name: str, props: dict[str, str]) -> list[str]:
    if name not in description.joints:
        return [f"{description.source}: <gazebo reference={name!r}> names no link or joint; ignored"]
    if props:
        return [
            f"{description.source}: <gazebo reference={name!r}> (a joint): "
            f"{', '.join(sorted(props))} have no Drake equivalent; ignored"
        ]
    return []


def _keep_simple_transmissions(root: ET.Element, source: str, warnings: list[str]) -> set[str]:
    """Remove the transmissions Drake cannot read (warning of each); the joints of those kept."""
    kept = set()
    for el in root.findall("transmission"):
        kind = (el.findtext("type") or el.get("type") or "").strip()
        if not kind.endswith("SimpleTransmission"):
            warnings.append(
                f"{source}: transmission {el.get('name')!r} of type "
                f"{kind!r} is not supported (SimpleTransmission is); ignored"
            )
            root.remove(el)
            continue
        kept.update(j.get("name") for j in el.findall("joint"))
    return kept


def _mesh_job(
    mesh: ET.Element, role: str, link: str, description: RobotDescription, base_dir: Path | None
) -> tuple:
    """(mesh element, role, what to call it in an error, source file, scale)."""
    url = mesh.get("filename", "")
    what = f"{description.source}: link {link!r} {role} mesh {url!r}"
    try:
        source = packages.resolve_url(url, relative_to=base_dir)
    except packages.PackageNotFoundError as exc:
        raise DescriptionError(f"{what}: {exc}") from None
    scale_text = mesh.get("scale")
    scale = (
        floats(scale_text, 3, f"{what} scale")
        if scale_text and len(scale_text.split()) == 3
        else (floats(scale_text, 1, f"{what} scale") * 3 if scale_text else (1.0, 1.0, 1.0))
    )
    return mesh, role, what, source, scale


def _convert_meshes(jobs: list[tuple]) -> None:
    try:
        converted = meshes.convert_all([(source, scale) for *_, source, scale in jobs])
    except meshes.MeshError as exc:
        failed = next((what for _, _, what, source, _ in jobs if f"mesh {source}:" in str(exc)), None)
        raise DescriptionError(f"{failed}: {exc}" if failed else str(exc)) from None
    for (mesh, role, *_), path in zip(jobs, converted):
        mesh.set("filename", path.absolute().as_uri())  # Drake reads file:// URIs from strings
        mesh.attrib.pop("scale", None)
        if role == "collision" and mesh.find(_drake("declare_convex")) is None:
            ET.SubElement(mesh, _drake("declare_convex"))


def _link_properties(link: ET.Element, props: dict[str, str], source: str) -> list[str]:
    name = link.get("name")
    warnings = []
    contact = {}
    if "mu1" in props or "mu2" in props:
        mu1 = floats(props.get("mu1", props.get("mu2")), 1, f"{source}: link {name!r} mu1")[0]
        mu2 = floats(props.get("mu2", props.get("mu1")), 1, f"{source}: link {name!r} mu2")[0]
        if mu1 != mu2:
            warnings.append(
                f"{source}: link {name!r}: mu1 {mu1} and mu2 {mu2} differ; Drake's "
                f"friction is isotropic: mu1 is used in every direction"
            )
        contact["mu_dynamic"] = contact["mu_static"] = mu1
    if "kp" in props:
        contact["point_contact_stiffness"] = floats(props["kp"], 1, f"{source}: link {name!r} kp")[0]
    if contact:
        for collision in link.findall("collision"):
            holder = collision.find(_drake("proximity_properties"))
            if holder is None:
                holder = ET.SubElement(collision, _drake("proximity_properties"))
            for key, value in contact.items():
                if holder.find(_drake(key)) is None:
                    ET.SubElement(holder, _drake(key), value=repr(float(value)))
    if "material" in props:
        material = props["material"]
        rgba = GAZEBO_COLORS.get(material)
        if rgba is None:
            warnings.append(
                f"{source}: link {name!r}: Gazebo material {material!r} is not one of "
                f"the known colours ({', '.join(GAZEBO_COLORS)}); the URDF's is kept"
            )
        else:
            for visual in link.findall("visual"):
                for old in visual.findall("material"):
                    visual.remove(old)
                mat = ET.SubElement(visual, "material")
                ET.SubElement(mat, "color", rgba=" ".join(repr(c) for c in rgba))
    return warnings


def _add_transmission(root: ET.Element, joint: str) -> None:
    trans = ET.SubElement(root, "transmission", name=f"{joint}_drive_transmission")
    ET.SubElement(trans, "type").text = "transmission_interface/SimpleTransmission"
    ET.SubElement(
        ET.SubElement(trans, "joint", name=joint), "hardwareInterface"
    ).text = "hardware_interface/EffortJointInterface"
    actuator = ET.SubElement(trans, "actuator", name=joint)
    ET.SubElement(actuator, "mechanicalReduction").text = "1"
