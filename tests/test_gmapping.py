"""The gmapping filter on synthetic data: a room of segments ray-cast here with numpy.

Pinned down: the motion model's spread (srr..stt), the compiled score and moves against a
direct evaluation of gmapping's definition (kernel 0, 1, 2), the compiled climb against
gmapping's optimize loop scoring every neighbour, the scan matcher's capture of a
known offset, the SLAM's pose error against the odometry's on a loop, resampling only below the Neff
threshold, map growth beyond xmin..ymax (10 m past the scans, as gmapping's enlargeStep), and the linear/angular/temporal update gating.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from support.raycast_reference import cast_numpy

from twil_control.mapping.gmapping.filter import GMapping, ScanGeometry, ScanSizeError
from twil_control.mapping.gmapping.gmapping_params import GMappingParams
from twil_control.mapping.gmapping.grid import ParticleMaps
from twil_control.mapping.gmapping.matcher import matcher_for
from twil_control.mapping.gmapping.motion import compose, noise_sigmas, noisy_motion, relative_motion

# -- a synthetic world -------------------------------------------------------------------------


def _box(cx, cy, w, h):
    x0, x1, y0, y1 = cx - w / 2, cx + w / 2, cy - h / 2, cy + h / 2
    return [[x0, y0, x1, y0], [x1, y0, x1, y1], [x1, y1, x0, y1], [x0, y1, x0, y0]]


def room_segments() -> np.ndarray:
    """An 8 x 6 m room with a partition wall (a door in it) and three boxes."""
    s = _box(0.0, 0.0, 8.0, 6.0)
    s += [[0.5, -3.0, 0.5, -0.6], [0.5, 0.6, 0.5, 3.0]]
    s += _box(-2.8, 2.2, 0.8, 0.6) + _box(2.5, -2.2, 1.0, 0.5) + _box(2.8, 2.0, 0.6, 0.6)
    return np.array(s, float)


def cast(segs: np.ndarray, pose, angles: np.ndarray, max_range: float = 10.0) -> np.ndarray:
    """Ranges of beams from `pose` at robot-frame `angles` (inf beyond max_range)."""
    r = cast_numpy(*pose, angles, segs, np.empty((0, 3)))
    return np.where(r <= max_range, r, np.inf)


LASER_ANGLES = np.linspace(-2.26889, 2.26889, 640)  # the qbot's Hokuyo: 640 beams over 260 deg


def loop_path(rate: float = 10.0, speed: float = 0.5, turn_rate: float = 1.0) -> np.ndarray:
    """Poses at `rate` Hz around the room (through the door and back), turning on the spot."""
    way = [
        (-2.5, -1.8),
        (-2.5, 1.4),
        (-0.6, 1.4),
        (-0.6, 0.0),
        (1.6, 0.0),
        (1.6, 1.6),
        (3.0, 1.0),
        (3.0, -1.2),
        (1.6, -1.2),
        (1.6, 0.0),
        (-0.6, 0.0),
        (-0.6, -1.8),
        (-2.5, -1.8),
    ]
    out, th = [], math.atan2(way[1][1] - way[0][1], way[1][0] - way[0][0])
    for a, b in zip(way[:-1], way[1:]):
        a, b = np.array(a), np.array(b)
        goal = math.atan2(b[1] - a[1], b[0] - a[0])
        turn = (goal - th + math.pi) % (2 * math.pi) - math.pi
        n_turn = int(abs(turn) / (turn_rate / rate))
        out += [[a[0], a[1], th + turn * (k + 1) / max(n_turn, 1)] for k in range(n_turn)]
        th = goal
        n = int(np.linalg.norm(b - a) / (speed / rate))
        out += [[*(a + s * (b - a)), th] for s in np.arange(n) / n]
    return np.array(out)


def noisy_odometry(truth: np.ndarray, noise, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    odom = [truth[0]]
    for k in range(1, len(truth)):
        odom.append(compose(odom[-1], noisy_motion(relative_motion(truth[k], truth[k - 1]), *noise, rng)))
    return np.array(odom)


def small_params(**kw) -> GMappingParams:
    base = dict(
        particles=20,
        delta=0.05,
        maxUrange=9.9,
        maxRange=10.0,
        linearUpdate=0.3,
        angularUpdate=0.3,
        xmin=-1.0,
        ymin=-1.0,
        xmax=1.0,
        ymax=1.0,
    )
    base.update(kw)
    return GMappingParams(**base)


# -- motion model ------------------------------------------------------------------------------


def test_motion_noise_matches_srr_srt_str_stt():
    srr, srt, str_, stt = 0.1, 0.2, 0.15, 0.25
    delta = np.array([0.5, 0.1, 0.3])
    rng = np.random.default_rng(1)
    samples = noisy_motion(delta, srr, srt, str_, stt, rng, n=40000)
    expected = [
        srr * 0.5 + str_ * 0.3 + 0.3 * srr * 0.1,  # x: srr|dx| + str|dth| + 0.3 srr|dy|
        srr * 0.1 + str_ * 0.3 + 0.3 * srr * 0.5,  # y
        stt * 0.3 + srt * math.hypot(0.5, 0.1),
    ]  # theta: stt|dth| + srt|d|
    np.testing.assert_allclose(noise_sigmas(delta, srr, srt, str_, stt), expected, rtol=1e-12)
    np.testing.assert_allclose(samples.std(axis=0), expected, rtol=0.02)  # 40000 draws: ~0.4 % s.e.
    np.testing.assert_allclose(samples.mean(axis=0), delta, atol=0.01 * max(expected))


def test_motion_is_drawn_in_the_old_pose_frame():
    """A forward motion of a robot heading +y moves particles along +y, whatever their x."""
    rng = np.random.default_rng(0)
    from twil_control.mapping.gmapping.motion import sample_motion

    poses = np.array([[5.0, 1.0, math.pi / 2]] * 3)
    out = sample_motion(poses, [0.0, 0.0, 0.0], [-1.0, 0.0, 0.0], 0, 0, 0, 0, rng)  # odom +x by 1 m
    np.testing.assert_allclose(out, [[5.0, 2.0, math.pi / 2]] * 3, atol=1e-12)


# -- scan matcher ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "offset", [(0.10, 0.0, 0.0), (0.0, -0.08, math.radians(3)), (0.06, 0.05, math.radians(-3))]
)
def test_scan_matcher_recovers_a_known_offset(offset):
    """A map from 8 scans around a spot; a new scan from 3 nearby poses, the search started at
    the known offset from each: the pose comes back within a cell and half a degree."""
    segs = room_segments()
    p = GMappingParams(delta=0.025, kernelSize=1, lstep=0.05, astep=0.05, iterations=5)
    rng = np.random.default_rng(0)
    centre = np.array([-1.5, -0.5, 0.4])
    maps = ParticleMaps(1, -5, -4, 5, 4, p.delta, p.kernelSize)
    for _ in range(8):
        pose = centre + rng.uniform([-0.5, -0.5, -0.4], [0.5, 0.5, 0.4])
        r = cast(segs, pose, LASER_ANGLES)
        ok = np.isfinite(r)
        maps.register_hits(0, pose, (r * np.cos(LASER_ANGLES))[ok], (r * np.sin(LASER_ANGLES))[ok])
    m = matcher_for(p.kernelSize)
    for _ in range(3):
        seen_from = centre + rng.uniform([-0.3, -0.3, -0.3], [0.3, 0.3, 0.3])
        r = cast(segs, seen_from, LASER_ANGLES)
        ok = np.isfinite(r)
        a = LASER_ANGLES[ok]
        x, y, th, score = m.optimize(
            maps.tiles[0],
            maps.cells,
            maps.ox,
            maps.oy,
            maps.delta,
            *(seen_from + np.array(offset)),
            r[ok] * np.cos(a),
            r[ok] * np.sin(a),
            np.cos(a),
            np.sin(a),
            p.sigma,
            p.lsigma,
            p.lstep,
            p.astep,
            p.iterations,
        )
        assert math.hypot(x - seen_from[0], y - seen_from[1]) < p.delta  # within a cell
        assert abs(th - seen_from[2]) < math.radians(0.5)  # within half a degree
        assert score > 0.9 * ok.sum()  # nearly every beam matched


def _reference_climb(score, pose, lstep, astep, iterations):
    """gmapping's ScanMatcher::optimize loop, scoring every neighbour of every round (no pose
    skipped, nothing dropped early), with the matcher's move order x+, x-, y+, y-, th+, th-
    (gmapping's own order differs only in which of two exactly equal scores wins)."""
    cur_pose, cur = np.array(pose, float), score(pose)
    best, ld, ad, refinement = -1.0, lstep, astep, 0
    while True:
        if best >= cur:
            refinement += 1
            ld, ad = ld * 0.5, ad * 0.5
        best = cur
        moved = cur_pose
        for step in ([ld, 0, 0], [-ld, 0, 0], [0, ld, 0], [0, -ld, 0], [0, 0, ad], [0, 0, -ad]):
            candidate = cur_pose + np.array(step)
            s = score(candidate)
            if s > cur:
                cur, moved = s, candidate
        cur_pose = moved
        if not (cur > best or refinement < iterations):
            return cur_pose, cur


def _room_map(segs, centre, rng, delta, kernel) -> ParticleMaps:
    """One particle's map of 6 noisy scans from poses up to 40 cm and 0.3 rad around `centre`;
    the grid's origin is a fraction of a cell off the walls' metre lines."""
    maps = ParticleMaps(1, -5.0123, -4.0071, 5, 4, delta, kernel)
    for _ in range(6):
        pose = centre + rng.uniform([-0.4, -0.4, -0.3], [0.4, 0.4, 0.3])
        r = cast(segs, pose, LASER_ANGLES) + rng.normal(0, 0.01, len(LASER_ANGLES))
        ok = np.isfinite(r)
        maps.register_hits(0, pose, (r * np.cos(LASER_ANGLES))[ok], (r * np.sin(LASER_ANGLES))[ok])
    return maps


@pytest.mark.parametrize("kernel", [0, 1, 2])
def test_compiled_climb_equals_gmapping_optimize_loop(kernel):
    """The compiled climb (the opposite of the last move, poses scored before and hopeless moves
    left out) ends at the pose and score of gmapping's loop scoring every neighbour, from 6
    starts up to 15 cm and 6 degrees off (climbs that come back to poses they scored)."""
    segs, delta = room_segments(), 0.025
    p = GMappingParams(delta=delta, kernelSize=kernel, lstep=0.05, astep=0.05, iterations=5)
    rng = np.random.default_rng(10 + kernel)
    centre = np.array([-1.5, -0.5, 0.4])
    maps = _room_map(segs, centre, rng, delta, kernel)
    m = matcher_for(kernel)
    common = (maps.tiles[0], maps.cells, maps.ox, maps.oy, delta)
    r = cast(segs, centre, LASER_ANGLES) + rng.normal(0, 0.01, len(LASER_ANGLES))
    ok = np.isfinite(r)
    a = LASER_ANGLES[ok]
    beams = (r[ok] * np.cos(a), r[ok] * np.sin(a), np.cos(a), np.sin(a))
    score = lambda pose: m.score(*common, *pose, *beams, p.sigma, p.lsigma)[0]  # noqa: E731
    for _ in range(6):
        start = centre + rng.uniform([-0.15, -0.15, -0.1], [0.15, 0.15, 0.1])
        x, y, th, got = m.optimize(*common, *start, *beams, p.sigma, p.lsigma, p.lstep, p.astep, p.iterations)
        want_pose, want = _reference_climb(score, start, p.lstep, p.astep, p.iterations)
        np.testing.assert_allclose([x, y, th], want_pose, atol=1e-9)
        assert got == pytest.approx(want, rel=1e-9)


def _definition_score(hits, mx, my, ox, oy, delta, K, pose, bx, by, dx, dy, sigma, lsigma):
    """gmapping's score and likelihood straight from the definition (matcher.py's docstring),
    on dense hit counts and mean endpoints: no masks, no cache, no tiles."""
    x, y, th = pose
    c, s = math.cos(th), math.sin(th)
    px, py = x + c * bx - s * by, y + s * bx + c * by  # endpoints (world)
    fx, fy = (px - ox) / delta, (py - oy) / delta  # in cells
    gx = fx - math.sqrt(2.0) * (c * dx - s * dy)  # the free points
    gy = fy - math.sqrt(2.0) * (s * dx + c * dy)
    rows, cols = hits.shape

    def held(ix, iy):
        return 0 <= ix < cols and 0 <= iy < rows and hits[iy, ix] > 0

    score = lik = 0.0
    for i in range(len(bx)):
        ix, iy, jx, jy = (int(math.floor(v)) for v in (fx[i], fy[i], gx[i], gy[i]))
        d2 = [
            (px[i] - mx[iy + qy, ix + qx]) ** 2 + (py[i] - my[iy + qy, ix + qx]) ** 2
            for qy in range(-K, K + 1)
            for qx in range(-K, K + 1)
            if held(ix + qx, iy + qy) and not held(jx + qx, jy + qy)
        ]
        if d2:
            score += math.exp(-min(d2) / sigma)
            lik -= min(d2) / lsigma
        else:
            lik -= 0.5 / lsigma
    return score, lik


@pytest.mark.parametrize("kernel", [0, 1, 2])
def test_compiled_score_and_moves_equal_the_definition(kernel):
    """The compiled pass (bit masks, per-beam cache, distances measured during the lookup)
    gives gmapping's score and likelihood at a pose, and the scores of its six moves, to 1e-9
    relative, in a map of 6 scans seen from poses a few cm to 20 cm off (some beams match,
    some do not). The grid's origin is a fraction of a cell off the walls' metre lines and the
    ranges are noisy, so no endpoint sits on a cell border, where the last bit of rounding
    decides the cell."""
    segs, delta, sigma, lsigma = room_segments(), 0.025, 0.05, 0.075
    rng = np.random.default_rng(kernel)
    centre = np.array([-1.0, 0.3, 0.2])
    maps = _room_map(segs, centre, rng, delta, kernel)
    hits, (mx, my) = maps.dense_hits(0), maps.dense_means(0)
    m = matcher_for(kernel)
    ld, ad = 0.05, 0.05
    moves = np.array([[ld, 0, 0], [-ld, 0, 0], [0, ld, 0], [0, -ld, 0], [0, 0, ad], [0, 0, -ad]])
    for k in range(4):
        pose = centre + rng.uniform([-0.2, -0.2, -0.1], [0.2, 0.2, 0.1]) * (k / 3)
        r = cast(segs, centre, LASER_ANGLES) + rng.normal(0, 0.01, len(LASER_ANGLES))
        ok = np.isfinite(r)
        a = LASER_ANGLES[ok]
        beams = (r[ok] * np.cos(a), r[ok] * np.sin(a), np.cos(a), np.sin(a))
        common = (maps.tiles[0], maps.cells, maps.ox, maps.oy, delta)
        score, lik = m.score(*common, *pose, *beams, sigma, lsigma)
        want = _definition_score(hits, mx, my, maps.ox, maps.oy, delta, kernel, pose, *beams, sigma, lsigma)
        assert score == pytest.approx(want[0], rel=1e-9, abs=1e-9)
        assert lik == pytest.approx(want[1], rel=1e-9)
        out = np.empty(6)
        m.score_moves(*common, *pose, *beams, sigma, ld, ad, -1, -math.inf, out)
        want_moves = [
            _definition_score(
                hits, mx, my, maps.ox, maps.oy, delta, kernel, pose + mv, *beams, sigma, lsigma
            )[0]
            for mv in moves
        ]
        assert out == pytest.approx(want_moves, rel=1e-9, abs=1e-9)
        if k == 0:  # the pose the map was built around: most beams match
            assert score > 0.5 * ok.sum()


# -- the filter --------------------------------------------------------------------------------


def run_filter(params, truth, odom, seed=3, rate=10.0, record=None):
    slam = GMapping(params, ScanGeometry(LASER_ANGLES), np.random.default_rng(seed))
    segs, noise_rng = room_segments(), np.random.default_rng(seed + 100)
    est, ref, odo = [], [], []
    for k in range(len(truth)):
        r = cast(segs, truth[k], LASER_ANGLES) + noise_rng.normal(0, 0.01, len(LASER_ANGLES))
        if slam.process(odom[k], r, k / rate):
            est.append(slam.best_pose())
            ref.append(truth[k])
            odo.append(odom[k])
            if record is not None:
                record(slam)
    return slam, np.array(est), np.array(ref), np.array(odo)


def _pos_err(a, b):
    return np.hypot(a[:, 0] - b[:, 0], a[:, 1] - b[:, 1])


def test_slam_pose_error_is_well_below_the_odometry_error_on_a_loop():
    truth = loop_path()
    odom = noisy_odometry(truth, (0.05, 0.15, 0.05, 0.15), seed=7)
    params = small_params(srr=0.1, srt=0.3, str=0.1, stt=0.3)
    slam, est, ref, odo = run_filter(params, truth, odom)
    slam_err, odo_err = _pos_err(est, ref), _pos_err(odo, ref)
    # the estimate lives in the map frame, which starts at the first odometry pose = the truth's
    assert odo_err.max() > 0.3  # the odometry really drifts
    assert slam_err.max() < 0.10  # 2 cells at delta 0.05
    assert np.sqrt(np.mean(slam_err**2)) < 0.25 * np.sqrt(np.mean(odo_err**2))
    # the best particle's whole path (what the published map is built from) is as good
    scans, poses = slam.trajectory()
    np.testing.assert_array_equal(scans, np.arange(slam.count))
    assert _pos_err(poses, ref).max() < 0.10


@pytest.mark.parametrize("threshold", [0.0, 0.5, 0.9, 1.0])
def test_resampling_happens_only_when_neff_drops_below_the_threshold(threshold):
    truth = loop_path()[:120]
    odom = noisy_odometry(truth, (0.05, 0.15, 0.05, 0.15), seed=2)
    params = small_params(resampleThreshold=threshold, srr=0.1, srt=0.3, str=0.1, stt=0.3)
    seen = []

    def record(slam):
        seen.append((slam.neff, slam.resample_count))

    run_filter(params, truth, odom, record=record)
    previous = 0
    decided = 0
    for neff, count in seen[1:]:
        resampled = count - previous
        assert resampled == int(neff < threshold * params.particles), (neff, threshold)
        decided += resampled
        previous = count
    if threshold == 0.0:
        assert decided == 0
    if threshold == 1.0:
        assert decided == len(seen) - 1  # weights are never exactly equal: every update resamples


def test_map_grows_beyond_the_initial_bounds():
    truth = loop_path()[:40]
    params = small_params(xmin=-0.5, ymin=-0.5, xmax=0.5, ymax=0.5, particles=5)
    slam, *_ = run_filter(params, truth, truth)
    grid = slam.occupancy()
    rows, cols = grid.data.shape
    x_end, y_end = grid.origin_x + cols * grid.resolution, grid.origin_y + rows * grid.resolution
    assert grid.origin_x <= -4.0 and x_end >= 4.0 and grid.origin_y <= -3.0 and y_end >= 3.0
    # the room's outer walls are mapped where they are: x = -4 and y = -3
    occ_y, occ_x = np.nonzero(grid.data == 100)
    wx = grid.origin_x + (occ_x + 0.5) * grid.resolution
    wy = grid.origin_y + (occ_y + 0.5) * grid.resolution
    assert np.any(np.abs(wx + 4.0) < grid.resolution) and np.any(np.abs(wy + 3.0) < grid.resolution)
    assert ((grid.data == 0).sum()) > 1000  # free space traced along the beams


def test_grid_grows_ten_metres_past_the_scans_on_the_side_they_leave_it_as_gmapping_enlarges():
    """gmapping's computeActiveArea: a side the scans cross moves m_enlargeStep (10 m) past them
    (in whole tiles, 0.4 m here), the other sides stay, and a box inside changes nothing. The
    published map is this grid, so a goal a few metres past the seen walls is on the map."""
    delta = 0.025
    maps = ParticleMaps(2, -5.0, -5.0, 5.0, 5.0, delta)
    tile = 16 * delta
    x0, y0 = maps.ox, maps.oy
    rows, cols = maps.shape_cells
    y1 = y0 + rows * delta
    assert not maps.ensure_inside(-4.0, -4.0, 4.0, 4.0)
    assert maps.ensure_inside(-4.0, -4.0, 6.3, 4.0)
    rows, cols = maps.shape_cells
    assert (maps.ox, maps.oy) == (x0, y0)
    assert rows * delta + y0 == pytest.approx(y1)
    assert 6.3 + 10.0 <= maps.ox + cols * delta < 6.3 + 10.0 + tile + 1e-9
    assert maps.tiles.shape == (2, rows // 16, cols // 16)
    # below and left at once; the grown right side stays
    right = maps.ox + cols * delta
    assert maps.ensure_inside(-7.0, -5.5, 4.0, 4.0)
    rows, cols = maps.shape_cells
    assert -7.0 - 10.0 - tile - 1e-9 < maps.ox <= -7.0 - 10.0
    assert -5.5 - 10.0 - tile - 1e-9 < maps.oy <= -5.5 - 10.0
    assert maps.ox + cols * delta == pytest.approx(right)
    assert not maps.ensure_inside(-16.0, -15.0, 16.0, 4.0)


def test_kept_map_counts_equal_a_fresh_trace_through_resampling_growth_and_other_particles():
    """counts() keeps the last path's counts and traces only where a new path leaves it: it
    must give exactly what tracing the whole path again gives, after resampling changed the
    best particle's ancestry, after the grid grew, and for another particle's path."""
    truth = loop_path()[:160]
    odom = noisy_odometry(truth, (0.05, 0.15, 0.05, 0.15), seed=4)
    params = small_params(
        xmin=-0.5, ymin=-0.5, xmax=0.5, ymax=0.5, particles=8, srr=0.1, srt=0.3, str=0.1, stt=0.3
    )
    slam, *_ = run_filter(params, truth, odom, record=lambda slam: slam.counts())
    rows, cols = slam.maps.shape_cells
    assert slam.resample_count > 0 and cols * params.delta > 5.0  # both happened (from 1 m)

    def fresh(particle=None):
        slam._counts_cache = None
        return slam.counts(particle)

    for particle in (None, 0, params.particles - 1, None):
        incremental = slam.counts(particle)
        expected = fresh(particle)
        np.testing.assert_array_equal(incremental[0], expected[0])
        np.testing.assert_array_equal(incremental[1], expected[1])
        assert expected[0].sum() > 1000 and expected[1].sum() > expected[0].sum()
        slam.counts(1)  # leave another path in the cache for the next check


def _gating_run(params, steps, dt=0.1):
    slam = GMapping(params, ScanGeometry(LASER_ANGLES), np.random.default_rng(0))
    segs = room_segments()
    processed = []
    for k, pose in enumerate(steps):
        processed.append(slam.process(pose, cast(segs, pose, LASER_ANGLES), k * dt))
    return np.flatnonzero(processed)


def test_linear_update_gates_on_travelled_distance():
    steps = [[-2.5 + 0.1 * k, 0.0, 0.0] for k in range(16)]
    idx = _gating_run(small_params(linearUpdate=0.5, angularUpdate=10.0, particles=3), steps)
    np.testing.assert_array_equal(idx, [0, 5, 10, 15])


def test_angular_update_gates_on_accumulated_turning():
    steps = [[-2.0, 0.0, 0.1 * k * (-1) ** (k // 8)] for k in range(16)]
    idx = _gating_run(small_params(linearUpdate=10.0, angularUpdate=0.45, particles=3), steps)
    assert list(idx[:2]) == [0, 5]  # 0.1 rad per scan: the 5th reaches 0.5 >= 0.45
    assert len(idx) == 4  # |turn| accumulates through the change of direction too


def test_temporal_update_processes_a_still_robot_and_negative_disables_it():
    still = [[-2.0, 0.0, 0.0]] * 25
    idx = _gating_run(small_params(temporalUpdate=1.0, particles=3), still, dt=0.1)
    np.testing.assert_array_equal(idx, [0, 11, 22])  # strictly more than 1 s after the last
    idx = _gating_run(small_params(temporalUpdate=-1.0, particles=3), still, dt=0.1)
    np.testing.assert_array_equal(idx, [0])


def test_scan_of_another_size_is_refused_by_the_filter():
    slam = GMapping(small_params(particles=2), ScanGeometry(LASER_ANGLES), np.random.default_rng(0))
    with pytest.raises(ScanSizeError, match="639 ranges.*640"):
        slam.process([0, 0, 0], np.ones(639), 0.0)


def test_nan_ranges_are_beams_without_a_return():
    segs = room_segments()
    pose = np.array([-2.0, 0.0, 0.0])
    r = cast(segs, pose, LASER_ANGLES)
    r_nan = r.copy()
    r_nan[::2] = np.nan
    a = GMapping(small_params(particles=1), ScanGeometry(LASER_ANGLES), np.random.default_rng(0))
    b = GMapping(small_params(particles=1), ScanGeometry(LASER_ANGLES[1::2]), np.random.default_rng(0))
    a.process(pose, r_nan, 0.0)
    b.process(pose, r[1::2], 0.0)
    np.testing.assert_array_equal(a.occupancy().data, b.occupancy().data)


@pytest.mark.parametrize(
    "bad, message",
    [
        (dict(kernelSize=3), "kernelSize must be 0, 1 or 2"),
        (dict(particles=0), "particles must be >= 1"),
        (dict(resampleThreshold=1.5), "resampleThreshold must be in"),
        (dict(maxUrange=80.0, maxRange=60.0), "maxUrange .* must not exceed maxRange"),
        (dict(xmin=1.0, xmax=-1.0), "xmin < xmax"),
        (dict(delta=0.0), "delta must be a positive"),
    ],
)
def test_bad_parameters_are_named(bad, message):
    with pytest.raises(ValueError, match=message):
        replace(GMappingParams(), **bad)
