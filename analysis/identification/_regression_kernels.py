"""Compiled kernel of the weighted local quadratic regression on a regular lattice.

One pass over the nodes: for each node its own window and weights (fixed or VARIFORC), the
6 × 6 normal equations, the mixed coefficient and its standard error. Used by
:mod:`analysis.identification.variforc`; the plain-Python reading of the algorithm is in the
docstring of :func:`weighted_quadratic_kernel`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["weighted_quadratic_kernel", "variforc_weight_1d"]

#: the monomials of the local quadratic, in the order of the coefficients
_N = 6


@njit(cache=True)
def variforc_weight_1d(u: float, s: float, box: bool) -> float:
    """Weight of a point at distance ``u`` (in steps) from the node along one axis.

    ``box``: 1 for ``|u| <= s`` (the fixed-factor window), else 0. Otherwise Egli (2013, eq. 6):
    1 for ``|u| <= s − 1``, ``1 − 2(|u| − s + 1)²`` up to ``s − ½``, ``2(|u| − s)²`` up to ``s``,
    0 beyond (continuous, with a continuous slope, over the last step).
    """
    a = abs(u)
    if box:
        return 1.0 if a <= s + 1e-9 else 0.0
    if a <= s - 1.0:
        return 1.0
    if a <= s - 0.5:
        d = a - s + 1.0
        return 1.0 - 2.0 * d * d
    if a <= s:
        d = a - s
        return 2.0 * d * d
    return 0.0


@njit(cache=True)
def _cholesky_solve(a: np.ndarray, b: np.ndarray, out: np.ndarray) -> bool:
    """Solve ``a x = b`` (6 × 6 symmetric) for every column of ``b`` into ``out``; ``False``
    if ``a`` is not numerically positive definite (a pivot below 1e-12 of the largest
    diagonal: a rank-deficient design)."""
    n = a.shape[0]
    lo = np.zeros((n, n))
    top = 0.0
    for i in range(n):
        top = max(top, a[i, i])
    if not top > 0.0:
        return False
    for j in range(n):
        d = a[j, j]
        for k in range(j):
            d -= lo[j, k] * lo[j, k]
        if d <= 1e-12 * top:
            return False
        lo[j, j] = math.sqrt(d)
        for i in range(j + 1, n):
            v = a[i, j]
            for k in range(j):
                v -= lo[i, k] * lo[j, k]
            lo[i, j] = v / lo[j, j]
    m = b.shape[1]
    for c in range(m):
        y = np.zeros(n)
        for i in range(n):
            v = b[i, c]
            for k in range(i):
                v -= lo[i, k] * y[k]
            y[i] = v / lo[i, i]
        for i in range(n - 1, -1, -1):
            v = y[i]
            for k in range(i + 1, n):
                v -= lo[k, i] * out[k, c]
            out[i, c] = v / lo[i, i]
    return True


@njit(cache=True)
def weighted_quadratic_kernel(
    values: np.ndarray,
    valid: np.ndarray,
    targets_i: np.ndarray,
    targets_j: np.ndarray,
    half_r: np.ndarray,
    half_s: np.ndarray,
    box: bool,
    side_fraction: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Weighted local quadratic regression at the target nodes of a regular lattice.

    Plain-Python reading, for every target node ``(i, j)`` with half-widths ``sr = half_r[k]``,
    ``ss = half_s[k]`` (in lattice steps, across ``r`` and along ``s``)::

        for every offset (di, dj) with |di|, |dj| <= floor(sr + ss):
            u_r, u_s = (di − dj)/2, (di + dj)/2              # offsets in r, s (steps)
            w = T(u_r; sr) · T(u_s; ss)                       # variforc_weight_1d
            if w == 0: skip                                   # outside the window
            count the offset in the window totals of its half-windows
            if the lattice node (i+di, j+dj) is valid:
                count it in the valid totals of its half-windows
                φ = (1, x, y, x², y², xy),  x = di/L, y = dj/L,  L = floor(sr + ss)
                A += w φ φᵀ;  b += w φ v;  B += w² φ φᵀ
        skip the node unless each of the 8 half-windows (Δr < 0, Δr > 0, Δs < 0, Δs > 0,
        Δα < 0, Δα > 0, Δβ < 0, Δβ > 0) holds at least side_fraction of its offsets valid
        c = A⁻¹ b                                             (Cholesky; skip if singular)
        RSS = Σ w (v − φᵀc)²      (second pass over the window)
        σ² = RSS / (Σ w − tr(A⁻¹B))                          # unbiased for homoscedastic noise
        z = A⁻¹ e_xy;  var(c_xy) = σ² zᵀ B z                 # sandwich: A⁻¹ B A⁻¹
        rho = −c_xy / L²,  se = sqrt(var(c_xy)) / L²          # per unit step²

    Returns ``(rho, se, sigma, n_points)`` per target (NaN / 0 where skipped); ``rho`` and
    ``se`` are per unit lattice step squared (divide by ``step²`` for field units).
    """
    n_a, n_b = values.shape
    nt = targets_i.size
    rho = np.full(nt, np.nan)
    se = np.full(nt, np.nan)
    sigma = np.full(nt, np.nan)
    npts = np.zeros(nt, dtype=np.int64)
    phi = np.zeros(_N)
    for t in range(nt):
        i0 = targets_i[t]
        j0 = targets_j[t]
        sr = half_r[t]
        ss = half_s[t]
        K = int(math.floor(sr + ss + 1e-9))
        if K < 1:
            continue
        scale = float(K)
        A = np.zeros((_N, _N))
        B = np.zeros((_N, _N))
        rhs = np.zeros((_N, 2))
        tot = np.zeros(8)
        ok = np.zeros(8)
        sw = 0.0
        n = 0
        for di in range(-K, K + 1):
            for dj in range(-K, K + 1):
                w = variforc_weight_1d(0.5 * (di - dj), sr, box)
                if w == 0.0:
                    continue
                w *= variforc_weight_1d(0.5 * (di + dj), ss, box)
                if w == 0.0:
                    continue
                ii = i0 + di
                jj = j0 + dj
                good = 0 <= ii < n_a and 0 <= jj < n_b and valid[ii, jj]
                # half-windows: r = di − dj, s = di + dj, α = di, β = dj
                flags = (
                    di - dj <= -1,
                    di - dj >= 1,
                    di + dj <= -1,
                    di + dj >= 1,
                    di <= -1,
                    di >= 1,
                    dj <= -1,
                    dj >= 1,
                )
                for q in range(8):
                    if flags[q]:
                        tot[q] += 1.0
                        if good:
                            ok[q] += 1.0
                if not good:
                    continue
                x = di / scale
                y = dj / scale
                phi[0] = 1.0
                phi[1] = x
                phi[2] = y
                phi[3] = x * x
                phi[4] = y * y
                phi[5] = x * y
                v = values[ii, jj]
                for p in range(_N):
                    wp = w * phi[p]
                    rhs[p, 0] += wp * v
                    for q in range(p, _N):
                        A[p, q] += wp * phi[q]
                        B[p, q] += wp * w * phi[q]
                sw += w
                n += 1
        lopsided = False
        for q in range(8):
            if ok[q] < side_fraction * tot[q] - 1e-6:
                lopsided = True
        if lopsided or n < _N:
            continue
        for p in range(_N):
            for q in range(p):
                A[p, q] = A[q, p]
                B[p, q] = B[q, p]
        rhs[5, 1] = 1.0
        sol = np.zeros((_N, 2))
        if not _cholesky_solve(A, rhs, sol):
            continue
        # A⁻¹ for the trace term tr(A⁻¹B)
        eye = np.eye(_N)
        inv = np.zeros((_N, _N))
        _cholesky_solve(A, eye, inv)
        trace = 0.0
        for p in range(_N):
            for q in range(_N):
                trace += inv[p, q] * B[q, p]
        rss = 0.0
        for di in range(-K, K + 1):
            for dj in range(-K, K + 1):
                ii = i0 + di
                jj = j0 + dj
                if not (0 <= ii < n_a and 0 <= jj < n_b and valid[ii, jj]):
                    continue
                w = variforc_weight_1d(0.5 * (di - dj), sr, box)
                if w == 0.0:
                    continue
                w *= variforc_weight_1d(0.5 * (di + dj), ss, box)
                if w == 0.0:
                    continue
                x = di / scale
                y = dj / scale
                fit = sol[0, 0] + sol[1, 0] * x + sol[2, 0] * y
                fit += sol[3, 0] * x * x + sol[4, 0] * y * y + sol[5, 0] * x * y
                r = values[ii, jj] - fit
                rss += w * r * r
        dof = sw - trace
        z = sol[:, 1]
        zbz = 0.0
        for p in range(_N):
            for q in range(_N):
                zbz += z[p] * B[p, q] * z[q]
        rho[t] = -sol[5, 0] / (scale * scale)
        npts[t] = n
        if dof > 0.0:
            s2 = rss / dof
            sigma[t] = math.sqrt(s2)
            se[t] = math.sqrt(max(s2 * zbz, 0.0)) / (scale * scale)
    return rho, se, sigma, npts
