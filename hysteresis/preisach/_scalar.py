"""Scalar fast paths of the continuous Preisach model's Everett function and gradient.

The oscillator's continuous engine evaluates them once per integrator stage with Python floats;
they do the same arithmetic as the vectorised methods of
:class:`~hysteresis.preisach.continuous.ContinuousPreisachModel` (identical results), without
the array overhead. ``self`` is the model.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from hysteresis.preisach._everett_kernels import everett_eval

__all__ = ["scalar_everett", "scalar_gradient"]


def scalar_everett(self: Any) -> Callable:
    """``everett`` with a fast path for scalar arguments (a :meth:`from_density` model: the
    compiled kernel on its table, the same arithmetic as the vectorised method; the engine
    calls it per stage)."""
    vector = self.everett
    fast = getattr(self, "_fast_scalar", None)
    if fast is not None:
        everett_scalar = fast[0]

        def everett_fast(a, b):
            if isinstance(a, float) and isinstance(b, float):
                return everett_scalar(a, b)
            return vector(a, b)[()]

        return everett_fast
    if self._density_fn is None:

        def everett_any(a, b):
            return vector(a, b)[()]

        return everett_any
    c = self.compiled_everett()
    kind, params, table = c.kind, c.params, c.table

    def everett(a, b):
        if not (isinstance(a, float) and isinstance(b, float)):
            return vector(a, b)[()]
        return everett_eval(kind, params, table, a, b)[0]

    return everett


def scalar_gradient(self: Any) -> Callable:
    """``everett_gradient`` with a fast path for scalar arguments of a density model (the
    compiled kernel on its table)."""
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
    if self._density_fn is None:
        return gradient_any
    c = self.compiled_everett()
    kind, params, table = c.kind, c.params, c.table

    def gradient(a, b):
        if not (isinstance(a, float) and isinstance(b, float)):
            return gradient_any(a, b)
        _, da, db = everett_eval(kind, params, table, a, b)
        return da, db

    return gradient
