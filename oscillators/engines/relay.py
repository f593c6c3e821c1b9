"""The relay engines: exact event-driven integration of the oscillator with relay operators.

The operator hands over its relays through the contract of :mod:`hysteresis.base`
(``relay_table()``, ``relay_outputs(state)``, ``state_from_relay_outputs(outputs, input)``);
between switches ``q'' + 2ζq' + q = cos φ + C·M`` is linear and solved in closed form, every
threshold crossing is located on that solution (:mod:`oscillators.engines._relay_kernels`:
algorithm, grazing convention, short-hop Taylor expansion) and the tangent flow gets the
saltation ``δv += C·ΔM/v*·δq`` at each switch. Methods (``engine_options={"method": ...}``):

* ``"nested"`` — O(1) per switch, when the table's thresholds nest
  (:meth:`hysteresis.relay_table.RelayTable.nested_plan`: equal widths, the paper's dimers);
* ``"heap"`` — any relays (random widths, identified densities, ties, zero widths, weights):
  the next up switch is the smallest ``alpha`` of the down relays, the next down switch the
  largest ``beta`` of the up relays, each kept in a priority queue over the presorted thresholds
  (a 64-ary bitset tree, :meth:`hysteresis.relay_table.RelayTable.heap_plan`: O(log₆₄ N) per
  switched relay); relays at one threshold switch together; ``M`` in integer weight units when
  the weights are multiples of one unit, else compensated (Neumaier) sums;
* ``"generic"`` — the Python reference path through ``switching(state)`` / ``apply``;
* ``"auto"`` (default) — ``"nested"`` when the plan exists, else ``"heap"``; ``"generic"``
  without a relay table (spins with ``compiled_switching()``: :mod:`.switching` instead).

Two classes: :class:`RelayKernelEngine` (the compiled kernels, nested or heap) and
:class:`RelayReferenceEngine` (the Python reference path). :class:`RelayEngine`, their common
base, is what :func:`~oscillators.engines.select.select_engine` hands out:
``RelayEngine(system, state, method=...)`` builds the one the method names.

Relays of zero weight never change ``M`` and are left out of the kernels (the operator state
returned rebuilds them from the staircase).

Filippov sliding (:mod:`oscillators.engines._sliding`, closed form, exit, tangent collapse):
a chattering across a zero-width threshold pushing in from both sides is set on ``q = θ, v = 0``
(kernel status 4) and slides with ``M = M_eq = (θ − cos φ)/C`` to its exit phase;
``records()["slides"]`` lists slide-in (+1) / slide-out (−1); a state taken during a slide
restarts sliding.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from hysteresis.seam import check_state, checked_apply, checked_relay_outputs, checked_relay_table
from oscillators.engines import _relay_kernels as kern
from oscillators.engines import _sliding as slide
from oscillators.engines.base import (
    SLIDE_EXCURSION,
    SWITCH_DTYPE,
    Engine,
    GrazingError,
    SlidingError,
    SwitchBudgetError,
    TangentFlow,
    grazing_message,
    split_times,
    switch_budget,
)
from oscillators.linear import exact_step, hom_matrix, particular_amplitudes, phase_column
from oscillators.parameters import check_closed_form
from oscillators.results import OscillatorState

__all__ = [
    "GrazingError",
    "METHODS",
    "RelayEngine",
    "RelayKernelEngine",
    "RelayReferenceEngine",
    "SWITCH_DTYPE",
    "SlidingError",
    "SwitchBudgetError",
]

METHODS = ("auto", "nested", "heap", "generic")
#: the fast short hop's limit ρh (make_params; 1e-3 before): more of a dense ensemble's hops
#: take the degree-6 path (remainder ~4e-22: the same hops to round-off; fig:dim 6.5% less CPU)
FAST_HOP = 3e-3


class RelayEngine(slide.SlidingMixin, TangentFlow, Engine):
    """Event-driven engine for piecewise-constant operators (see the module docstring).

    ``RelayEngine(system, state, method, taylor)`` returns a :class:`RelayKernelEngine` or, for
    ``method="generic"`` and without a relay table, a :class:`RelayReferenceEngine`.

    Parameters
    ----------
    system:
        The :class:`~oscillators.system.ForcedOscillator`.
    state:
        Start state; ``state.operator_state=None`` means ``operator.initial_state(q)``.
    method:
        ``"auto"``, ``"nested"``, ``"heap"`` or ``"generic"`` (module docstring).
    taylor:
        Use the short-hop Taylor expansion (default); ``False`` locates every switch by the
        exact scan (slower; for checks).
    """

    @classmethod
    def check_system(cls, system: Any) -> None:
        """Refuse (ζ, Ω) within :data:`~oscillators.parameters.RESONANCE_LIMIT` of resonance,
        and an operator whose ``relay_table()`` is not a relay table."""
        check_closed_form(float(system.damping_ratio), float(system.frequency))
        if system.operator.has_relay_table:
            checked_relay_table(system.operator)

    def __new__(cls, system: Any, state: OscillatorState, method: str = "auto", **_: Any):
        if cls is RelayEngine:
            if method not in METHODS:
                raise ValueError(f"method must be one of {METHODS}, got {method!r}")
            table = system.operator.has_relay_table
            if not table and method in ("nested", "heap"):
                name = type(system.operator).__name__
                raise ValueError(f"method {method!r} needs a relay table; {name} has none")
            cls = RelayReferenceEngine if method == "generic" or not table else RelayKernelEngine
        return super().__new__(cls)

    def __init__(
        self, system: Any, state: OscillatorState, method: str = "auto", taylor: bool = True
    ) -> None:
        super().__init__(system, state)
        if method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}, got {method!r}")
        q0, v0, t0 = float(state.q), float(state.v), float(state.t)
        if not all(math.isfinite(x) for x in (q0, v0, self._phi0, t0)):
            raise ValueError("the start state (q, v, phi, t) must be finite")
        op = system.operator
        self._op = op
        opstate = state.operator_state
        if opstate is None:
            opstate = op.initial_state(q0)
        _, opstate = checked_apply(op, np.array([q0]), opstate)
        self._opstate0 = opstate
        zeta = float(system.damping_ratio)
        amp_a, amp_b = particular_amplitudes(zeta, self._omega)
        self._par = kern.make_params(
            zeta, self._omega, float(system.coupling), self._phi0, amp_a, amp_b, t0, taylor,
            SLIDE_EXCURSION, FAST_HOP,
        )  # fmt: skip
        self._t0 = t0
        self._y = np.zeros((3, 3))
        self._chunks: list[np.ndarray] = []
        self._state_cache: OscillatorState | None = None
        # the sliding motion in progress (None: ordinary motion) and the slide records
        self._slide: slide._Slide | None = None
        self._slide_events: list[tuple[float, float, float, int, float]] = []
        self._collapsed = False  # a slide collapsed (δq, δv) since the last start/set

    def _now(self) -> tuple[float, float, Any]:
        """(q, v, operator state) now."""
        raise NotImplementedError

    def state(self) -> OscillatorState:
        if self._state_cache is None:
            q, v, opstate = self._now()
            self._state_cache = OscillatorState(
                q=q, v=v, phi=self.phase(), operator_state=opstate, t=self._t0 + self.elapsed
            )
        return self._state_cache

    def records(self) -> dict[str, np.ndarray]:
        """``{"switches": time, q, v, jump}`` and ``{"slides": time, q, v, kind, M}``
        (:data:`~oscillators.engines._sliding.SLIDE_DTYPE`: kind +1 slide-in, -1 slide-out;
        ``v`` the speed set to 0 at slide-in; ``M`` the equivalent output then)."""
        sw = np.concatenate(self._chunks) if self._chunks else np.empty((0, 4))
        rec = np.empty(sw.shape[0], dtype=SWITCH_DTYPE)
        for j, name in enumerate(SWITCH_DTYPE.names):
            rec[name] = sw[:, j]
        slides = np.array(self._slide_events, dtype=slide.SLIDE_DTYPE)
        return {"switches": rec, "slides": slides}

    # -- tangent flow: (δq, δv[, δφ]) columns in the 3×3 buffer the kernels update in place ----
    def _start_tangent(self, include_phase: bool) -> int:
        k = 3 if include_phase else 2
        self._y[:, :] = 0.0
        for j in range(k):
            self._y[j, j] = 1.0
        self._collapsed = False
        if self._slide is not None:  # started on the sliding set
            self._y[:2, :] = 0.0
            self._collapsed = True
        return k

    @property
    def tangent_space(self) -> tuple[str, ...]:
        return ("q", "v", "phi")[: self._ntan]

    def _deviations(self) -> np.ndarray:
        return self._y[: self._ntan, : self._ntan].copy()

    def _set_deviations(self, y: np.ndarray) -> None:
        self._y[: self._ntan, : self._ntan] = y
        self._collapsed = False

    def _rank_bound(self) -> int:
        # relays have no memory directions and every saltation matrix is invertible; a slide
        # collapses (δq, δv) (only the phase direction, if tracked, survives it)
        return self._ntan - 2 if self._collapsed else self._ntan


class RelayKernelEngine(RelayEngine):
    """The compiled relay engine: ``method`` ``"auto"``, ``"nested"`` or ``"heap"``."""

    name = "relay kernel"
    kernel_module = "oscillators.engines._relay_kernels"

    def __init__(
        self, system: Any, state: OscillatorState, method: str = "auto", taylor: bool = True
    ) -> None:
        super().__init__(system, state, method, taylor)
        if method == "generic":
            raise ValueError("method='generic' is the Python reference path (RelayEngine)")
        op = self._op
        q0, v0 = float(state.q), float(state.v)
        table = checked_relay_table(op)
        y0 = checked_relay_outputs(op, table, self._opstate0)
        self._table = table
        self._active, work = table.positive_part()
        self._work = work
        self._n_relays = int(work.n_relays)
        ya = y0[self._active]
        self._mp = kern.taylor_matrix_coefficients(float(system.damping_ratio), self._omega)
        self._tn1 = np.zeros(1, dtype=np.int64)
        self._tt1 = np.zeros(1)
        self._nobuf = np.empty((0, 3))
        self._nosw = np.empty((1, 4))
        self._cnt = np.zeros(1, dtype=np.int64)
        st = np.zeros(kern.N_ST)
        st[: kern.S_SIN + 1] = (q0, v0, 0.0, math.cos(self._phi0), math.sin(self._phi0))
        ist = np.zeros(kern.N_IST, dtype=np.int64)
        plan = work.nested_plan() if method in ("auto", "nested") else None
        k = plan.index_of(ya) if plan is not None else None
        if method == "nested" and k is None:
            raise ValueError(
                "method='nested' needs relays whose upper and lower thresholds increase together "
                "(RelayTable.nested_plan() is None for this operator)"
            )
        if k is not None:
            self._kind = kern.KIND_NESTED
            self._plan = plan
            self._tf, self._ti, self._bits, self._lay = kern.nested_kernel_table(plan)
            ist[kern.I_K] = k
            self.method = "nested"
            self.name = "relay kernel (nested, O(1))"
        else:
            self._kind = kern.KIND_HEAP
            heap = work.heap_plan()
            self._heap = heap
            bits, units_up, m, mc = heap.state_arrays(ya)
            self._par[kern.P_UNIT] = heap.unit
            self._tf, self._ti, self._bits, self._lay = heap.tf, heap.ti, bits, heap.lay
            ist[kern.I_UP] = units_up
            ist[kern.I_TOT] = heap.total_units
            st[kern.S_M] = m
            st[kern.S_MC] = mc
            self.method = "heap"
            self.name = "relay kernel (heap, O(log N))"
        self._run = kern.run_nested if self._kind == kern.KIND_NESTED else kern.run_heap
        kern._table_refresh(
            self._par, self._kind, self._tf, self._ti, self._bits, self._lay, st, ist
        )
        self._st = st
        self._ist = ist
        self._start_on_sliding_set(q0, v0)

    def _switched_copy(self, direction: int) -> tuple[float, float, float]:
        """(output, next up, next down threshold) after switching the relays at the current
        threshold in ``direction``, on a copy of the table state."""
        st, ist, bits = self._st.copy(), self._ist.copy(), self._bits.copy()
        kern._table_switch(
            self._par, self._kind, self._tf, self._ti, bits, self._lay, st, ist, direction
        )
        return float(st[kern.S_MV]), float(st[kern.S_UP]), float(st[kern.S_DN])

    def _start_on_sliding_set(self, q: float, v: float) -> None:
        """A start on a zero-width threshold pushing in from both sides starts sliding."""
        st = self._st
        m_now = float(st[kern.S_MV])
        for direction, theta in ((1, float(st[kern.S_UP])), (-1, float(st[kern.S_DN]))):
            if q != theta:
                continue
            m_other, up, down = self._switched_copy(direction)
            if (down if direction > 0 else up) != theta:
                continue  # not a zero-width group: no chattering at this threshold
            below, above = (m_now, m_other) if direction > 0 else (m_other, m_now)
            if slide.should_slide(
                q, v, float(st[kern.S_COS]), float(self._par[kern.P_ZETA]),
                float(self._par[kern.P_C]), below, above, m_now, float(self._par[kern.P_SL]),
            ):  # fmt: skip
                self._enter_slide(theta, v, m_now, m_other, direction, False)
                return

    def _clock(self) -> tuple[int, float]:
        return int(self._ist[kern.I_N]), float(self._st[kern.S_TAU])

    @property
    def output(self) -> float:
        """Operator output ``M`` now (``M_eq`` while sliding)."""
        if self._slide is not None:
            return self._slide_output(float(self._st[kern.S_TAU]))
        return float(self._st[kern.S_MV])

    def _slide_set_clock(self, n: int, tau: float, integral: float) -> None:
        st = self._st
        self._ist[kern.I_N] = n
        ph = self._phi0 + self._omega * tau
        st[kern.S_TAU] = tau
        st[kern.S_COS] = math.cos(ph)
        st[kern.S_SIN] = math.sin(ph)
        st[kern.S_Q] = self._slide.theta
        st[kern.S_V] = 0.0
        st[kern.S_IM] += integral

    def _slide_switch(self, direction: int) -> None:
        kern._table_switch(
            self._par, self._kind, self._tf, self._ti, self._bits, self._lay, self._st,
            self._ist, direction,
        )  # fmt: skip

    def _slide_targets(self, tgt_n: np.ndarray, tgt_tau: np.ndarray, i: int, buf, record) -> int:
        """Slide through the targets from ``i`` (rows of ``buf``: θ, 0, M_eq) until the exit;
        returns the first target not reached."""
        theta = self._slide.theta
        sample = buf.shape[0] > 0
        while i < tgt_n.size:
            tau = float(tgt_tau[i])
            if not self._slide_to(int(tgt_n[i]), tau, record):
                return i
            if sample:
                buf[i, 0] = theta
                buf[i, 1] = 0.0
                buf[i, 2] = self._slide_output(tau)
            i += 1
        return i

    def output_integral(self) -> float:
        """``∫ M dt`` since the start, exact: ``M`` is constant between switches, so the kernel
        adds ``M·h`` for every hop ``h``."""
        return float(self._st[kern.S_IM])

    @property
    def n_events(self) -> int:
        return int(self._ist[kern.I_NSW])

    def _advance(self, times: np.ndarray, out: np.ndarray | None, record: bool) -> None:
        if times.size == 1:
            # one target (the Lyapunov stepper's case): the clock reading by scalar arithmetic
            # into the reused target arrays, no array bookkeeping
            t = float(times[0])
            tgt_n, tgt_tau = self._tn1, self._tt1
            n = math.floor(t / self._period)
            tau = t - n * self._period
            if tau >= self._period:
                n, tau = n + 1, 0.0
            tgt_n[0], tgt_tau[0] = n, max(tau, 0.0)
        else:
            tgt_n, tgt_tau = split_times(times, self._period)
        self._run_targets(tgt_n, tgt_tau, out, record)

    def _run_targets(
        self, tgt_n: np.ndarray, tgt_tau: np.ndarray, out: np.ndarray | None, record: bool
    ) -> None:
        """Run the kernel through the target clock readings (period index, time in period)."""
        self._state_cache = None
        # the kernel writes straight into ``out`` when it has its layout (the stepper's buffer)
        direct = (
            out is not None
            and out.shape[1] == 3
            and out.dtype == np.float64
            and out.flags.c_contiguous
        )
        if direct:
            buf = out
        else:
            buf = np.empty((tgt_n.size, 3)) if out is not None else self._nobuf
        tan_on = self._ntan > 0
        n_now, tau_now = self._clock()
        span = (int(tgt_n[-1]) - n_now) * self._period + (float(tgt_tau[-1]) - tau_now)
        budget = switch_budget(self._n_relays, self._omega, span)
        nsw0 = int(self._ist[kern.I_NSW])
        self._ist[kern.I_MAXSW] = nsw0 + budget
        cap = 1 << 12 if record else 1
        sw = np.empty((cap, 4)) if record else self._nosw
        cnt = self._cnt
        i = 0
        if self._slide is not None:
            i = self._slide_targets(tgt_n, tgt_tau, 0, buf, record)
        while i < tgt_n.size:
            cnt[0] = 0
            status, i = self._run(
                self._par, self._tf, self._ti, self._bits, self._lay, self._st,
                self._ist, tgt_n, tgt_tau, i, buf, record, sw, cnt, tan_on, self._y, self._ntan,
                self._mp,
            )  # fmt: skip
            if record and cnt[0]:
                self._chunks.append(sw[: cnt[0]].copy())
            if status == 2:
                raise GrazingError(grazing_message(self._t0 + self.elapsed))
            if status == 3:
                st = self._st
                raise slide.budget_error(
                    self._par, self._t0 + self.elapsed, float(st[kern.S_COS]), float(st[kern.S_Q]),
                    float(st[kern.S_V]), float(st[kern.S_MV]), float(st[kern.S_JMP]),
                    int(st[kern.S_DIR]), budget,
                )  # fmt: skip
            if status == 4:
                st = self._st
                st[kern.S_PJ] = 0.0  # the chattering ends here
                m_now, jump = float(st[kern.S_MV]), float(st[kern.S_JMP])
                direction = int(st[kern.S_DIR])
                self._enter_slide(
                    float(st[kern.S_Q]), float(st[kern.S_V]), m_now, m_now - jump, -direction,
                    record,
                )  # fmt: skip
                i = self._slide_targets(tgt_n, tgt_tau, i, buf, record)
                continue
            if status == 0:
                break
            cap = min(cap * 4, 1 << 20)
            sw = np.empty((cap, 4))
        if out is not None and not direct:
            out[:, :3] = buf

    def kernel_arrays(self) -> tuple | None:
        """``(kind, par, tf, ti, bits, lay, st, ist, y, ntan, mp, sw, cnt, n_relays, omega,
        period)``: what a compiled loop needs to drive :func:`~._relay_kernels.run_table` itself
        with the tangent flow on (:mod:`analysis.dynamics._relay_benettin`; then call
        :meth:`kernel_moved`); ``None`` while the flow is off, sliding or collapsed."""
        if self._ntan == 0 or self._slide is not None or self._collapsed:
            return None
        return (self._kind, self._par, self._tf, self._ti, self._bits, self._lay, self._st,
                self._ist, self._y, self._ntan, self._mp, self._nosw, self._cnt,
                self._n_relays, self._omega, self._period)  # fmt: skip

    def kernel_moved(self) -> None:
        self._state_cache = None

    def relay_outputs(self) -> np.ndarray:
        """Relay outputs now (order of the operator's relay table; zero-weight relays: 0)."""
        if self._kind == kern.KIND_NESTED:
            ya = self._plan.outputs(int(self._ist[kern.I_K]), self._work.n_relays)
        else:
            ya = self._heap.outputs_from_bits(self._bits)
        y = np.zeros(self._table.n_relays)
        y[self._active] = ya
        return y

    def _now(self) -> tuple[float, float, Any]:
        q = float(self._st[kern.S_Q])
        v = float(self._st[kern.S_V])
        y = self.relay_outputs()
        table = self._table
        zero = y == 0.0
        u = q
        # right after a down switch q sits on the threshold that the input has just left
        # below: a zero-width relay there is down although alpha <= q
        if np.any(~zero & (table.alpha <= u) & (y < 0.0)):
            u = float(np.nextafter(q, -np.inf))
        y[zero] = table.initial_outputs(u)[zero]
        opstate = self._op.state_from_relay_outputs(y, u)
        check_state(opstate, f"returned by {type(self._op).__name__}.state_from_relay_outputs")
        return q, v, opstate


class RelayReferenceEngine(RelayEngine):
    """The Python reference loop (``method="generic"``): thresholds from
    ``operator.switching(state)``, switches through ``operator.apply``."""

    def __init__(
        self, system: Any, state: OscillatorState, method: str = "generic", taylor: bool = True
    ) -> None:
        super().__init__(system, state, method, taylor)
        if method not in ("auto", "generic"):
            raise ValueError(f"the reference path is method='generic', got {method!r}")
        self.method = "generic"
        self.name = "relay generic (Python)"
        self._q = float(state.q)
        self._v = float(state.v)
        self._n = 0
        self._tau = 0.0
        self._opstate = self._opstate0
        self._n_switches = 0
        self._switches: list[tuple[float, float, float, float]] = []
        self._integral = 0.0  # ∫M dt since the start
        self._n_relays = int(self._op.n_units)  # for the switch budget
        self._prev_switch = (math.nan, 0.0)  # (threshold, jump) of the previous switch
        self._start_on_sliding_set(self._q, self._v)

    def _other_side(self, theta: float, direction: int) -> tuple[Any, float, float]:
        """(operator state, output, reverse threshold) after moving the input across ``theta``
        in ``direction`` (+1: to θ, switching relays with α = θ up; -1: just below θ)."""
        u = theta if direction > 0 else float(np.nextafter(theta, -np.inf))
        _, st = self._op.apply(np.array([u]), self._opstate)
        sw = self._op.switching(st)
        return st, float(self._op.output(st)), float(sw.lower if direction > 0 else sw.upper)

    def _start_on_sliding_set(self, q: float, v: float) -> None:
        """As :meth:`RelayKernelEngine._start_on_sliding_set`, through ``switching()``."""
        sw = self._op.switching(self._opstate)
        m_now = self.output
        for direction, theta in ((1, float(sw.upper)), (-1, float(sw.lower))):
            if q != theta:
                continue
            _, m_other, back = self._other_side(theta, direction)
            if back != theta:
                continue
            below, above = (m_now, m_other) if direction > 0 else (m_other, m_now)
            c = math.cos(self._phi0)
            par = self._par
            if slide.should_slide(
                q, v, c, par[kern.P_ZETA], par[kern.P_C], below, above, m_now, par[kern.P_SL]
            ):
                self._enter_slide(theta, v, m_now, m_other, direction, False)
                return

    def _slide_set_clock(self, n: int, tau: float, integral: float) -> None:
        self._n, self._tau = n, tau
        self._q, self._v = self._slide.theta, 0.0
        self._integral += integral

    def _slide_switch(self, direction: int) -> None:
        self._opstate = self._other_side(self._slide.theta, direction)[0]

    def _clock(self) -> tuple[int, float]:
        return self._n, self._tau

    @property
    def output(self) -> float:
        """Operator output ``M`` now (``M_eq`` while sliding)."""
        if self._slide is not None:
            return self._slide_output(self._tau)
        return float(self._op.output(self._opstate))

    def output_integral(self) -> float:
        """``∫ M dt`` since the start (``M·h`` summed over the hops)."""
        return self._integral

    @property
    def n_events(self) -> int:
        return self._n_switches

    def _advance(self, times: np.ndarray, out: np.ndarray | None, record: bool) -> None:
        self._state_cache = None
        tgt_n, tgt_tau = split_times(times, self._period)
        y = self._y if self._ntan else None
        span = (int(tgt_n[-1]) - self._n) * self._period + (float(tgt_tau[-1]) - self._tau)
        self._budget = switch_budget(self._n_relays, self._omega, span)
        self._max_switches = self._n_switches + self._budget
        for i in range(tgt_n.size):
            while self._n < tgt_n[i]:
                self._hop_to(self._period, y, record)
                self._tau = 0.0
                self._n += 1
            self._hop_to(float(tgt_tau[i]), y, record)
            if out is not None:
                out[i, :3] = (self._q, self._v, self.output)
        if record and self._switches:
            self._chunks.append(np.array(self._switches, dtype=float).reshape(-1, 4))
            self._switches.clear()

    def _hop_to(self, tau_stop: float, y: np.ndarray | None, record: bool) -> None:
        """Advance to period time ``tau_stop`` switch by switch."""
        par = self._par
        ntan = self._ntan
        zeta, omega, coupling = par[kern.P_ZETA], par[kern.P_OMEGA], par[kern.P_C]
        amp_a, amp_b, phi0 = par[kern.P_A], par[kern.P_B], par[kern.P_PHI0]
        op = self._op
        while True:
            if self._slide is not None and self._slide_to(self._n, tau_stop, record):
                return
            horizon = tau_stop - self._tau
            if horizon <= 0.0:
                return
            sw = op.switching(self._opstate)
            m_old = self.output
            force = coupling * m_old
            ph = phi0 + omega * self._tau
            c, s = math.cos(ph), math.sin(ph)
            up, down = float(sw.upper), float(sw.lower)
            hc, direction = kern.scan_crossing(
                par, force, self._q, self._v, c, s, self._tau, horizon, up, down
            )
            hh = hc if direction != 0 else horizon
            ph1 = phi0 + omega * (self._tau + hh)
            c1, s1 = math.cos(ph1), math.sin(ph1)
            q1, v1 = exact_step(
                self._q, self._v, c, s, c1, s1, force, hh, zeta, omega, amp_a, amp_b
            )
            if y is not None:
                m00, m01, m10, m11 = hom_matrix(hh, zeta)
                pq, pv = (0.0, 0.0)
                if ntan == 3:
                    pq, pv = phase_column(m00, m01, m10, m11, c, s, c1, s1, omega, amp_a, amp_b)
                phi_h = np.array([[m00, m01], [m10, m11]])
                y[:2, :ntan] = phi_h @ y[:2, :ntan] + np.outer((pq, pv), y[2, :ntan])
            self._v = v1
            self._integral += m_old * hh
            if direction == 0:
                self._q = q1
                self._tau = tau_stop
                return
            self._tau += hh
            if direction > 0:
                self._q = up
                _, self._opstate = op.apply(np.array([self._q]), self._opstate)
            else:
                self._q = down
                below = np.nextafter(self._q, -np.inf)
                _, self._opstate = op.apply(np.array([below]), self._opstate)
            jump = self.output - m_old
            self._n_switches += 1
            t = par[kern.P_TBASE] + self._n * par[kern.P_T] + self._tau
            prev_q, prev_jump = self._prev_switch
            self._prev_switch = (self._q, jump)
            if jump != 0.0 and jump == -prev_jump and self._q == prev_q:
                c_now = math.cos(phi0 + omega * self._tau)
                m_now = self.output
                below, above = (m_now - jump, m_now) if direction > 0 else (m_now, m_now - jump)
                if slide.should_slide(
                    self._q, self._v, c_now, zeta, coupling, below, above, m_now, par[kern.P_SL]
                ):
                    self._prev_switch = (math.nan, 0.0)
                    self._enter_slide(self._q, self._v, m_now, m_now - jump, -direction, record)
                    continue
            if record:
                self._switches.append((t, self._q, self._v, jump))
            if self._n_switches >= self._max_switches:
                if record and self._switches:
                    self._chunks.append(np.array(self._switches, dtype=float).reshape(-1, 4))
                    self._switches.clear()
                c_now = math.cos(phi0 + omega * self._tau)
                raise slide.budget_error(
                    par, float(t), c_now, self._q, self._v, self.output, jump, direction,
                    self._budget,
                )  # fmt: skip
            if y is not None:
                if self._v == 0.0 and coupling * jump != 0.0:
                    raise GrazingError(grazing_message(float(t)))
                sal = coupling * jump / self._v if coupling * jump != 0.0 else 0.0
                y[1, :ntan] += sal * y[0, :ntan]

    def relay_outputs(self) -> np.ndarray:
        """Relay outputs now (order of the operator's relay table; an operator without one
        raises ``AttributeError``: read :meth:`state`)."""
        return self._op.relay_outputs(self._opstate)

    def _now(self) -> tuple[float, float, Any]:
        return self._q, self._v, self._opstate
