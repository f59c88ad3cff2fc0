"""Worlds that are large or odd: read in pieces, refused when SceneGraph cannot hold them, a
<plane> that would crash pydrake 1.51 made safe (a box), and Ctrl-C while a large world loads
(world/sdf_models.py, world/static_world.py)."""

from __future__ import annotations

import select
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

from twil_control import PACKAGE_ROOT
from twil_control.world import static_world
from twil_control.world.models import ModelError
from twil_control.world.sdf_models import scan_world
from twil_control.world.simulation import Simulation

PLANE = """<model name="ground"><static>true</static><link name="ground_link">
  <collision name="c"><geometry><plane><normal>0 0 1</normal><size>50 50</size></plane></geometry></collision>
</link></model>"""


def _box(i: int, static: bool = True, extra: str = "") -> str:
    x, y = 3.0 + 1.5 * (i % 20), 3.0 + 1.5 * (i // 20)
    return (
        f'<model name="box_{i}">{"<static>true</static>" if static else ""}'
        f'<pose>{x} {y} 0.5 0 0 {0.01 * i}</pose><link name="link">'
        f"{'' if static else '<inertial><mass>2</mass></inertial>'}"
        f'<collision name="collision"><geometry><box><size>0.5 0.6 1</size></box></geometry>'
        f"<drake:proximity_properties><drake:mu_dynamic>{0.3 + 0.001 * i}</drake:mu_dynamic>"
        f"<drake:mu_static>{0.3 + 0.001 * i}</drake:mu_static></drake:proximity_properties></collision>"
        f'<visual name="visual"><geometry><box><size>0.5 0.6 1</size></box></geometry>'
        f"<material><diffuse>0.8 0.5 {0.001 * i} 1</diffuse></material></visual>{extra}</link></model>"
    )


def _world(tmp_path, *models: str, name: str = "world.sdf"):
    path = tmp_path / name
    path.write_text(
        '<?xml version="1.0"?>\n<sdf version="1.9" xmlns:drake="http://drake.mit.edu">\n<world name="w">\n'
        + "\n".join(models)
        + "\n</world>\n</sdf>\n"
    )
    return path


def test_a_plane_before_14_static_models_no_longer_crashes(tmp_path):
    """pydrake 1.51 segfaults on this world (a half-space followed by 14 or more geometries in
    SceneGraph's broadphase); run in a child so that a crash fails the test, not the suite."""
    world = _world(tmp_path, PLANE, *(_box(i) for i in range(14)))
    code = textwrap.dedent(f"""
        from twil_control.world.simulation import Simulation
        sim = Simulation()
        sim.add_world({str(world)!r})
        sim.spawn("qbot", "qbot")
        sim.finalize()
        simulator = sim.build()
        simulator.AdvanceTo(0.5)
        body = sim.plant.GetBodyByName("base_link")
        print(sim.plant.EvalBodyPoseInWorld(sim.plant_context(simulator.get_context()), body).translation()[2])
    """)
    child = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert child.returncode == 0, child.stderr[-2000:]
    assert float(child.stdout.split()[-1]) == pytest.approx(0.055, abs=0.002)  # resting on the plane


def test_a_world_read_in_pieces_has_the_shapes_drake_reads_from_the_whole_file(tmp_path, monkeypatch):
    monkeypatch.setattr(static_world, "PIECE_MODELS", 7)  # 3 pieces; the plane is a box now
    world = _world(
        tmp_path,
        *(_box(i) for i in range(10)),
        PLANE,
        *(_box(i) for i in range(10, 20)),
        _box(20, static=False),
    )
    normalised = static_world.load_world(world)
    scan = scan_world(normalised.text)
    assert scan.split is not None and scan.collisions == 22
    pieces = static_world._pieces([m for m in scan.split.models if m.static])
    assert [len(p) for p in pieces] == [7, 7, 7]
    read = static_world.world_shapes(world)
    # the same normalised world parsed whole by Drake
    whole, _ = static_world._scratch_shapes(lambda p: p.AddModelsFromString(normalised.text.decode(), "sdf"))
    key = lambda s: (s.model, s.name)  # noqa: E731
    assert sorted(map(key, read)) == sorted(map(key, whole)) and len(read) == 41  # crate not fixed
    by_key = {key(s): s for s in whole}
    for s in read:
        w = by_key[key(s)]
        assert s.link == w.link and type(s.shape) is type(w.shape)
        np.testing.assert_allclose(s.X_WG.GetAsMatrix34(), w.X_WG.GetAsMatrix34(), atol=1e-15)
        if s.proximity is None:
            assert s.diffuse.rgba.tolist() == w.diffuse.rgba.tolist()
        else:
            mu = [
                p.GetProperty("material", "coulomb_friction").static_friction()
                for p in (s.proximity, w.proximity)
            ]
            assert mu[0] == mu[1]


def test_drake_messages_about_a_piece_name_the_file_and_line(tmp_path):
    bad = _world(
        tmp_path, _box(0), _box(1).replace("<size>0.5 0.6 1</size>", "<size>1 1</size>", 1), name="bad.sdf"
    )
    with pytest.raises(ModelError, match=rf"{bad}:5: error: .*box_1.*size"):
        Simulation().add_world(bad)


@pytest.mark.parametrize(
    "element, reason",
    [
        ("<include><uri>package://twil_control/sim/worlds/default.sdf</uri></include>", "<include>"),
        ('<frame name="f"/>', "world-level <frame>"),
    ],
)
def test_worlds_whose_models_refer_outside_themselves_are_read_whole(tmp_path, element, reason):
    scan = scan_world(_world(tmp_path, _box(0), element))
    assert scan.split is None and reason in scan.why_whole
    posed = _box(1).replace("<pose>", '<pose relative_to="box_0">')
    scan = scan_world(_world(tmp_path, _box(0), posed, name="posed.sdf"))
    assert scan.split is None and "relative_to 'box_0'" in scan.why_whole


FLOOR = """<model name="floor"><static>true</static><pose>0 0 -0.05 0 0 0</pose><link name="floor_link">
  <collision name="c"><geometry><box><size>100 100 0.1</size></box></geometry></collision>
</link></model>"""


def test_a_world_read_whole_beyond_max_collision_geometries_is_refused_before_it_is_parsed(
    tmp_path, monkeypatch
):
    posed = _box(1).replace("<pose>", '<pose relative_to="box_0">')  # keeps the world whole
    world = _world(tmp_path, _box(0), posed, *(_box(i) for i in range(2, 30)))
    monkeypatch.setattr(static_world, "_scratch_shapes", None)  # parsing would fail differently
    with pytest.raises(
        static_world.WorldTooLargeError,
        match=rf"{world}: 30 <collision> elements, more than "
        r"max_collision_geometries \(29\), in a world that is read whole.*pair of collision",
    ):
        Simulation().add_world(world, max_collision_geometries=29)


def _proximity_models(sim, simulator) -> set[str]:
    """The models whose geometries have a proximity role in the simulator's context."""
    from pydrake.geometry import Role

    query = sim.scene_graph.get_query_output_port().Eval(
        sim.scene_graph.GetMyContextFromRoot(simulator.get_context())
    )
    inspector = query.inspector()
    return {inspector.GetName(g).split("::")[0] for g in inspector.GetAllGeometryIds(Role.kProximity)}


def _base_xyz(sim, simulator):
    body = sim.plant.GetBodyByName("base_link")
    return sim.plant.EvalBodyPoseInWorld(sim.plant_context(simulator.get_context()), body).translation()


def test_beyond_max_collision_geometries_static_shapes_collide_near_the_robots_only(tmp_path):
    """31 collisions with a limit of 29: the static ones get their proximity role within 2 m of
    a movable body (world/proximity_window.py); qbot dropped onto a box rests on it; moved away
    between slices, the box's role goes to the boxes around its new place; the laser and the
    world's extent see every box all the time."""
    world = _world(tmp_path, FLOOR, *(_box(i) for i in range(30)))  # boxes 1.5 m apart from (3, 3)
    sim = Simulation()
    sim.add_world(world, max_collision_geometries=29)
    sim.spawn("qbot", "qbot", x=3.0, y=3.0, z=1.0)  # on top of box_0 (1 m tall)
    sim.finalize()
    simulator = sim.build()
    near = _proximity_models(sim, simulator)
    assert near == {"qbot", "floor", "box_0", "box_1", "box_20", "box_21"}  # within 2 m; box_2 is 2.75 m off
    assert len(sim.windowed_shapes) == 31
    simulator.AdvanceTo(1.0)
    x, y, z = _base_xyz(sim, simulator)
    rest = z - 1.0
    assert abs(x - 3.0) < 0.05 and abs(y - 3.0) < 0.05 and 0.0 < rest < 0.2  # on the box, not the floor

    from pydrake.math import RigidTransform

    body = sim.plant.GetBodyByName("base_link")
    sim.plant.SetFreeBodyPose(
        sim.plant_context(simulator.get_mutable_context()),
        body,
        RigidTransform([3.0 + 1.5 * 9, 3.0 + 1.5, 1.2]),
    )  # above box_29
    sim.update_proximity_window()
    near = _proximity_models(sim, simulator)
    assert {"floor", "box_29", "box_28", "box_9", "box_8"} <= near and "box_0" not in near
    simulator.AdvanceTo(2.0)
    assert _base_xyz(sim, simulator)[2] > 1.0  # resting on box_29

    extent = sim.world_extent()
    low, high = extent.bounds()
    np.testing.assert_allclose([low[0], high[0]], [-50.0, 50.0], atol=1e-9)  # the floor
    assert len(extent.low) == 31


@pytest.mark.slow
def test_ctrl_c_while_a_large_world_loads_ends_the_launch_promptly(tmp_path):
    """Reading is done piece by piece in Python, so a SIGINT is acted on between pieces
    (before: one C++ call of minutes for a world this size)."""
    world = _world(tmp_path, *(_box(i) for i in range(1500)))
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "twil_control.launch",
            str(PACKAGE_ROOT / "launch/qbot_sim.launch.yaml"),
            f"world:={world}",
            "--no-bag",
            "--duration",
            "1",
        ],
        stderr=subprocess.PIPE,
        bufsize=0,
    )  # unbuffered: select() sees every line
    try:
        deadline, seen = time.monotonic() + 120, ""
        while not ("reading" in seen and str(world) in seen):  # the world is being read
            assert time.monotonic() < deadline and proc.poll() is None, f"not read: {seen}"
            if select.select([proc.stderr], [], [], 1.0)[0]:
                seen += proc.stderr.readline().decode()
        proc.send_signal(signal.SIGINT)
        rest = proc.communicate(timeout=60)[1].decode()  # its whole build takes about 5 s
        assert "simulated" not in rest  # it stopped there, before time started
    finally:
        proc.kill()


def _static(name: str, x: float, geometry: str, rgba: str) -> str:
    return (
        f'<model name="{name}"><static>true</static><pose>{x} 6 0.5 0 0 0.3</pose><link name="link">'
        f'<collision name="collision"><geometry>{geometry}</geometry></collision>'
        f'<visual name="visual"><geometry>{geometry}</geometry><material><diffuse>{rgba}</diffuse>'
        f"</material></visual></link></model>"
    )


MERGE_WORLD = (
    [FLOOR]
    + [
        _static(
            f"box_{i}",
            1.5 * i,
            "<box><size>0.5 0.6 1</size></box>",
            "0.8 0.5 0.2 1" if i % 2 else "0.2 0.5 0.8 1",
        )
        for i in range(20)
    ]
    + [
        _static(
            "pillar_0", 31.0, "<cylinder><radius>0.2</radius><length>1</length></cylinder>", "0.8 0.5 0.2 1"
        ),
        _static(
            "pillar_1", 32.0, "<cylinder><radius>0.2</radius><length>1</length></cylinder>", "0.8 0.5 0.2 1"
        ),
        _static("ball", 33.0, "<sphere><radius>0.3</radius></sphere>", "0.8 0.5 0.2 1"),
        _static("pill", 34.0, "<capsule><radius>0.2</radius><length>0.5</length></capsule>", "0.1 0.1 0.1 1"),
    ]
)


def _world_visuals(sim: Simulation):
    """The static world's illustration geometry: name -> (shape, rgba, world corners of its
    shapes: a mesh's hull's, a primitive's box)."""
    from pydrake.geometry import Mesh, Role

    from twil_control.world.extent import shape_box

    query = sim.scene_graph.get_query_output_port().Eval(
        sim.scene_graph.GetMyContextFromRoot(sim.simulator.get_context())
    )
    inspector = query.inspector()
    robot = {int(i) for i in sim.robot_instances("qbot")}
    out = {}
    for gid in inspector.GetAllGeometryIds(Role.kIllustration):
        frame = inspector.GetFrameId(gid)
        if (
            frame != inspector.world_frame_id()
            and int(sim.plant.GetBodyFromFrameId(frame).model_instance()) in robot
        ):
            continue
        shape, X = inspector.GetShape(gid), query.GetPoseInWorld(gid)
        if isinstance(shape, Mesh):
            hull = shape.GetConvexHull()
            v = np.array([hull.vertex(i) for i in range(hull.num_vertices())])
            corners = (v.min(axis=0), v.max(axis=0))
        else:
            corners = shape_box(shape, np.asarray(X.rotation().matrix()), X.translation())
        rgba = tuple(inspector.GetIllustrationProperties(gid).GetProperty("phong", "diffuse").rgba)
        out[inspector.GetName(gid)] = (type(shape).__name__, rgba, corners)
    return out


def test_many_visuals_are_drawn_as_a_few_meshes_of_the_same_surfaces(tmp_path, monkeypatch):
    """Beyond MERGE_ABOVE static visuals, boxes, cylinders and spheres are drawn as one mesh per
    colour per batch (world/merged_visuals.py: SceneGraph's name check visits every geometry of
    the world frame): they cover what the shapes did, in the same colours, Meshcat draws them,
    the other shapes stay as they were, and the robot moves among them exactly as before."""
    from pydrake.geometry import Meshcat

    from twil_control.world import merged_visuals

    world = _world(tmp_path, *MERGE_WORLD)
    sims = {}
    for merge_above in (10**9, 5):
        monkeypatch.setattr(static_world, "MERGE_ABOVE", merge_above)
        monkeypatch.setattr(merged_visuals, "BATCH", 10)
        sim = Simulation()
        sim.add_world(world)
        sim.spawn("qbot", "qbot", x=1.0, y=3.0)
        sim.finalize()
        sims[merge_above] = sim
    meshcat = Meshcat()
    sims[5].add_visualizer(meshcat, publish_period=0)
    for sim in sims.values():
        sim.build()
    single, merged = _world_visuals(sims[10**9]), _world_visuals(sims[5])
    single = {name.split("::")[0]: v for name, v in single.items()}  # by model
    assert len(single) == 24
    # boxes 0-9, 10-19, then the pillars and the ball: two colours in each batch of boxes
    assert sorted(merged) == ["pill::visual"] + [
        f"world.sdf::visuals_{b}_{c}" for b, c in ((0, 0), (0, 1), (1, 0), (1, 1), (2, 0))
    ]
    assert merged["pill::visual"][:2] == single["pill"][:2]
    batches = [
        [f"box_{i}" for i in range(10)],
        [f"box_{i}" for i in range(10, 20)],
        ["pillar_0", "pillar_1", "ball"],
    ]
    for name, (shape, rgba, (low, high)) in merged.items():
        if shape == "Mesh":  # the hull of the batch's shapes of its colour
            batch = batches[int(name.split("_")[-2])]
            members = [single[m] for m in batch if single[m][1] == rgba]
            assert members
            # 6 decimals in the OBJ text; a turned polygon falls short of its circle's box by
            # at most r (1 - cos(pi / SEGMENTS)) (r = 0.3 m, the ball's)
            atol = 1e-5 + (0.3 * (1 - np.cos(np.pi / merged_visuals.SEGMENTS)) if "ball" in batch else 0.0)
            np.testing.assert_allclose(
                low, np.min([m[2][0] for m in members], axis=0), atol=atol, err_msg=name
            )
            np.testing.assert_allclose(
                high, np.max([m[2][1] for m in members], axis=0), atol=atol, err_msg=name
            )
    sims[5].diagram.ForcedPublish(sims[5].simulator.get_context())
    assert meshcat.HasPath("/drake/visualizer/world.sdf/visuals_2_0")
    for sim in sims.values():
        sim.simulator.AdvanceTo(0.5)
    np.testing.assert_allclose(
        _base_xyz(sims[5], sims[5].simulator), _base_xyz(sims[10**9], sims[10**9].simulator), atol=1e-12
    )


def test_a_world_read_whole_has_its_many_visuals_merged_too(tmp_path, monkeypatch):
    monkeypatch.setattr(static_world, "MERGE_ABOVE", 5)
    world = _world(tmp_path, '<frame name="f"/>', *MERGE_WORLD)  # a world-level frame: read whole
    assert "world-level <frame>" in scan_world(world).why_whole
    sim = Simulation()
    sim.add_world(world)
    sim.spawn("qbot", "qbot", x=1.0, y=3.0)
    sim.finalize()
    sim.build()
    assert sorted(_world_visuals(sim)) == ["pill::visual", "world.sdf::visuals_0_0", "world.sdf::visuals_0_1"]
