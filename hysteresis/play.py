"""The play (backlash) operator and the generalized play.

Play, paper eq. (real_play): a wagon of length ``p`` (``width``) centred at ``w`` is pushed by a
finger at the input ``u``::

    w = max(u - p/2, min(u + p/2, w_prev))

The output of :class:`PlayOperator` is the wagon position ``w``. The finger touches the right wall
when ``u = w + p/2`` (rising input drags the wagon) and the left wall when ``u = w - p/2``;
strictly between the walls the wagon stays where it is.

Generalized play (paper eq. play): the output is ``f(w)`` for a strictly increasing shape ``f``;
the paper's thermodynamic limit of the spin-dimer ensemble is ``f(w) = erf(w / (sqrt(2) R))``.
Because ``f`` is increasing, the output is ``max(f_+(u), min(f_-(u), y_prev))`` with the
envelopes ``f_+(u) = f(u - p/2)`` (lower, followed on a rising input: :meth:`ascending`) and
``f_-(u) = f(u + p/2)`` (upper, followed on a falling input: :meth:`descending`). Note the paper's
subscripts: its ``f_-`` is the *upper* (descending) envelope and ``f_+`` the *lower* (ascending).

Both operators share the state :class:`PlayState` (the memory is the wagon position ``w``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from numbers import Real
from typing import Any

import numpy as np
from numba import njit
from scipy.special import erf

from hysteresis._validation import (
    MAX_MAGNITUDE,
    ParameterTypeError,
    as_input_sequence,
    check_state_type,
    direction_sign,
    finite_scalar,
    nonnegative_scalar,
    positive_scalar,
)
from hysteresis.base import ContinuousHysteron
from hysteresis.flow import BranchFlow
from hysteresis.shape_table import ShapeTable, ShapeTableError, tabulate_shape

__all__ = [
    "CompiledPlay",
    "ErfShape",
    "ErfShapeDerivative",
    "PlayState",
    "PlayOperator",
    "GeneralizedPlay",
    "play_positions",
]

_EPS = np.finfo(np.float64).eps


@dataclass(frozen=True)
class PlayState:
    """Memory of a play: wagon position ``w`` and the input ``u`` it last saw
    (``|u - w| <= width/2``)."""

    position: float
    input: float


@dataclass(frozen=True)
class CompiledPlay:
    """What the oscillator's compiled play-limit kernel needs (a fast path, see
    :meth:`hysteresis.base.ContinuousHysteron.compiled_play`).

    Attributes
    ----------
    width:
        Wagon length p.
    shape:
        ``"identity"`` (plain play, output ``w``), ``"erf"`` (output ``erf(w/(√2 R))``) or
        ``"table"`` (output the piecewise cubic Hermite interpolant ``table`` of a user shape).
    spread:
        R of the erf shape (1.0 otherwise).
    table:
        The :class:`~hysteresis.shape_table.ShapeTable` of shape ``"table"`` (else ``None``).
    """

    width: float
    shape: str
    spread: float = 1.0
    table: ShapeTable | None = None


@njit(cache=True)
def _play_kernel(inputs, half_width, position):  # pragma: no cover - compiled
    """Wagon positions for a sequence of inputs.

    Plain-Python reading::

        w = position
        for k, u in enumerate(inputs):
            w = max(u - half_width, min(u + half_width, w))
            out[k] = w
    """
    out = np.empty_like(inputs)
    w = position
    for k in range(inputs.size):
        lo = inputs[k] - half_width
        hi = inputs[k] + half_width
        if w < lo:
            w = lo
        elif w > hi:
            w = hi
        out[k] = w
    return out


def play_positions(inputs: np.ndarray, width: float, position: float) -> np.ndarray:
    """Wagon positions of a play of ``width`` started at ``position`` (no validation)."""
    return _play_kernel(np.ascontiguousarray(inputs, dtype=np.float64), 0.5 * width, position)


def _wall_tolerance(position: float, input: float, half_width: float) -> float:
    # apply() sets w = u - p/2 exactly, but u - w then equals p/2 only up to rounding; a few ulps
    # of the magnitudes involved decide "on the wall".
    return 8.0 * _EPS * max(abs(position), abs(input), half_width, 1.0)


def _touches_wall(position: float, input: float, half_width: float, direction: int) -> bool:
    """True if the finger touches the wall it pushes when the input moves in ``direction``."""
    gap = direction * (input - position)  # distance from the centre towards the pushed wall
    return gap >= half_width - _wall_tolerance(position, input, half_width)


class _PlayBase(ContinuousHysteron[PlayState]):
    """Shared machinery of the play and the generalized play (memory: wagon position)."""

    def __init__(self, width: float) -> None:
        # bounded so that u ± p/2 stays finite for every admissible input
        self._width = nonnegative_scalar(width, "width", MAX_MAGNITUDE)

    @property
    def width(self) -> float:
        """Wagon length p (full width of the loop), >= 0."""
        return self._width

    @property
    def half_width(self) -> float:
        """p/2."""
        return 0.5 * self._width

    # -- output function of the wagon position (identity for the play) ----------------------
    def _f(self, w):
        raise NotImplementedError

    def _df(self, w):
        raise NotImplementedError

    # -- states ---------------------------------------------------------------------------
    def initial_state(self, u0: float) -> PlayState:
        """Rising from −∞ to ``u0`` leaves the wagon at ``w0 = u0 - p/2`` (right wall)."""
        u0 = finite_scalar(u0, "u0", MAX_MAGNITUDE)
        return PlayState(u0 - self.half_width, u0)

    def state(self, position: float, input: float) -> PlayState:
        """An explicit state; requires ``|input - position| <= width/2``."""
        position = finite_scalar(position, "position", MAX_MAGNITUDE)
        input = finite_scalar(input, "input", MAX_MAGNITUDE)
        half = self.half_width
        if abs(input - position) > half + _wall_tolerance(position, input, half):
            raise ValueError(
                f"position must satisfy |input - position| <= width/2 = {half} "
                f"(got position={position}, input={input})"
            )
        return PlayState(position, input)

    def with_memory(self, state: PlayState, values: Any, input: float, direction: int) -> PlayState:
        """The wagon at ``values[0]`` with the input at ``input``; a position beyond a wall is
        put on the wall (the state space is the closed strip ``|input − w| <= p/2``)."""
        self._check_state(state)
        direction_sign(direction)
        w = np.asarray(values, dtype=np.float64).reshape(-1)
        if w.size != 1:
            raise ValueError(f"values must hold the one wagon position, got {w.size} values")
        u = finite_scalar(input, "input", MAX_MAGNITUDE)
        half = self.half_width
        return self.state(float(np.clip(w[0], u - half, u + half)), u)

    def _check_state(self, state: object) -> None:
        """Type and consistency of a state (O(1)): finite position within p/2 of its input."""
        check_state_type(state, PlayState, self)
        w, u = state.position, state.input
        for value, label in ((w, "state.position"), (u, "state.input")):
            if isinstance(value, bool) or not isinstance(value, Real) or not math.isfinite(value):
                raise ValueError(f"{label} must be a finite real number, got {value!r}")
        half = self.half_width
        if abs(u - w) > half + _wall_tolerance(w, u, half):
            raise ValueError(
                f"state: position {w!r} is out of the input's reach (|input - position| must be "
                f"<= width/2 = {half}, input {u!r}); the state belongs to another operator"
            )

    def positions(self, inputs, state: PlayState | None = None) -> tuple[np.ndarray, PlayState]:
        """Wagon positions ``w`` for the inputs (the play output) and the final state."""
        u = as_input_sequence(inputs)
        if state is None:
            state = self.initial_state(u[0])
        else:
            self._check_state(state)
        w = play_positions(u, self._width, float(state.position))
        return w, PlayState(float(w[-1]), float(u[-1]))

    def apply(self, inputs, state: PlayState | None = None) -> tuple[np.ndarray, PlayState]:
        w, final = self.positions(inputs, state)
        return np.asarray(self._f(w), dtype=np.float64), final

    def output(self, state: PlayState) -> float:
        self._check_state(state)
        return float(self._f(float(state.position)))

    # -- branch flow (branch() and linearize() derive from it, hysteresis.base) -------------
    def on_wall(self, state: PlayState, direction: int) -> bool:
        """True if moving the input in ``direction`` drags the wagon (finger on that wall)."""
        direction = direction_sign(direction)
        check_state_type(state, PlayState, self)  # O(1): integrators call this every step
        return _touches_wall(float(state.position), float(state.input), self.half_width, direction)

    def branch_flow(self, state: PlayState, direction: int) -> BranchFlow:
        """The branch in ``direction`` as a :class:`~hysteresis.flow.BranchFlow` (any shape).

        Memory ``("w",)``, output ``y = f(w)`` (``∂y/∂u = 0``, ``∂y/∂w = f'(w)``). On the wall
        the input pushes: ``w`` slaved, ``y(u) = f(w0 + u − u0)``, no breakpoint. Inside:
        ``w`` frozen, ``y = f(w0)``; the breakpoint is the wall ahead, ``w0 ± p/2``, where
        ``δw := δu`` (``V_out``). A reversal pushes nothing (``V_in = I``).
        """
        direction = direction_sign(direction)
        w0 = float(state.position)
        u0 = float(state.input)
        f, df = self._f, self._df
        if self.on_wall(state, direction):

            def output(u):
                return f(w0 + (np.asarray(u, dtype=np.float64) - u0))

            def partials(u):
                u = np.asarray(u, dtype=np.float64)
                d_w = np.asarray(df(w0 + (u - u0)), dtype=np.float64)
                return np.zeros(u.shape)[()], d_w[..., None]

            return BranchFlow(
                direction=direction,
                input=u0,
                labels=("w",),
                memory=np.array([w0]),
                slaved=np.array([True]),
                output=output,
                partials=partials,
                breakpoint=direction * np.inf,
            )
        y0 = float(f(w0))
        d_w0 = float(df(w0))

        def output_inside(u):
            u = np.asarray(u, dtype=np.float64)
            return np.full(u.shape, y0)[()]

        def partials_inside(u):
            u = np.asarray(u, dtype=np.float64)
            return np.zeros(u.shape)[()], np.full(u.shape + (1,), d_w0)

        return BranchFlow(
            direction=direction,
            input=u0,
            labels=("w",),
            memory=np.array([w0]),
            slaved=np.array([False]),
            output=output_inside,
            partials=partials_inside,
            breakpoint=w0 + direction * self.half_width,
            breakpoint_resets=("w",),
            constant_partials=True,
        )


class PlayOperator(_PlayBase):
    """Play (backlash) operator of width ``p``; output is the wagon position ``w``.

    ``w = max(u - p/2, min(u + p/2, w_prev))`` (paper eq. real_play). ``width = 0`` is the
    identity.
    """

    def _f(self, w):
        return w

    def _df(self, w):
        return np.ones_like(np.asarray(w, dtype=np.float64))[()]

    @property
    def output_range(self) -> tuple[float, float]:
        return (-np.inf, np.inf)

    @property
    def max_slope(self) -> float:
        """1: the output follows the input on a wall (0 inside the play)."""
        return 1.0

    @property
    def min_slope(self) -> float:
        """0: between its walls the wagon stays and the output is flat (1 at width 0, the
        identity)."""
        return 1.0 if self._width == 0.0 else 0.0

    def compiled_play(self) -> CompiledPlay:
        """The plain play runs on the compiled play-limit kernel (identity shape)."""
        return CompiledPlay(width=self._width, shape="identity")

    def __repr__(self) -> str:
        return f"PlayOperator(width={self._width!r})"


class ErfShape:
    """The erf shape ``f(w) = erf(w / (sqrt(2) R))`` of :meth:`GeneralizedPlay.erf`, a
    picklable callable (``spread`` = R > 0, not validated here)."""

    def __init__(self, spread: float) -> None:
        self.spread = spread
        self._scale = math.sqrt(2.0) * spread

    def __call__(self, w):
        return erf(np.asarray(w, dtype=np.float64) / self._scale)[()]

    def __reduce__(self) -> tuple:
        return (type(self), (self.spread,))

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.spread!r})"


class ErfShapeDerivative(ErfShape):
    """``f'(w) = sqrt(2/π)/R · exp(−w²/(2R²))``, the derivative of :class:`ErfShape`."""

    def __init__(self, spread: float) -> None:
        super().__init__(spread)
        self._norm = math.sqrt(2.0 / math.pi) / spread

    def __call__(self, w):
        w = np.asarray(w, dtype=np.float64)
        return (self._norm * np.exp(-0.5 * (w / self.spread) ** 2))[()]


#: probe points of the shape check: both signs, scales from 1e-3 to 1e3
_PROBE = np.concatenate([-np.geomspace(1e3, 1e-3, 13), [0.0], np.geomspace(1e-3, 1e3, 13)])


def _evaluate(fn: Callable, w: np.ndarray, name: str) -> np.ndarray:
    try:
        with np.errstate(all="ignore"):
            value = fn(w.copy())
    except Exception as exc:
        raise ValueError(
            f"{name} must accept a numpy array of w values (vectorised); calling it on an array "
            f"raised {type(exc).__name__}: {exc}"
        ) from exc
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must return real numbers, got {type(value).__name__}") from exc
    if np.iscomplexobj(value):
        raise ParameterTypeError(f"{name} must return real numbers, got complex values")
    if arr.shape != w.shape:
        raise ValueError(
            f"{name} must return one value per input (shape {w.shape}), got shape {arr.shape}"
        )
    bad = ~np.isfinite(arr)
    if np.any(bad):
        raise ValueError(f"{name} must be finite, got {arr[bad][0]} at w = {w[bad][0]!r}")
    return arr


def _check_shape(shape: Callable, derivative: Callable) -> None:
    """Probe ``shape`` and ``shape_derivative`` on :data:`_PROBE` at construction: finite,
    one value per input, ``shape`` non-decreasing and not constant, ``shape_derivative >= 0``
    and consistent with central differences of ``shape`` (at one of two step sizes)."""
    w = _PROBE
    f = _evaluate(shape, w, "shape")
    steps = np.diff(f)
    if np.any(steps < 0):
        k = int(np.argmax(steps < 0))
        raise ValueError(
            f"shape must be increasing, but shape({w[k + 1]!r}) = {f[k + 1]!r} < "
            f"shape({w[k]!r}) = {f[k]!r}"
        )
    if not f[-1] > f[0]:
        raise ValueError("shape must be increasing, got a constant function on [-1e3, 1e3]")
    df = _evaluate(derivative, w, "shape_derivative")
    if np.any(df < 0):
        k = int(np.argmax(df < 0))
        raise ValueError(f"shape_derivative must be >= 0, got {df[k]!r} at w = {w[k]!r}")
    scale = float(np.max(np.abs(df)))
    ok = np.zeros(w.size, dtype=bool)
    fd = np.zeros(w.size)
    for rel in (1e-4, 1e-6):
        h = rel * np.maximum(1.0, np.abs(w))
        fd = (_evaluate(shape, w + h, "shape") - _evaluate(shape, w - h, "shape")) / (2 * h)
        ok |= np.abs(fd - df) <= 0.05 * np.maximum(np.abs(fd), np.abs(df)) + 1e-7 * scale
    if not np.all(ok):
        k = int(np.argmin(ok))
        raise ValueError(
            f"shape_derivative is inconsistent with shape: at w = {w[k]!r} it returns "
            f"{df[k]!r}, central differences of shape give {fd[k]!r}"
        )


class GeneralizedPlay(_PlayBase):
    """Generalized play: output ``shape(w)`` with ``w`` the wagon position of a play of ``width``.

    Parameters
    ----------
    width:
        Wagon length p >= 0.
    shape:
        Strictly increasing, vectorised callable ``f`` (numpy array in, array out).
    shape_derivative:
        Its derivative ``f'`` (vectorised).
    name:
        Optional label.

    The operator pickles (worker processes, saved runs) when ``shape`` and
    ``shape_derivative`` do: module-level functions or :class:`ErfShape`-like objects, not
    lambdas or closures.

    Attributes
    ----------
    shape_kind:
        ``"erf"`` for :meth:`erf` (then ``spread`` = R is set) or ``"custom"``, so that compiled
        integrators can specialise on the paper's case. ``shape_kind``, ``spread`` and ``name``
        are read-only properties.
    """

    def __init__(
        self,
        width: float,
        shape: Callable,
        shape_derivative: Callable,
        name: str | None = None,
    ) -> None:
        self._init(width, shape, shape_derivative, name, check=True)

    def _init(self, width, shape, shape_derivative, name, check: bool) -> None:
        super().__init__(width)
        if not callable(shape):
            raise ParameterTypeError("shape must be a callable, strictly increasing function of w")
        if not callable(shape_derivative):
            raise ParameterTypeError("shape_derivative must be a callable (derivative of shape)")
        if name is not None and not isinstance(name, str):
            raise ParameterTypeError(f"name must be a string or None, got {type(name).__name__}")
        if check:
            _check_shape(shape, shape_derivative)
        self._shape = shape
        self._shape_derivative = shape_derivative
        # read-only after construction (properties below): the play-limit integrator dispatches
        # on shape_kind/spread, so changing them later would desynchronise them from the shape.
        self._name = name
        self._shape_kind = "custom"
        self._spread: float | None = None

    @classmethod
    def erf(cls, width: float, spread: float) -> GeneralizedPlay:
        """The paper's thermodynamic limit ``M = erf(w / (sqrt(2) R))``, spread = R > 0.

        It is the Preisach model with density ``N(s; 0, R²) δ(r - p/2)`` in rotated
        coordinates (paper eqs. pdens_sr, prob_mag).
        """
        spread = positive_scalar(spread, "spread", MAX_MAGNITUDE)
        shape, derivative = ErfShape(spread), ErfShapeDerivative(spread)
        # the closed form needs no probe check (and a very small R would defeat the finite
        # differences of the check)
        op = cls.__new__(cls)
        op._init(width, shape, derivative, f"erf(w/(sqrt(2)*{spread}))", check=False)
        op._shape_kind = "erf"
        op._spread = spread
        return op

    @property
    def shape_kind(self) -> str:
        """``"erf"`` for :meth:`erf`, ``"custom"`` otherwise (read-only)."""
        return self._shape_kind

    @property
    def spread(self) -> float | None:
        """R of :meth:`erf` (read-only); ``None`` for a custom shape."""
        return self._spread

    @property
    def name(self) -> str | None:
        """Optional label (read-only)."""
        return self._name

    @property
    def shape(self) -> Callable:
        """Output shape f(w)."""
        return self._shape

    @property
    def shape_derivative(self) -> Callable:
        """f'(w)."""
        return self._shape_derivative

    def _f(self, w):
        return self._shape(w)

    def apply(self, inputs, state: PlayState | None = None) -> tuple[np.ndarray, PlayState]:
        w, final = self.positions(inputs, state)
        with np.errstate(all="ignore"):
            y = np.asarray(self._f(w), dtype=np.float64)
        if y.shape != w.shape or not np.all(np.isfinite(y)):
            bad = np.flatnonzero(~np.isfinite(y)) if y.shape == w.shape else np.array([0])
            raise ValueError(
                f"shape returned a non-finite value or the wrong shape at w = {w[bad[0]]!r} "
                "(outside the probe range checked at construction)"
            )
        return y, final

    def _df(self, w):
        return self._shape_derivative(w)

    def ascending(self, u) -> np.ndarray:
        """Lower envelope followed on a rising input, ``f(u - p/2)`` (the paper's ``f_+``)."""
        return self._shape(np.asarray(u, dtype=np.float64) - self.half_width)

    def descending(self, u) -> np.ndarray:
        """Upper envelope followed on a falling input, ``f(u + p/2)`` (the paper's ``f_-``)."""
        return self._shape(np.asarray(u, dtype=np.float64) + self.half_width)

    @property
    def output_range(self) -> tuple[float, float]:
        if self.shape_kind == "erf":
            return (-1.0, 1.0)
        with np.errstate(all="ignore"):
            lo = float(self._shape(np.array(-np.inf)))
            hi = float(self._shape(np.array(np.inf)))
        return (lo if not math.isnan(lo) else -np.inf, hi if not math.isnan(hi) else np.inf)

    @property
    def max_slope(self) -> float | None:
        """The steepest branch slope: ``max f'`` of the erf shape, ``1/(R√(2π))`` at ``w = 0``
        (on a wall the branch is ``f(u ∓ p/2)``); ``None`` for a user's shape (not known)."""
        if self.shape_kind == "erf":
            return 1.0 / (float(self._spread) * math.sqrt(2.0 * math.pi))
        return None

    @property
    def min_slope(self) -> float | None:
        """0 for width > 0: between the walls the output is flat. At width 0 the output is
        ``shape(u)``, whose least slope the operator does not know (``None``: an erf shape's
        slope vanishes only in the saturated tails)."""
        return 0.0 if self._width > 0.0 else None

    #: the shape table (built on the first compiled_play() call) is rebuilt, not pickled
    _transient_attributes = ("_shape_table",)

    def shape_table(self) -> ShapeTable:
        """The piecewise cubic Hermite table of a custom shape that the compiled play kernel
        integrates (:func:`~hysteresis.shape_table.tabulate_shape`: ``|f − table| <= 1e-10`` of
        the output range, verified; beyond the shape's transition range the saturation value).
        Built once and kept. :class:`~hysteresis.shape_table.ShapeTableError` if the shape
        does not saturate (an infinite ``output_range``) or needs more than
        :data:`~hysteresis.shape_table.MAX_KNOTS` knots."""
        table = self.__dict__.get("_shape_table")
        if table is None:
            table = tabulate_shape(self._shape, self._shape_derivative, self.output_range)
            self._shape_table = table
        return table

    def compiled_play(self) -> CompiledPlay | None:
        """The compiled play-limit kernel's description: ``GeneralizedPlay.erf`` in closed
        form; a custom shape as its :meth:`shape_table` (shape ``"table"``; the kernel
        integrates the table, within 1e-10 of the output range). A shape that cannot be
        tabulated (no saturation, or too many knots: :meth:`shape_table` says why) has no
        compiled description (``None``) and is integrated by the generic continuous engine."""
        if self._shape_kind == "erf":
            return CompiledPlay(width=self._width, shape="erf", spread=float(self._spread))
        try:
            table = self.shape_table()
        except ShapeTableError:
            return None
        return CompiledPlay(width=self._width, shape="table", table=table)

    def __repr__(self) -> str:
        if self.shape_kind == "erf":
            return f"GeneralizedPlay.erf(width={self._width!r}, spread={self.spread!r})"
        return f"GeneralizedPlay(width={self._width!r}, shape={self.name or self._shape!r})"
