"""The result of :func:`~analysis.identification.unmixing.unmix_forc`: end-members, proportions
and their intervals on the common ``(B_c, B_u)`` lattice, and the end-members as Preisach
operators.

End-members as operators
------------------------
An end-member diagram ``D_k`` (a density ``μ_αβ`` on the common lattice, in the units of the
normalised diagrams) becomes a valid Preisach model by the projection the toolkit uses for
measured data (:func:`hysteresis.preisach.projection.project_identification`): its Everett
function ``E(α, β) = ∬ D_k`` on a regular ``(α, β)`` lattice covering the end-member's
support (the nodes where ``D_k`` exceeds :data:`SUPPORT_FRACTION` of its peak, plus a step;
the density read bilinearly at the cell centres, 0 outside the common region), fitted by
non-negative cell masses (the negative lobes of a noisy or extrapolated end-member cannot be
relay weights), one relay per cell, weights normalised to 1 and the fitted mass ``K_k`` kept
as the scale. A sample with proportions ``p_k`` has the diagram ``Σ_k p_k D_k``, i.e. the
relay masses ``Σ_k p_k K_k w_k``: as an operator with outputs in ``[−1, 1]``,
``Σ_k (p_k K_k / K) · model_k`` with ``K = Σ_k p_k K_k`` (:meth:`ForcUnmixing.sample_operator`;
with ``normalize="irreversible"`` every ``K_k`` ≈ 1 and the weights are the proportions), an
operator of the algebra (:mod:`hysteresis.algebra`) that couples to the oscillator like any
other.
"""

from __future__ import annotations

import functools
import math
import operator
from dataclasses import dataclass
from typing import Any

import numpy as np

from hysteresis.preisach.projection import PreisachProjection, project_identification

__all__ = ["ForcUnmixing", "DEFAULT_MODEL_NODES"]

#: the (α, β) lattice of an end-member's model has at most this many nodes per axis (the
#: dense NNLS of the projection up to ~2500 cells; coarser than the common lattice if needed)
DEFAULT_MODEL_NODES = 48
#: an end-member's model covers the nodes where its density exceeds this fraction of its peak
#: (noise far from the populations would otherwise stretch the lattice over the whole region)
SUPPORT_FRACTION = 0.02


@dataclass(frozen=True)
class _EverettTable:
    """What :func:`project_identification` reads: nodes and the Everett table."""

    alpha: np.ndarray
    beta: np.ndarray
    everett: np.ndarray
    measured: None = None


@dataclass(frozen=True, eq=False)
class ForcUnmixing:
    """End-member unmixing of a FORC series, the result of
    :func:`~analysis.identification.unmixing.unmix_forc`.

    Arrays over samples follow the order of the inputs (those left out omitted:
    :attr:`input_indices`, :attr:`excluded`).

    Attributes
    ----------
    labels, input_indices:
        Name and index in ``inputs`` of every sample used.
    bc, bu, mask, step:
        The common lattice: ``B_c`` (rows) and ``B_u`` (columns) nodes, in the field unit of
        the data (mT for instrument files), the nodes common to every diagram, the step.
    diagrams, standard_errors:
        The normalised densities ``ρ`` and their standard errors on the lattice, shape
        ``(n, n_bc, n_bu)``, NaN outside :attr:`mask` (``standard_errors`` ``None`` without
        them).
    normalize, divisors:
        The normalisation and each sample's divisor (``M_s``, irreversible mass, kg, m³ or 1).
    mean, components:
        The mean diagram and the principal components (unit vectors over the mask) as grids.
    scores, explained_variance, explained_variance_ratio:
        Every sample's PC scores ``(n, r)``; variance of each component and its fraction.
    component_test, n_components, chosen_by:
        The evidence of the number of end-members (``χ²``, its bound, accepted: one row per
        candidate, :func:`~analysis.identification.endmembers.component_test`), the number
        used and how it was fixed: ``"noise"`` (smallest accepted), ``"largest"`` (none
        accepted: the largest considered), ``"given"`` or ``"end_members"``.
    end_member_scores, end_member_samples, end_members:
        The simplex's vertices in PC coordinates ``(m, m − 1)``, the samples that are the
        vertices (rows of :attr:`labels`; ``None`` for given coordinates), their diagrams
        ``(m, n_bc, n_bu)``. Automatic end-members are ordered by their median ``B_c``.
    proportions, proportion_intervals, proportion_se:
        ``(n, m)`` proportions (>= 0, sum 1); the bootstrap's ``level`` percentile intervals
        ``(n, m, 2)`` and standard deviations (``None`` without standard errors).
    simplex_distance:
        Distance of each sample's scores from the simplex (0 inside).
    level, n_boot:
        The intervals' coverage and replicates.
    excluded:
        ``(label, reason)`` of every input left out (unreadable, no overlap).
    """

    labels: tuple[str, ...]
    input_indices: tuple[int, ...]
    bc: np.ndarray
    bu: np.ndarray
    mask: np.ndarray
    step: float
    diagrams: np.ndarray
    standard_errors: np.ndarray | None
    normalize: str
    divisors: np.ndarray
    mean: np.ndarray
    components: np.ndarray
    scores: np.ndarray
    explained_variance: np.ndarray
    explained_variance_ratio: np.ndarray
    component_test: tuple[dict[str, float], ...]
    n_components: int
    chosen_by: str
    end_member_scores: np.ndarray
    end_member_samples: tuple[int, ...] | None
    end_members: np.ndarray
    proportions: np.ndarray
    proportion_intervals: np.ndarray | None
    proportion_se: np.ndarray | None
    simplex_distance: np.ndarray
    level: float
    n_boot: int
    excluded: tuple[tuple[str, str], ...]

    @property
    def n_samples(self) -> int:
        return len(self.labels)

    # -- end-members as Preisach operators --------------------------------------------------
    def projections(self, max_nodes: int = DEFAULT_MODEL_NODES) -> list[PreisachProjection]:
        """The projection of every end-member onto a valid Preisach model (module docstring):
        relays, weights, the scale ``K_k`` and the misfit. Cached per ``max_nodes``."""
        if isinstance(max_nodes, bool) or not isinstance(max_nodes, int) or max_nodes < 4:
            raise ValueError(f"max_nodes must be an integer >= 4, got {max_nodes!r}")
        cache = self.__dict__.setdefault("_projections", {})
        if max_nodes not in cache:
            cache[max_nodes] = [
                project_identification(self._everett_table(d, max_nodes)) for d in self.end_members
            ]
        return cache[max_nodes]

    def models(self, max_nodes: int = DEFAULT_MODEL_NODES) -> list[Any]:
        """A valid discrete Preisach model per end-member (weights >= 0 summing to 1; relay
        thresholds in the field unit of the data)."""
        return [p.model() for p in self.projections(max_nodes)]

    def sample_operator(self, sample: int | str, max_nodes: int = DEFAULT_MODEL_NODES) -> Any:
        """The operator ``Σ_k (p_k K_k / K) · model_k`` of one sample (row index or label):
        its irreversible FORC distribution as a Preisach operator with outputs in ``[−1, 1]``
        (the sample's normalised moment is ``offset + K · output``, :meth:`sample_scale`)."""
        row = self._row(sample)
        projections = self.projections(max_nodes)
        scales = np.array([p.scale for p in projections])
        w = self.proportions[row] * scales
        w = w / w.sum()
        parts = [wk * p.model() for wk, p in zip(w, projections, strict=True) if wk > 0]
        return functools.reduce(operator.add, parts)

    def sample_scale(self, sample: int | str, max_nodes: int = DEFAULT_MODEL_NODES) -> float:
        """``K = Σ_k p_k K_k``: the sample's irreversible mass in normalised units."""
        scales = np.array([p.scale for p in self.projections(max_nodes)])
        return float(self.proportions[self._row(sample)] @ scales)

    def _row(self, sample: int | str) -> int:
        if isinstance(sample, str):
            if sample not in self.labels:
                raise ValueError(f"sample {sample!r} is not one of the labels {self.labels}")
            return self.labels.index(sample)
        if isinstance(sample, bool) or not isinstance(sample, int | np.integer):
            raise ValueError(f"sample must be a row index or a label, got {sample!r}")
        if not 0 <= sample < self.n_samples:
            raise ValueError(f"sample must lie in [0, {self.n_samples - 1}], got {sample}")
        return int(sample)

    def _everett_table(self, density: np.ndarray, max_nodes: int) -> _EverettTable:
        """The Everett table of a density on the common lattice (module docstring)."""
        values = np.where(self.mask, density, 0.0)
        support = values > SUPPORT_FRACTION * max(float(values.max()), 0.0)
        if not support.any():
            raise ValueError("an end-member has no positive density: no Preisach model")
        bc = np.broadcast_to(self.bc[:, None], self.mask.shape)[support]
        bu = np.broadcast_to(self.bu[None, :], self.mask.shape)[support]
        lo = float(np.min(bu - bc)) - self.step
        hi = float(np.max(bu + bc)) + self.step
        cells = max(1, min(max_nodes - 1, math.ceil((hi - lo) / self.step)))
        nodes = np.linspace(lo, hi, cells + 1)
        h = nodes[1] - nodes[0]
        centres = 0.5 * (nodes[1:] + nodes[:-1])
        ac, bcen = np.meshgrid(centres, centres, indexing="ij")
        rho = self._interpolate(values, 0.5 * (ac - bcen), 0.5 * (ac + bcen))
        mass = np.where(ac > bcen, rho, 0.0) * h * h
        # E[k, l] = Σ_{i < k, j >= l} mass[i, j] (the relays switched up at α_k, still up at β_l)
        everett = np.zeros((cells + 1, cells + 1))
        suffix = np.cumsum(mass[:, ::-1], axis=1)[:, ::-1]
        everett[1:, :cells] = np.cumsum(suffix, axis=0)
        aa, bb = np.meshgrid(nodes, nodes, indexing="ij")
        everett[bb >= aa] = 0.0
        return _EverettTable(alpha=nodes, beta=nodes.copy(), everett=everett)

    def _interpolate(self, grid: np.ndarray, bc: np.ndarray, bu: np.ndarray) -> np.ndarray:
        """Bilinear interpolation of ``grid`` (on ``bc × bu``) at points; 0 outside."""
        fi = (bc - self.bc[0]) / self.step
        fj = (bu - self.bu[0]) / self.step
        n_i, n_j = grid.shape
        i0, j0 = np.floor(fi).astype(np.int64), np.floor(fj).astype(np.int64)
        ti, tj = fi - i0, fj - j0
        out = np.zeros(bc.shape)
        for di, wi in ((0, 1.0 - ti), (1, ti)):
            for dj, wj in ((0, 1.0 - tj), (1, tj)):
                i, j = i0 + di, j0 + dj
                inside = (i >= 0) & (i < n_i) & (j >= 0) & (j < n_j)
                v = np.zeros(bc.shape)
                v[inside] = grid[i[inside], j[inside]]
                out += wi * wj * v
        return out

    # -- reports ----------------------------------------------------------------------------
    def summary_rows(self) -> list[dict[str, Any]]:
        """One row per sample: label, input index, proportion (and interval) per end-member,
        distance from the simplex."""
        rows = []
        for r, label in enumerate(self.labels):
            row: dict[str, Any] = {"sample": label, "input_index": self.input_indices[r]}
            for k in range(self.n_components):
                row[f"p{k + 1}"] = float(self.proportions[r, k])
                if self.proportion_intervals is not None:
                    row[f"p{k + 1}_lo"] = float(self.proportion_intervals[r, k, 0])
                    row[f"p{k + 1}_hi"] = float(self.proportion_intervals[r, k, 1])
            row["simplex_distance"] = float(self.simplex_distance[r])
            rows.append(row)
        return rows

    def as_dict(self) -> dict[str, Any]:
        """The numbers of a report (JSON-ready: lists and floats, no grids)."""
        em = self.end_member_samples
        return {
            "samples": list(self.labels),
            "input_indices": list(self.input_indices),
            "normalize": self.normalize,
            "divisors": self.divisors.tolist(),
            "lattice": {
                "bc_range": [float(self.bc[0]), float(self.bc[-1])],
                "bu_range": [float(self.bu[0]), float(self.bu[-1])],
                "step": self.step,
                "common_nodes": int(self.mask.sum()),
            },
            "n_components": self.n_components,
            "chosen_by": self.chosen_by,
            "component_test": [dict(row) for row in self.component_test],
            "explained_variance_ratio": self.explained_variance_ratio.tolist(),
            "end_member_samples": None if em is None else [self.labels[i] for i in em],
            "end_member_scores": self.end_member_scores.tolist(),
            "proportions": self.proportions.tolist(),
            "proportion_intervals": None
            if self.proportion_intervals is None
            else self.proportion_intervals.tolist(),
            "proportion_se": None if self.proportion_se is None else self.proportion_se.tolist(),
            "level": self.level,
            "n_boot": self.n_boot,
            "simplex_distance": self.simplex_distance.tolist(),
            "scores": self.scores.tolist(),
            "excluded": [{"sample": s, "reason": why} for s, why in self.excluded],
        }
