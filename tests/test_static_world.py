"""A world's static models as anchored geometry: the same scene and the same physics, with no
bodies for the plant to step (world/static_world.py)."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.geometry import Role
from pydrake.systems.primitives import ConstantVectorSource

from twil_control import PACKAGE_ROOT
from twil_control.world.simulation import Simulation

HOUSE = PACKAGE_ROOT / "sim/worlds/house.sdf"


def _qbot_in(world, anchor: bool, torques=(0.0, 0.0, 0.0, 0.0), x: float = 0.0) -> Simulation:
    sim = Simulation()
    sim.add_world(world, anchor_static=anchor)
    sim.spawn("qbot", "qbot", x=x)
    sim.finalize()
    src = sim.builder.AddSystem(ConstantVectorSource(np.array(torques, dtype=float)))
    sim.builder.Connect(src.get_output_port(), sim.plant.get_actuation_input_port())
    return sim


def _world_geometry(sim: Simulation, role: Role) -> dict:
    """name -> (shape type, world pose 3x4, friction or diffuse colour) of every non-robot
    geometry, named `model::geometry` whether anchored or on a welded body."""
    if sim.simulator is None:
        sim.build()
    context = sim.scene_graph.GetMyContextFromRoot(sim.simulator.get_context())
    query = sim.scene_graph.get_query_output_port().Eval(context)
    inspector = query.inspector()
    robot = {int(i) for i in sim.robot_instances("qbot")}
    out = {}
    for gid in inspector.GetAllGeometryIds(role):
        frame = inspector.GetFrameId(gid)
        if frame == inspector.world_frame_id():
            name = inspector.GetName(gid)
        else:
            body = sim.plant.GetBodyFromFrameId(frame)
            if int(body.model_instance()) in robot:
                continue
            name = inspector.GetName(gid)  # Drake scopes a parsed model's geometry names
        props = inspector.GetProperties(gid, role)
        if role == Role.kProximity:
            friction = props.GetProperty("material", "coulomb_friction")
            material = (friction.static_friction(), friction.dynamic_friction())
        else:
            material = tuple(props.GetProperty("phong", "diffuse").rgba)
        out[name] = (
            type(inspector.GetShape(gid)).__name__,
            query.GetPoseInWorld(gid).GetAsMatrix34(),
            material,
        )
    return out


def test_the_house_keeps_every_shape_at_its_pose_with_only_the_robot_left_as_bodies():
    anchored, parsed = _qbot_in(HOUSE, True), _qbot_in(HOUSE, False)
    assert parsed.plant.num_bodies() == 41 and anchored.plant.num_bodies() == 8  # world + qbot's 7
    assert len(anchored.anchored_sources) == 33 + 33  # a collision and a visual per static link
    for role in (Role.kProximity, Role.kIllustration):
        a, p = _world_geometry(anchored, role), _world_geometry(parsed, role)
        assert sorted(a) == sorted(p) and len(a) == 33
        assert all(name.count("::") == 1 for name in a), sorted(a)  # model::geometry, once
        for name, (shape, X, material) in p.items():
            assert a[name][0] == shape
            np.testing.assert_allclose(a[name][1], X, atol=1e-12, err_msg=name)
            assert a[name][2] == material, name
    model, link = anchored.anchored_sources[next(iter(anchored.anchored_sources))]
    assert (model, link) == ("floor", "floor_link")


@pytest.mark.parametrize(
    "torques, x",
    [
        ((0.3, 0.3, 0.3, 0.3), 1.2),  # driven into a wall
        ((-1.0, 1.0, -1.0, 1.0), 0.0),
    ],
)  # spinning in place
def test_the_robot_moves_exactly_as_among_welded_bodies(torques, x):
    states = []
    for anchor in (True, False):
        sim = _qbot_in(HOUSE, anchor, torques, x)
        simulator = sim.build()
        simulator.AdvanceTo(2.0)
        states.append(sim.plant.GetPositionsAndVelocities(sim.plant_context(simulator.get_context())))
    assert np.abs(states[0] - states[1]).max() <= 1e-12
    q, v = states[0][:11], states[0][11:]  # q: quaternion, xyz, 4 wheels; v: w, v, 4 wheels
    assert abs(q[4] - x) > 0.3 or abs(v[2]) > 0.5  # it did move (m, or rad/s of yaw)


def test_in_a_world_with_a_moving_body_only_the_static_models_are_anchored(tmp_path):
    world = tmp_path / "crate.sdf"
    world.write_text("""<?xml version="1.0"?>
<sdf version="1.9"><world name="w">
  <model name="floor"><static>true</static><link name="floor_link">
    <collision name="c"><pose>0 0 -0.05 0 0 0</pose><geometry><box><size>4 4 0.1</size></box></geometry></collision>
  </link></model>
  <model name="crate"><pose>1 0 0.2 0 0 0</pose><link name="crate_link">
    <inertial><mass>2</mass></inertial>
    <collision name="c"><geometry><box><size>0.4 0.4 0.4</size></box></geometry></collision>
  </link></model>
</world></sdf>""")
    sim = Simulation()
    instances = sim.add_world(world)
    assert [sim.plant.GetModelInstanceName(i) for i in instances] == ["crate"]
    assert sorted(sim.anchored_sources.values()) == [("floor", "floor_link")]
    assert sim.plant.HasBodyNamed("crate_link") and not sim.plant.HasBodyNamed("floor_link")
