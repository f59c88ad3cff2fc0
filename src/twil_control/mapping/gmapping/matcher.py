"""gmapping's scan matcher: score and likelihood of a scan in a particle's hit map, and the
hill-climbing search for the pose that maximises the score.

For each beam endpoint p (and the point p_free, sqrt(2) cells back towards the sensor, which is
always in another cell), the cells within +-kernelSize of p are searched for the best match: a
cell holding endpoints whose counterpart around p_free holds none (so a beam never matches the
far side of a thin wall). The search reads the cells' `near` masks (grid.py):
candidates = near(p) & ~near(p_free). With d the distance from p to the matched cell's mean
endpoint:

    score      += exp(-d^2 / sigma)                       (only for matched beams)
    likelihood += -d^2 / lsigma   if matched,  -0.5 / lsigma otherwise

The search (gmapping's ScanMatcher::optimize) starts at the particle's predicted pose and tries
steps of +-lstep in x and y and +-astep in heading, moving to the best improving neighbour;
when none improves, the steps are halved; after `iterations` halvings it stops at the first
round that does not improve (gmapping's loop condition).

Speed (the filter's hot loop: about 50 scans evaluated per particle and processed scan): the six
neighbours of a hill-climbing round are scored in one pass over the beams (`score_moves`), so
the beam's transform is shared and the six lookups of a beam, a few cells apart, hit the same
cache lines; positions are worked in cell units; a cell is one 64-bit load (grid.py); the
kernel loop is unrolled (the functions are compiled once per kernel size, `matcher_for`) and
reads the neighbour cells from the endpoint's own tile unless the kernel crosses a tile border.
All particles are matched in one numba call, optionally in parallel threads (prange: each
particle reads only its own map).
"""
from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np
from numba import njit, prange

from .grid import MAX_KERNEL, TILE, TILE_MASK, TILE_SHIFT, unpack_mean

MAX_ROUNDS = 200  # a hill climb longer than this many rounds stops (a safety net)
FREE_CELL_RATIO = math.sqrt(2.0)  # the free point is this many cells back along the beam
MISS = 1e300
# the index of a 32-bit word's single set bit: multiply by a de Bruijn constant, top 5 bits
DEBRUIJN = 0x077CB531
BIT_INDEX = np.zeros(32, np.int64)
for _k in range(32):
    BIT_INDEX[(((1 << _k) * DEBRUIJN) & 0xFFFFFFFF) >> 27] = _k


@njit(cache=True, inline="always")
def _tile_at(tiles, ix, iy):
    if ix < 0 or iy < 0:
        return -1
    ty, tx = iy >> TILE_SHIFT, ix >> TILE_SHIFT
    if ty >= tiles.shape[0] or tx >= tiles.shape[1]:
        return -1
    return tiles[ty, tx]


@njit(cache=True, inline="always")
def _exp_neg(a):
    """exp(-a) for a >= 0: a Taylor polynomial below 0.125 (relative error < 1e-8), where
    nearly every matched beam lands, because math.exp costs as much as the rest of a beam."""
    if a < 0.125:
        return 1.0 - a * (1.0 - a * (0.5 - a * (1.0 / 6.0 - a * (1.0 / 24.0 - a / 120.0))))
    return math.exp(-a)


class Matcher(NamedTuple):
    score: object          # (tiles, cells, ox, oy, delta, x, y, th, bx, by, dx, dy, sigma, lsigma)
    score_moves: object    # (..., sigma, ld, ad, skip, to_beat, out): the six neighbours' scores
    optimize: object       # (..., lstep, astep, iterations) -> (x, y, th, score)
    match_serial: object   # all particles: (poses, scores, log likelihoods)
    match_parallel: object


@functools.cache
def matcher_for(kernel: int) -> Matcher:
    """The scan matcher compiled for one kernel size (0 .. MAX_KERNEL)."""
    if not 0 <= kernel <= MAX_KERNEL:
        raise ValueError(f"kernelSize must be between 0 and {MAX_KERNEL} (got {kernel})")
    K = int(kernel)
    W = 2 * K + 1
    NK = W * W

    @njit(inline="always")
    def keys(fx, fy, ux, uy):
        """The cells of an endpoint (fx, fy) (cell units from the grid's origin) and of its free
        point, back along the world direction (ux, uy); -1 off the grid's low side."""
        gx = fx - FREE_CELL_RATIO * ux
        gy = fy - FREE_CELL_RATIO * uy
        ix = int(fx) if fx >= 0.0 else -1
        iy = int(fy) if fy >= 0.0 else -1
        jx = int(gx) if gx >= 0.0 else -1
        jy = int(gy) if gy >= 0.0 else -1
        return ix, iy, jx, jy

    @njit(fastmath=True, inline="always")
    def candidates(tiles, cells, ix, iy, jx, jy, lx, ly):
        """The matchable cells around endpoint cell (ix, iy) with free cell (jx, jy): their mean
        endpoints, relative to the centre of cell (ix, iy), in lx, ly; returns their number."""
        t = _tile_at(tiles, ix, iy)
        if t < 0:
            return 0
        cx0, cy0 = ix & TILE_MASK, iy & TILE_MASK
        near = cells[t, cy0, cx0] & np.uint64(0xFFFFFFFF)
        if near == 0:
            return 0
        u = t if (jx >> TILE_SHIFT) == (ix >> TILE_SHIFT) and (jy >> TILE_SHIFT) == (iy >> TILE_SHIFT) \
            else _tile_at(tiles, jx, jy)
        if u >= 0:  # drop cells whose counterpart around the free point holds endpoints
            near &= ~cells[u, jy & TILE_MASK, jx & TILE_MASK]
        inside = K <= cx0 < TILE - K and K <= cy0 < TILE - K   # the kernel stays in tile t
        m = np.int64(near & np.uint64(0xFFFFFFFF))
        n = 0
        while m:   # over the set bits only (fewer unpredictable branches than testing all NK)
            low = m & -m
            k = BIT_INDEX[((low * DEBRUIJN) & 0xFFFFFFFF) >> 27]
            m ^= low
            kx = k % W - K
            ky = k // W - K
            if inside:
                word = cells[t, cy0 + ky, cx0 + kx]
            else:
                cx, cy = ix + kx, iy + ky
                word = cells[_tile_at(tiles, cx, cy), cy & TILE_MASK, cx & TILE_MASK]
            mx, my = unpack_mean(word)
            lx[n] = kx + mx
            ly[n] = ky + my
            n += 1
        return n

    @njit(fastmath=True, inline="always")
    def nearest(lx, ly, n, ax, ay):
        """Smallest squared distance from (ax, ay) to the n candidates, or MISS."""
        best = MISS
        for k in range(n):
            ddx = ax - lx[k]
            ddy = ay - ly[k]
            d2 = ddx * ddx + ddy * ddy
            if d2 < best:
                best = d2
        return best

    @njit(fastmath=True)
    def score(tiles, cells, ox, oy, delta, x, y, th, bx, by, dx, dy, sigma, lsigma):
        """(score, log likelihood) of the beams (robot-frame endpoints bx, by; unit
        directions dx, dy) seen from pose (x, y, th) in one particle's map."""
        inv = 1.0 / delta
        c, s = math.cos(th), math.sin(th)
        x0, y0 = (x - ox) * inv, (y - oy) * inv
        ks, kl = delta * delta / sigma, delta * delta / lsigma
        lx, ly = np.empty(NK), np.empty(NK)
        total = 0.0
        lik = 0.0
        for i in range(bx.shape[0]):
            ex, ey = bx[i] * inv, by[i] * inv
            fx, fy = x0 + c * ex - s * ey, y0 + s * ex + c * ey
            ix, iy, jx, jy = keys(fx, fy, c * dx[i] - s * dy[i], s * dx[i] + c * dy[i])
            n = candidates(tiles, cells, ix, iy, jx, jy, lx, ly)
            best = nearest(lx, ly, n, fx - ix - 0.5, fy - iy - 0.5)
            if best < 1e299:
                total += _exp_neg(best * ks)
                lik -= best * kl
            else:
                lik -= 0.5 / lsigma
        return total, lik

    @njit(fastmath=True)
    def score_moves(tiles, cells, ox, oy, delta, x, y, th, bx, by, dx, dy, sigma, ld, ad, skip,
                    to_beat, out):
        """Scores of the six hill-climbing neighbours of (x, y, th) in one pass over the beams:
        out[0..5] for x + ld, x - ld, y + ld, y - ld, th + ad, th - ad. A move whose score can
        no longer exceed `to_beat` (each remaining beam adds at most 1) is dropped and gets
        -inf, as does `skip`: the caller only wants the best move above `to_beat`, so dropping
        them changes nothing. The six endpoints of a beam often share the cell (and free cell)
        of the unmoved endpoint: its candidate cells are then looked up once."""
        inv = 1.0 / delta
        ks = delta * delta / sigma
        l = ld * inv
        mc, ms = np.empty(6), np.empty(6)
        mtx, mty = np.zeros(6), np.zeros(6)
        c, s = math.cos(th), math.sin(th)
        for m in range(4):
            mc[m], ms[m] = c, s
        mtx[0], mtx[1], mty[2], mty[3] = l, -l, l, -l
        mc[4], ms[4] = math.cos(th + ad), math.sin(th + ad)
        mc[5], ms[5] = math.cos(th - ad), math.sin(th - ad)
        x0, y0 = (x - ox) * inv, (y - oy) * inv
        alive = np.ones(6, np.bool_)
        if skip >= 0:
            alive[skip] = False
        total = np.zeros(6)
        lx, ly = np.empty(NK), np.empty(NK)   # candidates of the unmoved endpoint
        mx, my = np.empty(NK), np.empty(NK)   # of a moved one in another cell
        nb = bx.shape[0]
        for i in range(nb):
            ex, ey = bx[i] * inv, by[i] * inv
            fx, fy = x0 + c * ex - s * ey, y0 + s * ex + c * ey
            ux, uy = c * dx[i] - s * dy[i], s * dx[i] + c * dy[i]
            ix, iy, jx, jy = keys(fx, fy, ux, uy)
            n0 = -1
            for m in range(6):
                if not alive[m]:
                    continue
                if m < 4:
                    px, py, vx, vy = fx + mtx[m], fy + mty[m], ux, uy
                else:
                    px = x0 + mc[m] * ex - ms[m] * ey
                    py = y0 + ms[m] * ex + mc[m] * ey
                    vx = mc[m] * dx[i] - ms[m] * dy[i]
                    vy = ms[m] * dx[i] + mc[m] * dy[i]
                kx, ky, kjx, kjy = keys(px, py, vx, vy)
                if kx == ix and ky == iy and kjx == jx and kjy == jy:
                    if n0 < 0:
                        n0 = candidates(tiles, cells, ix, iy, jx, jy, lx, ly)
                    best = nearest(lx, ly, n0, px - kx - 0.5, py - ky - 0.5)
                else:
                    n = candidates(tiles, cells, kx, ky, kjx, kjy, mx, my)
                    best = nearest(mx, my, n, px - kx - 0.5, py - ky - 0.5)
                if best < 1e299:
                    total[m] += _exp_neg(best * ks)
            if (i & 31) == 31:   # drop the moves that cannot win any more
                left = nb - 1 - i
                any_alive = False
                for m in range(6):
                    if alive[m] and total[m] + left <= to_beat:
                        alive[m] = False
                    any_alive = any_alive or alive[m]
                if not any_alive:
                    break
        for m in range(6):
            out[m] = total[m] if alive[m] else -math.inf

    @njit
    def optimize(tiles, cells, ox, oy, delta, x, y, th, bx, by, dx, dy,
                 sigma, lsigma, lstep, astep, iterations):
        """Hill climbing from (x, y, th): (x, y, th, score) of the best pose found. After a
        move, the opposite move (back to a pose known to be worse) is not evaluated again."""
        cur, _ = score(tiles, cells, ox, oy, delta, x, y, th, bx, by, dx, dy, sigma, lsigma)
        ld, ad = lstep, astep
        refinement = 0
        skip = -1
        scores = np.zeros(6)
        for _round in range(MAX_ROUNDS):
            score_moves(tiles, cells, ox, oy, delta, x, y, th, bx, by, dx, dy, sigma, ld, ad, skip,
                        cur, scores)
            best, best_move = cur, -1
            for move in range(6):
                if move != skip and scores[move] > best:
                    best, best_move = scores[move], move
            if best_move >= 0:
                cur = best
                x += ld if best_move == 0 else -ld if best_move == 1 else 0.0
                y += ld if best_move == 2 else -ld if best_move == 3 else 0.0
                th += ad if best_move == 4 else -ad if best_move == 5 else 0.0
                skip = best_move ^ 1  # moves come in opposite pairs (0, 1), (2, 3), (4, 5)
            else:
                skip = -1
                refinement += 1
                if refinement > iterations:   # as gmapping: `iterations` halvings, then a last
                    break                      # round at the finest step

                ld *= 0.5
                ad *= 0.5
        return x, y, th, cur

    def match_all(tiles3d, cells, ox, oy, delta, poses, bx, by, dx, dy,
                  sigma, lsigma, lstep, astep, iterations, minimum_score):
        n = poses.shape[0]
        out = poses.copy()
        scores = np.zeros(n)
        liks = np.zeros(n)
        for i in prange(n):
            x, y, th, sc = optimize(tiles3d[i], cells, ox, oy, delta,
                                    poses[i, 0], poses[i, 1], poses[i, 2], bx, by, dx, dy,
                                    sigma, lsigma, lstep, astep, iterations)
            if sc > minimum_score:  # otherwise the match failed: keep the odometry's pose
                out[i, 0] = x
                out[i, 1] = y
                out[i, 2] = th
            scores[i] = sc
            _, liks[i] = score(tiles3d[i], cells, ox, oy, delta,
                               out[i, 0], out[i, 1], out[i, 2], bx, by, dx, dy, sigma, lsigma)
        return out, scores, liks

    return Matcher(score, score_moves, optimize, njit(match_all), njit(parallel=True)(match_all))
