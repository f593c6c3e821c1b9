"""Scalar fast paths of the continuous Preisach model's Everett function and gradient.

The oscillator's continuous engine evaluates them once per integrator stage with Python floats;
they do the same arithmetic as the vectorised methods of
:class:`~hysteresis.preisach.continuous.ContinuousPreisachModel` (identical results), without
the array overhead. ``self`` is the model.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from hysteresis.preisach.base import _gauss

__all__ = ["scalar_everett", "scalar_gradient"]


def scalar_everett(self: Any) -> Callable:
    """``everett`` with a fast path for scalar arguments (same arithmetic as the tabulated
    bilinear interpolation, so the result is identical; the engine calls it per stage)."""
    vector = self.everett
    fast = getattr(self, "_fast_scalar", None)
    if fast is not None:
        everett_scalar = fast[0]

        def everett_fast(a, b):
            if isinstance(a, float) and isinstance(b, float):
                return everett_scalar(a, b)
            return vector(a, b)[()]

        return everett_fast
    if getattr(self, "_table", None) is None:

        def everett_any(a, b):
            return vector(a, b)[()]

        return everett_any
    rows = self.__dict__.get("_table_rows")
    if rows is None:
        rows = self._table.tolist()
        self._table_rows = rows
    lo, up, h, n = self._lower, self._upper, self._h, self._n

    def everett(a, b):
        if not (isinstance(a, float) and isinstance(b, float)):
            return vector(a, b)[()]
        a = min(max(a, lo), up)
        b = min(max(b, lo), up)
        if not a > b:
            return 0.0
        fa = (a - lo) / h
        fb = (b - lo) / h
        i = min(max(math.floor(fa), 0), n - 1)
        j = min(max(math.floor(fb), 0), n - 1)
        ta = fa - i
        tb = fb - j
        r0, r1 = rows[i], rows[i + 1]
        e = (
            r0[j] * (1 - ta) * (1 - tb)
            + r1[j] * ta * (1 - tb)
            + r0[j + 1] * (1 - ta) * tb
            + r1[j + 1] * ta * tb
        )
        return max(e, 0.0)

    return everett


def scalar_gradient(self: Any) -> Callable:
    """``everett_gradient`` with a fast path for scalar arguments of a density model."""
    vector = self.everett_gradient

    def gradient_any(a, b):
        da, db = vector(a, b)
        return da[()], db[()]

    fast = getattr(self, "_fast_scalar", None)
    if fast is not None:
        gradient_scalar = fast[1]

        def gradient_fast(a, b):
            if isinstance(a, float) and isinstance(b, float):
                return gradient_scalar(a, b)
            return gradient_any(a, b)

        return gradient_fast
    if self._density_fn is None or self._gradient_fn != self._gradient_from_density:
        return gradient_any
    nodes, weights = _gauss(64)
    mu = self._density_fn
    lo, up, scale = self._lower, self._upper, self._mass_scale

    def gradient(a0, b0):
        if not (isinstance(a0, float) and isinstance(b0, float)):
            return gradient_any(a0, b0)
        a = min(max(a0, lo), up)
        b = min(max(b0, lo), up)
        if not a > b:
            return 0.0, 0.0
        span = a - b
        pts = b + span * nodes
        da = 0.0
        db = 0.0
        if lo <= a0 <= up:
            da = float(np.dot(np.asarray(mu(np.full(pts.shape, a), pts)), weights))
        if lo <= b0 <= up:
            db = -float(np.dot(np.asarray(mu(pts, np.full(pts.shape, b))), weights))
        return da * scale * span, db * scale * span

    return gradient
