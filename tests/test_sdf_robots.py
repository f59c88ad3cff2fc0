"""SDF robot models with their Gazebo plugins, as a Gazebo user writes them (tests/data/gazebo/
rover_gazebo: a skid-steer rover whose laser is a model of its own, included and fixed by a
revolute joint with equal limits): in the world file or spawned with spawn_model -sdf, driven by
gazebo_ros_skid_steer_drive and scanning with gazebo_ros_laser; gazebo_ros_control reading the
URDF's transmissions."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import read_bag
from support.ros_env import use_packages

from twil_control import PACKAGE_ROOT
from twil_control.description.gazebo_world import normalise
from twil_control.gazebo.plugins import ros_control_of
from twil_control.launch.loader import load_launch
from twil_control.launch.runner import Launch, RunOptions, run

DATA = PACKAGE_ROOT / "tests" / "data" / "gazebo"
ROVER_MODEL = DATA / "rover_gazebo" / "models" / "rover" / "model.sdf"
SEQUENCE = PACKAGE_ROOT / "tests" / "data" / "robots" / "tiny_description" / "config" / "cmd_sequence.yaml"


@pytest.fixture(autouse=True)
def _env(monkeypatch, tmp_path_factory):
    use_packages(monkeypatch, tmp_path_factory, DATA, without_gazebo_paths=True)


def _launch(tmp_path, *nodes: str):
    path = tmp_path / "rover.launch.yaml"
    path.write_text("launch:\n" + "".join(f"  - {node}\n" for node in nodes))
    return load_launch(path)


GZSERVER = 'node: {pkg: gazebo_ros, type: gzserver, name: gazebo, args: "-e ode %s"}'
DRIVE = f"node: {{pkg: twil_control, type: qbot_cmd_sequence, name: drive, params: {{file: {SEQUENCE}, topic: %s}}}}"


def _room_ranges(x: float, y: float, yaw: float, angles: np.ndarray) -> np.ndarray:
    """Ranges from (x, y) to the inner faces of rover_room's walls (the square |x|, |y| <= 2)."""
    c, s = np.cos(yaw + angles), np.sin(yaw + angles)
    with np.errstate(divide="ignore"):
        tx = np.where(c > 0, (2.0 - x) / c, (-2.0 - x) / c)
        ty = np.where(s > 0, (2.0 - y) / s, (-2.0 - y) / s)
    return np.minimum(tx, ty)


def test_the_rover_described_in_sdf_has_the_links_joints_and_plugins_a_urdf_would():
    world = normalise(DATA / "rover_gazebo" / "worlds" / "rover_room.world")
    rover = world.models[-1].robot
    assert rover.root == "chassis"
    assert sorted(rover.links) == [
        "chassis",
        "front_left_wheel",
        "front_right_wheel",
        "lidar::link",
        "rear_left_wheel",
        "rear_right_wheel",
    ]
    wheel = rover.joints["front_left"]
    assert (wheel.parent, wheel.child) == ("chassis", "front_left_wheel")
    np.testing.assert_allclose(wheel.xyz, (0.16, 0.17, -0.03), atol=1e-12)  # wheel in the chassis frame
    np.testing.assert_allclose(wheel.axis, (0.0, 0.0, -1.0), atol=1e-4)  # model y in the rolled wheel
    mount = rover.joints["lidar_joint"]
    assert (mount.type, mount.child) == ("fixed", "lidar::link")  # revolute 0..0: Gazebo holds it
    np.testing.assert_allclose(mount.xyz, (0.12, 0.0, 0.05), atol=1e-12)  # include pose 0.08, chassis 0.03
    assert [p.filename for p in rover.plugins] == ["libgazebo_ros_skid_steer_drive.so"]
    (laser,) = rover.sensors
    assert (laser.link, laser.type, [p.filename for p in laser.plugins]) == (
        "lidar::link",
        "ray",
        ["libgazebo_ros_laser.so"],
    )


@pytest.mark.slow
def test_a_rover_in_the_world_file_drives_under_its_skid_steer_plugin_and_scans_640_beams(tmp_path):
    plan = _launch(tmp_path, GZSERVER % "worlds/rover_room.world", DRIVE % "/rover/cmd_vel")
    result = run(plan, RunOptions(duration=2.0, bag=tmp_path / "run.bag"))
    assert result.error is None
    bag = read_bag(result.bag)
    odom = {t: m for t, m in bag["/rover/odom"]}
    assert len(odom) == pytest.approx(2.0 * 50, abs=2)  # updateRate 50
    at_1s = odom[1_000_000_000].pose.pose.position
    assert (at_1s.x, at_1s.y) == (pytest.approx(-0.5 + 0.3, abs=0.015), pytest.approx(0.2, abs=0.005))
    q = odom[max(odom)].pose.pose.orientation
    assert 2 * math.atan2(q.z, q.w) > 0.3  # then turning left (skid steering scrubs: under 1 rad)
    scans = [m for _, m in bag["/rover/laser/scan"]]
    assert len(scans) == pytest.approx(2.0 * 20, abs=1)  # update_rate 20
    for t, scan in bag["/rover/laser/scan"]:
        if t not in odom or t > 1_000_000_000:  # odometry (the true pose) at 50 Hz; straight ahead
            continue
        assert (len(scan.ranges), scan.header.frame_id) == (640, "laser")
        pose = odom[t].pose.pose
        yaw = 2 * math.atan2(pose.orientation.z, pose.orientation.w)
        forward = 0.12 + 0.01  # the lidar's include pose and its sensor's pose, from the chassis
        x, y = pose.position.x + forward * math.cos(yaw), pose.position.y + forward * math.sin(yaw)
        angles = scan.angle_min + scan.angle_increment * np.arange(640)
        error = np.abs(np.asarray(scan.ranges) - _room_ranges(x, y, yaw, angles))
        assert error.max() <= 0.0051 + 0.002, t  # 0.01 m resolution; the chassis's pitch


def test_spawn_model_sdf_loads_the_plugins_of_the_model_and_of_the_model_it_includes(tmp_path):
    plan = _launch(
        tmp_path,
        GZSERVER % "worlds/empty.world",
        "node: {pkg: gazebo_ros, type: spawn_model, name: spawn, args: "
        f'"-sdf -file {ROVER_MODEL} -model bot -robot_namespace bot -x 0.5 -y -0.3 -Y 1.0"}}',
    )
    launch = Launch(plan)
    launch.build()
    launch.start()
    try:
        bus = launch.master.bus
        for topic in ("/bot/odom", "/rover/laser/scan", "/tf"):  # the laser's topic is absolute
            assert bus.publishers_of(topic) == ["/gazebo"], topic
        assert bus.subscribers_of("/bot/cmd_vel") == ["/gazebo"]
        plant = launch.sim.plant
        assert plant.GetJointActuatorByName("front_left").effort_limit() == 20.0  # <torque>
        launch.simulator.AdvanceTo(0.5)
        context = plant.GetMyContextFromRoot(launch.simulator.get_context())
        chassis = plant.EvalBodyPoseInWorld(context, launch.sim.body("bot", "chassis"))
        # gazebo_ros places an SDF model at its own <pose> (z 0.1) after the spawn pose; it falls
        # onto its wheels: the chassis 0.03 above the wheel axes, 0.05 above the ground
        np.testing.assert_allclose(chassis.translation(), [0.5, -0.3, 0.08], atol=0.003)
        assert chassis.rotation().ToRollPitchYaw().yaw_angle() == pytest.approx(1.0, abs=1e-3)
        laser = plant.EvalBodyPoseInWorld(context, launch.sim.body("bot", "lidar::link")).translation()
        np.testing.assert_allclose(
            laser - chassis.translation(), [0.12 * math.cos(1.0), 0.12 * math.sin(1.0), 0.05], atol=0.003
        )
    finally:
        launch.shutdown()


URDF = """<robot name="rover">{links}{transmissions}</robot>"""


def test_gazebo_ros_control_in_an_sdf_model_reads_the_urdfs_transmissions(tmp_path):
    model = ROVER_MODEL.read_text()
    start, end = model.index("<plugin"), model.index("</plugin>") + len("</plugin>")
    sdf = tmp_path / "rover_rc.sdf"
    sdf.write_text(
        model[:start]
        + '<plugin name="gazebo_ros_control" filename="libgazebo_ros_control.so"><robotNamespace>/rover</robotNamespace></plugin>'
        + model[end:]
    )
    wheels = ("front_left", "front_right", "rear_left", "rear_right")
    urdf = URDF.format(
        links="<link name='chassis'/>",
        transmissions="".join(
            f"<transmission name='{w}_t'><type>transmission_interface/SimpleTransmission</type>"
            f"<joint name='{w}'><hardwareInterface>hardware_interface/VelocityJointInterface</hardwareInterface>"
            f"</joint><actuator name='{w}_m'/></transmission>"
            for w in wheels
        ),
    )
    (tmp_path / "rover.urdf").write_text(urdf)
    plan = _launch(
        tmp_path,
        f"param: {{name: robot_description, textfile: {tmp_path / 'rover.urdf'}}}",
        GZSERVER % "worlds/empty.world",
        f'node: {{pkg: gazebo_ros, type: spawn_model, name: spawn, args: "-sdf -file {sdf} -model rover"}}',
    )
    launch = Launch(plan)
    launch.build()
    try:
        plugin = ros_control_of(launch.nodes, "/rover")
        assert sorted(plugin.joint_configs) == sorted(wheels)
        assert {tuple(c.interfaces) for c in plugin.joint_configs.values()} == {("velocity",)}
    finally:
        launch.shutdown()
