"""The verdict rules of fig:bif_0, fig:bif, fig:sap, fig:mag and fig:mag_his: from measured
numbers to ``agree`` / ``disagree`` / ``inconclusive at this run size`` (the generic tests are in
:mod:`analysis.paper.decisions`)."""

from __future__ import annotations

import math

import numpy as np

from analysis.dynamics.period_adding import PeriodAdding
from analysis.dynamics.statistics import Z95, std_ratio_relative_error
from analysis.experiments.parameters import (
    PAPER_LARGEST_N,
)
from analysis.paper import decisions as dec
from analysis.paper.context import (
    AGREE,
    DISAGREE,
    INCONCLUSIVE,
    verdict,
)
from analysis.paper.prose import (
    fmt_value,
)

__all__ = [
    "MIN_WINDOW_VALUES",
    "CASCADE_MIN_WINDOWS",
    "window_mask",
    "is_period_adding",
    "cascade_verdict",
    "sap_falls",
    "std_ratio_verdict",
    "std_ratio_evidence",
]


#: minimum number of grid values of C inside a window of fig:bif for its claim to be decided
MIN_WINDOW_VALUES = 3


#: the period-adding test needs this many wide (>= 2 grid values) windows
CASCADE_MIN_WINDOWS = 3


def window_mask(cs: np.ndarray, lo: float, hi: float) -> np.ndarray:
    return (cs >= lo - 1e-9) & (cs <= hi + 1e-9)


def is_period_adding(cascade: PeriodAdding) -> bool:
    """Whether the windows below the onset (measured by
    :func:`~analysis.dynamics.period_adding.period_adding`) are a period-adding cascade: at
    least :data:`CASCADE_MIN_WINDOWS` wide windows whose periods fall monotonically by small
    steps (1 or 2) as C moves away from the onset, and long periods (or none resolved) right
    below the onset, where they grow without bound."""
    steps = np.asarray(cascade.steps, dtype=int)
    return bool(
        len(cascade.wide) >= CASCADE_MIN_WINDOWS
        and np.all(steps < 0)
        and np.all(steps >= -2)
        and cascade.long_near_onset
    )


def cascade_verdict(
    onset: float, step: float, adding: bool, values_below: int, first_period: int = 1
) -> str:
    """Verdict of the fig:bif_0 cascade claim: the onset within 0.25 of C = 9 (known to ± half
    the grid step, :func:`~analysis.paper.decisions.onset_within`) and period adding below it;
    the absence of period adding decides only if the grid holds enough values below the onset
    for three windows of two values. A sweep whose first value (above the onset) has no
    resolved period (``first_period == 0``) never saw the period-1 orbit: no onset can be
    placed, which is inconclusive, not a disagreement."""
    if not np.isfinite(onset) and first_period == 0:
        return INCONCLUSIVE
    if adding:
        adding_outcome = AGREE
    elif values_below < 2 * CASCADE_MIN_WINDOWS:
        adding_outcome = INCONCLUSIVE
    else:
        adding_outcome = DISAGREE
    return dec.combine(dec.onset_within(onset, 9.0, 0.25, step), adding_outcome)


def sap_falls(sap: np.ndarray, realizations: int) -> str:
    """Verdict of "the SAP at the largest N is below the SAP at the smallest N": the log ratio
    against 0, known to ± 1.96 · 2/sqrt(K − 1) (a ratio of two variance estimates over K
    realizations each, Gaussian approximation)."""
    sap = np.asarray(sap, dtype=float)
    if sap.size < 2 or realizations < 2 or not np.all(np.isfinite(sap[[0, -1]])):
        return INCONCLUSIVE
    if sap[0] <= 0 or sap[-1] <= 0:  # a zero SAP (all realizations alike) has no log
        return verdict(bool(sap[-1] < sap[0])) if sap[0] != sap[-1] else INCONCLUSIVE
    rel = 2.0 / math.sqrt(realizations - 1)
    return dec.below(math.log(sap[-1] / sap[0]), Z95 * rel, 0.0)


def std_ratio_verdict(ratio: float, clt: float, realizations: int, narrows: bool) -> str:
    """Verdict of a std-ratio claim of fig:mag_his: the ratio std(N2)/std(N1) against the
    midpoint between the CLT ratio sqrt(N1/N2) and 1 — below it if ``narrows``, above it
    otherwise — known to ± 1.96 · ratio/sqrt(K − 1) (two stds of K Gaussian samples each)."""
    if not (np.isfinite(ratio) and np.isfinite(clt)):
        return INCONCLUSIVE
    mid = 0.5 * (1.0 + clt)
    half = Z95 * ratio * std_ratio_relative_error(realizations)
    return dec.below(ratio, half, mid) if narrows else dec.below(-ratio, half, -mid)


def std_ratio_evidence(ratio: float, clt: float, realizations: int, largest: int | None) -> str:
    mid = 0.5 * (1.0 + clt) if np.isfinite(clt) else float("nan")
    rel = std_ratio_relative_error(realizations)
    size = f"; largest N {largest} (paper: {PAPER_LARGEST_N})" if largest is not None else ""
    return (
        f"std ratio {fmt_value(ratio, 2)} ± {fmt_value(Z95 * ratio * rel, 2)} (95 %, K = "
        f"{realizations} realizations per N) against the midpoint {fmt_value(mid, 2)} between the "
        f"CLT ratio {fmt_value(clt, 2)} and 1{size}"
    )
