"""Gazebo's stock material scripts (``media/materials/scripts/gazebo.material``) as colours.

A Gazebo world or model names its colours ``<material><script><name>Gazebo/Grey</name>``; a
URDF's ``<gazebo reference>`` says ``<material>Gazebo/Grey</material>``. Drake draws a diffuse
colour, so each stock name maps to its diffuse rgba (textured ones to their dominant colour;
the ``...Transparent`` ones keep their alpha).
"""

from __future__ import annotations

__all__ = ["GAZEBO_COLORS", "gazebo_color"]

GAZEBO_COLORS: dict[str, tuple[float, float, float, float]] = {
    "Gazebo/Black": (0.0, 0.0, 0.0, 1.0),
    "Gazebo/FlatBlack": (0.1, 0.1, 0.1, 1.0),
    "Gazebo/DarkGrey": (0.175, 0.175, 0.175, 1.0),
    "Gazebo/Grey": (0.7, 0.7, 0.7, 1.0),
    "Gazebo/LightGrey": (0.8, 0.8, 0.8, 1.0),
    "Gazebo/White": (1.0, 1.0, 1.0, 1.0),
    "Gazebo/Red": (1.0, 0.0, 0.0, 1.0),
    "Gazebo/RedBright": (0.87, 0.26, 0.07, 1.0),
    "Gazebo/Green": (0.0, 1.0, 0.0, 1.0),
    "Gazebo/Blue": (0.0, 0.0, 1.0, 1.0),
    "Gazebo/SkyBlue": (0.53, 0.81, 0.92, 1.0),
    "Gazebo/Yellow": (1.0, 1.0, 0.0, 1.0),
    "Gazebo/ZincYellow": (0.97, 0.95, 0.21, 1.0),
    "Gazebo/DarkYellow": (0.7, 0.7, 0.0, 1.0),
    "Gazebo/Orange": (1.0, 0.5, 0.05, 1.0),
    "Gazebo/Purple": (1.0, 0.0, 1.0, 1.0),
    "Gazebo/Indigo": (0.33, 0.0, 0.5, 1.0),
    "Gazebo/Turquoise": (0.0, 1.0, 1.0, 1.0),
    "Gazebo/Gold": (0.8, 0.65, 0.2, 1.0),
    "Gazebo/Wood": (0.6, 0.4, 0.2, 1.0),
    "Gazebo/WoodFloor": (0.6, 0.45, 0.3, 1.0),
    "Gazebo/Bricks": (0.6, 0.3, 0.2, 1.0),
    "Gazebo/Residential": (0.8, 0.8, 0.75, 1.0),
    "Gazebo/CeilingTiled": (0.9, 0.9, 0.9, 1.0),
    "Gazebo/GreyTransparent": (0.5, 0.5, 0.5, 0.5),
    "Gazebo/RedTransparent": (1.0, 0.0, 0.0, 0.5),
    "Gazebo/GreenTransparent": (0.0, 1.0, 0.0, 0.5),
    "Gazebo/BlueTransparent": (0.0, 0.0, 1.0, 0.5),
}


def gazebo_color(name: str) -> tuple[float, float, float, float] | None:
    """The rgba of a stock material name (None for a name that is not one)."""
    return GAZEBO_COLORS.get(name.strip())
