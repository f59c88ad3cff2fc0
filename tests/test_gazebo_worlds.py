"""World files as Gazebo reads them (description.gazebo_world, world/static_world.py): a
Gazebo-saved world built with no edits and one summary line of what means nothing here, a
ground plane anywhere, includes with their name, pose and static, SDF 1.4 to 1.7 in one world,
<physics> max_step_size as the plant's step, material scripts as colours."""

from __future__ import annotations

import logging
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from support.ros_env import use_packages

from twil_control import PACKAGE_ROOT
from twil_control.description.gazebo_world import normalise
from twil_control.world import static_world
from twil_control.world.simulation import Simulation

VENDOR = PACKAGE_ROOT / "tests" / "data" / "ros1" / "vendor"
BARN = VENDOR / "jackal_helper" / "worlds" / "BARN"
ROVER = PACKAGE_ROOT / "tests" / "data" / "gazebo"

PLANE = """<model name='ground_plane'><static>1</static><link name='link'>
  <collision name='collision'><geometry><plane><normal>0 0 1</normal><size>100 100</size></plane></geometry>
  <surface><friction><ode><mu>100</mu><mu2>50</mu2></ode></friction></surface></collision>
  <visual name='visual'><geometry><plane><normal>0 0 1</normal><size>100 100</size></plane></geometry></visual>
</link></model>"""


@pytest.fixture(autouse=True)
def _env(monkeypatch, tmp_path_factory):
    use_packages(monkeypatch, tmp_path_factory, ROVER, VENDOR, without_gazebo_paths=True)


def _cylinders(n: int) -> list[str]:
    side = int(np.ceil(np.sqrt(n)))
    return [
        f"<model name='cyl_{i}'><static>1</static><pose>{1 + 0.5 * (i % side)} {1 + 0.5 * (i // side)} 0.5 0 0 0</pose>"
        f"<link name='link'><collision name='collision'><geometry><cylinder><radius>0.075</radius>"
        f"<length>1</length></cylinder></geometry><max_contacts>10</max_contacts></collision>"
        f"<visual name='visual'><geometry><cylinder><radius>0.075</radius><length>1</length></cylinder>"
        f"</geometry></visual><self_collide>0</self_collide></link></model>"
        for i in range(n)
    ]


def _rest_heights_in_a_child(worlds: list[str], x: float, y: float, yaw: float) -> tuple[list[float], str]:
    """The qbot's base height after 0.5 s in each world, in a child process (pydrake 1.51 crashes,
    exit 139, on some worlds with planes: a crash fails the test, not the suite); and what the
    child logged."""
    code = textwrap.dedent(f"""
        import logging
        logging.basicConfig(level=logging.INFO, format="%(name)s %(levelname)s %(message)s")
        from twil_control.world.simulation import Simulation
        for world in {worlds!r}:
            sim = Simulation()
            sim.add_world(world)
            sim.spawn("qbot", "qbot", x={x}, y={y}, yaw={yaw})
            sim.finalize()
            simulator = sim.build()
            simulator.AdvanceTo(0.5)
            body = sim.plant.GetBodyByName("base_link")
            context = sim.plant_context(simulator.get_context())
            print("z", sim.plant.EvalBodyPoseInWorld(context, body).translation()[2])
    """)
    child = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert child.returncode == 0, child.stderr[-2000:]
    return [
        float(line.split()[1]) for line in child.stdout.splitlines() if line.startswith("z ")
    ], child.stderr


def test_a_ground_plane_first_or_last_among_400_cylinders_builds_and_the_robot_rests_on_it(tmp_path):
    worlds = []
    for where in ("first", "last"):
        models = [PLANE, *_cylinders(400)] if where == "first" else [*_cylinders(400), PLANE]
        world = tmp_path / f"field_{where}.world"
        world.write_text(
            "<sdf version='1.6'><world name='default'>\n" + "\n".join(models) + "\n</world></sdf>\n"
        )
        worlds.append(str(world))
    heights, log = _rest_heights_in_a_child(worlds, -1.0, -1.0, 0.0)
    assert heights == [pytest.approx(0.055, abs=0.002)] * 2  # on its wheels on the plane's top face
    assert (
        log.count("max_contacts 400, mu2 (friction is isotropic here: mu is used) 1, self_collide 400") == 2
    )


def test_a_gazebo_saved_barn_world_builds_as_it_comes_with_one_summary_line():
    (z,), log = _rest_heights_in_a_child([str(BARN / "world_0.world")], -2.25, 3.0, 1.57)  # BARN's start
    assert z == pytest.approx(0.055, abs=0.002)
    assert "drake WARNING" not in log and "WARNING" not in log  # Drake saw nothing it would ignore
    summary = [line for line in log.splitlines() if "without meaning" in line]
    assert summary == [
        f"twil_control.world.simulation INFO {BARN / 'world_0.world'}: 1060 Gazebo elements without "
        f"meaning in this simulation, ignored (element count): atmosphere 1, cast_shadows 1, gravity 210, "
        f"gui 1, kinematic 210, light 1, magnetic_field 1, material (a second one) 209, max_contacts 210, "
        f"mu2 (friction is isotropic here: mu is used) 1, real_time_factor 1, real_time_update_rate 1, "
        f"scene 1, self_collide 210, spherical_coordinates 1, state 1"
    ]


def test_a_barn_world_keeps_its_cylinders_its_step_and_its_gravity():
    world = normalise(BARN / "world_6.world")
    assert world.time_step == 0.001 and world.gravity == (0.0, 0.0, -9.8)
    assert world.text.count(b"\n") == (BARN / "world_6.world").read_bytes().count(b"\n")  # lines kept
    shapes = static_world.world_shapes(world)
    cylinders = [s for s in shapes if s.proximity is not None and type(s.shape).__name__ == "Cylinder"]
    assert len(cylinders) == len([m for m in world.models if m.name.startswith("unit_cylinder")])
    assert {(s.shape.radius(), s.shape.length()) for s in cylinders} == {(0.075, 1.0)}
    ground = [s for s in shapes if s.model == "ground_plane" and s.proximity is not None]
    assert len(ground) == 1 and ground[0].X_WG.translation()[2] == pytest.approx(-0.05)
    friction = ground[0].proximity.GetProperty("material", "coulomb_friction")
    assert (friction.static_friction(), friction.dynamic_friction()) == (100.0, 100.0)  # ODE's mu


def test_elements_without_meaning_are_counted_by_name_in_one_line_and_drake_sees_none(tmp_path, caplog):
    world = tmp_path / "saved.world"
    world.write_text(
        """<sdf version='1.6'><world name='default'>
  <light name='sun' type='directional'><pose>0 0 10 0 0 0</pose></light>
  <plugin name='gazebo_ros_state' filename='libgazebo_ros_state.so'/>
  <atmosphere type='adiabatic'/><wind/>
  <model name='box'><static>1</static><self_collide>0</self_collide><link name='link'>
    <collision name='c'><geometry><box><size>1 1 1</size></box></geometry><max_contacts>10</max_contacts>
      <surface><bounce/><contact><ode/></contact></surface></collision>
    <collision name='d'><pose>2 0 0 0 0 0</pose><geometry><box><size>1 1 1</size></box></geometry>
      <max_contacts>3</max_contacts></collision>
    <visual name='v'><cast_shadows>0</cast_shadows><geometry><box><size>1 1 1</size></box></geometry></visual>
    <kinematic>0</kinematic><sensor name='cam' type='camera'/>
  </link></model>
  <state world_name='default'><sim_time>1 0</sim_time></state>
</world></sdf>"""
    )
    with caplog.at_level(logging.INFO):
        Simulation().add_world(world)
    lines = [r.getMessage() for r in caplog.records if "without meaning" in r.getMessage()]
    assert lines == [
        f"{world}: 10 Gazebo elements without meaning in this simulation, ignored (element count): "
        f"atmosphere 1, cast_shadows 1, kinematic 1, light 1, max_contacts 2, plugin 1, self_collide 1, "
        f"sensor 1, state 1"
    ]  # the empty <wind/>, <bounce/> and <contact><ode/></contact> say nothing: not counted
    assert not [r for r in caplog.records if r.name.startswith("drake")]


def test_max_step_size_is_the_plants_step_unless_the_launch_sets_time_step(tmp_path):
    from twil_control.launch.loader import load_launch
    from twil_control.launch.runner import Launch

    launch_file = tmp_path / "room.launch.yaml"

    def step(params: str) -> float:
        launch_file.write_text(
            "launch:\n  - node: {pkg: gazebo_ros, type: gzserver, name: gazebo, "
            f'args: "-e ode worlds/rover_room.world"{params}}}\n'
        )
        launch = Launch(load_launch(launch_file))
        launch.build()
        try:
            return launch.sim.config.time_step
        finally:
            launch.shutdown()

    assert step("") == 0.002  # the world's <max_step_size>
    assert step(", params: {time_step: 0.001}") == 0.001


def test_material_scripts_are_colours_and_a_given_diffuse_wins(tmp_path):
    def visual(name: str, material: str) -> str:
        return (
            f"<model name='{name}'><static>1</static><link name='l'><visual name='v'>"
            f"<geometry><box><size>1 1 1</size></box></geometry><material>{material}</material>"
            f"</visual></link></model>"
        )

    script = "<script><uri>file://media/materials/scripts/gazebo.material</uri><name>{}</name></script>"
    world = tmp_path / "colours.world"
    world.write_text(
        "<sdf version='1.6'><world name='w'>"
        + visual("orange", script.format("Gazebo/Orange"))
        + visual("grey", script.format("Gazebo/Grey"))
        + visual("given", "<diffuse>0.1 0.2 0.3 1</diffuse>" + script.format("Gazebo/Red"))
        + visual("custom", script.format("MyShop/Marble"))
        + "</world></sdf>"
    )
    normalised = normalise(world)
    colours = {
        s.model: tuple(round(float(c), 6) for c in s.diffuse.rgba)
        for s in static_world.world_shapes(normalised)
    }
    assert colours == (
        {
            "orange": (1.0, 0.5, 0.05, 1.0),
            "grey": (0.7, 0.7, 0.7, 1.0),
            "given": (0.1, 0.2, 0.3, 1.0),  # Gazebo applies the colours given after the script
            "custom": (0.9, 0.9, 0.9, 1.0),  # Drake's default: not a stock name
        }
    )  # rgba stored as float32: rounded to 6 decimals
    assert normalised.ignored == {"material script MyShop/Marble (not a stock colour)": 1}


def _write_model(root, name: str, version: str, body: str) -> None:
    folder = root / name
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "model.config").write_text(f"<model><sdf version='{version}'>model.sdf</sdf></model>")
    (folder / "model.sdf").write_text(f"<sdf version='{version}'><model name='{name}'>{body}</model></sdf>")


LINK = "<link name='link'><inertial><mass>1</mass></inertial><collision name='c'><geometry><sphere><radius>0.1</radius></sphere></geometry></collision></link>"


def test_includes_keep_their_name_pose_and_static_and_joints_name_included_links(tmp_path, monkeypatch):
    models = tmp_path / "models"
    _write_model(models, "wheelie", "1.5", "<pose>0 0 5 0 0 0</pose>" + LINK)
    _write_model(
        models,
        "cart",
        "1.5",
        "<link name='base'><inertial><mass>2</mass></inertial></link>"
        "<include><uri>model://wheelie</uri><name>w1</name><pose>0.5 0 0 0 0 0</pose></include>"
        "<include><uri>model://wheelie</uri><name>w2</name><pose>-0.5 0 0 0 0 0</pose></include>"
        "<joint name='j1' type='fixed'><parent>base</parent><child>w1::link</child></joint>"
        "<joint name='j2' type='fixed'><parent>base</parent><child>w2::link</child></joint>",
    )
    monkeypatch.setenv("GAZEBO_MODEL_PATH", str(models))
    world = tmp_path / "w.world"
    world.write_text(
        "<sdf version='1.6'><world name='w'>"
        "<include><uri>model://cart</uri><name>cart_a</name><pose>1 2 0.3 0 0 1.5707963267948966</pose></include>"
        "<include><uri>model://wheelie</uri><name>post</name><static>true</static><pose>3 0 0 0 0 0</pose></include>"
        "<include><uri>model://wheelie</uri></include>"
        "</world></sdf>"
    )
    sim = Simulation()
    sim.add_world(world)
    assert sorted(sim.robots) == ["cart_a", "wheelie"]  # the world's moving models, by name
    sim.finalize()
    plant, context = sim.plant, sim.plant.CreateDefaultContext()

    def where(model: str, link: str) -> np.ndarray:
        return plant.EvalBodyPoseInWorld(context, sim.body(model, link)).translation()

    np.testing.assert_allclose(where("cart_a", "w1::link"), [1.0, 2.5, 0.3], atol=1e-9)  # yaw 90 deg
    np.testing.assert_allclose(where("cart_a", "w2::link"), [1.0, 1.5, 0.3], atol=1e-9)
    np.testing.assert_allclose(where("wheelie", "link"), [0.0, 0.0, 5.0], atol=1e-9)  # its own pose
    assert plant.num_bodies() == 1 + 3 + 1  # world; cart_a's base, w1, w2; wheelie (post is anchored)
    assert [s for s in sim.anchored_sources.values()] == [("post", "link")]


@pytest.mark.parametrize(
    "version, axis",
    [
        ("1.4", "<xyz>0 1 0</xyz>"),  # in the model frame, always
        ("1.5", "<xyz>0 1 0</xyz><use_parent_model_frame>true</use_parent_model_frame>"),
        ("1.6", "<xyz>0 0 1</xyz>"),  # in the joint frame: the child link is rolled 90 degrees
        ("1.7", "<xyz expressed_in='__model__'>0 1 0</xyz>"),
    ],
)
@pytest.mark.parametrize("world_version", ["1.4", "1.6", "1.7"])
def test_a_joint_axis_means_what_its_own_files_version_says(
    tmp_path, monkeypatch, version, axis, world_version
):
    models = tmp_path / "models"
    body = (
        "<link name='base'><inertial><mass>1</mass></inertial></link>"
        "<link name='wheel'><pose>0 0 0 -1.5707963267948966 0 0</pose><inertial><mass>1</mass></inertial></link>"
        f"<joint name='spin' type='revolute'><parent>base</parent><child>wheel</child><axis>{axis}</axis></joint>"
    )
    _write_model(models, "spinner", version, body)
    monkeypatch.setenv("GAZEBO_MODEL_PATH", str(models))
    world = tmp_path / "w.world"
    world.write_text(
        f"<sdf version='{world_version}'><world name='w'><include><uri>model://spinner</uri></include></world></sdf>"
    )
    sim = Simulation()
    sim.add_world(world)
    sim.finalize()
    joint = sim.plant.GetJointByName("spin")
    context = sim.plant.CreateDefaultContext()
    R_WF = joint.frame_on_child().CalcPoseInWorld(context).rotation().matrix()
    np.testing.assert_allclose(R_WF @ joint.revolute_axis(), [0.0, 1.0, 0.0], atol=1e-9)
