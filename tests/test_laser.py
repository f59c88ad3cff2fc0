"""The simulated laser: ray casting against analytic ranges, the robot's own geometry left out,
moving bodies seen where they are, the sensor model (noise, REP 117), and the LaserScan and
/tf_static a qbot_sim launch records.

Analytic ranges are computed here independently of mapping.raycast: ray-box by the 2D slab
method in the box's frame, ray-circle by the quadratic's closed form.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import read_bag
from pydrake.math import RigidTransform, RotationMatrix
from support.raycast_reference import cast_numpy

from twil_control import PACKAGE_ROOT
from twil_control.core.node import Master
from twil_control.core.params import ParamError, ParamServer
from twil_control.gazebo.laser_node import Laser
from twil_control.launch.loader import load_launch
from twil_control.launch.runner import RunOptions, run
from twil_control.mapping import raycast
from twil_control.mapping.laser_model import LaserSpec, readings
from twil_control.mapping.sections import Section, box_section, cylinder_section, polygon_area
from twil_control.world.laser import LaserScanner
from twil_control.world.laser_scene import LaserScene, cut
from twil_control.world.simulation import Simulation
from twil_control.world.world_section import world_section

pytestmark = pytest.mark.kernels

SCENE = PACKAGE_ROOT / "tests/data/worlds/laser_scene.sdf"
LAUNCH = PACKAGE_ROOT / "launch/qbot_sim.launch.yaml"
HOKUYO = LaserSpec(resolution=0.0)  # 640 beams over +-2.26889 rad, no rounding
SPAWN = (0.2, -0.1, 0.3)
SCAN_Z = 0.055 + 0.08  # qbot base_link at rest + laser mount
# Static shapes of tests/data/worlds/laser_scene.sdf: (centre x, y, yaw, size x, y) and circles.
BOX_A = (3.0, 1.0, 0.4, 1.0, 0.6)
CYL_A = (-2.0, 2.0, 0.4)
BALL = (0.5, -3.0, 0.3, 0.5)  # centre x, y, z, radius
CRATE = 0.4


def ray_box(ox, oy, theta, cx, cy, yaw, sx, sy) -> float:
    """Slab method in the box's frame: entry distance of the ray, inf if it misses."""
    c, s = math.cos(-yaw), math.sin(-yaw)
    px, py = c * (ox - cx) - s * (oy - cy), s * (ox - cx) + c * (oy - cy)
    dx, dy = c * math.cos(theta) - s * math.sin(theta), s * math.cos(theta) + c * math.sin(theta)
    t0, t1 = -math.inf, math.inf
    for p, d, h in ((px, dx, sx / 2), (py, dy, sy / 2)):
        if abs(d) < 1e-15:
            if abs(p) > h:
                return math.inf
            continue
        a, b = (-h - p) / d, (h - p) / d
        t0, t1 = max(t0, min(a, b)), min(t1, max(a, b))
    if t0 > t1 or t1 <= 0:
        return math.inf
    return t0 if t0 > 0 else t1


def ray_circle(ox, oy, theta, cx, cy, r) -> float:
    """Closed form of |o + t d - c| = r: the smaller positive root, inf if none."""
    fx, fy = ox - cx, oy - cy
    b = fx * math.cos(theta) + fy * math.sin(theta)
    disc = b * b - (fx * fx + fy * fy - r * r)
    if disc < 0:
        return math.inf
    roots = [t for t in (-b - math.sqrt(disc), -b + math.sqrt(disc)) if t > 0]
    return min(roots) if roots else math.inf


def analytic_scan(x, y, yaw, height, crate=None) -> np.ndarray:
    out = []
    bz, br = BALL[2], BALL[3]
    ball_r = math.sqrt(br * br - (height - bz) ** 2) if abs(height - bz) < br else None
    for a in HOKUYO.angles():
        th = yaw + a
        best = min(ray_box(x, y, th, *BOX_A), ray_circle(x, y, th, *CYL_A))
        if ball_r is not None:
            best = min(best, ray_circle(x, y, th, BALL[0], BALL[1], ball_r))
        if crate is not None:
            best = min(best, ray_box(x, y, th, *crate, CRATE, CRATE))
        out.append(best)
    return np.array(out)


@pytest.fixture(scope="module")
def scene():
    """qbot spawned at SPAWN in the analytic scene, with a LaserScanner on base_laser."""
    sim = Simulation()
    sim.add_world(SCENE)
    sim.spawn("qbot", "qbot", x=SPAWN[0], y=SPAWN[1], yaw=SPAWN[2])
    sim.finalize()
    qbot = sim.robot_instances("qbot")
    sensor = sim.plant.GetBodyByName("base_laser", qbot[0])
    scanner = sim.add_system(LaserScanner(sim, sensor, qbot, 1 / 30, lambda s: None, Master().clock))
    sim.build()
    root = sim.simulator.get_mutable_context()
    return sim, scanner, root


def _cast(scan):
    return raycast.cast(
        scan.x,
        scan.y,
        scan.yaw,
        HOKUYO.min_angle,
        HOKUYO.angle_increment,
        HOKUYO.samples,
        scan.segments,
        scan.circles,
    )


def _place_crate(sim, root, x, y, yaw):
    crate = sim.plant.GetBodyByName("crate_link")
    sim.plant.SetFreeBodyPose(
        sim.plant_context(root), crate, RigidTransform(RotationMatrix.MakeZRotation(yaw), [x, y, CRATE / 2])
    )


def _compare(measured, expected) -> float:
    """Max |error| (m) over beams that hit; asserts both agree on which beams miss."""
    hit = np.isfinite(expected)
    assert np.array_equal(np.isfinite(measured), hit), "hit/miss pattern differs from the analytic one"
    assert hit.sum() > 50 and (~hit).sum() > 50  # the scene has both hits and misses
    return float(np.max(np.abs(measured[hit] - expected[hit])))


def test_every_beam_matches_the_analytic_range_to_1_mm(scene):
    sim, scanner, root = scene
    _place_crate(sim, root, 1.0, 3.0, 0.3)
    scan = scanner.scan_input(scanner.GetMyContextFromRoot(root))
    assert (scan.x, scan.y, scan.yaw) == pytest.approx(SPAWN, abs=1e-12)
    assert scan.z == pytest.approx(SCAN_Z, abs=1e-12)
    expected = analytic_scan(*SPAWN, SCAN_Z, crate=(1.0, 3.0, 0.3))
    err = _compare(_cast(scan), expected)
    print(f"ray cast vs analytic: max error {1000 * err:.2e} mm over {np.isfinite(expected).sum()} hits")
    assert err < 1e-3
    # The numpy reference caster agrees with the culled numba one.
    ref = cast_numpy(scan.x, scan.y, scan.yaw, HOKUYO.angles(), scan.segments, scan.circles)
    assert _compare(ref, expected) < 1e-3


def test_a_moving_body_is_seen_at_its_current_pose(scene):
    sim, scanner, root = scene
    ctx = scanner.GetMyContextFromRoot(root)
    for pose in ((1.0, 3.0, 0.3), (2.5, -2.0, 0.7)):
        _place_crate(sim, root, *pose)
        ranges = _cast(scanner.scan_input(ctx))
        assert _compare(ranges, analytic_scan(*SPAWN, SCAN_Z, crate=pose)) < 1e-3
    # ... and the static part was not re-cut: one cached section for both scans.
    assert len(scanner.scene.static) == 4 and len(scanner.scene.dynamic) == 1  # floor, box, cyl, ball


def test_the_robot_does_not_see_its_own_chassis_and_wheels(scene):
    sim, scanner, root = scene
    _place_crate(sim, root, 1.0, 3.0, 0.3)
    assert sorted(scanner.scene.excluded) == sorted(
        f"qbot::{n}"
        for n in ("chassis", "left_front_wheel", "right_front_wheel", "left_rear_wheel", "right_rear_wheel")
    )
    query = scanner.GetInputPort("query").Eval(scanner.GetMyContextFromRoot(root))
    low = 0.06  # a plane through the chassis (z 0.03 .. 0.08) and the wheels (z 0 .. 0.11)
    x, y, yaw = SPAWN
    own = LaserScene(sim.plant, sim.scene_graph.model_inspector())  # nothing excluded
    seg, circ = own.arrays(query, low)
    with_robot = raycast.cast(x, y, yaw, HOKUYO.min_angle, HOKUYO.angle_increment, HOKUYO.samples, seg, circ)
    seg, circ = scanner.scene.arrays(query, low)
    without = raycast.cast(x, y, yaw, HOKUYO.min_angle, HOKUYO.angle_increment, HOKUYO.samples, seg, circ)
    assert np.nanmin(with_robot) < 0.35  # this plane would hit the chassis (half width 0.15)
    assert _compare(without, analytic_scan(x, y, yaw, low, crate=(1.0, 3.0, 0.3))) < 1e-3


@pytest.mark.parametrize("world", [PACKAGE_ROOT / "sim/worlds/house.sdf", SCENE])
def test_static_section_at_any_height_equals_cutting_every_shape_anew(world):
    """Upright boxes are cut once and only tested against their height range when the laser's
    height moves: the scene's section must still be, to the bit, a fresh cut of every shape,
    at heights through and exactly on the boxes' tops and bottoms."""
    sim = Simulation()
    sim.add_world(world)
    sim.finalize()
    sim.build()
    root = sim.simulator.get_context()
    query = sim.scene_graph.get_query_output_port().Eval(sim.scene_graph.GetMyContextFromRoot(root))
    scene = LaserScene(sim.plant, sim.scene_graph.model_inspector())
    scene.static_section(query, 0.1)
    upright = [p.upright for p in scene.static if p.upright is not None]
    assert len(upright) >= 1 and len(upright) < len(scene.static)  # both kinds are exercised
    heights = np.concatenate([np.linspace(-0.2, 2.2, 241), [u[1] for u in upright], [u[2] for u in upright]])
    for h in heights:
        fresh = Section()
        for prim in scene.static:
            cut(prim.shape, prim.R, prim.p, h, fresh)
        scene._static_cache = None  # force a re-cut at h
        got = scene.static_section(query, h)
        assert len(got.polygons) == len(fresh.polygons), h
        assert all(np.array_equal(a, b) for a, b in zip(got.polygons, fresh.polygons)), h
        assert np.array_equal(got.circles, fresh.circles), h


def test_sections_of_tilted_shapes():
    alpha = math.radians(30)
    R = RotationMatrix.MakeXRotation(alpha).matrix()
    poly = box_section(R, np.array([0.0, 0.0, 1.0]), (1.0, 1.0, 1.0), 1.0)
    assert polygon_area(poly) == pytest.approx(1.0 / math.cos(alpha), rel=1e-12)
    assert poly[:, 1].max() == pytest.approx(0.5 / math.cos(alpha), rel=1e-12)
    kind, poly = cylinder_section(R, np.array([0.0, 0.0, 1.0]), 0.2, 2.0, 1.0)
    ellipse = math.pi * 0.2 * 0.2 / math.cos(alpha)
    # A 32-sided inscribed prism: area ratio (32 / 2pi) sin(2pi / 32) = 0.99359.
    assert kind == "polygon" and polygon_area(poly) / ellipse == pytest.approx(
        32 / (2 * math.pi) * math.sin(2 * math.pi / 32), rel=1e-9
    )
    assert cylinder_section(np.eye(3), np.array([0, 0, 0.5]), 0.3, 1.0, 1.2) is None
    assert box_section(np.eye(3), np.array([0, 0, 0.5]), (1, 1, 1), 1.01) is None


def test_an_upright_box_is_cut_as_the_polyhedron_cut_gives_it():
    """box_section's short way for boxes with a vertical axis (its footprint, no hull per box:
    worlds of thousands) against the general cut of the 8-cornered polyhedron: the same
    vertices in the same order, faces and misses included, turned and upside-down boxes."""
    from twil_control.mapping.sections import _BOX_EDGES, box_vertices, convex_section

    rng = np.random.default_rng(7)
    cut_count = 0
    for k in range(3000):
        c, s = math.cos(yaw := rng.uniform(-4.0, 4.0)), math.sin(yaw)
        R = np.eye(3) if k % 7 == 0 else np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        if k % 3 == 1:
            R = R @ np.diag([1.0, -1.0, -1.0])  # upside down
        p, size = rng.uniform(-50.0, 50.0, 3), rng.uniform(0.01, 3.0, 3)
        h = p[2] + [rng.uniform(-0.6, 0.6), 0.5, -0.5][k % 3 if k % 5 else 0] * size[2]
        fast, general = box_section(R, p, size, h), convex_section(box_vertices(R, p, size), _BOX_EDGES, h)
        assert (fast is None) == (general is None), k
        if fast is not None:
            assert np.array_equal(fast, general), k
            cut_count += 1
    assert 2000 < cut_count < 3000  # both cuts and misses were tried


def test_noise_has_the_configured_stddev_and_follows_the_seed():
    spec = LaserSpec(noise_stddev=0.01, resolution=0.0)
    true = np.linspace(1.0, 9.0, spec.samples)
    rng = Master().rng("/qbot/laser")
    residuals = np.concatenate([readings(true, spec, rng) - true for _ in range(50)])
    print(f"noise: std {residuals.std():.5f} m, mean {residuals.mean():+.1e} m over {residuals.size} beams")
    assert residuals.std() == pytest.approx(0.01, rel=0.10)
    assert abs(residuals.mean()) < 0.001
    same = [readings(true, spec, Master().rng("/qbot/laser")) for _ in range(2)]
    assert np.array_equal(same[0], same[1])
    other = Master()
    other.seed = 1
    assert not np.array_equal(same[0], readings(true, spec, other.rng("/qbot/laser")))


def test_rep_117_out_of_range_readings_and_resolution():
    spec = LaserSpec(range_min=0.08, range_max=10.0, resolution=0.01)
    out = readings(np.array([0.05, 0.08, 3.14159, 9.999, 10.5, np.inf]), spec, None)
    assert out[0] == -np.inf  # closer than range_min: -inf
    assert out[1] == pytest.approx(0.08, abs=1e-7)
    assert out[2] == pytest.approx(3.14, abs=1e-6)  # rounded to the 0.01 m resolution
    assert out[3] == pytest.approx(10.0, abs=1e-6)
    assert out[4] == np.inf and out[5] == np.inf  # beyond range_max or no return: +inf
    assert out.dtype == np.float32


@pytest.mark.parametrize(
    "key, value, message",
    [
        ("samples", 1, "samples must be >= 2"),
        ("range_min", 20.0, "range_min < range_max"),
        ("update_rate", 0.0, "update_rate must be a positive"),
        ("noise_stddev", -0.1, "noise_stddev must be >= 0"),
    ],
)
def test_bad_laser_params_are_errors_naming_the_parameter(key, value, message):
    params = ParamServer()
    params.set("/qbot/laser", {"model": "qbot", key: value}, source="test.yaml:3")
    with pytest.raises(ParamError, match=message):
        Laser(Master(params), "laser", "/qbot")


@pytest.fixture(scope="module")
def launch_bag(tmp_path_factory):
    bag = tmp_path_factory.mktemp("laser") / "qbot.bag"
    result = run(
        load_launch(LAUNCH, {"world": str(PACKAGE_ROOT / "sim/worlds/house.sdf")}),
        RunOptions(duration=1.0, bag=bag, seed=7),
    )
    assert result.error is None, result.error
    return read_bag(bag)


def test_qbot_sim_records_30_scans_per_second_with_the_hokuyo_fields(launch_bag):
    scans = launch_bag["/qbot/laser/scan"]
    stamps = np.array([m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec for _, m in scans])
    in_first_second = np.count_nonzero(stamps < 1.0 - 1e-9) + 1  # + the t = 0 scan, sent before recording
    assert abs(in_first_second - 30) <= 1
    assert np.allclose(np.diff(stamps), 1 / 30, atol=1e-6)
    m = scans[0][1]
    assert m.header.frame_id == "base_laser"
    assert len(m.ranges) == 640 and len(m.intensities) == 0
    assert (m.angle_min, m.angle_max) == pytest.approx((-2.26889, 2.26889), abs=1e-6)
    # float32 fields: 639 increments span min..max to float32 precision
    assert m.angle_min + 639 * m.angle_increment == pytest.approx(m.angle_max, abs=1e-5)
    assert m.time_increment == 0.0 and m.scan_time == pytest.approx(1 / 30, rel=1e-6)
    assert (m.range_min, m.range_max) == pytest.approx((0.08, 10.0), rel=1e-6)
    # In the house every beam hits a wall within range (the room is 3.4 m x 7.9 m).
    assert np.all(np.isfinite(m.ranges)) and 0.3 < np.min(m.ranges) and np.max(m.ranges) < 7.0


def test_qbot_sim_publishes_the_laser_mount_on_tf_static(launch_bag):
    """robot_state_publisher's static transforms compose to the laser's mount in the URDF."""
    ((_, msg),) = launch_bag["/tf_static"]
    pairs = {(t.header.frame_id, t.child_frame_id): t.transform for t in msg.transforms}
    assert set(pairs) == {("base_link", "hokuyo_link"), ("hokuyo_link", "base_laser")}
    # hokuyo_joint (0, 0, 0.08) + base_laser_joint (0, 0, 0) of sim/robots/qbot/qbot.urdf
    for transform, z in (
        (pairs[("base_link", "hokuyo_link")], 0.08),
        (pairs[("hokuyo_link", "base_laser")], 0.0),
    ):
        tr, q = transform.translation, transform.rotation
        assert (tr.x, tr.y, tr.z) == pytest.approx((0.0, 0.0, z), abs=1e-12)
        assert (q.x, q.y, q.z, q.w) == pytest.approx((0.0, 0.0, 0.0, 1.0), abs=1e-12)


def test_same_seed_same_scans_other_seed_other_scans(launch_bag):
    def scans(seed):
        got = []
        run(
            load_launch(LAUNCH, {"world": str(PACKAGE_ROOT / "sim/worlds/house.sdf")}),
            RunOptions(duration=0.2, bag=None, seed=seed),
            on_master=lambda m: m.bus.subscribe(
                "/qbot/laser/scan", "sensor_msgs/LaserScan", lambda msg: got.append(msg.ranges.copy())
            ),
        )
        return got

    recorded = [m.ranges for _, m in launch_bag["/qbot/laser/scan"]]
    again = scans(7)[1:]  # [0] is the t = 0 scan the bag does not hold
    assert len(again) == 6 and all(np.array_equal(a, b) for a, b in zip(again, recorded))
    other = scans(8)[1:]
    assert not any(np.array_equal(a, b) for a, b in zip(other, recorded))


def test_unsupported_shapes_are_ignored_with_one_warning_naming_them(tmp_path, caplog):
    world = tmp_path / "odd.sdf"
    world.write_text("""<?xml version="1.0"?>
<sdf version="1.9"><world name="odd"><model name="pill"><static>true</static><link name="l">
  <collision name="capsule"><geometry><capsule><radius>0.2</radius><length>1</length></capsule></geometry></collision>
  <collision name="block"><geometry><box><size>1 1 1</size></box></geometry></collision>
</link></model></world></sdf>""")
    with caplog.at_level("WARNING", logger="twil_control.laser_scene"):
        section = world_section(world, 0.0)
    (record,) = caplog.records
    assert "ignores 1 proximity geometry" in record.message and "pill::capsule (Capsule)" in record.message
    assert len(section.polygons) == 1 and len(section.circles) == 0  # the box is still cut
