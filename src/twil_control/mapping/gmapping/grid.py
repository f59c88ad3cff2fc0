"""The particles' maps: gmapping-style hit counts per cell, stored in shared copy-on-write tiles.

What the scan matcher reads is packed into one 64-bit word per cell (the `near` mask of the
kernel cells holding endpoints, and the mean endpoint's offset), so a beam costs one load per
cell it looks at. Memory is the constraint with 80 particles, so maps are index arrays into a
shared pool of reference-counted tiles, copied on write (docs/slam.md).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from twil_control.errors import InputError

TILE_SHIFT = 4
TILE = 1 << TILE_SHIFT
TILE_MASK = TILE - 1
MAX_KERNEL = 2
MEAN_SCALE = 65000.0  # mean offsets in [-0.5, 0.5] cell -> int16
NEAR_MASK = np.uint64(0xFFFFFFFF)
# how far past the scans a grid grows on the side they left it: gmapping's ScanMatcher
# m_enlargeStep (10 m; slam_gmapping leaves it at that), which its particle maps and the published
# map both grow by, so the map covers a goal some metres beyond what the laser has seen
ENLARGE_STEP = 10.0
_INITIAL_CAPACITY = 1024  # tiles in the pool at start; doubled when exhausted


class ParticleMaps:
    """Hit-count maps of `n` particles over a common, growing grid."""

    def __init__(
        self,
        n: int,
        xmin: float,
        ymin: float,
        xmax: float,
        ymax: float,
        delta: float,
        kernel: int = 1,
        enlarge_step: float = ENLARGE_STEP,
    ) -> None:
        if not 0 <= kernel <= MAX_KERNEL:
            raise InputError(f"kernelSize must be 0, 1 or 2 (got {kernel})")
        self.kernel = int(kernel)
        self.delta = float(delta)
        self.enlarge_step = float(enlarge_step)
        self.ox, self.oy = float(xmin), float(ymin)  # world position of cell (0, 0)'s corner
        ntx = max(1, math.ceil((xmax - xmin) / delta / TILE))
        nty = max(1, math.ceil((ymax - ymin) / delta / TILE))
        self.tiles = np.full((n, nty, ntx), -1, np.int32)
        cap = _INITIAL_CAPACITY
        self.cells = np.zeros((cap, TILE, TILE), np.uint64)  # near mask + packed mean (see above)
        self.hits = np.zeros((cap, TILE, TILE), np.int32)
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
        """Grow the grid so the box is inside; True if it grew. As gmapping's computeActiveArea
        does: a side the box crosses moves enlarge_step beyond the box, in whole tiles."""
        span = TILE * self.delta
        nty, ntx = self.tiles.shape[1:]
        beyond = (
            self.ox - xmin,
            self.oy - ymin,
            xmax - (self.ox + ntx * span),
            ymax - (self.oy + nty * span),
        )
        if max(beyond) <= 0.0:
            return False
        pad = [math.ceil((b + self.enlarge_step) / span) if b > 0.0 else 0 for b in beyond]
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
        self.free[: len(free)] = free
        self.n_free = len(free)

    def register_hits(self, particle: int, pose, ex: np.ndarray, ey: np.ndarray) -> None:
        """Add beam endpoints (robot frame ex, ey) seen from `pose` to a particle's map."""
        self.register_all(np.array([particle], np.int64), np.asarray(pose, float).reshape(1, 3), ex, ey)

    def register_all(self, particles: np.ndarray, poses: np.ndarray, ex: np.ndarray, ey: np.ndarray) -> None:
        """Add the same robot-frame endpoints to several particles' maps, each from its pose."""
        ex, ey = np.ascontiguousarray(ex, float), np.ascontiguousarray(ey, float)
        k, start = 0, 0
        while k < len(particles):
            k, start, self.n_free, copies = _register_all(
                self.tiles,
                self.cells,
                self.hits,
                self.refcount,
                self.free,
                self.n_free,
                self.ox,
                self.oy,
                self.delta,
                self.kernel,
                particles,
                poses,
                ex,
                ey,
                k,
                start,
            )
            self.copies += copies
            if k < len(particles):
                self._grow_pool()

    def _grow_pool(self) -> None:
        cap = len(self.refcount)
        self.cells = np.concatenate([self.cells, np.zeros_like(self.cells)])
        self.hits = np.concatenate([self.hits, np.zeros_like(self.hits)])
        self.refcount = np.concatenate([self.refcount, np.zeros(cap, np.int32)])
        free = np.empty(2 * cap, np.int32)
        free[: self.n_free] = self.free[: self.n_free]
        free[self.n_free : self.n_free + cap] = np.arange(2 * cap - 1, cap - 1, -1, dtype=np.int32)
        self.free = free
        self.n_free += cap

    # -- figures -----------------------------------------------------------------------
    def tiles_in_use(self) -> int:
        return int(np.count_nonzero(self.refcount))

    def memory_bytes(self) -> int:
        """Bytes of the tiles in use plus every particle's index array."""
        per_tile = self.cells[0].nbytes + self.hits[0].nbytes
        return self.tiles_in_use() * per_tile + self.tiles.nbytes

    def dense_hits(self, particle: int) -> np.ndarray:
        """A particle's hit counts as one dense (rows, columns) array (tests, pictures)."""
        rows, cols = self.shape_cells
        out = np.zeros((rows, cols), np.int32)
        t = self.tiles[particle]
        for ty, tx in zip(*np.nonzero(t >= 0)):
            out[ty * TILE : (ty + 1) * TILE, tx * TILE : (tx + 1) * TILE] = self.hits[t[ty, tx]]
        return out

    def dense_means(self, particle: int) -> tuple[np.ndarray, np.ndarray]:
        """A particle's mean endpoints (world x, y; NaN where no endpoint) as dense arrays."""
        rows, cols = self.shape_cells
        words = np.zeros((rows, cols), np.uint64)
        t = self.tiles[particle]
        for ty, tx in zip(*np.nonzero(t >= 0)):
            words[ty * TILE : (ty + 1) * TILE, tx * TILE : (tx + 1) * TILE] = self.cells[t[ty, tx]]
        qx = ((words >> np.uint64(32)) & np.uint64(0xFFFF)).astype(np.uint16).view(np.int16)
        qy = (words >> np.uint64(48)).astype(np.uint16).view(np.int16)
        iy, ix = np.mgrid[0:rows, 0:cols]
        mx = self.ox + (ix + 0.5 + qx / MEAN_SCALE) * self.delta
        my = self.oy + (iy + 0.5 + qy / MEAN_SCALE) * self.delta
        empty = self.dense_hits(particle) == 0
        mx[empty] = np.nan
        my[empty] = np.nan
        return mx, my


@njit(cache=True, inline="always")
def unpack_mean(word):
    """(x, y) offset of a cell's mean endpoint from its centre, in cells."""
    qx = np.int64((word >> np.uint64(32)) & np.uint64(0xFFFF))
    qy = np.int64((word >> np.uint64(48)) & np.uint64(0xFFFF))
    qx = (qx ^ 0x8000) - 0x8000
    qy = (qy ^ 0x8000) - 0x8000
    return qx * (1.0 / MEAN_SCALE), qy * (1.0 / MEAN_SCALE)


@njit(cache=True, nogil=True)  # runs on slam_gmapping's worker thread beside the simulation
def _register_all(
    tiles3d, cells, hits, refcount, free, n_free, ox, oy, delta, kernel, particles, poses, ex, ey, k0, start
):
    """Add endpoints to the maps of particles[k0:] (endpoint `start` on for the first); stops
    early when the pool runs short of free tiles. Returns (particle k, endpoint index to resume
    from, n_free, tiles copied).

    Each endpoint writes its own cell (count and mean) and, when it is the cell's first, the
    `near` bit of every cell within the kernel. A tile is made writable first: allocated
    (zeroed) when the particle has none there, copied when other particles share it. All in
    one function body: numba counts references (atomically) to every array passed to a call,
    which in this loop cost more than the work."""
    inv = 1.0 / delta
    width = 2 * kernel + 1
    n_kernel = width * width
    copies = 0
    for k in range(k0, particles.shape[0]):
        tiles = tiles3d[particles[k]]
        nty, ntx = tiles.shape
        x, y, th = poses[k, 0], poses[k, 1], poses[k, 2]
        c, s = math.cos(th), math.sin(th)
        first = start if k == k0 else 0
        for i in range(first, ex.shape[0]):
            if n_free < 16:  # a cell and its kernel span at most 4 tiles, each maybe copied
                return k, i, n_free, copies
            fx = (x + c * ex[i] - s * ey[i] - ox) * inv
            fy = (y + s * ex[i] + c * ey[i] - oy) * inv
            ix = int(math.floor(fx))
            iy = int(math.floor(fy))
            if (
                ix < kernel
                or iy < kernel
                or ((iy + kernel) >> TILE_SHIFT) >= nty
                or ((ix + kernel) >> TILE_SHIFT) >= ntx
            ):
                continue  # the caller grows the grid first; a particle far off is simply clipped
            # target j = -1: the endpoint's cell; j = 0 .. n_kernel - 1: the cells that learn
            # it holds endpoints (only after its first endpoint)
            todo = 0
            j = -1
            while j < todo:
                if j < 0:
                    cx, cy = ix, iy
                else:
                    cx, cy = ix - (j % width - kernel), iy - (j // width - kernel)
                ty, tx = cy >> TILE_SHIFT, cx >> TILE_SHIFT
                t = tiles[ty, tx]
                if t < 0:  # no tile yet: a zeroed one
                    n_free -= 1
                    t = free[n_free]
                    for a in range(TILE):
                        for b in range(TILE):
                            cells[t, a, b] = 0
                            hits[t, a, b] = 0
                    refcount[t] = 1
                    tiles[ty, tx] = t
                elif refcount[t] > 1:  # shared: copy on write
                    n_free -= 1
                    u = free[n_free]
                    for a in range(TILE):
                        for b in range(TILE):
                            cells[u, a, b] = cells[t, a, b]
                            hits[u, a, b] = hits[t, a, b]
                    refcount[t] -= 1
                    refcount[u] = 1
                    tiles[ty, tx] = u
                    t = u
                    copies += 1
                cy, cx = cy & TILE_MASK, cx & TILE_MASK
                if j < 0:
                    n = hits[t, cy, cx] + 1
                    hits[t, cy, cx] = n
                    word = cells[t, cy, cx]
                    mx, my = unpack_mean(word)
                    mx += (fx - (ix + 0.5) - mx) / n
                    my += (fy - (iy + 0.5) - my) / n
                    qx = np.uint64(np.int64(round(mx * MEAN_SCALE)) & 0xFFFF)
                    qy = np.uint64(np.int64(round(my * MEAN_SCALE)) & 0xFFFF)
                    cells[t, cy, cx] = (word & NEAR_MASK) | (qx << np.uint64(32)) | (qy << np.uint64(48))
                    if n == 1:
                        todo = n_kernel
                else:
                    cells[t, cy, cx] |= np.uint64(1) << np.uint64(j)
                j += 1
    return particles.shape[0], 0, n_free, copies
