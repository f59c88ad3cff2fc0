"""The SDF-world rasteriser (ground-truth maps) on the house world, and its pure core."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from twil_control import PACKAGE_ROOT
from twil_control.mapping import raycast
from twil_control.mapping.laser_model import LaserSpec
from twil_control.mapping.map_io import read_map
from twil_control.mapping.raster import rasterize
from twil_control.mapping.sections import Section, polygon_area
from twil_control.tools.rasterize import QBOT_SCAN_HEIGHT, main
from twil_control.world.world_section import world_section

pytestmark = pytest.mark.kernels

HOUSE = PACKAGE_ROOT / "sim/worlds/house.sdf"
RES = 0.05
# Points from the world table in sim/worlds/house.sdf.
WALLS = {
    "wall_a_mid": (-1.5, 0.0),
    "wall_north": (0.0, 5.0),
    "wall_b_mid": (2.0, -0.75),
    "wall_c_east": (-2.3, 0.5),
    "wall_e_east": (1.2, 3.0),
    "wall_west": (-5.0, -4.0),
}
FURNITURE = {
    "kitchen_table": (-3.2, -2.5),
    "hall_column": (0.25, -3.0),
    "plant_pot": (4.6, 0.6),
    "bed": (-4.2, 3.9),
    "sofa": (3.5, 4.4),
    "bathtub": (4.1, -4.5),
}
DOORWAYS = {
    "hall-bedroom": (-1.5, 2.3),
    "hall-kitchen": (-1.5, -2.5),
    "bedroom-kitchen": (-3.5, 0.5),
    "hall-living": (2.0, 1.5),
    "hall-bath": (2.0, -3.0),
    "living-bath": (4.0, -1.0),
    "hall-study": (0.0, 3.0),
}
ROOMS = {
    "hall": (0.0, 0.0),
    "bedroom": (-3.0, 2.0),
    "kitchen": (-3.0, -1.2),
    "living": (3.5, 1.0),
    "bath": (3.0, -3.0),
    "study": (0.0, 3.8),
}


@pytest.fixture(scope="module")
def house(tmp_path_factory):
    """The house rasterised through the CLI, read back with map_io, and its section."""
    out = tmp_path_factory.mktemp("house") / "house"
    assert main([str(HOUSE), "-o", str(out), "--resolution", str(RES)]) == 0
    return read_map(out.with_suffix(".yaml")), world_section(HOUSE, QBOT_SCAN_HEIGHT)


def test_walls_and_furniture_are_occupied_doorways_and_rooms_free(house):
    grid, _ = house
    for name, (x, y) in {**WALLS, **FURNITURE}.items():
        assert grid.value_at(x, y) == 100, name
    for name, (x, y) in {**DOORWAYS, **ROOMS}.items():
        assert grid.value_at(x, y) == 0, name
    # Wall faces on the grid lines: wall_a_mid (x -1.55 .. -1.45) is exactly two cells wide.
    assert [grid.value_at(x, 0.0) for x in (-1.575, -1.525, -1.475, -1.425)] == [0, 100, 100, 0]
    assert grid.value_at(0.0, 5.5) == 0  # the free margin outside the house


def test_occupied_area_matches_the_shapes(house):
    grid, section = house
    area = sum(polygon_area(p) for p in section.polygons) + float(
        np.sum(math.pi * section.circles[:, 2] ** 2)
    )
    outline = sum(float(np.sum(np.hypot(*(np.roll(p, -1, 0) - p).T))) for p in section.polygons) + float(
        np.sum(2 * math.pi * section.circles[:, 2])
    )
    occupied = np.count_nonzero(grid.data == 100) * RES**2
    print(f"house: {len(section)} shapes, area {area:.3f} m^2, rasterised {occupied:.3f} m^2")
    assert len(section.polygons) == 27 and len(section.circles) == 5
    # Conservative (outline cells count) but never more than a cell's width along the outlines.
    assert area <= occupied + 1e-9 <= area + outline * RES


def test_every_room_is_reachable_from_the_spawn(house):
    grid, _ = house
    occupied = (grid.data == 100).astype(np.uint8)
    # Grow obstacles by the qbot's half width (0.20 m with its wheels) plus half a cell: the
    # free cells left are where its centre line can pass.
    r = int(math.ceil((0.20 + RES / 2) / RES))
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1))
    free = (cv2.dilate(occupied, kernel) == 0).astype(np.uint8)
    _, labels = cv2.connectedComponents(free, connectivity=4)
    spawn = labels[grid.cell_of(0.0, 0.0)]
    assert spawn != 0
    for name, (x, y) in {**ROOMS, **DOORWAYS}.items():
        assert labels[grid.cell_of(x, y)] == spawn, name


def test_laser_endpoints_land_on_occupied_cells(house):
    grid, section = house
    spec = LaserSpec()
    for x, y, yaw in ((0.0, 0.0, 0.0), (-3.0, 2.0, 1.0), (3.5, 1.0, -2.0)):
        ranges = raycast.cast(
            x, y, yaw, spec.min_angle, spec.angle_increment, spec.samples, section.segments(), section.circles
        )
        assert np.all(np.isfinite(ranges))
        a = yaw + spec.angles()
        # a hair past the surface: inside the shape the beam hit
        px, py = x + (ranges + 1e-6) * np.cos(a), y + (ranges + 1e-6) * np.sin(a)
        values = [grid.value_at(u, v) for u, v in zip(px, py)]
        assert values.count(100) == len(values)


def test_a_wall_thinner_than_a_cell_still_shows_and_aligned_boxes_cover_their_cells():
    thin = np.array([[0.52, 0.0], [0.54, 0.0], [0.54, 1.0], [0.52, 1.0]])  # 2 cm thick
    square = np.array([[0.1, 0.1], [0.3, 0.1], [0.3, 0.2], [0.1, 0.2]])  # on the grid
    grid = rasterize(Section([thin, square]), 0.05, (0.0, 0.0), (1.0, 1.0)).data
    assert np.all(grid[:, 10] == 100) and np.all(grid[:, 9] == 0) and np.all(grid[:, 11] == 0)
    assert np.count_nonzero(grid[:, :9] == 100) == 4 * 2
    assert np.all(grid[2:4, 2:6] == 100)


def test_cli_rejects_bad_input(tmp_path, capsys):
    assert main([str(tmp_path / "missing.sdf"), "-o", str(tmp_path / "m")]) == 2
    assert "world file not found" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main([str(HOUSE), "-o", str(tmp_path / "m"), "--origin", "0", "0"])
    assert "give --origin and --size together" in capsys.readouterr().err
