"""The relay (Preisach unit, hysteron): the elementary hysteresis loop.

Paper eq. (preisachunit): a relay with thresholds ``alpha >= beta`` outputs ``+1`` once the input
has reached ``u >= alpha`` and ``-1`` once it has fallen to ``u < beta``; for
``beta <= u < alpha`` it keeps its previous output. In rotated coordinates the loop has centre
``s = (alpha + beta)/2``, half-width ``r = (alpha - beta)/2`` and width ``p = 2r``.

Zero width (``alpha == beta``) is allowed and gives a reversible switch: ``+1`` for
``u >= alpha``, ``-1`` for ``u < alpha`` (this is how a non-hysteretic spin dimer flips).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Real

import numpy as np

from hysteresis._validation import (
    MAX_MAGNITUDE,
    as_input_sequence,
    check_state_type,
    finite_scalar,
    real_array,
)
from hysteresis.base import PiecewiseConstantHysteron, Switching
from hysteresis.relay_table import RelayTable

__all__ = ["Relay", "RelayState"]


@dataclass(frozen=True)
class RelayState:
    """Memory of a relay: its output (+1 or -1) and the input it last saw."""

    output: float
    input: float


class Relay(PiecewiseConstantHysteron[RelayState]):
    """Elementary hysteresis loop with upper threshold ``alpha`` and lower threshold ``beta``.

    Parameters
    ----------
    alpha:
        Upper switching input α: the output becomes +1 as soon as ``u >= alpha``.
    beta:
        Lower switching input β <= α: the output becomes -1 as soon as ``u < beta``.

    Both thresholds must be finite real numbers (not strings) of magnitude <= 1e300, so that
    the centre and the width are finite.
    """

    def __init__(self, alpha: float, beta: float) -> None:
        alpha = finite_scalar(alpha, "alpha", MAX_MAGNITUDE)
        beta = finite_scalar(beta, "beta", MAX_MAGNITUDE)
        if alpha < beta:
            raise ValueError(f"alpha must be >= beta (got alpha={alpha}, beta={beta})")
        self._alpha = alpha
        self._beta = beta

    @property
    def alpha(self) -> float:
        """Upper threshold α."""
        return self._alpha

    @property
    def beta(self) -> float:
        """Lower threshold β."""
        return self._beta

    @property
    def centre(self) -> float:
        """Loop centre s = (α + β)/2."""
        return 0.5 * (self._alpha + self._beta)

    @property
    def half_width(self) -> float:
        """Half-width r = (α − β)/2."""
        return 0.5 * (self._alpha - self._beta)

    @property
    def width(self) -> float:
        """Loop width p = α − β = 2r."""
        return self._alpha - self._beta

    def __repr__(self) -> str:
        return f"Relay(alpha={self._alpha!r}, beta={self._beta!r})"

    # -- states ---------------------------------------------------------------------------
    def initial_state(self, u0: float) -> RelayState:
        """State after rising from −∞ to ``u0``: +1 iff ``u0 >= alpha``."""
        u0 = finite_scalar(u0, "u0", MAX_MAGNITUDE)
        return RelayState(1.0 if u0 >= self._alpha else -1.0, u0)

    def state(self, output: float, input: float) -> RelayState:
        """An explicit state; the output must be reachable at that input.

        +1 needs ``input >= beta``, -1 needs ``input < alpha``.
        """
        output = finite_scalar(output, "output")
        input = finite_scalar(input, "input", MAX_MAGNITUDE)
        if output not in (1.0, -1.0):
            raise ValueError(f"output must be +1 or -1, got {output}")
        if output == 1.0 and input < self._beta:
            raise ValueError(f"input must be >= beta={self._beta} for output +1, got {input}")
        if output == -1.0 and input >= self._alpha:
            raise ValueError(f"input must be < alpha={self._alpha} for output -1, got {input}")
        return RelayState(output, input)

    def output(self, state: RelayState) -> float:
        self._check_state(state)
        return float(state.output)

    def _check_state(self, state: object) -> None:
        """Type and consistency of a state (O(1)): output ±1, reachable at its input."""
        check_state_type(state, RelayState, self)
        out, inp = state.output, state.input
        if out not in (1.0, -1.0):
            raise ValueError(f"state.output must be +1 or -1, got {out!r}")
        if isinstance(inp, bool) or not isinstance(inp, Real) or not math.isfinite(inp):
            raise ValueError(f"state.input must be a finite number, got {inp!r}")
        if (out == 1.0 and inp < self._beta) or (out == -1.0 and inp >= self._alpha):
            raise ValueError(
                f"state (output {out:+g} at input {inp!r}) is not reachable for this relay "
                f"(alpha={self._alpha}, beta={self._beta}): it belongs to another relay"
            )

    # -- driving ----------------------------------------------------------------------------
    def apply(self, inputs, state: RelayState | None = None) -> tuple[np.ndarray, RelayState]:
        """Outputs for the input sequence, vectorised.

        Algorithm: every input with ``u >= alpha`` sets the output to +1, every input with
        ``u < beta`` sets it to -1, every other input keeps the last set value (or the initial
        state's output). The last set value is found by a running maximum over the indices of
        the setting inputs (a forward fill), so the cost is O(n) numpy work.
        """
        u = as_input_sequence(inputs)
        if state is None:
            state = self.initial_state(u[0])
        else:
            self._check_state(state)
        marks = np.zeros(u.size, dtype=np.float64)
        marks[u < self._beta] = -1.0
        marks[u >= self._alpha] = 1.0  # alpha >= beta, so never both
        idx = np.where(marks != 0.0, np.arange(u.size), -1)
        np.maximum.accumulate(idx, out=idx)
        outputs = np.where(idx >= 0, marks[np.maximum(idx, 0)], float(state.output))
        return outputs, RelayState(float(outputs[-1]), float(u[-1]))

    def switching(self, state: RelayState) -> Switching:
        """From -1 the relay jumps by +2 when the input reaches α; from +1 by -2 below β."""
        self._check_state(state)
        if state.output > 0:
            return Switching(lower=self._beta, upper=np.inf, jump_down=-2.0, jump_up=0.0)
        return Switching(lower=-np.inf, upper=self._alpha, jump_down=0.0, jump_up=2.0)

    # -- relay contract (oscillators' relay engine) -------------------------------------------
    def relay_table(self) -> RelayTable:
        """The relay as a one-row :class:`~hysteresis.relay_table.RelayTable` of weight 1."""
        return RelayTable([self._alpha], [self._beta], [1.0])

    def relay_outputs(self, state: RelayState) -> np.ndarray:
        """``[state.output]``."""
        if not isinstance(state, RelayState):
            raise ValueError(f"state must be a RelayState, got {type(state).__name__}")
        return np.array([float(state.output)])

    def state_from_relay_outputs(self, outputs, input: float) -> RelayState:
        """The state with output ``outputs[0]`` at ``input`` (validated like :meth:`state`)."""
        y = real_array(outputs, "outputs")
        if y.shape != (1,):
            raise ValueError(f"outputs must have length 1 for a Relay, got shape {y.shape}")
        return self.state(float(y[0]), input)
