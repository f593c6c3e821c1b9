"""Preisach-plane identification: reversal curves, the Preisach density, FORC files, fitting.

Modules, by job:

- :mod:`~analysis.identification.curves` — reversal-curve data (:class:`ReversalCurves`), the
  Mayergoyz and Pike conventions, driving an operator through reversal curves, the protocol
  lattice of a measurement;
- :mod:`~analysis.identification.result` — :class:`PreisachIdentification`: nodes, Everett
  table, exact cell masses, marginals;
- :mod:`~analysis.identification.density` — the identification itself
  (:func:`identify_preisach`, :func:`identify_from_curves`);
- :mod:`~analysis.identification.smoothing` — the smoothed density (local quadratic regression);
- :mod:`~analysis.identification.metrics` — comparison with the paper's ridge density
  (:func:`compare_with_ridge`, and cell by cell along the ridge: :func:`compare_ridge_bins`);
- :mod:`~analysis.identification.forc_io` — instrument FORC files (CSV, MicroMag, Lake Shore;
  the readers live in :mod:`analysis.identification.forc_files`);
- :mod:`~analysis.identification.unmixing` — FORC unmixing of a sample series
  (:func:`unmix_forc`: FORC-PCA, end-members, proportions with intervals, end-members as
  Preisach operators; the algebra in :mod:`~analysis.identification.endmembers`);
- :mod:`~analysis.identification.fitting` — Preisach / Prandtl–Ishlinskii models fitted to
  arbitrary input/output records;
- :mod:`~analysis.identification.plots` — figures of identified densities and FORC diagrams.

The names below are those of the first five modules and :func:`unmix_forc`; import the rest
from their modules.
"""

from __future__ import annotations

from analysis.identification.curves import (
    ReversalCurves,
    measure_reversal_curves,
    pike_to_preisach,
    preisach_to_pike,
    protocol_lattice,
    regular_grid,
)
from analysis.identification.density import auto_grid, identify_from_curves, identify_preisach
from analysis.identification.metrics import (
    RidgeBins,
    RidgeComparison,
    compare_ridge_bins,
    compare_with_ridge,
    empirical_cdf,
    s_cdf_distance,
)
from analysis.identification.result import PreisachIdentification
from analysis.identification.smoothing import grid_quadratic_density, local_quadratic_density
from analysis.identification.unmixing import unmix_forc
from analysis.identification.unmixing_result import ForcUnmixing

__all__ = [
    "ReversalCurves",
    "PreisachIdentification",
    "RidgeComparison",
    "RidgeBins",
    "measure_reversal_curves",
    "identify_preisach",
    "identify_from_curves",
    "local_quadratic_density",
    "preisach_to_pike",
    "pike_to_preisach",
    "s_cdf_distance",
    "empirical_cdf",
    "compare_with_ridge",
    "compare_ridge_bins",
    "regular_grid",
    "protocol_lattice",
    "grid_quadratic_density",
    "auto_grid",
    "unmix_forc",
    "ForcUnmixing",
]
