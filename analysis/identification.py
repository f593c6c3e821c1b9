"""Preisach-plane identification from first-order reversal curves (FORCs).

Conventions
-----------
**Mayergoyz (used internally).** A reversal curve starts in *negative* saturation, rises
monotonically to the reversal input ``α`` and then falls monotonically to ``β <= α``; ``f_αβ`` is
the output on the way down, ``f_α = f_αα``. The Everett function is

    E(α, β) = (f_α − f_αβ) / 2,

and for a Preisach operator ``M = ∬ μ(α, β) y_αβ`` it counts the relays that switched up on the
way to ``α`` and back down on the way to ``β``::

    E(α, β) = Σ_k w_k [α_k <= α] [β_k > β]           (relay conventions of docs/architecture.md)

so that ``μ(α, β) = −∂²E/∂α∂β``. ``E(α, β) = 0`` for ``β >= α`` (nothing can have switched back),
which is the exact constant extension of the measured region used below.

**Pike (FORC literature).** A curve starts in *positive* saturation, falls to the reversal field
``H_r`` and rises through fields ``H >= H_r``, moment ``M(H_r, H)``; the FORC distribution is
``ρ(H_r, H) = −½ ∂²M/∂H_r∂H``. For a Preisach operator the same relay count gives

    E(α = H, β = H_r) = (M(H_r, H) − M(H_r, H_r)) / 2,   ρ(H_r, H) = μ(α = H, β = H_r),

i.e. Pike's (H, H_r) are Mayergoyz's (α, β) and the FORC coordinates ``H_c = (H − H_r)/2``,
``H_u = (H + H_r)/2`` are the rotated ``r``, ``s``. Both conventions therefore identify the *same*
cell masses for a Preisach operator (:func:`pike_to_preisach`, :func:`preisach_to_pike` convert the
coordinates; :meth:`ReversalCurves.mirrored` maps the data of one experiment onto the other
experiment on the mirror-image operator ``u → −u, y → −y``).

**Rotated coordinates.** ``s = (α+β)/2`` (centre), ``r = (α−β)/2`` (half-width). The Jacobian is
``dα dβ = 2 dr ds``, so a density per unit ``r``-``s`` area is ``μ_rs = 2 μ_αβ`` (the paper's
``μ(s) δ(r − p/2)`` is a density in ``r``-``s``). FORC software usually plots ``ρ(H_c, H_u)`` with
the value of ``ρ(H_r, H)``, i.e. *without* that factor 2.

Cells and exact masses
----------------------
On nodes ``α_0 < … < α_n`` and ``β_0 < … < β_m`` the cell ``(i, j)`` (1-based) is the half-open
rectangle ``α ∈ (α_{i−1}, α_i]``, ``β ∈ (β_{j−1}, β_j]``; its mass is the mixed second difference

    m_ij = E(α_i, β_{j−1}) − E(α_{i−1}, β_{j−1}) − E(α_i, β_j) + E(α_{i−1}, β_j),

which for a relay system is exactly the weight of relays with thresholds in the cell (a relay
exactly on a node belongs to the cell *below/left* of it). Cells on the diagonal are triangles;
the extension ``E = 0`` for ``β >= α`` makes them exact too. The masses telescope:
``Σ m_ij = E(α_n, β_0)``, the saturation magnetisation (1 for outputs in ``[−1, 1]``) minus the
relays outside the grid (``α <= α_0``, ``α > α_n`` or ``β <= β_0``).

On a regular grid (``α`` and ``β`` nodes equal, step ``Δ``) the cell centres fall on a half-step
lattice, ``s = α_0 + (i + j − 1) Δ/2`` and ``r = (i − j) Δ/2``. The marginals are masses on those
lattices: ``μ(s)`` bins ``k = i + j``, each representing the cell projection
``s ∈ (s_k − Δ/2, s_k + Δ/2]``, and ``μ(r)`` bins ``d = i − j``. A ridge ``r = p/2`` with ``p/Δ``
an integer lies on the single diagonal ``d = p/Δ``, so its ``s``-bin masses are exactly the
probabilities of the intervals ``(α_{i−1} − p/2, α_i − p/2]``; if ``p/Δ`` is not an integer the
ridge splits over ``d = ⌊p/Δ⌋`` and ``⌊p/Δ⌋ + 1`` with centre of mass still at ``p/2``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "ReversalCurves",
    "PreisachIdentification",
    "RidgeComparison",
    "measure_reversal_curves",
    "identify_preisach",
    "identify_from_curves",
    "local_quadratic_density",
    "preisach_to_pike",
    "pike_to_preisach",
    "s_cdf_distance",
    "empirical_cdf",
    "compare_with_ridge",
    "regular_grid",
    "protocol_lattice",
    "grid_quadratic_density",
]

CONVENTIONS = ("mayergoyz", "pike")


# ----------------------------------------------------------------------------------------------
# coordinates
# ----------------------------------------------------------------------------------------------
def preisach_to_pike(alpha: Any, beta: Any) -> tuple[np.ndarray, np.ndarray]:
    """Preisach thresholds (α, β) → Pike FORC coordinates (reversal field H_r, field H).

    ``H_r = β``, ``H = α``; the densities agree pointwise, ``ρ(H_r, H) = μ_αβ(α, β)``.
    """
    return np.asarray(beta, dtype=float), np.asarray(alpha, dtype=float)


def pike_to_preisach(reversal_field: Any, field_: Any) -> tuple[np.ndarray, np.ndarray]:
    """Pike FORC coordinates (H_r, H) → Preisach thresholds (α, β) = (H, H_r)."""
    return np.asarray(field_, dtype=float), np.asarray(reversal_field, dtype=float)


# ----------------------------------------------------------------------------------------------
# reversal-curve data
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class ReversalCurves:
    """A set of first-order reversal curves.

    Attributes
    ----------
    reversal_field:
        Reversal input of each curve (``α`` for Mayergoyz, ``H_r`` for Pike), shape (n_curves,).
    fields:
        Input values along each curve; the first value is the reversal input itself. Mayergoyz
        curves fall (strictly decreasing), Pike curves rise (strictly increasing).
    moments:
        Output at those inputs (same lengths as ``fields``).
    convention:
        ``"mayergoyz"`` (from negative saturation up to α, down to β) or ``"pike"`` (from
        positive saturation down to H_r, up to H).
    """

    reversal_field: np.ndarray
    fields: tuple[np.ndarray, ...]
    moments: tuple[np.ndarray, ...]
    convention: str = "mayergoyz"

    def __post_init__(self) -> None:
        if self.convention not in CONVENTIONS:
            raise ValueError(f"convention must be one of {CONVENTIONS}, got {self.convention!r}")
        rev = np.array(self.reversal_field, dtype=float).reshape(-1)
        if len(self.fields) != rev.size or len(self.moments) != rev.size:
            raise ValueError("reversal_field, fields and moments must have one entry per curve")
        if rev.size == 0:
            raise ValueError("at least one reversal curve is needed")
        fields = []
        moments = []
        sign = -1.0 if self.convention == "mayergoyz" else 1.0
        for c, (h, m) in enumerate(zip(self.fields, self.moments, strict=True)):
            h = np.array(h, dtype=float).reshape(-1)
            m = np.array(m, dtype=float).reshape(-1)
            if h.size == 0 or h.size != m.size:
                raise ValueError(f"curve {c}: fields and moments must be non-empty, equal length")
            if not (np.all(np.isfinite(h)) and np.all(np.isfinite(m))):
                raise ValueError(f"curve {c}: fields and moments must be finite (no NaN/inf)")
            if not np.all(sign * np.diff(h) > 0):
                direction = "decrease" if sign < 0 else "increase"
                raise ValueError(
                    f"curve {c}: fields must strictly {direction} along a {self.convention} curve"
                )
            if not math.isclose(h[0], rev[c], rel_tol=1e-9, abs_tol=1e-12):
                raise ValueError(
                    f"curve {c}: the first field ({h[0]}) must equal the reversal field ({rev[c]})"
                )
            h.setflags(write=False)
            m.setflags(write=False)
            fields.append(h)
            moments.append(m)
        if not np.all(np.isfinite(rev)):
            raise ValueError("reversal_field must be finite")
        if np.unique(rev).size != rev.size:
            raise ValueError("reversal fields must be distinct (one curve per reversal field)")
        rev.setflags(write=False)
        object.__setattr__(self, "reversal_field", rev)
        object.__setattr__(self, "fields", tuple(fields))
        object.__setattr__(self, "moments", tuple(moments))

    @property
    def n_curves(self) -> int:
        return int(self.reversal_field.size)

    @property
    def n_points(self) -> int:
        return int(sum(h.size for h in self.fields))

    def mirrored(self) -> ReversalCurves:
        """The same data read as the other experiment on the mirror-image operator.

        ``u → −u``, ``y → −y`` maps a Pike curve (from positive saturation down to ``H_r``, up)
        onto a Mayergoyz curve (from negative saturation up to ``α = −H_r``, down) and back. For an
        operator that is symmetric under the mirror (the erf play, a symmetric Preisach model) the
        mirrored Pike data are the Mayergoyz data of the operator itself.
        """
        other = "pike" if self.convention == "mayergoyz" else "mayergoyz"
        return ReversalCurves(
            -self.reversal_field,
            tuple(-h for h in self.fields),
            tuple(-m for m in self.moments),
            other,
        )

    def as_rows(self) -> np.ndarray:
        """All points as rows ``(reversal_field, field, moment)``, curve after curve."""
        rows = [
            np.column_stack([np.full(h.size, r), h, m])
            for r, h, m in zip(self.reversal_field, self.fields, self.moments, strict=True)
        ]
        return np.vstack(rows)


def regular_grid(step: float, saturation: float, centre: float = 0.0) -> np.ndarray:
    """Nodes ``centre + k·step`` for ``k = −K … K``, ``K = ⌈saturation/step⌉``.

    The grid covers at least ``[centre − saturation, centre + saturation]``.
    """
    step = _positive(step, "step")
    saturation = _positive(saturation, "saturation")
    centre = _finite(centre, "centre")
    k_max = int(math.ceil(saturation / step - 1e-9))
    return centre + step * np.arange(-k_max, k_max + 1, dtype=float)


def measure_reversal_curves(
    operator: Any,
    reversal_fields: Any,
    fields: Any | None = None,
    convention: str = "mayergoyz",
    saturation: float | None = None,
    progress: bool = False,
) -> ReversalCurves:
    """Drive ``operator`` through first-order reversal curves (one ``apply`` per curve).

    Parameters
    ----------
    operator:
        Any operator with ``initial_state(u0)`` and ``apply(inputs, state)``.
    reversal_fields:
        Reversal inputs (``α`` for Mayergoyz, ``H_r`` for Pike).
    fields:
        Input values at which the curves are sampled (default: the reversal fields themselves).
        Each curve visits the values beyond its reversal field in monotone order, starting with
        the reversal field.
    convention:
        ``"mayergoyz"``: ``initial_state(α)`` (rise from negative saturation), then fall.
        ``"pike"``: ``initial_state(saturation)``, fall to ``H_r``, then rise.
    saturation:
        Positive saturation input for Pike curves (required for ``"pike"``).
    """
    if convention not in CONVENTIONS:
        raise ValueError(f"convention must be one of {CONVENTIONS}, got {convention!r}")
    rev = np.unique(np.asarray(reversal_fields, dtype=float))
    if rev.size == 0 or not np.all(np.isfinite(rev)):
        raise ValueError("reversal_fields must be a non-empty sequence of finite numbers")
    pts = rev if fields is None else np.unique(np.asarray(fields, dtype=float))
    if not np.all(np.isfinite(pts)):
        raise ValueError("fields must be finite")
    if convention == "pike":
        if saturation is None:
            raise ValueError("saturation is required for Pike curves (positive saturation input)")
        saturation = _finite(saturation, "saturation")
        if saturation < rev.max() or saturation < pts.max():
            raise ValueError("saturation must be >= every reversal field and field (Pike curves)")
    out_fields, out_moments = [], []
    iterator = _progress(rev, progress, "reversal curves")
    for a in iterator:
        if convention == "mayergoyz":
            inputs = np.concatenate([[a], pts[pts < a][::-1]])
            state = operator.initial_state(float(a))
            y, _ = operator.apply(inputs, state)
        else:
            inputs = np.concatenate([[a], pts[pts > a]])
            state = operator.initial_state(float(saturation))
            y, _ = operator.apply(inputs, state)  # first input: monotone fall to H_r
        out_fields.append(inputs)
        out_moments.append(np.asarray(y, dtype=float))
    return ReversalCurves(rev, tuple(out_fields), tuple(out_moments), convention)


# ----------------------------------------------------------------------------------------------
# the identification result
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class PreisachIdentification:
    """Result of a Preisach-plane identification.

    Attributes
    ----------
    alpha, beta:
        Node values (ascending), shapes (n_a + 1,), (n_b + 1,).
    everett:
        ``E(α_i, β_j)``, shape (n_a + 1, n_b + 1); 0 (the exact extension) where ``β_j >= α_i``.
    cell_mass:
        Exact unsmoothed masses, shape (n_a, n_b): ``cell_mass[i−1, j−1]`` is the mass with
        ``α ∈ (α_{i−1}, α_i]``, ``β ∈ (β_{j−1}, β_j]``.
    step:
        Grid step ``Δ`` if the grid is regular (α and β nodes equal and uniform), else ``None``.
    output_range:
        Saturation outputs of the operator (used for :attr:`mass_outside_grid`).
    density_alpha_beta:
        Smoothed ``μ_αβ`` at the nodes (NaN where not evaluated), or ``None``.
    smoothing:
        ``(half-width across r, half-width along s)`` of the regression window in units of the
        step, or ``None``.
    convention:
        Convention of the reversal curves the identification was made from.
    measured:
        Boolean mask of the nodes, shape (n_a + 1, n_b + 1): ``True`` where ``E`` comes from
        measured points (protocol grid of :func:`identify_from_curves`), ``None`` when every
        node is exact (operators, shared-field data).
    reversible_ridge:
        Whether the smoothed density includes the reversible ridge at ``r = 0`` (the extension
        ``E = 0`` for ``β >= α`` used in the regression) or excludes it (measured points only).
    n_curves, n_points:
        Size of the data set the identification was made from (``None`` if not from curves).
    """

    alpha: np.ndarray
    beta: np.ndarray
    everett: np.ndarray
    cell_mass: np.ndarray
    step: float | None
    output_range: tuple[float, float] = (-1.0, 1.0)
    density_alpha_beta: np.ndarray | None = None
    smoothing: tuple[float, float] | None = None
    convention: str = "mayergoyz"
    measured: np.ndarray | None = None
    reversible_ridge: bool = True
    n_curves: int | None = None
    n_points: int | None = None

    # -- totals ----------------------------------------------------------------------------
    @property
    def total_mass(self) -> float:
        """Σ cell masses = E(α_n, β_0) − E(α_0, β_0) (telescoped)."""
        return float(self.cell_mass.sum())

    @property
    def mass_outside_grid(self) -> float:
        """Saturation magnetisation ``(hi − lo)/2`` minus :attr:`total_mass` (NaN if unbounded)."""
        lo, hi = self.output_range
        if not (math.isfinite(lo) and math.isfinite(hi)):
            return float("nan")
        return 0.5 * (hi - lo) - self.total_mass

    @property
    def is_regular(self) -> bool:
        return self.step is not None

    def _diagonal_cells(self) -> np.ndarray:
        """Cells that touch the diagonal ``α = β`` (``α_lo < β_hi``): they hold the zero-width
        relays, i.e. the reversible part of a measured sample."""
        a_lo, _, _, b_hi = self.cell_bounds()
        return a_lo < b_hi

    @property
    def reversible_mass(self) -> float:
        """Mass of the cells touching the diagonal (the reversible ridge at ``r = 0``)."""
        return float(self.cell_mass[self._diagonal_cells()].sum())

    @property
    def irreversible_mass(self) -> float:
        """Mass of the cells off the diagonal (``α_lo >= β_hi``): :attr:`total_mass` without
        :attr:`reversible_mass`. For FORC data in moment units this is the irreversible moment
        ``∬ ρ dH_r dH`` (half the irreversible magnetisation change)."""
        return float(self.cell_mass[~self._diagonal_cells()].sum())

    def density_peak(self) -> tuple[float, float, float]:
        """``(r, s, μ_αβ)`` at the node of the largest smoothed density.

        In FORC terms ``(B_c, B_u, ρ)`` (``ρ = μ_αβ``, Pike's −½ ∂²M/∂H_r∂H). Needs an
        identification made with ``smoothing``; NaN nodes (outside the measured region) are
        ignored.
        """
        if self.density_alpha_beta is None:
            raise ValueError("density_peak needs an identification made with smoothing")
        dens = self.density_alpha_beta
        if not np.any(np.isfinite(dens)):
            raise ValueError("the smoothed density is NaN everywhere (too few data points)")
        i, j = np.unravel_index(np.nanargmax(dens), dens.shape)
        a, b = float(self.alpha[i]), float(self.beta[j])
        return 0.5 * (a - b), 0.5 * (a + b), float(dens[i, j])

    # -- cells -----------------------------------------------------------------------------
    def cell_bounds(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Broadcast arrays ``(α_lo, α_hi, β_lo, β_hi)`` of every cell, shape (n_a, n_b)."""
        a_lo = self.alpha[:-1, None] + 0.0 * self.beta[None, 1:]
        a_hi = self.alpha[1:, None] + 0.0 * self.beta[None, 1:]
        b_lo = self.beta[None, :-1] + 0.0 * self.alpha[1:, None]
        b_hi = self.beta[None, 1:] + 0.0 * self.alpha[1:, None]
        return a_lo, a_hi, b_lo, b_hi

    def cell_centres_rs(self) -> tuple[np.ndarray, np.ndarray]:
        """Cell centres in rotated coordinates ``(r, s)``, shapes (n_a, n_b)."""
        a_lo, a_hi, b_lo, b_hi = self.cell_bounds()
        a_c = 0.5 * (a_lo + a_hi)
        b_c = 0.5 * (b_lo + b_hi)
        return 0.5 * (a_c - b_c), 0.5 * (a_c + b_c)

    def cell_area(self) -> np.ndarray:
        """Area in the α-β plane of the physical part (``β <= α``) of every cell (triangles on
        the diagonal have half the area of the square)."""
        a_lo, a_hi, b_lo, b_hi = self.cell_bounds()
        w = b_hi - b_lo

        def antiderivative(x):  # ∫ clip(x' − b_lo, 0, w) dx'
            t = np.clip(x - b_lo, 0.0, None)
            return np.where(t <= w, 0.5 * t * t, 0.5 * w * w + w * (t - w))

        return antiderivative(a_hi) - antiderivative(a_lo)

    def cell_density_rs(self) -> np.ndarray:
        """Unsmoothed density per unit r-s area, ``μ_rs = 2 · mass / area_αβ`` (NaN for cells
        with no physical part)."""
        area = self.cell_area()
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(area > 0, 2.0 * self.cell_mass / area, np.nan)

    @property
    def density_rs(self) -> np.ndarray | None:
        """Smoothed density per unit r-s area, ``μ_rs = 2 μ_αβ`` at the nodes."""
        if self.density_alpha_beta is None:
            return None
        return 2.0 * self.density_alpha_beta

    # -- marginals on the half-step lattice (regular grids) ----------------------------------
    def _require_regular(self) -> float:
        if self.step is None:
            raise ValueError(
                "marginals on the half-step lattice need a regular grid (equal, uniform α and β "
                "nodes); use cell_centres_rs() and cell_mass for irregular data"
            )
        return self.step

    def s_marginal(self) -> tuple[np.ndarray, np.ndarray]:
        """``(s_k, mass_k)``: mass of the cells with ``i + j = k``, ``s_k = α_0 + (k − 1)Δ/2``.

        Bin ``k`` holds cells whose projection is ``s ∈ (s_k − Δ/2, s_k + Δ/2]``; neighbouring
        bins overlap by half, a ridge ``r = p/2`` (``p/Δ`` integer) fills every other bin exactly.
        """
        step = self._require_regular()
        n = self.cell_mass.shape[0]
        i, j = np.indices(self.cell_mass.shape)
        k = (i + 1) + (j + 1)
        masses = np.bincount(k.ravel(), weights=self.cell_mass.ravel(), minlength=2 * n + 1)[2:]
        centres = self.alpha[0] + (np.arange(2, 2 * n + 1) - 1) * 0.5 * step
        return centres, masses

    def r_marginal(self) -> tuple[np.ndarray, np.ndarray]:
        """``(r_d, mass_d)`` for diagonals ``d = i − j = 0 … n−1``, ``r_d = dΔ/2``.

        Bin ``d`` holds cells whose projection is ``r ∈ ((d−1)Δ/2, (d+1)Δ/2)``.
        """
        step = self._require_regular()
        n = self.cell_mass.shape[0]
        i, j = np.indices(self.cell_mass.shape)
        d = (i - j).ravel()
        keep = d >= 0
        masses = np.bincount(d[keep], weights=self.cell_mass.ravel()[keep], minlength=n)
        return np.arange(n) * 0.5 * step, masses

    def s_density(self) -> tuple[np.ndarray, np.ndarray]:
        """``μ(s)`` estimate for plotting: the s-marginal with the kernel [¼, ½, ¼] / (Δ/2).

        Normalised for any density. For a ridge on one diagonal (every other bin filled) it is
        exactly mass/Δ at the filled bins and the mean of the neighbours at the empty ones.
        """
        step = self._require_regular()
        s, m = self.s_marginal()
        padded = np.concatenate([[0.0], m, [0.0]])
        smooth = 0.25 * padded[:-2] + 0.5 * padded[1:-1] + 0.25 * padded[2:]
        return s, smooth / (0.5 * step)


# ----------------------------------------------------------------------------------------------
# identification
# ----------------------------------------------------------------------------------------------
def identify_preisach(
    operator: Any,
    step: float,
    saturation: float,
    *,
    centre: float = 0.0,
    smoothing: float | tuple[float, float] | None = None,
    progress: bool = False,
) -> PreisachIdentification:
    """Identify the Preisach density of ``operator`` from reversal curves on a regular grid.

    The grid is :func:`regular_grid` ``(step, saturation, centre)``. For every node ``α_i`` the
    operator is put in ``initial_state(α_i)`` (rise from negative saturation) and driven by one
    ``apply`` through the descending nodes ``α_i, α_{i−1}, …, α_0`` (Mayergoyz convention). The
    result holds the Everett function on the grid and the exact cell masses (see module
    docstring). ``saturation`` should make the operator saturate at ``±saturation`` (for the
    paper's density, ``saturation >= 5R + p/2`` leaves < 6·10⁻⁷ of the mass outside).

    Parameters
    ----------
    smoothing:
        ``None`` (no smoothed density), a smoothing factor ``SF`` (isotropic) or
        ``(SF_r, SF_s)``: local quadratic regression of ``E`` over the nodes with
        ``|Δr| <= SF_r·Δ`` and ``|Δs| <= SF_s·Δ`` (keep ``SF_r`` small across a ridge and
        ``SF_s`` larger along it); see :func:`local_quadratic_density`.
    """
    from hysteresis._validation import check_grid_nodes

    check_grid_nodes(step, saturation)  # refuse an unbounded grid (MAX_GRID_NODES) up front
    grid = regular_grid(step, saturation, centre)
    curves = measure_reversal_curves(operator, grid, convention="mayergoyz", progress=progress)
    output_range = tuple(float(x) for x in getattr(operator, "output_range", (-1.0, 1.0)))
    return identify_from_curves(curves, smoothing=smoothing, output_range=output_range, extend=True)


def _everett_table(curves: ReversalCurves) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """E on (curve nodes × union of fields); returns (alpha_nodes, beta_nodes, E[alpha, beta]).

    Along each curve E is taken at its native points, linearly interpolated between them (exact
    at the native points; exact everywhere when the curves share their field values), zero on the
    reversal side (the exact extension) and constant beyond the curve's last point (the curve is
    assumed to end in saturation).
    """
    order = np.argsort(curves.reversal_field)
    rev = curves.reversal_field[order]
    pts = np.unique(np.concatenate(curves.fields))
    table = np.zeros((rev.size, pts.size))
    for row, c in enumerate(order):
        h = curves.fields[c]
        m = curves.moments[c]
        if curves.convention == "mayergoyz":
            e = 0.5 * (m[0] - m)  # E(α = H_r, β = h)
            # h falls; np.interp needs ascending abscissae
            vals = np.interp(pts, h[::-1], e[::-1])  # constant beyond both ends
            vals[pts >= h[0]] = 0.0
        else:
            e = 0.5 * (m - m[0])  # E(α = h, β = H_r)
            vals = np.interp(pts, h, e)
            vals[pts <= h[0]] = 0.0
        table[row] = vals
    if curves.convention == "mayergoyz":
        return rev, pts, table
    return pts, rev, table.T.copy()


def _is_regular(alpha: np.ndarray, beta: np.ndarray) -> float | None:
    if alpha.size < 2 or alpha.size != beta.size or not np.array_equal(alpha, beta):
        return None
    d = np.diff(alpha)
    step = (alpha[-1] - alpha[0]) / (alpha.size - 1)
    if np.allclose(d, step, rtol=1e-9, atol=0.0):
        return float(step)
    return None


GRIDS = ("auto", "native", "protocol")
MAX_PROTOCOL_NODES = 3000
WINDOWS = ("rs", "pike")


def identify_from_curves(
    curves: ReversalCurves,
    *,
    smoothing: float | tuple[float, float] | None = None,
    output_range: tuple[float, float] = (-1.0, 1.0),
    extend: bool | None = None,
    grid: str = "auto",
    step: float | None = None,
    window: str = "rs",
) -> PreisachIdentification:
    """Identify from reversal-curve data (measured or simulated, regular or irregular).

    Parameters
    ----------
    curves:
        The reversal curves (either convention).
    smoothing:
        ``None`` (cell masses only), a smoothing factor ``SF`` or ``(SF_r, SF_s)``: local
        quadratic regression of ``E`` in the window ``|Δr| <= SF_r·Δ``, ``|Δs| <= SF_s·Δ``
        (see :func:`identify_preisach`). On the native grid of irregular data the unit ``Δ`` is
        the larger of the median reversal-field spacing and the median field step.
    output_range:
        Saturation outputs (for :attr:`PreisachIdentification.mass_outside_grid`); pass
        ``(-inf, inf)`` for measured data of unknown saturation.
    extend:
        Use the extension ``E = 0`` for ``β >= α`` in the regression. This is exact for relay
        (Preisach) systems and puts the reversible part of a measured sample into a ridge at
        ``r = 0``; ``False`` regresses measured points only (the usual irreversible FORC
        density, NaN where a window has no data on one side of a node). Default (``None``):
        ``True`` on the native grid (simulated data), ``False`` on the protocol grid
        (measured data: the reversible ridge is excluded unless asked for).
    grid:
        ``"native"``: nodes are the reversal fields along one axis and the union of all field
        values along the other (exact cell masses of simulated or shared-lattice data; no
        regridding). ``"protocol"``: a regular lattice with the measurement's field step ``Δ``
        (``step``, default the median field increment along the curves), anchored at the
        reversal fields; each curve is interpolated linearly onto it along the field and
        neighbouring curves linearly across reversal fields. Use it for measured data, whose
        field values all differ slightly (the native grid of such data has near-zero-area
        cells). ``"auto"`` (default): ``"protocol"`` when the union of field values has more
        than twice as many values as the longest curve plus the number of curves (measured
        fields), else ``"native"``.
    step:
        Lattice step of the protocol grid (> 0); ignored on the native grid.
    window:
        Shape of the regression window on the protocol grid: ``"rs"`` (default),
        ``|Δr| <= SF_r·Δ`` and ``|Δs| <= SF_s·Δ``; ``"pike"``, Pike et al. (1999)'s square
        ``|Δα| <= SF·Δ`` and ``|ΔB_r| = |Δβ| <= SF·Δ`` (``(2 SF + 1)²`` points, ``SF = SF_r``).
        The native grid always uses ``"rs"``.

    Returns
    -------
    PreisachIdentification
        With ``measured`` set on the protocol grid (nodes backed by data; outside it ``E`` is
        extended: 0 for ``β >= α``, constant beyond a curve's last point) and the smoothed
        density NaN wherever the node is not measured or its window lacks data on either side
        across or along the diagonal.
    """
    if grid not in GRIDS:
        raise ValueError(f"grid must be one of {GRIDS}, got {grid!r}")
    if grid == "auto":
        n_union = np.unique(np.concatenate(curves.fields)).size
        longest = max(h.size for h in curves.fields)
        grid = "protocol" if n_union > 2 * (longest + curves.n_curves) else "native"
    if window not in WINDOWS:
        raise ValueError(f"window must be one of {WINDOWS}, got {window!r}")
    if grid == "protocol":
        ext = False if extend is None else bool(extend)
        return _identify_protocol(curves, smoothing, output_range, ext, step, window)
    extend = True if extend is None else bool(extend)
    alpha, beta, E = _everett_table(curves)
    if alpha.size < 2 or beta.size < 2:
        raise ValueError("need at least two reversal curves and two distinct fields")
    mass = E[1:, :-1] - E[:-1, :-1] - E[1:, 1:] + E[:-1, 1:]
    reg_step = _is_regular(alpha, beta)
    density = None
    sm = None
    if smoothing is not None:
        sm = _smoothing_factors(smoothing)
        unit = reg_step if reg_step is not None else _typical_step(curves)
        pa, pb, pe = _native_points(
            curves, beta if curves.convention == "mayergoyz" else alpha, extend
        )
        aa, bb = np.meshgrid(alpha, beta, indexing="ij")
        where = bb <= aa
        density = np.full(aa.shape, np.nan)
        density[where] = local_quadratic_density(
            pa, pb, pe, aa[where], bb[where], sm[0] * unit, sm[1] * unit
        )
    for arr in (alpha, beta, E, mass):
        arr.setflags(write=False)
    if density is not None:
        density.setflags(write=False)
    return PreisachIdentification(
        alpha=alpha,
        beta=beta,
        everett=E,
        cell_mass=mass,
        step=reg_step,
        output_range=(float(output_range[0]), float(output_range[1])),
        density_alpha_beta=density,
        smoothing=sm,
        convention=curves.convention,
        reversible_ridge=extend,
        n_curves=curves.n_curves,
        n_points=curves.n_points,
    )


def _rising_form(curves: ReversalCurves) -> tuple[np.ndarray, list, list]:
    """Curves as rising branches ``(R_c, h, E_c(h))`` with ``h >= R_c``: Pike curves as they
    are, Mayergoyz curves mirrored (``R = −α``, ``h = −β``); ``E`` is the Everett function in
    both cases."""
    if curves.convention == "pike":
        rev = np.asarray(curves.reversal_field)
        fields = list(curves.fields)
        ev = [0.5 * (m - m[0]) for m in curves.moments]
    else:
        rev = -np.asarray(curves.reversal_field)
        fields = [-h for h in curves.fields]
        ev = [0.5 * (m[0] - m) for m in curves.moments]
    return rev, fields, ev


def protocol_lattice(curves: ReversalCurves, step: float | None = None) -> np.ndarray:
    """Regular nodes of the measurement protocol for ``curves``.

    The step is ``step`` or the median increment of the field along the curves; the lattice
    is anchored at the reversal fields (circular mean of their offsets modulo the step, so that
    a regular protocol with slightly drifting measured fields lands on its nominal nodes) and
    spans from the lowest reversal field to the highest field (Pike; mirrored for Mayergoyz).
    """
    rev, fields, _ = _rising_form(curves)
    if step is None:
        inc = np.concatenate([np.diff(h) for h in fields])
        if inc.size == 0:
            raise ValueError("every curve has one point: pass the lattice step explicitly")
        step = float(np.median(inc))
    step = _positive(step, "step")
    phase = np.angle(np.mean(np.exp(2j * np.pi * rev / step)))
    offset = step * phase / (2 * np.pi)
    lo = float(rev.min())
    hi = float(max(h[-1] for h in fields))
    k_lo = int(np.floor((lo - offset) / step + 0.5))
    k_hi = int(np.floor((hi - offset) / step + 0.5))
    if k_hi - k_lo < 1:
        raise ValueError(f"step {step} is larger than the field range of the data")
    if k_hi - k_lo >= MAX_PROTOCOL_NODES:
        # the lattice is square: memory and time grow with the square of the node count
        raise ValueError(
            f"step {step} gives {k_hi - k_lo + 1} nodes (> {MAX_PROTOCOL_NODES}); choose a "
            "larger step"
        )
    return offset + step * np.arange(k_lo, k_hi + 1, dtype=float)


def _protocol_table(
    curves: ReversalCurves, step: float | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Everett table on the protocol lattice: ``(nodes, E[α, β], measured[α, β], step)``."""
    nodes = protocol_lattice(curves, step)
    step = float(nodes[1] - nodes[0])
    rev, fields, ev = _rising_form(curves)
    order = np.argsort(rev)
    rev = rev[order]
    n = nodes.size
    half = 0.5 * step
    g = np.empty((rev.size, n))
    meas = np.empty((rev.size, n), dtype=bool)
    for row, c in enumerate(order):
        h, e = fields[c], ev[c]
        g[row] = np.interp(nodes, h, e)  # 0 below the reversal field, constant beyond the end
        g[row, nodes < h[0]] = 0.0
        meas[row] = (nodes >= h[0] - half) & (nodes <= h[-1] + half)
    # across reversal fields: linear interpolation between the bracketing curves
    k = np.clip(np.searchsorted(rev, nodes), 1, max(rev.size - 1, 1))
    if rev.size == 1:
        t = np.zeros(n)
        c0 = c1 = np.zeros(n, dtype=int)
    else:
        c0, c1 = k - 1, k
        t = np.clip((nodes - rev[c0]) / (rev[c1] - rev[c0]), 0.0, 1.0)
    table = (1.0 - t)[:, None] * g[c0] + t[:, None] * g[c1]
    used0 = t < 1.0 - 1e-9
    used1 = t > 1e-9
    m_tab = (meas[c0] | ~used0[:, None]) & (meas[c1] | ~used1[:, None])
    # nodes farther than half a step outside the reversal-field range are not measured
    outside = (nodes < rev[0] - half) | (nodes > rev[-1] + half)
    m_tab[outside] = False
    # above the highest reversal field nothing reverses: E(x, h) = E_last(h) − E_last(x) (the
    # upper branch of the last curve; a constant in x would pile its cumulative rise into
    # every diagonal cell)
    above = np.flatnonzero(nodes > rev[-1] + half)
    if above.size:
        last = g[np.argmax(rev)] if rev.size else g[0]
        table[above] = last[None, :] - last[above][:, None]
    # table[R, h]; physical region h >= R; on and below the diagonal E = 0 exactly
    below = nodes[None, :] <= nodes[:, None]
    table[below] = 0.0
    diag = np.eye(n, dtype=bool) & ~outside[:, None]
    m_tab = (m_tab & ~below) | diag
    if curves.convention == "pike":  # alpha = h, beta = R
        E, measured = table.T.copy(), m_tab.T.copy()
        out_nodes = nodes
    else:  # alpha = -R', beta = -h'
        E, measured = table[::-1, ::-1].copy(), m_tab[::-1, ::-1].copy()
        out_nodes = -nodes[::-1]
    return out_nodes, E, measured, step


def _identify_protocol(
    curves: ReversalCurves,
    smoothing: float | tuple[float, float] | None,
    output_range: tuple[float, float],
    extend: bool,
    step: float | None,
    window: str = "rs",
) -> PreisachIdentification:
    nodes, E, measured, step = _protocol_table(curves, step)
    mass = E[1:, :-1] - E[:-1, :-1] - E[1:, 1:] + E[:-1, 1:]
    density = None
    sm = None
    if smoothing is not None:
        sm = _smoothing_factors(smoothing)
        aa, bb = np.meshgrid(nodes, nodes, indexing="ij")
        valid = measured | ((bb > aa) if extend else False)
        evaluate = measured & (bb <= aa)
        density = grid_quadratic_density(E, valid, evaluate, step, sm[0], sm[1], window)
        density.setflags(write=False)
    alpha = nodes.copy()
    beta = nodes.copy()
    for arr in (alpha, beta, E, mass, measured):
        arr.setflags(write=False)
    return PreisachIdentification(
        alpha=alpha,
        beta=beta,
        everett=E,
        cell_mass=mass,
        step=step,
        output_range=(float(output_range[0]), float(output_range[1])),
        density_alpha_beta=density,
        smoothing=sm,
        convention=curves.convention,
        measured=measured,
        reversible_ridge=extend,
        n_curves=curves.n_curves,
        n_points=curves.n_points,
    )


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
    from scipy.signal import fftconvolve

    E = np.asarray(everett, dtype=float)
    v = np.asarray(valid, dtype=bool)
    ev = np.asarray(evaluate, dtype=bool)
    if E.ndim != 2 or v.shape != E.shape or ev.shape != E.shape:
        raise ValueError("everett, valid and evaluate must be 2-D arrays of the same shape")
    step = _positive(step, "step")
    sf_r = _positive(sf_r, "sf_r")
    sf_s = _positive(sf_s, "sf_s")
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


def _native_points(
    curves: ReversalCurves, other_nodes: np.ndarray, extend: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Scattered (α, β, E) at the native curve points, plus extension points E = 0."""
    a_list, b_list, e_list = [], [], []
    for r, h, m in zip(curves.reversal_field, curves.fields, curves.moments, strict=True):
        if curves.convention == "mayergoyz":
            a_list.append(np.full(h.size, r))
            b_list.append(h)
            e_list.append(0.5 * (m[0] - m))
            if extend:
                ext = other_nodes[other_nodes > r]
                a_list.append(np.full(ext.size, r))
                b_list.append(ext)
                e_list.append(np.zeros(ext.size))
        else:
            a_list.append(h)
            b_list.append(np.full(h.size, r))
            e_list.append(0.5 * (m - m[0]))
            if extend:
                ext = other_nodes[other_nodes < r]
                a_list.append(ext)
                b_list.append(np.full(ext.size, r))
                e_list.append(np.zeros(ext.size))
    return np.concatenate(a_list), np.concatenate(b_list), np.concatenate(e_list)


def _typical_step(curves: ReversalCurves) -> float:
    """Smoothing unit for irregular data: the larger of the median spacing of the reversal
    fields and the median field step along the curves."""
    rev = np.diff(np.sort(curves.reversal_field))
    along = np.concatenate([np.abs(np.diff(h)) for h in curves.fields])
    candidates = [float(np.median(x)) for x in (rev, along) if x.size]
    if not candidates:
        raise ValueError("smoothing needs at least two reversal curves or two points per curve")
    return max(candidates)


def _smoothing_factors(smoothing: float | tuple[float, float]) -> tuple[float, float]:
    if np.ndim(smoothing) == 0:
        sf = _positive(smoothing, "smoothing")
        return (sf, sf)
    if len(smoothing) != 2:
        raise ValueError("smoothing must be a positive number or a pair (SF_r, SF_s)")
    return (
        _positive(smoothing[0], "smoothing[0] (SF_r)"),
        _positive(smoothing[1], "smoothing[1] (SF_s)"),
    )


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
    from scipy.spatial import cKDTree

    a = np.asarray(alpha, dtype=float).ravel()
    b = np.asarray(beta, dtype=float).ravel()
    e = np.asarray(everett, dtype=float).ravel()
    qa = np.asarray(at_alpha, dtype=float).ravel()
    qb = np.asarray(at_beta, dtype=float).ravel()
    hr = _positive(half_width_r, "half_width_r")
    hs = _positive(half_width_s, "half_width_s")
    if not (a.size == b.size == e.size):
        raise ValueError("alpha, beta and everett must have the same length")
    # scaled rotated coordinates: the window is the unit Chebyshev ball
    pts = np.column_stack([0.5 * (a - b) / hr, 0.5 * (a + b) / hs])
    qpts = np.column_stack([0.5 * (qa - qb) / hr, 0.5 * (qa + qb) / hs])
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


# ----------------------------------------------------------------------------------------------
# comparison with the analytic ridge density N(s; s0, R²) δ(r − p/2)
# ----------------------------------------------------------------------------------------------
def empirical_cdf(samples: Any) -> Callable[[np.ndarray], np.ndarray]:
    """Right-continuous empirical CDF of ``samples``."""
    x = np.sort(np.asarray(samples, dtype=float).ravel())
    if x.size == 0:
        raise ValueError("samples must be non-empty")

    def cdf(t: Any) -> np.ndarray:
        return np.searchsorted(x, np.asarray(t, dtype=float), side="right") / x.size

    return cdf


def s_cdf_distance(ident: PreisachIdentification, cdf: Callable[[np.ndarray], np.ndarray]) -> float:
    """Sup-norm distance between the identified s-marginal CDF and ``cdf``.

    A cell's mass lies in ``s ∈ ((α_lo+β_lo)/2, (α_hi+β_hi)/2]``, so the CDF ``G`` of the
    identified mass is only known to lie between ``L(x) = Σ m[s_hi <= x]`` and
    ``U(x) = Σ m[s_lo < x]``. The distance is ``sup_x max(cdf − U, L − cdf, 0)``, the distance of
    ``cdf`` to that band (mass outside the grid is not included). It is exact at the resolution
    of the grid: for a ridge on one diagonal the band collapses to points at the cell edges, and
    the empirical CDF of the relays' own centres has distance exactly 0.
    """
    a_lo, a_hi, b_lo, b_hi = ident.cell_bounds()
    m = np.asarray(ident.cell_mass).ravel()
    keep = m != 0.0
    s_lo = (0.5 * (a_lo + b_lo)).ravel()[keep]
    s_hi = (0.5 * (a_hi + b_hi)).ravel()[keep]
    m = m[keep]
    if m.size == 0:
        return float("nan")
    o_hi = np.argsort(s_hi, kind="stable")
    o_lo = np.argsort(s_lo, kind="stable")
    sh, ch = s_hi[o_hi], np.cumsum(m[o_hi])
    sl, cl = s_lo[o_lo], np.cumsum(m[o_lo])
    # L at x = s_hi values: all cells with s_hi <= x
    lower = ch[np.searchsorted(sh, sh, side="right") - 1]
    # U at x = s_lo values: all cells with s_lo < x
    pos = np.searchsorted(sl, sl, side="left")
    upper = np.where(pos > 0, cl[np.maximum(pos - 1, 0)], 0.0)
    d1 = np.max(lower - np.asarray(cdf(sh), dtype=float))
    d2 = np.max(np.asarray(cdf(sl), dtype=float) - upper)
    return float(max(d1, d2, 0.0))


@dataclass(frozen=True)
class RidgeComparison:
    """Identified density vs ``N(s; centre, R²) δ(r − p/2)``.

    ``r_mass_within_2_cells``: fraction of the identified mass whose cell centre is within two
    grid cells of the ridge (``|r_c − p/2| <= Δ``, two diagonals on the regular lattice where
    ``r`` steps by ``Δ/2``). ``s_cdf_distance_empirical`` and ``kolmogorov_bound``
    (``1.36/sqrt(n)``, 95 %) are set when the finite ensemble's centres were given.
    """

    total_mass: float
    r_centre: float
    r_spread: float
    r_mass_within_2_cells: float
    s_cdf_distance_gaussian: float
    s_cdf_distance_empirical: float | None = None
    kolmogorov_bound: float | None = None
    n_units: int | None = None

    def as_dict(self) -> dict[str, Any]:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


def compare_with_ridge(
    ident: PreisachIdentification,
    width: float,
    spread: float,
    centre: float = 0.0,
    centres: Any | None = None,
) -> RidgeComparison:
    """Compare with the paper's density ``N(s; centre, R²) δ(r − p/2)`` (width p, spread R).

    ``centres``: the loop centres ``s_k`` of a finite ensemble (e.g. ``(α + β)/2`` from
    ``SpinDimerEnsemble.thresholds()``) for the distance to their empirical CDF.
    """
    from scipy.stats import norm

    width = _positive(width, "width")
    spread = _positive(spread, "spread")
    m = np.asarray(ident.cell_mass)
    total = float(m.sum())
    r_c, _ = ident.cell_centres_rs()
    if total == 0.0:
        raise ValueError("the identified mass is zero; check step and saturation")
    r_mean = float((m * r_c).sum() / total)
    r_spread = float(np.sqrt(max((m * (r_c - r_mean) ** 2).sum() / total, 0.0)))
    cell = ident.step if ident.step is not None else float(np.median(np.diff(ident.alpha)))
    near = np.abs(r_c - 0.5 * width) <= cell * (1 + 1e-9)
    within = float(m[near].sum() / total)

    def gauss(x: np.ndarray) -> np.ndarray:
        return norm.cdf(x, loc=centre, scale=spread)

    d_gauss = s_cdf_distance(ident, gauss)
    d_emp = bound = n = None
    if centres is not None:
        c = np.asarray(centres, dtype=float).ravel()
        d_emp = s_cdf_distance(ident, empirical_cdf(c))
        n = int(c.size)
        bound = 1.36 / math.sqrt(n)
    return RidgeComparison(total, r_mean, r_spread, within, d_gauss, d_emp, bound, n)


# ----------------------------------------------------------------------------------------------
# helpers
# ----------------------------------------------------------------------------------------------
def _finite(x: Any, name: str) -> float:
    try:
        v = float(x)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a finite real number, got {x!r}") from exc
    if not math.isfinite(v):
        raise ValueError(f"{name} must be a finite real number, got {v}")
    return v


def _positive(x: Any, name: str) -> float:
    v = _finite(x, name)
    if v <= 0:
        raise ValueError(f"{name} must be > 0, got {v}")
    return v


def _progress(seq: Sequence, enabled: bool, desc: str):
    if not enabled:
        return seq
    from hysteresis._progress import progress_bar

    return progress_bar(seq, desc=desc)
