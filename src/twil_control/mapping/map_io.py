"""ROS map files: the map_server / map_saver pair of an image (PGM) and a YAML description.

Pure: numpy, PyYAML, and OpenCV to decode images other than PGM. The grid (`OccupancyMap.data`)
is (height, width) int8 in nav_msgs/OccupancyGrid's order (row 0 at the origin's y); reading
follows map_server's rules and writing map_saver's, except that `image:` holds the file name
only, so the pair can be moved together (docs/slam.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from twil_control.errors import TwilControlError

from ..core.yaml_io import YamlError, load_yaml

OCCUPIED, FREE, UNKNOWN = 100, 0, -1
MODES = ("trinary", "scale", "raw")
REQUIRED = ("image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh")

#: map_saver's defaults: cells >= 65 are written occupied, cells 0..25 free.
SAVER_OCCUPIED, SAVER_FREE = 65, 25
SAVER_OCCUPIED_THRESH, SAVER_FREE_THRESH = 0.65, 0.196


class MapFileError(TwilControlError, ValueError):
    """A map YAML or image that cannot be read, or a grid that cannot be written."""


@dataclass
class OccupancyMap:
    data: np.ndarray  # (height, width) int8, row 0 at origin y
    resolution: float  # m per cell
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0)  # x, y, yaw of cell (0, 0)'s corner

    @property
    def height(self) -> int:
        return self.data.shape[0]

    @property
    def width(self) -> int:
        return self.data.shape[1]

    def cell_of(self, x: float, y: float) -> tuple[int, int]:
        """(row, column) of the cell holding world point (x, y) (origin yaw assumed 0)."""
        return (
            int(math.floor((y - self.origin[1]) / self.resolution)),
            int(math.floor((x - self.origin[0]) / self.resolution)),
        )

    def value_at(self, x: float, y: float) -> int:
        row, col = self.cell_of(x, y)
        if not (0 <= row < self.height and 0 <= col < self.width):
            raise IndexError(f"point ({x}, {y}) is outside the map")
        return int(self.data[row, col])


# -- images ------------------------------------------------------------------------------


def pixels_to_grid(
    pixels: np.ndarray,
    negate: bool,
    occupied_thresh: float,
    free_thresh: float,
    mode: str = "trinary",
    alpha: np.ndarray | None = None,
) -> np.ndarray:
    """map_server's conversion of image pixels (top row first) to grid values (row 0 bottom)."""
    if mode not in MODES:
        raise MapFileError(f"mode must be one of {', '.join(MODES)} (got {mode!r})")
    v = np.asarray(pixels, dtype=np.float64)
    if negate:
        v = 255.0 - v
    if mode == "raw":
        grid = v.astype(np.int64).astype(np.uint8).view(np.int8)
    else:
        p = (255.0 - v) / 255.0
        if mode == "trinary":
            middle = np.full(p.shape, UNKNOWN, dtype=np.int8)
        else:
            span = max(occupied_thresh - free_thresh, 1e-12)
            ratio = np.clip((p - free_thresh) / span, 0.0, 1.0)  # only used between the two
            middle = (1 + 98 * ratio).astype(np.int8)
            if alpha is not None:
                middle[np.asarray(alpha) < 1] = UNKNOWN
        grid = np.where(p > occupied_thresh, OCCUPIED, np.where(p < free_thresh, FREE, middle))
    return np.flipud(grid).astype(np.int8)


def grid_to_pixels(data: np.ndarray, occupied: int = SAVER_OCCUPIED, free: int = SAVER_FREE) -> np.ndarray:
    """map_saver's conversion of grid values (row 0 bottom) to PGM pixels (top row first)."""
    d = np.asarray(data).astype(np.int16)
    pixels = np.full(d.shape, 205, dtype=np.uint8)
    pixels[(d >= 0) & (d <= free)] = 254
    pixels[(d >= occupied) & (d <= 100)] = 0
    return np.flipud(pixels)


def write_pgm(path: str | Path, pixels: np.ndarray, comment: str = "") -> None:
    """Binary (P5) 8-bit PGM."""
    pixels = np.ascontiguousarray(pixels, dtype=np.uint8)
    head = "P5\n" + (f"# {comment}\n" if comment else "") + f"{pixels.shape[1]} {pixels.shape[0]}\n255\n"
    Path(path).write_bytes(head.encode("ascii") + pixels.tobytes())


def read_image(path: str | Path) -> tuple[np.ndarray, np.ndarray | None]:
    """(mean of the colour channels, alpha channel or None) of an image, top row first."""
    import cv2  # only for decoding; PGM P5 and PNG are what maps use

    img = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if img is None:
        raise MapFileError(f"cannot read map image {path} (missing, or not an image OpenCV decodes)")
    if img.dtype != np.uint8:
        raise MapFileError(f"map image {path} must have 8-bit channels (got {img.dtype})")
    if img.ndim == 2:
        return img.astype(np.float64), None
    if img.shape[2] in (2, 4):  # grey + alpha, BGR + alpha
        return img[:, :, :-1].mean(axis=2), img[:, :, -1]
    return img.mean(axis=2), None


# -- the YAML + image pair ---------------------------------------------------------------


def _number(meta: dict, key: str, where: str) -> float:
    value = meta[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise MapFileError(f"{where}: '{key}' must be a finite number (got {value!r})")
    return float(value)


def read_map(yaml_path: str | Path) -> OccupancyMap:
    """Load a map_server YAML and its image; errors name the file and the key."""
    yaml_path = Path(yaml_path)
    try:
        meta = load_yaml(yaml_path)
    except YamlError as error:
        raise MapFileError(f"cannot read map file: {error}") from None
    if not isinstance(meta, dict):
        raise MapFileError(f"{yaml_path}: a map file is a mapping with keys {', '.join(REQUIRED)}")
    missing = [k for k in REQUIRED if k not in meta]
    if missing:
        raise MapFileError(
            f"{yaml_path}: missing {', '.join(missing)} (a map file needs "
            f"{', '.join(REQUIRED)}; mode is optional)"
        )
    unknown = sorted(set(meta) - set(REQUIRED) - {"mode"})
    if unknown:
        raise MapFileError(
            f"{yaml_path}: unknown key(s) {', '.join(unknown)}; allowed: {', '.join(REQUIRED)}, mode"
        )
    where = str(yaml_path)
    resolution = _number(meta, "resolution", where)
    if resolution <= 0:
        raise MapFileError(f"{where}: 'resolution' must be > 0 m per cell (got {resolution})")
    origin = meta["origin"]
    if not (isinstance(origin, list) and len(origin) == 3):
        raise MapFileError(f"{where}: 'origin' must be a list [x, y, yaw] (got {origin!r})")
    origin = tuple(_number({"origin": o}, "origin", where) for o in origin)
    occ, free = _number(meta, "occupied_thresh", where), _number(meta, "free_thresh", where)
    if not 0 <= free <= occ <= 1:
        raise MapFileError(
            f"{where}: need 0 <= free_thresh <= occupied_thresh <= 1 "
            f"(got free_thresh {free}, occupied_thresh {occ})"
        )
    negate = meta["negate"]
    if isinstance(negate, float) or negate not in (0, 1):
        raise MapFileError(f"{where}: 'negate' must be 0 or 1 (got {negate!r})")
    mode = meta.get("mode", "trinary")
    if mode not in MODES:
        raise MapFileError(f"{where}: 'mode' must be one of {', '.join(MODES)} (got {mode!r})")
    image = Path(str(meta["image"]))
    if not image.is_absolute():
        image = yaml_path.parent / image
    pixels, alpha = read_image(image)
    data = pixels_to_grid(pixels, bool(negate), occ, free, mode, alpha)
    return OccupancyMap(data, resolution, origin)  # type: ignore[arg-type]


def write_map(
    grid: OccupancyMap, basename: str | Path, occupied: int = SAVER_OCCUPIED, free: int = SAVER_FREE
) -> tuple[Path, Path]:
    """Write basename.pgm and basename.yaml as map_saver does; returns (yaml, pgm) paths."""
    if not 0 <= free < occupied <= 100:
        raise MapFileError(f"need 0 <= free < occupied <= 100 (got free {free}, occupied {occupied})")
    data = np.asarray(grid.data)
    if data.ndim != 2 or data.size == 0:
        raise MapFileError(f"a map grid is a non-empty 2D array (got shape {data.shape})")
    base = Path(basename)
    pgm, yml = base.with_name(base.name + ".pgm"), base.with_name(base.name + ".yaml")
    write_pgm(
        pgm, grid_to_pixels(data, occupied, free), f"CREATOR: twil_control map_io {grid.resolution:.3f} m/pix"
    )
    x, y, yaw = grid.origin
    yml.write_text(
        f"image: {pgm.name}\nresolution: {grid.resolution:f}\n"
        f"origin: [{x:f}, {y:f}, {yaw:f}]\nnegate: 0\n"
        f"occupied_thresh: {SAVER_OCCUPIED_THRESH}\nfree_thresh: {SAVER_FREE_THRESH}\n"
    )
    return yml, pgm
