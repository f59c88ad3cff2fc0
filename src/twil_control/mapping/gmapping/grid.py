"""The particles' maps: gmapping-style hit counts per cell, stored in shared copy-on-write tiles.

As in gmapping, a particle's own map registers only the beam endpoints (its matcher runs with
map generation off): each cell keeps the number of endpoints that fell in it and their mean
position, which the scan matcher uses for sub-cell distances. Free space is traced only for the
published map (occupancy.py).

For the matcher's speed each cell also keeps a `near` bit mask: bit (ky + k)(2k + 1) + (kx + k)
is set when cell (x + kx, y + ky) holds endpoints, for |kx|, |ky| <= k = kernelSize. The matcher
then finds the candidate cells of a beam with two loads instead of a (2k + 1)^2 search. The masks
are kept up to date when a cell receives its first endpoint (kernelSize <= 2: 25 bits).

Memory is the constraint (80 particles): every particle's map is a small array of tile indices
into one shared pool of TILE x TILE cell blocks with reference counts. Resampling copies the
index arrays only; a particle writing into a tile that others still share first copies that one
tile (copy on write). All particles share one grid extent (origin and size in tiles), which
grows by whole tiles when scans reach beyond it.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

TILE_SHIFT = 4
TILE = 1 << TILE_SHIFT
TILE_MASK = TILE - 1
MAX_KERNEL = 2
GROW_MARGIN_TILES = 2      # extra tiles added around a growth, so growth is rare
_INITIAL_CAPACITY = 1024   # tiles in the pool at start; doubled when exhausted


class ParticleMaps:
    """Hit-count maps of `n` particles over a common, growing grid."""

    def __init__(self, n: int, xmin: float, ymin: float, xmax: float, ymax: float, delta: float,
                 kernel: int = 1) -> None:
        if not 0 <= kernel <= MAX_KERNEL:
            raise ValueError(f"kernelSize must be 0, 1 or 2 (got {kernel})")
        self.kernel = int(kernel)
        self.delta = float(delta)
        self.ox, self.oy = float(xmin), float(ymin)  # world position of cell (0, 0)'s corner
        ntx = max(1, math.ceil((xmax - xmin) / delta / TILE))
        nty = max(1, math.ceil((ymax - ymin) / delta / TILE))
        self.tiles = np.full((n, nty, ntx), -1, np.int32)
        cap = _INITIAL_CAPACITY
        self.hits = np.zeros((cap, TILE, TILE), np.int32)
        self.mean_x = np.zeros((cap, TILE, TILE), np.float32)  # mean endpoint, as an offset
        self.mean_y = np.zeros((cap, TILE, TILE), np.float32)  # from the cell centre (m)
        self.near = np.zeros((cap, TILE, TILE), np.uint32)     # the kernel's occupancy bits
        self.refcount = np.zeros(cap, np.int32)
        self.free = np.arange(cap - 1, -1, -1, dtype=np.int32)  # a stack; top = n_free - 1
        self.n_free = cap
        self.copies = 0  # tiles copied on write so far (for the memory/speed figures)

    # -- extent ------------------------------------------------------------------------
    @property
    def shape_cells(self) -> tuple[int, int]:
        """(rows, columns) of cells covered by the grid."""
        return self.tiles.shape[1] * TILE, self.tiles.shape[2] * TILE

    def ensure_inside(self, xmin: float, ymin: float, xmax: float, ymax: float) -> bool:
        """Grow the grid (whole tiles, plus a margin) so the box is inside; True if it grew."""
        span = TILE * self.delta
        nty, ntx = self.tiles.shape[1:]
        left = math.ceil(max(0.0, self.ox - xmin) / span)
        bottom = math.ceil(max(0.0, self.oy - ymin) / span)
        right = math.ceil(max(0.0, xmax - (self.ox + ntx * span)) / span)
        top = math.ceil(max(0.0, ymax - (self.oy + nty * span)) / span)
        if not (left or bottom or right or top):
            return False
        pad = [(l + GROW_MARGIN_TILES if l else 0) for l in (left, bottom, right, top)]
        self.tiles = np.pad(self.tiles, ((0, 0), (pad[1], pad[3]), (pad[0], pad[2])), constant_values=-1)
        self.ox -= pad[0] * span
        self.oy -= pad[1] * span
        return True

    # -- particles ---------------------------------------------------------------------
    def resample(self, indices: np.ndarray) -> None:
        """Particle i becomes a copy of particle indices[i]; tiles are shared, not copied."""
        self.tiles = np.ascontiguousarray(self.tiles[indices])
        used = self.tiles[self.tiles >= 0]
        self.refcount[:] = np.bincount(used, minlength=len(self.refcount)).astype(np.int32)
        free = np.flatnonzero(self.refcount == 0).astype(np.int32)[::-1]
        self.free[:len(free)] = free
        self.n_free = len(free)

    def register_hits(self, particle: int, pose, ex: np.ndarray, ey: np.ndarray) -> None:
        """Add beam endpoints (robot frame ex, ey) seen from `pose` to a particle's map."""
        start = 0
        while True:
            start, self.n_free, copies = _register_hits(
                self.tiles[particle], self.hits, self.mean_x, self.mean_y, self.near, self.refcount,
                self.free, self.n_free, self.ox, self.oy, self.delta, self.kernel, float(pose[0]),
                float(pose[1]), float(pose[2]), ex, ey, start)
            self.copies += copies
            if start >= len(ex):
                return
            self._grow_pool()

    def _grow_pool(self) -> None:
        cap = len(self.refcount)
        self.hits = np.concatenate([self.hits, np.zeros_like(self.hits)])
        self.mean_x = np.concatenate([self.mean_x, np.zeros_like(self.mean_x)])
        self.mean_y = np.concatenate([self.mean_y, np.zeros_like(self.mean_y)])
        self.near = np.concatenate([self.near, np.zeros_like(self.near)])
        self.refcount = np.concatenate([self.refcount, np.zeros(cap, np.int32)])
        free = np.empty(2 * cap, np.int32)
        free[:self.n_free] = self.free[:self.n_free]
        free[self.n_free:self.n_free + cap] = np.arange(2 * cap - 1, cap - 1, -1, dtype=np.int32)
        self.free = free
        self.n_free += cap

    # -- figures -----------------------------------------------------------------------
    def tiles_in_use(self) -> int:
        return int(np.count_nonzero(self.refcount))

    def memory_bytes(self) -> int:
        """Bytes of the tiles in use plus every particle's index array."""
        per_tile = sum(a[0].nbytes for a in (self.hits, self.mean_x, self.mean_y, self.near))
        return self.tiles_in_use() * per_tile + self.tiles.nbytes

    def dense_hits(self, particle: int) -> np.ndarray:
        """A particle's hit counts as one dense (rows, columns) array (tests, pictures)."""
        rows, cols = self.shape_cells
        out = np.zeros((rows, cols), np.int32)
        t = self.tiles[particle]
        for ty, tx in zip(*np.nonzero(t >= 0)):
            out[ty * TILE:(ty + 1) * TILE, tx * TILE:(tx + 1) * TILE] = self.hits[t[ty, tx]]
        return out


@njit(cache=True)
def _writable(tiles, hits, mean_x, mean_y, near, refcount, free, n_free, ty, tx):
    """The index of tile (ty, tx) of one particle, allocated (zeroed) when unknown and copied
    when shared. Returns (tile, n_free, copied); the caller guarantees a free tile."""
    t = tiles[ty, tx]
    if t < 0:
        n_free -= 1
        t = free[n_free]
        hits[t, :, :] = 0
        mean_x[t, :, :] = 0.0
        mean_y[t, :, :] = 0.0
        near[t, :, :] = 0
        refcount[t] = 1
        tiles[ty, tx] = t
        return t, n_free, 0
    if refcount[t] > 1:
        n_free -= 1
        u = free[n_free]
        hits[u, :, :] = hits[t, :, :]
        mean_x[u, :, :] = mean_x[t, :, :]
        mean_y[u, :, :] = mean_y[t, :, :]
        near[u, :, :] = near[t, :, :]
        refcount[t] -= 1
        refcount[u] = 1
        tiles[ty, tx] = u
        return u, n_free, 1
    return t, n_free, 0


@njit(cache=True)
def _register_hits(tiles, hits, mean_x, mean_y, near, refcount, free, n_free, ox, oy, delta,
                   kernel, x, y, th, ex, ey, start):
    """Add endpoints start.. to one particle's tiles; stops early (returning the index to resume
    from) when the pool runs short of free tiles. Returns (next index, n_free, tiles copied)."""
    c, s = math.cos(th), math.sin(th)
    inv = 1.0 / delta
    nty, ntx = tiles.shape
    width = 2 * kernel + 1
    copies = 0
    for i in range(start, ex.shape[0]):
        if n_free < 8:  # a cell and its kernel span at most 4 tiles
            return i, n_free, copies
        px = x + c * ex[i] - s * ey[i]
        py = y + s * ex[i] + c * ey[i]
        ix = int(math.floor((px - ox) * inv))
        iy = int(math.floor((py - oy) * inv))
        if ix < kernel or iy < kernel or ((iy + kernel) >> TILE_SHIFT) >= nty \
                or ((ix + kernel) >> TILE_SHIFT) >= ntx:
            continue  # the caller grows the grid first; a particle far off is simply clipped
        t, n_free, cp = _writable(tiles, hits, mean_x, mean_y, near, refcount, free, n_free,
                                  iy >> TILE_SHIFT, ix >> TILE_SHIFT)
        copies += cp
        cy, cx = iy & TILE_MASK, ix & TILE_MASK
        n = hits[t, cy, cx] + 1
        hits[t, cy, cx] = n
        mean_x[t, cy, cx] += (px - (ox + (ix + 0.5) * delta) - mean_x[t, cy, cx]) / n
        mean_y[t, cy, cx] += (py - (oy + (iy + 0.5) * delta) - mean_y[t, cy, cx]) / n
        if n > 1:
            continue
        # first endpoint in this cell: every cell within the kernel learns it has a neighbour here
        for ky in range(-kernel, kernel + 1):
            for kx in range(-kernel, kernel + 1):
                nx, ny = ix - kx, iy - ky
                u, n_free, cp = _writable(tiles, hits, mean_x, mean_y, near, refcount, free, n_free,
                                          ny >> TILE_SHIFT, nx >> TILE_SHIFT)
                copies += cp
                near[u, ny & TILE_MASK, nx & TILE_MASK] |= np.uint32(1) << np.uint32((ky + kernel) * width + kx + kernel)
    return ex.shape[0], n_free, copies
