"""gmapping's scan matcher: score and likelihood of a scan in a particle's hit map, and the
hill-climbing search for the pose that maximises the score (gmapping's ScanMatcher).

It is the filter's hot loop: one compiled pass over the beams scores all six neighbours of a
round, matchable cells are cached per beam between rounds, moves that can no longer win are
dropped, and the pass stays one compiled body (its helpers are inlined, not called: numba counts
array references atomically at every call, which serialises threads). The algorithm and why each
choice: docs/slam.md, "How the filter works". All particles are matched in one numba call,
optionally in threads.
"""

from __future__ import annotations

import functools
import math
import os
from typing import NamedTuple

import numpy as np
from numba import njit, prange, set_parallel_chunksize
from numba.cpython.unsafe.numbers import trailing_zeros

from twil_control.errors import InputError

from .grid import MAX_KERNEL, TILE, TILE_MASK, TILE_SHIFT, unpack_mean

# numba's threading layer here is OpenMP: GNU libgomp reads OMP_WAIT_POLICY once, when numba
# loads it at the first parallel call (not at import; pydrake's bundled libgomp is another copy and
# does not matter). By default each worker spins for a few milliseconds after the particles are
# matched, on the core that the filter's registration, the other
# nodes of a launch or another process need next; PASSIVE puts it to sleep at once (waking it at
# the next scan costs microseconds). Set here, at import and so before any parallel call, which
# covers launches too; a value already in the environment is kept.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

MAX_ROUNDS = 200  # a hill climb longer than this many rounds stops (a safety net)
FREE_CELL_RATIO = math.sqrt(2.0)  # the free point is this many cells back along the beam
MISS = 1e300  # squared distance of a beam without a matchable cell
MATCHED = 1e299  # squared distances below this are matches
N_MOVES = 6  # x + ld, x - ld, y + ld, y - ld, th + ad, th - ad
UNMOVED = 6  # slot of the pose itself in _evaluate's score vector
STALE = -1  # cache key of a beam whose cache holds nothing
SAME_POSE = 1e-9  # poses closer than this (m, rad) in every coordinate are the same pose
PRUNE_EVERY = 8  # beams between checks for moves that can no longer win (a power of 2)
# kernel bit k -> cell offset (k % W - K, k // W - K), W = 2K + 1, one row per kernel size K
KERNEL_DX = np.array([[k % (2 * K + 1) - K for k in range(32)] for K in range(MAX_KERNEL + 1)], np.int64)
KERNEL_DY = np.array([[k // (2 * K + 1) - K for k in range(32)] for K in range(MAX_KERNEL + 1)], np.int64)


@njit(cache=True, inline="always")
def _exp_neg(a):
    """exp(-a) for a >= 0: a Taylor polynomial below 0.125 (relative error < 1e-8), where
    nearly every matched beam lands, because math.exp costs as much as the rest of a beam."""
    if a < 0.125:
        return 1.0 - a * (1.0 - a * (0.5 - a * (1.0 / 6.0 - a * (1.0 / 24.0 - a / 120.0))))
    return math.exp(-a)


@njit(cache=True, inline="always")
def _keys(fx, fy, ux, uy):
    """The cells of an endpoint (fx, fy) (cell units from the grid's origin) and of its free
    point, back along the world direction (ux, uy); -1 off the grid's low side."""
    gx = fx - FREE_CELL_RATIO * ux
    gy = fy - FREE_CELL_RATIO * uy
    ix = int(fx) if fx >= 0.0 else -1
    iy = int(fy) if fy >= 0.0 else -1
    jx = int(gx) if gx >= 0.0 else -1
    jy = int(gy) if gy >= 0.0 else -1
    return ix, iy, jx, jy


@njit(cache=True, inline="always")
def _cache_key(ix, iy, jx, jy):
    """One integer for an endpoint cell and its free cell (the free cell is within 3 cells)."""
    return ((ix + 1) << 40) | ((iy + 1) << 16) | ((jx - ix + 8) << 8) | (jy - iy + 8)


class Matcher(NamedTuple):
    score: object  # (tiles, cells, ox, oy, delta, x, y, th, bx, by, dx, dy, sigma, lsigma)
    score_moves: object  # (..., sigma, ld, ad, skip, to_beat, out): the six neighbours' scores
    optimize: object  # (..., lstep, astep, iterations) -> (x, y, th, score)
    match_serial: object  # all particles: (poses, scores, log likelihoods)
    match_parallel: object


@njit(cache=True)
def new_cache(K, nb):
    """Per beam: cache key, number of matchable cells, their mean endpoints (x, y) relative
    to the endpoint cell's centre (a moved endpoint's cells are measured, not kept)."""
    nk = (2 * K + 1) ** 2
    return np.full(nb, STALE, np.int64), np.zeros(nb, np.int64), np.empty((nb, nk, 2))


@njit(cache=True, inline="always")
def _moved_endpoint(m, fx, fy, ux, uy, l, x0, y0, ex, ey, dxi, dyi, cp, sp, cm, sm):
    """A beam's endpoint (px, py) and world direction (vx, vy) after move m (UNMOVED: the pose
    itself); (fx, fy, ux, uy) are the unmoved ones, (ex, ey, dxi, dyi) the robot-frame ones."""
    if m == 0:
        return fx + l, fy, ux, uy
    if m == 1:
        return fx - l, fy, ux, uy
    if m == 2:
        return fx, fy + l, ux, uy
    if m == 3:
        return fx, fy - l, ux, uy
    if m == 4:
        return x0 + cp * ex - sp * ey, y0 + sp * ex + cp * ey, cp * dxi - sp * dyi, sp * dxi + cp * dyi
    if m == 5:
        return x0 + cm * ex - sm * ey, y0 + sm * ex + cm * ey, cm * dxi - sm * dyi, sm * dxi + cm * dyi
    return fx, fy, ux, uy


@njit(cache=True, inline="always")
def _tile_at(tiles, kx, ky):
    """The tile holding cell (kx, ky), -1 off the grid."""
    nty, ntx = tiles.shape
    if kx >= 0 and ky >= 0 and (ky >> TILE_SHIFT) < nty and (kx >> TILE_SHIFT) < ntx:
        return tiles[ky >> TILE_SHIFT, kx >> TILE_SHIFT]
    return -1


@njit(cache=True, inline="always")
def _matchable_bits(tiles, cells, t, kx, ky, kjx, kjy):
    """The kernel cells around (kx, ky) (in tile t) that hold endpoints while their
    counterpart around the free cell (kjx, kjy) holds none."""
    near = cells[t, ky & TILE_MASK, kx & TILE_MASK] & np.uint64(0xFFFFFFFF)
    if near == 0:
        return np.int64(0)
    same_tile = (kjx >> TILE_SHIFT) == (kx >> TILE_SHIFT) and (kjy >> TILE_SHIFT) == (ky >> TILE_SHIFT)
    u = t if same_tile else _tile_at(tiles, kjx, kjy)
    if u >= 0:  # drop cells whose counterpart around the free point holds endpoints
        near &= ~cells[u, kjy & TILE_MASK, kjx & TILE_MASK]
    return np.int64(near & np.uint64(0xFFFFFFFF))


@njit(cache=True, inline="always")
def _look_up(K, tiles, cells, kx, ky, kjx, kjy, ax, ay, r, nb, cxy):
    """(least squared distance from (ax, ay) to a matchable cell's mean endpoint, MISS without
    one; number of matchable cells), keeping their means in cache row r when r < nb."""
    best = MISS
    n = 0
    t = _tile_at(tiles, kx, ky)
    if t < 0:
        return best, n
    cx0, cy0 = kx & TILE_MASK, ky & TILE_MASK
    inside = K <= cx0 < TILE - K and K <= cy0 < TILE - K  # kernel within tile t
    bits = _matchable_bits(tiles, cells, t, kx, ky, kjx, kjy)
    while bits:  # over the set bits only
        k = trailing_zeros(bits)
        bits &= bits - 1
        qx, qy = KERNEL_DX[K, k], KERNEL_DY[K, k]
        if inside:
            word = cells[t, cy0 + qy, cx0 + qx]
        else:  # cells near a tile border (the caller grew the grid around them)
            gx, gy = kx + qx, ky + qy
            word = cells[tiles[gy >> TILE_SHIFT, gx >> TILE_SHIFT], gy & TILE_MASK, gx & TILE_MASK]
        mx, my = unpack_mean(word)
        mx += qx
        my += qy
        ddx, ddy = ax - mx, ay - my
        best = min(best, ddx * ddx + ddy * ddy)
        if r < nb:
            cxy[r, n, 0] = mx
            cxy[r, n, 1] = my
            n += 1
    return best, n


@njit(cache=True, inline="always")
def _cached_best(r, cn, cxy, ax, ay):
    """The least squared distance from (ax, ay) to the means kept in cache row r."""
    best = MISS
    for k in range(cn[r]):
        ddx = ax - cxy[r, k, 0]
        ddy = ay - cxy[r, k, 1]
        best = min(best, ddx * ddx + ddy * ddy)
    return best


@njit(cache=True, inline="always")
def _drop_losing_moves(alive, total, left, to_beat):
    """Drop the moves that cannot beat `to_beat` with `left` beams to go (each adds at most 1);
    whether any move, or the pose itself, is still scored."""
    any_alive = alive[UNMOVED]
    for m in range(N_MOVES):
        if alive[m] and total[m] + left <= to_beat:
            alive[m] = False
        any_alive = any_alive or alive[m]
    return any_alive


@njit(cache=True, fastmath=True)
def evaluate(
    K,
    tiles,
    cells,
    ox,
    oy,
    delta,
    x,
    y,
    th,
    bx,
    by,
    dx,
    dy,
    sigma,
    lsigma,
    ld,
    ad,
    active,
    to_beat,
    out,
    ckey,
    cn,
    cxy,
):
    """Scores of up to 7 poses in one pass over the beams (robot-frame endpoints bx, by,
    unit directions dx, dy): out[0..5] the six neighbours of (x, y, th), out[6] the pose
    itself, whose log likelihood is returned. active[m] says which to score; a neighbour
    that can no longer beat `to_beat` is dropped and gets -inf (the caller only wants the
    best neighbour above it, so that changes nothing)."""
    inv = 1.0 / delta
    ks, kl = delta * delta / sigma, delta * delta / lsigma
    l = ld * inv
    c, s = math.cos(th), math.sin(th)
    cp, sp = math.cos(th + ad), math.sin(th + ad)
    cm, sm = math.cos(th - ad), math.sin(th - ad)
    x0, y0 = (x - ox) * inv, (y - oy) * inv
    alive = active.copy()
    total = np.zeros(7)
    lik = 0.0
    nb = bx.shape[0]
    for i in range(nb):
        ex, ey = bx[i] * inv, by[i] * inv
        fx, fy = x0 + c * ex - s * ey, y0 + s * ex + c * ey
        ux, uy = c * dx[i] - s * dy[i], s * dx[i] + c * dy[i]
        ix, iy, jx, jy = _keys(fx, fy, ux, uy)
        fresh = ckey[i] == _cache_key(ix, iy, jx, jy)
        for m in range(7):
            if not alive[m]:
                continue
            px, py, vx, vy = _moved_endpoint(
                m, fx, fy, ux, uy, l, x0, y0, ex, ey, dx[i], dy[i], cp, sp, cm, sm
            )
            kx, ky, kjx, kjy = _keys(px, py, vx, vy)
            ax, ay = px - kx - 0.5, py - ky - 0.5
            if kx == ix and ky == iy and kjx == jx and kjy == jy:  # the beam's own cache row
                if fresh:
                    best = _cached_best(i, cn, cxy, ax, ay)
                else:
                    best, cn[i] = _look_up(K, tiles, cells, kx, ky, kjx, kjy, ax, ay, i, nb, cxy)
                    ckey[i] = _cache_key(kx, ky, kjx, kjy)
                    fresh = True
            else:  # a moved endpoint in other cells: measured, not kept
                best, _ = _look_up(K, tiles, cells, kx, ky, kjx, kjy, ax, ay, nb, nb, cxy)
            if best < MATCHED:
                total[m] += _exp_neg(best * ks)
                if m == UNMOVED:
                    lik -= best * kl
            elif m == UNMOVED:
                lik -= 0.5 / lsigma
        if (i & PRUNE_EVERY - 1) == PRUNE_EVERY - 1 and not _drop_losing_moves(
            alive, total, nb - 1 - i, to_beat
        ):
            break
    for m in range(7):
        out[m] = total[m] if alive[m] else -math.inf
    return lik


@njit(cache=True)
def score_cached(K, tiles, cells, ox, oy, delta, x, y, th, bx, by, dx, dy, sigma, lsigma, ckey, cn, cxy):
    active = np.zeros(7, np.bool_)
    active[UNMOVED] = True
    out = np.empty(7)
    lik = evaluate(
        K,
        tiles,
        cells,
        ox,
        oy,
        delta,
        x,
        y,
        th,
        bx,
        by,
        dx,
        dy,
        sigma,
        lsigma,
        0.0,
        0.0,
        active,
        -math.inf,
        out,
        ckey,
        cn,
        cxy,
    )
    return out[UNMOVED], lik


@njit(cache=True)
def score(K, tiles, cells, ox, oy, delta, x, y, th, bx, by, dx, dy, sigma, lsigma):
    """(score, log likelihood) of the beams seen from pose (x, y, th) in one particle's map."""
    ckey, cn, cxy = new_cache(K, bx.shape[0])
    return score_cached(
        K, tiles, cells, ox, oy, delta, x, y, th, bx, by, dx, dy, sigma, lsigma, ckey, cn, cxy
    )


@njit(cache=True)
def score_moves(K, tiles, cells, ox, oy, delta, x, y, th, bx, by, dx, dy, sigma, ld, ad, skip, to_beat, out):
    """Scores of the six hill-climbing neighbours of (x, y, th): out[0..5] for x + ld,
    x - ld, y + ld, y - ld, th + ad, th - ad; -inf for `skip` and for a move that cannot
    beat `to_beat`."""
    ckey, cn, cxy = new_cache(K, bx.shape[0])
    active = np.ones(7, np.bool_)
    active[UNMOVED] = False
    if skip >= 0:
        active[skip] = False
    res = np.empty(7)
    evaluate(
        K,
        tiles,
        cells,
        ox,
        oy,
        delta,
        x,
        y,
        th,
        bx,
        by,
        dx,
        dy,
        sigma,
        1.0,
        ld,
        ad,
        active,
        to_beat,
        res,
        ckey,
        cn,
        cxy,
    )
    out[:N_MOVES] = res[:N_MOVES]


@njit(cache=True)
def climb(
    K,
    tiles,
    cells,
    ox,
    oy,
    delta,
    x,
    y,
    th,
    bx,
    by,
    dx,
    dy,
    sigma,
    lsigma,
    lstep,
    astep,
    iterations,
    ckey,
    cn,
    cxy,
):
    """Hill climbing from (x, y, th): (x, y, th, score) of the best pose found. After a
    move, the opposite move (back to a pose known to be worse) is not evaluated again."""
    cur, _ = score_cached(
        K, tiles, cells, ox, oy, delta, x, y, th, bx, by, dx, dy, sigma, lsigma, ckey, cn, cxy
    )
    ld, ad = lstep, astep
    refinement = 0
    skip = -1
    active = np.zeros(7, np.bool_)
    scores = np.empty(7)
    seen = np.empty((N_MOVES * MAX_ROUNDS + 1, 3))  # every pose scored so far
    seen[0, 0], seen[0, 1], seen[0, 2] = x, y, th
    n_seen = 1
    for _round in range(MAX_ROUNDS):
        for m in range(N_MOVES):
            active[m] = m != skip
            if active[m]:  # a pose scored before cannot beat the current score (it only rises): not again
                mx = x + (ld if m == 0 else -ld if m == 1 else 0.0)
                my = y + (ld if m == 2 else -ld if m == 3 else 0.0)
                mt = th + (ad if m == 4 else -ad if m == 5 else 0.0)
                for k in range(n_seen):
                    if (
                        abs(seen[k, 0] - mx) < SAME_POSE
                        and abs(seen[k, 1] - my) < SAME_POSE
                        and abs(seen[k, 2] - mt) < SAME_POSE
                    ):
                        active[m] = False
                        break
                if active[m]:
                    seen[n_seen, 0], seen[n_seen, 1], seen[n_seen, 2] = mx, my, mt
                    n_seen += 1
        evaluate(
            K,
            tiles,
            cells,
            ox,
            oy,
            delta,
            x,
            y,
            th,
            bx,
            by,
            dx,
            dy,
            sigma,
            lsigma,
            ld,
            ad,
            active,
            cur,
            scores,
            ckey,
            cn,
            cxy,
        )
        best, best_move = cur, -1
        for move in range(N_MOVES):
            if active[move] and scores[move] > best:
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
            if refinement > iterations:  # as gmapping: `iterations` halvings, then a last
                break  # round at the finest step
            ld *= 0.5
            ad *= 0.5
    return x, y, th, cur


@njit(cache=True)
def optimize(
    K, tiles, cells, ox, oy, delta, x, y, th, bx, by, dx, dy, sigma, lsigma, lstep, astep, iterations
):
    ckey, cn, cxy = new_cache(K, bx.shape[0])
    return climb(
        K,
        tiles,
        cells,
        ox,
        oy,
        delta,
        x,
        y,
        th,
        bx,
        by,
        dx,
        dy,
        sigma,
        lsigma,
        lstep,
        astep,
        iterations,
        ckey,
        cn,
        cxy,
    )


@njit(cache=True)
def _match_particle(
    K,
    i,
    tiles3d,
    cells,
    ox,
    oy,
    delta,
    poses,
    bx,
    by,
    dx,
    dy,
    sigma,
    lsigma,
    lstep,
    astep,
    iterations,
    minimum_score,
    out,
    scores,
    liks,
):
    """Particle i's match (out[i], scores[i]) and the log likelihood at the pose kept (liks[i])."""
    ckey, cn, cxy = new_cache(K, bx.shape[0])
    x, y, th, sc = climb(
        K,
        tiles3d[i],
        cells,
        ox,
        oy,
        delta,
        poses[i, 0],
        poses[i, 1],
        poses[i, 2],
        bx,
        by,
        dx,
        dy,
        sigma,
        lsigma,
        lstep,
        astep,
        iterations,
        ckey,
        cn,
        cxy,
    )
    if sc > minimum_score:  # otherwise the match failed: keep the odometry's pose
        out[i, 0] = x
        out[i, 1] = y
        out[i, 2] = th
    scores[i] = sc
    _, liks[i] = score_cached(
        K,
        tiles3d[i],
        cells,
        ox,
        oy,
        delta,
        out[i, 0],
        out[i, 1],
        out[i, 2],
        bx,
        by,
        dx,
        dy,
        sigma,
        lsigma,
        ckey,
        cn,
        cxy,
    )


# the same loop twice, serial and in threads: two functions, as numba's disk cache keys a
# compiled function by its source, so one function compiled both ways would share one entry.
# Both release the GIL (nogil): slam_gmapping with a processing_latency matches on a worker
# thread while the simulation's Python runs on
@njit(cache=True, nogil=True)
def _match_serial(
    K,
    tiles3d,
    cells,
    ox,
    oy,
    delta,
    poses,
    bx,
    by,
    dx,
    dy,
    sigma,
    lsigma,
    lstep,
    astep,
    iterations,
    minimum_score,
):
    n = poses.shape[0]
    out, scores, liks = poses.copy(), np.zeros(n), np.zeros(n)
    for i in range(n):
        _match_particle(
            K,
            i,
            tiles3d,
            cells,
            ox,
            oy,
            delta,
            poses,
            bx,
            by,
            dx,
            dy,
            sigma,
            lsigma,
            lstep,
            astep,
            iterations,
            minimum_score,
            out,
            scores,
            liks,
        )
    return out, scores, liks


@njit(cache=True, parallel=True, nogil=True)
def _match_threads(
    K,
    tiles3d,
    cells,
    ox,
    oy,
    delta,
    poses,
    bx,
    by,
    dx,
    dy,
    sigma,
    lsigma,
    lstep,
    astep,
    iterations,
    minimum_score,
):
    n = poses.shape[0]
    out, scores, liks = poses.copy(), np.zeros(n), np.zeros(n)
    for i in prange(n):  # each particle reads only its own map and writes only its own row
        _match_particle(
            K,
            i,
            tiles3d,
            cells,
            ox,
            oy,
            delta,
            poses,
            bx,
            by,
            dx,
            dy,
            sigma,
            lsigma,
            lstep,
            astep,
            iterations,
            minimum_score,
            out,
            scores,
            liks,
        )
    return out, scores, liks


def _match_parallel(*args):
    """_match_all in numba threads, which take particles two at a time as they finish (not
    half the particles each: on a shared machine one thread may get less of a core)."""
    previous = set_parallel_chunksize(2)
    try:
        return _match_threads(*args)
    finally:
        set_parallel_chunksize(previous)


@functools.cache
def matcher_for(kernel: int) -> Matcher:
    """The scan matcher for one kernel size (0 .. MAX_KERNEL). The compiled functions take the
    kernel size as their first argument (module level, so numba caches them on disk: a
    launch does not spend seconds compiling them again); these bind it."""
    if not 0 <= kernel <= MAX_KERNEL:
        raise InputError(f"kernelSize must be between 0 and {MAX_KERNEL} (got {kernel})")
    k = int(kernel)
    return Matcher(
        *(functools.partial(f, k) for f in (score, score_moves, optimize, _match_serial, _match_parallel))
    )
