"""Smoothed Preisach (FORC) density: local quadratic regression of the Everett function.

Both estimators fit ``a + bΔα + cΔβ + dΔα² + eΔβ² + gΔαΔβ`` to the Everett function in a window
around each node and return ``μ_αβ = −g`` (a 2-D Savitzky–Golay filter):
:func:`grid_quadratic_density` on a regular lattice (all nodes at once, FFT correlations) and
:func:`local_quadratic_density` on scattered points (one least-squares problem per point).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from analysis.identification._checks import positive_number

__all__ = ["grid_quadratic_density", "local_quadratic_density"]

#: shapes of the regression window on a regular lattice
WINDOWS = ("rs", "pike")


def grid_quadratic_density(
    everett: Any,
    valid: Any,
    evaluate: Any,
    step: float,
    sf_r: float,
    sf_s: float,
    window: str = "rs",
) -> np.ndarray:
    """Local quadratic regression of ``E`` on a regular lattice (fast, FFT correlations).

    The same estimator as :func:`local_quadratic_density` — at each node a least-squares fit
    of ``a + bΔα + cΔβ + dΔα² + eΔβ² + gΔαΔβ`` to the valid nodes in the window
    ``|Δr| <= sf_r·step``, ``|Δs| <= sf_s·step``, ``μ_αβ = −g`` — computed for all nodes at once:
    the normal equations are correlations of the validity mask (and of ``E``) with the window
    times monomials (15 + 6 FFT correlations), then a batched 6×6 symmetric solve. Cost
    O(n² log n) for an n × n lattice instead of one least-squares problem per node.

    Parameters
    ----------
    everett:
        ``E[α_i, β_j]`` on the lattice (values at invalid nodes are ignored).
    valid:
        Boolean mask of the nodes whose ``E`` enters the regression.
    evaluate:
        Boolean mask of the nodes where the density is wanted.
        A node gets a value only if each of its eight half-windows (``Δr < 0``, ``Δr > 0``,
        ``Δs < 0``, ``Δs > 0``, ``Δα < 0``, ``Δα > 0``, ``Δβ < 0``, ``Δβ > 0``) has at least half
        of its nodes valid.
    step:
        Lattice step (> 0).
    sf_r, sf_s:
        Window half-widths across ``r`` and along ``s`` in steps (> 0).
    window:
        ``"rs"`` as above, or ``"pike"``: the square ``|Δα|, |Δβ| <= sf_r·step`` of Pike et al.
        (1999) (``sf_s`` unused).

    Returns
    -------
    numpy.ndarray
        ``μ_αβ`` at the nodes; NaN where not evaluated, where the window lacks a valid node on
        either side of the node across (``r``) or along (``s``) the diagonal, or along ``α``
        or ``β`` (the fit would extrapolate; without the extension this blanks the diagonal
        ``r = 0``), or
        where the design is rank-deficient.
    """
    E = np.asarray(everett, dtype=float)
    v = np.asarray(valid, dtype=bool)
    ev = np.asarray(evaluate, dtype=bool)
    if E.ndim != 2 or v.shape != E.shape or ev.shape != E.shape:
        raise ValueError("everett, valid and evaluate must be 2-D arrays of the same shape")
    step = positive_number(step, "step")
    sf_r = positive_number(sf_r, "sf_r")
    sf_s = positive_number(sf_s, "sf_s")
    if window not in WINDOWS:
        raise ValueError(f"window must be one of {WINDOWS}, got {window!r}")
    w = int(math.floor((sf_r if window == "pike" else sf_r + sf_s) + 1e-9))
    out = np.full(E.shape, np.nan)
    if w < 1:
        return out
    d = np.arange(-w, w + 1)
    di, dj = np.meshgrid(d, d, indexing="ij")
    if window == "pike":
        K = np.ones(di.shape, dtype=bool)
    else:
        K = (np.abs(di - dj) <= 2 * sf_r + 1e-9) & (np.abs(di + dj) <= 2 * sf_s + 1e-9)
    x = di / w
    y = dj / w
    vf = v.astype(float)
    ve = np.where(v, E, 0.0)

    def corr(img: np.ndarray, kern: np.ndarray) -> np.ndarray:
        from scipy.signal import (
            fftconvolve,  # heavy at import: loaded where used (fast `hyst` start)
        )

        return fftconvolve(img, kern[::-1, ::-1], mode="same")

    targets = np.flatnonzero(ev)
    # data on both sides of the node across and along the diagonal (r and s): no extrapolation
    # onto the diagonal from one side, nor past the end of the curves
    # (and along α and β: no extrapolation past the end of a curve or the last reversal field)
    sides = [K & (di - dj <= -1), K & (di - dj >= 1), K & (di + dj <= -1), K & (di + dj >= 1)]
    sides += [K & (di <= -1), K & (di >= 1), K & (dj <= -1), K & (dj >= 1)]
    ok = np.ones(targets.size, dtype=bool)
    for side in sides:
        # at least half of every half-window: a lopsided window extrapolates its quadratic
        # from one side and biases the mixed derivative (by tens of % of the peak at an edge)
        ok &= corr(vf, side.astype(float)).ravel()[targets] >= 0.75 * side.sum() - 1e-6
    targets = targets[ok]
    if targets.size == 0:
        return out
    powers = [(0, 0), (1, 0), (0, 1), (2, 0), (0, 2), (1, 1)]
    moments: dict[tuple[int, int], np.ndarray] = {}
    for p1 in powers:
        for p2 in powers:
            key = (p1[0] + p2[0], p1[1] + p2[1])
            if key not in moments:
                kern = np.where(K, x ** key[0] * y ** key[1], 0.0)
                moments[key] = corr(vf, kern).ravel()[targets]
    A = np.empty((targets.size, 6, 6))
    for k, p1 in enumerate(powers):
        for m, p2 in enumerate(powers):
            A[:, k, m] = moments[(p1[0] + p2[0], p1[1] + p2[1])]
    rhs = np.empty((targets.size, 6))
    for k, p in enumerate(powers):
        rhs[:, k] = corr(ve, np.where(K, x ** p[0] * y ** p[1], 0.0)).ravel()[targets]
    lam, vec = np.linalg.eigh(A)
    good = lam[:, 0] > 1e-9 * np.maximum(lam[:, -1], 1e-300)
    proj = np.einsum("nki,nk->ni", vec, rhs)
    with np.errstate(divide="ignore", invalid="ignore"):
        coef = np.einsum("nki,ni->nk", vec, proj / lam)
    g = coef[:, 5]
    flat = out.ravel()
    flat[targets[good]] = -g[good] / (w * step) ** 2
    return flat.reshape(E.shape)


def local_quadratic_density(
    alpha: Any,
    beta: Any,
    everett: Any,
    at_alpha: Any,
    at_beta: Any,
    half_width_r: float,
    half_width_s: float,
) -> np.ndarray:
    """Smoothed ``μ_αβ = −∂²E/∂α∂β`` by local quadratic regression (2-D Savitzky–Golay).

    At each evaluation point the scattered samples ``E(α, β)`` within the window
    ``|Δr| <= half_width_r``, ``|Δs| <= half_width_s`` (``r``, ``s`` rotated coordinates) are fitted
    by least squares with ``a + bΔα + cΔβ + dΔα² + eΔβ² + gΔαΔβ``; the result is ``−g``. An exactly
    quadratic ``E`` is reproduced exactly (on any point set with an unisolvent window). For a
    curve output ``f_αβ = … + g_f αβ`` (Mayergoyz) this is ``μ_αβ = g_f/2``, ``μ_rs = g_f``.
    Windows with fewer than 6 points or a rank-deficient design give NaN.
    """
    a = np.asarray(alpha, dtype=float).ravel()
    b = np.asarray(beta, dtype=float).ravel()
    e = np.asarray(everett, dtype=float).ravel()
    qa = np.asarray(at_alpha, dtype=float).ravel()
    qb = np.asarray(at_beta, dtype=float).ravel()
    hr = positive_number(half_width_r, "half_width_r")
    hs = positive_number(half_width_s, "half_width_s")
    if not (a.size == b.size == e.size):
        raise ValueError("alpha, beta and everett must have the same length")
    # scaled rotated coordinates: the window is the unit Chebyshev ball
    pts = np.column_stack([0.5 * (a - b) / hr, 0.5 * (a + b) / hs])
    qpts = np.column_stack([0.5 * (qa - qb) / hr, 0.5 * (qa + qb) / hs])
    from scipy.spatial import cKDTree  # heavy at import: loaded where used (fast `hyst` start)

    tree = cKDTree(pts)
    groups = tree.query_ball_point(qpts, r=1.0 + 1e-9, p=np.inf)
    scale = max(hr, hs)
    out = np.full(qa.size, np.nan)
    for q, idx in enumerate(groups):
        if len(idx) < 6:
            continue
        idx = np.asarray(idx)
        x = (a[idx] - qa[q]) / scale
        y = (b[idx] - qb[q]) / scale
        design = np.column_stack([np.ones_like(x), x, y, x * x, y * y, x * y])
        coef, _, rank, _ = np.linalg.lstsq(design, e[idx], rcond=None)
        if rank < 6:
            continue
        out[q] = -coef[5] / scale**2
    return out
