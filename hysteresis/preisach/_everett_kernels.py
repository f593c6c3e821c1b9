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
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["KIND_GAUSSIAN", "KIND_TABLE", "GAUSSIAN_HEADER", "everett_eval", "everett_many"]

#: ``kind`` of the Gaussian width-disorder Everett function (quadrature)
KIND_GAUSSIAN = 0
#: ``kind`` of a tabulated (bicubic Hermite) Everett function
KIND_TABLE = 1
#: number of scalar entries in front of the nodes and weights in the Gaussian ``params``
GAUSSIAN_HEADER = 10

_SQRT1_2 = 0.7071067811865476


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
