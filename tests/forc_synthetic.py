"""Synthetic FORC data from a known density (shared by the identification tests).

The moment model ``M(H, Hr) = 2A Φ((H − HA)/SA) Φ((HB − Hr)/SB) + 0.3 tanh(Hr/7)`` on a
lattice of unit step (Pike convention, curves ``H >= Hr``), with independent Gaussian noise of
standard deviation ``noise`` on every measured moment; its FORC density is :func:`true_rho`,
peaked at ``B_c = (HA − HB)/2``, ``B_u = (HA + HB)/2``.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import norm

from analysis.identification import ReversalCurves

A_SAT, HA, SA, HB, SB = 1.0, 2.0, 12.0, -4.0, 11.0  # the moment model below (steps of 1)


def true_rho(H, Hr, ha=HA, hb=HB):
    """ρ = −½ ∂²M/∂Hr∂H of ``M = 2A Φ((H − ha)/SA) Φ((hb − Hr)/SB) + m0(Hr)``."""
    return A_SAT * norm.pdf((H - ha) / SA) * norm.pdf((hb - Hr) / SB) / (SA * SB)


def noisy_curves(rng, noise, grid, ha=HA, hb=HB):
    """The curves of the model (peak at ``B_c = (ha − hb)/2``, ``B_u = (ha + hb)/2``)."""
    rev, fields, moments = [], [], []
    for hr in grid:
        h = grid[grid >= hr]
        m = 2 * A_SAT * norm.cdf((h - ha) / SA) * norm.cdf((hb - hr) / SB) + 0.3 * np.tanh(hr / 7)
        rev.append(hr)
        fields.append(h)
        moments.append(m + rng.normal(0.0, noise, h.size))
    return ReversalCurves(np.array(rev), tuple(fields), tuple(moments), "pike")
