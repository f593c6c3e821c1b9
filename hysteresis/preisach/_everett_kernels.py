"""Numba kernels of the continuous Preisach model's Everett function (one ``(a, b)`` at a time).

:func:`everett_eval` returns ``(E, ∂E/∂a, ∂E/∂b)`` with exactly the semantics of
:meth:`ContinuousPreisachModel.everett
<hysteresis.preisach.continuous.ContinuousPreisachModel.everett>` and
:meth:`~hysteresis.preisach.continuous.ContinuousPreisachModel.everett_gradient`:

* both arguments are clipped to ``[lower, upper]`` (the density vanishes outside);
* ``E = 0`` and a zero gradient for ``b >= a`` (after clipping);
* a gradient component is 0 where its (unclipped) argument lies beyond the support.

It dispatches on ``kind`` (see :class:`~hysteresis.preisach.everett_table.CompiledEverett`,
which builds ``params`` and ``table``):

``kind = 0`` (:data:`KIND_GAUSSIAN`), the Gaussian width-disorder density of
:meth:`ContinuousPreisachModel.gaussian`; ``table`` is unused and ``params`` holds::

    [lower, upper, half, width_spread, spread, r_lo, r_hi, norm_r, norm_s, total,
     g_1 .. g_n, w_1 .. w_n]

(``half = p/2``; ``g``, ``w`` the Gauss–Legendre nodes and weights on ``[0, 1]``). In Python::

    top = clip((a − b)/2, r_lo, r_hi); span = top − r_lo; r = r_lo + span·g
    wr = span·w·norm_r·exp(−((r − half)/σ_r)²/2)
    E = Σ wr·(Φ((a − r)/R) − Φ((b + r)/R)) / total
    ∂E/∂a = Σ wr·exp(−((a − r)/R)²/2)·norm_s / total
    ∂E/∂b = −Σ wr·exp(−((b + r)/R)²/2)·norm_s / total

— the same quadrature, in the same order, as :func:`hysteresis.preisach.gaussian.gaussian_everett`
(``Φ`` computed as ``scipy.special.ndtr`` does, from ``math.erf``/``math.erfc``).

``kind = 1`` (:data:`KIND_TABLE`), a bicubic Hermite interpolant on the square grid
``x_k = lower + k·h``, ``h = (upper − lower)/n``; ``params = [lower, upper]`` and ``table`` has
shape ``(n + 1, n + 1, 4)`` with ``table[i, j] = (E, ∂E/∂a, ∂E/∂b, ∂²E/∂a∂b)`` at
``(x_i, x_j)``. In the cell ``[x_i, x_{i+1}] × [x_j, x_{j+1}]`` with local coordinates
``s = (a − x_i)/h``, ``t = (b − x_j)/h``::

    E = Σ_{p,q ∈ {0,1}} [A_p(s)A_q(t) E_pq + h B_p(s)A_q(t) Ea_pq
                         + h A_p(s)B_q(t) Eb_pq + h² B_p(s)B_q(t) Eab_pq]

with the cubic Hermite basis ``A_0 = 1 − 3s² + 2s³``, ``A_1 = 3s² − 2s³``,
``B_0 = s − 2s² + s³``, ``B_1 = s³ − s²``; the gradient is the exact derivative of this
polynomial (one C¹ function: E and its gradient are consistent). In a diagonal cell
``i == j`` (its part ``a > b``) the polynomial's trace on the diagonal, ``T(s) = P(s, s)``, is
subtracted through ``D(s, t) = t²(1 − s)² T(t)/(t²(1 − t)²)`` (a polynomial: ``T`` has double
zeros at 0 and 1 because the nodal values and gradients vanish on the diagonal), so that
``E → 0`` exactly as ``b → a`` while ``D`` and its gradient vanish on the cell's edges ``t = 0``
and ``s = 1`` (the result stays C¹ across cells). The table's construction and error bounds:
:mod:`hysteresis.preisach.everett_table`.

``kind = 2`` (:data:`KIND_SEPARABLE`), the Gaussian width-disorder density of
:meth:`ContinuousPreisachModel.gaussian` through its separable form (built by
:func:`hysteresis.preisach.gaussian.gaussian_table`, which derives the error bound)::

    E(a, b) = F(a, t) + F(−b, t) − W(t),   t = clip((a − b)/2, r_lo, r_hi)
    F(x, t) = ∫_{r_lo}^{t} w(r) Φ((x − r)/R) dr,   W(t) = ∫_{r_lo}^{t} w(r) dr

(``w`` the normal law N(p/2, σ_r²); both divided by the mass ``total``; from
``Φ((b + r)/R) = 1 − Φ((−b − r)/R)``). ``W`` is the closed form
``(Φ((t − p/2)/σ_r) − Φ((r_lo − p/2)/σ_r))/total``; ``F`` a bi-quintic Hermite interpolant
on the grid ``x_i = −L + i·h_x`` (``i = 0 .. n_x``), ``t_j = r_lo + j·h_t`` (``j = 0 .. n_t``)
with ``table[i, j, 3α + β] = h_x^α h_t^β ∂_x^α ∂_t^β F(x_i, t_j)`` (α, β ∈ {0, 1, 2}) and
``params`` ::

    [lower, upper, h_x, r_lo, r_hi, h_t, half, width_spread, total, Φ((r_lo − half)/σ_r)]

In the cell ``[x_i, x_{i+1}] × [t_j, t_{j+1}]`` with ``s = (x − x_i)/h_x``,
``u = (t − t_j)/h_t``::

    F = Σ_{p,q ∈ {0,1}} Σ_{α,β} Q_{α,p}(s) Q_{β,q}(u) table[i + p, j + q, 3α + β]

with the quintic Hermite basis ``Q_{0,0} = 1 − 10s³ + 15s⁴ − 6s⁵``, ``Q_{0,1} = 1 − Q_{0,0}``,
``Q_{1,0} = s − 6s³ + 8s⁴ − 3s⁵``, ``Q_{1,1} = −4s³ + 7s⁴ − 3s⁵``,
``Q_{2,0} = s²(1 − s)³/2``, ``Q_{2,1} = s³(1 − s)²/2`` (``F`` is C² across cells). The gradient
is the exact derivative of this ``E`` (one function)::

    c = (F_t(a, t) + F_t(−b, t) − w(t)/total)/2   if r_lo < (a − b)/2 < r_hi, else 0
    ∂E/∂a = F_x(a, t) + c,   ∂E/∂b = −F_x(−b, t) − c

(``c`` vanishes for the exact ``F`` at ``t = (a − b)/2``; for the interpolant it is of the
order of its error, so the gradient jumps by that much across ``t = r_hi``).
``(a − b)/2 <= r_lo``: ``E = 0`` (no mass below ``r_lo``); ``(a − b)/2 >= r_hi``: the t-basis
at ``u = 1`` is ``Q_{0,1} = 1`` and all others 0, so ``F`` is read as a 1-D quintic along the
edge ``t = r_hi`` (:func:`_quintic_edge`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# numba's on-disk cache of a caller (oscillators/engines/_continuous_kernels.py) is keyed on the
# caller's own source file only: after editing a kernel here, touch that file (or clear its
# __pycache__) so that the engine does not keep a stale copy of everett_eval.

__all__ = [
    "KIND_GAUSSIAN",
    "KIND_TABLE",
    "KIND_SEPARABLE",
    "GAUSSIAN_HEADER",
    "everett_eval",
    "everett_many",
]

#: ``kind`` of the Gaussian width-disorder Everett function (quadrature)
KIND_GAUSSIAN = 0
#: ``kind`` of a tabulated (bicubic Hermite) Everett function
KIND_TABLE = 1
#: ``kind`` of the separable Gaussian width-disorder Everett function (bi-quintic table of F)
KIND_SEPARABLE = 2
#: number of scalar entries in front of the nodes and weights in the Gaussian ``params``
GAUSSIAN_HEADER = 10

_SQRT1_2 = 0.7071067811865476
_SQRT_PI = 1.7724538509055159


@njit(cache=True)
def _ndtr(x: float) -> float:
    """Standard normal CDF, branch for branch as ``scipy.special.ndtr`` (cephes)."""
    y = x * _SQRT1_2
    z = abs(y)
    if z < _SQRT1_2:
        return 0.5 + 0.5 * math.erf(y)
    out = 0.5 * math.erfc(z)
    if y > 0.0:
        out = 1.0 - out
    return out


@njit(cache=True)
def _gaussian(params: np.ndarray, a: float, b: float, grad_a: bool, grad_b: bool):
    """Kind 0 at clipped ``a > b``; ``grad_a``/``grad_b``: whether that component is wanted."""
    half = params[2]
    width_spread = params[3]
    spread = params[4]
    r_lo = params[5]
    r_hi = params[6]
    norm_r = params[7]
    norm_s = params[8]
    total = params[9]
    n = (params.size - GAUSSIAN_HEADER) // 2
    top = min(max(0.5 * (a - b), r_lo), r_hi)
    span = top - r_lo
    e = 0.0
    da = 0.0
    db = 0.0
    for k in range(n):
        r = r_lo + span * params[GAUSSIAN_HEADER + k]
        z = (r - half) / width_spread
        wr = span * params[GAUSSIAN_HEADER + n + k] * norm_r * math.exp(-0.5 * z * z)
        xa = (a - r) / spread
        xb = (b + r) / spread
        e += wr * (_ndtr(xa) - _ndtr(xb))
        if grad_a:
            da += wr * math.exp(-0.5 * xa * xa)
        if grad_b:
            db += wr * math.exp(-0.5 * xb * xb)
    return e / total, da * norm_s / total, -db * norm_s / total


@njit(cache=True)
def _hermite_cell(table: np.ndarray, i: int, j: int, s: float, t: float, h: float):
    """Bicubic Hermite value and gradient in cell ``(i, j)`` at local ``(s, t)`` (see module)."""
    s2 = s * s
    t2 = t * t
    # basis in s and its derivative d/ds
    a0 = 1.0 - 3.0 * s2 + 2.0 * s2 * s
    a1 = 3.0 * s2 - 2.0 * s2 * s
    b0 = s - 2.0 * s2 + s2 * s
    b1 = s2 * s - s2
    da0 = -6.0 * s + 6.0 * s2
    da1 = -da0
    db0 = 1.0 - 4.0 * s + 3.0 * s2
    db1 = 3.0 * s2 - 2.0 * s
    # basis in t
    c0 = 1.0 - 3.0 * t2 + 2.0 * t2 * t
    c1 = 3.0 * t2 - 2.0 * t2 * t
    e0 = t - 2.0 * t2 + t2 * t
    e1 = t2 * t - t2
    dc0 = -6.0 * t + 6.0 * t2
    dc1 = -dc0
    de0 = 1.0 - 4.0 * t + 3.0 * t2
    de1 = 3.0 * t2 - 2.0 * t
    value = 0.0
    gs = 0.0
    gt = 0.0
    for p in range(2):
        ap = a0 if p == 0 else a1
        bp = b0 if p == 0 else b1
        dap = da0 if p == 0 else da1
        dbp = db0 if p == 0 else db1
        for q in range(2):
            cq = c0 if q == 0 else c1
            eq = e0 if q == 0 else e1
            dcq = dc0 if q == 0 else dc1
            deq = de0 if q == 0 else de1
            f = table[i + p, j + q, 0]
            fa = h * table[i + p, j + q, 1]
            fb = h * table[i + p, j + q, 2]
            fab = h * h * table[i + p, j + q, 3]
            value += ap * cq * f + bp * cq * fa + ap * eq * fb + bp * eq * fab
            gs += dap * cq * f + dbp * cq * fa + dap * eq * fb + dbp * eq * fab
            gt += ap * dcq * f + bp * dcq * fa + ap * deq * fb + bp * deq * fab
    return value, gs / h, gt / h


@njit(cache=True)
def _tabulated(params: np.ndarray, table: np.ndarray, a: float, b: float):
    """Kind 1 at clipped ``a > b`` (cell indices clamped to the grid); in a diagonal cell
    ``i == j`` minus the correction ``D`` that makes the interpolant vanish on ``a = b``."""
    lower = params[0]
    upper = params[1]
    n = table.shape[0] - 1
    h = (upper - lower) / n
    fa = (a - lower) / h
    fb = (b - lower) / h
    i = min(max(int(math.floor(fa)), 0), n - 1)
    j = min(max(int(math.floor(fb)), 0), n - 1)
    s = fa - i
    t = fb - j
    value, ga, gb = _hermite_cell(table, i, j, s, t, h)
    if i != j:
        return value, ga, gb
    # diagonal cell: the trace T(x) = P(x, x) of the interpolant P (degree 6, double zeros at
    # x = 0 and 1) is T = x²(1 − x)² R(x) with R quadratic; R from T at x = 1/4, 1/2, 3/4
    r1 = _hermite_cell(table, i, j, 0.25, 0.25, h)[0] / (0.0625 * 0.5625)
    r2 = _hermite_cell(table, i, j, 0.5, 0.5, h)[0] / 0.0625
    r3 = _hermite_cell(table, i, j, 0.75, 0.75, h)[0] / (0.5625 * 0.0625)
    # Lagrange basis on the nodes 1/4, 1/2, 3/4 (spacing 1/4): R(t) and R'(t)
    u1 = (t - 0.5) * (t - 0.75) * 8.0
    u2 = (t - 0.25) * (t - 0.75) * -16.0
    u3 = (t - 0.25) * (t - 0.5) * 8.0
    du1 = (2.0 * t - 1.25) * 8.0
    du2 = (2.0 * t - 1.0) * -16.0
    du3 = (2.0 * t - 0.75) * 8.0
    rt = r1 * u1 + r2 * u2 + r3 * u3
    drt = r1 * du1 + r2 * du2 + r3 * du3
    # D(s, t) = t²(1 − s)² R(t): D = T on the diagonal, D and ∇D vanish on t = 0 and s = 1
    # (the edges shared with the neighbouring cells, so the result stays C¹)
    w = (1.0 - s) * (1.0 - s)
    d = t * t * w * rt
    dds = -2.0 * t * t * (1.0 - s) * rt
    ddt = w * (2.0 * t * rt + t * t * drt)
    return value - d, ga - dds / h, gb - ddt / h


@njit(cache=True)
def _quintic(s: float):
    """Quintic Hermite basis at ``s`` and its derivative, ordered
    ``(Q00, Q01, Q10, Q11, Q20, Q21, Q00', Q01', Q10', Q11', Q20', Q21')`` (module docstring)."""
    s2 = s * s
    s3 = s2 * s
    s4 = s3 * s
    s5 = s4 * s
    q00 = 1.0 - 10.0 * s3 + 15.0 * s4 - 6.0 * s5
    d00 = -30.0 * s2 + 60.0 * s3 - 30.0 * s4
    return (
        q00,
        1.0 - q00,
        s - 6.0 * s3 + 8.0 * s4 - 3.0 * s5,
        -4.0 * s3 + 7.0 * s4 - 3.0 * s5,
        0.5 * (s2 - 3.0 * s3 + 3.0 * s4 - s5),
        0.5 * (s3 - 2.0 * s4 + s5),
        d00,
        -d00,
        1.0 - 18.0 * s2 + 32.0 * s3 - 15.0 * s4,
        -12.0 * s2 + 28.0 * s3 - 15.0 * s4,
        0.5 * (2.0 * s - 9.0 * s2 + 12.0 * s3 - 5.0 * s4),
        0.5 * (3.0 * s2 - 8.0 * s3 + 5.0 * s4),
    )


@njit(cache=True, inline="always")
def _contract(table, i, j, c, b0, b1, b2, b3, b4, b5):
    """``Σ_{q,β} Q_{β,q} table[i, j + q, c + β]`` (the t-basis ``b0..b5`` ordered as
    :func:`_quintic`)."""
    return (
        b0 * table[i, j, c]
        + b2 * table[i, j, c + 1]
        + b4 * table[i, j, c + 2]
        + b1 * table[i, j + 1, c]
        + b3 * table[i, j + 1, c + 1]
        + b5 * table[i, j + 1, c + 2]
    )


@njit(cache=True)
def _quintic_cell(table: np.ndarray, x: float, x0: float, hx: float, j: int, u):
    """``(F, ∂F/∂x, h_t ∂F/∂t)`` of the bi-quintic interpolant at ``x`` in the t-cell ``j``
    (``u``: the t-basis and its derivative at the local coordinate, :func:`_quintic`)."""
    nx = table.shape[0] - 1
    fx = (x - x0) / hx
    i = min(max(int(math.floor(fx)), 0), nx - 1)
    v0, v1, v2, v3, v4, v5, w0, w1, w2, w3, w4, w5 = _quintic(fx - i)
    b0, b1, b2, b3, b4, b5, d0, d1, d2, d3, d4, d5 = u
    # node p = 0 has the x-basis (v0, v2, v4) for α = 0, 1, 2 (derivatives w0, w2, w4), node
    # p = 1 (v1, v3, v5); the t-contractions g (values) and e (t-derivatives) per (p, α)
    g00 = _contract(table, i, j, 0, b0, b1, b2, b3, b4, b5)
    g01 = _contract(table, i, j, 3, b0, b1, b2, b3, b4, b5)
    g02 = _contract(table, i, j, 6, b0, b1, b2, b3, b4, b5)
    g10 = _contract(table, i + 1, j, 0, b0, b1, b2, b3, b4, b5)
    g11 = _contract(table, i + 1, j, 3, b0, b1, b2, b3, b4, b5)
    g12 = _contract(table, i + 1, j, 6, b0, b1, b2, b3, b4, b5)
    e00 = _contract(table, i, j, 0, d0, d1, d2, d3, d4, d5)
    e01 = _contract(table, i, j, 3, d0, d1, d2, d3, d4, d5)
    e02 = _contract(table, i, j, 6, d0, d1, d2, d3, d4, d5)
    e10 = _contract(table, i + 1, j, 0, d0, d1, d2, d3, d4, d5)
    e11 = _contract(table, i + 1, j, 3, d0, d1, d2, d3, d4, d5)
    e12 = _contract(table, i + 1, j, 6, d0, d1, d2, d3, d4, d5)
    value = v0 * g00 + v2 * g01 + v4 * g02 + v1 * g10 + v3 * g11 + v5 * g12
    gx = w0 * g00 + w2 * g01 + w4 * g02 + w1 * g10 + w3 * g11 + w5 * g12
    gt = v0 * e00 + v2 * e01 + v4 * e02 + v1 * e10 + v3 * e11 + v5 * e12
    return value, gx / hx, gt


@njit(cache=True)
def _quintic_edge(table: np.ndarray, x: float, x0: float, hx: float):
    """``(F, ∂F/∂x)`` of the interpolant at ``x`` on the edge ``t = r_hi`` (the t-basis there
    is ``Q_{0,1} = 1``, all others 0: a 1-D quintic in x, the same numbers as
    :func:`_quintic_cell` at ``u = 1``)."""
    nx = table.shape[0] - 1
    j = table.shape[1] - 1
    fx = (x - x0) / hx
    i = min(max(int(math.floor(fx)), 0), nx - 1)
    v0, v1, v2, v3, v4, v5, w0, w1, w2, w3, w4, w5 = _quintic(fx - i)
    g00 = table[i, j, 0]
    g01 = table[i, j, 3]
    g02 = table[i, j, 6]
    g10 = table[i + 1, j, 0]
    g11 = table[i + 1, j, 3]
    g12 = table[i + 1, j, 6]
    value = v0 * g00 + v2 * g01 + v4 * g02 + v1 * g10 + v3 * g11 + v5 * g12
    gx = w0 * g00 + w2 * g01 + w4 * g02 + w1 * g10 + w3 * g11 + w5 * g12
    return value, gx / hx


@njit(cache=True)
def _separable(params: np.ndarray, table: np.ndarray, a: float, b: float):
    """Kind 2 at clipped ``a > b`` (see the module docstring)."""
    x0 = params[0]
    hx = params[2]
    r_lo = params[3]
    r_hi = params[4]
    ht = params[5]
    half = params[6]
    width_spread = params[7]
    total = params[8]
    t_raw = 0.5 * (a - b)
    if t_raw <= r_lo:
        return 0.0, 0.0, 0.0
    if t_raw >= r_hi:
        # beyond the band (t clipped): E(a, b) = G(a) + G(−b) − W(r_hi), two 1-D quintics
        fa, fa_x = _quintic_edge(table, a, x0, hx)
        fb, fb_x = _quintic_edge(table, -b, x0, hx)
        e = fa + fb - (_ndtr((r_hi - half) / width_spread) - params[9]) / total
        return e, fa_x, -fb_x
    # in the band r_lo < t < r_hi
    t = t_raw
    nt = table.shape[1] - 1
    ft = (t - r_lo) / ht
    j = min(int(math.floor(ft)), nt - 1)
    u = _quintic(ft - j)
    fa, fa_x, fa_t = _quintic_cell(table, a, x0, hx, j, u)
    fb, fb_x, fb_t = _quintic_cell(table, -b, x0, hx, j, u)
    z = (t - half) / width_spread
    w_total = (_ndtr(z) - params[9]) / total
    e = fa + fb - w_total
    w = math.exp(-0.5 * z * z) * (_SQRT1_2 / _SQRT_PI) / (width_spread * total)
    c = 0.5 * ((fa_t + fb_t) / ht - w)
    return e, fa_x + c, -fb_x - c


@njit(cache=True)
def everett_eval(kind: int, params: np.ndarray, table: np.ndarray, a: float, b: float):
    """``(E(a, b), ∂E/∂a, ∂E/∂b)`` of the Everett function ``kind`` (see the module docstring
    for ``params``/``table`` and the clipping semantics). Unknown ``kind``: NaN (the Python
    side builds only known kinds)."""
    lower = params[0]
    upper = params[1]
    ac = min(max(a, lower), upper)
    bc = min(max(b, lower), upper)
    if not ac > bc:
        return 0.0, 0.0, 0.0
    grad_a = lower <= a <= upper
    grad_b = lower <= b <= upper
    if kind == KIND_GAUSSIAN:
        e, da, db = _gaussian(params, ac, bc, grad_a, grad_b)
    elif kind == KIND_TABLE:
        e, da, db = _tabulated(params, table, ac, bc)
    elif kind == KIND_SEPARABLE:
        e, da, db = _separable(params, table, ac, bc)
    else:
        return math.nan, math.nan, math.nan
    if not grad_a:
        da = 0.0
    if not grad_b:
        db = 0.0
    return e, da, db


@njit(cache=True)
def everett_many(kind: int, params: np.ndarray, table: np.ndarray, a: np.ndarray, b: np.ndarray):
    """:func:`everett_eval` at every pair ``(a[k], b[k])`` (1-D arrays of one length): the
    arrays ``(E, ∂E/∂a, ∂E/∂b)``."""
    e = np.empty(a.size)
    da = np.empty(a.size)
    db = np.empty(a.size)
    for k in range(a.size):
        e[k], da[k], db[k] = everett_eval(kind, params, table, a[k], b[k])
    return e, da, db
