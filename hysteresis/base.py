"""The operator contract shared by every hysteresis operator.

A hysteresis operator is a rate-independent map from an input history ``u(t)`` to an output
``y(t)``. Every operator in this package is a small immutable object holding its parameters; the
memory lives in a separate immutable *state* object, so

    outputs, state = operator.apply(inputs, state)

never mutates anything and the memory never grows with the length of the input.

Two families exist, and the forced-oscillator engines (:func:`oscillators.engines.select_engine`)
treat them differently. The contract is exactly what those engines use; its required methods
are abstract, so a class that misses one cannot be instantiated (Python's ``TypeError`` names
the method).

* **Piecewise-constant** operators (``piecewise_constant = True``: ``Relay``, discrete
  ``PreisachModel``, ``SpinDimerEnsemble``): the output is constant between switching inputs.
  Required: :meth:`~PiecewiseConstantHysteron.relay_table` (the relays and their weights, which
  the event-driven engine integrates), :meth:`~PiecewiseConstantHysteron.relay_outputs` and
  :meth:`~PiecewiseConstantHysteron.state_from_relay_outputs` (the state to and from the
  relays' outputs), and :meth:`~PiecewiseConstantHysteron.switching` (next switching inputs and
  jumps, the Python reference engine's view). Between switches the coupled oscillator is linear
  with a constant force ``C*M``; at a switch it applies the saltation matrix with entry
  ``C*ΔM/v*`` (paper eq. ``salt_matrix``).
* **Continuous** operators (``PlayOperator``, ``GeneralizedPlay``, continuous ``PreisachModel``,
  ``PrandtlIshlinskii``): for a fixed direction of input motion the output follows a smooth
  monotone branch between breakpoints. Required: :meth:`~ContinuousHysteron.branch_flow` (the
  branch as a function of the input, with its memory variables and breakpoint,
  :class:`hysteresis.flow.BranchFlow`), which the generic continuous engine integrates.
  Optional: :meth:`~ContinuousHysteron.compiled_play` (a fast path) and
  :attr:`~Hysteron.max_slope` (the largest branch slope, for the oscillator's instability
  warning). ``branch`` (value, slope,
  breakpoint) and ``linearize`` (derivatives with respect to the input and the memory
  variables) are not part of what an operator must provide: they are derived from
  ``branch_flow`` once, here.

Conventions (see docs/architecture.md): a relay with thresholds ``alpha >= beta`` outputs +1
once the input has reached ``u >= alpha`` and -1 once it has fallen to ``u < beta``.
``initial_state(u0)`` is the state reached by rising monotonically from negative saturation to
``u0``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any

import numpy as np

from hysteresis.flow import BranchFlow

__all__ = [
    "Hysteron",
    "PiecewiseConstantHysteron",
    "ContinuousHysteron",
    "Switching",
    "Branch",
    "Linearization",
]


@dataclass(frozen=True)
class Switching:
    """Where a piecewise-constant operator switches next, seen from its current state.

    Attributes
    ----------
    lower:
        The output jumps as soon as the input falls strictly below ``lower`` (``-inf`` if it
        never does).
    upper:
        The output jumps as soon as the input reaches ``upper`` (``+inf`` if it never does).
    jump_down:
        Output change when the input crosses ``lower`` (<= 0 for a Preisach-type operator); it
        includes every unit whose threshold equals ``lower`` exactly.
    jump_up:
        Output change when the input reaches ``upper`` (>= 0).
    """

    lower: float
    upper: float
    jump_down: float
    jump_up: float


@dataclass(frozen=True)
class Branch:
    """The smooth branch a continuous operator follows for a given direction of input motion.

    Attributes
    ----------
    value:
        Output at the current input.
    slope:
        ``dy/du`` on the branch in the requested direction (0 inside a play).
    breakpoint:
        The input at which the branch changes in that direction (a play wall, a wiped-out
        extremum), ``±inf`` if none.
    """

    value: float
    slope: float
    breakpoint: float


@dataclass(frozen=True)
class Linearization:
    """First-order behaviour of a continuous operator on its current branch.

    With memory variables ``m`` (for the play: ``m = (w,)``) and output ``y = g(u, m)``:

    ``δy = d_output_d_input * δu + d_output_d_memory @ δm``, and while the input moves on this
    branch ``δm_i`` is frozen (``slaved[i] == False``) or follows the input, ``δm_i = δu``
    (``slaved[i] == True``). When the input leaves a frozen branch onto a wall (paper's
    ``V_out``), the memory perturbation is reset, ``δm_i := δu`` for every ``i`` in
    ``reset_on_leave``; entering the play is smooth (``V_in = I``).
    """

    d_output_d_input: float
    d_output_d_memory: np.ndarray
    slaved: np.ndarray
    reset_on_leave: np.ndarray


class Hysteron(ABC):
    """Abstract rate-independent hysteresis operator.

    Subclasses are immutable parameter holders. Their state objects are immutable too.
    """

    #: True for operators whose output is constant between switching inputs.
    piecewise_constant: bool = False

    @abstractmethod
    def initial_state(self, u0: float) -> Any:
        """State after rising monotonically from negative saturation to ``u0``."""

    @abstractmethod
    def apply(self, inputs: Any, state: Any = None) -> tuple[np.ndarray, Any]:
        """Drive the operator with ``inputs`` (1-D, length >= 1) starting from ``state``.

        ``state=None`` means ``initial_state(inputs[0])``. Returns the outputs (same length as
        ``inputs``) and the final state. Nothing is mutated.
        """

    @abstractmethod
    def output(self, state: Any) -> float:
        """Output of the operator in ``state``."""

    @property
    def output_range(self) -> tuple[float, float]:
        """Saturation values (negative, positive) of the output."""
        return (-1.0, 1.0)

    @property
    def max_slope(self) -> float | None:
        """Largest slope ``dy/du`` on any branch of any state of the operator, or ``None``
        (the default) when the operator does not know it.

        Optional. The forced oscillator reads it for operators with an unbounded
        :attr:`output_range`: the stiffness on a branch of slope ``s`` is ``1 − C·s``, so it
        warns of a positive-feedback instability only when ``C·max_slope >= 1`` (with ``None``
        it assumes slope 1, the plain play's). ``PlayOperator``: 1; ``PrandtlIshlinskii``: the
        sum of its positive weights.
        """
        return None

    # -- pickling (worker processes, saved runs) -------------------------------------------
    #: attributes left out of a pickle: caches rebuilt on demand
    _transient_attributes: tuple[str, ...] = ()

    def __reduce__(self) -> tuple:
        """Pickle the attributes as they are (the parameters and the state-ownership
        fingerprint are copied, not recomputed: the copy gives the same outputs bit for bit
        and accepts the original's states), noting which arrays are read-only (pickle
        protocols < 5 drop that flag; :meth:`__setstate__` sets it again)."""
        attrs = {k: v for k, v in vars(self).items() if k not in self._transient_attributes}
        readonly = tuple(
            k for k, v in attrs.items() if isinstance(v, np.ndarray) and not v.flags.writeable
        )
        return (_new_instance, (type(self),), (attrs, readonly))

    def __setstate__(self, state: tuple[dict[str, Any], tuple[str, ...]]) -> None:
        attrs, readonly = state
        for name in readonly:
            attrs[name].setflags(write=False)
        self.__dict__.update(attrs)


def _new_instance(cls: type) -> Any:
    """An uninitialised instance of ``cls`` (unpickling: :meth:`Hysteron.__setstate__` fills
    it)."""
    return cls.__new__(cls)


class PiecewiseConstantHysteron(Hysteron):
    """Operator whose output is constant between switching inputs (relay-type)."""

    piecewise_constant = True

    # -- what the oscillator's relay engine needs (oscillators.engines.select_engine) ----------
    @abstractmethod
    def relay_table(self) -> Any:
        """The operator as a table of relays (:class:`hysteresis.relay_table.RelayTable`):
        thresholds, weights, ``M = Σ weights·y``. The oscillator's event-driven engine runs on
        it."""

    @abstractmethod
    def relay_outputs(self, state: Any) -> np.ndarray:
        """Outputs ``y_i = ±1`` of the relays of :meth:`relay_table` in ``state`` (table order)."""

    @abstractmethod
    def state_from_relay_outputs(self, outputs: np.ndarray, input: float) -> Any:
        """The operator state whose relays output ``outputs`` at the current ``input``."""

    # -- what the Python reference engine needs (RelayEngine(method="generic")) ---------------
    @abstractmethod
    def switching(self, state: Any) -> Switching:
        """Next switching inputs below/above the state's current input and the jumps there."""


class ContinuousHysteron(Hysteron):
    """Operator with continuous, piecewise-smooth branches (play-type)."""

    piecewise_constant = False

    # -- derived from branch_flow (one implementation for every continuous operator) ---------
    def branch(self, state: Any, direction: int) -> Branch:
        """Branch followed when the input moves in ``direction`` (+1 rising, -1 falling):
        the output in ``state``, the slope ``dy/du`` of :meth:`branch_flow` at the state's input
        (:meth:`BranchFlow.slope <hysteresis.flow.BranchFlow.slope>`) and its breakpoint."""
        flow = self.branch_flow(state, direction)
        return Branch(
            value=float(self.output(state)),
            slope=float(flow.slope(flow.input)),
            breakpoint=float(flow.breakpoint),
        )

    def linearize(self, state: Any, direction: int) -> Linearization:
        """Derivatives on the branch followed in ``direction`` (+1 rising, -1 falling), read
        from :meth:`branch_flow`: its partials at the state's input, its memory variables
        (frozen or slaved) and the ones whose perturbation is reset at the breakpoint."""
        flow = self.branch_flow(state, direction)
        d_input, d_memory = flow.partials(flow.input)
        position = {label: i for i, label in enumerate(flow.labels)}
        return Linearization(
            d_output_d_input=float(d_input),
            d_output_d_memory=np.array(d_memory, dtype=np.float64).reshape(flow.n_memory),
            slaved=np.array(flow.slaved, dtype=bool),
            reset_on_leave=np.array(
                [position[label] for label in flow.breakpoint_resets], dtype=np.int64
            ),
        )

    # -- what the oscillator's continuous engines need (oscillators.engines.select_engine) -----
    @abstractmethod
    def branch_flow(self, state: Any, direction: int) -> BranchFlow:
        """The branch followed in ``direction`` (+1 rising, -1 falling) as a function of the
        input, with its memory variables, their linearization and the next breakpoint
        (:class:`hysteresis.flow.BranchFlow`). The generic continuous engine of the oscillator
        integrates any operator that provides it."""

    def compiled_play(self) -> Any:
        """A description for the compiled play-limit kernel
        (:class:`hysteresis.play.CompiledPlay`) if this operator is a play with a shape the
        kernel knows (identity, erf, or a tabulated shape,
        :class:`hysteresis.shape_table.ShapeTable`), else ``None`` (the default): a fast path
        only.

        An operator whose ``compiled_play()`` is not ``None`` also offers
        ``state(position, input)``, the state with the wagon at ``position`` and the input at
        ``input``: the oscillator's play engine builds the operator states it hands back through
        it (it does not construct the play's state class itself).
        """
        return None

    def compiled_flow(self) -> Any:
        """A description for the compiled continuous engine
        (:class:`hysteresis.flow.CompiledFlow`: Prandtl–Ishlinskii plays, or a Preisach
        model's compiled Everett function), else ``None`` (the default: the generic continuous
        engine integrates the operator through :meth:`branch_flow`). A fast path only: the
        compiled engine follows the same branches, events and memory labels."""
        return None
