"""amcl's particle filter (pf.c): a weighted set of poses with KLD-sampling, recovery by random
particles (Augmented MCL's w_slow and w_fast), and the clusters amcl reports its estimate from.
The update, the resampling and kld_limit: docs/localization.md.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numba import njit

#: amcl's histogram bin (pf_kdtree): x, y in metres and heading in radians
BIN_SIZE = (0.5, 0.5, 10.0 * math.pi / 180.0)
#: pf_update_converged: every particle within this of the mean in x and y
CONVERGED_DISTANCE = 0.5


def kld_limit(k: int, err: float, z: float, min_samples: int, max_samples: int) -> int:
    """The particles KLD-sampling needs with k occupied bins (docs/localization.md)."""
    if k < 1 or k > max_samples or k == 1:
        return max_samples
    b = 2.0 / (9.0 * (k - 1))
    x = 1.0 - b + math.sqrt(b) * z
    n = int(math.ceil((k - 1) / (2.0 * err) * x * x * x))
    return min(max(n, min_samples), max_samples)


@dataclass(frozen=True)
class Cluster:
    weight: float
    mean: np.ndarray  # x, y, heading in (-pi, pi]
    cov: np.ndarray  # 3x3: x, y block and the circular variance of the heading at [2, 2]
    count: int


class ParticleFilter:
    """`poses` (n, 3) and `weights` (n,) of the current set, and its statistics."""

    def __init__(
        self,
        min_samples: int,
        max_samples: int,
        alpha_slow: float,
        alpha_fast: float,
        pop_err: float,
        pop_z: float,
        random_poses: Callable[[int], np.ndarray],
        rng: np.random.Generator,
        selective_resampling: bool = False,
    ) -> None:
        self.min_samples, self.max_samples = int(min_samples), int(max_samples)
        self.alpha_slow, self.alpha_fast = float(alpha_slow), float(alpha_fast)
        self.random_poses, self.rng = random_poses, rng
        self.selective_resampling = selective_resampling
        self._limits = np.array(
            [
                kld_limit(k, pop_err, pop_z, self.min_samples, self.max_samples)
                for k in range(self.max_samples + 1)
            ],
            dtype=np.int64,
        )
        self.poses = np.zeros((self.max_samples, 3))
        self.weights = np.full(self.max_samples, 1.0 / self.max_samples)
        self.w_slow = self.w_fast = 0.0
        self.n_effective = 0.0
        self.converged = False
        self.clusters: list[Cluster] = []
        self.mean = np.zeros(3)
        self.cov = np.zeros((3, 3))

    def __len__(self) -> int:
        return len(self.poses)

    # -- initialisation --------------------------------------------------------------------
    def init_gaussian(self, mean, cov) -> None:
        """max_samples poses drawn from N(mean, cov) (cov 3x3; amcl diagonalises it)."""
        values, vectors = np.linalg.eigh(np.asarray(cov, dtype=float))
        sd = np.sqrt(np.clip(values, 0.0, None))
        draws = self.rng.standard_normal((self.max_samples, 3)) * sd
        self._reset(np.asarray(mean, dtype=float) + draws @ vectors.T)

    def init_uniform(self) -> None:
        """max_samples random poses on the map's free cells (global localisation)."""
        self._reset(self.random_poses(self.max_samples))

    def _reset(self, poses: np.ndarray) -> None:
        self.poses = np.ascontiguousarray(poses, dtype=float)
        self.weights = np.full(len(poses), 1.0 / len(poses))
        self.w_slow = self.w_fast = 0.0
        self.converged = False
        self.cluster_stats()

    # -- updates ---------------------------------------------------------------------------
    def update_sensor(self, weigh: Callable[[np.ndarray, np.ndarray], float]) -> None:
        """weigh(poses, weights) multiplies the weights in place and returns their total."""
        total = weigh(self.poses, self.weights)
        if total > 0.0:
            w_avg = float(self.weights.sum()) / len(self.weights)
            self.weights /= total
            self.n_effective = 1.0 / float(np.dot(self.weights, self.weights))
            self.w_slow = (
                w_avg if self.w_slow == 0.0 else self.w_slow + self.alpha_slow * (w_avg - self.w_slow)
            )
            self.w_fast = (
                w_avg if self.w_fast == 0.0 else self.w_fast + self.alpha_fast * (w_avg - self.w_fast)
            )
        else:
            self.weights[:] = 1.0 / len(self.weights)
            self.n_effective = math.inf

    def resample(self) -> None:
        if self.selective_resampling and self.n_effective > 0.5 * len(self.poses):
            self.weights = self.weights / self.weights.sum()
            self.cluster_stats()
            return
        n = self.max_samples
        w_diff = max(0.0, 1.0 - self.w_fast / self.w_slow) if self.w_slow > 0.0 else 0.0
        cum = np.concatenate([[0.0], np.cumsum(self.weights)])
        u_select = self.rng.random(n)
        if w_diff > 0.0:
            u_random = self.rng.random(n)
            pool = np.ascontiguousarray(self.random_poses(int(np.count_nonzero(u_random < w_diff))))
        else:
            u_random, pool = np.ones(0), np.zeros((0, 3))
        poses, count = _kld_resample(
            self.poses, cum, u_select, u_random, w_diff, pool, self._limits, *BIN_SIZE
        )
        if w_diff > 0.0:
            self.w_slow = self.w_fast = 0.0
        self.poses = poses[:count]
        self.weights = np.full(count, 1.0 / count)
        self.cluster_stats()
        self.update_converged()

    def update_converged(self) -> bool:
        """Whether every particle lies within CONVERGED_DISTANCE of the mean in x and in y."""
        self.converged = bool(_converged(self.poses, CONVERGED_DISTANCE))
        return self.converged

    # -- statistics ------------------------------------------------------------------------
    def cluster_stats(self) -> None:
        """The clusters of the current set, and its overall weighted mean and covariance."""
        labels, count = _cluster_labels(self.poses, *BIN_SIZE)
        stats = _cluster_sums(self.poses, self.weights, labels, count)
        self.clusters = []
        for c in range(count):
            w, n = stats[c, 0], int(stats[c, 9])
            m = stats[c, 1:5] / w
            cov = np.zeros((3, 3))
            cov[0, 0] = stats[c, 5] / w - m[0] * m[0]
            cov[0, 1] = cov[1, 0] = stats[c, 6] / w - m[0] * m[1]
            cov[1, 1] = stats[c, 8] / w - m[1] * m[1]
            cov[2, 2] = -2.0 * math.log(math.sqrt(stats[c, 3] ** 2 + stats[c, 4] ** 2) / w)
            self.clusters.append(Cluster(w, np.array([m[0], m[1], math.atan2(m[3], m[2])]), cov, n))
        tot = stats[:count].sum(axis=0)
        w = tot[0]
        m = tot[1:5] / w
        self.mean = np.array([m[0], m[1], math.atan2(m[3], m[2])])
        self.cov = np.zeros((3, 3))
        self.cov[0, 0] = tot[5] / w - m[0] * m[0]
        self.cov[0, 1] = self.cov[1, 0] = tot[6] / w - m[0] * m[1]
        self.cov[1, 1] = tot[8] / w - m[1] * m[1]
        self.cov[2, 2] = -2.0 * math.log(math.sqrt(tot[3] ** 2 + tot[4] ** 2))  # as amcl: not / w

    def best_cluster(self) -> Cluster | None:
        """The cluster of largest weight (the first of equals), as amcl publishes it."""
        best = None
        for c in self.clusters:
            if c.weight > 0.0 and (best is None or c.weight > best.weight):
                best = c
        return best


_OFFSET = 1 << 20
_MASK = (1 << 21) - 1


@njit(cache=True)
def _key(x, y, a, sx, sy, sa):
    kx = int(math.floor(x / sx)) + _OFFSET
    ky = int(math.floor(y / sy)) + _OFFSET
    ka = int(math.floor(a / sa)) + _OFFSET
    return ((kx & _MASK) << 42) | ((ky & _MASK) << 21) | (ka & _MASK)


@njit(cache=True)
def _insert(table, key):
    """Add key to the open-addressing set `table` (-1 = empty); True if it was new."""
    mask = table.shape[0] - 1
    h = (key ^ (key >> 21) ^ (key >> 42)) * 0x9E3779B1 & mask
    while True:
        if table[h] == -1:
            table[h] = key
            return True
        if table[h] == key:
            return False
        h = (h + 1) & mask


@njit(cache=True)
def _kld_resample(old, cum, u_select, u_random, w_diff, pool, limits, sx, sy, sa):
    n_old = old.shape[0]
    n_max = u_select.shape[0]
    size = 1
    while size < 4 * n_max:
        size *= 2
    table = np.full(size, -1, np.int64)
    out = np.empty((n_max, 3))
    bins = 0
    used_pool = 0
    m = 0
    while m < n_max:
        if w_diff > 0.0 and u_random[m] < w_diff:
            out[m] = pool[used_pool]
            used_pool += 1
        else:
            i = np.searchsorted(cum, u_select[m], side="right") - 1  # c[i] <= r < c[i + 1]
            i = min(max(i, 0), n_old - 1)
            out[m] = old[i]
        if _insert(table, _key(out[m, 0], out[m, 1], out[m, 2], sx, sy, sa)):
            bins += 1
        m += 1
        if m > limits[min(bins, limits.shape[0] - 1)]:
            break
    return out, m


_NEIGHBOURS = np.array(
    [
        (dx, dy, da)
        for dx in (-1, 0, 1)
        for dy in (-1, 0, 1)
        for da in (-1, 0, 1)
        if (dx, dy, da) != (0, 0, 0)
    ],
    dtype=np.int64,
)


@njit(cache=True)
def _cluster_labels(poses, sx, sy, sa):
    """Per particle the label of its cluster (bins joined through their 26 neighbours), and the
    number of clusters."""
    n = poses.shape[0]
    keys = np.empty(n, np.int64)
    for j in range(n):
        keys[j] = _key(poses[j, 0], poses[j, 1], poses[j, 2], sx, sy, sa)
    order = np.argsort(keys)
    sorted_keys = keys[order]
    uniq = np.empty(n, np.int64)
    bin_of = np.empty(n, np.int64)
    k = 0
    for t in range(n):
        if t == 0 or sorted_keys[t] != sorted_keys[t - 1]:
            uniq[k] = sorted_keys[t]
            k += 1
        bin_of[order[t]] = k - 1
    uniq = uniq[:k]
    label = np.full(k, -1, np.int64)
    stack = np.empty(k, np.int64)
    count = 0
    for start in range(k):
        if label[start] >= 0:
            continue
        label[start] = count
        top = 0
        stack[0] = start
        top = 1
        while top > 0:
            top -= 1
            b = stack[top]
            key = uniq[b]
            for t in range(_NEIGHBOURS.shape[0]):
                nk = key + (_NEIGHBOURS[t, 0] << 42) + (_NEIGHBOURS[t, 1] << 21) + _NEIGHBOURS[t, 2]
                pos = np.searchsorted(uniq, nk)
                if pos < k and uniq[pos] == nk and label[pos] < 0:
                    label[pos] = count
                    stack[top] = pos
                    top += 1
        count += 1
    out = np.empty(n, np.int64)
    for j in range(n):
        out[j] = label[bin_of[j]]
    return out, count


@njit(cache=True)
def _converged(poses, distance):
    n = poses.shape[0]
    mx = my = 0.0
    for j in range(n):
        mx += poses[j, 0]
        my += poses[j, 1]
    mx /= n
    my /= n
    for j in range(n):
        if abs(poses[j, 0] - mx) > distance or abs(poses[j, 1] - my) > distance:
            return False
    return True


@njit(cache=True)
def _cluster_sums(poses, weights, labels, count):
    """Per cluster: weight, sum w x, w y, w cos, w sin, w xx, w xy, w yx, w yy, particles."""
    s = np.zeros((count, 10))
    for j in range(poses.shape[0]):
        c = labels[j]
        w = weights[j]
        x, y = poses[j, 0], poses[j, 1]
        s[c, 0] += w
        s[c, 1] += w * x
        s[c, 2] += w * y
        s[c, 3] += w * math.cos(poses[j, 2])
        s[c, 4] += w * math.sin(poses[j, 2])
        s[c, 5] += w * x * x
        s[c, 6] += w * x * y
        s[c, 7] += w * y * x
        s[c, 8] += w * y * y
        s[c, 9] += 1.0
    return s
