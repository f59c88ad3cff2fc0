"""An SDF world's static geometry cut at a height (the map rasteriser's input).

The world's shapes are read by Drake (world/static_world.py, in pieces, so a large world is
read in time proportional to its size) and cut by the functions the simulated laser's
`LaserScene` uses, so the ground-truth map and the laser see the same shapes. Only static
geometry is kept (static models, or links welded to the world): free bodies have no fixed
place on a map. A Gazebo world is read as the simulation reads it (description.gazebo_world),
its static meshes as the convex pieces the physics and the laser see (world/mesh_pieces.py).
"""

from __future__ import annotations

from pathlib import Path

from ..mapping.sections import Section
from .laser_scene import SUPPORTED, cut, warn_uncut
from .static_world import world_shapes


def world_section(world: str | Path, height: float) -> Section:
    """The static shapes of `world` (an SDF/URDF path or a short model name) at z = height."""
    section = Section()
    ignored = []
    for s in world_shapes(world):
        if s.proximity is None:
            continue
        if not isinstance(s.shape, SUPPORTED):
            ignored.append(f"{s.scoped_name} ({type(s.shape).__name__})")
            continue
        cut(s.shape, s.X_WG.rotation().matrix(), s.X_WG.translation(), height, section)
    warn_uncut(ignored, "the map section")
    return section
