"""Robot descriptions as a ROS user writes them (pure, no Drake): the URDF with its <gazebo>
tags and transmissions, the plugins' parameters, inertia checks, and the URDF rewritten for
Drake (meshes converted and cached, contact and colour properties mapped)."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import pytest
import trimesh
from support.ros_env import use_packages

from twil_control import PACKAGE_ROOT
from twil_control.description import meshes
from twil_control.description.drake_urdf import DRAKE_NS, urdf_for_drake
from twil_control.description.plugins import configure
from twil_control.description.urdf import DescriptionError, parse_urdf
from twil_control.description.xacro_command import run_xacro

ROBOTS = PACKAGE_ROOT / "tests" / "data" / "robots"
TINY_XACRO = ROBOTS / "tiny_description" / "urdf" / "tiny.urdf.xacro"
D = f"{{{DRAKE_NS}}}"


@pytest.fixture(autouse=True)
def _env(monkeypatch, tmp_path_factory):
    use_packages(monkeypatch, tmp_path_factory, ROBOTS)


def _tiny(*args: str):
    return parse_urdf(run_xacro([str(TINY_XACRO), *args]), "tiny")


def test_a_compiled_plugin_on_gazebo_plugin_path_fails_to_load_in_one_line(tmp_path, monkeypatch):
    # BARN's world plugins (jackal_helper/plugins/*.so, on GAZEBO_PLUGIN_PATH as run.py sets it)
    (tmp_path / "libgazebo_ros_planar_move.so").write_bytes(b"\x7fELF")
    monkeypatch.setenv("GAZEBO_PLUGIN_PATH", f"/nonexistent:{tmp_path}")
    warnings = configure(_tiny(), "tiny").warnings
    assert len(warnings) == 2
    assert (
        f"failed to load plugin 'planar_move' (libgazebo_ros_planar_move.so): "
        f"{tmp_path / 'libgazebo_ros_planar_move.so'} (GAZEBO_PLUGIN_PATH) is a compiled Gazebo plugin, "
        "which cannot run in this simulation"
    ) in warnings[0]
    assert "\n" not in warnings[0] and "is not supported" in warnings[1]  # not on the path: as before


def test_urdf_links_joints_transmissions_and_gazebo_elements():
    d = _tiny("drive:=ros_control")
    assert d.name == "tiny" and d.root == "base_footprint"
    assert d.joints["left_wheel_joint"].type == "continuous"
    assert d.joints["left_wheel_joint"].axis == (0.0, 1.0, 0.0)
    assert d.joints["right_wheel_joint"].xyz == pytest.approx((0.0, -0.1, 0.0))
    assert [(t.joint, t.interfaces) for t in d.transmissions] == [
        ("left_wheel_joint", ["hardware_interface/VelocityJointInterface"]),
        ("right_wheel_joint", ["hardware_interface/VelocityJointInterface"]),
    ]
    assert [p.filename for p in d.plugins] == [
        "libgazebo_ros_control.so",
        "libgazebo_ros_p3d.so",
        "libgazebo_ros_planar_move.so",
    ]
    assert [(s.type, s.link) for s in d.sensors] == [
        ("ray", "laser_link"),
        ("imu", "imu_link"),
        ("camera", "imu_link"),
    ]
    assert d.link_properties["left_wheel_link"]["kp"] == "1000000.0"


def test_plugin_parameters_with_gazebo_ros_names_and_one_warning_per_unsupported():
    configured = configure(_tiny(), "tiny")
    (drive,) = configured.drives
    assert (drive.kind, drive.left_joints, drive.right_joints) == (
        "diff_drive",
        ["left_wheel_joint"],
        ["right_wheel_joint"],
    )
    assert (drive.wheel_separation, drive.wheel_diameter, drive.torque) == pytest.approx((0.2, 0.1, 5.0))
    assert (drive.update_rate, drive.wheel_acceleration, drive.robot_base_frame) == (
        50.0,
        2.0,
        "base_footprint",
    )
    assert drive.publish_wheel_tf and drive.publish_wheel_joint_state and not drive.legacy_mode
    (laser,) = configured.lasers
    assert (laser.samples, laser.min_angle, laser.max_angle) == (180, -1.5708, 1.5708)
    assert (laser.range_min, laser.range_max, laser.range_resolution) == (0.05, 5.0, 0.01)
    assert (laser.topic, laser.frame, laser.update_rate, laser.noise.stddev) == (
        "scan",
        "laser_link",
        10.0,
        0.005,
    )
    (imu,) = configured.imus
    assert (imu.link, imu.topic, imu.update_rate) == ("imu_link", "imu", 100.0)
    assert (imu.rate_noise.stddev, imu.accel_noise.stddev) == (0.001, 0.01)
    (p3d,) = configured.p3d
    assert (p3d.link, p3d.topic, p3d.update_rate) == ("base_link", "ground_truth/odom", 50.0)
    assert len(configured.warnings) == 2
    assert "plugin 'planar_move' (libgazebo_ros_planar_move.so) is not supported" in configured.warnings[0]
    assert (
        "sensor 'camera' (camera) on link imu_link's plugin 'camera_plugin' (libgazebo_ros_camera.so) "
        "is not supported"
    ) in configured.warnings[1]
    assert (
        "supported plugins: libgazebo_ros_control.so, libgazebo_ros_diff_drive.so" in configured.warnings[1]
    )
    skid = configure(_tiny("drive:=skid_steer", "odometry_source:=encoder"), "tiny", "/other")
    (drive,) = skid.drives
    assert drive.kind == "skid_steer" and drive.odometry_source == "encoder"
    assert drive.namespace == "/other"  # -robot_namespace replaces robotNamespace
    assert drive.covariance == (0.001, 0.001, 0.05)
    assert configure(_tiny("drive:=ros_control"), "tiny").ros_control[0].namespace == "/tiny"


def _robot(links: str, joints: str = "") -> str:
    return f'<robot name="r">{links}{joints}</robot>'


INERTIAL = (
    '<inertial><mass value="1"/><inertia ixx="{}" ixy="0" ixz="0" iyy="{}" iyz="0" izz="{}"/></inertial>'
)


def test_inertia_checks_name_the_link():
    good = INERTIAL.format(1, 1, 1)
    massless = _robot(
        f'<link name="base">{good}</link><link name="arm"/>',
        '<joint name="j" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/></joint>',
    )
    with pytest.raises(
        DescriptionError,
        match=r"link 'arm' \(the child of revolute joint 'j'\) moves but has "
        r"no <inertial>",
    ):
        parse_urdf(massless, "r").check_inertia()
    broken = _robot(f'<link name="base">{INERTIAL.format(1, 1, 3)}</link>')
    with pytest.raises(
        DescriptionError,
        match=r"link 'base' has a non-physical <inertial>: principal moments "
        r"\[1.0, 1.0, 3.0\] break the triangle inequality",
    ):
        parse_urdf(broken, "r").check_inertia()
    # a massless root welded to a body with mass is one rigid body with mass: fine
    welded = _robot(
        f'<link name="footprint"/><link name="base">{good}</link>',
        '<joint name="w" type="fixed"><parent link="footprint"/><child link="base"/></joint>',
    )
    parse_urdf(welded, "r").check_inertia()


def test_urdf_for_drake_converts_meshes_and_maps_gazebo_properties():
    d = _tiny()
    text, warnings = urdf_for_drake(d, "robot_1", None, ("left_wheel_joint",))
    root = ET.fromstring(text)
    assert root.get("name") == "robot_1" and root.find("gazebo") is None
    base = root.find("link[@name='base_link']")
    visual_mesh = base.find("visual/geometry/mesh")
    collision_mesh = base.find("collision/geometry/mesh")
    assert visual_mesh.get("scale") is None and visual_mesh.get("filename").startswith("file:///")
    assert collision_mesh.find(f"{D}declare_convex") is not None
    box = trimesh.load(visual_mesh.get("filename")[len("file://") :])
    assert box.extents == pytest.approx([0.2, 0.15, 0.06], abs=1e-9)  # the STL's mm scaled to m
    laser = trimesh.load(root.find("link[@name='laser_link']/visual/geometry/mesh").get("filename")[7:])
    assert laser.extents == pytest.approx([0.06, 0.06, 0.04], abs=1e-6)  # the DAE cylinder
    props = root.find("link[@name='left_wheel_link']/collision/" + D + "proximity_properties")
    assert float(props.find(D + "mu_dynamic").get("value")) == 1.0
    assert float(props.find(D + "point_contact_stiffness").get("value")) == 1e6
    colour = base.find("visual/material/color").get("rgba")
    assert [float(c) for c in colour.split()] == [1.0, 0.5, 0.05, 1.0]  # Gazebo/Orange
    assert len(warnings) == 1
    assert warnings[0].startswith(
        "tiny: <gazebo reference> tags with no Drake equivalent are ignored: fdir1 "
        "(left_wheel_link, right_wheel_link); kd (left_wheel_link, right_wheel_link); "
        "minDepth (left_wheel_link, right_wheel_link)"
    )


def test_meshes_are_converted_once_and_unknown_formats_refused(tmp_path):
    source = ROBOTS / "tiny_description" / "meshes" / "wheel.obj"
    first = meshes.convert(source, (2.0, 2.0, 2.0))
    stamp = first.stat().st_mtime_ns
    assert meshes.convert(source, (2.0, 2.0, 2.0)) == first and first.stat().st_mtime_ns == stamp
    assert meshes.convert(source, (1.0, 1.0, 1.0)) != first  # the scale is part of the key
    assert trimesh.load(first).extents == pytest.approx([0.2, 0.2, 0.06], abs=1e-9)  # r 0.05, h 0.03, x2
    bad = tmp_path / "part.3ds"
    bad.write_bytes(b"x")
    with pytest.raises(
        meshes.MeshError, match=r"part.3ds: format .3ds is not supported; supported: .stl, .dae, .obj"
    ):
        meshes.convert(bad)
