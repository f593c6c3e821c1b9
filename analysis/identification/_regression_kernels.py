"""Compiled kernels of the weighted local quadratic regression on a regular lattice.

Every node has its own window, a rectangle in the rotated lattice coordinates ``p = Δi − Δj``
(across, ``Δr = pΔ/2``) and ``q = Δi + Δj`` (along, ``Δs = qΔ/2``), with a separable weight
``T(p/2; s_r)·T(q/2; s_s)`` whose half-width ``s_r`` depends on the node's line ``u = i − j``
only and ``s_s`` on ``w = i + j`` only (the VARIFORC law; a fixed factor is the constant
case). The window sums therefore factor: sums along a line of constant ``u`` (in ``q``) first,
for every line, centre and parity (:func:`line_sums`), then, per node, a sum over the lines
``u + p`` of its window (:func:`node_fits`): ``O(n²·(Q + P))`` instead of ``O(n²·P·Q)``. Used by
:mod:`analysis.identification.variforc`, where the estimator is described.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["variforc_weight_1d", "line_sums", "node_fits", "reach", "N_SUMS"]

#: per line, centre and parity: Σ T qᵉ·[valid] (e = 0..4), Σ T qᵉ·v (e = 0..2), Σ T·v²,
#: Σ T² qᵉ·[valid] (e = 0..4)
N_SUMS = 14
_N = 6
#: exponents (a, e) of p and q of the basis 1, p, q, p², q², pq
_POWERS = ((0, 0), (1, 0), (0, 1), (2, 0), (0, 2), (1, 1))


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
def reach(s: float, box: bool) -> int:
    """Largest integer ``q >= 0`` with ``T(q/2; s) > 0`` (the window's extent in ``p`` or
    ``q``)."""
    q = int(math.floor(2.0 * s + 1e-9)) + 1
    while q > 0 and variforc_weight_1d(0.5 * q, s, box) <= 0.0:
        q -= 1
    return q


@njit(cache=True)
def line_sums(
    values: np.ndarray,
    valid: np.ndarray,
    u_lo: int,
    u_hi: int,
    c_lo: int,
    c_hi: int,
    ss_of_w: np.ndarray,
    qr_of_w: np.ndarray,
    box: bool,
    errors: bool,
    out: np.ndarray,
) -> None:
    """Sums along the lines ``u = i − j`` in ``[u_lo, u_hi]`` around the centres ``c`` (the
    position ``j`` along the line) in ``[c_lo, c_hi)``, for both parities ``π`` of ``q``.

    Plain-Python reading::

        for u, c, π:
            w0 = u + 2c − π                  # the Bu index of the node these sums serve
            s, Q = ss_of_w[w0], qr_of_w[w0]  # its half-width along s and its reach in q
            for every q ≡ π (mod 2), |q| <= Q:
                j = c + (q − π)/2;  i = j + u    # the lattice node on line u at offset q
                if (i, j) is a valid node: t = T(q/2; s); accumulate t·qᵉ, t·qᵉ·v, t·v², t²·qᵉ

    into ``out[u − u_lo, c − c_lo, π, :]`` (layout: :data:`N_SUMS`).
    """
    n = values.shape[0]
    n_w = ss_of_w.size
    for u in range(u_lo, u_hi + 1):
        j_first = max(0, -u)
        j_last = min(n - 1, n - 1 - u)
        for c in range(c_lo, c_hi):
            for pi in range(2):
                row = out[u - u_lo, c - c_lo, pi]
                row[:] = 0.0
                w0 = u + 2 * c - pi
                if w0 < 0 or w0 >= n_w or j_first > j_last:
                    continue
                s = ss_of_w[w0]
                Q = qr_of_w[w0]
                q_start = -Q if (Q - pi) % 2 == 0 else -Q + 1
                # the line's nodes in reach: j = c + (q − π)/2
                k_lo = max((q_start - pi) // 2, j_first - c)
                k_hi = min((Q - pi) // 2, j_last - c)
                for k in range(k_lo, k_hi + 1):
                    j = c + k
                    i = j + u
                    if not valid[i, j]:
                        continue
                    q = 2 * k + pi
                    t = variforc_weight_1d(0.5 * q, s, box)
                    if t <= 0.0:
                        continue
                    v = values[i, j]
                    qe = 1.0
                    for e in range(5):
                        row[e] += t * qe
                        if e < 3:
                            row[5 + e] += t * qe * v
                        if errors:
                            row[9 + e] += t * t * qe
                        qe *= q
                    row[8] += t * v * v


@njit(cache=True)
def _count(cum: np.ndarray, line: int, j_a: int, j_b: int, n: int) -> float:
    """Valid nodes on ``line`` with ``j`` in ``[j_a, j_b]`` (clipped to the lattice)."""
    a = max(j_a, 0)
    b = min(j_b, n - 1)
    if a > b:
        return 0.0
    return float(cum[line, b + 1] - cum[line, a])


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
    for c in range(b.shape[1]):
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
def node_fits(
    sums: np.ndarray,
    u_lo: int,
    c_lo: int,
    cum: np.ndarray,
    targets_i: np.ndarray,
    targets_j: np.ndarray,
    sr_t: np.ndarray,
    pr_t: np.ndarray,
    qr_t: np.ndarray,
    box: bool,
    side_fraction: float,
    errors: bool,
    rho: np.ndarray,
    se: np.ndarray,
    sigma: np.ndarray,
    npts: np.ndarray,
) -> None:
    """The regression at every target node from the line sums (results written in place).

    Plain-Python reading, for a node ``(i, j)`` (``u = i − j``) with half-width ``s_r`` and
    reaches ``P`` (in ``p``) and ``Q`` (in ``q``)::

        for p in −P … P:                      # the lines u + p of the window
            t = T(p/2; s_r);  m, π = divmod(p, 2);  c = j − m
            moments S[a, e] += t pᵃ · (line sums of line u + p, centre c, parity π)[e]
            count the window's nodes (all, and valid, from prefix sums along the line) in the
            half-windows p < 0, p > 0, q < 0, q > 0, Δi < 0, Δi > 0, Δj < 0, Δj > 0
        skip unless every half-window holds side_fraction of its nodes valid
        A = S in the basis (1, p, q, p², q², pq) / L (L = max(P, Q)); c = A⁻¹ b (Cholesky)
        ρ = 2 (c_p² − c_q²) / L²               # −∂²v/∂i∂j per step²: p² = (Δi−Δj)², q² = (Δi+Δj)²
        errors: RSS = Σ w v² − cᵀb; σ² = RSS/(Σ w − tr(A⁻¹B)); var = σ² zᵀBz, z = A⁻¹ (e_p² − e_q²)
    """
    n = cum.shape[1] - 1
    n_lines = cum.shape[0]
    mom = np.zeros((5, 5))
    mom2 = np.zeros((5, 5))
    rhs = np.zeros((_N, 2))
    A = np.zeros((_N, _N))
    B = np.zeros((_N, _N))
    sol = np.zeros((_N, 2))
    inv = np.zeros((_N, _N))
    eye = np.eye(_N)
    tot = np.zeros(8)
    ok = np.zeros(8)
    for t in range(targets_i.size):
        i0 = targets_i[t]
        j0 = targets_j[t]
        u0 = i0 - j0
        sr = sr_t[t]
        P = pr_t[t]
        Q = qr_t[t]
        if P < 1 or Q < 1:
            continue
        mom[:, :] = 0.0
        mom2[:, :] = 0.0
        rhs[:, :] = 0.0
        tot[:] = 0.0
        ok[:] = 0.0
        swv2 = 0.0
        n_cnt = 0.0
        for p in range(-P, P + 1):
            tr = variforc_weight_1d(0.5 * p, sr, box)
            if tr <= 0.0:
                continue
            m = p // 2
            pi = p - 2 * m
            c = j0 - m
            u = u0 + p
            line = u + n - 1
            # q runs over q ≡ π (mod 2), |q| <= Q; the node at q sits at j = c + (q − π)/2
            q_a = -Q if (Q - pi) % 2 == 0 else -Q + 1
            q_b = Q if (Q - pi) % 2 == 0 else Q - 1
            n_all = (q_b - q_a) // 2 + 1
            inside = 0 <= line < n_lines
            n_valid = 0.0
            if inside:
                n_valid = _count(cum, line, c + (q_a - pi) // 2, c + (q_b - pi) // 2, n)
            n_cnt += n_valid
            # half-windows in p: the whole column
            if p <= -1:
                tot[0] += n_all
                ok[0] += n_valid
            elif p >= 1:
                tot[1] += n_all
                ok[1] += n_valid
            # in q (q <= −1, q >= 1), Δi = (p+q)/2 (q <= −2 − p, q >= 2 − p), Δj = (q−p)/2
            # (q <= p − 2, q >= p + 2): ranges of q, counted with the parity π
            for h in range(6):
                if h == 0:
                    lo, hi = q_a, -1
                elif h == 1:
                    lo, hi = 1, q_b
                elif h == 2:
                    lo, hi = q_a, -2 - p
                elif h == 3:
                    lo, hi = 2 - p, q_b
                elif h == 4:
                    lo, hi = q_a, p - 2
                else:
                    lo, hi = p + 2, q_b
                lo = max(lo, q_a)
                hi = min(hi, q_b)
                if (lo - pi) % 2 != 0:
                    lo += 1
                if (hi - pi) % 2 != 0:
                    hi -= 1
                if lo > hi:
                    continue
                tot[2 + h] += (hi - lo) // 2 + 1
                if inside:
                    ok[2 + h] += _count(cum, line, c + (lo - pi) // 2, c + (hi - pi) // 2, n)
            if not inside or n_valid == 0.0:
                continue
            row = sums[u - u_lo, c - c_lo, pi]
            pa = 1.0
            for a in range(5):
                for e in range(5 - a):
                    mom[a, e] += tr * pa * row[e]
                    if errors:
                        mom2[a, e] += tr * tr * pa * row[9 + e]
                pa *= p
            rhs[0, 0] += tr * row[5]
            rhs[1, 0] += tr * p * row[5]
            rhs[2, 0] += tr * row[6]
            rhs[3, 0] += tr * p * p * row[5]
            rhs[4, 0] += tr * row[7]
            rhs[5, 0] += tr * p * row[6]
            swv2 += tr * row[8]
        lopsided = False
        for h in range(8):
            if ok[h] < side_fraction * tot[h] - 1e-6:
                lopsided = True
        if lopsided or n_cnt < _N:
            continue
        L = float(max(P, Q))
        for k in range(_N):
            for l in range(_N):
                a = _POWERS[k][0] + _POWERS[l][0]
                e = _POWERS[k][1] + _POWERS[l][1]
                f = L ** (a + e)
                A[k, l] = mom[a, e] / f
                B[k, l] = mom2[a, e] / f
        for k in range(_N):
            rhs[k, 0] /= L ** (_POWERS[k][0] + _POWERS[k][1])
        rhs[:, 1] = 0.0
        rhs[3, 1] = 1.0
        rhs[4, 1] = -1.0
        if not _cholesky_solve(A, rhs, sol):
            continue
        rho[t] = 2.0 * (sol[3, 0] - sol[4, 0]) / (L * L)
        npts[t] = int(n_cnt)
        if not errors:
            continue
        _cholesky_solve(A, eye, inv)
        trace = 0.0
        for k in range(_N):
            for l in range(_N):
                trace += inv[k, l] * B[l, k]
        fitted = 0.0
        for k in range(_N):
            fitted += sol[k, 0] * rhs[k, 0]
        rss = swv2 - fitted
        dof = mom[0, 0] - trace
        zbz = 0.0
        for k in range(_N):
            for l in range(_N):
                zbz += sol[k, 1] * B[k, l] * sol[l, 1]
        if dof > 0.0:
            s2 = max(rss, 0.0) / dof
            sigma[t] = math.sqrt(s2)
            se[t] = 2.0 * math.sqrt(max(s2 * zbz, 0.0)) / (L * L)
