"""A memoryless operator ``u ↦ f(u)``: the static nonlinearity of generalized models.

:class:`StaticMap` turns a continuous, piecewise-smooth function ``f`` of the input into an
operator like any other (state, ``apply``, ``branch_flow``), so that it composes: placed before a
play or a Prandtl–Ishlinskii operator in a :class:`~hysteresis.cascade.Cascade` it is the input
nonlinearity of a generalized Prandtl–Ishlinskii model, placed after one its output map.

Branch flow: no memory variables; ``y(u) = f(u)``, ``∂y/∂u = f'(u)``, no breakpoint in either
direction. The derivative is the user's (checked at construction) or numeric: the Richardson
extrapolation of central differences with steps ``h`` and ``h/2``,

    D(h) = (f(u + h) − f(u − h)) / 2h,   f'(u) ≈ (4 D(h/2) − D(h)) / 3,

``h = ε^{1/5}·max(1, |u|) ≈ 7.4e-4·max(1, |u|)`` (the realised step, ``(u + h) − (u − h)``, is
used): the ``h²`` term of the central difference cancels, the truncation error is ``O(h⁴ f⁽⁵⁾)``
and the rounding error about ``3ε·max|f|/h``, together ``≈ 1e-12`` relative to the scale of a
function whose derivatives are of order one on unit scale (``ε^{4/5}``). Within ``h`` of a kink
of a piecewise-smooth ``f`` the numeric derivative averages the two one-sided slopes.

Monotonicity (what a cascade needs): :attr:`StaticMap.monotonicity` is ``+1`` if ``f`` is
non-decreasing, ``-1`` if non-increasing, ``0`` otherwise, read from the values of ``f`` on the
probe grid :data:`PROBE` (1 001 points: ±1e-3 to ±100 logarithmically and [−10, 10] uniformly;
``f`` must be finite there, so ``exp`` is accepted, ``log`` is not).
An operator with memory driven by ``f`` changes its direction of input motion where ``f``
turns, so :class:`~hysteresis.cascade.Cascade` refuses a non-monotone map in front of one; a
decreasing map reverses the outer operator's direction. The probe cannot see a turn between two
of its points: such a map is outside the contract.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from numbers import Real
from typing import Any

import numpy as np

from hysteresis._validation import (
    MAX_MAGNITUDE,
    ParameterTypeError,
    as_input_sequence,
    check_state_type,
    direction_sign,
    finite_scalar,
)
from hysteresis.base import ContinuousHysteron
from hysteresis.flow import BranchFlow

__all__ = ["StaticMap", "StaticMapState", "PROBE"]

_EPS = float(np.finfo(np.float64).eps)
#: relative step of the numeric derivative, ε^{1/5} (module docstring)
STEP = _EPS**0.2

#: probe grid of the construction checks (finite values, monotonicity, output_range, max_slope)
PROBE = np.unique(
    np.concatenate(
        [
            -np.geomspace(1e2, 1e-3, 300),
            [0.0],
            np.geomspace(1e-3, 1e2, 300),
            np.linspace(-10.0, 10.0, 401),
        ]
    )
)
#: where a given derivative is compared with the numeric one: away from round numbers, where a
#: piecewise-smooth map has its kinks
_CHECK = np.array([0.0137, 0.0731, 0.289, 0.677, 1.313, 2.71, 5.92, 13.7, 41.3, 97.1])
_CHECK = np.concatenate([-_CHECK[::-1], _CHECK])


@dataclass(frozen=True)
class StaticMapState:
    """State of a :class:`StaticMap`: only the input it last saw (no memory)."""

    input: float


def _values(fn: Callable, u: np.ndarray, name: str) -> np.ndarray:
    """``fn(u)`` as a float array of ``u``'s shape, finite, or one sentence naming ``name``."""
    try:
        with np.errstate(all="ignore"):
            value = fn(u.copy())
    except Exception as exc:
        raise ValueError(
            f"{name} must accept a numpy array of inputs (vectorised); calling it raised "
            f"{type(exc).__name__}: {exc}"
        ) from exc
    if np.iscomplexobj(value):
        raise ParameterTypeError(f"{name} must return real numbers, got complex values")
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must return real numbers, got {type(value).__name__}") from exc
    if arr.shape != u.shape:
        raise ValueError(
            f"{name} must return one value per input (shape {u.shape}), got shape {arr.shape}"
        )
    bad = ~np.isfinite(arr)
    if np.any(bad):
        k = int(np.argmax(bad))
        raise ValueError(
            f"{name} must be finite, got {float(arr.flat[k])} at u = {float(u.flat[k])!r}"
        )
    return arr


class StaticMap(ContinuousHysteron[StaticMapState]):
    """The memoryless operator ``y = f(u)`` (see the module docstring).

    Parameters
    ----------
    f:
        Continuous, piecewise-smooth, vectorised function of the input (numpy array in, array of
        the same shape out), finite for every real input.
    derivative:
        ``f'`` (vectorised), or ``None`` for the numeric derivative of the module docstring. A
        given derivative must agree with the numeric one within its error estimate at 20 points
        (``ValueError`` naming ``derivative`` otherwise).
    output_range:
        ``(low, high)`` bounds of ``f`` if known (checked on the probe grid); default unbounded.
    max_slope:
        An upper bound of ``f'`` if known (checked on the probe grid); default ``None``.
    name:
        Optional label.

    Notes
    -----
    The operator pickles when ``f`` and ``derivative`` do (module-level functions, numpy ufuncs,
    picklable callable objects; not lambdas or closures).
    """

    def __init__(
        self,
        f: Callable,
        derivative: Callable | None = None,
        *,
        output_range: tuple[float, float] | None = None,
        max_slope: float | None = None,
        name: str | None = None,
    ) -> None:
        if not callable(f):
            raise ParameterTypeError(f"f must be a callable function of the input, got {f!r}")
        if derivative is not None and not callable(derivative):
            raise ParameterTypeError(f"derivative must be a callable or None, got {derivative!r}")
        if name is not None and not isinstance(name, str):
            raise ParameterTypeError(f"name must be a string or None, got {type(name).__name__}")
        self._f = f
        self._derivative = derivative
        self._name = name
        values = _values(f, PROBE, "f")
        # a step of a few ulps against the trend is rounding of a saturated map, not a turn
        steps = np.diff(values)
        slack = 16 * _EPS * np.maximum(np.abs(values[1:]), np.abs(values[:-1]))
        rising, falling = np.all(steps >= -slack), np.all(steps <= slack)
        self._monotonicity = 1 if rising else (-1 if falling else 0)
        if derivative is not None:
            self._check_derivative()
        self._range = self._check_range(output_range, values)
        self._max_slope = self._check_max_slope(max_slope)

    # -- construction checks ---------------------------------------------------------------
    def _check_derivative(self) -> None:
        given = _values(self._derivative, _CHECK, "derivative")
        numeric, error = self._numeric(_CHECK)
        # error: twice the h² error of the half-step difference (bounds the extrapolation's
        # truncation) plus its rounding, plus the given derivative's own rounding
        tol = error + 64 * _EPS * np.abs(given)
        bad = np.abs(given - numeric) > tol
        if np.any(bad):
            k = int(np.argmax(bad))
            u, g, fd, t = (float(a[k]) for a in (_CHECK, given, numeric, tol))
            raise ValueError(
                f"derivative disagrees with f: at u = {u!r} it returns {g!r}, Richardson central "
                f"differences of f give {fd!r} ± {t:.2g}"
            )

    @staticmethod
    def _check_range(output_range: Any, values: np.ndarray) -> tuple[float, float]:
        if output_range is None:
            return (-math.inf, math.inf)
        try:
            lo, hi = output_range
        except (TypeError, ValueError) as exc:
            raise ValueError(
                f"output_range must be a pair (low, high), got {output_range!r}"
            ) from exc
        for v in (lo, hi):
            if isinstance(v, bool) or not isinstance(v, Real) or math.isnan(v):
                raise ParameterTypeError(f"output_range must hold two real numbers, got {v!r}")
        lo, hi = float(lo), float(hi)
        if not lo <= hi:
            raise ValueError(f"output_range must have low <= high, got ({lo}, {hi})")
        outside = (values < lo) | (values > hi)
        if np.any(outside):
            u, y = float(PROBE[int(np.argmax(outside))]), float(values[int(np.argmax(outside))])
            raise ValueError(f"output_range ({lo}, {hi}) does not contain f({u!r}) = {y!r}")
        return (lo, hi)

    def _check_max_slope(self, max_slope: Any) -> float | None:
        if max_slope is None:
            return None
        bound = finite_scalar(max_slope, "max_slope")
        slope, error = self._numeric(PROBE)
        above = slope - error > bound * (1.0 + 1e-9) + 1e-12
        if np.any(above):
            u, s = float(PROBE[int(np.argmax(above))]), float(slope[int(np.argmax(above))])
            raise ValueError(f"max_slope {bound!r} is below the slope {s!r} of f at u = {u!r}")
        return bound

    # -- the function and its derivative ----------------------------------------------------
    @property
    def f(self) -> Callable:
        """The map ``f``."""
        return self._f

    @property
    def name(self) -> str | None:
        """Optional label."""
        return self._name

    @property
    def monotonicity(self) -> int:
        """``+1`` (``f`` non-decreasing on the probe grid), ``-1`` (non-increasing) or ``0``."""
        return self._monotonicity

    @property
    def output_range(self) -> tuple[float, float]:
        return self._range

    @property
    def max_slope(self) -> float | None:
        """The bound given at construction (``None``: unknown)."""
        return self._max_slope

    def _numeric(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Richardson-extrapolated central difference of ``f`` at ``u`` and an error bound."""
        u = np.asarray(u, dtype=np.float64)
        h = STEP * np.maximum(1.0, np.abs(u))
        up, um = u + h, u - h
        up2, um2 = u + 0.5 * h, u - 0.5 * h
        fp, fm = _values(self._f, up, "f"), _values(self._f, um, "f")
        fp2, fm2 = _values(self._f, up2, "f"), _values(self._f, um2, "f")
        d1 = (fp - fm) / (up - um)
        d2 = (fp2 - fm2) / (up2 - um2)
        scale = np.maximum(np.maximum(np.abs(fp), np.abs(fm)), np.maximum(np.abs(fp2), np.abs(fm2)))
        error = 2.0 * np.abs(d1 - d2) + 8.0 * _EPS * scale / h
        return (4.0 * d2 - d1) / 3.0, error

    def derivative(self, u) -> np.ndarray:
        """``f'(u)``: the given derivative, or the numeric one (module docstring)."""
        u = np.asarray(u, dtype=np.float64)
        if self._derivative is not None:
            return _values(self._derivative, u, "derivative")[()]
        return self._numeric(u)[0][()]

    # -- the operator contract ------------------------------------------------------------
    def initial_state(self, u0: float) -> StaticMapState:
        """No memory: the state is the input."""
        return StaticMapState(finite_scalar(u0, "u0", MAX_MAGNITUDE))

    def apply(self, inputs, state: StaticMapState | None = None):
        """``f`` of every input; the state only records the last input. ``ValueError`` naming
        ``f`` if it returns a non-finite value."""
        u = as_input_sequence(inputs)
        if state is not None:
            check_state_type(state, StaticMapState, self)
        try:
            y = _values(self._f, u, "f")
        except ValueError as exc:
            raise ValueError(f"{exc} (outside the probe range checked at construction)") from None
        return y, StaticMapState(float(u[-1]))

    def output(self, state: StaticMapState) -> float:
        check_state_type(state, StaticMapState, self)
        return float(_values(self._f, np.array([float(state.input)]), "f")[0])

    def with_memory(
        self, state: StaticMapState, values: Any, input: float, direction: int
    ) -> StaticMapState:
        """No memory: the state at ``input`` (``values`` empty)."""
        check_state_type(state, StaticMapState, self)
        direction_sign(direction)
        if np.asarray(values).size:
            raise ValueError(f"values must be empty (a static map has no memory), got {values!r}")
        return StaticMapState(finite_scalar(input, "input", MAX_MAGNITUDE))

    def branch_flow(self, state: StaticMapState, direction: int) -> BranchFlow:
        """No memory, ``y(u) = f(u)``, partials ``(f'(u), ())``, no breakpoint."""
        direction = direction_sign(direction)
        check_state_type(state, StaticMapState, self)
        f, derivative = self._f, self.derivative

        def output(u):
            return np.asarray(f(np.asarray(u, dtype=np.float64)), dtype=np.float64)[()]

        def partials(u):
            u = np.asarray(u, dtype=np.float64)
            return np.asarray(derivative(u), dtype=np.float64)[()], np.zeros(u.shape + (0,))

        return BranchFlow(
            direction=direction,
            input=float(state.input),
            labels=(),
            memory=np.zeros(0),
            slaved=np.zeros(0, dtype=bool),
            output=output,
            partials=partials,
            breakpoint=direction * math.inf,
        )

    def __repr__(self) -> str:
        return f"StaticMap({self._name})" if self._name else f"StaticMap({self._f!r})"
