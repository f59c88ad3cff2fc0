"""Robot descriptions and worlds in sim/: they load offline, carry the documented numbers, and
behave on the floor (rest, drive straight, saturate without spinning the wheels)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pydrake.geometry import Box, Cylinder, Role, Sphere
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlant, MultibodyPlantConfig
from pydrake.multibody.tree import JointActuatorIndex, JointIndex
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource

from twil_control import PACKAGE_ROOT
from twil_control.world import models
from twil_control.world.models import MODELS, ModelError, add_model

# ---- numbers from the sources (Barrett's WAM table as the lab used it; the files' own choices) ----
WAM_TABLE_MASSES = [  # Barrett D1001/D1005 as the lab's description gives them, links 0 (base) .. 7
    9.97059584,
    10.76768767,
    3.87493756,
    1.80228141,
    2.40016804,
    0.12376019,
    0.41797364,
    0.06864753,
]
WAM_MASS = sum(WAM_TABLE_MASSES)  # 29.42605188 kg
TWIL_CHASSIS_MASS, TWIL_WHEEL_MASS = 48.0, 1.0
TWIL_MASS = TWIL_CHASSIS_MASS + 2 * TWIL_WHEEL_MASS  # 50 kg
QBOT_MASS = 5.0 + 4 * 0.2 + 0.1  # chassis + 4 wheels + Hokuyo = 5.9 kg
WHEEL_RADIUS, WHEEL_SEPARATION = 0.075, 0.322
TWIL_WHEEL_EFFORT_LIMIT = 6.0
WAM_EFFORT_LIMITS = [75.6, 50.85, 50.85, 28.8, 5.688, 5.688, 9.152]
WAM_JOINTS = [f"wam_joint_{i}" for i in range(1, 8)]
TWIL_WHEELS = ["left_wheel_joint", "right_wheel_joint"]
QBOT_WHEELS = ["left_front", "right_front", "left_rear", "right_rear"]
WAM_HOME = [0.0, -2.0, 0.0, 3.1, 0.0, 0.0, 0.0]


def box_inertia(m, a, b, c):
    return np.array([m * (b * b + c * c), m * (a * a + c * c), m * (a * a + b * b)]) / 12


def cylinder_inertia_about_y(m, r, w):
    """Solid cylinder whose axis is y (a wheel): (Ixx, Iyy, Izz)."""
    diam = m * (3 * r * r + w * w) / 12
    return np.array([diam, m * r * r / 2, diam])


# ---- helpers ------------------------------------------------------------------------------------
def load(*names, time_step=0.0):
    """A finalized plant (with scene graph) holding the named models; returns (plant, sg, ids)."""
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlant(MultibodyPlantConfig(time_step=time_step), builder)
    instances = {name: add_model(plant, name) for name in names}
    plant.Finalize()
    return plant, scene_graph, instances


def joints_of(plant, instance_list, type_name):
    names = []
    for i in range(plant.num_joints()):
        joint = plant.get_joint(JointIndex(i))
        if joint.model_instance() in instance_list and joint.type_name() == type_name:
            names.append(joint.name())
    return names


def actuators_of(plant, instance_list):
    """[(actuator name, joint name, effort limit)] in index order."""
    out = []
    for i in range(plant.num_actuators()):
        actuator = plant.get_joint_actuator(JointActuatorIndex(i))
        if actuator.model_instance() in instance_list:
            out.append((actuator.name(), actuator.joint().name(), actuator.effort_limit()))
    return out


class Run:
    """A world + one robot on the floor, constant wheel torques, stepping in fixed intervals."""

    def __init__(
        self, robot, wheel_torque, wheels, approximation="lagged", x=0.0, y=0.0, yaw=0.0, lock_arm_at=None
    ):
        builder = DiagramBuilder()
        config = MultibodyPlantConfig(
            time_step=0.001, contact_model="point", discrete_contact_approximation=approximation
        )
        plant, self.scene_graph = AddMultibodyPlant(config, builder)
        add_model(plant, "default_world")
        instances = add_model(plant, robot)
        base_instance = next(i for i in instances if plant.HasBodyNamed("base_link", i))
        self.X_W0 = models.set_base_pose(plant, base_instance, x, y, yaw)
        plant.Finalize()
        u = np.zeros(plant.num_actuated_dofs())
        for name in wheels:
            u[plant.GetJointActuatorByName(name).input_start()] = wheel_torque
        source = builder.AddSystem(ConstantVectorSource(u))
        builder.Connect(source.get_output_port(), plant.get_actuation_input_port())
        self.simulator = Simulator(builder.Build())
        self.plant = plant
        self.context = plant.GetMyContextFromRoot(self.simulator.get_mutable_context())
        if lock_arm_at is not None:  # joint locking needs SAP
            for name, q in zip(WAM_JOINTS, lock_arm_at):
                joint = plant.GetJointByName(name)
                joint.set_angle(self.context, q)
                joint.Lock(self.context)
        self.base = plant.GetBodyByName("base_link", base_instance)
        self.wheel = plant.GetJointByName(wheels[0])
        self.wheel_radius = WHEEL_RADIUS if robot.startswith("twil") else 0.055

    def pose(self) -> RigidTransform:
        return self.plant.EvalBodyPoseInWorld(self.context, self.base)

    def samples(self, duration, every=0.01):
        """Advance to `duration`, yielding after each `every` seconds."""
        t = self.simulator.get_context().get_time()
        for k in range(1, round(duration / every) + 1):
            self.simulator.AdvanceTo(t + k * every)
            yield

    def slip(self):
        """|wheel rim speed - base forward speed| of the first wheel (m/s)."""
        X = self.pose()
        V = self.plant.EvalBodySpatialVelocityInWorld(self.context, self.base)
        forward = X.rotation().matrix()[:, 0] @ V.translational()
        return abs(self.wheel.get_angular_rate(self.context) * self.wheel_radius - forward)

    def planar_motion(self):
        """(distance along the initial heading, lateral drift, yaw change in rad)."""
        X0, X = self.X_W0, self.pose()
        d = X.translation() - X0.translation()
        heading = X0.rotation().matrix()[:, 0]
        left = X0.rotation().matrix()[:, 1]
        yaw = RollPitchYaw(X.rotation()).yaw_angle() - RollPitchYaw(X0.rotation()).yaw_angle()
        return float(heading @ d), float(left @ d), math.atan2(math.sin(yaw), math.cos(yaw))


# ---- loading, names, counts, masses -------------------------------------------------------------
def test_every_short_name_points_at_a_shipped_file_under_sim():
    assert models.SIM_DIR == PACKAGE_ROOT / "sim"
    assert set(MODELS) == {"twil", "wam", "wam_fixed", "twil_wam", "qbot", "default_world"}
    for name, path in MODELS.items():
        assert path.is_file(), name
        assert models.SIM_DIR in path.parents
        assert "drake_models" not in path.read_text()  # offline: nothing fetched at run time


@pytest.mark.parametrize(
    "name, mass, revolute, actuated",
    [
        ("twil", TWIL_MASS, TWIL_WHEELS, TWIL_WHEELS),
        ("wam", WAM_MASS, WAM_JOINTS, WAM_JOINTS),
        ("wam_fixed", WAM_MASS, WAM_JOINTS, WAM_JOINTS),
        ("twil_wam", TWIL_MASS + WAM_MASS, TWIL_WHEELS + WAM_JOINTS, TWIL_WHEELS + WAM_JOINTS),
        ("qbot", QBOT_MASS, QBOT_WHEELS, QBOT_WHEELS),
    ],
)
def test_robot_has_documented_mass_joints_and_actuators(name, mass, revolute, actuated):
    plant, _, instances = load(name)
    ids = instances[name]
    context = plant.CreateDefaultContext()
    assert plant.CalcTotalMass(context, ids) == pytest.approx(mass, abs=1e-6)
    assert joints_of(plant, ids, "revolute") == revolute
    actuators = actuators_of(plant, ids)
    # Drake names each actuator after the URDF <transmission><actuator name>: the joint's name.
    assert [a for a, _, _ in actuators] == actuated
    assert [j for _, j, _ in actuators] == actuated
    assert len(actuators) == len(revolute)
    for i in range(plant.num_joints()):  # no damping anywhere (control model == plant)
        joint = plant.get_joint(JointIndex(i))
        assert np.all(joint.default_damping_vector() == 0), joint.name()


def test_wam_total_mass_is_the_sum_of_the_robots_md_table():
    assert WAM_MASS == pytest.approx(29.42605188, abs=1e-9)


def test_effort_limits_come_from_the_descriptions():
    plant, _, instances = load("twil_wam", "qbot")
    limits = {a: e for a, _, e in actuators_of(plant, sum(instances.values(), []))}
    for name in TWIL_WHEELS:
        assert limits[name] == TWIL_WHEEL_EFFORT_LIMIT
    for name, limit in zip(WAM_JOINTS, WAM_EFFORT_LIMITS):
        assert limits[name] == limit
    for name in QBOT_WHEELS:
        assert limits[name] == 200.0  # the original drive plugin's wheel torque limit


def test_free_and_fixed_bases():
    plant, _, instances = load("twil_wam")
    assert {plant.get_body(b).name() for b in plant.GetFloatingBaseBodies()} == {"base_link"}
    assert plant.num_positions() == 7 + 2 + 7  # quaternion + xyz, 2 wheels, 7 arm joints
    plant, _, _ = load("wam_fixed")
    assert len(plant.GetFloatingBaseBodies()) == 0
    X_WB = plant.EvalBodyPoseInWorld(plant.CreateDefaultContext(), plant.GetBodyByName("wam_base_link"))
    assert X_WB.translation() == pytest.approx([0, 0, 0.346], abs=1e-12)


def test_twil_geometry_and_inertia_as_documented():
    plant, sg, instances = load("twil")
    context = plant.CreateDefaultContext()
    base = plant.GetBodyByName("base_link")
    chassis = base.default_spatial_inertia()
    assert chassis.get_mass() == TWIL_CHASSIS_MASS
    assert chassis.get_com() == pytest.approx([0.05, 0, 0.155], abs=1e-12)  # d_chassis = 0.05
    I_Bcm = chassis.Shift(chassis.get_com()).CalcRotationalInertia().CopyToFullMatrix3()
    assert np.abs(I_Bcm - np.diag(box_inertia(48.0, 0.6, 0.45, 0.3))).max() < 1e-9
    wheel = plant.GetBodyByName("left_wheel_link").default_rotational_inertia().CopyToFullMatrix3()
    assert np.diag(wheel) == pytest.approx(cylinder_inertia_about_y(1.0, 0.075, 0.04), abs=1e-10)
    # platform CoM: d = 48 * 0.05 / 50 = 0.048 ahead of the axle midpoint (base_link origin)
    p_BCm = plant.CalcCenterOfMassPositionInWorld(context, instances["twil"])
    assert p_BCm[0] == pytest.approx(48 * 0.05 / 50, abs=1e-12)
    for side, y in (("left", 1), ("right", -1)):
        X_BW = plant.CalcRelativeTransform(
            context, base.body_frame(), plant.GetFrameByName(f"{side}_wheel_link")
        )
        assert X_BW.translation() == pytest.approx([0, y * WHEEL_SEPARATION / 2, 0], abs=1e-12)
        joint = plant.GetJointByName(f"{side}_wheel_joint")
        assert joint.revolute_axis() == pytest.approx([0, 1, 0])
    inspector = sg.model_inspector()
    shapes = {
        inspector.GetName(g): inspector.GetShape(g) for g in inspector.GetAllGeometryIds(Role.kProximity)
    }
    for wheel_name in ("twil::left_wheel", "twil::right_wheel"):  # spheres, not cylinders
        assert isinstance(shapes[wheel_name], Sphere) and shapes[wheel_name].radius() == WHEEL_RADIUS
    for name, mu in (("twil::left_wheel", 1.0), ("twil::castor", 0.0), ("twil::anti_tip_castor", 0.0)):
        gid = next(g for g in inspector.GetAllGeometryIds(Role.kProximity) if inspector.GetName(g) == name)
        friction = inspector.GetProximityProperties(gid).GetProperty("material", "coulomb_friction")
        assert (friction.static_friction(), friction.dynamic_friction()) == (mu, mu)


def test_wam_kinematics_match_the_standard_dh_table():
    a = [0, 0, 0.045, -0.045, 0, 0, 0]
    d = [0, 0, 0.55, 0, 0.3, 0, 0.06]
    alpha = [-math.pi / 2, math.pi / 2, -math.pi / 2, math.pi / 2, -math.pi / 2, math.pi / 2, 0]

    def dh(a, d, al, th):
        ct, st, ca, sa = math.cos(th), math.sin(th), math.cos(al), math.sin(al)
        return np.array(
            [[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0, sa, ca, d], [0, 0, 0, 1]]
        )

    plant, _, _ = load("wam_fixed")
    context = plant.CreateDefaultContext()
    base = plant.GetFrameByName("wam_base_link")
    rng = np.random.default_rng(7)
    for q in [np.zeros(7), np.array(WAM_HOME), *rng.uniform(-1.5, 1.5, (3, 7))]:
        plant.SetPositions(context, q)
        T = np.eye(4)
        for i in range(7):
            T = T @ dh(a[i], d[i], alpha[i], q[i])
            X = plant.CalcRelativeTransform(context, base, plant.GetFrameByName(f"wam_link_{i + 1}"))
            assert np.abs(X.GetAsMatrix4() - T).max() < 1e-12, (q, i)


def test_wam_inertia_is_the_table_in_dh_frames():
    plant, _, _ = load("wam_fixed")
    link7 = plant.GetBodyByName("wam_link_7").default_spatial_inertia()
    assert link7.get_com() == pytest.approx([-0.00007974, 0.00016313, -0.00323552], abs=1e-12)
    I7 = link7.Shift(link7.get_com()).CalcRotationalInertia().CopyToFullMatrix3()
    expected = np.array([[0.00003773, -0.00000019, 0], [-0.00000019, 0.00003806, 0], [0, 0, 0.00007408]])
    assert np.abs(I7 - expected).max() < 1e-12
    # base: inertia given about axes rotated rpy (pi/2, 0, pi/2): I_link = R I R^T
    base = plant.GetBodyByName("wam_base_link").default_spatial_inertia()
    R = RollPitchYaw(math.pi / 2, 0, math.pi / 2).ToRotationMatrix().matrix()
    I_axes = np.array(
        [
            [0.10916849, 0.00640270, 0.02557874],
            [0.00640270, 0.18294303, 0.00161433],
            [0.02557874, 0.00161433, 0.11760385],
        ]
    )
    I0 = base.Shift(base.get_com()).CalcRotationalInertia().CopyToFullMatrix3()
    assert np.abs(I0 - R @ I_axes @ R.T).max() < 1e-12
    for name in ("wam_link_3_virtual", "wam_link_4_virtual"):  # massless, welded
        assert plant.GetBodyByName(name).default_mass() == 0


def test_qbot_layout_as_in_robots_md():
    plant, sg, _ = load("qbot")
    context = plant.CreateDefaultContext()
    base = plant.GetFrameByName("base_link")
    for name, (x, y) in zip(QBOT_WHEELS, [(0.25, 0.18), (0.25, -0.18), (-0.25, 0.18), (-0.25, -0.18)]):
        X = plant.CalcRelativeTransform(context, base, plant.GetFrameByName(f"{name}_wheel_link"))
        assert X.translation() == pytest.approx([x, y, 0], abs=1e-12)
        assert plant.GetJointByName(name).revolute_axis() == pytest.approx([0, 1, 0])
    laser = plant.CalcRelativeTransform(context, base, plant.GetFrameByName("base_laser"))
    assert laser.translation() == pytest.approx([0, 0, 0.08], abs=1e-12)
    chassis = plant.GetBodyByName("base_link").default_rotational_inertia().CopyToFullMatrix3()
    assert np.diag(chassis) == pytest.approx(box_inertia(5.0, 0.5, 0.3, 0.05), abs=1e-9)
    wheel = plant.GetBodyByName("left_front_wheel_link").default_rotational_inertia().CopyToFullMatrix3()
    assert np.diag(wheel) == pytest.approx(cylinder_inertia_about_y(0.2, 0.055, 0.0375), abs=1e-12)


def test_default_world_is_static_with_obstacles_clear_of_the_3m_circle():
    plant, sg, instances = load("default_world")
    assert plant.num_positions() == 0 and plant.num_velocities() == 0  # everything welded
    names = {plant.GetModelInstanceName(i) for i in instances["default_world"]}
    assert names == {"floor", "box_1", "box_2", "box_3", "cylinder_1", "cylinder_2"}
    # SDFormat gives an <inertial>-less link 1 kg; they are welded, so it never matters.
    assert plant.CalcTotalMass(plant.CreateDefaultContext(), instances["default_world"]) == pytest.approx(6.0)
    inspector = sg.model_inspector()
    context = plant.CreateDefaultContext()
    shapes = {"box": 0, "cylinder": 0}
    for gid in inspector.GetAllGeometryIds(Role.kProximity):
        X_WG = plant.EvalBodyPoseInWorld(
            context, plant.GetBodyFromFrameId(inspector.GetFrameId(gid))
        ) @ inspector.GetPoseInFrame(gid)
        shape = inspector.GetShape(gid)
        props = inspector.GetProximityProperties(gid)
        mu = props.GetProperty("material", "coulomb_friction").static_friction()
        if inspector.GetName(gid) == "floor::collision":
            assert isinstance(shape, Box) and X_WG.translation()[2] + shape.height() / 2 == pytest.approx(0.0)
            assert mu == 1.0
            continue
        if isinstance(shape, Box):
            shapes["box"] += 1
            half = np.array([shape.width(), shape.depth(), 0]) / 2
            # distance from the origin to the rotated rectangle, in the box's own frame
            p = X_WG.inverse() @ np.zeros(3)
            nearest = np.hypot(max(abs(p[0]) - half[0], 0), max(abs(p[1]) - half[1], 0))
            bottom = X_WG.translation()[2] - shape.height() / 2
        else:
            assert isinstance(shape, Cylinder)
            shapes["cylinder"] += 1
            nearest = np.hypot(*X_WG.translation()[:2]) - shape.radius()
            bottom = X_WG.translation()[2] - shape.length() / 2
        assert nearest > 3.0, inspector.GetName(gid)  # also clears (0,0)->(2,1) and (0,0)->(-1,0)
        assert bottom == pytest.approx(0.0, abs=1e-12)  # standing on the floor
    assert shapes == {"box": 3, "cylinder": 2}


# ---- the loader ---------------------------------------------------------------------------------
def test_missing_file_raises_model_error_naming_the_file_and_the_known_models(tmp_path):
    plant = MultibodyPlant(0.0)
    with pytest.raises(ModelError, match=r"model file not found: .*nope\.urdf; known models: twil, wam"):
        add_model(plant, tmp_path / "nope.urdf")
    with pytest.raises(ModelError, match="not found"):
        add_model(plant, "package://drake_models/iiwa_description/urdf/iiwa14.urdf")
    assert isinstance(ModelError("x"), ValueError)


def test_unparsable_file_raises_model_error_naming_the_file(tmp_path):
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot name='bad'><link name='a'><inertial><mass value='-1'/></inertial></link>")
    with pytest.raises(ModelError, match=r"failed to parse model file .*bad\.urdf"):
        add_model(MultibodyPlant(0.0), bad)
    bad_directives = tmp_path / "bad.dmd.yaml"
    bad_directives.write_text(
        "directives:\n- add_model:\n    name: x\n    file: package://twil_control/sim/nothing.urdf\n"
    )
    with pytest.raises(ModelError, match=r"bad\.dmd\.yaml"):
        add_model(MultibodyPlant(0.0), bad_directives)


def test_package_urls_prefixes_and_registration():
    plant = MultibodyPlant(0.0)
    parser = Parser(plant)
    models.register_package(parser)
    models.register_package(parser)  # idempotent
    assert parser.package_map().GetPath("twil_control") == str(PACKAGE_ROOT)
    (first,) = add_model(plant, "package://twil_control/sim/robots/qbot/qbot.urdf", parser=parser)
    (second,) = add_model(plant, "qbot", model_name_prefix="qbot2")
    assert plant.GetModelInstanceName(first) == "qbot"
    assert plant.GetModelInstanceName(second) == "qbot2::qbot"
    assert models.rest_height(plant, second) == 0.055


# ---- dynamics on the floor ----------------------------------------------------------------------
@pytest.mark.parametrize("robot, lock", [("twil", None), ("qbot", None), ("twil_wam", WAM_HOME)])
def test_robot_rests_on_its_wheels_and_castor(robot, lock):
    """Spawned at models.REST_HEIGHT with zero torque: z stays within 1.5 mm for 0.5 s, the base
    creeps under 1 mm, and only wheels and the front castor touch the floor."""
    wheels = QBOT_WHEELS if robot == "qbot" else TWIL_WHEELS
    run = Run(robot, 0.0, wheels, approximation="sap", lock_arm_at=lock)
    z0 = run.pose().translation()[2]
    zs = [run.pose().translation()[2] for _ in run.samples(0.5, every=0.02)]
    assert max(abs(z - z0) for z in zs) < 1.5e-3
    assert np.hypot(*(run.pose().translation()[:2])) < 1e-3
    inspector = run.scene_graph.model_inspector()
    contacts = run.plant.get_contact_results_output_port().Eval(run.context)
    touching = set()
    for k in range(contacts.num_point_pair_contacts()):
        pair = contacts.point_pair_contact_info(k).point_pair()
        touching |= {inspector.GetName(pair.id_A), inspector.GetName(pair.id_B)}
    touching.discard("floor::collision")
    model = "qbot" if robot == "qbot" else "twil"
    expected = {f"{model}::{w.replace('_joint', '')}" + ("_wheel" if robot == "qbot" else "") for w in wheels}
    if robot != "qbot":
        expected.add("twil::castor")
    assert touching == expected


@pytest.mark.parametrize("approximation", ["lagged", "sap"])
@pytest.mark.parametrize("x, y, yaw", [(0.0, 0.0, 0.0), (0.5, -0.5, math.radians(30))])
def test_twil_drives_straight_under_equal_wheel_torques(approximation, x, y, yaw):
    """2 N m on both wheels for 2 s: forward along the heading by the rigid-body distance
    (a = 2 tau / (r m_eff), m_eff = m + 2 I_axle / r^2) within 2 %, lateral drift under 1 % of
    the distance, yaw change under 0.5 deg."""
    tau = 2.0
    run = Run("twil", tau, TWIL_WHEELS, approximation=approximation, x=x, y=y, yaw=yaw)
    for _ in run.samples(2.0, every=0.5):
        pass
    forward, lateral, dyaw = run.planar_motion()
    m_eff = TWIL_MASS + 2 * 0.0028125 / WHEEL_RADIUS**2
    expected = 0.5 * (2 * tau / WHEEL_RADIUS / m_eff) * 2.0**2  # 2.09 m
    assert forward == pytest.approx(expected, rel=0.02)
    assert abs(lateral) < 0.01 * forward
    assert abs(math.degrees(dyaw)) < 0.5


@pytest.mark.parametrize("robot, lock", [("twil", None), ("twil_wam", WAM_HOME)])
def test_saturated_wheel_torque_is_clamped_and_does_not_spin_the_wheels(robot, lock):
    """100 N m requested: Drake clamps to the 6 N m effort limit; the platform rocks onto its
    anti-tip ball (pitch under 1 deg) but the wheels keep their grip (slip under 0.1 m/s)."""
    run = Run(robot, 100.0, TWIL_WHEELS, approximation="sap", lock_arm_at=lock)
    worst_slip = worst_pitch = 0.0
    for _ in run.samples(1.0, every=0.005):
        worst_slip = max(worst_slip, run.slip())
        worst_pitch = max(worst_pitch, abs(RollPitchYaw(run.pose().rotation()).pitch_angle()))
    applied = run.plant.get_net_actuation_output_port().Eval(run.context)
    for name in TWIL_WHEELS:
        assert applied[run.plant.GetJointActuatorByName(name).input_start()] == TWIL_WHEEL_EFFORT_LIMIT
    assert worst_slip < 0.1
    assert math.degrees(worst_pitch) < 1.0
    forward, lateral, _ = run.planar_motion()
    m = TWIL_MASS + (WAM_MASS if lock else 0.0) + 2 * 0.0028125 / WHEEL_RADIUS**2
    assert forward == pytest.approx(0.5 * 2 * TWIL_WHEEL_EFFORT_LIMIT / WHEEL_RADIUS / m, rel=0.03)


def test_qbot_drives_straight_under_equal_wheel_torques():
    """0.1 N m on all four wheels for 2 s: forward by the rigid-body distance within 2 %,
    lateral drift under 1 %, yaw under 0.5 deg."""
    tau = 0.1
    run = Run("qbot", tau, QBOT_WHEELS)
    for _ in run.samples(2.0, every=0.5):
        pass
    forward, lateral, dyaw = run.planar_motion()
    m_eff = QBOT_MASS + 4 * 0.0003025 / 0.055**2
    assert forward == pytest.approx(0.5 * (4 * tau / 0.055 / m_eff) * 2.0**2, rel=0.02)
    assert abs(lateral) < 0.01 * forward
    assert abs(math.degrees(dyaw)) < 0.5
