"""Fractal dimensions of attractors: Kaplan–Yorke (Lyapunov) dimension and box counting."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numba import njit

from hysteresis._validation import (
    as_generator,
    bounded_work,
    finite_scalar,
    positive_integer,
    real_array,
)

#: most box sizes (the scaling-region search costs sizes³ line fits)
MAX_SIZES = 200
#: most grid placements per size
MAX_OFFSETS = 1000

__all__ = ["kaplan_yorke_dimension", "box_counting_dimension", "BoxCountingResult", "box_counts"]


def kaplan_yorke_dimension(exponents: Sequence[float] | np.ndarray) -> float:
    """Kaplan–Yorke dimension ``D_KY = j + Σ_{i<=j} λ_i / |λ_{j+1}|`` (paper eq. kaplan_yorke).

    ``j`` is the largest index with ``Σ_{i<=j} λ_i >= 0``. The exponents are sorted in descending
    order first; ``-inf`` is allowed (the play limit has one). If every partial sum is negative
    (a regular attractor with all exponents < 0) the dimension is 0; if all partial sums are
    non-negative the dimension is the number of exponents.
    """
    lam = real_array(exponents, "exponents")
    if lam.ndim != 1 or lam.size == 0:
        raise ValueError("exponents must be a non-empty 1-D sequence")
    if np.any(np.isnan(lam)) or np.any(lam == np.inf):
        raise ValueError("exponents must not contain NaN or +inf")
    lam = np.sort(lam)[::-1]
    partial = np.cumsum(lam)
    nonneg = np.nonzero(partial >= 0.0)[0]
    if nonneg.size == 0:
        return 0.0
    j = int(nonneg[-1]) + 1  # number of exponents in the expanding sum
    if j == lam.size:
        return float(lam.size)
    if np.isneginf(lam[j]):
        return float(j)
    return float(j + partial[j - 1] / abs(lam[j]))


# ---------------------------------------------------------------------------------------------
# Box counting
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class BoxCountingResult:
    """Outcome of :func:`box_counting_dimension`, with everything needed to judge the fit.

    Attributes
    ----------
    dimension:
        ``D_BC``, the slope of ``log N(ε)`` against ``log(1/ε)`` on the chosen scaling region.
    stderr:
        Standard error of that slope from the least-squares fit (statistical only; it does not
        include the systematic error of the finite scaling region).
    intercept:
        Intercept of the fit, ``log N ≈ intercept + dimension·log(1/ε)``.
    sizes:
        Every box size ε tried, in decreasing order.
    counts:
        Number of occupied boxes for each size (minimum or mean over grid placements).
    region:
        ``(start, stop)`` slice into ``sizes``/``counts`` of the scaling region used for the fit.
    local_slopes:
        Slopes between neighbouring sizes, ``Δlog N / Δlog(1/ε)`` (length ``len(sizes) - 1``).
    n_points:
        Number of (finite) points used.
    """

    dimension: float
    stderr: float
    intercept: float
    sizes: np.ndarray
    counts: np.ndarray
    region: tuple[int, int]
    local_slopes: np.ndarray
    n_points: int

    @property
    def fit_sizes(self) -> np.ndarray:
        """The box sizes of the scaling region."""
        return self.sizes[self.region[0] : self.region[1]]

    @property
    def fit_counts(self) -> np.ndarray:
        """The counts of the scaling region."""
        return self.counts[self.region[0] : self.region[1]]


def _as_points(points: np.ndarray) -> np.ndarray:
    pts = real_array(points, "points")
    if pts.ndim == 1:
        pts = pts[:, None]
    if pts.ndim != 2 or pts.shape[0] < 2 or pts.shape[1] < 1:
        raise ValueError(f"points must have shape (n, d) with n >= 2, got {np.shape(points)}")
    bad = ~np.all(np.isfinite(pts), axis=1)
    if np.any(bad):
        raise ValueError(
            f"points must be finite; row {int(np.argmax(bad))} (and {int(bad.sum()) - 1} more) "
            "contains NaN or inf"
        )
    return pts


def _occupied(cells: np.ndarray) -> int:
    """Number of distinct rows of the integer array ``cells`` (n, d).

    Rows are packed into one int64 key when the grid is small enough (the common case), which
    is much faster than ``np.unique(axis=0)``.
    """
    # column by column: numpy's axis-0 reduction of an (n, 2) array is ~40x slower
    span = np.array([cells[:, k].max() for k in range(cells.shape[1])]) + 1
    if np.prod(span.astype(float)) < 2.0**62:
        key = cells[:, 0].astype(np.int64)
        for k in range(1, cells.shape[1]):
            key = key * np.int64(span[k]) + cells[:, k]
        key.sort()  # distinct values of a sorted array: ~10x faster than np.unique's hashing
        return int(np.count_nonzero(key[1:] != key[:-1])) + 1
    return int(np.unique(cells, axis=0).shape[0])


@njit(cache=True)
def _occupied_grid(shifted: np.ndarray, shift: np.ndarray, e: float) -> int:
    """:func:`_occupied` of ``floor((shifted + shift) / e)`` (non-negative cells) in one
    compiled pass, without the temporaries; -1 if the packed key could overflow (the caller
    then counts with :func:`_occupied`). The same cells, so the same count."""
    n, d = shifted.shape
    cells = np.empty((n, d), dtype=np.int64)
    span = np.zeros(d, dtype=np.int64)
    for i in range(n):
        for k in range(d):
            c = np.int64(math.floor((shifted[i, k] + shift[k]) / e))
            cells[i, k] = c
            if c + 1 > span[k]:
                span[k] = c + 1
    total = 1.0
    for k in range(d):
        total *= float(span[k])
    if not total < 2.0**62:
        return -1
    key = cells[:, 0].copy()
    for k in range(1, d):
        key = key * span[k] + cells[:, k]
    count = 0
    if total <= 16.0 * n:  # coarse boxes: mark the occupied ones (keys repeat a lot)
        seen = np.zeros(int(total), dtype=np.bool_)
        for i in range(n):
            if not seen[key[i]]:
                seen[key[i]] = True
                count += 1
        return count
    key.sort()
    count = 1
    for i in range(1, n):
        if key[i] != key[i - 1]:
            count += 1
    return count


def box_counts(
    points: np.ndarray,
    sizes: Sequence[float] | np.ndarray,
    offsets: int = 1,
    seed: int | np.random.Generator = 0,
    reduce: str = "min",
) -> np.ndarray:
    """Number of boxes of side ε that contain at least one point, for each ε in ``sizes``.

    Plain reading: shift the points so the smallest coordinate is 0, add a grid offset drawn
    uniformly from ``[0, ε)`` per axis (none for the first offset), and count the distinct rows
    of ``floor(points / ε)``. With ``offsets > 1`` the count is the minimum (``reduce="min"``,
    nearest to the minimal cover) or the mean (``reduce="mean"``) over that many grids.
    """
    pts = _as_points(points)
    eps = real_array(sizes, "sizes")
    if eps.ndim != 1 or eps.size == 0 or np.any(~(eps > 0)) or not np.all(np.isfinite(eps)):
        raise ValueError("sizes must be a non-empty 1-D sequence of finite positive box sizes")
    bounded_work(eps.size, "sizes", MAX_SIZES, "box sizes")
    offsets = positive_integer(offsets, "offsets")
    bounded_work(offsets, "offsets", MAX_OFFSETS, "grid placements per size")
    if reduce not in ("min", "mean"):
        raise ValueError(f"reduce must be 'min' or 'mean', got {reduce!r}")
    rng = as_generator(seed)
    shifted = np.ascontiguousarray(pts - pts.min(axis=0), dtype=np.float64)
    no_shift = np.zeros(pts.shape[1])
    counts = np.empty(eps.size)
    for i, e in enumerate(eps):
        found = np.empty(offsets)
        for k in range(offsets):
            shift = no_shift if k == 0 else rng.uniform(0.0, e, size=pts.shape[1])
            count = _occupied_grid(shifted, shift, float(e))
            if count < 0:  # cells too many to pack into one int64 key
                count = _occupied(np.floor((shifted + shift) / e).astype(np.int64))
            found[k] = count
        counts[i] = found.min() if reduce == "min" else found.mean()
    return counts


def _typical_spacing(pts: np.ndarray, rng: np.random.Generator, sample: int = 2000) -> float:
    """Median nearest-neighbour distance among the points (a subsample for large sets)."""

    # deliberately lazy: scipy.spatial costs ~0.2 s at every `hyst` start
    from scipy.spatial import cKDTree

    tree = cKDTree(pts)
    idx = rng.choice(pts.shape[0], size=min(sample, pts.shape[0]), replace=False)
    dist, _ = tree.query(pts[idx], k=2)
    d = dist[:, 1]
    d = d[d > 0]
    if d.size == 0:
        return 0.0
    return float(np.median(d))


def _linear_fit(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float, np.ndarray]:
    """Least squares ``y = a + b x``; returns slope, its standard error, intercept, residuals."""
    n = x.size
    xm, ym = x.mean(), y.mean()
    sxx = np.sum((x - xm) ** 2)
    slope = float(np.sum((x - xm) * (y - ym)) / sxx)
    intercept = float(ym - slope * xm)
    resid = y - (intercept + slope * x)
    if n > 2:
        stderr = float(np.sqrt(np.sum(resid**2) / (n - 2) / sxx))
    else:
        stderr = float("nan")
    return slope, stderr, intercept, resid


def _scaling_region(
    x: np.ndarray, y: np.ndarray, usable: np.ndarray, min_points: int
) -> tuple[int, int]:
    """The contiguous window of usable sizes on which ``log N`` is most convincingly linear.

    Every window of at least ``min_points`` consecutive usable sizes is fitted by a straight
    line; the window with the smallest ``stderr(slope) / sqrt(span)`` wins, where ``span`` is the
    range of ``log 1/ε`` it covers. The standard error grows with curvature (the crossover to
    the coarse regime, the saturation at ``N ≈ n``), and the ``sqrt(span)`` factor prefers long
    windows, so that the oscillation of ``N(ε)`` with the grid phase of lacunar sets (Cantor
    sets) is averaged over rather than dodged by a short window.
    """
    idx = np.nonzero(usable)[0]
    if idx.size < 2:
        raise ValueError(
            "too few box sizes in the usable range (counts between the coarse limit and the "
            "point-number limit); give more points or explicit sizes"
        )
    # contiguous runs of usable indices
    runs: list[tuple[int, int]] = []
    start = idx[0]
    for a, b in zip(idx[:-1], idx[1:], strict=False):
        if b != a + 1:
            runs.append((start, a + 1))
            start = b
    runs.append((start, idx[-1] + 1))

    best: tuple[float, int, int] | None = None
    for lo, hi in runs:
        m = min(min_points, hi - lo)
        if m < 2:
            continue
        for i in range(lo, hi - m + 1):
            for j in range(i + m, hi + 1):
                if j - i > 2:
                    _, stderr, _, _ = _linear_fit(x[i:j], y[i:j])
                else:
                    stderr = np.inf  # two points: no error estimate, use only as a last resort
                span = float(x[j - 1] - x[i])
                key = stderr / np.sqrt(span) if np.isfinite(stderr) else np.inf
                if best is None or key < best[0] or (key == best[0] and j - i > best[2] - best[1]):
                    best = (key, i, j)
    if best is None:
        raise ValueError("no window of at least 2 consecutive usable box sizes")
    return best[1], best[2]


def box_counting_dimension(
    points: np.ndarray,
    sizes: Sequence[float] | np.ndarray | None = None,
    *,
    n_sizes: int = 24,
    offsets: int = 4,
    reduce: str = "min",
    max_fill: float = 0.1,
    min_boxes: float = 8.0,
    min_points: int = 5,
    seed: int | np.random.Generator = 0,
) -> BoxCountingResult:
    """Box-counting (capacity) dimension ``D_0 = lim log N(ε) / log(1/ε)`` (paper eq.
    box_counting) of a point set, with the linear scaling region chosen automatically.

    Parameters
    ----------
    points:
        Array (n, d) of points on the attractor, e.g. a Poincaré section ``(q, v)``.
    sizes:
        Box sizes ε to use. By default ``n_sizes`` log-spaced sizes from the attractor extent
        (largest coordinate range) down to the median nearest-neighbour spacing.
    n_sizes:
        Number of automatic sizes.
    offsets:
        Number of grid placements per size: the grid anchored at the minimum corner plus
        ``offsets - 1`` random shifts.
    reduce:
        ``"min"`` (default) keeps the smallest count over the placements, the closest to the
        minimal cover that defines ``N(ε)`` (random shifts of a mean count add partially filled
        edge boxes, which biases the slope low at coarse scales); ``"mean"`` averages them.
    max_fill:
        Sizes whose count exceeds ``max_fill · n`` are not used in the fit: there the boxes hold
        so few points that empty boxes are undersampled and the count saturates at ``n``.
    min_boxes:
        Sizes larger than ``extent / min_boxes`` are not used in the fit (too coarse).
    min_points:
        Minimum number of sizes in the scaling region.
    seed:
        Seed or generator for the grid offsets and the nearest-neighbour subsample.

    Returns
    -------
    BoxCountingResult
        Dimension, slope standard error, intercept, all sizes and counts, the chosen region.
    """
    pts = _as_points(points)
    n = pts.shape[0]
    max_fill = finite_scalar(max_fill, "max_fill")
    min_boxes = finite_scalar(min_boxes, "min_boxes")
    min_points = positive_integer(min_points, "min_points")
    n_sizes = positive_integer(n_sizes, "n_sizes")
    bounded_work(n_sizes, "n_sizes", MAX_SIZES, "box sizes")
    if not 0.0 < max_fill <= 1.0:
        raise ValueError(f"max_fill must be in (0, 1], got {max_fill}")
    if min_boxes < 1.0:
        raise ValueError(f"min_boxes must be >= 1, got {min_boxes}")
    if min_points < 2:
        raise ValueError(f"min_points must be >= 2, got {min_points}")
    rng = as_generator(seed)
    low = pts.min(axis=0)
    extent = float(np.max(pts.max(axis=0) - low))
    if not extent > 0.0:
        raise ValueError("points all coincide: the box-counting dimension is 0 and not fitted")
    if not math.isfinite(extent):
        raise ValueError("points span more than the largest float: scale them down")
    # boxes in units of the extent: the dimension of a scaled set is the same, and a set
    # scaled by 1e±200 (squared distances overflow or underflow) is counted like the original
    unit = (pts - low) / extent
    if sizes is None:
        if n_sizes < min_points:
            raise ValueError(f"n_sizes must be >= min_points={min_points}, got {n_sizes}")
        spacing = _typical_spacing(unit, rng)
        smallest = max(spacing, 1e-9)
        if not smallest < 1.0 / min_boxes:
            raise ValueError(
                "too few distinct points to resolve any scaling region (median "
                f"nearest-neighbour distance {spacing:.3g} of the extent, need < "
                f"{1.0 / min_boxes:.3g})"
            )
        eps_unit = np.geomspace(1.0, smallest, n_sizes)
    else:
        eps = real_array(sizes, "sizes")
        if eps.ndim != 1 or eps.size < 2 or np.any(~(eps > 0)) or not np.all(np.isfinite(eps)):
            raise ValueError("sizes must be a 1-D sequence of at least 2 finite positive sizes")
        bounded_work(eps.size, "sizes", MAX_SIZES, "box sizes")
        eps_unit = np.sort(eps)[::-1] / extent
        if not np.all(eps_unit > 0.0) or not np.all(np.isfinite(eps_unit)):
            raise ValueError(f"sizes must be within float range of the extent {extent:.3g}")
    counts = box_counts(unit, eps_unit, offsets=offsets, seed=rng, reduce=reduce)
    eps = eps_unit * extent
    x = np.log(1.0 / eps_unit) - math.log(extent)
    y = np.log(counts)
    usable = (counts <= max_fill * n) & (eps_unit <= 1.0 / min_boxes)
    if sizes is not None and np.count_nonzero(usable) < 2:
        usable = np.ones_like(usable)  # explicit sizes: trust the caller
    i, j = _scaling_region(x, y, usable, min_points)
    slope, stderr, intercept, _ = _linear_fit(x[i:j], y[i:j])
    local = np.diff(y) / np.diff(x)
    return BoxCountingResult(
        dimension=slope,
        stderr=stderr,
        intercept=intercept,
        sizes=eps,
        counts=counts,
        region=(int(i), int(j)),
        local_slopes=local,
        n_points=n,
    )
