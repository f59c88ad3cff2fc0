"""amcl's filter, piece by piece, against values worked out by hand from amcl's formulas: the
odometry models' spread against odom_alpha1..5 (variances used as standard deviations in diff
and omni, their square roots in the -corrected models), the likelihood-field, likelihood-field-
prob and beam weights of hand-placed beams, the map's ray casting and distance cut-off, the KLD
bound and the resampled set's size, recovery particles, clusters, and the update gating."""

from __future__ import annotations

import math

import numpy as np
import pytest
from support.amcl_reference import calc_range_reference

from twil_control.localization.amcl_filter import Amcl, Scan, map_to_odom
from twil_control.localization.amcl_laser import (
    FLT_MAX,
    LaserData,
    LaserModel,
    LaserModelParams,
    calc_range,
    prepare_ranges,
)
from twil_control.localization.amcl_map import FREE, OCCUPIED, UNKNOWN, AmclMap
from twil_control.localization.amcl_odom import sample_motion
from twil_control.localization.amcl_params import AmclParams
from twil_control.localization.amcl_pf import ParticleFilter, kld_limit

pytestmark = pytest.mark.kernels

N = 200_000  # samples for the motion statistics: standard deviations within 0.5 %


def _moved(model, delta, alphas, start=(0.0, 0.0, 0.0), old_yaw=0.0, seed=0) -> np.ndarray:
    poses = np.tile(np.asarray(start, float), (N, 1))
    odom_pose = (delta[0], delta[1], old_yaw + delta[2])
    sample_motion(poses, model, delta, odom_pose, alphas, np.random.default_rng(seed))
    return poses


@pytest.mark.parametrize(
    "model, alphas",
    [("diff", (0.0, 0.02, 0.05, 0.0, 0.0)), ("diff-corrected", (0.0, 0.0004, 0.0025, 0.0, 0.0))],
)
def test_diff_models_straight_ahead_spread_as_alpha2_and_alpha3(model, alphas):
    # 1 m ahead: rot1 = rot2 = 0, trans = 1. sd(rot1) = sd(rot2) = a2 * 1 (diff) = sqrt(a2 * 1)
    # (corrected) = 0.02 rad; sd(trans) = a3 * 1 = sqrt(a3 * 1) = 0.05 m. Then x ~ trans (sd 0.05),
    # y ~ rot1 (sd 0.02 m at 1 m), heading = rot1 + rot2 (sd 0.02 sqrt 2).
    p = _moved(model, (1.0, 0.0, 0.0), alphas)
    assert p[:, 0].mean() == pytest.approx(1.0, abs=1e-3)
    assert p[:, 0].std() == pytest.approx(0.05, rel=0.01)
    assert p[:, 1].std() == pytest.approx(0.02, rel=0.01)
    assert p[:, 2].std() == pytest.approx(0.02 * math.sqrt(2), rel=0.01)


def test_diff_model_takes_alphas_as_variances_where_corrected_takes_their_roots():
    alphas = (0.0, 0.0, 0.01, 0.0, 0.0)  # diff: sd(trans) 0.01; corrected: sqrt(0.01) = 0.1
    assert _moved("diff", (1.0, 0.0, 0.0), alphas)[:, 0].std() == pytest.approx(0.01, rel=0.02)
    assert _moved("diff-corrected", (1.0, 0.0, 0.0), alphas)[:, 0].std() == pytest.approx(0.1, rel=0.01)


def test_diff_model_turning_in_place_spreads_as_alpha1_and_alpha4():
    # 0.5 rad on the spot: trans < 1 cm so rot1 = 0, rot2 = 0.5; sd(rot2) = a1 0.5^2 = 0.025,
    # sd(trans) = a4 (0 + 0.5^2) = 0.025, sd(rot1) = 0: the heading spreads by 0.025, x by 0.025.
    p = _moved("diff", (0.0, 0.0, 0.5), (0.1, 0.3, 0.3, 0.1, 0.0))
    assert p[:, 2].mean() == pytest.approx(0.5, abs=1e-3)
    assert p[:, 2].std() == pytest.approx(0.025, rel=0.01)
    assert p[:, 0].std() == pytest.approx(0.025, rel=0.01)
    assert p[:, 1].std() < 1e-12


def test_diff_model_spreads_driving_backwards_as_forwards():
    # 1 m backwards: rot1 = pi folds to 0, so the noise is the forward motion's
    p = _moved("diff", (-1.0, 0.0, 0.0), (0.0, 0.02, 0.05, 0.0, 0.0))
    assert p[:, 0].mean() == pytest.approx(-1.0, abs=1e-3)
    assert p[:, 0].std() == pytest.approx(0.05, rel=0.01)
    assert p[:, 1].std() == pytest.approx(0.02, rel=0.01)


@pytest.mark.parametrize(
    "model, alphas, sds",
    [
        # omni: sd(trans) = a3 t^2, sd(rot) = a2 t^2, sd(strafe) = a5 t^2 for t = 1, rot = 0
        ("omni", (0.0, 0.02, 0.05, 0.0, 0.03), (0.05, 0.03, 0.02)),
        # omni-corrected: sqrt(a3 t^2), sqrt(a2 t^2), sqrt(a5 t^2)
        ("omni-corrected", (0.0, 0.0004, 0.0025, 0.0, 0.0009), (0.05, 0.03, 0.02)),
    ],
)
def test_omni_models_spread_along_across_and_in_heading(model, alphas, sds):
    # a particle heading +y moves 1 m along its own heading (the odometry went 1 m along its x)
    p = _moved(model, (1.0, 0.0, 0.0), alphas, start=(0.0, 0.0, math.pi / 2))
    assert p[:, 1].mean() == pytest.approx(1.0, abs=1e-3)
    assert p[:, 1].std() == pytest.approx(sds[0], rel=0.01)  # along: trans
    assert p[:, 0].std() == pytest.approx(sds[1], rel=0.01)  # across: strafe
    assert p[:, 2].std() == pytest.approx(sds[2], rel=0.01)  # heading: rot


# -- laser models ------------------------------------------------------------------------------


def _dot_map() -> AmclMap:
    """20 x 20 cells of 0.1 m from (0, 0), one occupied cell (10, 10): centre (1.05, 1.05)."""
    state = np.full((20, 20), FREE, np.int8)
    state[10, 10] = OCCUPIED
    return AmclMap(state, 0.1)


# The particle at (0.45, 1.05) heading +y, the laser 0.1 m to its right: the laser sits at
# (0.55, 1.05). Beams (robot-frame bearing, range): -pi/2 0.5 m ends on the occupied cell (z = 0);
# 0 0.3 m ends in cell (5, 13): z = sqrt(5^2 + 3^2) 0.1 = 0.5831 m; pi/2 1.0 m ends off the
# map (z = max_occ_dist = 0.8); a max-range reading and a NaN are skipped.
POSE = np.array([[0.45, 1.05, math.pi / 2]])
BEARINGS = np.array([-math.pi / 2, 0.0, math.pi / 2, 0.0, 0.0])
RANGES = np.array([0.5, 0.3, 1.0, 5.0, np.nan])
LF = dict(z_hit=0.5, z_rand=0.5, sigma_hit=0.2, likelihood_max_dist=0.8, max_beams=5)


def _pz(z: float) -> float:
    return 0.5 * math.exp(-z * z / (2 * 0.2**2)) + 0.5 / 5.0  # z_rand / range_max


def _weigh(model: str, poses=POSE, ranges=RANGES, bearings=BEARINGS, grid=None, **kw) -> float:
    lm = LaserModel(LaserModelParams(model=model, **{**LF, **kw}), grid or _dot_map())
    w = np.ones(len(poses))
    total = lm.weigh(np.array(poses, float), w, LaserData(ranges, bearings, 5.0, 0.0, -0.1), False)
    assert total == pytest.approx(w.sum())
    return float(w[0])


def test_likelihood_field_weight_is_one_plus_the_sum_of_cubed_beam_probabilities():
    expected = 1.0 + _pz(0.0) ** 3 + _pz(math.sqrt(34) * 0.1) ** 3 + _pz(0.8) ** 3
    assert expected == pytest.approx(1.0 + 0.6**3 + 0.1071319**3 + 0.1001677**3, rel=1e-6)
    assert _weigh("likelihood_field") == pytest.approx(expected, rel=1e-12)


def test_likelihood_field_prob_weight_is_the_product_of_beam_probabilities():
    expected = _pz(0.0) * _pz(math.sqrt(34) * 0.1) * _pz(0.8)
    assert _weigh("likelihood_field_prob") == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize(
    "error_threshold, expected",
    [
        # beam 0 ends within beam_skip_distance (0.5) of an obstacle for every particle: kept; beams 1
        # (0.58 m) and 2 (off the map) for none: skipped, as are the two without a reading; 4 of 5
        # skipped is under 0.9 of them, so only beam 0 counts
        (0.9, _pz(0.0)),
        # ... but at or over 0.7 of them the filter may be lost: every beam counts
        (0.7, _pz(0.0) * _pz(math.sqrt(34) * 0.1) * _pz(0.8)),
    ],
)
def test_beam_skipping_keeps_the_beams_most_particles_agree_with(error_threshold, expected):
    params = LaserModelParams(
        model="likelihood_field_prob", do_beamskip=True, beam_skip_error_threshold=error_threshold, **LF
    )
    lm = LaserModel(params, _dot_map())
    w = np.ones(2)
    lm.weigh(np.vstack([POSE, POSE]), w, LaserData(RANGES, BEARINGS, 5.0, 0.0, -0.1), converged=True)
    assert w == pytest.approx([expected, expected], rel=1e-12)
    w = np.ones(2)  # before the filter has converged, no beam is skipped
    lm.weigh(np.vstack([POSE, POSE]), w, LaserData(RANGES, BEARINGS, 5.0, 0.0, -0.1), converged=False)
    assert w[0] == pytest.approx(_pz(0.0) * _pz(math.sqrt(34) * 0.1) * _pz(0.8), rel=1e-12)


def test_likelihood_field_uses_one_beam_in_step():
    # 5 beams, laser_max_beams 3: step (5 - 1) // (3 - 1) = 2: beams 0, 2 and 4 (4 is NaN)
    expected = 1.0 + _pz(0.0) ** 3 + _pz(0.8) ** 3
    assert _weigh("likelihood_field", max_beams=3) == pytest.approx(expected, rel=1e-12)


def test_distance_field_is_cut_off_beyond_max_occ_dist_in_whole_cells():
    grid = _dot_map()
    d = grid.distance_field(0.25)  # amcl's radius: int(0.25 / 0.1) = 2 cells
    assert d[10, 10] == 0.0
    assert d[10, 12] == pytest.approx(0.2)  # 2 cells
    assert d[11, 12] == 0.25  # sqrt(5) cells: beyond the radius
    assert d[10, 13] == 0.25
    assert d[11, 11] == pytest.approx(math.sqrt(2) * 0.1)


def _corridor() -> AmclMap:
    """40 x 10 cells of 0.1 m: a wall at column 30, an unknown cell at (5, 7), free elsewhere."""
    state = np.full((10, 40), FREE, np.int8)
    state[:, 30] = OCCUPIED
    state[7, 5] = UNKNOWN
    return AmclMap(state, 0.1)


def test_map_ranges_stop_at_walls_unknown_cells_and_the_edge():
    g = _corridor()
    rng = lambda x, y, a, m=5.0: calc_range(g.clearance(), 0.0, 0.0, 0.1, x, y, a, m)  # noqa: E731
    assert rng(0.55, 0.55, 0.0) == pytest.approx(2.5)  # cells 5 -> 30
    assert rng(0.55, 0.55, math.pi / 2) == pytest.approx(0.2)  # the unknown cell 2 up
    assert rng(0.55, 0.55, -math.pi / 2) == pytest.approx(0.6)  # off the map below row 0
    assert rng(0.55, 0.55, 0.0, 1.0) == 1.0  # free up to max range
    assert rng(1.55, 0.55, math.pi / 4) == pytest.approx(math.hypot(5, 5) * 0.1)  # the top edge diagonally
    assert rng(3.05, 0.55, 0.0) == 0.0  # inside the wall


def test_map_ranges_jumping_free_stretches_equal_amcl_s_cell_by_cell_walk():
    rng = np.random.default_rng(3)
    state = np.where(rng.random((60, 80)) < 0.03, OCCUPIED, FREE).astype(np.int8)
    state[rng.random((60, 80)) < 0.01] = UNKNOWN
    state[20:40, 30] = OCCUPIED
    g = AmclMap(state, 0.05, -1.0, 0.5)
    clear = g.clearance()
    for x, y, a, m in zip(
        rng.uniform(-1.5, 3.5, 3000),
        rng.uniform(0.0, 4.0, 3000),
        rng.uniform(-4, 4, 3000),
        rng.uniform(0, 6, 3000),
    ):
        got = calc_range(clear, -1.0, 0.5, 0.05, x, y, a, m)
        assert got == calc_range_reference(state, -1.0, 0.5, 0.05, x, y, a, m), (x, y, a, m)


def test_beam_model_weight_from_hit_short_and_max_readings():
    # laser at (0.55, 0.55) heading +x: the map says 2.5 m. Readings 2.5 (a hit), 2.0 (short),
    # 5.0 (range_max: no return). z_hit 0.5, z_short 0.05, z_max 0.05, z_rand 0.5, sigma 0.2,
    # lambda 0.1, range_max 5.
    pose = [[0.55, 0.65, 0.0]]  # the laser 0.1 m to the right
    ranges, bearings = np.array([2.5, 2.0, 5.0]), np.zeros(3)
    hit = 0.5 + 0.5 / 5
    short = 0.5 * math.exp(-0.25 / 0.08) + 0.05 * 0.1 * math.exp(-0.1 * 2.0) + 0.5 / 5
    none = 0.5 * math.exp(-6.25 / 0.08) + 0.05
    assert short == pytest.approx(0.1260621, rel=1e-6)
    kw = dict(z_short=0.05, z_max=0.05, lambda_short=0.1, max_beams=3)
    w = _weigh("beam", pose, ranges, bearings, _corridor(), **kw)
    assert w == pytest.approx(1.0 + hit**3 + short**3 + none**3, rel=1e-12)


def test_scan_ranges_are_read_as_amcl_node_reads_them():
    r = prepare_ranges(
        np.array([0.05, 0.08, 1.0, 10.0, 12.0, -np.inf, np.inf, np.nan], np.float32), 0.08, 10.0
    )
    assert r[:4].tolist() == [10.0, 10.0, 1.0, 10.0]  # <= range_min -> range_max
    assert r[4] == FLT_MAX and r[5] == 10.0 and r[6] == FLT_MAX
    assert math.isnan(r[7])


# -- the particle filter -----------------------------------------------------------------------


@pytest.mark.parametrize(
    "k, err, z, expected",
    [
        (2, 0.01, 0.99, 97),  # x = 1 - 2/9 + sqrt(2/9) 0.99 = 1.24447, 1/0.02 x^3 = 96.37
        (3, 0.01, 0.99, 182),  # x = 1 - 1/9 + 0.99/3 = 1.21889, 2/0.02 x^3 = 181.09
        (10, 0.02, 0.99, 326),  # x = 1.13087, 9/0.04 x^3 = 325.40
        (50, 0.05, 3.0, 842),  # x = 1.19750, 49/0.1 x^3 = 841.43
    ],
)
def test_kld_bound_is_fox_s_formula(k, err, z, expected):
    assert kld_limit(k, err, z, 1, 100_000) == expected


def test_kld_bound_clamps_and_asks_for_max_with_one_bin():
    assert kld_limit(1, 0.01, 0.99, 100, 5000) == 5000  # amcl: one bin -> max_samples
    assert kld_limit(2, 0.01, 0.99, 100, 5000) == 100  # 97 -> min_samples
    assert kld_limit(50, 0.01, 0.99, 100, 500) == 500
    assert kld_limit(0, 0.01, 0.99, 100, 500) == 500


def _pf(min_s=1, max_s=100_000, err=0.01, z=0.99, grid=None, seed=0) -> ParticleFilter:
    grid = grid or _dot_map()
    rng = np.random.default_rng(seed)
    return ParticleFilter(min_s, max_s, 0.001, 0.1, err, z, lambda n: grid.random_free_poses(rng, n), rng)


def test_resampling_stops_one_past_the_kld_bound_of_the_bins_it_filled():
    pf = _pf()
    pf.poses = np.array([[0.1, 0.1, 0.0], [3.1, 0.1, 0.0], [0.1, 3.1, 0.0]])  # three far-apart bins
    pf.weights = np.full(3, 1 / 3)
    pf.resample()
    assert len(pf) == kld_limit(3, 0.01, 0.99, 1, 100_000) + 1 == 183
    assert np.allclose(pf.weights, 1 / 183)
    assert len(pf.clusters) == 3


def test_resampling_draws_in_proportion_to_weight():
    pf = _pf(min_s=20_000, max_s=20_000)
    pf.poses = np.array([[0.1, 0.1, 0.0], [3.1, 0.1, 0.0]])
    pf.weights = np.array([0.8, 0.2])
    pf.resample()
    assert len(pf) == 20_000
    assert np.mean(pf.poses[:, 0] < 1.0) == pytest.approx(0.8, abs=0.01)


def test_recovery_draws_random_free_poses_in_proportion_to_one_minus_w_fast_over_w_slow():
    grid = _corridor()
    pf = _pf(min_s=4000, max_s=4000, grid=grid)
    pf.poses = np.array([[0.55, 0.55, 0.0]])
    pf.weights = np.ones(1)
    pf.w_slow, pf.w_fast = 1.0, 0.6  # w_diff = 0.4
    pf.resample()
    random = ~np.all(pf.poses == [0.55, 0.55, 0.0], axis=1)
    assert random.mean() == pytest.approx(0.4, abs=0.025)
    cells = np.floor(pf.poses[random, :2] / 0.1).astype(int)
    assert np.all(grid.occ_state[cells[:, 1], cells[:, 0]] == FREE)
    assert pf.w_slow == pf.w_fast == 0.0  # restarted after random particles


def test_w_slow_and_w_fast_follow_the_mean_likelihood_at_their_rates():
    pf = _pf()
    pf._reset(np.zeros((4, 3)))

    def times(factor):
        def weigh(poses, w):
            w *= factor
            return float(w.sum())

        return weigh

    pf.update_sensor(times(2.0))  # weights 1/4 each: mean likelihood 2 / 4 = 0.5, taken as is
    assert (pf.w_slow, pf.w_fast) == (0.5, 0.5)
    pf.update_sensor(times(4.0))  # mean 4 / 4 = 1.0
    assert pf.w_slow == pytest.approx(0.5 + 0.001 * 0.5)
    assert pf.w_fast == pytest.approx(0.5 + 0.1 * 0.5)
    assert np.allclose(pf.weights, 0.25)


def test_clusters_of_two_groups_and_the_heavier_one_as_the_estimate():
    pf = _pf()
    rng = np.random.default_rng(1)
    a = np.column_stack(
        [1.0 + 0.05 * rng.standard_normal(30), 1.0 + 0.05 * rng.standard_normal(30), np.full(30, 0.3)]
    )
    b = np.column_stack(
        [5.0 + 0.05 * rng.standard_normal(10), 5.0 + 0.05 * rng.standard_normal(10), np.full(10, -0.3)]
    )
    pf._reset(np.vstack([a, b]))
    assert len(pf.clusters) == 2
    best = pf.best_cluster()
    assert best.count == 30 and best.weight == pytest.approx(0.75)
    assert best.mean == pytest.approx([a[:, 0].mean(), a[:, 1].mean(), 0.3], abs=1e-12)
    assert best.cov[0, 0] == pytest.approx(a[:, 0].var(), rel=1e-9)
    assert pf.mean[:2] == pytest.approx(np.vstack([a, b])[:, :2].mean(axis=0))


def test_initial_particles_follow_the_given_covariance_with_correlation():
    pf = _pf(min_s=1, max_s=100_000)
    cov = np.array([[0.04, 0.03, 0.0], [0.03, 0.09, 0.0], [0.0, 0.0, 0.01]])
    pf.init_gaussian((1.0, 2.0, 0.5), cov)
    assert len(pf) == 100_000
    assert np.cov(pf.poses.T) == pytest.approx(cov, abs=2e-3)
    assert pf.poses.mean(axis=0) == pytest.approx([1.0, 2.0, 0.5], abs=3e-3)


# -- the filter as amcl_node drives it ---------------------------------------------------------


def _filter(**kw) -> Amcl:
    params = AmclParams(
        initial_cov_xx=0.0, initial_cov_yy=0.0, initial_cov_aa=0.0, min_particles=50, max_particles=50, **kw
    )
    return Amcl(params, _corridor(), np.random.default_rng(0))


SCAN = Scan(np.full(10, 2.0, np.float32), 0.1, 5.0, -0.5, 0.1)


@pytest.mark.parametrize(
    "odom, updates",
    [
        ((0.15, 0.15, 0.0), False),  # 0.21 m away, but under update_min_d in x and in y: amcl tests each axis
        ((0.21, 0.0, 0.0), True),
        ((0.0, 0.0, 0.6), True),  # over update_min_a = pi / 6
        ((0.0, 0.0, 0.5), False),
    ],
)
def test_the_filter_updates_once_the_odometry_moved_past_update_min_d_or_min_a(odom, updates):
    f = _filter()
    first = f.process((0.0, 0.0, 0.0), SCAN)
    assert first.updated and first.estimate is not None  # the first scan: a sensor update and a pose
    assert f.process(odom, SCAN).updated is updates


def test_a_no_motion_update_is_one_update_without_motion():
    f = _filter()
    f.process((0.0, 0.0, 0.0), SCAN)
    f.request_nomotion_update()
    assert f.process((0.0, 0.0, 0.0), SCAN).updated
    assert not f.process((0.0, 0.0, 0.0), SCAN).updated


def test_resample_interval_publishes_every_nth_update():
    f = _filter(resample_interval=3, update_min_d=0.0, update_min_a=0.0)
    f.process((0.0, 0.0, 0.0), SCAN)  # the first scan: update 1
    steps = [f.process((0.01 * k, 0.0, 0.0), SCAN) for k in range(1, 7)]
    assert [s.resampled for s in steps] == [False, True, False, False, True, False]
    assert all((s.estimate is not None) == s.resampled for s in steps)


def test_map_to_odom_puts_the_robot_at_the_estimate():
    est, odom = np.array([2.0, 1.0, 0.5]), np.array([0.3, -0.4, -1.0])
    mo = map_to_odom(est, odom)
    c, s = math.cos(mo[2]), math.sin(mo[2])
    robot = [mo[0] + c * odom[0] - s * odom[1], mo[1] + s * odom[0] + c * odom[1], mo[2] + odom[2]]
    assert robot == pytest.approx(est)
