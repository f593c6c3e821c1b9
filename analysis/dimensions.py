"""Fractal dimensions of attractors: Kaplan–Yorke (Lyapunov) dimension and box counting."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["kaplan_yorke_dimension"]


def kaplan_yorke_dimension(exponents: Sequence[float] | np.ndarray) -> float:
    """Kaplan–Yorke dimension ``D_KY = j + Σ_{i<=j} λ_i / |λ_{j+1}|`` (paper eq. kaplan_yorke).

    ``j`` is the largest index with ``Σ_{i<=j} λ_i >= 0``. The exponents are sorted in descending
    order first; ``-inf`` is allowed (the play limit has one). If every partial sum is negative
    (a regular attractor with all exponents < 0) the dimension is 0; if all partial sums are
    non-negative the dimension is the number of exponents.
    """
    lam = np.asarray(exponents, dtype=float)
    if lam.ndim != 1 or lam.size == 0:
        raise ValueError("exponents must be a non-empty 1-D sequence")
    if np.any(np.isnan(lam)) or np.any(lam == np.inf):
        raise ValueError("exponents must not contain NaN or +inf")
    lam = np.sort(lam)[::-1]
    partial = np.cumsum(lam)
    nonneg = np.nonzero(partial >= 0.0)[0]
    if nonneg.size == 0:
        return 0.0
    j = int(nonneg[-1]) + 1  # number of exponents in the expanding sum
    if j == lam.size:
        return float(lam.size)
    if np.isneginf(lam[j]):
        return float(j)
    return float(j + partial[j - 1] / abs(lam[j]))
