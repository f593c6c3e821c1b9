"""The Gaussian width-disorder density of :meth:`ContinuousPreisachModel.gaussian
<hysteresis.preisach.continuous.ContinuousPreisachModel.gaussian>`: its Everett function as a
bi-quintic Hermite table of the separable form (what the model and the compiled engine
evaluate), and the Gauss–Legendre quadrature of the one remaining integral (the reference).

Separable form (``w`` = N(p/2, σ_r²) on ``[r_lo, r_hi]``, ``Φ`` the standard normal CDF, all
divided by the mass ``total``; from ``Φ((b + r)/R) = 1 − Φ((−b − r)/R)``)::

    E(a, b) = ∫_{r_lo}^{t} w(r) [Φ((a − r)/R) − Φ((b + r)/R)] dr = F(a, t) + F(−b, t) − W(t)
    F(x, t) = ∫_{r_lo}^{t} w(r) Φ((x − r)/R) dr,   W(t) = ∫_{r_lo}^{t} w(r) dr,
    t = clip((a − b)/2, r_lo, r_hi)

``W`` in closed form (erf), ``F`` on ``[−L, L] × [r_lo, r_hi]`` by the bi-quintic Hermite
interpolant of :func:`hysteresis.preisach._everett_kernels.everett_eval` (kind 2). Its nodal
data: ``F``, ``F_x``, ``F_xx`` by Gauss–Legendre quadrature (:data:`BUILD_NODES` nodes per
t-cell, cumulated over the cells: on a cell of width ``h_t ≈ σ_r/25`` the rule's error is far
below rounding; 4 nodes already agree with 8 to 1e-15), the t-derivatives in closed form with
``z = (x − t)/R``::

    F_t = w Φ(z)            F_xt = w φ(z)/R          F_xxt = −w z φ(z)/R²
    F_tt = w′Φ(z) − w φ(z)/R          F_xtt = w′φ(z)/R + w z φ(z)/R²
    F_xxtt = −w′ z φ(z)/R² + w (1 − z²) φ(z)/R³

Error bound (interpolation; :func:`table_error_bounds`). The 1-D quintic Hermite interpolant
``H`` of ``f, f′, f″`` at the ends of a cell of width ``h`` has ``|f − Hf| <= h⁶‖f⁽⁶⁾‖/46080``
(the remainder ``f⁽⁶⁾(ξ)(x − x₀)³(x − x₁)³/6!``) and ``|(f − Hf)′| <= h⁵‖f⁽⁶⁾‖/1920`` (``(f −
Hf)′`` has the zeros ``x₀, x₀, z, x₁, x₁``, ``z`` by Rolle, so it is ``f⁽⁶⁾(ξ)/5!`` times a
product bounded by ``h⁴/16 · h``). With ``f − H_t H_x f = (f − H_t f) + H_t(f − H_x f)`` and the
basis sums ``max Σ|Q_{0,p}| = 1``, ``max Σ|Q_{1,p}| = 5/16``, ``max Σ|Q_{2,p}| = 1/32``
(``N_ij`` a bound of ``‖∂_x^i ∂_t^j F‖``, :func:`derivative_bound`)::

    |F − F̂| <= h_t⁶/46080 N_06 + h_x⁶/46080 (N_60 + 5/16 h_t N_61 + 1/32 h_t² N_62)
    |∂_x(F − F̂)| <= h_t⁶/46080 N_16 + h_x⁵/1920 (N_60 + 5/16 h_t N_61 + 1/32 h_t² N_62)
    |∂_t(F − F̂)| <= h_x⁶/46080 N_61 + h_t⁵/1920 (N_06 + 5/16 h_x N_16 + 1/32 h_x² N_26)

``E`` holds two values of ``F`` (``W`` is exact to rounding), its gradient
``∂E/∂a = F_x(a, t) + (F_t(a, t) + F_t(−b, t) − w(t))/2`` (the last bracket only in the band
``r_lo < (a − b)/2 < r_hi``), so ``|E − Ê| <= 2|F − F̂|/total`` and
``|∇(E − Ê)| <= (|∂_x(F − F̂)| + |∂_t(F − F̂)|)/total``. :func:`gaussian_table` chooses the
grid so that the value bound is at most :data:`EVERETT_TOLERANCE` = 1e-12 (half of it from
each direction); the gradient bound (1e-9 at σ_r = 0.2, 1.2e-8 at σ_r = 0.0125) is returned
with the table. Why 1e-12 and not 1e-11: an RK8 step of the oscillator spans several cells,
so the integrator sees the interpolation error as roughness of the right-hand side and errs
by its order per step; at 1e-11 the compiled engine's Poincaré sections (C = 4, σ_r = 0.2,
10 periods, chaotic) moved by 5e-9 from the converged ones, at 1e-12 by 2e-10, as with the
analytic quadrature (measured). ``N_ij`` from the
Leibniz rule, ``‖w⁽ᵏ⁾‖ <= m_k/σ_r^{k+1}``, ``‖Φ⁽ⁿ⁾‖ <= m_{n−1}`` (``m_k = max|φ⁽ᵏ⁾|``,
:data:`PHI_DERIVATIVE_MAX`)::

    N_i0 = m_{i−1}/R^i,   N_ij = Σ_{k<j} C(j−1, k) m_k/σ_r^{k+1} · P_{i+j−1−k},
    P_0 = 1,  P_n = m_{n−1}/R^n

Size: ``n_x ≈ 2L/(0.041 R)``, ``n_t ≈ (r_hi − r_lo)/(0.04 σ_r)`` cells (σ_r <~ R), e.g.
562 × 326 at p = 2, R = 1, σ_r = 0.2 (490 × 388 at σ_r = 0.0125): memory
``72 (n_x + 1)(n_t + 1)`` bytes (13 MB; 12.7–14.3 MB for σ_r in 0.0125 ... 0.4); built in
0.13–0.22 s and cached per parameter set (:func:`gaussian_table`, an LRU cache of
:data:`_TABLE_CACHE` tables) — the width-disorder study builds thousands of models through
workers, with a handful of distinct parameter sets.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.special import ndtr

from hysteresis._validation import (
    bounded_work,
    positive_integer,
    positive_scalar,
    readonly_array,
)
from hysteresis.preisach._everett_kernels import KIND_GAUSSIAN, KIND_SEPARABLE
from hysteresis.preisach.base import _gauss
from hysteresis.preisach.everett_table import EMPTY_TABLE, CompiledEverett

__all__ = [
    "EVERETT_TOLERANCE",
    "GaussianEverett",
    "GaussianTable",
    "derivative_bound",
    "gaussian_everett",
    "gaussian_support",
    "gaussian_table",
    "table_error_bounds",
]

#: the bound of ``|E − Ê|`` :func:`gaussian_table` builds its grid for
EVERETT_TOLERANCE = 1e-12
#: Gauss–Legendre nodes per t-cell of the quadratures that build the nodal ``F, F_x, F_xx``
BUILD_NODES = 6
#: ``m_k = max_z |φ⁽ᵏ⁾(z)|`` (k = 0 .. 6) of the standard normal density, rounded up (the
#: maxima of ``|He_k(z)| φ(z)`` on a fine grid, checked in the tests)
PHI_DERIVATIVE_MAX = (
    0.39894229,
    0.24197073,
    0.39894229,
    0.55058784,
    1.19682685,
    2.30710593,
    5.98413421,
)
#: ``max_s Σ_p |Q_{α,p}(s)|`` of the quintic Hermite basis, α = 0, 1, 2
_BASIS_SUMS = (1.0, 5.0 / 16.0, 1.0 / 32.0)
#: tables kept by :func:`gaussian_table` (~13 MB each)
_TABLE_CACHE = 8
#: largest number of table nodes ``(n_x + 1)(n_t + 1)`` (72 bytes each: 144 MB); reached only
#: for width laws far wider than ``spread`` (the t-grid then resolves ``R``, not ``σ_r``)
_MAX_TABLE_NODES = 2_000_000


def gaussian_support(
    width: float, spread: float, width_spread: float
) -> tuple[float, float, float, float, float, float]:
    """Validated ``(width, spread, width_spread)`` (all > 0) and the support:
    ``(width, spread, width_spread, r_lo, r_hi, L)`` with ``r_lo = max(0, p/2 − 8σ_r)``,
    ``r_hi = p/2 + 8σ_r``, ``L = r_hi + 9R``."""
    width = positive_scalar(width, "width")
    spread = positive_scalar(spread, "spread")
    width_spread = positive_scalar(width_spread, "width_spread")
    half = 0.5 * width
    r_lo = max(0.0, half - 8.0 * width_spread)
    r_hi = half + 8.0 * width_spread
    return width, spread, width_spread, r_lo, r_hi, r_hi + 9.0 * spread


@dataclass(frozen=True)
class GaussianEverett:
    """The reference quadrature of the Everett function of the density
    ``N(s; 0, R²)·N(r; p/2, σ_r²)`` on ``[−L, L]`` (``nodes``-point Gauss–Legendre over
    ``[r_lo, t]``; not what the model evaluates, see :func:`gaussian_table`).

    ``everett``/``gradient`` are vectorised (arguments in the support, ``a > b``);
    ``parameters`` is ``(width, spread, width_spread)`` after validation; ``kernel_params``
    the same quadrature as the ``params`` of the compiled kernel
    (:func:`hysteresis.preisach._everett_kernels.everett_eval`, kind 0).
    """

    everett: Callable
    gradient: Callable
    bound: float
    parameters: tuple[float, float, float]
    kernel_params: np.ndarray

    def compiled(self) -> CompiledEverett:
        """This quadrature for the compiled kernel (kind 0)."""
        return CompiledEverett(KIND_GAUSSIAN, self.kernel_params, EMPTY_TABLE)


def gaussian_everett(
    width: float, spread: float, width_spread: float, nodes: int = 48
) -> GaussianEverett:
    """The ``nodes``-point (>= 4) Gauss–Legendre quadrature of the Gaussian width-disorder
    Everett function (:class:`GaussianEverett`; parameters as :func:`gaussian_support`)."""
    width, spread, width_spread, r_lo, r_hi, bound = gaussian_support(width, spread, width_spread)
    n = positive_integer(nodes, "nodes", minimum=4)
    half = 0.5 * width
    g, gw = _gauss(n)
    norm_r = 1.0 / (width_spread * math.sqrt(2.0 * math.pi))
    norm_s = 1.0 / (spread * math.sqrt(2.0 * math.pi))

    def _nodes(a, b):
        a, b = np.broadcast_arrays(np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64))
        top = np.clip(0.5 * (a - b), r_lo, r_hi)
        span = (top - r_lo)[..., None]
        r = r_lo + span * g
        wr = span * gw * norm_r * np.exp(-0.5 * ((r - half) / width_spread) ** 2)
        return a[..., None], b[..., None], r, wr

    def raw(a, b):
        a, b, r, wr = _nodes(a, b)
        return np.sum(wr * (ndtr((a - r) / spread) - ndtr((b + r) / spread)), axis=-1)

    total = float(raw(bound, -bound))

    def everett(a, b):
        return raw(a, b) / total

    def gradient(a, b):
        a, b, r, wr = _nodes(a, b)
        da = np.sum(wr * np.exp(-0.5 * ((a - r) / spread) ** 2), axis=-1) * norm_s
        db = -np.sum(wr * np.exp(-0.5 * ((b + r) / spread) ** 2), axis=-1) * norm_s
        return da / total, db / total

    return GaussianEverett(
        everett=everett,
        gradient=gradient,
        bound=bound,
        parameters=(width, spread, width_spread),
        kernel_params=readonly_array(
            [-bound, bound, half, width_spread, spread, r_lo, r_hi, norm_r, norm_s, total]
            + list(g)
            + list(gw)
        ),
    )


def derivative_bound(i: int, j: int, width_spread: float, spread: float) -> float:
    """A bound of ``‖∂_x^i ∂_t^j F‖`` on ``[−L, L] × [r_lo, r_hi]`` (``F`` before the division
    by ``total``; the Leibniz rule of the module docstring; ``i, j <= 6``)."""
    m = PHI_DERIVATIVE_MAX

    def phi_part(n: int) -> float:  # ‖∂^n Φ((x − t)/R)‖ in x or t
        return 1.0 if n == 0 else m[n - 1] / spread**n

    if j == 0:
        return phi_part(i)  # ∫ w <= 1
    return sum(
        math.comb(j - 1, k) * m[k] / width_spread ** (k + 1) * phi_part(i + j - 1 - k)
        for k in range(j)
    )


def table_error_bounds(
    hx: float, ht: float, width_spread: float, spread: float, total: float
) -> tuple[float, float]:
    """``(value, gradient)`` bounds of ``|E − Ê|`` and ``|∇(E − Ê)|`` (each component) of the
    bi-quintic table with cells ``hx × ht`` (module docstring)."""

    def n(i, j):
        return derivative_bound(i, j, width_spread, spread)

    s0, s1, s2 = _BASIS_SUMS
    x_part = n(6, 0) * s0 + s1 * ht * n(6, 1) + s2 * ht * ht * n(6, 2)
    t_part = n(0, 6) * s0 + s1 * hx * n(1, 6) + s2 * hx * hx * n(2, 6)
    value = ht**6 / 46080.0 * n(0, 6) + hx**6 / 46080.0 * x_part
    d_x = ht**6 / 46080.0 * n(1, 6) + hx**5 / 1920.0 * x_part
    d_t = hx**6 / 46080.0 * n(6, 1) + ht**5 / 1920.0 * t_part
    return 2.0 * value / total, (d_x + d_t) / total


@dataclass(frozen=True, eq=False)
class GaussianTable:
    """The model's Everett function: ``compiled`` (kind 2, read-only arrays), the stated
    ``value_bound``/``gradient_bound`` of its interpolation error, its grid ``cells``
    ``(n_x, n_t)`` and ``parameters`` ``(width, spread, width_spread)``."""

    compiled: CompiledEverett
    value_bound: float
    gradient_bound: float
    cells: tuple[int, int]
    parameters: tuple[float, float, float]

    @property
    def nbytes(self) -> int:
        return int(self.compiled.table.nbytes)


def _grid(span: float, width_spread: float, spread: float, total: float, tol: float):
    """Cells ``(n_x, n_t)`` with ``2·(t-part)/total <= tol/2`` and ``2·(x-part)/total <= tol/2``
    in the value bound of :func:`table_error_bounds`."""
    x_span, t_span = span
    budget = 0.25 * tol * total  # per F and per direction
    ht = (budget * 46080.0 / derivative_bound(0, 6, width_spread, spread)) ** (1.0 / 6.0)
    n_t = max(1, math.ceil(t_span / ht))
    ht = t_span / n_t
    s0, s1, s2 = _BASIS_SUMS
    x_part = (
        s0 * derivative_bound(6, 0, width_spread, spread)
        + s1 * ht * derivative_bound(6, 1, width_spread, spread)
        + s2 * ht * ht * derivative_bound(6, 2, width_spread, spread)
    )
    hx = (budget * 46080.0 / x_part) ** (1.0 / 6.0)
    return max(1, math.ceil(x_span / hx)), n_t


def gaussian_table(
    width: float, spread: float, width_spread: float, nodes: int = BUILD_NODES
) -> GaussianTable:
    """The bi-quintic table of ``F`` (module docstring; cached per parameter set). ``nodes``
    (>= 4): Gauss–Legendre nodes per t-cell of the build quadratures."""
    width, spread, width_spread, *_ = gaussian_support(width, spread, width_spread)
    return _build_table(width, spread, width_spread, positive_integer(nodes, "nodes", minimum=4))


@functools.lru_cache(maxsize=_TABLE_CACHE)
def _build_table(width: float, spread: float, width_spread: float, nodes: int) -> GaussianTable:
    _, _, _, r_lo, r_hi, bound = gaussian_support(width, spread, width_spread)
    half = 0.5 * width
    norm_r = 1.0 / (width_spread * math.sqrt(2.0 * math.pi))
    phi_lo = float(ndtr((r_lo - half) / width_spread))
    g, gw = _gauss(nodes)
    # a lower bound of the mass (W(r_hi) less the tails Φ(−9) beyond ±L) for the grid
    mass = (float(ndtr((r_hi - half) / width_spread)) - phi_lo) * (1.0 - 2.0 * float(ndtr(-9.0)))
    n_x, n_t = _grid((2.0 * bound, r_hi - r_lo), width_spread, spread, mass, EVERETT_TOLERANCE)
    bounded_work((n_x + 1) * (n_t + 1), "width_spread/spread", _MAX_TABLE_NODES, "table nodes")
    hx = 2.0 * bound / n_x
    ht = (r_hi - r_lo) / n_t
    x = -bound + hx * np.arange(n_x + 1)
    x[-1] = bound
    t = r_lo + ht * np.arange(n_t + 1)
    t[-1] = r_hi
    # cell quadratures: r at the nodes of every t-cell, weights ht·gw·w(r)
    r = (t[:-1, None] + ht * g[None, :]).ravel()
    wr = (ht * np.broadcast_to(gw, (n_t, nodes))).ravel() * norm_r
    wr = wr * np.exp(-0.5 * ((r - half) / width_spread) ** 2)
    z = (x[:, None] - r[None, :]) / spread
    phi = np.exp(-0.5 * z * z) / math.sqrt(2.0 * math.pi)
    table = np.zeros((n_x + 1, n_t + 1, 9))
    for col, values in ((0, ndtr(z)), (3, phi / spread), (6, -z * phi / spread**2)):
        cells = (values * wr).reshape(n_x + 1, n_t, nodes).sum(axis=-1)
        table[:, 1:, col] = np.cumsum(cells, axis=1)
    del z, phi
    # t-derivatives in closed form at the nodes
    zt = (x[:, None] - t[None, :]) / spread
    ph = np.exp(-0.5 * zt * zt) / math.sqrt(2.0 * math.pi)
    w = norm_r * np.exp(-0.5 * ((t - half) / width_spread) ** 2)
    dw = -(t - half) / width_spread**2 * w
    table[..., 1] = w * ndtr(zt)
    table[..., 4] = w * ph / spread
    table[..., 7] = -w * zt * ph / spread**2
    table[..., 2] = dw * ndtr(zt) - w * ph / spread
    table[..., 5] = dw * ph / spread + w * zt * ph / spread**2
    table[..., 8] = -dw * zt * ph / spread**2 + w * (1.0 - zt * zt) * ph / spread**3
    # the mass E(L, −L) = 2 F(L, r_hi) − W(r_hi), by the same cell quadratures as the table
    # layout [F, F_t, F_tt, F_x, F_xt, F_xtt, F_xx, F_xxt, F_xxtt]: index 3α + β, scaled
    total = 2.0 * table[-1, -1, 0] - (float(ndtr((r_hi - half) / width_spread)) - phi_lo)
    scale = np.array([hx**al * ht**be for al in range(3) for be in range(3)]) / total
    table *= scale
    if not np.all(np.isfinite(table)):
        raise ValueError("the Gaussian width-disorder table is not finite (width, spread)")
    value_bound, gradient_bound = table_error_bounds(hx, ht, width_spread, spread, total)
    params = [-bound, bound, hx, r_lo, r_hi, ht, half, width_spread, total, phi_lo]
    return GaussianTable(
        compiled=CompiledEverett(KIND_SEPARABLE, np.array(params), table),
        value_bound=value_bound,
        gradient_bound=gradient_bound,
        cells=(n_x, n_t),
        parameters=(width, spread, width_spread),
    )
