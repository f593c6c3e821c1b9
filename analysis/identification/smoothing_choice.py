"""Automatic choice of the VARIFORC smoothing for the FORC density (``smoothing="auto"``).

The quantity of interest is the mixed derivative ``ρ = −½ ∂²M/∂B_a∂B_b``, not ``M``: a
criterion that scores the fit of ``M`` (leave-one-out cross-validation, the former default)
prefers little smoothing, because the fit of ``M`` gains little from a wider window while the
variance of ``ρ`` grows like ``s⁻⁶`` as the window shrinks. The choice here targets ``ρ``
directly, with the Lepski / intersection-of-confidence-intervals principle used for the
bandwidths of local polynomial estimators (Lepski 1991; Goldenshluger & Nemirovski 1997;
Katkovnik 1999, "A new method for varying adaptive bandwidth selection", IEEE Trans. Signal
Process. 47, 2567): smoothing more is accepted as long as the smoother estimate stays
consistent, within its noise, with every less smoothed one; the first candidate that departs
from a finer one by more than noise can explain is biased, and the previous one is chosen.
(FORCsensei, Heslop et al. 2020 JGR 125, e2020JB020418, compares the same family of VARIFORC
smoothings by Bayesian model selection of the regression of ``M``; the rule here needs no prior
and uses the standard errors of ``ρ`` the toolkit already computes.)

The rule, over the candidates ``s_1 ∈`` :data:`AUTO_CANDIDATES` in increasing order (VARIFORC
far-field half-widths ``s_c1 = s_b1 = s_1``, ridge half-widths ``min(3, s_1)``, ``λ = 0.07``):

1. the noise ``σ`` of the lattice values, from their fourth differences along both lattice
   axes (:func:`lattice_noise`; independent of the smoothing and of the local fits' residuals,
   which a wide window inflates by its own lack of fit);
2. for each candidate ``k``, ``ρ_k`` and its noise standard error ``se_k = σ·g_k``
   (``g_k`` the regression's standard error for unit noise) on the evaluated nodes of a
   sub-lattice (every ``stride``-th node along both axes, ``stride`` keeping about
   :data:`TARGET_NODES` nodes: the statistic is a mean over many strongly correlated nodes);
3. the *signal* nodes: evaluated by every candidate and significant, ``|ρ_k| > 1.96 se_k``, for
   at least one candidate (nodes of pure noise would dilute the bias test);
4. ``T_jk = mean over the signal nodes of ((ρ_k − ρ_j)/se_j)²`` for every finer ``j < k``;
   candidate ``k`` is accepted if ``max_j T_jk <= T_MAX = 2``, and the choice is the last
   candidate of the accepted run that starts at the finest one.

Why ``T_MAX = 2``: without bias ``ρ_k − ρ_j`` is noise of variance
``se_j² + se_k² − 2 cov(ρ_j, ρ_k) <= se_j² + se_k² <= 2 se_j²`` (the two estimates share the
data of the smaller window, so their covariance is not negative, and ``se_k <= se_j``); hence
``E[T_jk] <= 2`` for unbiased candidates, and a larger mean is the mean squared bias
difference ``(b_k − b_j)²/se_j²`` showing through. The choice is therefore the largest smoothing
whose extra bias is not detectable above the noise of the finer estimates — the bias–variance
balance point of Lepski's method.

Without noise (``σ = 0``, exact simulated data) every difference is bias and the finest
candidate is chosen; with no signal node every candidate is consistent and the largest is.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from analysis.identification.variforc import (
    LocalRegression,
    VariforcParameters,
    weighted_quadratic_density,
)

__all__ = ["AUTO_CANDIDATES", "auto_candidates", "lattice_noise", "choose_smoothing", "T_MAX"]

#: the VARIFORC far-field half-widths s_1 = s_c1 = s_b1 that ``smoothing="auto"`` compares
#: (ridge half-widths min(3, s_1), λ = 0.07: the defaults' shape, scaled)
AUTO_CANDIDATES = (2.0, 3.0, 4.0, 5.0, 7.0, 9.0)
#: the largest mean squared standardized difference that noise alone can give (module docstring)
T_MAX = 2.0
#: about this many sub-lattice nodes carry the comparison (speed; see ``stride``)
TARGET_NODES = 12000
Z95 = 1.959963984540054


def auto_candidates() -> list[VariforcParameters]:
    """The VARIFORC parameter sets ``smoothing="auto"`` chooses from (finest first)."""
    return [
        VariforcParameters(sc0=min(3.0, s), sc1=s, sb0=min(3.0, s), sb1=s) for s in AUTO_CANDIDATES
    ]


def lattice_noise(values: np.ndarray, valid: np.ndarray) -> float:
    """Robust noise level of the lattice values: the median absolute fourth difference over
    runs of five valid nodes along each axis, ``/0.6745/sqrt(70)`` (white noise of standard
    deviation ``σ`` has fourth differences of variance ``70σ²``; a smooth surface adds only
    ``Δ⁴`` times its fourth derivative); the smaller of the two axes' estimates (an axis
    across sharp switching reads high). Raises if no axis has a run of five valid nodes."""
    ests = []
    for axis in (0, 1):
        if values.shape[axis] < 5:
            continue
        d = np.diff(values, 4, axis=axis)
        ok = np.ones(d.shape, dtype=bool)
        for k in range(5):
            ok &= np.take(valid, np.arange(k, k + d.shape[axis]), axis=axis)
        if ok.any():
            ests.append(float(np.median(np.abs(d[ok]))) / 0.6744897501960817 / np.sqrt(70.0))
    if not ests:
        raise ValueError("automatic smoothing needs runs of five valid lattice nodes")
    return min(ests)


def _sub_lattice(evaluate: np.ndarray) -> tuple[np.ndarray, int]:
    stride = max(1, int(round(np.sqrt(evaluate.sum() / TARGET_NODES))))
    sub = np.zeros_like(evaluate)
    sub[::stride, ::stride] = evaluate[::stride, ::stride]
    return sub, stride


def choose_smoothing(
    values: np.ndarray,
    valid: np.ndarray,
    evaluate: np.ndarray,
    step: float,
    origin: float,
) -> tuple[VariforcParameters, dict[str, Any]]:
    """The candidate chosen by the rule of the module docstring and its record (criterion,
    candidates, ``scores`` ``max_j T_jk`` of the candidates compared — the comparison stops
    at the first rejected one — threshold, chosen ``s_1``, lattice noise, signal nodes,
    sub-lattice stride)."""
    cands = auto_candidates()
    sigma = float(lattice_noise(values, valid))
    record: dict[str, Any] = {
        "criterion": (
            "Lepski/ICI on rho: largest s_1 with mean((rho_k - rho_j)/se_j)^2 <= T_max over the "
            "significant nodes for every finer s_1"
        ),
        "candidates_s1": list(AUTO_CANDIDATES),
        "threshold": T_MAX,
        "noise_sigma": sigma,
    }
    sub, stride = _sub_lattice(evaluate)
    record["stride"] = stride
    if not sigma > 0.0:  # exact data: any difference is bias
        record.update(scores=[], chosen_s1=AUTO_CANDIDATES[0], nodes=0)
        return cands[0], record
    fits: list[LocalRegression] = []
    ses: list[np.ndarray] = []
    for c in cands:
        f = weighted_quadratic_density(values, valid, sub, step, c, origin, True)
        with np.errstate(divide="ignore", invalid="ignore"):
            ses.append(np.where(f.sigma > 0, sigma * f.se / f.sigma, np.nan))
        fits.append(f)
    common = np.logical_and.reduce(
        [np.isfinite(f.rho) & np.isfinite(s) for f, s in zip(fits, ses, strict=True)]
    )
    if not common.any():
        raise ValueError("automatic smoothing: no node is evaluated by every candidate")
    signal = common & np.logical_or.reduce(
        [np.abs(f.rho) > Z95 * s for f, s in zip(fits, ses, strict=True)]
    )
    record["nodes"] = int(signal.sum())
    scores = [0.0]
    best = 0
    if signal.any():
        for k in range(1, len(cands)):
            t = max(
                float(np.mean(((fits[k].rho - fits[j].rho)[signal] / ses[j][signal]) ** 2))
                for j in range(k)
            )
            scores.append(t)
            if t > T_MAX:
                break
            best = k
    else:
        best = len(cands) - 1
    record.update(scores=scores, chosen_s1=AUTO_CANDIDATES[best])
    return cands[best], record
