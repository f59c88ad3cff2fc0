"""The operator's view (rviz's and the rqt goal plugin's roles) as a node on the bus.

It subscribes to what the running graph offers and draws into Drake's Meshcat, one scene path per
layer. Everything goes out together in frames, so the browser renders once per frame; while the
simulation is behind real time frames are dropped (never when recording), because a browser
without a GPU renders on the simulation's cores. Messages are placed through the robot's true
pose, so a map lines up with the walls exactly when localisation is right (docs/view.md).
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from twil_control.errors import InputError

from ..control.transforms import quat_from_yaw
from ..core.actionlib import status_name
from ..core.messages import header, msg_class
from ..core.ros_node import RosNode
from ..core.tf import TfBuffer, TfError
from ..errors import TwilControlError

log = logging.getLogger("twil_control.view")

WORLD, TRUTH, BASE, MAP = "world", "base_link_ground_truth", "base_link", "map"
TICK = 0.05  # s of simulated time between ticks (panel actions, frames when due)
MAX_RATE = 60.0  # frames per second: no browser shows more
MIN_FRAME_SHARE = 4  # dropping never thins the frames below rate / MIN_FRAME_SHARE
PERIODS = {"grid": 0.5, "scan": 0.1, "plan": 0.2, "marker": 0.2, "state": 0.2}
ROBOT_CONTROLLER_EXCLUDE = ("joint_state_controller/JointStateController",)
GOAL_TOPIC = "/move_base_simple/goal"
INITIAL_POSE_TOPIC = "/initialpose"
#: rviz's 2D Pose Estimate covariance: 0.5 m in x and y, pi / 12 in heading (standard deviations)
INITIAL_POSE_COVARIANCE = {0: 0.25, 7: 0.25, 35: (math.pi / 12) ** 2}


def layer_of(topic: str, typ: str) -> str | None:
    """The view's layer for a topic of type `typ`, None for a topic it does not draw."""
    if typ == "nav_msgs/OccupancyGrid":
        return _grid_layer(topic)
    if typ == "nav_msgs/Path":
        return _plan_layer(topic)
    if typ == "sensor_msgs/LaserScan":
        return "scan"
    if typ == "geometry_msgs/PoseStamped" and topic == GOAL_TOPIC:
        return "goal"
    if typ == "twil_control/MoveBaseActionGoal" and topic.endswith("move_base/goal"):
        return "action_goal"
    if typ == "twil_control/CartLinearizingCommand":
        return "cart_reference"
    if typ == "sensor_msgs/JointState" and topic == "/joint_states":
        return "joint_states"  # the arm's pose, for a cart reference before any command
    if typ == "actionlib_msgs/GoalStatusArray" and topic.endswith("move_base/status"):
        return "status"
    return None


def _plan_layer(topic: str) -> str | None:
    if topic.endswith("local_plan"):
        return "local_plan"
    return "global_plan" if topic.endswith("/plan") else None


def _grid_layer(topic: str) -> str | None:
    if topic.rsplit("/", 1)[-1] == "map":
        return "map"
    if topic.endswith("global_costmap/costmap"):
        return "global_costmap"
    if topic.endswith("local_costmap/costmap"):
        return "local_costmap"
    return None


class ViewPortError(TwilControlError, OSError):
    """The view's panel cannot listen where it was asked to (a port in use, an address this
    machine does not have)."""


@dataclass
class ViewOptions:
    serve: bool = True  # the live page: Meshcat + the goal panel
    host: str = "127.0.0.1"  # address both servers bind to
    port: int = 8800  # the panel's port (0: any free port)
    meshcat_port: int | None = None  # None: Meshcat picks a free one in 7000..7099
    save_html: Path | None = None  # write a self-contained HTML recording of the run here
    replace_html: bool = False  # replace an existing save_html file (never, by default)
    rate: float = 20.0  # frames per second at most (robot poses and layers sent together);
    # frames are dropped while the simulation is behind real time


class ViewNode(RosNode):
    def __init__(
        self,
        master,
        name: str = "view",
        namespace: str = "/",
        remappings=None,
        args=(),
        options: ViewOptions | None = None,
    ) -> None:
        super().__init__(master, name, namespace, remappings, args)
        from pydrake.geometry import Meshcat, MeshcatParams

        from .scene import Scene

        self.options = o = options or ViewOptions()
        if not (isinstance(o.rate, (int, float)) and 0 < o.rate <= MAX_RATE):
            raise InputError(f"view rate {o.rate!r}: frames per second must be in (0, {MAX_RATE:g}]")
        if o.save_html is not None and o.save_html.exists() and not o.replace_html:
            raise FileExistsError(
                f"--save-html {o.save_html} exists; choose another name (it is never overwritten)"
            )
        self.meshcat = Meshcat(MeshcatParams(host=o.host, port=o.meshcat_port, show_stats_plot=False))
        self.scene = Scene(self.meshcat)
        # Looking down on the spawn area from behind-left (rviz's default orbit is similar); the
        # user orbits from there.
        self.meshcat.SetCameraPose([-3.0, -3.0, 4.0], [0.5, 0.0, 0.0])
        self.tf = TfBuffer(self)
        self.visualizer = None
        self.recording = o.save_html is not None
        self.server = None
        if o.serve:
            from .panel_server import PanelServer

            try:
                self.server = PanelServer(self.meshcat.web_url(), o.host, o.port)
            except OSError as error:
                raise ViewPortError(
                    f"--view-port {o.port}: the view cannot serve on {o.host}:{o.port} ({error.strerror}); "
                    "choose another port with --view-port PORT (0: any free port) or another --view-host"
                ) from None
            log.info(
                "view: open %s (goal panel + Meshcat; Meshcat alone at %s)",
                self.server.url,
                self.meshcat.web_url(),
            )
        self.latest: dict[str, object] = {}  # layer -> newest message not drawn yet
        self.last_draw: dict[str, float] = {}
        self.status = None
        self.last_action = None
        self.controllers: list[dict] = []
        self.mode = "none"
        self._goal_pub = self._cancel_pub = self._cart_pub = self._initialpose_pub = None
        self._cart_last = None
        self._cart_topic: str | None = None
        self._wall0 = None
        self._sim = None
        self._next_frame = -math.inf
        self._last_frame = -math.inf
        self.frames_sent = self.frames_dropped = 0
        self._standin = False
        self._started = False

    # -- the runner's hooks -------------------------------------------------------------------
    def build_systems(self, sim) -> None:
        # Live: no periodic publishing of its own; the view's frames publish it (ForcedPublish),
        # so the robot moves in the same frame as the layers and a dropped frame costs nothing.
        # Recording: Drake's animation takes its frame rate from the publish period, so the
        # visualizer publishes periodically, at the view's rate (in step with the frames), and
        # no frame is dropped.
        self._sim = sim
        period = 1.0 / self.options.rate if self.recording else 0.0
        self.visualizer = sim.add_visualizer(self.meshcat, publish_period=period)

    def on_start(self) -> None:
        """Subscribe to what the graph offers (every node has advertised by now)."""
        self._started = True
        types = self.master.bus.topic_types()
        self._subscribe_layers(types)
        self._advertise_panel_outputs(types)
        if self.recording and self.visualizer is not None:
            self.visualizer.StartRecording(set_transforms_while_recording=self.options.serve)
        elif self.recording:
            self.meshcat.StartRecording(set_visualizations_while_recording=self.options.serve)
        if self.visualizer is None:
            from pydrake.geometry import Rgba

            self.scene.box("robot", (0.5, 0.4, 0.2), Rgba(0.9, 0.6, 0.1, 1.0), 0.1)
            self._standin = True
        self.create_timer(min(TICK, 1.0 / self.options.rate), lambda e: self.tick(self.now()))

    def _subscribe_layers(self, types: dict[str, str]) -> None:
        """One subscription per topic the view draws; move_base's cancel topic gets a publisher."""
        for topic, typ in types.items():
            if typ == "actionlib_msgs/GoalID" and topic.endswith("move_base/cancel"):
                self._cancel_pub = self.create_publisher(topic, "actionlib_msgs/GoalID")
                continue
            layer = layer_of(topic, typ)
            if layer == "cart_reference":
                self._cart_topic = topic
            if layer is not None:
                self.create_subscription(topic, typ, self._keeper(layer))

    def _advertise_panel_outputs(self, types: dict[str, str]) -> None:
        """The panel's Start drives move_base when it listens, else the cart controller; Set pose
        goes to a localiser listening on /initialpose."""
        bus = self.master.bus
        if GOAL_TOPIC in types and bus.subscribers_of(GOAL_TOPIC):
            self.mode = "navigation: Start sends a goal to move_base"
            self._goal_pub = self.create_publisher(GOAL_TOPIC, "geometry_msgs/PoseStamped")
        elif self._cart_topic is not None:
            self.mode = "cart: Start sets the cart controller's reference pose"
            self._cart_pub = self.create_publisher(self._cart_topic, "twil_control/CartLinearizingCommand")
        if bus.subscribers_of(INITIAL_POSE_TOPIC):  # a localiser (amcl) listens
            self._initialpose_pub = self.create_publisher(
                INITIAL_POSE_TOPIC, "geometry_msgs/PoseWithCovarianceStamped"
            )

    def shutdown(self) -> None:
        if self.frames_dropped:
            log.info(
                "view: %d frames sent, %d dropped to keep the simulation in real time",
                self.frames_sent,
                self.frames_dropped,
            )
        try:
            if self.recording and self._started:
                self._save_html()
        finally:
            if self.server is not None:
                self.server.close()
            self.scene.close()

    def _arm_reference(self):
        """The arm part of a cart reference the panel sends: the last command's arm positions
        (the panel moves the platform only), or, before any command (a launch without a
        reference program), the arm where it is, from /joint_states and the controller's
        arm_joints parameter."""
        if self._cart_last is not None:
            return np.asarray(self._cart_last.arm_positions, float)
        js = self.latest.get("joint_states")
        if js is None:
            return None
        joints = self.get_param(self._cart_topic.rsplit("/", 1)[0] + "/arm_joints", None)
        names = list(js.name)
        if not joints or any(j not in names for j in joints):
            return None
        return np.array([js.position[names.index(j)] for j in joints], float)

    # -- subscriptions --------------------------------------------------------------------------
    def _keeper(self, layer: str):
        def keep(msg) -> None:
            if layer == "status":
                if msg.status_list:  # the newest goal is last; keep the last known when the list empties
                    s = msg.status_list[-1]
                    self.status = {
                        "name": status_name(s.status),
                        "code": int(s.status),
                        "text": s.text,
                        "goal": s.goal_id.id,
                    }
                return
            if layer == "cart_reference":
                self._cart_last = msg
            if layer == "action_goal":
                layer_, msg = "goal", msg.goal.target_pose
                self.latest[layer_] = msg
                return
            self.latest[layer] = msg

        return keep

    # -- the tick: actions, drawing, the panel's snapshot ------------------------------------------
    def tick(self, t: float) -> None:
        if self._wall0 is None:
            self._wall0 = (time.perf_counter(), t)
        if self.server is not None:
            for action in self.server.pending():
                ok, message = self._apply(action)
                self.last_action = {"id": action.id, "ok": ok, "message": message}
                (log.info if ok else log.warning)("panel: %s", message)
        if t >= self._next_frame - 1e-9:
            period = 1.0 / self.options.rate
            self._next_frame = max(self._next_frame + period, t + 0.5 * period)
            if self._behind(t, period) and t - self._last_frame < MIN_FRAME_SHARE * period - 1e-9:
                self.frames_dropped += 1
            else:
                self._frame(t)
        if self.server is not None and t - self.last_draw.get("state", -math.inf) >= PERIODS["state"] - 1e-9:
            self.last_draw["state"] = t
            self.controllers = self._list_controllers()
            self.server.set_state(self.snapshot(t))

    def _behind(self, t: float, period: float) -> bool:
        """Is the simulation more than a frame behind its real-time schedule? Only a live view
        of a simulation paced to real time (or a rate) drops frames."""
        if self.server is None or self.recording or self._sim is None or self._sim.simulator is None:
            return False
        target = self._sim.simulator.get_target_realtime_rate()
        if target <= 0:
            return False
        wall0, t0 = self._sim.pace_anchor or self._wall0
        return (time.perf_counter() - wall0) * target - (t - t0) > period

    def _frame(self, t: float) -> None:
        """Send one frame: the layers that are due, and the robot."""
        self._last_frame = t
        self.frames_sent += 1
        rec = t if self.recording else None
        for layer, kind in (
            ("map", "grid"),
            ("global_costmap", "grid"),
            ("local_costmap", "grid"),
            ("scan", "scan"),
            ("global_plan", "plan"),
            ("local_plan", "plan"),
            ("goal", "marker"),
            ("cart_reference", "marker"),
        ):
            if layer in self.latest and t - self.last_draw.get(layer, -math.inf) >= PERIODS[kind] - 1e-9:
                msg = self.latest.pop(layer)
                self.last_draw[layer] = t
                self._draw(layer, kind, msg, rec)
        if self.visualizer is not None:
            if self.recording:
                return  # the visualizer publishes itself, on the same beat
            root = self._sim.simulator.get_context()
            self.visualizer.ForcedPublish(self.visualizer.GetMyContextFromRoot(root))
        elif self._standin and t - self.last_draw.get("robot", -math.inf) >= PERIODS["marker"] - 1e-9:
            X = self._robot_pose()
            if X is not None:
                self.last_draw["robot"] = t
                self.scene.place("robot", X, rec)

    def flush(self, t: float) -> None:
        """Draw whatever is still waiting, throttles aside (the end of a bag)."""
        self.last_draw.clear()
        self._frame(t)

    def snapshot(self, t: float) -> dict:
        wall0, t0 = self._wall0 or (time.perf_counter(), t)
        wall = time.perf_counter() - wall0
        X = self._robot_pose()
        robot = (
            None
            if X is None
            else [
                float(X.translation()[0]),
                float(X.translation()[1]),
                float(X.rotation().ToRollPitchYaw().yaw_angle()),
            ]
        )
        return {
            "time": t,
            "rtf": (t - t0) / wall if wall > 0.5 else None,
            "mode": self.mode,
            "robot": robot,
            "status": self.status,
            "controllers": self.controllers,
            "last_action": self.last_action,
            "frames": {"sent": self.frames_sent, "dropped": self.frames_dropped},
        }

    # -- drawing ------------------------------------------------------------------------------------
    def _draw(self, layer: str, kind: str, msg, rec) -> None:
        from pydrake.geometry import Rgba

        from .scene import planar

        sc = self.scene
        if kind == "grid":
            X = self.world_from(msg.header.frame_id)
            if X is None:
                self.latest.setdefault(layer, msg)  # no pose yet: try again next time
                return
            sc.grid(layer, msg, "map" if layer == "map" else "costmap")
            sc.place(layer, X)
        elif kind == "scan":
            X = self.world_from(msg.header.frame_id)
            if X is None:
                return
            r = np.asarray(msg.ranges, float)
            a = msg.angle_min + msg.angle_increment * np.arange(len(r))
            ok = np.isfinite(r) & (r >= msg.range_min) & (r <= msg.range_max)
            xyz = np.vstack([r[ok] * np.cos(a[ok]), r[ok] * np.sin(a[ok]), np.zeros(int(ok.sum()))])
            sc.points("scan", xyz, Rgba(1.0, 0.1, 0.1, 1.0), 0.05)
            sc.place("scan", X)
        elif kind == "plan":
            X = self.world_from(msg.header.frame_id)
            if X is None:
                return
            xyz = np.array([[p.pose.position.x, p.pose.position.y, 0.03] for p in msg.poses]).T.reshape(3, -1)
            color = Rgba(0.1, 0.8, 0.1, 1.0) if layer == "global_plan" else Rgba(0.1, 0.4, 1.0, 1.0)
            sc.line(layer, xyz, color, 4.0 if layer == "global_plan" else 3.0)
            sc.place(layer, X)
        elif layer == "goal":
            X = self.world_from(msg.header.frame_id)
            if X is None:
                self.latest.setdefault(layer, msg)
                return
            from .scene import pose_transform

            p, q = msg.pose.position, msg.pose.orientation
            sc.arrow("goal", Rgba(1.0, 0.0, 1.0, 1.0))
            sc.place("goal", X @ pose_transform((p.x, p.y, p.z), (q.x, q.y, q.z, q.w)), rec)
        elif layer == "cart_reference":
            # The command's pose is in the controller's pose frame: world (ground truth) or the
            # odometry frame, which coincides with the world when the robot starts at the origin.
            pp = msg.platform_pose
            sc.arrow("cart_reference", Rgba(1.0, 0.6, 0.0, 1.0))
            sc.place("cart_reference", planar(pp.x, pp.y, pp.theta), rec)

    def world_from(self, frame: str):
        """X_world_frame through the robot's truth (docs/view.md), or None."""
        from pydrake.math import RigidTransform

        from .scene import pose_transform

        if frame in ("", WORLD):
            return RigidTransform()
        tf = self.tf
        try:
            X_world_truth = pose_transform(*tf.lookup_transform(WORLD, TRUTH))
            return X_world_truth @ pose_transform(*tf.lookup_transform(BASE, frame))
        except TfError:
            pass
        if frame == MAP:
            return RigidTransform()
        try:
            return pose_transform(*tf.lookup_transform(MAP, frame))
        except TfError:
            return None

    def _robot_pose(self):
        from .scene import pose_transform

        for target, source in ((WORLD, TRUTH), (MAP, BASE), ("odom", BASE)):
            try:
                return pose_transform(*self.tf.lookup_transform(target, source))
            except TfError:
                continue
        return None

    # -- panel actions (simulation thread) ----------------------------------------------------------
    def _apply(self, action) -> tuple[bool, str]:
        if action.kind == "goal":
            g = action.payload
            if self._goal_pub is not None:
                q = quat_from_yaw(g.ori)
                P = msg_class("geometry_msgs/Point")
                Q = msg_class("geometry_msgs/Quaternion")
                self._goal_pub.publish(
                    msg_class("geometry_msgs/PoseStamped")(
                        header=header(MAP, self.now()),
                        pose=msg_class("geometry_msgs/Pose")(
                            position=P(x=g.x, y=g.y, z=0.0), orientation=Q(x=q[0], y=q[1], z=q[2], w=q[3])
                        ),
                    )
                )
                if self.status is None or self.status["name"] not in ("ACTIVE", "PENDING"):
                    self.status = {"name": "PENDING", "code": 0, "text": "sent to move_base", "goal": ""}
                return True, f"goal ({g.x:g}, {g.y:g}, {g.ori:g}) sent on {GOAL_TOPIC} in frame {MAP}"
            if self._cart_pub is not None:
                arm = self._arm_reference()
                if arm is None:
                    return (
                        False,
                        "neither a cart command nor the arm's joint states seen yet; try again in a moment",
                    )
                n = len(arm)
                self._cart_pub.publish(
                    msg_class("twil_control/CartLinearizingCommand")(
                        header=header("", self.now()),
                        platform_pose=msg_class("geometry_msgs/Pose2D")(x=g.x, y=g.y, theta=g.ori),
                        arm_positions=arm,
                        arm_velocities=np.zeros(n),
                        arm_accelerations=np.zeros(n),
                    )
                )
                self.status = {
                    "name": "SENT",
                    "code": -1,
                    "text": f"cart reference ({g.x:g}, {g.y:g}, {g.ori:g})",
                    "goal": "",
                }
                return True, f"cart reference pose ({g.x:g}, {g.y:g}, {g.ori:g}) sent on {self._cart_topic}"
            return (
                False,
                "this launch has neither move_base nor a cart controller: there is nothing to send a goal to",
            )
        if action.kind == "initialpose":
            return self._initial_pose(action.payload)
        if action.kind == "cancel":
            if self._cancel_pub is None:
                return False, "this launch has no move_base: there is no goal to cancel"
            self._cancel_pub.publish(msg_class("actionlib_msgs/GoalID")(stamp=header("", 0.0).stamp, id=""))
            return True, "cancel sent to move_base (all goals)"
        if action.kind == "controller":
            return self._switch(action.payload)
        return False, f"unknown action {action.kind}"

    def _initial_pose(self, g) -> tuple[bool, str]:
        """The form's pose on /initialpose as rviz's 2D Pose Estimate sends it."""
        if self._initialpose_pub is None:
            return (
                False,
                f"nothing listens on {INITIAL_POSE_TOPIC} in this launch (a localiser such as amcl does)",
            )
        q = quat_from_yaw(g.ori)
        cov = np.zeros(36)
        for i, v in INITIAL_POSE_COVARIANCE.items():
            cov[i] = v
        self._initialpose_pub.publish(
            msg_class("geometry_msgs/PoseWithCovarianceStamped")(
                header=header(MAP, self.now()),
                pose=msg_class("geometry_msgs/PoseWithCovariance")(
                    pose=msg_class("geometry_msgs/Pose")(
                        position=msg_class("geometry_msgs/Point")(x=g.x, y=g.y, z=0.0),
                        orientation=msg_class("geometry_msgs/Quaternion")(x=q[0], y=q[1], z=q[2], w=q[3]),
                    ),
                    covariance=cov,
                ),
            )
        )
        return True, f"initial pose ({g.x:g}, {g.y:g}, {g.ori:g}) sent on {INITIAL_POSE_TOPIC} in frame {MAP}"

    def _managers(self) -> list[str]:
        return sorted(
            n[: -len("list_controllers")]
            for n in self.master.services
            if n.endswith("controller_manager/list_controllers")
        )

    def _list_controllers(self) -> list[dict]:
        out = []
        for prefix in self._managers():
            for c in self.master.call_service(prefix + "list_controllers").controller:
                if c.type not in ROBOT_CONTROLLER_EXCLUDE:
                    out.append(
                        {"name": c.name, "state": c.state, "type": c.type, "manager": prefix.rstrip("/")}
                    )
        return out

    def _switch(self, enable: bool) -> tuple[bool, str]:
        from ..ros_control.srv import STRICT

        controllers = self._list_controllers()
        if not controllers:
            return False, "no controller manager with a robot controller in this launch"
        done = []
        for prefix in self._managers():
            names = [
                c["name"]
                for c in controllers
                if c["manager"] == prefix.rstrip("/") and (c["state"] != "running") == enable
            ]
            if not names:
                continue
            start, stop = (names, []) if enable else ([], names)
            ok = self.master.call_service(prefix + "switch_controller", start, stop, STRICT).ok
            if not ok:
                owner = getattr(self.master.services[prefix + "switch_controller"][1], "__self__", None)
                why = getattr(owner, "last_error", "") or "see the log"
                return False, f"{prefix}switch_controller refused: {why}"
            done += names
        verb = "started" if enable else "stopped"
        return True, (f"{verb} {', '.join(done)}" if done else f"controllers already {verb}")

    # -- static HTML ----------------------------------------------------------------------------------
    def _save_html(self) -> None:
        path = self.options.save_html
        if self.visualizer is not None:
            self.visualizer.StopRecording()
            self.visualizer.PublishRecording()
        else:
            self.meshcat.StopRecording()
            self.meshcat.PublishRecording()
        path.parent.mkdir(parents=True, exist_ok=True)
        text = self.meshcat.StaticHtml()
        try:  # "x": a file of that name that appeared during the run is not replaced
            with open(path, "w" if self.options.replace_html else "x", encoding="utf-8") as out:
                out.write(text)
        except FileExistsError:
            log.error(
                "view: %s appeared during the run and is never overwritten; the HTML recording was not saved",
                path,
            )
            return
        log.info("view: wrote %s (%.1f MB, self-contained; open it in a browser)", path, len(text) / 1e6)
