"""move_base with twil_control/BacksteppingLocalPlanner (the TWIL platform): the waypoint
follower's choices (pure), its parameters, move_base on the bus driving a kinematic platform
under the paper's kinematic law (no Drake), and (slow) TWIL + WAM in Drake through
launch/twil_navigation.launch.yaml."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml
from support.nav_fakes import occupancy_grid

from twil_control import PACKAGE_ROOT
from twil_control.control.gains import validate_gains
from twil_control.control.kinematic_law import eta
from twil_control.control.polar import error_coordinates
from twil_control.control.transforms import quat_from_yaw, yaw_from_quat
from twil_control.core.messages import header, msg_class
from twil_control.core.node import Master, Node
from twil_control.core.tf import StaticTfBroadcaster, TfBroadcaster, transform_stamped
from twil_control.navigation import costmap as cm
from twil_control.navigation.backstepping_planner import (
    BacksteppingPlannerError,
    BacksteppingPlannerParams,
    WaypointFollower,
    segment_free,
)
from twil_control.navigation.collision import GridChecker
from twil_control.navigation.footprint import FootprintCells, parse_footprint
from twil_control.nodes.move_base import SUCCEEDED, MoveBase

RES = 0.05
CONTROLLER = "/twil/ros_control/cart_linearizing_controller"
ARM = [f"wam_joint_{i}" for i in range(1, 8)]
ARM_POSE = [0.0, -1.2, 0.1, 2.5, 0.0, 0.3, 0.0]
TWIL_COMMON = yaml.safe_load((PACKAGE_ROOT / "config/twil_costmap_common_params.yaml").read_text())


def _open(width=120, height=80) -> cm.Costmap:
    m = cm.Costmap(width, height, RES, 0.0, 0.0)
    m.costs = np.zeros((height, width), np.uint8)
    return m


def _straight(x0=0.5, x1=5.0, y=2.0, yaw=0.0) -> np.ndarray:
    x = np.arange(x0, x1 + 1e-9, RES)
    return np.column_stack([x, np.full(len(x), y), np.full(len(x), yaw)])


# -- the waypoint follower (pure) ------------------------------------------------------------------
def test_the_waypoint_is_lookahead_away_on_the_path_headed_against_it():
    f = WaypointFollower(BacksteppingPlannerParams(lookahead=0.6))
    ref = f.compute(_open(), (0.5, 2.0, math.pi), _straight())
    x, y, yaw = ref.pose
    assert math.hypot(x - 0.5, y - 2.0) == pytest.approx(0.6, abs=0.03)  # one resampling step
    assert y == pytest.approx(2.0, abs=1e-9)
    assert abs(math.remainder(yaw - math.pi, 2 * math.pi)) < 1e-9  # backwards: path + pi
    assert not ref.goal_reached and not ref.final
    forwards = WaypointFollower(BacksteppingPlannerParams(lookahead=0.6, backwards=False))
    assert forwards.compute(_open(), (0.5, 2.0, 0.0), _straight()).pose[2] == pytest.approx(0.0, abs=1e-9)


def test_near_the_goal_the_reference_is_the_goal_pose_and_within_tolerance_it_is_reached():
    f = WaypointFollower(
        BacksteppingPlannerParams(lookahead=0.6, xy_goal_tolerance=0.1, yaw_goal_tolerance=0.1)
    )
    plan = _straight(yaw=0.0)
    plan[-1, 2] = 2.0
    ref = f.compute(_open(), (4.6, 2.0, math.pi), plan)
    assert ref.final and ref.pose == pytest.approx((5.0, 2.0, 2.0))
    assert f.compute(_open(), (4.95, 2.02, 2.05), plan).goal_reached
    assert not f.compute(_open(), (4.95, 2.02, 2.2), plan).goal_reached  # yaw 0.2 off


def test_the_xy_tolerance_latches_only_when_asked():
    plan = _straight()
    for latch, expected in ((True, True), (False, False)):
        f = WaypointFollower(
            BacksteppingPlannerParams(
                xy_goal_tolerance=0.1, yaw_goal_tolerance=0.1, latch_xy_goal_tolerance=latch
            )
        )
        f.goal_reached((4.95, 2.0, 1.0), plan[-1])  # inside xy, yaw off
        assert f.goal_reached((4.8, 2.0, 0.0), plan[-1]) is expected  # 0.2 m off, yaw right


def test_the_waypoint_moves_back_along_the_plan_when_the_chord_would_cut_an_obstacle():
    m = _open()
    # an L-shaped plan round a block; the block's inscribed zone covers the corner's chord
    leg1 = np.column_stack([np.full(21, 1.0), np.linspace(1.0, 2.0, 21), np.full(21, math.pi / 2)])
    leg2 = np.column_stack([np.linspace(1.0, 2.0, 21), np.full(21, 2.0), np.zeros(21)])
    plan = np.vstack([leg1, leg2[1:]])
    m.costs[22:38, 22:36] = cm.INSCRIBED  # x 1.1..1.8, y 1.1..1.9: inside the corner
    m.costs[28:32, 28:32] = cm.LETHAL
    f = WaypointFollower(BacksteppingPlannerParams(lookahead=1.2, min_lookahead=0.15))
    ref = f.compute(m, (1.0, 1.0, -math.pi / 2), plan)
    assert segment_free(m, (1.0, 1.0), ref.pose[:2])
    # moved back from the 1.2 m crossing (1.66, 2.0) to about the corner: the chord passes x < 1.1
    assert ref.pose[0] < 1.1 + 0.05 and ref.pose[1] == pytest.approx(2.0, abs=0.03)
    assert 0.15 <= math.hypot(ref.pose[0] - 1.0, ref.pose[1] - 1.0) < 1.2
    # blocked everywhere beyond min_lookahead: no valid reference
    m.costs[:, 21:] = cm.LETHAL
    m.costs[21:, :] = cm.LETHAL
    assert f.compute(m, (1.0, 1.0, -math.pi / 2), plan).pose is None


def test_segments_may_leave_the_inscribed_zone_but_never_cross_lethal_cells():
    m = _open()
    m.costs[38:43, :] = cm.INSCRIBED  # a band y 1.9..2.15 the robot stands in
    assert segment_free(m, (1.0, 2.0), (1.0, 3.0))  # leaving it
    assert not segment_free(m, (1.0, 1.0), (1.0, 3.0))  # crossing it
    m.costs[45, 50] = cm.LETHAL
    assert not segment_free(m, (2.5, 1.5), (2.5, 3.0))
    assert not segment_free(m, (1.0, 1.0), (9.0, 1.0))  # leaves the costmap


@pytest.mark.parametrize(
    "key, value, words",
    [
        ("lookahead", 0.0, "lookahead must be a finite number > 0"),
        ("min_lookahead", math.nan, "min_lookahead must be a finite number > 0"),
        ("min_lookahead", 1.0, "min_lookahead (1.0) must be <= lookahead (0.6)"),
    ],
)
def test_bad_follower_parameters_are_refused_naming_them(key, value, words):
    with pytest.raises(BacksteppingPlannerError, match=words.replace("(", r"\(").replace(")", r"\)")):
        BacksteppingPlannerParams(**{key: value})


# -- move_base on the bus with a kinematic TWIL --------------------------------------------------------
class KinematicTwil(Node):
    """The platform under the paper's kinematic law: u = eta(e, psi, alpha) (27)-(28) towards the
    reference of the last CartLinearizingCommand (what the backstepping law makes u track), at
    `rate` Hz; odom -> base_link and map -> odom (identity) on /tf, the arm on /joint_states.
    Records the commands and the poses it passed through."""

    def __init__(self, master: Master, pose, rate: float = 100.0) -> None:
        super().__init__(master, "fake_twil")
        cfg = yaml.safe_load((PACKAGE_ROOT / "config/cart_linearizing_controller.yaml").read_text())
        self.gains = validate_gains(cfg["cart_linearizing_controller"]["gains"])
        self.pose = np.array(pose, float)
        self.start = self.pose.copy()
        self.reference = None
        self.commands = []
        self.poses = [self.pose.copy()]
        self._tf = TfBroadcaster(self)
        StaticTfBroadcaster(self).send(
            transform_stamped(
                "map", "odom", 0.0, tuple(self.start[:2]) + (0.0,), quat_from_yaw(self.start[2])
            )
        )
        self._joints = self.create_publisher("/joint_states", "sensor_msgs/JointState")
        self.create_subscription(f"{CONTROLLER}/command", "twil_control/CartLinearizingCommand", self._on_cmd)
        self._dt = 1.0 / rate
        self._publish()
        self.create_timer(self._dt, self._step)

    def odom_pose(self):
        """The pose in odom (the controller's odometry frame: where it started)."""
        c, s = math.cos(self.start[2]), math.sin(self.start[2])
        dx, dy = self.pose[0] - self.start[0], self.pose[1] - self.start[1]
        return c * dx + s * dy, -s * dx + c * dy, self.pose[2] - self.start[2]

    def _on_cmd(self, msg) -> None:
        p = msg.platform_pose
        self.reference = (p.x, p.y, p.theta)
        self.commands.append((self.now(), msg.header.frame_id, self.reference, list(msg.arm_positions)))

    def _step(self, event) -> None:
        if self.reference is not None:
            e, psi, alpha = error_coordinates(*self.odom_pose(), *self.reference)
            u1, u2 = eta(e, psi, alpha, validate_gains(self.gains).vector) if e > 1e-3 else (0.0, 0.0)
            x, y, th = self.pose
            self.pose = np.array(
                [x + u1 * math.cos(th) * self._dt, y + u1 * math.sin(th) * self._dt, th + u2 * self._dt]
            )
            self.poses.append(self.pose.copy())
        self._publish()

    def _publish(self) -> None:
        x, y, th = self.odom_pose()
        self._tf.send(transform_stamped("odom", "base_link", self.now(), (x, y, 0.0), quat_from_yaw(th)))
        self._joints.publish(
            msg_class("sensor_msgs/JointState")(
                header=header("", self.now()),
                name=ARM + ["left_wheel_joint"],
                position=np.array(ARM_POSE + [0.0]),
                velocity=np.zeros(8),
                effort=np.zeros(8),
            )
        )


def _room() -> np.ndarray:
    """A 6 m x 4 m room with walls and a 0.5 m pillar at (3, 1)."""
    g = np.zeros((80, 120), np.int8)
    g[:2, :] = g[-2:, :] = 100
    g[:, :2] = g[:, -2:] = 100
    g[15:25, 55:65] = 100
    return g


def _twil_move_base(master: Master, **overrides) -> None:
    cfg, server = PACKAGE_ROOT / "config", master.params
    for ns in ("/move_base/global_costmap", "/move_base/local_costmap"):
        server.load_file(cfg / "twil_costmap_common_params.yaml", ns)
    for f in ("global_costmap_params.yaml", "local_costmap_params.yaml", "twil_move_base_params.yaml"):
        server.load_file(cfg / f, "/move_base")
    server.set("/move_base/local_costmap/static_map", True)
    server.load_file(cfg / "cart_linearizing_controller.yaml", "/twil/ros_control")
    for key, value in overrides.items():
        server.set(f"/move_base/{key}", value)


def _send(pub, master, x, y, yaw):
    q = quat_from_yaw(yaw)
    pub.publish(
        msg_class("geometry_msgs/PoseStamped")(
            header=header("map", master.clock.now()),
            pose=msg_class("geometry_msgs/Pose")(
                position=msg_class("geometry_msgs/Point")(x=x, y=y, z=0.0),
                orientation=msg_class("geometry_msgs/Quaternion")(x=q[0], y=q[1], z=q[2], w=q[3]),
            ),
        )
    )


def test_move_base_drives_the_platform_round_a_pillar_by_pose_references_without_touching_it():
    master = Master()
    _twil_move_base(master)
    test = Node(master, "test")
    test.create_publisher("/map", "nav_msgs/OccupancyGrid", latch=True).publish(occupancy_grid(_room(), RES))
    twil = KinematicTwil(master, (1.5, 1.0, math.pi))
    MoveBase(master, "move_base")
    results = []
    test.create_subscription(
        "/move_base/result",
        "twil_control/MoveBaseActionResult",
        lambda m: results.append((master.clock.now(), m.status)),
    )
    goal_pub = test.create_publisher("/move_base_simple/goal", "geometry_msgs/PoseStamped")
    master.spin_until(0.5)
    _send(goal_pub, master, 4.5, 1.0, math.pi)
    master.spin_until(60.0)

    assert [r[1].status for r in results] == [SUCCEEDED]
    x, y, yaw = twil.pose
    assert math.hypot(x - 4.5, y - 1.0) <= 0.1 + 0.01  # xy_goal_tolerance (+ one 100 Hz step)
    assert abs(math.remainder(yaw - math.pi, 2 * math.pi)) <= 0.1 + 0.01
    # every command: in odom, the arm held where /joint_states had it
    assert {c[1] for c in twil.commands} == {"odom"}
    assert all(c[3] == pytest.approx(ARM_POSE) for c in twil.commands)
    # after the result the reference holds the pose it stopped at: the platform stays put
    stop = max(i for i, c in enumerate(twil.commands) if c[0] <= results[0][0])
    assert twil.commands[stop][2] == pytest.approx(twil.odom_pose(), abs=0.02)
    # it went round the pillar (x 2.75..3.25, y 0.75..1.25) and no footprint ever met a wall or it
    poses = np.array(twil.poses)
    assert poses[:, 0].max() > 4.0 and poses[:, 1].max() > 1.25 + 0.25
    m = cm.Costmap(120, 80, RES, 0.0, 0.0)
    m.costs = np.where(_room() == 100, cm.LETHAL, cm.FREE).astype(np.uint8)
    checker = GridChecker(m, FootprintCells(parse_footprint(TWIL_COMMON["footprint"]), RES))
    assert all(checker.pose_free(*p) for p in poses[::5])
    # the path is not much longer than the way round the pillar (4.2 m with the inflation's detour)
    assert np.sum(np.hypot(*np.diff(poses[:, :2], axis=0).T)) < 5.5


def test_rotate_recovery_is_refused_with_the_backstepping_planner():
    master = Master()
    _twil_move_base(master, clearing_rotation_allowed=True)
    Node(master, "x")
    with pytest.raises(ValueError, match="clearing_rotation_allowed must be false"):
        MoveBase(master, "move_base")


def test_a_missing_arm_joints_parameter_is_an_error_naming_it():
    master = Master()
    _twil_move_base(master, **{"BacksteppingLocalPlanner/controller": "/nowhere/cart"})
    with pytest.raises(ValueError, match="/nowhere/cart/arm_joints"):
        MoveBase(master, "move_base")


# -- TWIL + WAM in Drake -------------------------------------------------------------------------------
@pytest.mark.slow
def test_twil_reaches_a_goal_behind_a_cylinder_through_move_base_in_drake(tmp_path):
    from twil_control.bag.reader import Bag
    from twil_control.launch.loader import load_launch
    from twil_control.launch.runner import RunOptions, run
    from twil_control.tools import rasterize

    world = PACKAGE_ROOT / "sim/worlds/default.sdf"
    assert (
        rasterize.main(
            [
                str(world),
                "-o",
                str(tmp_path / "default"),
                "--height",
                "0.2",
                "--origin",
                "-10",
                "-10",
                "--size",
                "20",
                "20",
            ]
        )
        == 0
    )
    # cylinder_2 (r 0.4 at (2.5, 3.5)) stands on the straight line from the spawn to the goal
    goal = (3.7, 3.5, math.pi)
    plan = load_launch(
        PACKAGE_ROOT / "launch/twil_navigation.launch.yaml",
        {
            "map": str(tmp_path / "default.yaml"),
            "x": "1.3",
            "y": "3.5",
            "yaw": str(math.pi),
            "goal": " ".join(map(str, goal)),
        },
    )
    bag = tmp_path / "nav.bag"
    result = run(plan, RunOptions(duration=40.0, bag=bag, seed=1))
    assert result.error is None
    b = Bag(bag)
    results = [m.status for _, m in b.messages("/move_base/result")]
    assert [r.status for r in results] == [SUCCEEDED]
    assert result.sim_time < 40.0  # the run ended with the goal's result
    truth = np.array(
        [
            (
                m.pose.pose.position.x,
                m.pose.pose.position.y,
                yaw_from_quat(
                    (
                        m.pose.pose.orientation.x,
                        m.pose.pose.orientation.y,
                        m.pose.pose.orientation.z,
                        m.pose.pose.orientation.w,
                    )
                ),
            )
            for _, m in b.messages("/twil/ground_truth/odom")
        ]
    )
    # the final true pose within move_base's tolerances (0.1 m, 0.1 rad; + 0.01 for the 10 ms
    # between the ground truth's samples and the tf move_base decided on)
    x, y, yaw = truth[-1]
    assert math.hypot(x - goal[0], y - goal[1]) <= 0.11
    assert abs(math.remainder(yaw - goal[2], 2 * math.pi)) <= 0.11
    # round the cylinder, never touching it or anything else but the floor (the contact monitor's
    # messages are all empty), the axle midpoint at least the inscribed radius from its surface
    assert np.abs(truth[:, 1] - 3.5).max() > 0.4 + 0.26
    assert (np.hypot(truth[:, 0] - 2.5, truth[:, 1] - 3.5) - 0.4).min() > 0.26
    collisions = [m.data for _, m in b.messages("/twil/contact_monitor/collisions")]
    assert collisions and all(c == "" for c in collisions)
    # the arm held where it started while the platform drove
    cmds = [np.array(m.arm_positions) for _, m in b.messages(f"{CONTROLLER}/command")]
    assert cmds and np.abs(np.array(cmds) - cmds[0]).max() == 0.0
    names = None
    arm_end = None
    for _, m in b.messages("/joint_states"):
        names = list(m.name)
        arm_end = np.array([m.position[names.index(j)] for j in ARM])
    assert np.abs(arm_end - cmds[0]).max() < 0.01
