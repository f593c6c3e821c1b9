"""The compiled form of a continuous Preisach model's Everett function, and its tables.

:class:`CompiledEverett` is what :meth:`ContinuousPreisachModel.compiled_everett
<hysteresis.preisach.continuous.ContinuousPreisachModel.compiled_everett>` returns: plain
float64 arrays that the numba kernel
:func:`hysteresis.preisach._everett_kernels.everett_eval` evaluates as
``everett_eval(kind, params, table, a, b) -> (E, ∂E/∂a, ∂E/∂b)``, with the semantics of the
model's :meth:`everett` / :meth:`everett_gradient` (see that module for the layouts).

Tables (kind 1): nodal ``(E, ∂E/∂a, ∂E/∂b, ∂²E/∂a∂b = −μ)`` on the square grid
``x_k = lower + k h``, ``h = (upper − lower)/n`` (:func:`density_table` for
:meth:`PreisachModel.from_density`, :func:`everett_function_table` for a user's Everett
function), interpolated bicubically (Hermite) — E and its gradient are one C¹ function.
Above the diagonal the table holds the symmetric extension ``F(a, b) = E(b, a)``, which is C²
across ``a = b`` (there ``E = ∇E = 0``, ``E_aa = E_bb = μ``, ``E_ab = −μ``); the kernel
subtracts the interpolant's trace on the diagonal so that ``E(a, b) → 0`` as ``b → a``.
Memory: ``32 (n + 1)²`` bytes.

Error bound (interpolation; the nodal data are quadratures or differences, far more
accurate). Write ``‖·‖`` for the largest magnitude over the cell, ``μ₁ = ∂μ/∂α``,
``μ₂ = ∂μ/∂β`` and

    B₄ = h⁴/384 · (‖∂⁴E/∂a⁴‖ + ‖∂⁴E/∂b⁴‖ + h/4 · ‖∂⁵E/∂a∂b⁴‖).

* Cells off the diagonal (``E`` as smooth as ``μ``; ``∂⁴E/∂a⁴`` involves ``μ``'s derivatives
  up to order 2 on the diagonal and ``(a − b) ‖∂³μ/∂α³‖``): ``|E − Ĕ| <= B₄``, from
  ``f − H_a H_b f = (f − H_a f) + H_a (f − H_b f)``, the 1-D cubic Hermite bound
  ``h⁴ ‖f⁗‖/384`` and the basis sums ``|A₀| + |A₁| = 1``, ``|B₀| + |B₁| <= 1/4``. The
  gradient: ``|∂(E − Ĕ)/∂a| <= (√3/216) h³ ‖∂⁴E/∂a⁴‖ + (3/384) h³ ‖∂⁴E/∂b⁴‖ + h⁴/384 ·
  ‖∂⁵E/∂a∂b⁴‖`` (``∂/∂b`` with ``a``, ``b`` exchanged), using ``|A₀'| + |A₁'| <= 3``,
  ``|B₀'| + |B₁'| <= 1``.
* Diagonal cells: the extension ``F`` is ``G + κ|a − b|³`` with ``G`` smooth and
  ``κ = (μ₁ − μ₂)/12`` on the diagonal (the odd part of ``E``'s cubic Taylor term in
  ``a − b``). The interpolant, corrected on the diagonal, reproduces ``|a − b|³`` on the unit
  cell to within ``K = 0.02296`` (value) and ``K' = 0.2575`` (gradient; both constants maximised
  once on a fine grid of the unit cell with this kernel), so
  ``|E − Ĕ| <= K κ̄ h³ + 2 B₄`` and ``|∇(E − Ĕ)| <= K' κ̄ h² + O(h³)`` with
  ``κ̄ = (max_diag |μ₁ − μ₂| + h ‖∇(μ₁ − μ₂)‖)/12`` (the second term bounds the variation of
  ``κ`` across the cell). Where ``μ₁ = μ₂`` on the diagonal (e.g. a density of ``α − β``
  alone) the diagonal cells keep fourth order.

A density with jumps (e.g. a uniform density cut at the support) has ``E`` only C¹ across the
jump lines: there the error is ``O(h²)`` times the jump (as for any Hermite interpolant).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hysteresis._validation import readonly_array
from hysteresis.preisach._everett_kernels import (
    KIND_GAUSSIAN,
    KIND_SEPARABLE,
    KIND_TABLE,
    everett_eval,
)

__all__ = ["CompiledEverett", "EMPTY_TABLE"]

#: the ``table`` of a kind that needs none (shape ``(0, 0, 0)``)
EMPTY_TABLE = readonly_array(np.zeros((0, 0, 0)))


@dataclass(frozen=True, eq=False)
class CompiledEverett:
    """An Everett function as arrays for the compiled kernel ``everett_eval``.

    ``kind``: 0 = the Gaussian width-disorder quadrature (``table`` empty, shape
    ``(0, 0, 0)``), 1 = a bicubic Hermite table of nodal ``(E, ∂E/∂a, ∂E/∂b, ∂²E/∂a∂b)``,
    shape ``(n + 1, n + 1, 4)`` on the grid ``lower + k·(upper − lower)/n``, 2 = the
    separable Gaussian width-disorder form, a bi-quintic table of ``F(x, t)``, shape
    ``(n_x + 1, n_t + 1, 9)`` (:mod:`hysteresis.preisach.gaussian`). ``params``: 1-D
    float64, ``params[0:2] = (lower, upper)`` (the support) followed by the kind's own
    parameters. Both arrays are read-only float64; the object pickles as its fields.
    """

    kind: int
    params: np.ndarray
    table: np.ndarray

    def __post_init__(self) -> None:
        if self.kind not in (KIND_GAUSSIAN, KIND_TABLE, KIND_SEPARABLE):
            raise ValueError(
                f"kind must be {KIND_GAUSSIAN}, {KIND_TABLE} or {KIND_SEPARABLE}, got {self.kind!r}"
            )
        params = readonly_array(self.params)
        table = readonly_array(self.table)
        if params.ndim != 1 or params.size < 2 or not params[1] > params[0]:
            raise ValueError("params must be 1-D and start with lower < upper")
        if table.ndim != 3:
            raise ValueError(f"table must be 3-D, got shape {table.shape}")
        if self.kind == KIND_TABLE and (
            table.shape[0] < 2 or table.shape[1] != table.shape[0] or table.shape[2] != 4
        ):
            raise ValueError(f"a kind-1 table must have shape (n+1, n+1, 4), got {table.shape}")
        if self.kind == KIND_SEPARABLE and (
            min(table.shape[:2], default=0) < 2 or table.shape[2] != 9 or params.size != 10
        ):
            raise ValueError(
                f"a kind-2 table must have shape (n_x+1, n_t+1, 9) and 10 params, got "
                f"{table.shape} and {params.size}"
            )
        object.__setattr__(self, "kind", int(self.kind))
        object.__setattr__(self, "params", params)
        object.__setattr__(self, "table", table)

    @property
    def lower(self) -> float:
        return float(self.params[0])

    @property
    def upper(self) -> float:
        return float(self.params[1])

    def __call__(self, a: float, b: float) -> tuple[float, float, float]:
        """``(E, ∂E/∂a, ∂E/∂b)`` at one point, through the compiled kernel."""
        return everett_eval(self.kind, self.params, self.table, float(a), float(b))


def _symmetrise(table: np.ndarray) -> np.ndarray:
    """Fill ``b > a`` with the symmetric extension ``F(a, b) = E(b, a)`` (nodal data
    ``(E, ∂E/∂b, ∂E/∂a, ∂²E/∂a∂b)`` of the mirrored node): only the nodes ``(x_i, x_{i+1})``
    of the diagonal cells are read; ``F`` is C² across the diagonal (see the error bound)."""
    i, j = np.triu_indices(table.shape[0], 1)
    table[i, j, 0] = table[j, i, 0]
    table[i, j, 1] = table[j, i, 2]
    table[i, j, 2] = table[j, i, 1]
    table[i, j, 3] = table[j, i, 3]
    return table


def _density_values(density, alpha, beta) -> np.ndarray:
    mu = np.asarray(density(*np.broadcast_arrays(alpha, beta)), dtype=np.float64)
    mu = np.broadcast_to(mu, np.broadcast_shapes(np.shape(alpha), np.shape(beta)))
    if not np.all(np.isfinite(mu)) or np.any(mu < 0):
        raise ValueError("density must be finite and >= 0 on lower <= beta <= alpha <= upper")
    return mu


#: density values per block of the line quadratures in :func:`density_table` (memory bound)
_BLOCK = 1 << 20


def density_table(
    density, lower: float, upper: float, n: int, mass_tolerance: float
) -> tuple[np.ndarray, float]:
    """Nodal Hermite data ``(E, ∂E/∂a, ∂E/∂b, ∂²E/∂a∂b)`` of the density's Everett function on
    the grid ``x_k = lower + k h``, ``h = (upper − lower)/n``, shape ``(n + 1, n + 1, 4)``, and
    the mass scale ``1/total`` (the density's quadrature mass, divided out so that
    ``E(upper, lower) = 1``; ``ValueError`` if ``|total − 1| > mass_tolerance``).

    Quadratures (4-point Gauss–Legendre per grid cell or segment): ``E(x_i, x_j)`` is the sum of
    the cell masses with α-cell ``< i`` and β-cell ``>= j`` (square cells by the tensor rule, the
    diagonal half-cells in collapsed coordinates ``α = x + hξ``, ``β = x + hξη``);
    ``∂E/∂a(x_i, x_j) = ∫_{x_j}^{x_i} μ(x_i, β) dβ``, ``∂E/∂b = −∫_{x_j}^{x_i} μ(α, x_j) dα``
    (segment sums), ``∂²E/∂a∂b = −μ(x_i, x_j)``. The density is evaluated only on the triangle.
    """
    from hysteresis.preisach.base import _gauss

    h = (upper - lower) / n
    nodes = lower + h * np.arange(n + 1)
    g, gw = _gauss(4)
    # square cells (alpha-cell i > beta-cell j): tensor Gauss
    ii, jj = np.tril_indices(n, -1)
    qa = nodes[ii][:, None, None] + h * g[None, :, None]
    qb = nodes[jj][:, None, None] + h * g[None, None, :]
    sq = h * h * np.einsum("kij,i,j->k", _density_values(density, qa, qb), gw, gw)
    del qa, qb
    # diagonal cells: triangle beta <= alpha, collapsed coordinates (Jacobian h² ξ)
    d = np.arange(n)
    ta = nodes[d][:, None, None] + h * g[None, :, None] + 0.0 * g[None, None, :]
    tb = nodes[d][:, None, None] + h * g[None, :, None] * g[None, None, :]
    tri = h * h * np.einsum("kij,i,j,i->k", _density_values(density, ta, tb), gw, gw, g)
    cell = np.zeros((n, n))
    cell[ii, jj] = sq
    cell[d, d] = tri
    total = float(cell.sum())
    if abs(total - 1.0) > mass_tolerance:
        raise ValueError(
            f"density must have mass 1 on the triangle lower <= beta <= alpha <= upper "
            f"(within mass_tolerance={mass_tolerance}), got {total!r}"
        )
    scale = 1.0 / total
    table = np.zeros((n + 1, n + 1, 4))
    # E(x_i, x_j) = sum of cells with alpha-cell < i and beta-cell >= j
    suffix = np.cumsum(cell[:, ::-1], axis=1)[:, ::-1]  # sum over beta-cells >= j
    table[1:, :n, 0] = np.cumsum(suffix, axis=0) * scale
    del cell, suffix
    table[n, 0, 0] = 1.0  # saturation exactly (the cumulative sum rounds)
    # line integrals over segments [x_k, x_{k+1}], k < i, in blocks of rows
    rows = max(1, _BLOCK // (4 * n))
    seg = nodes[:n, None] + h * g[None, :]  # (n, 4) quadrature points of every segment
    ks = np.arange(n)
    for start in range(1, n + 1, rows):
        i = np.arange(start, min(n + 1, start + rows))
        # ∂E/∂a(x_i, x_j) = Σ_{k=j}^{i-1} ∫ μ(x_i, β) over segment k (only k < i: the triangle)
        r, k = np.nonzero(ks[None, :] < i[:, None])
        line_a = np.zeros((i.size, n))
        line_a[r, k] = h * (_density_values(density, nodes[i[r]][:, None], seg[k]) @ gw)
        table[i, :n, 1] = np.cumsum(line_a[:, ::-1], axis=1)[:, ::-1] * scale
    for start in range(0, n, rows):
        j = np.arange(start, min(n, start + rows))
        # ∂E/∂b(x_i, x_j) = −Σ_{k=j}^{i-1} ∫ μ(α, x_j) over segment k (only k >= j)
        c, k = np.nonzero(ks[None, :] >= j[:, None])
        line_b = np.zeros((j.size, n))
        line_b[c, k] = h * (_density_values(density, seg[k], nodes[j[c]][:, None]) @ gw)
        table[1:, j, 2] = -(np.cumsum(line_b, axis=1) * scale).T
    ii, jj = np.tril_indices(n + 1)
    table[ii, jj, 3] = -scale * _density_values(density, nodes[ii], nodes[jj])
    # the diagonal: E and its gradient vanish there (E = μ (a − b)²/2 + ...)
    table[np.arange(n + 1), np.arange(n + 1), :3] = 0.0
    return _symmetrise(table), scale


def _stencil(x: np.ndarray, lower: float, upper: float, step: float):
    """Second-order first-derivative stencils at ``x``: central where ``x ± step`` lies in
    ``[lower, upper]``, one-sided (``(−3f₀ + 4f₁ − f₂)/2``) at the bounds. Returns offsets and
    weights, shape ``(x.size, 3)`` (in units of ``step``)."""
    offsets = np.tile(np.array([-1.0, 1.0, 0.0]), (x.size, 1))
    weights = np.tile(np.array([-0.5, 0.5, 0.0]), (x.size, 1))
    low = x - step < lower
    high = x + step > upper
    offsets[low] = [0.0, 1.0, 2.0]
    weights[low] = [-1.5, 2.0, -0.5]
    offsets[high] = [0.0, -1.0, -2.0]
    weights[high] = [1.5, -2.0, 0.5]
    return offsets, weights


def everett_function_table(everett, gradient, lower: float, upper: float, n: int) -> np.ndarray:
    """Nodal Hermite data (shape ``(n + 1, n + 1, 4)``, layout of :func:`density_table`) of a
    vectorised Everett callable ``everett(a, b)`` on the triangle (and of ``gradient(a, b) ->
    (∂E/∂a, ∂E/∂b)`` if given).

    Derivatives the callables do not give are differences that stay inside the triangle
    (``u = upper − lower``; ``ε`` the float64 epsilon): the gradient by second-order
    differences of ``E`` with step ``ε^{1/3} u`` (error ``~ε^{2/3}`` relative to the largest
    third derivative and to ``E``); ``∂²E/∂a∂b`` off the diagonal by differences of ``∂E/∂a``
    in ``b`` (step ``ε^{1/3} u``) or, without a gradient, by the tensor stencil of ``E`` with
    step ``min(ε^{1/4} u, h/8)`` (error ``~ε^{1/2}``); on the diagonal ``∂²E/∂a∂b = −μ(x, x)``
    by the Richardson extrapolation ``2m(δ) − m(2δ)`` of ``m(δ) = 2E(x + δ, x)/δ²`` (or
    ``2E(x, x − δ)/δ²`` at ``x = upper``), ``δ = 10⁻⁴ u``. The nodal ``∂²E/∂a∂b`` enters the
    interpolant multiplied by ``h²/16`` at most, so these errors stay far below the
    interpolation error of :func:`density_table`'s bound.
    """
    span = upper - lower
    h = span / n
    eps = np.finfo(np.float64).eps
    nodes = lower + h * np.arange(n + 1)
    ii, jj = np.tril_indices(n + 1, -1)  # strictly below the diagonal: a > b
    a, b = nodes[ii], nodes[jj]

    def e(x, y):
        return np.asarray(everett(x, y), dtype=np.float64)

    table = np.zeros((n + 1, n + 1, 4))
    table[ii, jj, 0] = e(a, b)
    step1 = eps ** (1.0 / 3.0) * span
    oa, wa = _stencil(a, lower, upper, step1)
    ob, wb = _stencil(b, lower, upper, step1)
    if gradient is not None:
        ga, gb = (np.asarray(v, dtype=np.float64) for v in gradient(a, b))
        table[ii, jj, 1] = np.broadcast_to(ga, a.shape)
        table[ii, jj, 2] = np.broadcast_to(gb, a.shape)
        cross = sum(
            wb[:, k] * np.asarray(gradient(a, b + ob[:, k] * step1)[0], dtype=np.float64)
            for k in range(3)
        )
        table[ii, jj, 3] = cross / step1
    else:
        table[ii, jj, 1] = sum(wa[:, k] * e(a + oa[:, k] * step1, b) for k in range(3)) / step1
        table[ii, jj, 2] = sum(wb[:, k] * e(a, b + ob[:, k] * step1) for k in range(3)) / step1
        step2 = min(eps**0.25 * span, h / 8.0)
        oa, wa = _stencil(a, lower, upper, step2)
        ob, wb = _stencil(b, lower, upper, step2)
        cross = np.zeros(a.shape)
        for p in range(3):
            for q in range(3):
                cross += wa[:, p] * wb[:, q] * e(a + oa[:, p] * step2, b + ob[:, q] * step2)
        table[ii, jj, 3] = cross / (step2 * step2)
    # the diagonal: E = ∂E/∂a = ∂E/∂b = 0 and ∂²E/∂a∂b = −μ(x, x)
    delta = 1e-4 * span
    x = nodes
    top = x + 2.0 * delta > upper

    def m(d):
        out = np.empty(x.size)
        out[top] = e(x[top], x[top] - d)
        out[~top] = e(x[~top] + d, x[~top])
        return 2.0 * out / (d * d)

    d = np.arange(n + 1)
    table[d, d, 3] = -(2.0 * m(delta) - m(2.0 * delta))
    if not np.all(np.isfinite(table)):
        raise ValueError("everett (and everett_gradient) must be finite on the triangle")
    return _symmetrise(table)
