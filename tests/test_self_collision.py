"""A spawned model's links collide with each other only when it asks for it, as in Gazebo
(world/simulation.py): a URDF whose arm overlaps its base has no contact between them, unless a
link sets <selfCollide>true</selfCollide>; an SDF model the same with <self_collide>. The floor
still touches the model either way."""

from __future__ import annotations

import pytest
from pydrake.geometry import Box
from pydrake.math import RigidTransform
from pydrake.multibody.plant import CoulombFriction

from twil_control.description.urdf import parse_urdf
from twil_control.world.simulation import Simulation

INERTIAL = '<inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>'


def _urdf(self_collide: bool) -> str:
    gazebo = '<gazebo reference="arm"><selfCollide>true</selfCollide></gazebo>' if self_collide else ""
    return f"""<robot name="r">
  <link name="base">{INERTIAL}<collision><geometry><box size="0.4 0.4 0.1"/></geometry></collision></link>
  <link name="middle">{INERTIAL}</link>
  <link name="arm">{INERTIAL}<collision><origin xyz="0.1 0 0"/><geometry><sphere radius="0.1"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="middle"/><axis xyz="0 0 1"/>
    <limit effort="1" velocity="1" lower="-1" upper="1"/></joint>
  <joint name="j2" type="revolute"><parent link="middle"/><child link="arm"/><axis xyz="0 0 1"/>
    <limit effort="1" velocity="1" lower="-1" upper="1"/></joint>
  {gazebo}
</robot>"""


def _contacts(sim: Simulation) -> list[tuple[str, str]]:
    sim.finalize()
    simulator = sim.build()
    context = sim.scene_graph.GetMyContextFromRoot(simulator.get_context())
    query = sim.scene_graph.get_query_output_port().Eval(context)
    inspector = query.inspector()
    return sorted(
        tuple(sorted((inspector.GetName(p.id_A), inspector.GetName(p.id_B))))
        for p in query.ComputePointPairPenetration()
    )


def _floor(sim: Simulation) -> None:
    """A 4 m floor slab whose top is 1 cm above z = 0: the models' bases sink into it."""
    plant = sim.plant
    floor = RigidTransform([0, 0, -0.5 + 0.01])
    plant.RegisterCollisionGeometry(plant.world_body(), floor, Box(4, 4, 1), "floor", CoulombFriction(1, 1))


@pytest.mark.parametrize(("self_collide", "pairs"), [(False, 1), (True, 2)])
def test_urdf_links_collide_with_each_other_only_with_self_collide(self_collide, pairs):
    sim = Simulation()
    _floor(sim)
    sim.spawn_description("r", parse_urdf(_urdf(self_collide), "r.urdf"), pose=(0, 0, 0.05, 0, 0, 0))
    contacts = _contacts(sim)
    assert len(contacts) == pairs  # the base on the floor; the arm in the base only if asked
    assert any("floor" in pair for pair in contacts)


SDF = """<?xml version="1.0"?><sdf version="1.6"><model name="s">{flag}
  <pose>0 0 0.05 0 0 0</pose>
  <link name="base">{inertial}<collision name="c"><geometry><box><size>0.4 0.4 0.1</size></box></geometry></collision></link>
  <link name="arm"><pose>0.1 0 0 0 0 0</pose>{inertial}<collision name="c"><geometry><sphere><radius>0.1</radius></sphere></geometry></collision></link>
  <link name="middle">{inertial}</link>
  <joint name="j1" type="revolute"><parent>base</parent><child>middle</child><axis><xyz>0 0 1</xyz></axis></joint>
  <joint name="j2" type="revolute"><parent>middle</parent><child>arm</child><axis><xyz>0 0 1</xyz></axis></joint>
</model></sdf>"""
SDF_INERTIAL = (
    "<inertial><mass>1</mass><inertia><ixx>0.01</ixx><iyy>0.01</iyy><izz>0.01</izz></inertia></inertial>"
)


@pytest.mark.parametrize(("flag", "pairs"), [("", 1), ("<self_collide>true</self_collide>", 2)])
def test_sdf_links_collide_with_each_other_only_with_self_collide(flag, pairs):
    sim = Simulation()
    _floor(sim)
    sim.spawn_description("s", sdf_text=SDF.format(flag=flag, inertial=SDF_INERTIAL).encode(), source="s.sdf")
    assert len(_contacts(sim)) == pairs
