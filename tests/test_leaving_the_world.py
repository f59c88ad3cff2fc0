"""A robot that leaves the world is reported, not recorded as if nothing happened.

In a world without a floor the qbot falls: the world node notices when it is more than
fall_distance below everything (time and pose in the message) and, being required, stops the
run: exit 1, the bag kept up to then. A spawn pose outside the world is refused before time
starts, naming the spawn_model option, its value and the world's extent; a spawn pose with
nothing under it is warned about at start."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from conftest import read_bag
from pydrake.geometry import Box, Capsule, Convex, Cylinder, Ellipsoid, HalfSpace, Sphere
from pydrake.math import RotationMatrix

from twil_control import PACKAGE_ROOT
from twil_control.launch.__main__ import main
from twil_control.world.extent import shape_box

QBOT = str(PACKAGE_ROOT / "launch" / "qbot_sim.launch.yaml")

WALL = """
    <model name="{name}"><static>true</static><pose>{x} {y} 0.5 0 0 0</pose>
      <link name="link"><collision name="c"><geometry><box><size>{sx} {sy} 1</size></box></geometry></collision>
      </link></model>"""


@pytest.fixture
def walls_only(tmp_path):
    """A 6 m x 6 m room of four walls standing on z = 0, and no floor."""
    walls = "".join(
        WALL.format(name=n, x=x, y=y, sx=sx, sy=sy)
        for n, x, y, sx, sy in (
            ("north", 0, 3, 6, 0.2),
            ("south", 0, -3, 6, 0.2),
            ("east", 3, 0, 0.2, 6),
            ("west", -3, 0, 0.2, 6),
        )
    )
    path = tmp_path / "walls.sdf"
    path.write_text(f'<?xml version="1.0"?><sdf version="1.9"><world name="walls">{walls}</world></sdf>')
    return path


def test_a_robot_falling_out_of_a_world_without_floor_stops_the_run(tmp_path, capsys, walls_only):
    bag = tmp_path / "fall.bag"
    assert main([QBOT, f"world:={walls_only}", "--duration", "3", "--bag", str(bag), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert (
        f"no geometry of the world {walls_only} lies under 'qbot' spawned at (x, y) = (0, 0): it will fall"
        in err
    )
    # free fall from z = 0.055 reaches -1 m (1 m below the walls' bottom, z = 0) at 0.46 s: the
    # 10 Hz check sees it at 0.5 s
    found = re.search(
        r"required node /gazebo failed at t = 0\.500 s: robot 'qbot' left the world at "
        r"t = 0\.500 s: its base_link is at \(x, y, z\) = \(0\.000, 0\.000, (-\d\.\d+)\) m, more "
        r"than 1 m below the world's lowest geometry \(z = 0\.000 m\), with nothing under it to "
        r"land on",
        err,
    )
    assert found, err
    assert float(found.group(1)) == pytest.approx(0.055 - 0.5 * 9.81 * 0.5**2, abs=0.01)
    assert "stopped at t = 0.500 s" in err
    truth = read_bag(bag)["/qbot/ground_truth/odom"]  # the bag is closed and holds the fall
    assert truth[-1][0] <= 0.5e9 and truth[-1][1].pose.pose.position.z < -1.0


@pytest.mark.parametrize("launch", [QBOT, QBOT.replace(".launch.yaml", ".launch")])  # YAML and its XML twin
@pytest.mark.parametrize("arg, option, value", [("x:=1e308", "x", "1e+308"), ("y:=-11.5", "y", "-11.5")])
def test_a_spawn_pose_outside_the_world_is_refused_before_time_starts(
    tmp_path, capsys, launch, arg, option, value
):
    bag = tmp_path / "out.bag"
    assert main([launch, arg, "--duration", "1", "--bag", str(bag)]) == 2
    err = capsys.readouterr().err
    assert (
        f"error: node /spawn_qbot: spawn_model -{option} {value} (launch arg {arg}) puts 'qbot' outside the world "
        "sim/worlds/default.sdf, whose geometry spans x [-10, 10] m and y [-10, 10] m; a model may be "
        "spawned at most 1 m outside it"
    ) in err
    assert not bag.exists() and not bag.with_name("out.bag.active").exists()


def test_the_default_world_warns_about_nothing(tmp_path, capsys):
    assert main([QBOT, "--duration", "0.6", "--no-bag"]) == 0
    err = capsys.readouterr().err
    assert "WARNING" not in err and "left the world" not in err


R_YAW = RotationMatrix.MakeZRotation(math.pi / 4).matrix()
R_TILT = RotationMatrix.MakeXRotation(math.pi / 2).matrix()  # z axis along -y


@pytest.mark.parametrize(
    "shape, R, low, high",
    [
        (Box(2, 1, 0.5), np.eye(3), [-1, -0.5, -0.25], [1, 0.5, 0.25]),
        (Box(2, 2, 1), R_YAW, [-math.sqrt(2), -math.sqrt(2), -0.5], [math.sqrt(2), math.sqrt(2), 0.5]),
        (Sphere(0.3), R_YAW, [-0.3] * 3, [0.3] * 3),
        (Cylinder(0.5, 2), np.eye(3), [-0.5, -0.5, -1], [0.5, 0.5, 1]),
        (Cylinder(0.5, 2), R_TILT, [-0.5, -1, -0.5], [0.5, 1, 0.5]),
        (Capsule(0.5, 2), R_TILT, [-0.5, -1.5, -0.5], [0.5, 1.5, 0.5]),
        (Ellipsoid(1, 2, 3), R_TILT, [-1, -3, -2], [1, 3, 2]),
    ],
)
def test_shape_boxes_enclose_each_posed_shape_exactly(shape, R, low, high):
    p = np.array([1.0, 2.0, 3.0])
    lo, hi = shape_box(shape, R, p)
    np.testing.assert_allclose(lo, p + low, atol=1e-12)
    np.testing.assert_allclose(hi, p + high, atol=1e-12)


def test_a_horizontal_half_space_is_everything_below_its_surface_and_a_mesh_its_hull(tmp_path):
    lo, hi = shape_box(HalfSpace(), np.eye(3), np.array([0.0, 0.0, -0.2]))
    assert list(lo) == [-math.inf] * 3 and list(hi) == [math.inf, math.inf, -0.2]
    assert np.isinf(shape_box(HalfSpace(), R_TILT, np.zeros(3))[1]).all()
    obj = tmp_path / "tet.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 2 0\nv 0 0 3\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    lo, hi = shape_box(Convex(str(obj), 2.0), np.eye(3), np.array([1.0, 0.0, 0.0]))
    assert list(lo) == [1, 0, 0] and list(hi) == [3, 4, 6]
