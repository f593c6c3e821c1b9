"""Operator algebra: weighted sums of operators, ``a * op``, ``op1 + op2``, ``-op``, ``op1 - op2``.

A sum ``y = Σ_k a_k · H_k[u]`` of rate-independent operators driven by one input is again
rate independent, and it is an operator of the contract (:mod:`hysteresis.base`) whatever its
parts are, so it couples to the forced oscillator like any operator:

* every part piecewise constant and every weight ``>= 0`` (relays, discrete Preisach models,
  spin dimers): a :class:`RelaySum`, a piecewise-constant operator whose relay table is the
  parts' tables concatenated with their weights scaled; the oscillator's compiled relay engine
  integrates it as it integrates one Preisach model; with a part that has no relay table
  (``has_relay_table`` false: a random-field Ising lattice) a :class:`SwitchingSum`, known by
  its next switching inputs (the parts' nearest, jumps added), which the relay engine's Python
  reference path integrates;
* anything else (a continuous part, or a relay-type part with a negative weight, which no relay
  table with weights ``>= 0`` holds): a :class:`BranchSum`, whose branch flow
  (:class:`~hysteresis.flow.BranchFlow`) is assembled from the parts': the output and its
  partials are the weighted sums, the memory variables are the continuous parts' (labels
  ``"k:label"``, ``k`` the part's index), the breakpoint is the nearest of the parts' — a
  continuous part's wall or wipe-out, or a relay-type part's next switch, where the output
  jumps by the part's weighted jump (``breakpoint_jump``). The generic continuous engine of
  the oscillator integrates it, with the saltation ``δv += C·Δy/v*·δq`` at every jump: a play
  plus relays is a hybrid system with exactly located events and a tangent flow.

The state of a sum is a :class:`SumState`, the tuple of its parts' states (in the order of
:attr:`WeightedSum.parts`). ``apply`` drives every part with the same inputs and returns
``Σ_k a_k · y_k`` accumulated in the order of the parts (``a_0·y_0 + a_1·y_1 + ...``), so a
sum's outputs are the weighted sum of its parts' outputs exactly, and continuing from a returned
state equals one long call because it does for every part.

Nested sums flatten: ``(a*H1 + b*H2) + c*(d*H3)`` has the parts ``H1, H2, H3`` with weights
``a, b, c·d``. The algebra is attached to :class:`~hysteresis.base.Hysteron` here (at the end of
this module) rather than written in ``base.py``, because the sum classes derive from the
contract's classes: a method in ``base.py`` building them would make the two modules import each
other.
"""

from __future__ import annotations

import math
from numbers import Real
from typing import Any

import numpy as np

from hysteresis._validation import as_input_sequence, direction_sign
from hysteresis.base import (
    ContinuousHysteron,
    Hysteron,
    PiecewiseConstantHysteron,
    Switching,
    SwitchingHysteron,
)
from hysteresis.flow import BranchFlow, CompiledFlow
from hysteresis.inverse import InverseOperator
from hysteresis.relay_table import RelayTable
from hysteresis.seam import (
    check_state,
    checked_branch_flow,
    checked_relay_outputs,
    checked_relay_table,
)
from hysteresis.sum_flows import compiled_sum_flow, composed_fields, play_parts
from hysteresis.sum_state import SumState

__all__ = ["SumState", "WeightedSum", "RelaySum", "SwitchingSum", "BranchSum", "weighted_sum"]


def _check_weight(weight: Any, name: str = "weight") -> float:
    """A real, finite weight (booleans, complex numbers, strings refused)."""
    if isinstance(weight, bool) or not isinstance(weight, Real):
        raise TypeError(f"{name} must be a real number, got {type(weight).__name__} {weight!r}")
    w = float(weight)
    if not math.isfinite(w):
        raise ValueError(f"{name} must be finite, got {w}")
    return w


def weighted_sum(parts: Any, weights: Any) -> WeightedSum:
    """The operator ``Σ_k weights[k] · parts[k]`` (see the module docstring).

    Parts that are sums themselves are flattened (their weights multiplied). The result is a
    :class:`RelaySum` when every part is piecewise constant with a weight ``>= 0`` (a
    :class:`SwitchingSum` if a part has no relay table), else a :class:`BranchSum`.
    """
    parts = list(parts)
    weights = list(weights)
    if len(parts) != len(weights):
        raise ValueError(f"weights must have one entry per part ({len(parts)}), got {len(weights)}")
    if not parts:
        raise ValueError("a sum needs at least one part")
    flat_parts: list[Hysteron] = []
    flat_weights: list[float] = []
    for i, (part, weight) in enumerate(zip(parts, weights, strict=True)):
        w = _check_weight(weight, f"weights[{i}]")
        if not isinstance(part, Hysteron):
            raise TypeError(
                f"parts[{i}] must be a hysteresis operator (a hysteresis.base.Hysteron), got "
                f"{type(part).__name__}"
            )
        if isinstance(part, WeightedSum):
            flat_parts.extend(part.parts)
            flat_weights.extend(w * float(a) for a in part.weights)
        else:
            flat_parts.append(part)
            flat_weights.append(w)
    relay_type = all(p.piecewise_constant for p in flat_parts) and min(flat_weights) >= 0.0
    tables = all(p.has_relay_table for p in flat_parts)
    cls = (RelaySum if tables else SwitchingSum) if relay_type else BranchSum
    return cls(flat_parts, flat_weights)


class WeightedSum(Hysteron[SumState]):
    """``y = Σ_k weights[k] · parts[k][u]``: what every sum shares (parts, weights, ``apply``,
    the state's checks, ranges). Build sums with the operators (``0.6 * play + 0.4 * relays``)
    or :func:`weighted_sum`."""

    def __new__(cls, *args: Any, **kwargs: Any) -> Any:
        if cls is WeightedSum:  # the family is decided by the parts (weighted_sum)
            raise TypeError(
                "WeightedSum is the common base of RelaySum and BranchSum: build a sum with "
                "the operators (0.6 * play + 0.4 * relays) or weighted_sum(parts, weights)"
            )
        return super().__new__(cls)

    def __init__(self, parts: list[Hysteron], weights: list[float]) -> None:
        self._parts = tuple(parts)
        self._weights = np.array(weights, dtype=np.float64)
        self._weights.setflags(write=False)

    @property
    def parts(self) -> tuple[Hysteron, ...]:
        """The operators summed (flattened: no part is a sum)."""
        return self._parts

    @property
    def weights(self) -> np.ndarray:
        """The weight of each part (read-only)."""
        return self._weights

    def __repr__(self) -> str:
        terms = " + ".join(
            f"{float(w)!r} * {p!r}" for w, p in zip(self._weights, self._parts, strict=True)
        )
        return f"{type(self).__name__}({terms})"

    # -- state -----------------------------------------------------------------------------------
    def _check_state(self, state: Any) -> SumState:
        if not isinstance(state, SumState):
            raise TypeError(
                f"state must be a SumState of this sum (from initial_state, apply or state()), "
                f"got {type(state).__name__}"
            )
        if len(state) != len(self._parts):
            raise ValueError(
                f"state must hold one state per part ({len(self._parts)}), got {len(state)}"
            )
        u = check_state(state[0], "given as part 0 of the sum's state")
        for k in range(1, len(state)):
            if check_state(state[k], f"given as part {k} of the sum's state") != u:
                raise ValueError(
                    f"the parts of a sum's state must have seen one input: part 0 saw {u}, "
                    f"part {k} saw {state[k].input}"
                )
        return state

    def state(self, *part_states: Any) -> SumState:
        """The sum's state from one state per part (in the order of :attr:`parts`), all at one
        input; each part checks its own state when it is used."""
        return self._check_state(SumState(part_states))

    def initial_state(self, u0: float) -> SumState:
        """Every part rising from negative saturation to ``u0``."""
        return SumState(p.initial_state(u0) for p in self._parts)

    def output(self, state: SumState) -> float:
        """``Σ_k weights[k] · parts[k].output(state[k])`` (in the order of the parts)."""
        state = self._check_state(state)
        total = 0.0
        for w, p, s in zip(self._weights, self._parts, state, strict=True):
            total = total + float(w) * float(p.output(s))
        return total

    def apply(self, inputs: Any, state: SumState | None = None) -> tuple[np.ndarray, SumState]:
        """Drive every part with ``inputs``; the outputs are ``Σ_k weights[k]·y_k``, summed in
        the order of the parts."""
        u = as_input_sequence(inputs)
        state = self.initial_state(float(u[0])) if state is None else self._check_state(state)
        total = np.zeros(u.size)
        finals = []
        for w, p, s in zip(self._weights, self._parts, state, strict=True):
            y, s_next = p.apply(u, s)
            total = total + float(w) * np.asarray(y, dtype=np.float64)
            finals.append(s_next)
        return total, SumState(finals)

    # -- what follows from the parts -------------------------------------------------------------
    @property
    def output_range(self) -> tuple[float, float]:
        """``Σ_k`` of each part's range scaled by its weight (a negative weight swaps the ends)."""
        low = high = 0.0
        for w, p in zip(self._weights, self._parts, strict=True):
            a, b = (float(w) * x for x in p.output_range)
            low, high = low + min(a, b), high + max(a, b)
        return (low, high)

    @property
    def max_slope(self) -> float | None:
        """A bound of the steepest branch: ``Σ_k`` of ``w_k·max_slope_k`` for ``w_k >= 0`` and
        ``w_k·min_slope_k`` for ``w_k < 0`` (``|w_k|·max_slope_k`` where the least slope is not
        known); the parts' steepest branches need not meet. Relay-type parts are flat between
        their jumps. ``None`` if a continuous part does not know its steepest slope."""
        total = 0.0
        for w, p in zip(self._weights, self._parts, strict=True):
            w = float(w)
            if p.piecewise_constant or w == 0.0:
                continue
            top, low = p.max_slope, p.min_slope
            if top is None:
                return None
            total += w * float(top) if w > 0.0 else (w * low if low is not None else -w * top)
        return total

    @property
    def min_slope(self) -> float | None:
        """The least branch slope, ``Σ_k`` of ``w_k·min_slope_k`` (``w_k >= 0``) and
        ``w_k·max_slope_k`` (``w_k < 0``), or ``None`` if a part does not know the bound it
        needs. Relay-type parts add 0 between their jumps (a sum with relays still has no
        inverse: its output jumps)."""
        total = 0.0
        for w, p in zip(self._weights, self._parts, strict=True):
            w = float(w)
            if w == 0.0:
                continue
            bound = p.min_slope if w > 0.0 else p.max_slope
            if p.piecewise_constant:
                bound = 0.0
            if bound is None:
                return None
            total += w * float(bound)
        return total


class SwitchingSum(WeightedSum, SwitchingHysteron):
    """A sum of piecewise-constant operators with weights ``>= 0``, known by its next switching
    inputs (a part without a relay table, such as a random-field Ising lattice, keeps the sum
    off the relay kernels: the relay engine's Python reference path integrates it)."""

    @property
    def n_units(self) -> int:
        """The parts' units together."""
        return sum(int(p.n_units) for p in self._parts)

    def switching(self, state: SumState) -> Switching:
        """The nearest switch of any part; parts switching at the same input add their jumps."""
        state = self._check_state(state)
        upper, lower, jump_up, jump_down = math.inf, -math.inf, 0.0, 0.0
        for w, p, s in zip(self._weights, self._parts, state, strict=True):
            if w == 0.0:
                continue
            sw = p.switching(s)
            if sw.upper < upper:
                upper, jump_up = sw.upper, float(w) * sw.jump_up
            elif sw.upper == upper and math.isfinite(upper):
                jump_up += float(w) * sw.jump_up
            if sw.lower > lower:
                lower, jump_down = sw.lower, float(w) * sw.jump_down
            elif sw.lower == lower and math.isfinite(lower):
                jump_down += float(w) * sw.jump_down
        return Switching(lower=lower, upper=upper, jump_down=jump_down, jump_up=jump_up)


class RelaySum(SwitchingSum, PiecewiseConstantHysteron):
    """A sum of piecewise-constant operators with weights ``>= 0``: its relay table is the
    parts' tables concatenated (weights scaled), in the order of the parts."""

    def __init__(self, parts: list[Hysteron], weights: list[float]) -> None:
        super().__init__(parts, weights)
        self._table: RelayTable | None = None

    _transient_attributes = ("_table",)

    def __setstate__(self, state: Any) -> None:
        super().__setstate__(state)
        self._table = None

    def _sizes(self) -> list[int]:
        return [checked_relay_table(p).n_relays for p in self._parts]

    def relay_table(self) -> RelayTable:
        """The parts' relays, table after table, weights multiplied by the part's weight."""
        if self._table is None:
            tables = [checked_relay_table(p) for p in self._parts]
            self._table = RelayTable(
                np.concatenate([t.alpha for t in tables]),
                np.concatenate([t.beta for t in tables]),
                np.concatenate(
                    [float(w) * t.weights for w, t in zip(self._weights, tables, strict=True)]
                ),
            )
        return self._table

    def relay_outputs(self, state: SumState) -> np.ndarray:
        """The parts' relay outputs, concatenated in table order."""
        state = self._check_state(state)
        return np.concatenate(
            [
                checked_relay_outputs(p, checked_relay_table(p), s)
                for p, s in zip(self._parts, state, strict=True)
            ]
        )

    def state_from_relay_outputs(self, outputs: Any, input: float) -> SumState:
        """Split ``outputs`` by part (table order) and build each part's state."""
        y = np.asarray(outputs, dtype=np.float64)
        sizes = self._sizes()
        if y.shape != (sum(sizes),):
            raise ValueError(f"outputs must have one entry per relay ({sum(sizes)}), got {y.shape}")
        bounds = np.cumsum([0, *sizes])
        return SumState(
            p.state_from_relay_outputs(y[bounds[k] : bounds[k + 1]], input)
            for k, p in enumerate(self._parts)
        )


class BranchSum(WeightedSum, ContinuousHysteron):
    """A sum with a continuous part (or a relay-type part of negative weight): integrated
    through its assembled branch flow (see the module docstring), relays as jumps."""

    def branch_flow(self, state: SumState, direction: int) -> BranchFlow:
        """The parts' branches in ``direction`` assembled: output and partials weighted and
        summed, memory labels ``"k:label"``, the nearest breakpoint (a continuous part's, or a
        relay-type part's next switch with its weighted jump; a falling switch at the largest
        float below the threshold, where the relay convention ``u < β`` holds)."""
        direction = direction_sign(direction)
        state = self._check_state(state)
        u0 = float(state.input)
        # (weight, flow, index in the sum) of the continuous parts: labels name a part by its
        # index in the sum
        flows: list[tuple[float, BranchFlow, int]] = []
        constant = 0.0
        # (breakpoint, jump, index of the continuous flow or -1 for a relay-type part)
        ends: list[tuple[float, float, int]] = []
        for i, (w, p, s) in enumerate(zip(self._weights, self._parts, state, strict=True)):
            w = float(w)
            if p.piecewise_constant:
                constant += w * float(p.output(s))
                if w == 0.0:
                    continue
                sw = p.switching(s)
                if direction > 0 and math.isfinite(sw.upper):
                    ends.append((sw.upper, w * sw.jump_up, -1))
                elif direction < 0 and math.isfinite(sw.lower):
                    ends.append((math.nextafter(sw.lower, -math.inf), w * sw.jump_down, -1))
            else:
                flow = p.branch_flow(s, direction)
                if math.isfinite(flow.breakpoint):  # (a cascade's output may jump there too)
                    ends.append((float(flow.breakpoint), w * flow.breakpoint_jump, len(flows)))
                flows.append((w, flow, i))
        breakpoint = direction * math.inf
        jump = 0.0
        resets: list[str] = []
        removes: list[str] = []
        if ends:
            breakpoint = min(e[0] for e in ends) if direction > 0 else max(e[0] for e in ends)
        labels: list[str] = []
        sizes: list[int] = []
        for _, flow, index in flows:
            labels.extend(f"{index}:{lab}" for lab in flow.labels)
            sizes.append(flow.n_memory)
        gradient_of = -1  # the part whose breakpoint moves with its memory (a cascade's)
        for bp, dy, k in ends:
            if bp != breakpoint:
                continue
            jump += dy
            if k >= 0:
                _, flow, index = flows[k]
                if flow.breakpoint_gradient is not None and gradient_of < 0:
                    gradient_of = k
                resets.extend(f"{index}:{lab}" for lab in flow.breakpoint_resets)
                removes.extend(f"{index}:{lab}" for lab in flow.breakpoint_removes)
        weights = np.array([w for w, _, _ in flows])
        parts = [f for _, f, _ in flows]
        bounds = np.cumsum([0, *sizes])

        def output(u):
            total = constant
            for a, f in zip(weights, parts, strict=True):
                total = total + a * f.output(u)
            return total

        def partials(u):
            u = np.asarray(u, dtype=np.float64)
            d_u = np.zeros(u.shape)
            d_m = np.zeros(u.shape + (int(bounds[-1]),))
            for k, (a, f) in enumerate(zip(weights, parts, strict=True)):
                du_k, dm_k = f.partials(u)
                d_u = d_u + a * np.asarray(du_k, dtype=np.float64)
                d_m[..., bounds[k] : bounds[k + 1]] = a * np.asarray(dm_k, dtype=np.float64)
            return d_u[()], d_m

        extra = composed_fields(parts, [i for _, _, i in flows], bounds, gradient_of)
        return BranchFlow(
            direction=direction,
            input=u0,
            labels=tuple(labels),
            memory=np.concatenate([f.memory for f in parts]) if parts else np.zeros(0),
            slaved=np.concatenate([f.slaved for f in parts]) if parts else np.zeros(0, bool),
            output=output,
            partials=partials,
            breakpoint=breakpoint,
            breakpoint_resets=tuple(resets),
            breakpoint_removes=tuple(removes),
            breakpoint_jump=jump,
            reversal_pushes=any(f.reversal_pushes for f in parts),
            pushed=np.concatenate([f.pushed for f in parts]) if parts else None,
            constant_partials=all(f.constant_partials for f in parts),
            **extra,
        )

    # -- the memory as coordinates (hysteresis.base.ContinuousHysteron.with_memory) --------------
    def _memory_parts(self, state: SumState, direction: int) -> list[int]:
        """The number of memory variables of each part's branch (0 for relay-type parts)."""
        return [
            0 if p.piecewise_constant else checked_branch_flow(p, s, direction).n_memory
            for p, s in zip(self._parts, state, strict=True)
        ]

    def with_memory(self, state: SumState, values: Any, input: float, direction: int) -> SumState:
        """Each continuous part's ``with_memory`` with its slice of ``values`` (the labels
        ``"k:label"`` in the order of the parts); relay-type parts keep the outputs ``state``
        gives them (they switch nothing while the input stays between their thresholds)."""
        state = self._check_state(state)
        d = direction_sign(direction)
        values = np.asarray(values, dtype=np.float64).reshape(-1)
        sizes = self._memory_parts(state, d)
        if sum(sizes) != values.size:
            raise ValueError(f"values must hold {sum(sizes)} memory values, got {values.size}")
        parts, pos = [], 0
        for p, s, n in zip(self._parts, state, sizes, strict=True):
            if p.piecewise_constant:
                if not p.has_relay_table:
                    raise ValueError(
                        f"{type(p).__name__} cannot set its memory from a vector (interacting "
                        "units, no relay table)"
                    )
                parts.append(p.state_from_relay_outputs(p.relay_outputs(s), input))
            else:
                parts.append(p.with_memory(s, values[pos : pos + n], input, d))
            pos += n
        return SumState(parts)

    def memory_restart(self, state: SumState, direction: int, u: float) -> tuple:
        """The parts' ``memory_restart`` side by side (block-diagonal ``d_dm``)."""
        state = self._check_state(state)
        d = direction_sign(direction)
        rows = [
            p.memory_restart(s, d, u)
            for p, s in zip(self._parts, state, strict=True)
            if not p.piecewise_constant
        ]
        sizes = [np.asarray(r[0]).size for r in rows]
        n = sum(sizes)
        values, d_du, d_dm = np.zeros(n), np.zeros(n), np.zeros((n, n))
        pos = 0
        for (v, a, A), k in zip(rows, sizes, strict=True):
            values[pos : pos + k] = v
            d_du[pos : pos + k] = a
            d_dm[pos : pos + k, pos : pos + k] = np.asarray(A, dtype=np.float64).reshape(k, k)
            pos += k
        return values, d_du, d_dm

    # -- the compiled fast path: a sum of plays and relays (hysteresis/sum_flows.py) --------------
    def compiled_flow(self) -> CompiledFlow | None:
        """A sum of plays (identity or erf shape), Prandtl–Ishlinskii operators and relay-type
        operators is one set of plays ``y = Σ a_i f_i(w_i)`` plus relays ``Σ c_j y_j`` for the
        oscillator's compiled continuous engine (:func:`hysteresis.sum_flows.compiled_sum_flow`);
        ``None`` for any other sum."""
        return compiled_sum_flow(self)

    @property
    def uncompiled_reason(self) -> str | None:
        """Why the oscillator integrates this sum with the generic (Python) engine, or ``None``
        when it has a compiled description (a sum of plays, erf plays and Prandtl–Ishlinskii
        operators)."""
        if play_parts(self) is not None:
            return None
        names = ", ".join(type(p).__name__ for p in self._parts)
        return (
            f"the sum of {names} has no compiled description (the compiled engines take one "
            "Preisach model, one set of relays, or plays, erf plays and Prandtl–Ishlinskii "
            "operators summed)"
        )


# -- the algebra on every operator ---------------------------------------------------------------
def _is_number(x: Any) -> bool:
    return isinstance(x, (Real, complex, np.number)) and not isinstance(x, bool)


def _scaled(op: Hysteron, a: Any) -> Any:
    if isinstance(a, Hysteron):
        raise TypeError(
            "the product of two operators is not an operator of the algebra: use "
            "hysteresis.Cascade(inner, outer) for outer driven by inner's output"
        )
    if not _is_number(a):
        return NotImplemented
    return weighted_sum([op], [_check_weight(a)])


def _add(op: Hysteron, other: Any) -> Any:
    if isinstance(other, Hysteron):
        return weighted_sum([op, other], [1.0, 1.0])
    if _is_number(other):
        if other == 0 and not isinstance(other, complex):
            return op  # sum([op1, op2]) starts from 0
        raise TypeError(
            "an operator plus a number is not an operator of the algebra: a constant offset "
            "is hysteresis.StaticMap composed with the operator"
        )
    return NotImplemented


def _neg(op: Hysteron) -> WeightedSum:
    return weighted_sum([op], [-1.0])


def _sub(op: Hysteron, other: Any) -> Any:
    if isinstance(other, Hysteron):
        return weighted_sum([op, other], [1.0, -1.0])
    return _add(op, other)


def _rsub(op: Hysteron, other: Any) -> Any:
    if _is_number(other) and other == 0:
        return _neg(op)
    return _add(op, other)


def _inverse(op: Hysteron) -> InverseOperator:
    """``op.inverse()``: the numeric inverse operator (:class:`~hysteresis.inverse.
    InverseOperator`, branch inversion to a few ulps); an operator with a closed-form inverse
    (``PrandtlIshlinskii``) overrides it. An operator with jumps or flat branches raises a
    one-line ``ValueError`` saying why it has none."""
    return InverseOperator(op)


Hysteron.inverse = _inverse  # type: ignore[attr-defined]
Hysteron.__mul__ = _scaled  # type: ignore[method-assign]
Hysteron.__rmul__ = _scaled  # type: ignore[method-assign]
Hysteron.__add__ = _add  # type: ignore[method-assign]
Hysteron.__radd__ = _add  # type: ignore[method-assign]
Hysteron.__neg__ = _neg  # type: ignore[method-assign]
Hysteron.__sub__ = _sub  # type: ignore[method-assign]
Hysteron.__rsub__ = _rsub  # type: ignore[method-assign]
