"""The goal panel without a browser: the form's rules, the HTTP API, and what the view node does
with a queued action (a goal on /move_base_simple/goal, a cancel, a controller switch)."""

from __future__ import annotations

import json
import math
import re
import urllib.error
import urllib.request

import numpy as np
import pytest

from twil_control.core.node import Master, Node
from twil_control.view.panel import PanelInputError, parse_enable, parse_field, parse_goal_form
from twil_control.view.panel_server import PanelServer

pytestmark = pytest.mark.usefixtures("meshcat_freed_here")  # conftest: Meshcat is thread-bound


# -- the form's rules --------------------------------------------------------------------------
@pytest.mark.parametrize(
    "key,raw,value",
    [
        ("x", "20", 20.0),
        ("x", "-20", -20.0),
        ("y", " 1.5 ", 1.5),
        ("ori", "-3.14", -3.14),
        ("ori", 3.14, 3.14),
        ("y", 0, 0.0),
    ],
)
def test_values_inside_the_spin_box_ranges_are_accepted(key, raw, value):
    assert parse_field(key, raw) == value


@pytest.mark.parametrize(
    "key,raw,message",
    [
        ("x", "20.01", "X = 20.01 m is out of range: allowed [-20, 20] m"),
        ("y", -25, "Y = -25 m is out of range: allowed [-20, 20] m"),
        ("ori", "3.15", "Ori = 3.15 rad is out of range: allowed [-3.14, 3.14] rad"),
        ("x", "", "X is empty"),
        ("x", "one", "X must be a number in [-20, 20] m (got 'one')"),
        ("y", "nan", "Y must be a finite number"),
        ("ori", "inf", "Ori must be a finite number"),
        ("x", True, "X must be a number"),
        ("x", None, "X must be a number"),
    ],
)
def test_values_outside_are_refused_saying_why(key, raw, message):
    with pytest.raises(PanelInputError, match="^" + re.escape(message)):
        parse_field(key, raw)


def test_a_form_reports_every_bad_field_at_once():
    with pytest.raises(PanelInputError) as info:
        parse_goal_form({"x": "21", "ori": "9", "z": 1})
    text = str(info.value)
    for part in (
        "unknown field(s) z",
        "X = 21 m is out of range",
        "Y is missing",
        "Ori = 9 rad is out of range",
    ):
        assert part in text
    assert parse_goal_form({"x": "1", "y": "-2", "ori": "0.5"}).ori == 0.5


def test_the_controller_switch_takes_a_boolean():
    assert parse_enable({"enable": False}) is False
    for bad in ({"enable": "no"}, {}, {"enable": True, "x": 1}, [True]):
        with pytest.raises(PanelInputError, match='"enable": true'):
            parse_enable(bad)


# -- the HTTP API --------------------------------------------------------------------------------
@pytest.fixture
def server():
    s = PanelServer("http://127.0.0.1:7000", "127.0.0.1", 0)
    yield s
    s.close()


def _post(server: PanelServer, path: str, body) -> tuple[int, dict]:
    data = body if isinstance(body, bytes) else json.dumps(body).encode()
    req = urllib.request.Request(
        server.base_url + path,
        data=data,
        method="POST",
        headers={"Content-Type": "application/json", "Authorization": f"token {server.token}"},
    )
    try:
        with urllib.request.urlopen(req, timeout=5) as r:
            return r.status, json.loads(r.read())
    except urllib.error.HTTPError as e:
        return e.code, json.loads(e.read())


def test_server_binds_to_localhost_and_serves_the_page_with_the_meshcat_frame(server):
    assert server.url.startswith("http://127.0.0.1:") and server.url.endswith(f"/?token={server.token}")
    browser = urllib.request.build_opener(urllib.request.HTTPCookieProcessor())
    with browser.open(server.url, timeout=5) as r:  # redirected to /, the token kept as a cookie
        page = r.read().decode()
    assert '<iframe id="meshcat" src="http://localhost:7000"' in page  # another site: its own process
    for element in (
        'id="x"',
        'id="y"',
        'id="ori"',
        'id="start"',
        'id="cancel"',
        'id="initialpose"',
        'id="controller"',
        'id="status"',
    ):
        assert element in page


def test_valid_posts_are_queued_in_order_and_bad_ones_refused_with_the_reason(server):
    assert _post(server, "api/goal", {"x": "1", "y": "2", "ori": "-1.5"}) == (202, {"queued": 1})
    code, body = _post(server, "api/goal", {"x": "1", "y": "22", "ori": "0"})
    assert code == 400 and body["error"] == "Y = 22 m is out of range: allowed [-20, 20] m"
    assert _post(server, "api/cancel", {}) == (202, {"queued": 2})
    assert _post(server, "api/controller", {"enable": False}) == (202, {"queued": 3})
    assert _post(server, "api/initialpose", {"x": "0.5", "y": "-1", "ori": "3"}) == (202, {"queued": 4})
    code, body = _post(server, "api/initialpose", {"x": "0.5", "y": "-1", "ori": "4"})
    assert code == 400 and body["error"] == "Ori = 4 rad is out of range: allowed [-3.14, 3.14] rad"
    code, body = _post(server, "api/goal", b"{not json")
    assert code == 400 and "not JSON" in body["error"]
    code, body = _post(server, "api/teleport", {})
    assert code == 404 and "/api/goal" in body["error"]
    actions = server.pending()
    assert [(a.id, a.kind) for a in actions] == [
        (1, "goal"),
        (2, "cancel"),
        (3, "controller"),
        (4, "initialpose"),
    ]
    assert (actions[3].payload.x, actions[3].payload.y, actions[3].payload.ori) == (0.5, -1.0, 3.0)
    assert (actions[0].payload.x, actions[0].payload.y, actions[0].payload.ori) == (1.0, 2.0, -1.5)
    assert actions[2].payload is False
    assert server.pending() == []


def test_state_is_the_last_snapshot_published(server):
    server.set_state({"time": 2.5, "status": {"name": "ACTIVE"}, "controllers": [], "last_action": None})
    req = urllib.request.Request(
        server.base_url + "api/state", headers={"Authorization": f"token {server.token}"}
    )
    with urllib.request.urlopen(req, timeout=5) as r:
        assert json.loads(r.read())["status"]["name"] == "ACTIVE"


# -- actions applied by the view node -------------------------------------------------------------
class FakeManager:
    """A controller manager's two services, as master.call_service sees them."""

    def __init__(self, master: Master) -> None:
        self.states = {"joint_state_controller": "running", "drive": "running"}
        self.last_error = ""
        master.advertise_service("/bot/controller_manager/list_controllers", "/bot/cm", self.list_controllers)
        master.advertise_service(
            "/bot/controller_manager/switch_controller", "/bot/cm", self.switch_controller
        )
        self.calls = []

    def list_controllers(self):
        from twil_control.ros_control.srv import ControllerState, ListControllersResponse

        types = {"joint_state_controller": "joint_state_controller/JointStateController", "drive": "x/Drive"}
        return ListControllersResponse([ControllerState(n, s, types[n]) for n, s in self.states.items()])

    def switch_controller(self, start, stop, strictness):
        from twil_control.ros_control.srv import SwitchControllerResponse

        self.calls.append((list(start), list(stop), strictness))
        for n in stop:
            self.states[n] = "stopped"
        for n in start:
            self.states[n] = "running"
        return SwitchControllerResponse(True)


def test_view_applies_goal_cancel_and_controller_switch():
    from twil_control.ros_control.srv import STRICT
    from twil_control.view.panel import GoalForm
    from twil_control.view.panel_server import Action
    from twil_control.view.view_node import ViewNode, ViewOptions

    master = Master()
    move_base = Node(master, "move_base")
    goals, cancels = [], []
    move_base.create_subscription("/move_base_simple/goal", "geometry_msgs/PoseStamped", goals.append)
    move_base.create_subscription("/move_base/cancel", "actionlib_msgs/GoalID", cancels.append)
    manager = FakeManager(master)
    view = ViewNode(master, options=ViewOptions(serve=False))
    try:
        view.on_start()
        ok, text = view._apply(Action(1, "goal", GoalForm(1.5, -2.0, 1.2)))
        assert ok and "sent on /move_base_simple/goal in frame map" in text
        (g,) = goals
        assert g.header.frame_id == "map"
        assert (g.pose.position.x, g.pose.position.y) == (1.5, -2.0)
        q = g.pose.orientation
        assert 2 * math.atan2(q.z, q.w) == pytest.approx(1.2, abs=1e-12) and q.x == q.y == 0.0
        assert view._apply(Action(2, "cancel", None))[0] and cancels[0].id == ""
        assert view._list_controllers() == [
            {"name": "drive", "state": "running", "type": "x/Drive", "manager": "/bot/controller_manager"}
        ]
        assert view._apply(Action(3, "controller", False)) == (True, "stopped drive")
        assert manager.calls == [([], ["drive"], STRICT)]
        assert manager.states == {"joint_state_controller": "running", "drive": "stopped"}
        assert view._apply(Action(4, "controller", False)) == (True, "controllers already stopped")
        assert view._apply(Action(5, "controller", True)) == (True, "started drive")
    finally:
        view.shutdown()


def test_the_panel_sets_a_localiser_s_pose_as_rviz_s_2d_pose_estimate():
    from twil_control.view.panel import GoalForm
    from twil_control.view.panel_server import Action
    from twil_control.view.view_node import ViewNode, ViewOptions

    master = Master()
    amcl = Node(master, "amcl")
    poses = []
    amcl.create_subscription("/initialpose", "geometry_msgs/PoseWithCovarianceStamped", poses.append)
    view = ViewNode(master, options=ViewOptions(serve=False))
    try:
        view.on_start()
        ok, text = view._apply(Action(1, "initialpose", GoalForm(1.5, -2.0, 0.7)))
        assert ok and text == "initial pose (1.5, -2, 0.7) sent on /initialpose in frame map"
        (p,) = poses
        assert p.header.frame_id == "map" and (p.pose.pose.position.x, p.pose.pose.position.y) == (1.5, -2.0)
        q = p.pose.pose.orientation
        assert 2 * math.atan2(q.z, q.w) == pytest.approx(0.7, abs=1e-12)
        cov = np.asarray(p.pose.covariance)
        assert (cov[0], cov[7], cov[35]) == (0.25, 0.25, pytest.approx((math.pi / 12) ** 2))
        assert np.count_nonzero(cov) == 3
    finally:
        view.shutdown()
    lonely = ViewNode(Master(), options=ViewOptions(serve=False))
    try:
        lonely.on_start()
        ok, text = lonely._apply(Action(1, "initialpose", GoalForm(0, 0, 0)))
        assert not ok and "nothing listens on /initialpose" in text
    finally:
        lonely.shutdown()


def test_without_move_base_or_cart_controller_a_goal_is_refused_saying_why():
    from twil_control.view.panel import GoalForm
    from twil_control.view.panel_server import Action
    from twil_control.view.view_node import ViewNode, ViewOptions

    view = ViewNode(Master(), options=ViewOptions(serve=False))
    try:
        view.on_start()
        ok, text = view._apply(Action(1, "goal", GoalForm(0, 0, 0)))
        assert not ok and "neither move_base nor a cart controller" in text
        ok, text = view._apply(Action(2, "controller", True))
        assert not ok and "no controller manager" in text
    finally:
        view.shutdown()


def test_cart_reference_from_the_panel_keeps_the_arm_where_the_last_command_or_joint_states_put_it():
    """TWIL without a reference program (program:=false): the panel's pose goes to the cart
    controller with the arm held where /joint_states has it; after a command, with its arm."""
    from twil_control.core.messages import header, msg_class
    from twil_control.view.panel import GoalForm
    from twil_control.view.panel_server import Action
    from twil_control.view.view_node import ViewNode, ViewOptions

    ns = "/twil/ros_control/cart_linearizing_controller"
    master = Master()
    master.params.set(f"{ns}/arm_joints", ["a1", "a2"])
    controller = Node(master, "controller")
    commands = []
    controller.create_subscription(f"{ns}/command", "twil_control/CartLinearizingCommand", commands.append)
    joints = Node(master, "joint_state_publisher").create_publisher("/joint_states", "sensor_msgs/JointState")
    view = ViewNode(master, options=ViewOptions(serve=False))
    try:
        view.on_start()
        ok, text = view._apply(Action(1, "goal", GoalForm(1.0, 2.0, 0.5)))
        assert not ok and "joint states" in text and not commands
        joints.publish(
            msg_class("sensor_msgs/JointState")(
                header=header("", 0.0),
                name=["wheel", "a2", "a1"],
                position=np.array([9.0, 0.2, 0.1]),
                velocity=np.zeros(3),
                effort=np.zeros(3),
            )
        )
        ok, text = view._apply(Action(2, "goal", GoalForm(1.0, 2.0, 0.5)))
        assert ok and f"sent on {ns}/command" in text
        c = commands[-1]
        assert (c.platform_pose.x, c.platform_pose.y, c.platform_pose.theta) == (1.0, 2.0, 0.5)
        assert list(c.arm_positions) == [0.1, 0.2] and not np.any(c.arm_velocities)
        assert view._apply(Action(3, "goal", GoalForm(-1.0, 0.0, 0.0)))[0]
        assert list(commands[-1].arm_positions) == [0.1, 0.2]  # the last command's arm, kept
    finally:
        view.shutdown()


# -- frames: dropped while the simulation is behind real time, never below a quarter ---------------
class _PacedSim:
    """Stands in for world.simulation.Simulation: a simulator paced to real time (rate 1)."""

    pace_anchor = None  # paced from the view's own start

    class simulator:
        @staticmethod
        def get_target_realtime_rate():
            return 1.0


class _QuietServer:
    def pending(self):
        return []

    def set_state(self, state):
        self.state = state

    def close(self):
        pass


def _frames_over_one_second(monkeypatch, wall_per_sim: float, recording: bool = False):
    """Tick a live view for 1 s of simulated time at its 50 ms beat while the wall clock runs
    `wall_per_sim` times as fast as simulated time; (sent, dropped)."""
    from twil_control.view import view_node
    from twil_control.view.view_node import ViewNode, ViewOptions

    wall = {"now": 100.0}
    monkeypatch.setattr(view_node.time, "perf_counter", lambda: wall["now"])
    view = ViewNode(Master(), options=ViewOptions(serve=False, rate=20.0))
    try:
        view.server, view._sim, view.recording = _QuietServer(), _PacedSim(), recording
        for k in range(21):
            t = 0.05 * k
            wall["now"] = 100.0 + wall_per_sim * t
            view.tick(t)
        return view.frames_sent, view.frames_dropped
    finally:
        view.server = None
        view.recording = False
        view.shutdown()


def test_a_view_on_time_sends_every_frame(monkeypatch):
    assert _frames_over_one_second(monkeypatch, wall_per_sim=1.0) == (21, 0)


def test_a_view_behind_real_time_drops_frames_down_to_a_quarter_of_its_rate(monkeypatch):
    # wall time runs 3x faster than simulated time: behind after the first frame, for good
    sent, dropped = _frames_over_one_second(monkeypatch, wall_per_sim=3.0)
    assert sent + dropped == 21
    assert sent == 6  # t = 0 (on time), then every 4th beat: 0.2, 0.4, ... 1.0 s (5 Hz)


def test_a_recorded_run_never_drops_a_frame(monkeypatch):
    assert _frames_over_one_second(monkeypatch, wall_per_sim=3.0, recording=True) == (21, 0)


def test_view_rate_outside_its_range_is_refused():
    from twil_control.view.view_node import ViewNode, ViewOptions

    for rate in (0.0, -5.0, 61.0, float("nan")):
        with pytest.raises(ValueError, match=r"view rate .*frames per second must be in \(0, 60\]"):
            ViewNode(Master(), options=ViewOptions(serve=False, rate=rate))
