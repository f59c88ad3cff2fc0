"""A laser mounted upside down (Husky's LMS1xx on its tower: rolled by pi) sweeps clockwise seen
from above, as Gazebo's ray sensor in that frame does; the costmap reads such a scan through
its frame's full orientation, as tf projects it."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from twil_control.gazebo.laser_node import LaserSensor
from twil_control.mapping.laser_model import LaserSpec


def _ranges(upside_down: bool) -> np.ndarray:
    spec = LaserSpec(samples=181, min_angle=-math.pi / 2, max_angle=math.pi / 2, range_max=30.0)
    wall_on_the_right = np.array([[-5.0, -1.0, 5.0, -1.0]])  # y = -1, the sensor at the origin facing +x
    scan = SimpleNamespace(
        x=0.0, y=0.0, yaw=0.0, segments=wall_on_the_right, circles=np.zeros((0, 3)), upside_down=upside_down
    )
    return LaserSensor.true_ranges(SimpleNamespace(spec=spec), scan)


def test_an_upside_down_laser_sees_on_its_positive_angles_what_lies_to_the_right():
    upright, flipped = _ranges(False), _ranges(True)
    angles = np.linspace(-math.pi / 2, math.pi / 2, 181)
    # upright: the wall to the right (negative angles), 1 m away straight to the side
    assert upright[0] == pytest.approx(1.0) and np.isinf(upright[-1])
    # upside down, the sensor's y axis points to the robot's right: the same wall on its left
    assert flipped[-1] == pytest.approx(1.0) and np.isinf(flipped[0])
    assert np.allclose(flipped, upright[::-1])
    assert flipped[135] == pytest.approx(1.0 / math.sin(angles[135]))
