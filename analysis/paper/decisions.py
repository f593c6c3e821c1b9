"""Three-way decisions of the report's claims: agree, disagree, or inconclusive at this run size.

Each function takes the decisive statistic of one claim and what the run knows of its
uncertainty (a standard error, a number of realizations, a grid step) and returns one of
:data:`~analysis.paper.context.VERDICTS`. The criterion is always the paper's (or the one the
claim states); a result is *inconclusive* only where the run's own uncertainty straddles that
criterion, never because a threshold was moved. The functions are pure so that they can be
tested on synthetic numbers without a simulation. The statistics and their uncertainties are
measured in :mod:`analysis.dynamics.statistics`.
"""

from __future__ import annotations

import math

from analysis.dynamics.statistics import Z95, ks_sampling_scale, wilson_interval
from analysis.paper.context import AGREE, DISAGREE, INCONCLUSIVE

__all__ = [
    "below",
    "combine",
    "every_in_window",
    "majority_in_window",
    "needs_size",
    "ks_below",
    "mean_within",
    "onset_within",
    "power_law_exponent",
    "fraction_matches",
]


def _finite(*xs: float) -> bool:
    return all(isinstance(x, (int, float)) and math.isfinite(x) for x in xs)


def below(value: float, halfwidth: float, threshold: float) -> str:
    """Claim ``value < threshold`` for a value known to ``± halfwidth``: agree if the whole
    interval lies below the threshold, disagree if it lies at or above it, inconclusive if it
    straddles it (or the value or its uncertainty is not finite)."""
    if not _finite(value, halfwidth, threshold) or halfwidth < 0:
        return INCONCLUSIVE
    if value + halfwidth < threshold:
        return AGREE
    if value - halfwidth >= threshold:
        return DISAGREE
    return INCONCLUSIVE


def mean_within(mean: float, sem: float, target: float, tol: float, z: float = Z95) -> str:
    """Claim ``|mean − target| <= tol`` for a sample mean with standard error ``sem``: agree if
    the ``z``-sigma interval of the mean lies inside ``[target − tol, target + tol]``, disagree if
    it lies wholly outside it, inconclusive if it straddles an end (or ``sem`` is not finite,
    e.g. a single realization)."""
    if not _finite(mean, sem, target, tol) or sem < 0:
        return INCONCLUSIVE
    dev, half = abs(mean - target), z * sem
    if dev + half <= tol:
        return AGREE
    if dev - half > tol:
        return DISAGREE
    return INCONCLUSIVE


def onset_within(onset: float, target: float, tol: float, step: float) -> str:
    """Claim ``|onset − target| <= tol`` for an onset located between two grid values ``step``
    apart (so known to ``± step/2``). No onset found (``nan``) is a disagreement: the sweep
    crossed the range without the transition. A grid coarser than the tolerance can still
    decide if the onset is far enough from (or close enough to) the target."""
    if not _finite(target, tol, step) or step < 0:
        return INCONCLUSIVE
    if not _finite(onset):
        return DISAGREE
    dev, half = abs(onset - target), 0.5 * step
    if dev + half <= tol:
        return AGREE
    if dev - half > tol:
        return DISAGREE
    return INCONCLUSIVE


def fraction_matches(k: int, n: int, target: float) -> str:
    """Claim "the fraction is ≈ ``target``" from ``k`` of ``n``: disagree if ``target`` is outside
    the 95 % Wilson interval; inconclusive if it is inside but the interval is wider than
    ``target`` itself (it could not tell ``target`` from half or twice as much, or from none);
    agree otherwise."""
    lo, hi = wilson_interval(k, n)
    if not _finite(lo, hi):
        return INCONCLUSIVE
    if not lo <= target <= hi:
        return DISAGREE
    return INCONCLUSIVE if hi - lo > target else AGREE


def power_law_exponent(exponent: float, stderr: float, target: float, floor: float) -> str:
    """Claim "exponent = ``target``" for a fitted exponent: agree if within ``max(3σ, floor)`` of
    the target, else disagree — unless the fit has no finite standard error, or it agrees only
    because its 3σ interval is so wide that it also holds 0 (no decay at all): then
    inconclusive."""
    if not _finite(exponent, stderr):
        return INCONCLUSIVE
    tol = max(3.0 * stderr, floor)
    if abs(exponent - target) > tol:
        return DISAGREE
    return INCONCLUSIVE if abs(exponent) <= 3.0 * stderr else AGREE


def ks_below(distance: float, n1: int, n2: int, threshold: float) -> str:
    """Claim "KS distance < ``threshold``": decided only if the distance is farther from the
    threshold than its sampling scale :func:`~analysis.dynamics.statistics.ks_sampling_scale`."""
    return below(distance, ks_sampling_scale(n1, n2), threshold)


def combine(*outcomes: str) -> str:
    """The verdict of a claim made of several parts: disagree if any part disagrees, else
    inconclusive if any part is, else agree."""
    if DISAGREE in outcomes:
        return DISAGREE
    if INCONCLUSIVE in outcomes:
        return INCONCLUSIVE
    return AGREE


def needs_size(outcome: str, have: float, need: float) -> str:
    """A claim about a size ``need`` (e.g. the paper's largest N) measured at ``have``: the
    outcome stands only if ``have >= need``; a smaller run cannot decide it either way."""
    return outcome if have >= need else INCONCLUSIVE


def every_in_window(holds: int, count: int, minimum: int = 3) -> str:
    """Claim "the property holds at every grid value of a window" from ``holds`` of ``count``
    values: one value without it is a counterexample (disagree, at any count); all holding
    decides only with at least ``minimum`` values (none or one or two are no test)."""
    if holds < count:
        return DISAGREE
    return AGREE if count >= minimum else INCONCLUSIVE


def majority_in_window(holds: int, count: int, minimum: int = 3) -> str:
    """Claim "the property holds at least at half of the grid values of a window": decided only
    with at least ``minimum`` values in the window."""
    if count < minimum:
        return INCONCLUSIVE
    return AGREE if holds >= 0.5 * count else DISAGREE
