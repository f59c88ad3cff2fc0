"""move_base against a kinematic robot in a generated world, on the in-process bus, no Drake: the
planners' own share of a navigation run, many times faster than the simulation.

The robot integrates cmd_vel (a unicycle, the commanded velocities reached within the robot's
acceleration limits) at 100 Hz and publishes odom -> base_link on /tf with map -> odom the
identity (the true pose: slam:=false's fake localisation); a planar laser is ray cast against
the world's circles and box edges (mapping.raycast) at its rate with 1 cm of range noise; the
rasterised world is served on /map when the global costmap has a static layer. A collision is
the footprint polygon touching a shape. move_base reads the parameter files as a launch loads
them (common costmap file into both costmap namespaces, the others into /move_base).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from twil_control.control.transforms import quat_from_yaw
from twil_control.core.messages import header, msg_class
from twil_control.core.node import Master, Node
from twil_control.core.tf import StaticTfBroadcaster, TfBroadcaster, transform_stamped
from twil_control.mapping import raycast


@dataclass
class Robot:
    """A robot's shape, limits and laser, as the kinematic run needs them."""

    name: str
    footprint: list  # [[x, y], ...] in base_link
    acc_lin: float = 2.5  # m/s^2
    acc_ang: float = 3.2  # rad/s^2
    laser_xy: tuple = (0.0, 0.0)  # in base_link
    laser_frame: str = "base_laser"
    laser_topic: str = "/scan"
    angle_min: float = -2.26889
    angle_max: float = 2.26889
    samples: int = 640
    range_max: float = 10.0
    rate: float = 30.0
    cmd_topic: str = "/cmd_vel"
    files: list = field(default_factory=list)  # [(path, namespace)] in load order


CONFIG = Path(__file__).resolve().parents[1] / "config"


def qbot() -> Robot:
    common = yaml.safe_load((CONFIG / "costmap_common_params.yaml").read_text())
    return Robot(
        "qbot",
        common["footprint"],
        2.5,
        3.2,
        (0.0, 0.0),
        "base_laser",
        "/qbot/laser/scan",
        files=[
            (CONFIG / "costmap_common_params.yaml", "/move_base/global_costmap"),
            (CONFIG / "costmap_common_params.yaml", "/move_base/local_costmap"),
            (CONFIG / "global_costmap_params.yaml", "/move_base"),
            (CONFIG / "local_costmap_params.yaml", "/move_base"),
            (CONFIG / "base_local_planner_params.yaml", "/move_base"),
            (CONFIG / "move_base_params.yaml", "/move_base"),
        ],
    )


def jackal(folder: Path = CONFIG / "jackal_nav") -> Robot:
    """A Jackal-sized robot (0.508 x 0.430 m) with BARN's laser (Hokuyo UST-10: 720 beams over
    270 degrees, 30 m, 50 Hz, 0.055 m ahead of base_link) and jackal_control's acceleration
    limits (20 m/s^2, 25 rad/s^2), on the parameter files of `folder` laid out as BARN's
    jackal_helper/configs/params."""
    return Robot(
        "jackal",
        [[0.254, 0.215], [-0.254, 0.215], [-0.254, -0.215], [0.254, -0.215]],
        20.0,
        25.0,
        (0.055, 0.0),
        "front_laser",
        "/front/scan",
        -2.35619,
        2.35619,
        720,
        30.0,
        50.0,
        "/cmd_vel",
        files=[
            (folder / "costmap_common_params.yaml", "/move_base/global_costmap"),
            (folder / "costmap_common_params.yaml", "/move_base/local_costmap"),
            (folder / "global_costmap_params.yaml", "/move_base"),
            (folder / "local_costmap_params.yaml", "/move_base"),
            (folder / "base_local_planner_params.yaml", "/move_base"),
            (folder / "move_base_params.yaml", "/move_base"),
        ],
    )


def scene(sc) -> tuple[np.ndarray, np.ndarray]:
    """(segments (n, 4), circles (m, 3)) of a _nav_worlds.Scenario."""
    segs = []
    for b in sc.boxes:
        c, s = math.cos(b.yaw), math.sin(b.yaw)
        corners = [(sx * b.sx / 2, sy * b.sy / 2) for sx, sy in ((1, 1), (-1, 1), (-1, -1), (1, -1))]
        pts = [(b.x + c * x - s * y, b.y + s * x + c * y) for x, y in corners]
        segs += [(*pts[i], *pts[(i + 1) % 4]) for i in range(4)]
    circles = [(k.x, k.y, k.r) for k in sc.cylinders]
    return np.array(segs, float).reshape(-1, 4), np.array(circles, float).reshape(-1, 3)


def occupancy(segs: np.ndarray, circles: np.ndarray, res: float, extra=(), margin: float = 1.5):
    """(int8 grid 0/100, origin (x, y)) with every cell whose centre lies within half a cell of a
    shape occupied, covering the shapes and the `extra` points with a margin."""
    pts = np.vstack(
        [segs[:, :2], segs[:, 2:], circles[:, :2] - circles[:, 2:3], circles[:, :2] + circles[:, 2:3]]
        + [np.array(extra, float).reshape(-1, 2)]
    )
    lo, hi = pts.min(0) - margin, pts.max(0) + margin
    w, h = int(math.ceil((hi[0] - lo[0]) / res)), int(math.ceil((hi[1] - lo[1]) / res))
    xs = lo[0] + (np.arange(w) + 0.5) * res
    ys = lo[1] + (np.arange(h) + 0.5) * res
    X, Y = np.meshgrid(xs, ys)
    occ = np.zeros((h, w), bool)
    half = res / 2
    for cx, cy, r in circles:
        c0, c1 = max(int((cx - r - lo[0]) / res) - 2, 0), min(int((cx + r - lo[0]) / res) + 3, w)
        r0, r1 = max(int((cy - r - lo[1]) / res) - 2, 0), min(int((cy + r - lo[1]) / res) + 3, h)
        occ[r0:r1, c0:c1] |= np.hypot(X[r0:r1, c0:c1] - cx, Y[r0:r1, c0:c1] - cy) <= r + half
    for x0, y0, x1, y1 in segs:
        d = np.array([x1 - x0, y1 - y0])
        L2 = max(d @ d, 1e-12)
        t = np.clip(((X - x0) * d[0] + (Y - y0) * d[1]) / L2, 0, 1)
        occ |= np.hypot(X - (x0 + t * d[0]), Y - (y0 + t * d[1])) <= half * math.sqrt(2)
    return np.where(occ, 100, 0).astype(np.int8), (float(lo[0]), float(lo[1]))


def _seg_intersect(p, q, a, b) -> bool:
    def cross(o, u, v):
        return (u[0] - o[0]) * (v[1] - o[1]) - (u[1] - o[1]) * (v[0] - o[0])

    d1, d2, d3, d4 = cross(a, b, p), cross(a, b, q), cross(p, q, a), cross(p, q, b)
    return (d1 * d2 < 0) and (d3 * d4 < 0)


def footprint_hits(poly: np.ndarray, segs: np.ndarray, circles: np.ndarray) -> bool:
    """Whether the footprint polygon (k, 2) touches a circle or crosses a segment (or holds one)."""
    lo, hi = poly.min(0), poly.max(0)
    if len(circles):
        c = circles[
            (circles[:, 0] + circles[:, 2] >= lo[0])
            & (circles[:, 0] - circles[:, 2] <= hi[0])
            & (circles[:, 1] + circles[:, 2] >= lo[1])
            & (circles[:, 1] - circles[:, 2] <= hi[1])
        ]
        for cx, cy, r in c:
            if _inside(poly, cx, cy) or _distance_to_edges(poly, cx, cy) < r:
                return True
    if len(segs):
        s = segs[
            (np.maximum(segs[:, 0], segs[:, 2]) >= lo[0])
            & (np.minimum(segs[:, 0], segs[:, 2]) <= hi[0])
            & (np.maximum(segs[:, 1], segs[:, 3]) >= lo[1])
            & (np.minimum(segs[:, 1], segs[:, 3]) <= hi[1])
        ]
        n = len(poly)
        for x0, y0, x1, y1 in s:
            if _inside(poly, x0, y0):
                return True
            for i in range(n):
                if _seg_intersect(poly[i], poly[(i + 1) % n], (x0, y0), (x1, y1)):
                    return True
    return False


def _distance_to_edges(poly: np.ndarray, x: float, y: float) -> float:
    a, b = poly, np.roll(poly, -1, axis=0)
    d = b - a
    t = np.clip(((x - a[:, 0]) * d[:, 0] + (y - a[:, 1]) * d[:, 1]) / np.maximum((d * d).sum(1), 1e-12), 0, 1)
    return float(np.hypot(x - a[:, 0] - t * d[:, 0], y - a[:, 1] - t * d[:, 1]).min())


def _inside(poly: np.ndarray, x: float, y: float) -> bool:
    inside = False
    n = len(poly)
    for i in range(n):
        (xa, ya), (xb, yb) = poly[i], poly[(i + 1) % n]
        if (ya > y) != (yb > y) and x < xa + (y - ya) * (xb - xa) / (yb - ya):
            inside = not inside
    return inside


class KinematicRobot(Node):
    def __init__(self, master: Master, robot: Robot, segs, circles, rng) -> None:
        super().__init__(master, "kinematic_robot")
        self.robot = robot
        self.segs, self.circles = segs, circles
        self.pose = np.zeros(3)
        self.vel = np.zeros(2)
        self.cmd = (0.0, 0.0)
        self.collided_at: float | None = None
        self.moved_at: float | None = None
        self.trace: list[tuple[float, float, float]] = []
        self.fp = np.array(robot.footprint, float)
        self.rng = rng
        self._tf = TfBroadcaster(self)
        st = StaticTfBroadcaster(self)
        st.send(transform_stamped("map", "odom", 0.0, (0, 0, 0), (0, 0, 0, 1)))
        st.send(transform_stamped("base_link", robot.laser_frame, 0.0, (*robot.laser_xy, 0.0), (0, 0, 0, 1)))
        self.create_subscription(robot.cmd_topic, "geometry_msgs/Twist", self._on_cmd)
        self._scan_pub = self.create_publisher(robot.laser_topic, "sensor_msgs/LaserScan")
        self._scan = msg_class("sensor_msgs/LaserScan")
        self._inc = (robot.angle_max - robot.angle_min) / (robot.samples - 1)
        self._dt = 0.01
        self._publish_tf()
        self.create_timer(self._dt, self._step)
        self.create_timer(1.0 / robot.rate, self._laser)

    def _on_cmd(self, msg) -> None:
        v, w = float(msg.linear.x), float(msg.angular.z)
        self.cmd = (v, w) if math.isfinite(v) and math.isfinite(w) else (0.0, 0.0)

    def _step(self, event) -> None:
        r = self.robot
        dv = np.clip(self.cmd[0] - self.vel[0], -r.acc_lin * self._dt, r.acc_lin * self._dt)
        dw = np.clip(self.cmd[1] - self.vel[1], -r.acc_ang * self._dt, r.acc_ang * self._dt)
        self.vel = self.vel + (dv, dw)
        v, w = self.vel
        x, y, th = self.pose
        self.pose = np.array(
            [x + v * math.cos(th) * self._dt, y + v * math.sin(th) * self._dt, th + w * self._dt]
        )
        t = self.now()
        if self.moved_at is None and math.hypot(*self.pose[:2]) > 0.1:
            self.moved_at = t
        if self.collided_at is None and self._hits():
            self.collided_at = t
        if not self.trace or t - self.trace[-1][0] >= 0.1:
            self.trace.append((t, float(self.pose[0]), float(self.pose[1])))
        self._publish_tf()

    def polygon(self) -> np.ndarray:
        x, y, th = self.pose
        c, s = math.cos(th), math.sin(th)
        return np.column_stack(
            [x + c * self.fp[:, 0] - s * self.fp[:, 1], y + s * self.fp[:, 0] + c * self.fp[:, 1]]
        )

    def _hits(self) -> bool:
        return footprint_hits(self.polygon(), self.segs, self.circles)

    def _publish_tf(self) -> None:
        x, y, th = self.pose
        self._tf.send(transform_stamped("odom", "base_link", self.now(), (x, y, 0.0), quat_from_yaw(th)))

    def _laser(self, event) -> None:
        r = self.robot
        x, y, th = self.pose
        lx = x + math.cos(th) * r.laser_xy[0] - math.sin(th) * r.laser_xy[1]
        ly = y + math.sin(th) * r.laser_xy[0] + math.cos(th) * r.laser_xy[1]
        ranges = raycast.cast(lx, ly, th, r.angle_min, self._inc, r.samples, self.segs, self.circles)
        ranges = ranges + self.rng.normal(0.0, 0.01, ranges.shape)
        ranges = np.where(ranges > r.range_max, np.inf, ranges).astype(np.float32)
        self._scan_pub.publish(
            self._scan(
                header=header(r.laser_frame, self.now()),
                angle_min=r.angle_min,
                angle_max=r.angle_max,
                angle_increment=self._inc,
                time_increment=0.0,
                scan_time=1.0 / r.rate,
                range_min=0.08,
                range_max=r.range_max,
                ranges=ranges,
                intensities=np.zeros(0, dtype=np.float32),
            )
        )


@dataclass
class KinematicResult:
    status: str  # succeeded, collided, timeout, aborted
    time_s: float
    final_m: float
    end: tuple
    text: str
    trace: list
    wall_s: float


def run(
    sc,
    robot: Robot,
    overrides: dict | None = None,
    timeout: float = 100.0,
    success_radius: float = 1.0,
    seed: int = 0,
    goal_frame: str = "map",
    stop_on_collision: bool = True,
    collision_counts_after: float = 0.0,
    bag: Path | None = None,
) -> KinematicResult:
    """One episode: the goal sent at 0.5 s; success once within success_radius of it (BARN: 1 m)
    or when move_base reports SUCCEEDED within it; timeout measured from the first motion as
    BARN's run.py does (from the goal while the robot has not moved). With `bag`, every topic
    is recorded there."""
    from twil_control.nodes.move_base import MoveBase

    wall0 = time.perf_counter()
    master = Master()
    master.seed = seed
    for path, ns in robot.files:
        master.params.load_file(path, ns)
    for key, value in (overrides or {}).items():
        master.params.set(key if key.startswith("/") else f"/move_base/{key}", value)
    segs, circles = scene(sc)
    grid, origin = occupancy(segs, circles, 0.05, [sc.start[:2], sc.goal[:2]])
    pub = Node(master, "world")
    pub.create_publisher("/map", "nav_msgs/OccupancyGrid", latch=True).publish(_grid_msg(grid, origin))
    robot_node = KinematicRobot(master, robot, segs, circles, np.random.default_rng(seed))
    mb = MoveBase(master, "move_base")
    recorder = None
    if bag is not None:
        from twil_control.bag.recorder import BagRecorder

        recorder = BagRecorder(bag, master.bus)
    results = []
    pub.create_subscription(
        "/move_base/result", "twil_control/MoveBaseActionResult", lambda m: results.append(m.status)
    )
    goal_pub = pub.create_publisher("/move_base_simple/goal", "geometry_msgs/PoseStamped")
    master.spin_until(0.5)
    gx, gy, gyaw = sc.goal
    q = quat_from_yaw(gyaw)
    goal_pub.publish(
        msg_class("geometry_msgs/PoseStamped")(
            header=header(goal_frame, master.clock.now()),
            pose=msg_class("geometry_msgs/Pose")(
                position=msg_class("geometry_msgs/Point")(x=gx, y=gy, z=0.0),
                orientation=msg_class("geometry_msgs/Quaternion")(x=q[0], y=q[1], z=q[2], w=q[3]),
            ),
        )
    )
    status, text = "timeout", ""
    t = master.clock.now()
    while True:
        t += 0.1
        master.spin_until(t)
        if recorder is not None:
            recorder.flush()
        d = math.hypot(robot_node.pose[0] - gx, robot_node.pose[1] - gy)
        if (
            robot_node.collided_at is not None
            and stop_on_collision
            and robot_node.collided_at >= collision_counts_after
        ):
            status = "collided"
            break
        if d <= success_radius:
            status = "succeeded"
            break
        if results:
            s = results[-1]
            status, text = ("succeeded" if s.status == 3 and d <= success_radius else "aborted"), s.text
            break
        start = robot_node.moved_at if robot_node.moved_at is not None else 0.5
        if t - start >= timeout:
            break
    start = robot_node.moved_at if robot_node.moved_at is not None else 0.5
    if recorder is not None:
        recorder.close()
    del mb
    return KinematicResult(
        status,
        t - start,
        math.hypot(robot_node.pose[0] - gx, robot_node.pose[1] - gy),
        tuple(float(v) for v in robot_node.pose),
        text,
        robot_node.trace,
        time.perf_counter() - wall0,
    )


def _grid_msg(data: np.ndarray, origin):
    h, w = data.shape
    info = msg_class("nav_msgs/MapMetaData")(
        map_load_time=header("", 0.0).stamp,
        resolution=0.05,
        width=w,
        height=h,
        origin=msg_class("geometry_msgs/Pose")(
            position=msg_class("geometry_msgs/Point")(x=origin[0], y=origin[1], z=0.0),
            orientation=msg_class("geometry_msgs/Quaternion")(x=0.0, y=0.0, z=0.0, w=1.0),
        ),
    )
    return msg_class("nav_msgs/OccupancyGrid")(header=header("map", 0.0), info=info, data=data.ravel())
