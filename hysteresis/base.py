"""The operator contract shared by every hysteresis operator.

A hysteresis operator is a rate-independent map from an input history ``u(t)`` to an output
``y(t)``. Every operator in this package is a small immutable object holding its parameters; the
memory lives in a separate immutable *state* object, so

    outputs, state = operator.apply(inputs, state)

never mutates anything and the memory never grows with the length of the input.

Two families exist (the piecewise-constant one in two kinds), and the forced-oscillator engines
(:func:`oscillators.engines.select_engine`) treat them differently. The contract is exactly what
those engines use; its required methods are abstract, so a class that misses one cannot be
instantiated (the ``TypeError`` names the method and what it must return).

* **Piecewise-constant** operators (``piecewise_constant = True``: ``Relay``, discrete
  ``PreisachModel``, ``SpinDimerEnsemble``): the output is constant between switching inputs.
  Required: :meth:`~PiecewiseConstantHysteron.relay_table` (the relays and their weights, which
  the event-driven engine integrates), :meth:`~PiecewiseConstantHysteron.relay_outputs` and
  :meth:`~PiecewiseConstantHysteron.state_from_relay_outputs` (the state to and from the
  relays' outputs). Everything else is derived from these three in the base class:
  ``initial_state``, ``output``, ``apply`` (the relays driven one by one, O(N) per input) and
  ``switching`` (next switching inputs and jumps, the Python reference engine's view); the
  library's operators override them with faster versions. Between switches the coupled
  oscillator is linear with a constant force ``C*M``; at a switch it applies the saltation
  matrix with entry ``C*ΔM/v*`` (paper eq. ``salt_matrix``).

  An operator whose units interact (the spins of a random-field Ising lattice, whose flips
  come in avalanches) is piecewise constant but no table of independent relays:
  :class:`SwitchingHysteron`, the base of ``PiecewiseConstantHysteron``, asks only for
  ``initial_state``, ``apply``, ``output``, :meth:`~SwitchingHysteron.switching` (next
  switching inputs and the output jumps there, an avalanche being one jump) and
  :attr:`~SwitchingHysteron.n_units` (the switch budget's scale). The contract attribute
  ``has_relay_table`` tells the two kinds apart; the oscillator's relay engine integrates an
  operator without a table exactly through ``switching``/``apply`` (its Python reference
  path, ``RelayEngine(method="generic")``). Optional, the compiled path (the generalisation
  of ``relay_table`` to interacting units): :meth:`~SwitchingHysteron.compiled_switching`
  returns a :class:`hysteresis.compiled_spins.CompiledSpins` — Ising spins with fields
  ``f_i``, a ferromagnetic coupling ``J`` on a lattice or graph, and two callables between
  the operator's state and packed spins — and the oscillator's switching engine
  (:mod:`oscillators.engines.switching`) couples it without a trial run: the next switching
  input in each direction from its compiled plan (sorted lists of the thresholds
  ``−(f_i + J·n)``, one per neighbour-sum value ``n``), each avalanche one jump ``C·ΔM`` at
  its trigger input with the saltation ``C·ΔM/v*``, ``n_events`` counting spin flips.
* **Continuous** operators (``PlayOperator``, ``GeneralizedPlay``, continuous ``PreisachModel``,
  ``PrandtlIshlinskii``): for a fixed direction of input motion the output follows a smooth
  monotone branch between breakpoints. Required: ``initial_state``, ``apply`` (the state
  transition: a branch flow describes a branch but builds no state) and
  :meth:`~ContinuousHysteron.branch_flow` (the branch as a function of the input, with its
  memory variables and breakpoint, :class:`hysteresis.flow.BranchFlow`), which the generic
  continuous engine integrates. Derived from ``branch_flow`` in the base class: ``output``
  (the branch's value at the state's input), ``branch`` (value, slope, breakpoint) and
  ``linearize`` (derivatives with respect to the input and the memory variables). Optional:
  :meth:`~ContinuousHysteron.compiled_play` and :meth:`~ContinuousHysteron.compiled_flow` (fast
  paths; an operator that offers one also offers the state constructor the compiled engine
  builds its states with, checked by :func:`oscillators.engines.select_engine`) and
  :attr:`~Hysteron.max_slope` (the largest branch slope, for the oscillator's instability
  warning) and :attr:`~Hysteron.min_slope` (the least one, which decides whether
  :class:`hysteresis.inverse.InverseOperator` can invert the operator).

States: every operator state is immutable and exposes the input it last saw as ``.input``
(:class:`HysteronState`); an operator is generic in its state type, ``Hysteron[StateT]``.

The seam: what an operator hands an engine is checked where it is handed over (once per call
of the operator's method, never inside compiled loops), and a wrong answer raises one sentence
naming the method, what it returned and what it must return (:mod:`hysteresis.seam`). A class that
misses a required method cannot be instantiated; the ``TypeError`` names the method, its
arguments and what it must return.

Conventions (see docs/architecture.md): a relay with thresholds ``alpha >= beta`` outputs +1
once the input has reached ``u >= alpha`` and -1 once it has fallen to ``u < beta``.
``initial_state(u0)`` is the state reached by rising monotonically from negative saturation to
``u0``.
"""

from __future__ import annotations

import inspect
import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, Generic, Protocol, TypeVar, runtime_checkable

import numpy as np

from hysteresis._validation import as_input_sequence
from hysteresis.compiled_spins import CompiledSpins
from hysteresis.flow import BranchFlow
from hysteresis.relay_table import RelayTable
from hysteresis.seam import checked_branch_flow, checked_relay_outputs, checked_relay_table

__all__ = [
    "Hysteron",
    "HysteronState",
    "PiecewiseConstantHysteron",
    "SwitchingHysteron",
    "ContinuousHysteron",
    "StateT",
    "Switching",
    "Branch",
    "Linearization",
]


@runtime_checkable
class HysteronState(Protocol):
    """What every operator state offers: the input it last saw.

    States are immutable objects of the operator's own type (a frozen dataclass, say) holding
    the memory; the engines read ``input`` (where the state's input must equal the oscillator's
    ``q``) and hand the state back to the operator, never looking inside otherwise.
    """

    @property
    def input(self) -> float:
        """The input the operator last saw (a finite real number)."""
        ...


#: The state type of an operator: ``class MyPlay(ContinuousHysteron[MyPlayState])``.
StateT = TypeVar("StateT", bound=HysteronState)


#: What each required method returns, for the error of an operator class that misses one.
_MUST_RETURN = {
    "initial_state": "the state reached by rising from negative saturation to u0",
    "apply": "the pair (outputs, final state)",
    "branch_flow": "a hysteresis.flow.BranchFlow, the branch followed while the input moves in "
    "direction",
    "relay_table": "a hysteresis.relay_table.RelayTable (thresholds and weights)",
    "relay_outputs": "an array of the relays' outputs +1/-1 in table order",
    "state_from_relay_outputs": "the state whose relays output outputs at that input",
    "output": "the output in that state (a float)",
    "switching": "a hysteresis.base.Switching (the next switching inputs below and above the "
    "state's input and the output jumps there)",
    "n_units": "the number of switching units (relays, spins), the scale of the engine's switch "
    "budget",
}


def _missing_methods_message(cls: type) -> str:
    """One sentence naming the required methods ``cls`` misses and what they must return."""
    parts = []
    for name in sorted(cls.__abstractmethods__):
        what = _MUST_RETURN.get(name, "what its docstring in hysteresis.base says")
        member = getattr(cls, name)
        if isinstance(member, property):
            parts.append(f"the property {name} returning {what}")
            continue
        params = list(inspect.signature(member).parameters)[1:]
        parts.append(f"{name}({', '.join(params)}) returning {what}")
    needs = "; and ".join(parts)
    return (
        f"Can't instantiate abstract class {cls.__name__}: it must implement {needs} (the "
        "operator contract, hysteresis.base)"
    )


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


class Hysteron(ABC, Generic[StateT]):
    """Abstract rate-independent hysteresis operator with states of type ``StateT``.

    Subclasses are immutable parameter holders. Their state objects are immutable too and
    expose ``.input`` (:class:`HysteronState`).
    """

    #: True for operators whose output is constant between switching inputs.
    piecewise_constant: bool = False
    #: True for piecewise-constant operators that hand over a table of independent relays
    #: (``relay_table()``, the compiled relay kernels); False for every other operator.
    has_relay_table: bool = False

    def __new__(cls, *args: Any, **kwargs: Any) -> Any:
        # Python's own error names the missing methods only; this one also says what they
        # return (the contract a newcomer implements)
        if getattr(cls, "__abstractmethods__", None):
            raise TypeError(_missing_methods_message(cls))
        return super().__new__(cls)

    @abstractmethod
    def initial_state(self, u0: float) -> StateT:
        """State after rising monotonically from negative saturation to ``u0``."""

    @abstractmethod
    def apply(self, inputs: Any, state: StateT | None = None) -> tuple[np.ndarray, StateT]:
        """Drive the operator with ``inputs`` (1-D, length >= 1) starting from ``state``.

        ``state=None`` means ``initial_state(inputs[0])``. Returns the outputs (same length as
        ``inputs``) and the final state. Nothing is mutated.
        """

    @abstractmethod
    def output(self, state: StateT) -> float:
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

    @property
    def min_slope(self) -> float | None:
        """Least slope ``dy/du`` that a branch keeps over an interval of inputs, over every
        state reachable from :meth:`initial_state`; ``None`` (the default) when the operator
        does not know it.

        Optional. :class:`hysteresis.inverse.InverseOperator` reads it. ``0``: some branch is
        flat over an interval of inputs (a play between its walls); negative: some branch
        decreases. Either way the output does not determine the input, and the inverse is
        refused. A positive value guarantees strictly increasing branches. ``None`` is also the
        answer of an operator whose slope vanishes only at isolated inputs or in the saturated
        tails, which makes no branch flat (a continuous Preisach model at every reversal, an
        erf shape of width 0): the inverse then checks each branch it follows.
        ``PlayOperator``: 0 (1 at width 0); ``PrandtlIshlinskii``: the least partial sum of
        its weights (0 without a width-0 play); piecewise-constant operators: 0.
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


class SwitchingHysteron(Hysteron[StateT]):
    """Operator whose output is constant between switching inputs, known by where it switches.

    The output jumps at switching inputs; the jumps need not be those of independent relays
    (a random-field Ising lattice flips its spins in avalanches whose size depends on the
    state). A new operator writes ``initial_state``, ``apply``, ``output``, :meth:`switching`
    and :attr:`n_units`. The oscillator's relay engine integrates it exactly: between switches
    the motion is linear with the force ``C·M``, at ``switching(state).upper`` (reached) or
    below ``switching(state).lower`` the operator is advanced by ``apply`` and the tangent flow
    gets the saltation ``C·ΔM/v*`` of the whole jump (its Python reference path: no relay
    table, no compiled kernel). :class:`PiecewiseConstantHysteron`, the relay-table kind,
    derives all of this from its relays.
    """

    piecewise_constant = True

    @abstractmethod
    def switching(self, state: StateT) -> Switching:
        """Where the output jumps next seen from ``state`` and by how much
        (:class:`Switching`): the output jumps by ``jump_up`` once the input reaches ``upper``
        and by ``jump_down`` once it falls strictly below ``lower``, with
        ``lower <= state.input < upper``; each jump is the whole change (every unit that
        switches there, an avalanche included)."""

    @property
    @abstractmethod
    def n_units(self) -> int:
        """Number of switching units (relays, spins): the oscillator's switch budget per
        ``advance`` call scales with it (at most one jump per unit and direction of a
        monotone input sweep)."""

    def compiled_switching(self) -> CompiledSpins | None:
        """The operator's units as interacting Ising spins for the compiled switching engine
        (:class:`hysteresis.compiled_spins.CompiledSpins`: fields, coupling, graph, the sorted
        order of the fields, and the state to and from packed spins), else ``None`` (the
        default: the relay engine's Python reference path through :meth:`switching` and
        ``apply``). A fast path only: the engine follows the same avalanches, at the same
        trigger inputs, to the same states."""
        return None


class PiecewiseConstantHysteron(SwitchingHysteron[StateT]):
    """Operator whose output is constant between switching inputs (relay-type).

    A new operator writes the three abstract methods (its relays, and its state to and from
    their outputs); everything else is derived from them here, once, generic and O(N) per
    call: a library operator overrides it with a faster version of the same answer.
    """

    has_relay_table = True

    @property
    def n_units(self) -> int:
        """The number of relays of :meth:`relay_table`."""
        return checked_relay_table(self).n_relays

    @property
    def min_slope(self) -> float:
        """0: the output is constant between switching inputs (and jumps at them)."""
        return 0.0

    # -- what the oscillator's relay engine needs (oscillators.engines.select_engine) ----------
    @abstractmethod
    def relay_table(self) -> RelayTable:
        """The operator as a table of relays (:class:`hysteresis.relay_table.RelayTable`):
        thresholds, weights, ``M = Σ weights·y``. The oscillator's event-driven engine runs on
        it."""

    @abstractmethod
    def relay_outputs(self, state: StateT) -> np.ndarray:
        """Outputs ``y_i = ±1`` of the relays of :meth:`relay_table` in ``state`` (table order)."""

    @abstractmethod
    def state_from_relay_outputs(self, outputs: np.ndarray, input: float) -> StateT:
        """The operator state whose relays output ``outputs`` at the current ``input``."""

    # -- derived from the three above ---------------------------------------------------------
    def initial_state(self, u0: float) -> StateT:
        """Rising from negative saturation to ``u0`` leaves exactly the relays with
        ``alpha <= u0`` up (:meth:`RelayTable.initial_outputs`)."""
        return self.state_from_relay_outputs(checked_relay_table(self).initial_outputs(u0), u0)

    def output(self, state: StateT) -> float:
        """``M = Σ weights·y`` of the relays in ``state`` (correctly rounded sum)."""
        table = checked_relay_table(self)
        return float(table.output(checked_relay_outputs(self, table, state)))

    def apply(self, inputs: Any, state: StateT | None = None) -> tuple[np.ndarray, StateT]:
        """Drive every relay of the table through ``inputs`` (the relay rule per relay: an
        input ``u >= alpha`` sets +1, ``u < beta`` sets -1, any other keeps the last value),
        O(N) per input; the final state through :meth:`state_from_relay_outputs`."""
        u = as_input_sequence(inputs)
        if state is None:
            state = self.initial_state(float(u[0]))
        table = checked_relay_table(self)
        outputs, y = _drive_relays(table, checked_relay_outputs(self, table, state), u)
        return outputs, self.state_from_relay_outputs(y, float(u[-1]))

    # -- what the Python reference engine needs (RelayEngine(method="generic")) ---------------
    def switching(self, state: StateT) -> Switching:
        """Next switching inputs below/above the state's current input and the jumps there,
        read from the relays: ``upper`` is the least ``alpha`` of the down relays, ``lower``
        the greatest ``beta`` of the up relays, each jump ``2·Σ w`` over the relays at that
        threshold (relays of zero weight never change the output and are left out)."""
        table = checked_relay_table(self)
        y = checked_relay_outputs(self, table, state)
        live = table.weights > 0.0
        down, up = live & (y < 0.0), live & (y > 0.0)
        upper, jump_up, lower, jump_down = math.inf, 0.0, -math.inf, 0.0
        if np.any(down):
            upper = float(np.min(table.alpha[down]))
            jump_up = 2.0 * math.fsum(table.weights[down & (table.alpha == upper)])
        if np.any(up):
            lower = float(np.max(table.beta[up]))
            jump_down = -2.0 * math.fsum(table.weights[up & (table.beta == lower)])
        return Switching(lower=lower, upper=upper, jump_down=jump_down, jump_up=jump_up)


#: inputs × relays driven at once by the derived ``apply`` (bounds its work arrays)
_DRIVE_BLOCK = 1 << 20


def _drive_relays(table: RelayTable, y: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Outputs ``M`` at every input and the final relay outputs, from outputs ``y`` before
    ``u[0]``: per relay, the last input that set it (``u >= alpha``: +1, ``u < beta``: -1) by a
    running maximum of the setting indices (a forward fill), in blocks of inputs."""
    alpha, beta, weights = table.alpha, table.beta, table.weights
    outputs = np.empty(u.size)
    rows = max(1, _DRIVE_BLOCK // table.n_relays)
    y = np.array(y, dtype=np.float64)
    for i0 in range(0, u.size, rows):
        block = u[i0 : i0 + rows, None]
        marks = np.where(block >= alpha, 1.0, np.where(block < beta, -1.0, 0.0))
        setter = np.where(marks != 0.0, np.arange(block.shape[0])[:, None], -1)
        np.maximum.accumulate(setter, axis=0, out=setter)
        ys = np.where(setter >= 0, np.take_along_axis(marks, np.maximum(setter, 0), 0), y)
        outputs[i0 : i0 + block.shape[0]] = ys @ weights
        y = ys[-1].copy()
    return outputs, y


class ContinuousHysteron(Hysteron[StateT]):
    """Operator with continuous, piecewise-smooth branches (play-type).

    A new operator writes ``initial_state``, ``apply`` and :meth:`branch_flow`; ``output``,
    :meth:`branch` and :meth:`linearize` are derived from the branch flow here.
    """

    piecewise_constant = False

    def output(self, state: StateT) -> float:
        """The output in ``state``: the rising branch's value at the state's input (the output
        is continuous, so either branch gives it)."""
        flow = checked_branch_flow(self, state, 1)
        return float(flow.output(flow.input))

    # -- derived from branch_flow (one implementation for every continuous operator) ---------
    def branch(self, state: StateT, direction: int) -> Branch:
        """Branch followed when the input moves in ``direction`` (+1 rising, -1 falling):
        the output in ``state``, the slope ``dy/du`` of :meth:`branch_flow` at the state's input
        (:meth:`BranchFlow.slope <hysteresis.flow.BranchFlow.slope>`) and its breakpoint."""
        flow = self.branch_flow(state, direction)
        return Branch(
            value=float(self.output(state)),
            slope=float(flow.slope(flow.input)),
            breakpoint=float(flow.breakpoint),
        )

    def linearize(self, state: StateT, direction: int) -> Linearization:
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
    def branch_flow(self, state: StateT, direction: int) -> BranchFlow:
        """The branch followed in ``direction`` (+1 rising, -1 falling) as a function of the
        input, with its memory variables, their linearization and the next breakpoint
        (:class:`hysteresis.flow.BranchFlow`). The generic continuous engine of the oscillator
        integrates any operator that provides it."""

    # -- the memory as coordinates (periodic orbits, continuation) --------------------------
    def with_memory(self, state: StateT, values: Any, input: float, direction: int) -> StateT:
        """The state at ``input`` whose branch in ``direction`` reports the memory ``values``
        (in the order of ``branch_flow(state, direction).labels``); ``state`` is the template
        that supplies what the values do not say (a composite's relay outputs, the parts'
        structure). A value beyond what a state can hold is put on the nearest state (a wagon
        beyond its wall is put on the wall). Optional: the periodic-orbit coordinates
        (:class:`analysis.dynamics.orbit_coordinates.StateCoordinates`) ask for it for
        operators whose memory they do not know otherwise; the default refuses in one
        sentence."""
        raise ValueError(
            f"{type(self).__name__} cannot set its memory from a vector of values "
            "(ContinuousHysteron.with_memory is not implemented for it)"
        )

    def memory_restart(self, state: StateT, direction: int, u: float) -> tuple:
        """``(values (n,), d_du (n,), d_dm (n, n))``: the memory that the branch of the state
        reached at input ``u`` on the branch of ``state`` in ``direction`` reports (the branch
        restarted there), and how its perturbation follows from the tangent rows of the branch
        of ``state``: ``δm_restarted = d_du·δu + d_dm @ δm`` (``δm`` the rows an integrator
        carries, :mod:`hysteresis.flow`: a slaved variable's row is ``δu`` already).

        It converts the oscillator's tangent rows, which are the perturbations of the memory
        of the branch the motion is on, into those of the memory a state reports. The default
        is exact for memory that is the state's own, frozen variables keeping their value and
        slaved ones moving with the input (:meth:`BranchFlow.memory_at`): ``d_du = 0``,
        ``d_dm = I``. A variable that is the value *at the branch start* of something that
        keeps changing along the branch (a Duhem operator's ``z0``: the state's ``z`` is
        ``Z(u; z0)``) overrides it."""
        flow = checked_branch_flow(self, state, direction)
        n = flow.n_memory
        values = np.asarray(flow.memory_at(float(u)), dtype=np.float64).reshape(n)
        return values, np.zeros(n), np.eye(n)

    def compiled_play(self) -> Any:
        """A description for the compiled play-limit kernel
        (:class:`hysteresis.play.CompiledPlay`) if this operator is a play with a shape the
        kernel knows (identity, erf, or a tabulated shape,
        :class:`hysteresis.shape_table.ShapeTable`), else ``None`` (the default): a fast path
        only.

        An operator whose ``compiled_play()`` is not ``None`` also offers
        ``state(position, input)``, the state with the wagon at ``position`` and the input at
        ``input``: the oscillator's play engine builds the operator states it hands back through
        it (it does not construct the play's state class itself). Required in code:
        :func:`oscillators.engines.select_engine` refuses the operator without it.
        """
        return None

    def compiled_flow(self) -> Any:
        """A description for the compiled continuous engine
        (:class:`hysteresis.flow.CompiledFlow`: Prandtl–Ishlinskii plays, or a Preisach
        model's compiled Everett function), else ``None`` (the default: the generic continuous
        engine integrates the operator through :meth:`branch_flow`). A fast path only: the
        compiled engine follows the same branches, events and memory labels. Such an operator
        also offers the state constructor the engine builds its states with,
        ``state(positions, input)`` (plays) or ``state_from_extrema(extrema)`` (Preisach),
        required by :func:`oscillators.engines.select_engine`."""
        return None
