"""The compiled form of a continuous Preisach model's Everett function.

:class:`CompiledEverett` is what :meth:`ContinuousPreisachModel.compiled_everett
<hysteresis.preisach.continuous.ContinuousPreisachModel.compiled_everett>` returns: plain
float64 arrays that the numba kernel
:func:`hysteresis.preisach._everett_kernels.everett_eval` evaluates as
``everett_eval(kind, params, table, a, b) -> (E, ∂E/∂a, ∂E/∂b)``, with the semantics of the
model's :meth:`everett` / :meth:`everett_gradient` (see that module for the layouts).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hysteresis._validation import readonly_array
from hysteresis.preisach._everett_kernels import KIND_GAUSSIAN, KIND_TABLE, everett_eval

__all__ = ["CompiledEverett", "EMPTY_TABLE"]

#: the ``table`` of a kind that needs none (shape ``(0, 0, 0)``)
EMPTY_TABLE = readonly_array(np.zeros((0, 0, 0)))


@dataclass(frozen=True, eq=False)
class CompiledEverett:
    """An Everett function as arrays for the compiled kernel ``everett_eval``.

    ``kind``: 0 = the Gaussian width-disorder quadrature (``table`` empty, shape
    ``(0, 0, 0)``), 1 = a bicubic Hermite table of nodal ``(E, ∂E/∂a, ∂E/∂b, ∂²E/∂a∂b)``,
    shape ``(n + 1, n + 1, 4)`` on the grid ``lower + k·(upper − lower)/n``. ``params``: 1-D
    float64, ``params[0:2] = (lower, upper)`` (the support) followed by the kind's own
    parameters. Both arrays are read-only float64; the object pickles as its fields.
    """

    kind: int
    params: np.ndarray
    table: np.ndarray

    def __post_init__(self) -> None:
        if self.kind not in (KIND_GAUSSIAN, KIND_TABLE):
            raise ValueError(f"kind must be {KIND_GAUSSIAN} or {KIND_TABLE}, got {self.kind!r}")
        params = readonly_array(self.params)
        table = readonly_array(self.table)
        if params.ndim != 1 or params.size < 2 or not params[1] > params[0]:
            raise ValueError("params must be 1-D and start with lower < upper")
        if table.ndim != 3:
            raise ValueError(f"table must be 3-D, got shape {table.shape}")
        if self.kind == KIND_TABLE and (
            table.shape[0] < 2 or table.shape[1] != table.shape[0] or table.shape[2] != 4
        ):
            raise ValueError(f"a kind-1 table must have shape (n+1, n+1, 4), got {table.shape}")
        object.__setattr__(self, "kind", int(self.kind))
        object.__setattr__(self, "params", params)
        object.__setattr__(self, "table", table)

    @property
    def lower(self) -> float:
        return float(self.params[0])

    @property
    def upper(self) -> float:
        return float(self.params[1])

    def __call__(self, a: float, b: float) -> tuple[float, float, float]:
        """``(E, ∂E/∂a, ∂E/∂b)`` at one point, through the compiled kernel."""
        return everett_eval(self.kind, self.params, self.table, float(a), float(b))
