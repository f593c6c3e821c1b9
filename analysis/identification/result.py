"""The result of a Preisach-plane identification: nodes, Everett table, exact cell masses.

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
import warnings
from dataclasses import dataclass

import numpy as np

#: a cell mass ``E₁₁ − E₁₀ − E₀₁ + E₀₀`` of Everett values ``|E| <= E_max`` is computed with three
#: roundings, each at most ``ε/2`` of a partial sum ``<= 4 E_max``: ``|error| <= 6 ε E_max``.
#: Masses within this of 0 are a density exactly 0 (measured: a paramagnet ``M = f(H)``, whose
#: off-diagonal masses vanish exactly, gives 1.2 ε E_max; constant data exactly 0)
MASS_ROUNDOFF_ULPS = 6.0

#: the FORC peak and the profiles skip nodes with ``B_c < RIDGE_EXCLUSION_STEPS`` grid steps:
#: the reversible ridge at ``B_c = 0`` and the nodes beside it, whose smoothing windows are
#: one-sided (or reach the extension ``E = 0``), are not the sample's coercivity peak. PmagPy's
#: FORC code excludes the same three field steps (on its conventional example the VARIFORC
#: peak moves from the region's edge to the coercivity peak)
RIDGE_EXCLUSION_STEPS = 3

__all__ = ["PreisachIdentification", "RIDGE_EXCLUSION_STEPS"]


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
    density_se:
        Standard error of :attr:`density_alpha_beta` at every node (``uncertainty=True``), or
        ``None``.
    smoothing_method:
        ``"fixed"`` (the factors in :attr:`smoothing`) or ``"variforc"`` (parameters in
        :attr:`variforc`; :attr:`smoothing` is then ``None``).
    variforc:
        The VARIFORC parameters (``sc0, sc1, sb0, sb1, lam, bu0``) or ``None``.
    noise_sigma:
        Noise of the half moments ``M/2`` estimated from the fourth differences along the
        curves (:func:`~analysis.identification.density.measurement_noise`), with
        ``density_se``; else ``None``.
    smoothing_widths:
        Window half-widths ``(s_c, s_b)`` per node in steps (lattice regression), or ``None``.
    smoothing_choice:
        With ``smoothing="auto"``: the criterion, the candidates, their scores and the choice.
    curve_kind:
        :attr:`~analysis.identification.ReversalCurves.kind` of the curves identified:
        ``"in-field"`` or ``"remanence"`` (a remanence FORC diagram: the remanence-carrying
        relays only, :mod:`analysis.identification.curves`).
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
    density_se: np.ndarray | None = None
    smoothing_method: str = "fixed"
    variforc: dict | None = None
    noise_sigma: float | None = None
    smoothing_widths: tuple[np.ndarray, np.ndarray] | None = None
    smoothing_choice: dict | None = None
    curve_kind: str = "in-field"

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
        :attr:`reversible_mass`, the exact sum of the mixed differences of the Everett table.

        Definition and coordinates: ``∬ μ_αβ dα dβ = ∬ ρ dH dH_r`` over the measured field
        pairs ``(H, H_r)`` off the ``B_c = 0`` ridge; for a relay system the weight of the
        relays with ``B_c > 0`` (1 for a saturated ``[−1, 1]`` operator without a reversible
        part), for FORC data half the irreversible moment change ``M(H_r, H) − M(H_r, H_r)``
        summed over the cells (``E = ΔM/2``). In the diagram's own coordinates
        ``B_c = (H − H_r)/2``, ``B_u = (H + H_r)/2`` the Jacobian is
        ``|∂(B_c, B_u)/∂(H, H_r)| = ½``, so ``∬ ρ dB_c dB_u`` — the integral of the plotted
        diagram over its area, the convention of FORC software integrating ρ(B_c, B_u) such as
        PmagPy's — is half of this: :attr:`irreversible_mass_bcbu`."""
        return float(self.cell_mass[~self._diagonal_cells()].sum())

    @property
    def irreversible_mass_bcbu(self) -> float:
        """``∬ ρ dB_c dB_u = ½`` :attr:`irreversible_mass` (the Jacobian ``dB_c dB_u =
        ½ dH dH_r``): the irreversible mass in the FORC diagram's coordinates (PmagPy's
        convention)."""
        return 0.5 * self.irreversible_mass

    @property
    def density_is_zero(self) -> bool:
        """Every cell mass is 0 within the round-off of the Everett table
        (:data:`MASS_ROUNDOFF_ULPS`): the density is exactly 0 (a constant moment), and the
        smoothed density's values are round-off, with no peak."""
        e_max = float(np.max(np.abs(self.everett))) if self.everett.size else 0.0
        bound = MASS_ROUNDOFF_ULPS * np.finfo(np.float64).eps * e_max
        return bool(np.all(np.abs(self.cell_mass) <= bound))

    @property
    def grid_step(self) -> float:
        """The grid step ``Δ``: :attr:`step` on a regular grid, else the median α spacing."""
        if self.step is not None:
            return float(self.step)
        return float(np.median(np.diff(self.alpha)))

    def ridge_excluded(self) -> np.ndarray:
        """Mask of the nodes, shape of :attr:`everett`: ``True`` where
        ``B_c = (α − β)/2 < RIDGE_EXCLUSION_STEPS · Δ`` (:data:`RIDGE_EXCLUSION_STEPS`), the
        ``B_c ≈ 0`` ridge that the peak search and the profiles skip."""
        bc = 0.5 * (self.alpha[:, None] - self.beta[None, :])
        # a node on the boundary (B_c = 3Δ exactly, up to the grid's round-off) is kept
        return bc < RIDGE_EXCLUSION_STEPS * self.grid_step * (1.0 - 1e-9)

    def peak_search_nodes(self, values: np.ndarray) -> np.ndarray:
        """Mask of the nodes the peak is sought among: ``values`` finite and not
        :meth:`ridge_excluded`, or every finite node if none lies beyond the ridge."""
        finite = np.isfinite(values)
        away = finite & ~self.ridge_excluded()
        return away if away.any() else finite

    def density_peak(self, exclude_ridge: bool = True) -> tuple[float, float, float]:
        """``(r, s, μ_αβ)`` at the node of the largest smoothed density.

        In FORC terms ``(B_c, B_u, ρ)`` (``ρ = μ_αβ``, Pike's −½ ∂²M/∂H_r∂H). Needs an
        identification made with ``smoothing``; NaN nodes (outside the measured region) are
        ignored. With ``exclude_ridge`` (default) the nodes with ``B_c`` below
        :data:`RIDGE_EXCLUSION_STEPS` grid steps are skipped (:meth:`ridge_excluded`), as
        PmagPy does, unless no evaluated node lies beyond them. A density exactly 0
        (:attr:`density_is_zero`) has no peak: NaN three times, with a warning.
        """
        if self.density_alpha_beta is None:
            raise ValueError("density_peak needs an identification made with smoothing")
        if self.density_is_zero:
            warnings.warn(
                "the FORC density is zero everywhere (constant moment): no peak",
                RuntimeWarning,
                stacklevel=1,  # one location: a report that asks twice shows it once
            )
            return math.nan, math.nan, math.nan
        dens = self.density_alpha_beta
        if not np.any(np.isfinite(dens)):
            raise ValueError("the smoothed density is NaN everywhere (too few data points)")
        if exclude_ridge:
            dens = np.where(self.peak_search_nodes(dens), dens, np.nan)
        i, j = np.unravel_index(np.nanargmax(dens), dens.shape)
        a, b = float(self.alpha[i]), float(self.beta[j])
        return 0.5 * (a - b), 0.5 * (a + b), float(dens[i, j])

    def peak_at_exclusion_edge(self) -> bool:
        """The peak of :meth:`density_peak` is not resolved: it lies within one grid step of
        the ridge exclusion's edge (``B_c < (RIDGE_EXCLUSION_STEPS + 1)·Δ``) and the smoothed
        density is larger still inside the exclusion. On a coarse grid (5–7 mT steps: the
        exclusion is 15–20 mT) the density then rises toward the ``B_c = 0`` ridge across the
        edge, and the coercivity peak, if any, lies at or below the edge: the value at the
        edge is a bound, not a peak. False without smoothing, for a density exactly 0, or
        when no node lies beyond the exclusion."""
        dens = self.density_alpha_beta
        if dens is None or self.density_is_zero or not np.any(np.isfinite(dens)):
            return False
        kept = self.peak_search_nodes(dens)
        inside = np.isfinite(dens) & ~kept
        if not inside.any():
            return False
        top = np.where(kept, dens, np.nan)
        i, j = np.unravel_index(np.nanargmax(top), top.shape)
        bc = 0.5 * (float(self.alpha[i]) - float(self.beta[j]))
        near_edge = bc < (RIDGE_EXCLUSION_STEPS + 1) * self.grid_step * (1.0 - 1e-9)
        return bool(near_edge and np.nanmax(np.where(inside, dens, np.nan)) > top[i, j])

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
