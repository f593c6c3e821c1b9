"""Tabulated shapes of the generalized play: a piecewise cubic Hermite interpolant of ``f``.

:meth:`GeneralizedPlay.compiled_play <hysteresis.play.GeneralizedPlay.compiled_play>` hands a
user shape (e.g. ``tanh``) to the compiled play-limit kernel as a :class:`ShapeTable`, built
once by :func:`tabulate_shape` from ``f`` and ``f'`` on a uniform grid.

Range. The play's wagon can reach any ``w`` (the input is the oscillator's displacement), so
the table covers the shape's *transition*: with the limits ``f(±∞)`` (``output_range``, both
finite — a shape that does not saturate is not tabulated, :class:`ShapeTableError`) and the
tolerance ``δ = rtol·(f(+∞) − f(−∞))``, the grid spans ``[W₋, W₊]`` with
``W₊ = inf{w : f(+∞) − f(w) <= δ}`` and ``W₋ = sup{w : f(w) − f(−∞) <= δ}`` (bisection).
Beyond it the table continues with the end knot's value and slope 0: since ``f`` increases,
the error there is at most ``δ``.

Knots. The cubic Hermite interpolant on a step ``h`` has ``|f − Ĭf| <= h⁴ max|f⁗|/384`` and
``|f' − (Ĭf)'| <= √3 h³ max|f⁗|/216``. ``max|f⁗|`` is estimated by third differences of
``f'`` on 4096 probe intervals (times 2, for peaks between probe points); ``h`` is chosen for
``δ/2`` and then verified a posteriori at 7 interior points of every interval (the measured
error must be ``<= δ``; otherwise the knots are doubled). More than :data:`MAX_KNOTS` knots
(16 MiB) raise :class:`ShapeTableError`. Total: ``|f − table| <= δ`` everywhere (verified, the
value kept in :attr:`ShapeTable.error`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from hysteresis._validation import readonly_array

__all__ = ["MAX_KNOTS", "SHAPE_TABLE_RTOL", "ShapeTable", "ShapeTableError", "tabulate_shape"]

#: tolerance of a tabulated shape, relative to its output range ``f(+∞) − f(−∞)``
SHAPE_TABLE_RTOL = 1e-10
#: largest number of knots of a shape table (two float64 arrays: 16 MiB)
MAX_KNOTS = 1 << 20
#: probe intervals of the fourth-derivative estimate
_PROBE_INTERVALS = 4096
#: interior points per interval of the a-posteriori check
_CHECK_FRACTIONS = np.arange(1, 8) / 8.0


class ShapeTableError(ValueError):
    """The shape cannot be tabulated (it does not saturate, or needs more than
    :data:`MAX_KNOTS` knots for the tolerance)."""


@dataclass(frozen=True, eq=False)
class ShapeTable:
    """Piecewise cubic Hermite interpolant of a shape on the knots ``lower + k·step``.

    ``values``/``slopes``: ``f``, ``f'`` at the knots (read-only float64); beyond the last knot
    on either side the value of that knot and slope 0. ``error``: the verified bound
    ``max |f − table|`` (absolute), ``<= tolerance``; ``slope_error``: the largest measured
    ``|f' − table'|`` on the verification points.
    """

    lower: float
    step: float
    values: np.ndarray
    slopes: np.ndarray
    tolerance: float
    error: float
    slope_error: float

    @property
    def upper(self) -> float:
        return self.lower + self.step * (self.values.size - 1)

    @property
    def knots(self) -> int:
        return int(self.values.size)

    def evaluate(self, w) -> tuple[np.ndarray, np.ndarray]:
        """``(value, slope)`` of the interpolant at ``w`` (vectorised, NumPy)."""
        w = np.asarray(w, dtype=np.float64)
        m = self.values.size
        x = (w - self.lower) / self.step
        k = np.clip(np.floor(x), 0, m - 2).astype(np.int64)
        s = np.clip(x - k, 0.0, 1.0)
        f0, f1 = self.values[k], self.values[k + 1]
        d0, d1 = self.slopes[k] * self.step, self.slopes[k + 1] * self.step
        s2 = s * s
        value = (
            (1 - 3 * s2 + 2 * s2 * s) * f0
            + (s - 2 * s2 + s2 * s) * d0
            + (3 * s2 - 2 * s2 * s) * f1
            + (s2 * s - s2) * d1
        )
        slope = (
            (-6 * s + 6 * s2) * f0
            + (1 - 4 * s + 3 * s2) * d0
            + (6 * s - 6 * s2) * f1
            + (3 * s2 - 2 * s) * d1
        ) / self.step
        outside = (x < 0) | (x > m - 1)
        slope = np.where(outside, 0.0, slope)
        return value[()], slope[()]

    def kernel_array(self) -> np.ndarray:
        """``[lower, step, knots, values..., slopes...]`` (the play kernel's layout)."""
        return np.concatenate(
            [[self.lower, self.step, float(self.knots)], self.values, self.slopes]
        )


def _level_crossing(g: Callable[[float], bool]) -> float:
    """``inf{w : g(w)}`` for a predicate that is false left of it and true right of it."""
    lo, hi = -1.0, 1.0
    while g(lo):
        lo *= 2.0
        if lo < -1e300:
            raise ShapeTableError("the shape saturates nowhere inside [-1e300, 1e300]")
    while not g(hi):
        hi *= 2.0
        if hi > 1e300:
            raise ShapeTableError("the shape does not reach its limit inside [-1e300, 1e300]")
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if not lo < mid < hi or hi - lo <= 1e-12 * max(1.0, abs(mid)):
            break
        if g(mid):
            hi = mid
        else:
            lo = mid
    return hi


def tabulate_shape(
    shape: Callable,
    derivative: Callable,
    limits: tuple[float, float],
    rtol: float = SHAPE_TABLE_RTOL,
) -> ShapeTable:
    """The :class:`ShapeTable` of ``shape`` (vectorised, increasing, limits ``f(∓∞)`` =
    ``limits``) and its ``derivative`` within ``rtol`` of the output range (see the module)."""
    lo_val, hi_val = (float(v) for v in limits)
    if not (math.isfinite(lo_val) and math.isfinite(hi_val)) or not hi_val > lo_val:
        raise ShapeTableError(
            f"only a saturating shape (finite limits f(-inf) < f(+inf)) is tabulated, got "
            f"limits ({lo_val}, {hi_val})"
        )

    def f(w):
        return np.asarray(shape(np.asarray(w, dtype=np.float64)), dtype=np.float64)

    def df(w):
        return np.asarray(derivative(np.asarray(w, dtype=np.float64)), dtype=np.float64)

    delta = rtol * (hi_val - lo_val)
    w_hi = _level_crossing(lambda w: hi_val - float(f(w)) <= delta)
    # W₋ = sup{w : f(w) − f(−∞) <= δ} = −inf{x : f(−x) − f(−∞) <= δ}
    w_lo = -_level_crossing(lambda x: float(f(-x)) - lo_val <= delta)
    if not w_hi > w_lo:
        raise ShapeTableError(f"the shape's transition range is empty ([{w_lo}, {w_hi}])")
    span = w_hi - w_lo
    probe = np.linspace(w_lo, w_hi, _PROBE_INTERVALS + 1)
    d = span / _PROBE_INTERVALS
    fourth = 2.0 * float(np.max(np.abs(np.diff(df(probe), 3)))) / d**3
    target = 0.5 * delta
    h = (384.0 * target / fourth) ** 0.25 if fourth > 0 else span
    knots = max(2, int(math.ceil(span / h)) + 1)
    while True:
        if knots > MAX_KNOTS:
            raise ShapeTableError(
                f"the shape needs more than {MAX_KNOTS} knots to be tabulated within "
                f"{delta:.3g} (estimated max|f''''| = {fourth:.3g} on [{w_lo:.6g}, {w_hi:.6g}])"
            )
        grid = np.linspace(w_lo, w_hi, knots)
        step = (w_hi - w_lo) / (knots - 1)
        table = ShapeTable(
            lower=w_lo,
            step=step,
            values=readonly_array(f(grid)),
            slopes=readonly_array(df(grid)),
            tolerance=delta,
            error=0.0,
            slope_error=0.0,
        )
        pts = (grid[:-1, None] + step * _CHECK_FRACTIONS[None, :]).ravel()
        value, slope = table.evaluate(pts)
        error = float(np.max(np.abs(value - f(pts))))
        if error <= delta:
            slope_error = float(np.max(np.abs(slope - df(pts))))
            return ShapeTable(
                lower=w_lo,
                step=step,
                values=table.values,
                slopes=table.slopes,
                tolerance=delta,
                error=max(error, hi_val - float(table.values[-1]), float(table.values[0]) - lo_val),
                slope_error=slope_error,
            )
        knots = 2 * knots - 1
