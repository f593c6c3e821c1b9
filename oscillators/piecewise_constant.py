"""The relay engine: exact event-driven integration of the oscillator with relay operators.

The operator hands over its relays through the contract of :mod:`hysteresis.base`
(``relay_table()``, ``relay_outputs(state)``, ``state_from_relay_outputs(outputs, input)``);
between switches ``q'' + 2ζq' + q = cos φ + C·M`` is linear and solved in closed form, every
threshold crossing is located on that solution (:mod:`oscillators._pc_kernels`: algorithm,
grazing convention, short-hop Taylor expansion) and the tangent flow gets the saltation
``δv += C·ΔM/v*·δq`` at each switch. Methods (``engine_options={"method": ...}``):

* ``"nested"`` — O(1) per switch, when the table's thresholds nest
  (:meth:`hysteresis.relay_table.RelayTable.nested_plan`: equal widths, the paper's dimers);
* ``"heap"`` — any relays (random widths, identified densities, ties, zero widths, weights):
  the next up switch is the smallest ``alpha`` of the down relays, the next down switch the
  largest ``beta`` of the up relays, each kept in a priority queue over the presorted thresholds
  (a 64-ary bitset tree: O(log₆₄ N) per switched relay); relays at one threshold switch
  together; ``M`` in integer weight units when the weights are multiples of one unit, else
  compensated (Neumaier) sums;
* ``"generic"`` — the Python reference path through ``switching(state)`` / ``apply``;
* ``"auto"`` (default) — ``"nested"`` when the plan exists, else ``"heap"``; ``"generic"`` for
  an operator that implements ``switching()``/``apply()`` but not the relay contract.

Relays of zero weight never change ``M`` and are left out of the kernels (the operator state
returned rebuilds them from the staircase).
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np

from oscillators import _pc_kernels as kern
from oscillators.engine import Engine, GrazingError, split_times, wrap_phase
from oscillators.linear import exact_step, hom_matrix, particular_amplitudes, phase_column
from oscillators.results import OscillatorState

__all__ = ["GrazingError", "METHODS", "RelayEngine", "SWITCH_DTYPE"]

SWITCH_DTYPE = np.dtype([("time", "f8"), ("q", "f8"), ("v", "f8"), ("jump", "f8")])
METHODS = ("auto", "nested", "heap", "generic")


def _grazing_message(t: float | None = None) -> str:
    where = f" at t = {t!r}" if t is not None else ""
    return (
        f"grazing switch{where}: a threshold was reached exactly at a turning point (v* = 0), "
        "so the saltation C·ΔM/v* is infinite and the tangent flow is undefined on this orbit; "
        "perturb the initial condition or the parameters"
    )


def _params(system: Any, phi0: float, t_base: float, taylor: bool) -> np.ndarray:
    zeta = float(system.damping_ratio)
    omega = float(system.frequency)
    amp_a, amp_b = particular_amplitudes(zeta, omega)
    return kern.make_params(zeta, omega, float(system.coupling), phi0, amp_a, amp_b, t_base, taylor)


class _Prepared:
    """What the kernels need from a relay table, built once per table (see :func:`_prepared`):
    the relays of positive weight (``active``, as the table ``work``) and their heap form."""

    def __init__(self, table: Any) -> None:
        from hysteresis.relay_table import RelayTable

        self.active = np.flatnonzero(table.weights > 0.0)
        if self.active.size == 0:
            raise ValueError("the operator's relay table has no relay of positive weight")
        if self.active.size < table.n_relays:
            act = self.active
            self.work = RelayTable(table.alpha[act], table.beta[act], table.weights[act])
        else:
            self.work = table
        self._heap: kern.HeapTable | None = None

    def heap(self) -> kern.HeapTable:
        if self._heap is None:
            w = self.work
            self._heap = kern.HeapTable(
                np.asarray(w.alpha), np.asarray(w.beta), np.asarray(w.weights)
            )
        return self._heap


def _has_relay_table(op: Any) -> bool:
    """True if the operator implements the relay contract (not the base-class stub)."""
    from hysteresis.base import PiecewiseConstantHysteron

    impl = getattr(type(op), "relay_table", None)
    return impl is not None and impl is not PiecewiseConstantHysteron.relay_table


@functools.lru_cache(maxsize=16)
def _prepared(table: Any) -> _Prepared:
    """Per-table preparation, cached: engines are rebuilt often (stroboscopic maps, ensembles,
    Lyapunov re-initialisations) and the sorting is O(N log N). Tables are immutable and hashed
    by identity; operators cache their table."""
    return _Prepared(table)


class _Generic:
    """The Python reference loop: thresholds from ``operator.switching(state)``."""

    def __init__(self, op: Any, par: np.ndarray, q: float, v: float, opstate: Any) -> None:
        self.op = op
        self.par = par
        self.q = q
        self.v = v
        self.tau = 0.0
        self.n = 0
        self.opstate = opstate
        self.n_switches = 0
        self.switches: list[tuple[float, float, float, float]] = []
        self.integral = 0.0  # ∫M dt since the start

    @property
    def output(self) -> float:
        return float(self.op.output(self.opstate))

    def advance(self, tau_stop: float, y: np.ndarray | None, ntan: int, record: bool) -> None:
        par = self.par
        zeta, omega, coupling = par[kern.P_ZETA], par[kern.P_OMEGA], par[kern.P_C]
        amp_a, amp_b, phi0 = par[kern.P_A], par[kern.P_B], par[kern.P_PHI0]
        while True:
            horizon = tau_stop - self.tau
            if horizon <= 0.0:
                return
            sw = self.op.switching(self.opstate)
            m_old = self.output
            force = coupling * m_old
            ph = phi0 + omega * self.tau
            c, s = math.cos(ph), math.sin(ph)
            up, down = float(sw.upper), float(sw.lower)
            hc, direction = kern.scan_crossing(
                par, force, self.q, self.v, c, s, self.tau, horizon, up, down
            )
            hh = hc if direction != 0 else horizon
            ph1 = phi0 + omega * (self.tau + hh)
            c1, s1 = math.cos(ph1), math.sin(ph1)
            q1, v1 = exact_step(self.q, self.v, c, s, c1, s1, force, hh, zeta, omega, amp_a, amp_b)
            if y is not None:
                m00, m01, m10, m11 = hom_matrix(hh, zeta)
                pq, pv = (0.0, 0.0)
                if ntan == 3:
                    pq, pv = phase_column(m00, m01, m10, m11, c, s, c1, s1, omega, amp_a, amp_b)
                phi_h = np.array([[m00, m01], [m10, m11]])
                y[:2, :ntan] = phi_h @ y[:2, :ntan] + np.outer((pq, pv), y[2, :ntan])
            self.v = v1
            self.integral += m_old * hh
            if direction == 0:
                self.q = q1
                self.tau = tau_stop
                return
            self.tau += hh
            if direction > 0:
                self.q = up
                _, self.opstate = self.op.apply(np.array([self.q]), self.opstate)
            else:
                self.q = down
                below = np.nextafter(self.q, -np.inf)
                _, self.opstate = self.op.apply(np.array([below]), self.opstate)
            jump = self.output - m_old
            self.n_switches += 1
            t = par[kern.P_TBASE] + self.n * par[kern.P_T] + self.tau
            if record:
                self.switches.append((t, self.q, self.v, jump))
            if y is not None:
                if self.v == 0.0 and coupling * jump != 0.0:
                    raise GrazingError(_grazing_message(float(t)))
                sal = coupling * jump / self.v if coupling * jump != 0.0 else 0.0
                y[1, :ntan] += sal * y[0, :ntan]


class RelayEngine(Engine):
    """Event-driven engine for piecewise-constant operators (see the module docstring).

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

    def __init__(
        self, system: Any, state: OscillatorState, method: str = "auto", taylor: bool = True
    ) -> None:
        super().__init__(system, state)
        if method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}, got {method!r}")
        q0, v0, phi0 = float(state.q), float(state.v), float(state.phi)
        t0 = float(state.t)
        if not all(math.isfinite(x) for x in (q0, v0, phi0, t0)):
            raise ValueError("the start state (q, v, phi, t) must be finite")
        op = system.operator
        self._op = op
        opstate = state.operator_state
        if opstate is None:
            opstate = op.initial_state(q0)
        _, opstate = op.apply(np.array([q0]), opstate)
        self._par = _params(system, phi0, t0, taylor)
        self._period = float(self._par[kern.P_T])
        self._omega = float(system.frequency)
        self._phi0 = phi0
        self._t0 = t0
        self._ntan = 0
        self._y = np.zeros((3, 3))
        self._mp = kern.taylor_matrix_coefficients(
            float(system.damping_ratio), float(system.frequency)
        )
        self._chunks: list[np.ndarray] = []
        self._state_cache: OscillatorState | None = None
        self._tn1 = np.zeros(1, dtype=np.int64)
        self._tt1 = np.zeros(1)
        self._nobuf = np.empty((0, 3))
        self._nosw = np.empty((1, 4))
        self._cnt = np.zeros(1, dtype=np.int64)
        self._generic: _Generic | None = None
        if method == "auto" and not _has_relay_table(op):
            method = "generic"  # an operator known through switching()/apply() only
        if method == "generic":
            self._generic = _Generic(op, self._par, q0, v0, opstate)
            self.method = "generic"
            self.name = "relay generic (Python)"
            return
        table = op.relay_table()
        y0 = table.check_outputs(op.relay_outputs(opstate), q0)
        self._table = table
        prep = _prepared(table)
        self._active = prep.active
        work = prep.work
        self._work = work
        ya = y0[self._active]
        st = np.zeros(kern.N_ST)
        st[: kern.S_SIN + 1] = (q0, v0, 0.0, math.cos(phi0), math.sin(phi0))
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
            heap = prep.heap()
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

    # -- motion --------------------------------------------------------------------------------
    @property
    def elapsed(self) -> float:
        if self._generic is not None:
            return self._generic.n * self._period + self._generic.tau
        return int(self._ist[kern.I_N]) * self._period + float(self._st[kern.S_TAU])

    @property
    def output(self) -> float:
        """Operator output ``M`` now."""
        if self._generic is not None:
            return self._generic.output
        return float(self._st[kern.S_MV])

    def output_integral(self) -> float:
        """``∫ M dt`` since the start, exact: ``M`` is constant between switches, so the kernel
        adds ``M·h`` for every hop ``h``."""
        if self._generic is not None:
            return self._generic.integral
        return float(self._st[kern.S_IM])

    def advance(
        self, times: np.ndarray | float, out: np.ndarray | None = None, record: bool = False
    ) -> None:
        if type(times) is float or np.size(times) == 1:
            # one target (the Lyapunov stepper's case): no array bookkeeping on the way in
            if type(times) is not float:
                if np.ndim(times) > 1:
                    raise ValueError("times must be a scalar or a 1-D array")
                times = float(np.reshape(times, -1)[0])
            t = times
            if not math.isfinite(t):
                raise ValueError("times must be finite")
            tgt_n, tgt_tau = self._tn1, self._tt1
            n = math.floor(t / self._period)
            tau = t - n * self._period
            if tau >= self._period:
                n, tau = n + 1, 0.0
            tgt_n[0], tgt_tau[0] = n, max(tau, 0.0)
            first = t
        else:
            times = np.asarray(times, dtype=np.float64)
            if times.ndim != 1:
                raise ValueError("times must be a scalar or a 1-D array")
            if times.size == 0:
                return
            if not np.all(np.isfinite(times)):
                raise ValueError("times must be finite")
            if np.any(np.diff(times) < 0.0):
                raise ValueError("times must be sorted")
            tgt_n, tgt_tau = split_times(times, self._period)
            first = float(times[0])
        now = self.elapsed
        if first < now - 1e-12 * max(1.0, abs(now)):
            raise ValueError(f"times must be >= the current elapsed time {now!r}, got {first!r}")
        if out is not None and (out.ndim != 2 or out.shape[0] != tgt_n.size or out.shape[1] < 3):
            raise ValueError(f"out must have shape ({tgt_n.size}, >= 3), got {out.shape}")
        self._state_cache = None
        if self._generic is not None:
            self._advance_generic(tgt_n, tgt_tau, out, record)
            return
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
        cap = 1 << 12 if record else 1
        sw = np.empty((cap, 4)) if record else self._nosw
        cnt = self._cnt
        i = 0
        while True:
            cnt[0] = 0
            status, i = self._run(
                self._par, self._tf, self._ti, self._bits, self._lay, self._st,
                self._ist, tgt_n, tgt_tau, i, buf, record, sw, cnt, tan_on, self._y, self._ntan,
                self._mp,
            )  # fmt: skip
            if record and cnt[0]:
                self._chunks.append(sw[: cnt[0]].copy())
            if status == 2:
                raise GrazingError(_grazing_message(self._t0 + self.elapsed))
            if status == 0:
                break
            cap = min(cap * 4, 1 << 20)
            sw = np.empty((cap, 4))
        if out is not None and not direct:
            out[:, :3] = buf

    def _advance_generic(self, tgt_n, tgt_tau, out, record) -> None:
        g = self._generic
        y = self._y if self._ntan else None
        for i in range(tgt_n.size):
            while g.n < tgt_n[i]:
                g.advance(self._period, y, self._ntan, record)
                g.tau = 0.0
                g.n += 1
            g.advance(float(tgt_tau[i]), y, self._ntan, record)
            if out is not None:
                out[i, :3] = (g.q, g.v, g.output)
        if record and g.switches:
            self._chunks.append(np.array(g.switches, dtype=float).reshape(-1, 4))
            g.switches.clear()

    def relay_outputs(self) -> np.ndarray:
        """Relay outputs now (order of the operator's relay table; zero-weight relays: 0)."""
        if self._generic is not None:
            return self._op.relay_outputs(self._generic.opstate)
        n = self._table.n_relays
        if self._kind == kern.KIND_NESTED:
            ya = self._plan.outputs(int(self._ist[kern.I_K]), self._work.n_relays)
        else:
            ya = self._heap.outputs_from_bits(self._bits)
        y = np.zeros(n)
        y[self._active] = ya
        return y

    def state(self) -> OscillatorState:
        if self._state_cache is not None:
            return self._state_cache
        if self._generic is not None:
            g = self._generic
            q, v, tau, opstate = g.q, g.v, g.tau, g.opstate
        else:
            q = float(self._st[kern.S_Q])
            v = float(self._st[kern.S_V])
            tau = float(self._st[kern.S_TAU])
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
        phi = wrap_phase(self._phi0 + self._omega * tau)
        self._state_cache = OscillatorState(
            q=q, v=v, phi=phi, operator_state=opstate, t=self._t0 + self.elapsed
        )
        return self._state_cache

    def records(self) -> dict[str, np.ndarray]:
        sw = np.concatenate(self._chunks) if self._chunks else np.empty((0, 4))
        rec = np.empty(sw.shape[0], dtype=SWITCH_DTYPE)
        for j, name in enumerate(SWITCH_DTYPE.names):
            rec[name] = sw[:, j]
        return {"switches": rec}

    @property
    def n_events(self) -> int:
        if self._generic is not None:
            return self._generic.n_switches
        return int(self._ist[kern.I_NSW])

    # -- tangent flow --------------------------------------------------------------------------
    def start_tangent(self, include_phase: bool = False) -> None:
        self._ntan = 3 if include_phase else 2
        self._y[:, :] = 0.0
        for j in range(self._ntan):
            self._y[j, j] = 1.0

    @property
    def tangent_space(self) -> tuple[str, ...]:
        return ("q", "v", "phi")[: self._ntan]

    def deviations(self) -> np.ndarray:
        self._need_tangent()
        return self._y[: self._ntan, : self._ntan].copy()

    def set_deviations(self, y: np.ndarray) -> None:
        self._need_tangent()
        y = np.asarray(y, dtype=np.float64)
        if y.shape != (self._ntan, self._ntan):
            raise ValueError(
                f"deviations must have shape {(self._ntan, self._ntan)}, got {y.shape}"
            )
        self._y[: self._ntan, : self._ntan] = y

    def rank_bound(self) -> int:
        # relays have no memory directions and every saltation matrix is invertible
        return self._ntan

    def _need_tangent(self) -> None:
        if self._ntan == 0:
            raise ValueError("the tangent flow is off: call start_tangent() first")
