"""Synthetic FORC sample series: known Preisach populations mixed in known proportions.

Three populations, continuous Gaussian Preisach models (``ContinuousPreisachModel.gaussian``:
density ``N(s; 0, R²)·N(r; p/2, σ_r²)``), stand for a hard single-domain-like population
(narrow along ``B_u``, ``B_c = 1``), a vortex-like one (``B_c = 0.5``, broader) and a soft,
interacting multidomain-like one (``B_c = 0.2``, spread along ``B_u``). Their reversal curves
are measured once per grid (Mayergoyz convention, ``measure_reversal_curves``); a sample of
proportions ``p`` is the operator ``Σ_k p_k · model_k`` of the operator algebra, whose outputs
are ``Σ_k p_k`` × the parts' outputs exactly (:mod:`hysteresis.algebra`), so its curves are the
weighted sums of the populations' curves (tested against the algebra's operator in
test_unmixing.py). Independent Gaussian noise of a given standard deviation is added to every
moment, seeded.
"""

from __future__ import annotations

import functools

import numpy as np

from analysis.identification import ReversalCurves, measure_reversal_curves, regular_grid
from hysteresis.preisach import ContinuousPreisachModel

#: (p = 2 B_c, R, σ_r) of the three populations
POPULATIONS = ((2.0, 0.25, 0.15), (1.0, 0.45, 0.2), (0.4, 0.8, 0.12))


@functools.cache
def population_models() -> tuple[ContinuousPreisachModel, ...]:
    return tuple(ContinuousPreisachModel.gaussian(*p) for p in POPULATIONS)


@functools.cache
def population_curves(step: float = 0.05, saturation: float = 3.0) -> tuple[ReversalCurves, ...]:
    grid = regular_grid(step, saturation)
    return tuple(measure_reversal_curves(m, grid) for m in population_models())


def mixed_curves(
    proportions,
    noise: float,
    rng: np.random.Generator,
    step: float = 0.05,
    saturation: float = 3.0,
) -> ReversalCurves:
    """The curves of ``Σ_k p_k · population_k`` with noise of standard deviation ``noise``."""
    parts = population_curves(step, saturation)
    p = np.asarray(proportions, dtype=float)
    first = parts[0]
    moments = []
    for c in range(first.n_curves):
        m = sum(pk * part.moments[c] for pk, part in zip(p, parts, strict=True))
        moments.append(m + rng.normal(0.0, noise, m.size))
    return ReversalCurves(first.reversal_field, first.fields, tuple(moments), first.convention)


def core_proportions(n: int, seed: int) -> np.ndarray:
    """``n`` samples of three populations: the three pure ones first, then proportions
    uniform on the simplex (a flat Dirichlet), seeded."""
    rng = np.random.default_rng(seed)
    return np.vstack([np.eye(3), rng.dirichlet(np.ones(3), size=n - 3)])
