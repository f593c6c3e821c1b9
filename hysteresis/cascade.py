"""Cascades ``y = outer[inner[u]]``: one operator driven by another's output.

:class:`Cascade` composes any two operators: ``apply`` drives ``inner`` with the input and
``outer`` with the inner's output sequence (exact by construction; continuing from a returned
state equals one long call because it does for the parts). The generalized Prandtl–Ishlinskii
models are cascades: ``Cascade(StaticMap(f), pi)`` (input nonlinearity) and
``Cascade(pi, StaticMap(g))`` (output map; ``Cascade(play, StaticMap(g))`` is the generalized
play ``g(w)``).

A cascade is a :class:`~hysteresis.base.ContinuousHysteron`: its :meth:`Cascade.branch_flow` is
derived from the parts' branch flows, so the oscillator's generic continuous engine integrates
it, tangent flow included, without knowing its class. A piecewise-constant part is seen as a
branch flow without memory variables whose output is constant and whose breakpoint is its next
switch (``α`` rising, the largest float below ``β`` falling) with the jump of its output.

The composite branch (input ``u`` moving in direction ``d``)
-------------------------------------------------------------
* The inner follows its branch ``x(u; m_in)``. The outer's input moves in direction
  ``d·σ``, ``σ`` the sense of the inner branch: the inner's declared ``monotonicity`` (a
  :class:`~hysteresis.static_map.StaticMap`: ``-1`` for a decreasing map, which reverses the
  outer), else the sign of the inner branch's slope at its start, else of its output change
  ahead, else ``+1`` (a flat inner branch does not move the outer; every library operator with
  memory has non-decreasing branches).
* Memory: ``"in:" + label`` for every inner variable (slaved ones stay slaved) and
  ``"out:" + label`` for the outer's *frozen* variables. The outer's slaved variables follow
  ``x``, not ``u``: they are **driven** (:mod:`hysteresis.flow`, "Driven memory"),
  ``δm = ∂x/∂u δu + ∂x/∂m_in δm_in``, and leave the labels while they are dragged.
* Output ``y = h(x(u; m_in); m_out)`` and, by the chain rule with ``h_x* = ∂h/∂x + Σ_slaved
  ∂h/∂m`` (the outer's slope), ``∂y/∂u = h_x*·∂x/∂u``, ``∂y/∂m_in = h_x*·∂x/∂m_in``,
  ``∂y/∂m_out = ∂h/∂m_out``.
* Breakpoint: the nearer of the inner's breakpoint and the first input at which the inner
  output reaches the outer's breakpoint ``b`` (``d·σ·(x − b) >= 0``), found by bisection on the
  floats between the branch start and the inner's breakpoint (bracketed by doubling steps when
  that is infinite), with ``x`` computed by the inner's own ``apply`` (so an integrator that
  stops there and applies the cascade sees the event: the first float, to round-off). A relay
  switch of the outer there is a jump (``breakpoint_jump``, the output change ``apply`` gives)
  whose input moves with the inner memory: ``breakpoint_gradient`` ``∂u*/∂m_in =
  −(∂x/∂m_in)/(dx/du)``, ``∂u*/∂m_out = (∂b/∂m_out)/(dx/du)``.
* An outer Preisach model that reverses pushes the inner *output* ``x(u0)``: its
  ``pushed_gradient`` is ``∂x/∂u``, ``∂x/∂m_in``.

Refused at construction (one sentence each, ``ValueError``)
-----------------------------------------------------------
* a piecewise-constant inner (relays, discrete Preisach, spin dimers, or a cascade whose output
  jumps) in front of an outer with *continuous* memory (play, Prandtl–Ishlinskii, continuous
  Preisach): the outer's memory would jump with the input, which no branch flow describes. In
  front of a memoryless or piecewise-constant outer it is accepted: the cascade's branches are
  flat with jumps at the inner's switches;
* a non-monotone inner (``monotonicity == 0``: a :class:`StaticMap` that turns) in front of an
  outer with memory: where ``x`` turns the outer reverses inside a branch of ``u``, at inputs no
  branch flow reports as breakpoints.

At run time an inner whose branch jumps (a composite with relays that is no cascade) in front
of an outer with continuous memory raises the same ``ValueError`` in :meth:`branch_flow`.

``initial_state(u0)``: the inner's ``initial_state(u0)`` and the outer's ``initial_state`` at
the inner's output (rising from negative saturation part by part). For a decreasing inner the
cascade's own history from ``u = −∞`` would bring the outer *down* from positive saturation;
this state is the outer's rising one instead (drive the cascade from a large input to get the
other).
"""

from __future__ import annotations

import math
import struct
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from hysteresis._validation import (
    MAX_MAGNITUDE,
    ParameterTypeError,
    as_input_sequence,
    check_state_type,
    direction_sign,
)
from hysteresis.base import ContinuousHysteron, Hysteron
from hysteresis.composite_memory import cascade_memory_restart, cascade_with_memory
from hysteresis.flow import BranchFlow
from hysteresis.seam import checked_branch_flow
from hysteresis.static_map import StaticMap

__all__ = ["Cascade", "CascadeState"]


@dataclass(frozen=True, eq=False)
class CascadeState:
    """State of a :class:`Cascade`: the inner's state and the outer's (whose input is the
    inner's output)."""

    inner: Any
    outer: Any

    @property
    def input(self) -> float:
        """The cascade's input: the inner's."""
        return float(self.inner.input)


# -- what the parts are -------------------------------------------------------------------------
def _memory_kind(op: Hysteron) -> str:
    """``"none"`` (memoryless), ``"discrete"`` (relay configurations only) or ``"continuous"``."""
    if isinstance(op, StaticMap):
        return "none"
    if op.piecewise_constant:
        return "discrete"
    if isinstance(op, Cascade):
        return op.memory_kind
    return "continuous"


def _jumps(op: Hysteron) -> bool | None:
    """True if the output jumps, False if it is continuous, None if unknown."""
    if op.piecewise_constant:
        return True
    if isinstance(op, StaticMap):
        return False
    if isinstance(op, Cascade):
        return op.output_jumps
    return None


def _monotonicity(op: Hysteron) -> int | None:
    """The declared monotonicity (StaticMap, Cascade), else None (read per branch)."""
    value = getattr(op, "monotonicity", None)
    return value if value in (-1, 0, 1) else None


def _slope_sign(op: Hysteron) -> int:
    """Sign of every branch slope: declared, else +1 (library operators with memory)."""
    m = _monotonicity(op)
    return 1 if m is None else m


# -- floats in order (bisection to round-off) -------------------------------------------------
_SIGN = 1 << 63


def _key(x: float) -> int:
    i = struct.unpack("<q", struct.pack("<d", x))[0]
    return i if i >= 0 else -(i + _SIGN)


def _float(k: int) -> float:
    return struct.unpack("<d", struct.pack("<q", k if k >= 0 else -k - _SIGN))[0]


def _first_true(pred: Callable[[float], bool], a: float, b: float) -> float:
    """The first float from ``a`` towards ``b`` where ``pred`` holds (``pred(a)`` false,
    ``pred(b)`` true): bisection on the ordered floats, at most 64 steps."""
    ka, kb = _key(a), _key(b)
    while abs(kb - ka) > 1:
        km = (ka + kb) // 2
        if pred(_float(km)):
            kb = km
        else:
            ka = km
    return _float(kb)


def _part_flow(op: Hysteron, state: Any, direction: int) -> BranchFlow:
    """A part's branch flow; a piecewise-constant part as a flat flow that ends at its next
    switch with the jump there."""
    if not op.piecewise_constant:
        return checked_branch_flow(op, state, direction)
    sw = op.switching(state)
    level = float(op.output(state))
    if direction > 0:
        bp, jump = float(sw.upper), float(sw.jump_up)
    else:
        bp, jump = float(sw.lower), float(sw.jump_down)
        bp = math.nextafter(bp, -math.inf) if math.isfinite(bp) else -math.inf
    if not math.isfinite(bp):
        bp, jump = direction * math.inf, 0.0

    def output(x):
        return np.full(np.shape(x), level)[()]

    def partials(x):
        shape = np.shape(x)
        return np.zeros(shape)[()], np.zeros(shape + (0,))

    return BranchFlow(
        direction=direction,
        input=float(state.input),
        labels=(),
        memory=np.zeros(0),
        slaved=np.zeros(0, dtype=bool),
        output=output,
        partials=partials,
        breakpoint=bp,
        breakpoint_jump=jump,
        constant_partials=True,
    )


class Cascade(ContinuousHysteron[CascadeState]):
    """``y = outer[inner[u]]`` (see the module docstring: branches, refusals, states).

    Parameters
    ----------
    inner, outer:
        Any operators (:class:`~hysteresis.base.Hysteron`).
    """

    def __init__(self, inner: Hysteron, outer: Hysteron) -> None:
        for name, op in (("inner", inner), ("outer", outer)):
            if not isinstance(op, Hysteron):
                raise ParameterTypeError(
                    f"{name} must be a hysteresis operator (Hysteron), got {type(op).__name__}"
                )
        outer_memory = _memory_kind(outer)
        if _jumps(inner) and outer_memory == "continuous":
            raise ValueError(
                f"inner {inner!r} has an output that jumps, and outer {outer!r} has continuous "
                "memory whose branches need a continuous input (a jump would move that memory "
                "discontinuously, which no branch flow describes)"
            )
        if _monotonicity(inner) == 0 and outer_memory != "none":
            raise ValueError(
                f"inner {inner!r} is not monotone, and outer {outer!r} has memory: where the "
                "inner output turns, the outer reverses inside a branch of the input, at "
                "inputs that no branch flow reports as breakpoints"
            )
        self._inner = inner
        self._outer = outer
        kinds = (_memory_kind(inner), outer_memory)
        self._memory_kind = next((k for k in ("continuous", "discrete") if k in kinds), "none")
        self._outer_memory = outer_memory
        ji, jo = _jumps(inner), _jumps(outer)
        self._jumps = True if (ji or jo) else (False if ji is False and jo is False else None)
        mi, mo = _monotonicity(inner), _monotonicity(outer)
        self._inner_monotonicity = mi
        if 0 in (mi, mo):
            self._monotonicity = 0
        else:
            self._monotonicity = None if mi is None or mo is None else mi * mo

    # -- properties --------------------------------------------------------------------------
    @property
    def inner(self) -> Hysteron:
        """The operator driven by the input."""
        return self._inner

    @property
    def outer(self) -> Hysteron:
        """The operator driven by the inner's output."""
        return self._outer

    @property
    def memory_kind(self) -> str:
        """``"none"``, ``"discrete"`` or ``"continuous"``: the richest memory of the parts."""
        return self._memory_kind

    @property
    def output_jumps(self) -> bool | None:
        """True if the output jumps (a piecewise-constant part), False if continuous, None if a
        part does not say."""
        return self._jumps

    @property
    def monotonicity(self) -> int | None:
        """``±1``/``0`` when both parts declare theirs (their product; ``0`` if either turns),
        else ``None``."""
        return self._monotonicity

    @property
    def output_range(self) -> tuple[float, float]:
        """The outer's; for a monotone memoryless outer and a bounded inner, the outer's values
        at the inner's bounds (within the outer's own range)."""
        lo, hi = self._outer.output_range
        a, b = self._inner.output_range
        if (
            self._outer_memory == "none"
            and _monotonicity(self._outer) in (-1, 1)
            and math.isfinite(a)
            and math.isfinite(b)
        ):
            ys, _ = self._outer.apply(np.array([a, b]))
            return (max(lo, float(np.min(ys))), min(hi, float(np.max(ys))))
        return (lo, hi)

    @property
    def max_slope(self) -> float | None:
        """``0`` if a part is piecewise constant or the parts' slopes have opposite signs (a
        decreasing map in front of or behind a non-decreasing part); the product of the parts'
        bounds when both are non-decreasing and know theirs (operators with memory are taken as
        non-decreasing, true of the library's with non-negative weights and densities); else
        ``None``."""
        if self._inner.piecewise_constant or self._outer.piecewise_constant:
            return 0.0
        si, so = _slope_sign(self._inner), _slope_sign(self._outer)
        if si * so == -1:
            return 0.0
        bi, bo = self._inner.max_slope, self._outer.max_slope
        if si == so == 1 and bi is not None and bo is not None:
            return max(float(bi), 0.0) * max(float(bo), 0.0)
        return None

    def __repr__(self) -> str:
        return f"Cascade({self._inner!r}, {self._outer!r})"

    # -- states ------------------------------------------------------------------------------
    def _x_at(self, inner_state: Any, u: float) -> float:
        """The inner output at ``u`` from ``inner_state`` (the arithmetic of ``apply``)."""
        return float(self._inner.apply(np.array([u]), inner_state)[0][0])

    def initial_state(self, u0: float) -> CascadeState:
        """The inner rising from negative saturation to ``u0``, the outer rising to the inner's
        output there (module docstring: a decreasing inner)."""
        inner_state = self._inner.initial_state(u0)
        x0 = self._x_at(inner_state, float(inner_state.input))
        return CascadeState(inner_state, self._outer.initial_state(x0))

    def _check_state(self, state: Any) -> None:
        """The type, and the outer's input equal to the inner's output (relative 1e-9: the
        parts compute it with their own rounding)."""
        check_state_type(state, CascadeState, self)
        x = float(self._inner.output(state.inner))
        x_outer = float(state.outer.input)
        if abs(x - x_outer) > 1e-9 * max(1.0, abs(x)):
            raise ValueError(
                f"state: the outer's input {x_outer!r} is not the inner's output {x!r}; the "
                "state belongs to another operator"
            )

    def apply(self, inputs, state: CascadeState | None = None):
        """The inner driven by ``inputs``, the outer by the inner's outputs."""
        u = as_input_sequence(inputs)
        if state is None:
            state = self.initial_state(float(u[0]))
        else:
            self._check_state(state)
        x, inner_state = self._inner.apply(u, state.inner)
        y, outer_state = self._outer.apply(x, state.outer)
        return np.asarray(y, dtype=np.float64), CascadeState(inner_state, outer_state)

    def output(self, state: CascadeState) -> float:
        check_state_type(state, CascadeState, self)
        return float(self._outer.output(state.outer))

    # -- the branch flow -----------------------------------------------------------------------
    def _sense(self, flow: BranchFlow) -> int:
        """Direction of the inner output per unit input motion on ``flow`` (module docstring)."""
        if self._inner_monotonicity in (-1, 1):
            return self._inner_monotonicity
        u0, d = flow.input, flow.direction
        slope = float(flow.slope(u0))
        if slope != 0.0 and math.isfinite(slope):
            return 1 if slope > 0 else -1
        bp = flow.breakpoint
        far = bp if math.isfinite(bp) else u0 + d * max(1.0, abs(u0))
        change = float(flow.output(u0 + 0.5 * (far - u0))) - float(flow.output(u0))
        if change != 0.0 and math.isfinite(change):
            return 1 if change * d > 0 else -1
        return 1

    def _reached(self, inner: BranchFlow, state: Any, dx: int, target: float) -> float | None:
        """The first input (direction ``inner.direction``, not beyond the inner breakpoint) at
        which the inner output, computed by ``apply``, satisfies ``dx·(x − target) >= 0``."""
        u0, d = inner.input, inner.direction

        def by_apply(u: float) -> bool:
            return dx * (self._x_at(state, u) - target) >= 0.0

        def by_formula(u: float) -> bool:
            return dx * (float(inner.output(u)) - target) >= 0.0

        if by_apply(u0):
            return u0
        end = inner.breakpoint
        if math.isfinite(end):
            if not by_apply(end):
                return None
        else:
            # doubling steps ahead, screened on the (vectorised) branch formula
            steps = u0 + d * max(1.0, abs(u0)) * np.exp2(np.arange(-40.0, 1000.0))
            steps = steps[np.abs(steps) <= MAX_MAGNITUDE]
            with np.errstate(all="ignore"):
                xs = np.asarray(inner.output(steps), dtype=np.float64)
            hits = np.flatnonzero(np.isfinite(xs) & (dx * (xs - target) >= 0.0))
            confirmed = [float(s) for s in steps[hits[0] :]] if hits.size else []
            end = next((s for s in confirmed[:8] if by_apply(s)), None)
            if end is None:
                return None
        # the formula's crossing first (cheap), then apply's within a widening ulp bracket
        if not by_formula(u0) and by_formula(end):
            guess = _key(_first_true(by_formula, u0, end))
            k0, k1 = _key(u0), _key(end)
            sign = 1 if k1 > k0 else -1
            width = 2
            while width < abs(k1 - k0):
                lo = _float(guess - sign * width)
                hi = _float(guess + sign * width)
                if (lo - u0) * d > 0 and (end - hi) * d > 0 and not by_apply(lo) and by_apply(hi):
                    return _first_true(by_apply, lo, hi)
                width *= 64
        return _first_true(by_apply, u0, end)

    def branch_flow(self, state: CascadeState, direction: int) -> BranchFlow:
        """The composite branch in ``direction`` (module docstring)."""
        inner, outer, dx = self._part_flows(state, direction)
        return self._compose(state, inner, outer, dx)

    # -- the memory as coordinates (periodic orbits; hysteresis.composite_memory) ---------------
    def _part_flows(self, state: CascadeState, direction: int) -> tuple:
        d = direction_sign(direction)
        check_state_type(state, CascadeState, self)
        inner = _part_flow(self._inner, state.inner, d)
        dx = d * self._sense(inner)
        return inner, _part_flow(self._outer, state.outer, dx), dx

    def with_memory(
        self, state: CascadeState, values: Any, input: float, direction: int
    ) -> CascadeState:
        """The inner's memory (labels ``"in:"``) and the outer's frozen memory (``"out:"``)
        set from ``values`` at ``input``; the outer's dragged variables stay dragged at the new
        inner output (:func:`hysteresis.composite_memory.cascade_with_memory`)."""
        flows = self._part_flows(state, direction)
        values = np.asarray(values, dtype=np.float64)
        parts = cascade_with_memory(
            self._inner, self._outer, state, flows, values, input, self._x_at
        )
        return CascadeState(*parts)

    def memory_restart(self, state: CascadeState, direction: int, u: float) -> tuple:
        """The parts' restarts, the outer's at the inner output ``x(u)`` with ``δx`` by the
        chain rule (:func:`hysteresis.composite_memory.cascade_memory_restart`)."""
        flows = self._part_flows(state, direction)
        return cascade_memory_restart(self._inner, self._outer, state, flows, u)

    def _compose(self, state: CascadeState, I: BranchFlow, O: BranchFlow, dx: int) -> BranchFlow:
        d, u0 = I.direction, I.input
        nI = I.n_memory
        so = np.array(O.slaved, dtype=bool)
        fo = ~so
        nOf = int(fo.sum())
        n = nI + nOf
        labels = tuple("in:" + lab for lab in I.labels) + tuple(
            "out:" + lab for lab, keep in zip(O.labels, fo, strict=True) if keep
        )
        pI = np.array(I.pushed, dtype=bool)
        pO = np.array(O.pushed, dtype=bool) & fo
        x_output, x_partials, h_output, h_partials = I.output, I.partials, O.output, O.partials

        def output(u):
            return h_output(x_output(u))

        def partials(u):
            x = x_output(u)
            gu, gm = x_partials(u)
            hx, hm = h_partials(x)
            hm = np.asarray(hm, dtype=np.float64)
            slope = np.asarray(hx, dtype=np.float64) + np.sum(hm[..., so], axis=-1)
            gm = np.asarray(gm, dtype=np.float64)
            d_m = np.concatenate([slope[..., None] * gm, hm[..., fo]], axis=-1)
            return (slope * np.asarray(gu, dtype=np.float64))[()], d_m

        def x_gradient(u: float) -> tuple[float, np.ndarray]:
            """``∂x/∂u`` and ``∂x/∂m`` over the composite memory (outer columns zero)."""
            gu, gm = x_partials(u)
            return float(gu), np.concatenate([np.asarray(gm, dtype=np.float64), np.zeros(nOf)])

        def outer_rows(u: float, b: np.ndarray, B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            """Rows ``b·δx + B @ δm_out`` in composite terms (slaved outer columns follow x)."""
            gu, gx = x_gradient(u)
            b_eff = b + B[:, so].sum(axis=1)
            return b_eff * gu, b_eff[:, None] * gx[None, :] + _pad(B[:, fo], nI, left=True)

        driven_labels = (
            tuple("in:" + lab for lab in I.driven_labels)
            + tuple("out:" + lab for lab, s in zip(O.labels, so, strict=True) if s)
            + tuple("out:" + lab for lab in O.driven_labels)
        )
        driven = None
        if driven_labels:

            def driven(u):
                values, d_du, d_dm = [], [], []
                if I.driven_labels:
                    v, a, A = I.driven(u)
                    values.append(np.asarray(v, dtype=np.float64))
                    d_du.append(np.asarray(a, dtype=np.float64))
                    d_dm.append(_pad(np.asarray(A, dtype=np.float64), nOf, left=False))
                x = float(x_output(u))
                if np.any(so):
                    values.append(np.asarray(O.memory_at(x), dtype=np.float64)[so])
                    b, B = np.ones(int(so.sum())), np.zeros((int(so.sum()), O.n_memory))
                    rows = outer_rows(u, b, B)
                    d_du.append(rows[0])
                    d_dm.append(rows[1])
                if O.driven_labels:
                    v, b, B = O.driven(x)
                    values.append(np.asarray(v, dtype=np.float64))
                    rows = outer_rows(u, np.asarray(b, dtype=np.float64), np.asarray(B, float))
                    d_du.append(rows[0])
                    d_dm.append(rows[1])
                values = np.concatenate(values)
                return values, np.concatenate(d_du), np.vstack(d_dm).reshape(values.size, n)

        pushed_gradient = None
        if np.any(pO) or (np.any(pI) and I.pushed_gradient is not None):

            def pushed_gradient(u):
                d_du, d_dm = [], []
                # the inner's pushed rows: δu, or the inner's own gradient
                if I.pushed_gradient is not None:
                    a, A = I.pushed_gradient(u)
                    a = np.asarray(a, dtype=np.float64).reshape(-1)
                    A = np.asarray(A, dtype=np.float64).reshape(a.size, nI)
                else:
                    a, A = np.ones(int(pI.sum())), np.zeros((int(pI.sum()), nI))
                if np.any(pI):
                    d_du.append(a)
                    d_dm.append(_pad(A, nOf, left=False))
                if np.any(pO):
                    # the outer pushes x(u0): its gradient with the inner's pushed columns folded
                    # into δu (columns of pushed variables must be zero)
                    gu, gm = x_partials(u)
                    gm = np.asarray(gm, dtype=np.float64).copy()
                    gu = float(gu) + float(gm[pI] @ a)
                    gm_eff = gm + gm[pI] @ A
                    gm_eff[pI] = 0.0
                    gx = np.concatenate([gm_eff, np.zeros(nOf)])
                    k = int(pO.sum())
                    if O.pushed_gradient is not None:
                        b, B = O.pushed_gradient(float(x_output(u)))
                        b = np.asarray(b, dtype=np.float64).reshape(k)
                        B = np.asarray(B, dtype=np.float64).reshape(k, O.n_memory)
                    else:
                        b, B = np.ones(k), np.zeros((k, O.n_memory))
                    b_eff = b + B[:, so].sum(axis=1)
                    d_du.append(b_eff * gu)
                    d_dm.append(b_eff[:, None] * gx[None, :] + _pad(B[:, fo], nI, left=True))
                d_du = np.concatenate(d_du)
                return d_du, np.vstack(d_dm).reshape(d_du.size, n)

        # -- the breakpoint: the inner's, or where x reaches the outer's -----------------------
        b_in, b_out = I.breakpoint, O.breakpoint
        u_out = self._reached(I, state.inner, dx, b_out) if math.isfinite(b_out) else None
        inner_event = u_out is None or (math.isfinite(b_in) and u_out == b_in)
        outer_event = u_out is not None
        bp = u_out if outer_event else b_in
        resets: tuple[str, ...] = ()
        removes: tuple[str, ...] = ()
        if inner_event and math.isfinite(b_in):
            resets = tuple("in:" + lab for lab in I.breakpoint_resets)
            removes = tuple("in:" + lab for lab in I.breakpoint_removes)
        if outer_event:
            # an outer variable reset there becomes driven: it leaves the labels
            gone = set(O.breakpoint_removes) | set(O.breakpoint_resets)
            removes += tuple(lab for lab in labels if lab[4:] in gone and lab.startswith("out:"))
        jump, gradient = 0.0, None
        inner_jumps = inner_event and I.breakpoint_jump != 0.0
        if inner_jumps or (outer_event and O.breakpoint_jump != 0.0):
            jump, gradient = self._jump(state, I, O, bp, inner_jumps)
        return BranchFlow(
            direction=d,
            input=u0,
            labels=labels,
            memory=np.concatenate([I.memory, O.memory[fo]]),
            slaved=np.concatenate([I.slaved, np.zeros(nOf, dtype=bool)]),
            output=output,
            partials=partials,
            breakpoint=bp,
            breakpoint_resets=resets,
            breakpoint_removes=removes,
            breakpoint_jump=jump,
            reversal_pushes=I.reversal_pushes or O.reversal_pushes,
            pushed=np.concatenate([pI, pO[fo]]),
            constant_partials=I.constant_partials and O.constant_partials,
            breakpoint_gradient=gradient,
            driven_labels=driven_labels,
            driven=driven,
            pushed_gradient=pushed_gradient,
        )

    def _jump(
        self, state: CascadeState, I: BranchFlow, O: BranchFlow, bp: float, inner_jumps: bool
    ) -> tuple[float, np.ndarray]:
        """The output's jump at ``bp`` (what ``apply`` gives there minus the branch's value)
        and the breakpoint's motion with the frozen memory."""
        nOf = int(np.sum(~np.asarray(O.slaved, dtype=bool)))
        x_before = float(I.output(bp))
        x_after = self._x_at(state.inner, bp)
        if inner_jumps:
            if self._outer_memory == "continuous" or O.n_memory:
                raise ValueError(
                    f"inner {self._inner!r} jumps at input {bp!r}, and outer {self._outer!r} has "
                    "continuous memory whose branches need a continuous input (a jump would move "
                    "that memory discontinuously, which no branch flow describes)"
                )
            ys, _ = self._outer.apply(np.array([x_before, x_after]), state.outer)
        else:
            ys, _ = self._outer.apply(np.array([x_after]), state.outer)
        jump = float(ys[-1]) - float(O.output(x_before))
        if inner_jumps:
            grad = I.breakpoint_gradient
            grad = np.zeros(I.n_memory) if grad is None else np.asarray(grad, dtype=np.float64)
            return jump, np.concatenate([grad, np.zeros(nOf)])
        # x(u*; m_in) = b(m_out): δu* = (∂b/∂m_out δm_out − ∂x/∂m_in δm_in) / (dx/du)
        slope = float(I.slope(bp))
        _, gm = I.partials(bp)
        gm = np.where(np.asarray(I.slaved, dtype=bool), 0.0, np.asarray(gm, dtype=np.float64))
        fo = ~np.asarray(O.slaved, dtype=bool)
        gb = O.breakpoint_gradient
        gb = np.zeros(nOf) if gb is None else np.asarray(gb, dtype=np.float64)[fo]
        with np.errstate(divide="ignore", invalid="ignore"):
            grad = np.concatenate([-gm, gb]) / slope
        grad = np.where(np.concatenate([gm, gb]) == 0.0, 0.0, grad)
        return jump, grad


def _pad(block: np.ndarray, width: int, left: bool) -> np.ndarray:
    """``block`` with ``width`` zero columns on the left or right."""
    zeros = np.zeros((block.shape[0], width))
    return np.hstack([zeros, block] if left else [block, zeros])
