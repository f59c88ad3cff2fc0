"""Command line: rasterise an SDF world's static geometry into a map_server map pair.

    python -m twil_control.tools.rasterize sim/worlds/house.sdf -o maps/house [--resolution 0.05]
        [--height 0.135] [--origin X Y] [--size W H] [--margin 0.5]

The ground truth SLAM maps are compared with. The world is cut by the simulated laser's own code,
so map and laser agree on every shape; the default height is qbot's scan plane.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..errors import InputError, exit_on_error
from ..mapping.map_io import write_map
from ..mapping.raster import default_extent, rasterize

#: The qbot's scan-plane height above the floor: base_link at rest 0.055 m + mount 0.08 m.
QBOT_SCAN_HEIGHT = 0.135


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m twil_control.tools.rasterize", description=(__doc__ or "").split("\n", 1)[0]
    )
    parser.add_argument("world", type=Path, help="SDF world file")
    parser.add_argument("-o", "--output", required=True, help="basename of the .pgm/.yaml pair")
    parser.add_argument("--resolution", type=float, default=0.05, help="m per cell (0.05)")
    parser.add_argument(
        "--height",
        type=float,
        default=QBOT_SCAN_HEIGHT,
        help=f"cutting plane z in m ({QBOT_SCAN_HEIGHT}: the qbot's scan plane)",
    )
    parser.add_argument(
        "--origin", type=float, nargs=2, metavar=("X", "Y"), help="map corner (cell (0, 0)'s lower-left) in m"
    )
    parser.add_argument("--size", type=float, nargs=2, metavar=("W", "H"), help="map size in m")
    parser.add_argument(
        "--margin",
        type=float,
        default=0.5,
        help="free border around the shapes when --origin/--size are not given",
    )
    args = parser.parse_args(argv)
    if not args.resolution > 0:
        parser.error(f"--resolution must be > 0 (got {args.resolution})")
    if (args.origin is None) != (args.size is None):
        parser.error("give --origin and --size together, or neither (extent from the world)")

    return exit_on_error(lambda: _rasterize(args))


def _rasterize(args: argparse.Namespace) -> int:
    from ..world.world_section import world_section  # Drake, only once the arguments are good

    section = world_section(args.world, args.height)
    if args.origin is None:
        try:
            origin, size = default_extent(section, args.resolution, args.margin)
        except InputError as error:
            raise InputError(f"{args.world} at z = {args.height} m: {error}") from None
    else:
        origin, size = tuple(args.origin), tuple(args.size)
    grid = rasterize(section, args.resolution, origin, size)
    out = Path(args.output)
    out.parent.mkdir(parents=True, exist_ok=True)
    yml, pgm = write_map(grid, out)
    occupied = int((grid.data == 100).sum())
    print(
        f"{args.world}: {len(section)} shapes at z = {args.height} m -> {grid.width} x "
        f"{grid.height} cells of {args.resolution} m, origin ({origin[0]:g}, {origin[1]:g}), "
        f"{occupied} occupied; wrote {yml} and {pgm}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
