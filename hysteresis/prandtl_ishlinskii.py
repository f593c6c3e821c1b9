"""Prandtl–Ishlinskii operator: a weighted superposition of plays, and its exact inverse.

``y = Σ_i a_i · F_{p_i}[u]`` where ``F_p`` is the play of width ``p`` (:class:`PlayOperator`) and
``a_i`` the weights. A linear term ``a_0 · u`` is the play of width 0 (the identity), so there is
no separate parameter for it: include ``0.0`` among the widths.

Inverse (Krasnosel'skii & Pokrovskii, *Systems with Hysteresis*, 1989; Brokate & Sprekels,
*Hysteresis and Phase Transitions*, 1996, §2.3; Kuhnen, IEEE Trans. Autom. Control 48 (2003) 1227,
"Modeling, identification and compensation of complex hysteretic nonlinearities").
With half-widths (thresholds) ``0 = r_0 < r_1 < ... < r_n`` (``r_i = p_i/2``) and partial sums
``A_i = a_0 + ... + a_i``, the initial loading curve ``φ(r) = Σ_i a_i (r - r_i)_+`` is strictly
increasing iff every ``A_i > 0``. The inverse is again a Prandtl–Ishlinskii operator with

    r'_i = φ(r_i) = Σ_{j<=i} a_j (r_i - r_j),
    a'_0 = 1/a_0,   a'_i = -a_i / (A_i A_{i-1})  (i >= 1),

(its loading curve is φ⁻¹). With consistent memories the plays of the inverse, driven by
``y``, are ``z_i = A_i w_i + Σ_{j>i} a_j w_j`` (``w_j`` the forward plays): by summation by parts
``y - z_i = Σ_{k<i} A_k (w_k - w_{k+1})`` and ``|w_k - w_{k+1}| <= r_{k+1} - r_k`` (semigroup
property of nested plays), so ``|y - z_i| <= r'_i`` with equality exactly when the input
touches the wall of play ``i``, and then ``dz_i = dy``. Hence ``u = Σ a'_i z_i``;
:meth:`PrandtlIshlinskii.inverse_state` builds the ``z_i`` from a forward state. The default
initial states (rising from −∞) of an operator and its inverse are consistent automatically:
``initial_state(u0)`` of the forward operator maps to ``inverse().initial_state(y0)`` with
``y0`` its output.
"""

from __future__ import annotations

from dataclasses import dataclass
from numbers import Real
from typing import Any

import numpy as np
from numba import njit

from hysteresis._validation import (
    MAX_MAGNITUDE,
    as_input_sequence,
    check_state_type,
    direction_sign,
    finite_array,
    finite_scalar,
    frozen_state_reduce,
    readonly_array,
)
from hysteresis.base import ContinuousHysteron
from hysteresis.flow import BranchFlow, CompiledFlow
from hysteresis.play import _touches_wall, _wall_tolerance

__all__ = ["PrandtlIshlinskii", "PIState"]


@dataclass(frozen=True)
class PIState:
    """Memory of a Prandtl–Ishlinskii operator: the wagon positions of all its plays (in the
    order of increasing width, read-only array) and the last input."""

    positions: np.ndarray
    input: float

    def __reduce__(self) -> tuple:
        return frozen_state_reduce(self)


@njit(cache=True)
def _pi_kernel(inputs, half_widths, weights, positions):  # pragma: no cover - compiled
    """Outputs and final wagon positions.

    Plain-Python reading::

        w = positions.copy()
        for k, u in enumerate(inputs):
            w = max(u - r, min(u + r, w))        # every play, elementwise
            out[k] = sum(weights * w)
    """
    w = positions.copy()
    out = np.empty_like(inputs)
    for k in range(inputs.size):
        u = inputs[k]
        y = 0.0
        for i in range(w.size):
            lo = u - half_widths[i]
            hi = u + half_widths[i]
            if w[i] < lo:
                w[i] = lo
            elif w[i] > hi:
                w[i] = hi
            y += weights[i] * w[i]
        out[k] = y
    return out, w


def _wagon_label(index: int) -> str:
    """Memory label of wagon ``index`` (order of increasing width)."""
    return f"w{index}"


class PrandtlIshlinskii(ContinuousHysteron[PIState]):
    """``y = Σ_i weights_i · play_{widths_i}(u)``.

    Parameters
    ----------
    widths:
        Distinct play widths p_i >= 0 (sorted internally, weights follow). Width 0 is the
        linear term.
    weights:
        Finite weights a_i (same length).

    Notes
    -----
    Widths and weights must have magnitude <= 1e300 (larger values overflow ``u ± p/2``);
    an output that still overflows for a given input raises ``ValueError`` in :meth:`apply`.
    """

    def __init__(self, widths, weights) -> None:
        widths = finite_array(widths, "widths", ndim=1, max_abs=MAX_MAGNITUDE)
        weights = finite_array(weights, "weights", ndim=1, max_abs=MAX_MAGNITUDE)
        if widths.shape != weights.shape:
            raise ValueError(
                f"weights must have the same length as widths ({widths.size}), got {weights.size}"
            )
        if np.any(widths < 0):
            raise ValueError("widths must be >= 0")
        order = np.argsort(widths, kind="stable")
        widths, weights = widths[order], weights[order]
        if np.any(np.diff(widths) == 0):
            raise ValueError("widths must be distinct")
        self._widths = readonly_array(widths)
        self._weights = readonly_array(weights)
        self._half = readonly_array(0.5 * widths)

    @property
    def widths(self) -> np.ndarray:
        """Play widths p_i, increasing."""
        return self._widths

    @property
    def weights(self) -> np.ndarray:
        """Weights a_i (in the order of ``widths``)."""
        return self._weights

    @property
    def half_widths(self) -> np.ndarray:
        """Thresholds r_i = p_i/2."""
        return self._half

    @property
    def output_range(self) -> tuple[float, float]:
        return (-np.inf, np.inf)

    @property
    def max_slope(self) -> float:
        """Largest branch slope: the sum of the positive weights.

        On a branch the slope is the sum of the weights of the plays dragged at their wall
        (:meth:`branch_flow`); an explicit :meth:`state` may put any subset of plays on a wall,
        so the largest slope is the sum of the positive weights (on the states reached from
        :meth:`initial_state`, where the dragged plays are the narrowest ones, it is the largest
        partial sum ``a_0 + ... + a_i``, which is the same when all weights are >= 0)."""
        return float(np.sum(np.maximum(self._weights, 0.0)))

    @property
    def min_slope(self) -> float:
        """Least branch slope: the least partial sum ``A_i = a_0 + ... + a_i`` (and 0 if the
        narrowest play has a width > 0).

        On a state reached from :meth:`initial_state` the plays dragged at their walls are the
        narrowest ones (nested plays: a wider play on its wall drags every narrower one), so a
        branch that has moved by ``2r`` since its last reversal has the slope ``A_i`` for
        ``r_i < r < r_{i+1}``, and slope 0 for ``r < r_0`` if ``r_0 > 0``. It is positive
        exactly when the closed-form :meth:`inverse` exists. (An explicit :meth:`state` may
        put a wide play on its wall with a narrower one inside, which no input history does;
        :attr:`max_slope` covers those too.)"""
        partial = np.cumsum(self._weights)
        least = float(np.min(partial))
        return least if self._widths[0] == 0.0 else min(least, 0.0)

    def __repr__(self) -> str:
        return (
            f"PrandtlIshlinskii(widths={self._widths.tolist()}, weights={self._weights.tolist()})"
        )

    def loading_curve(self, r) -> np.ndarray:
        """Initial loading curve ``φ(r) = Σ a_i (r - r_i)_+``.

        After a reversal that all plays followed, moving the input by ``2r`` changes the output
        by ``2 φ(r)`` (Masing rule); the inverse operator has the loading curve ``φ⁻¹``."""
        r = np.asarray(r, dtype=np.float64)
        return np.sum(self._weights * np.maximum(r[..., None] - self._half, 0.0), axis=-1)

    # -- states ---------------------------------------------------------------------------
    def initial_state(self, u0: float) -> PIState:
        """Rising from −∞: every wagon on its right wall, ``w_i = u0 - p_i/2``."""
        u0 = finite_scalar(u0, "u0", MAX_MAGNITUDE)
        return PIState(readonly_array(u0 - self._half), u0)

    def state(self, positions, input: float) -> PIState:
        """Explicit state; requires ``|input - positions_i| <= widths_i/2`` for every play."""
        positions = finite_array(positions, "positions", ndim=1)
        input = finite_scalar(input, "input", MAX_MAGNITUDE)
        if positions.shape != self._widths.shape:
            raise ValueError(f"positions must have length {self._widths.size}")
        for w, r in zip(positions, self._half, strict=True):
            if abs(input - w) > r + _wall_tolerance(w, input, r):
                raise ValueError(
                    "positions must satisfy |input - positions_i| <= widths_i/2 "
                    f"(position {w} with half-width {r} at input {input})"
                )
        return PIState(readonly_array(positions), input)

    def with_memory(self, state: PIState, values: Any, input: float, direction: int) -> PIState:
        """The wagons at ``values`` (one per play, in the order of the labels ``w0, w1, ..``)
        with the input at ``input``; a position beyond its wall is put on the wall."""
        self._check_state(state)
        direction_sign(direction)
        u = finite_scalar(input, "input", MAX_MAGNITUDE)
        w = np.asarray(values, dtype=np.float64).reshape(-1)
        if w.shape != self._half.shape:
            raise ValueError(f"values must hold {self._half.size} wagon positions, got {w.size}")
        return self.state(np.clip(w, u - self._half, u + self._half), u)

    def _check_state(self, state: object) -> np.ndarray:
        """Type, size and consistency of a state (O(n_plays)); returns the positions."""
        check_state_type(state, PIState, self)
        try:
            w = np.asarray(state.positions, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise ValueError("state.positions must be an array of real numbers") from exc
        if w.shape != self._widths.shape:
            raise ValueError(
                f"state has {w.size if w.ndim == 1 else w.shape} play positions, this operator "
                f"has {self._widths.size} plays: the state belongs to another operator"
            )
        u = state.input
        if not (
            np.all(np.isfinite(w))
            and isinstance(u, Real)
            and not isinstance(u, bool)
            and np.isfinite(u)
        ):
            raise ValueError("state positions and input must be finite real numbers")
        # relative 1e-9, not a few ulps: states computed elsewhere (inverse_state sums
        # weighted positions with cancellation) sit on a wall only up to their rounding
        tol = 1e-9 * np.maximum(np.maximum(np.abs(w), abs(u)), np.maximum(self._half, 1.0))
        bad = np.abs(u - w) > self._half + tol
        if np.any(bad):
            i = int(np.argmax(bad))
            raise ValueError(
                f"state: play {i} position {w[i]!r} is out of the input's reach "
                f"(|input - position| must be <= width/2 = {self._half[i]}, input {u!r}); "
                "the state belongs to another operator"
            )
        return w

    def apply(self, inputs, state: PIState | None = None) -> tuple[np.ndarray, PIState]:
        u = as_input_sequence(inputs)
        if state is None:
            state = self.initial_state(u[0])
        positions = self._check_state(state)
        out, w = _pi_kernel(u, self._half, self._weights, np.array(positions, dtype=float))
        if not np.all(np.isfinite(out)):
            k = int(np.argmax(~np.isfinite(out)))
            raise ValueError(
                f"inputs: the output overflows at input {u[k]!r} with these weights "
                f"(max |weight| {float(np.max(np.abs(self._weights)))!r}); scale them down"
            )
        return out, PIState(readonly_array(w), float(u[-1]))

    def output(self, state: PIState) -> float:
        return float(np.dot(self._weights, self._check_state(state)))

    # -- inverse --------------------------------------------------------------------------
    def _check_invertible(self) -> np.ndarray:
        if self._widths[0] != 0.0 or self._weights[0] <= 0.0:
            raise ValueError(
                "weights: the inverse needs a linear term, a width-0 play with weight > 0 "
                f"(got smallest width {self._widths[0]} with weight {self._weights[0]})"
            )
        partial = np.cumsum(self._weights)
        if np.any(partial <= 0.0):
            raise ValueError(
                "weights: every partial sum a_0 + ... + a_i must be > 0 for the inverse "
                f"(got {partial.tolist()})"
            )
        return partial

    def inverse(self) -> PrandtlIshlinskii:
        """The exact inverse Prandtl–Ishlinskii operator (see the module docstring)."""
        partial = self._check_invertible()
        r, a = self._half, self._weights
        # r'_i = Σ_{j<=i} a_j (r_i - r_j) = A_i r_i - Σ_{j<=i} a_j r_j
        r_inv = partial * r - np.cumsum(a * r)
        a_inv = np.empty_like(a)
        a_inv[0] = 1.0 / a[0]
        a_inv[1:] = -a[1:] / (partial[1:] * partial[:-1])
        return PrandtlIshlinskii(2.0 * r_inv, a_inv)

    def inverse_state(self, state: PIState) -> PIState:
        """State of :meth:`inverse` consistent with ``state`` of this operator:
        ``z_i = A_i w_i + Σ_{j>i} a_j w_j`` at input ``y = output(state)``."""
        partial = self._check_invertible()
        w = np.asarray(state.positions, dtype=np.float64)
        aw = self._weights * w
        tail = np.cumsum(aw[::-1])[::-1] - aw  # Σ_{j>i} a_j w_j
        return PIState(readonly_array(partial * w + tail), self.output(state))

    # -- compiled engine --------------------------------------------------------------------
    def compiled_flow(self) -> CompiledFlow:
        """The plays for the oscillator's compiled continuous engine (half-widths, weights;
        memory labels ``w0 ... w{K-1}`` as in :meth:`branch_flow`)."""
        return CompiledFlow(
            kind="prandtl_ishlinskii",
            label=_wagon_label,
            half_widths=self._half,
            weights=self._weights,
        )

    # -- branch flow (branch() and linearize() derive from it, hysteresis.base) -------------
    def _walls(self, state: PIState, direction: int) -> np.ndarray:
        check_state_type(state, PIState, self)  # O(1); the size is checked by zip(strict)
        u = float(state.input)
        return np.array(
            [
                _touches_wall(float(w), u, float(r), direction)
                for w, r in zip(state.positions, self._half, strict=True)
            ]
        )

    def _breakpoint(self, state: PIState, direction: int, walls: np.ndarray):
        inside = ~walls
        if not np.any(inside):
            return direction * np.inf, np.zeros(0, dtype=np.int64)
        ahead = np.asarray(state.positions)[inside] + direction * self._half[inside]
        bp = float(np.min(ahead) if direction > 0 else np.max(ahead))
        idx = np.flatnonzero(inside)
        tol = 8.0 * np.finfo(float).eps * max(abs(bp), 1.0)
        return bp, idx[np.abs(ahead - bp) <= tol].astype(np.int64)

    def branch_flow(self, state: PIState, direction: int) -> BranchFlow:
        """The branch in ``direction`` as a :class:`~hysteresis.flow.BranchFlow`.

        Memory: the K wagon positions ``w0 ... w{K-1}`` (order of increasing width). Wagons
        whose wall the input pushes are slaved, the others frozen; ``y = Σ a_i w_i`` is affine
        on the branch, ``y(u) = y0 + (Σ_slaved a_i)(u − u0)``, with ``∂y/∂u = 0`` and
        ``∂y/∂w_i = a_i``. Breakpoint: the nearest wall ahead of a frozen wagon, where that
        wagon (every wagon with that wall, ties included) gets ``δw_i := δu`` (``V_out``);
        ``±inf`` once every wagon is dragged. A reversal pushes nothing (``V_in = I``).
        """
        direction = direction_sign(direction)
        walls = self._walls(state, direction)
        bp, reset = self._breakpoint(state, direction, walls)
        labels = tuple(_wagon_label(i) for i in range(self._widths.size))
        u0 = float(state.input)
        y0 = self.output(state)
        dragged = float(np.sum(self._weights[walls]))
        weights = np.array(self._weights)

        def output(u):
            return y0 + dragged * (np.asarray(u, dtype=np.float64) - u0)

        def partials(u):
            u = np.asarray(u, dtype=np.float64)
            return np.zeros(u.shape)[()], np.broadcast_to(weights, u.shape + weights.shape)

        return BranchFlow(
            direction=direction,
            input=u0,
            labels=labels,
            memory=np.asarray(state.positions, dtype=np.float64),
            slaved=walls,
            output=output,
            partials=partials,
            breakpoint=bp,
            breakpoint_resets=tuple(labels[i] for i in reset),
            constant_partials=True,
        )
