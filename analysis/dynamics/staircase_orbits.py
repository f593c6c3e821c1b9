"""The stroboscopic map of a continuous Preisach system in staircase coordinates, closed loop.

On a periodic orbit a continuous Preisach staircase (:mod:`hysteresis.preisach.continuous`)
holds, at the section, a **frozen prefix** ``F`` (older extrema that the orbit never reaches)
and the orbit's **own extrema** ``O`` (pushed at its reversals and wiped out by the same
reversals one period later). Return-point memory makes every periodic orbit sit exactly on the
border of a wipe-out: the orbit's maximum reaches the remembered maximum ``M ∈ O`` at the very
reversal that replaces it. A neighbouring state either wipes ``M`` just before its reversal
(the staircase keeps its length), or turns back just below it (``M`` and its partner stay and
two new entries are pushed), or wipes its partner on the way down: the map ``P^k`` of the full
staircase is continuous but not smooth there, and Newton would cross between these sectors.

The **closed-loop map** ``P̃`` replaces the image's own extrema by what the orbit's reversals
leave on the frozen prefix: with ``R_1 .. R_m`` the reversal points of the motion over ``k``
periods and ``q'`` its end,

    P̃(x) = (q', v', F, O'),   (F, O', q') = staircase of the input history F, R_1 .. R_m, q'

(the model's own wiping-out, :meth:`~hysteresis.preisach.base.PreisachModel.
state_from_extrema`). On the wipe-out side ``P̃ = P^k``; on the others ``P̃`` drops a pair of
entries that differs from the new one by the distance to the border (an Everett mass of that
order), so ``P̃`` and ``P^k`` have the same fixed points, and ``P̃`` is smooth across the border
(the reversal points and the motion depend smoothly on the state: the branch slope changes at
a wipe-out, but at ``v = 0``). This holds for one border per orbit period; it fails where the
orbit's own maximum *and* minimum both sit on their borders and the density couples them. At
the period-1 orbit of a ``from_density`` model (C = 1, tested) the one-sided finite differences
of ``P̃`` differ by 0.0167 in the ``q`` column, the same at 32, 64, 128 and 256 table cells (so
not the table's error), and the engines return one side each (round-off decides). The reading:
a maximum just above the remembered one wipes that pair, and the output after the next minimum
depends on the new maximum through ``2∫ μ(R_max, β) dβ`` over the frozen minimum .. ``R_min``;
just below, the minimum wipes the pair ``(R_max, m)`` and the output returns to the branch of
the remembered maximum, independent of ``R_max``: a first-order difference. A one-sided
Jacobian that loses the structural rank below makes
:func:`~analysis.dynamics.periodic_orbits.refine_periodic_orbit` warn; the other side's
Jacobian keeps it and cannot be told apart here. Newton converges either way (both sides share
the fixed point), and so does the continuation; the multipliers are one side's.

Its Jacobian: rows ``q, v`` from the engine's tangent flow at the end; the frozen rows the
identity; the row of an own extremum ``R_i`` the tangent ``δq`` at its reversal time
(``dR_i = δq(t_i) + v(t_i)·dt_i`` with ``v(t_i) = 0``), from a second pass of the tangent flow
stopped at the reversal times.

Reset directions: each own extremum is replaced inside the orbit (wiped out at the reversal that
pushes its successor, a copy of ``δq`` there). At one of the orbit's two extreme reversals every
own extremum is wiped (they all lie in the orbit's range: the maximum wipes the pairs above the
lowest own entry, the minimum then wipes that one too), so ``D P̃`` factors through ``(q, v)``
and the frozen prefix at that instant: its own-extrema directions are structural zero
multipliers, set to exactly 0 (label ``reset``, exponent −∞) instead of their round-off
remainder (1e-18 .. 1e-10: a zero pair splits like a Jordan block). Two multipliers are left,
those of ``(q, v)``.

Lyapunov exponents: ``lyapunov_spectrum`` in the full staircase keeps every extremum that a
perturbation turning back inside the loop leaves behind (new neutral directions), and finds
exponents near 0 next to such an orbit; the counterpart of ``P̃``'s Floquet exponents is
:func:`analysis.dynamics.memory.memory_frozen_exponents` with a projection interval of one orbit
period (which drops the long-lived extrema).

:func:`settle_staircase` makes the start state canonical: the transient leaves, next to the
orbit's own extrema, older extrema that converge onto them (an amplitude approaching the
orbit's from outside pushes extrema that the orbit never quite wipes out); entries within
``MERGE_TOLERANCE·max(1, extent)`` of the orbit's range ``[min R, max R]`` are collapsed onto
the orbit (the state becomes ``F, R_1 .. R_m, q'``), those beyond stay, frozen.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from oscillators import DivergenceError, OscillatorState

__all__ = [
    "MERGE_TOLERANCE",
    "StaircaseChangedError",
    "StaircaseShot",
    "closed_loop_shot",
    "settle_staircase",
]

#: relative distance to the orbit's range below which a remembered extremum is collapsed onto
#: the orbit by :func:`settle_staircase`
MERGE_TOLERANCE = 1e-6


class StaircaseChangedError(ValueError):
    """The motion's staircase left the structure of the start: a frozen extremum was wiped out
    (the orbit grew onto it: a grazing of the frozen prefix, a border collision) or the orbit
    has another number of own extrema. The closed-loop map is not defined there; a
    continuation treats it like a change of the switching sequence."""


@dataclass
class StaircaseShot:
    """One closed-loop integration of ``k`` periods: the states after each period (the last one
    rebuilt as ``F, own extrema, q'``), ``D P̃``, the events, and the structural rank bound of
    ``D P̃`` (its dimension minus the reset directions, module docstring)."""

    states: list[OscillatorState]
    jacobian: np.ndarray
    events: np.ndarray
    rank: int


def _run(system: Any, state: OscillatorState, k: int, engine_options: dict | None):
    """k periods with the tangent flow: states after each period, final deviations, events."""
    eng = system.engine(state, **(engine_options or {}))
    eng.start_tangent(False)
    out = np.empty((1, len(eng.sample_columns)))
    states = []
    for i in range(1, k + 1):
        eng.advance(np.array([i * system.period]), out, True)
        eng.check_finite(out[:, :2])
        states.append(eng.state())
    dev = eng.deviations()
    if not np.all(np.isfinite(dev)):
        raise DivergenceError(f"the tangent flow is not finite after {k} periods of {system!r}")
    return states, dev, eng.records()["events"]


def _reversals(events: np.ndarray, t0: float) -> tuple[np.ndarray, np.ndarray]:
    """Elapsed times and inputs of the reversals (kind −1) among ``events``."""
    rev = events[events["kind"] == -1]
    return rev["time"] - t0, rev["q"].astype(np.float64)


def _closed_state(operator: Any, prefix: np.ndarray, reversals: np.ndarray, end: OscillatorState):
    """``end`` with the staircase of the history ``prefix, reversals, end.q``."""
    history = np.concatenate([prefix, reversals, [end.q]])
    op_state = operator.state_from_extrema(history)
    return OscillatorState(q=end.q, v=end.v, phi=end.phi, operator_state=op_state, t=end.t)


def settle_staircase(
    system: Any, state: OscillatorState, k: int, engine_options: dict | None = None
) -> tuple[OscillatorState, int]:
    """The canonical start after ``k`` periods from ``state`` and its frozen prefix length:
    remembered extrema within ``MERGE_TOLERANCE·max(1, extent)`` of the range of the motion's
    reversal points are collapsed onto the orbit (module docstring)."""
    states, _, events = _run(system, state, k, engine_options)
    _, rev = _reversals(events, state.t)
    extrema = np.asarray(state.operator_state.extrema, dtype=np.float64)[:-1]
    if rev.size == 0:
        return states[-1], extrema.size
    lo, hi = float(rev.min()), float(rev.max())
    margin = MERGE_TOLERANCE * max(1.0, hi - lo)
    outside = (extrema < lo - margin) | (extrema > hi + margin)
    n = int(np.argmin(outside)) if not np.all(outside) else extrema.size
    return _closed_state(system.operator, extrema[:n], rev, states[-1]), n


def closed_loop_shot(
    system: Any,
    state: OscillatorState,
    k: int,
    prefix: int,
    engine_options: dict | None = None,
) -> StaircaseShot:
    """``P̃`` over ``k`` periods from ``state`` whose first ``prefix`` extrema are frozen, and
    its Jacobian in the coordinates ``(q, v, extrema[:-1])`` (module docstring).

    Raises :class:`StaircaseChangedError` if the closed staircase has another length or its
    frozen prefix is not kept bit for bit (the motion wiped a frozen extremum)."""
    extrema = np.asarray(state.operator_state.extrema, dtype=np.float64)
    d = 2 + extrema.size - 1
    states, dev, events = _run(system, state, k, engine_options)
    times, rev = _reversals(events, state.t)
    frozen = extrema[:prefix]
    closed = _closed_state(system.operator, frozen, rev, states[-1])
    got = np.asarray(closed.operator_state.extrema, dtype=np.float64)
    if got.size != extrema.size or not np.array_equal(got[:prefix], frozen):
        raise StaircaseChangedError(
            f"the orbit's staircase changed: {extrema.size} extrema with {prefix} frozen at the "
            f"start, {got.size} after {k} periods (a frozen extremum was wiped out or the orbit "
            "has another number of own extrema)"
        )
    own = got[prefix:-1]
    jac = np.zeros((2 + prefix + own.size, d))
    jac[:2] = dev[:2]
    jac[2 : 2 + prefix, 2 : 2 + prefix] = np.eye(prefix)
    if own.size:
        # the surviving reversal points (values are exact copies of the recorded inputs; the
        # last occurrence is the one the staircase keeps)
        idx = [int(np.nonzero(rev == e)[0][-1]) for e in own]
        eng = system.engine(state, **(engine_options or {}))
        eng.start_tangent(False)
        for row, i in enumerate(idx):
            eng.advance(np.array([times[i]]))
            jac[2 + prefix + row] = eng.deviations()[0]
    # the own extrema are reset directions (module docstring): rank (q, v) plus the frozen prefix
    return StaircaseShot([*states[:-1], closed], jac, events, 2 + prefix)
