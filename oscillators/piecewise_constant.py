"""Event-driven, exact integration of the oscillator with a piecewise-constant operator.

Between switches the equation ``q'' + 2ζq' + q = cos φ + C·M_k`` is linear and solved in closed
form (:mod:`oscillators.linear`); every threshold crossing is located on that solution (see
:mod:`oscillators._pc_kernels` for the algorithm, the grazing convention and the short-hop Taylor
expansion). Two engines:

* **equal-width kernel** (numba, O(1) per switch): discrete Preisach models whose relays can be
  ordered so that the upper and the lower thresholds increase together — every equal-width model,
  in particular the paper's spin dimers (``SpinDimerEnsemble.to_preisach()`` with all dimers
  hysteretic) and a single :class:`~hysteresis.relay.Relay`. The reachable relay states are then
  prefixes of that order and the state is one index ``k``.
* **generic** (Python): any :class:`~hysteresis.base.PiecewiseConstantHysteron`, driven through
  ``switching(state)`` and ``apply([u], state)``; same exact crossing search.

Time is kept as (period index, time within the period) so the forcing phase stays exact.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from oscillators import _pc_kernels as kern
from oscillators.engine import Engine, GrazingError, split_times, wrap_phase
from oscillators.linear import exact_step, hom_matrix, particular_amplitudes, phase_column
from oscillators.results import OscillatorState

__all__ = [
    "GrazingError",
    "EqualWidthPlan",
    "RelayEngine",
    "equal_width_plan",
    "SWITCH_DTYPE",
]

SWITCH_DTYPE = np.dtype([("time", "f8"), ("q", "f8"), ("v", "f8"), ("jump", "f8")])


def _grazing_message(t: float | None = None) -> str:
    where = f" at t = {t!r}" if t is not None else ""
    return (
        f"grazing switch{where}: a threshold was reached exactly at a turning point (v* = 0), "
        "so the saltation C·ΔM/v* is infinite and the tangent flow is undefined on this orbit; "
        "perturb the initial condition or the parameters"
    )


# -- equal-width plan -------------------------------------------------------------------------
@dataclass(frozen=True)
class EqualWidthPlan:
    """Relays grouped by identical thresholds, sorted; ``mval[k]`` = output with k groups up."""

    up: np.ndarray
    down: np.ndarray
    mval: np.ndarray

    @property
    def n_groups(self) -> int:
        return int(self.up.size)

    def index_at(self, q: float) -> int:
        """Index reached by rising from negative saturation to ``q`` (groups with up <= q)."""
        return int(np.searchsorted(self.up, q, side="right"))


def _relay_arrays(operator: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """(alpha, beta, weights) of a discrete relay system, or None."""
    from hysteresis.relay import Relay

    if isinstance(operator, Relay):
        return np.array([operator.alpha]), np.array([operator.beta]), np.array([1.0])
    model = operator
    to_preisach = getattr(operator, "to_preisach", None)
    if to_preisach is not None:
        model = to_preisach()
    alpha = getattr(model, "alpha", None)
    beta = getattr(model, "beta", None)
    weights = getattr(model, "weights", None)
    if alpha is None or beta is None or weights is None:
        return None
    alpha = np.asarray(alpha, dtype=float)
    beta = np.asarray(beta, dtype=float)
    weights = np.asarray(weights, dtype=float)
    if alpha.ndim != 1 or alpha.shape != beta.shape or alpha.shape != weights.shape:
        return None
    return alpha, beta, weights


def equal_width_plan(operator: Any) -> EqualWidthPlan | None:
    """The O(1)-per-switch plan of a relay system, or None if its thresholds do not nest.

    Eligible: after grouping relays with identical (alpha, beta), both the upper and the lower
    thresholds increase strictly along the order (true for equal widths).
    """
    arrays = _relay_arrays(operator)
    if arrays is None:
        return None
    alpha, beta, weights = arrays
    order = np.lexsort((beta, alpha))
    a = alpha[order]
    b = beta[order]
    w = weights[order]
    new_group = np.ones(a.size, dtype=bool)
    new_group[1:] = (a[1:] != a[:-1]) | (b[1:] != b[:-1])
    starts = np.flatnonzero(new_group)
    up = a[starts]
    down = b[starts]
    gw = np.add.reduceat(w, starts)
    if up.size > 1 and (np.any(np.diff(up) <= 0.0) or np.any(np.diff(down) <= 0.0)):
        return None
    # output with the first k groups up, the rest down: M = sum(up w) - sum(down w)
    total = float(np.sum(w))
    if np.all(w == w[0]):
        # equal weights (dimers: M_k = 4k/N - 1 for Σw = 1): exact integer counting, no
        # summation drift; scaled by Σw like the unequal-weight branch
        counts = np.concatenate([[0], np.cumsum(np.diff(np.append(starts, a.size)))])
        mval = (2.0 * counts - a.size) / a.size * total
    else:
        cum = np.concatenate([[0.0], np.cumsum(gw)])
        mval = 2.0 * cum - total
    return EqualWidthPlan(up=up, down=down, mval=mval)


def _state_from_index(operator: Any, plan: EqualWidthPlan, k: int, q: float) -> Any:
    """An operator state with the first k groups up, current input q (built by an input path)."""
    if k == 0:
        return operator.initial_state(q)
    u1 = float(plan.up[k - 1])
    state = operator.initial_state(u1)
    _, state = operator.apply(np.array([u1, q]), state)
    return state


def _index_from_state(operator: Any, plan: EqualWidthPlan, q0: float, state: Any) -> int | None:
    """Index k of an operator state at input q0, or None if the state is not a prefix state."""
    if state is None:
        return plan.index_at(q0)
    _, state = operator.apply(np.array([q0]), state)
    m = float(operator.output(state))
    k = int(np.argmin(np.abs(plan.mval - m)))
    if abs(plan.mval[k] - m) > 1e-9:
        return None
    rebuilt = _state_from_index(operator, plan, k, q0)
    relay_states = getattr(operator, "relay_states", None)
    if relay_states is None and hasattr(operator, "to_preisach"):
        relay_states = getattr(operator.to_preisach(), "relay_states", None)
    if relay_states is not None:
        if not np.array_equal(np.asarray(relay_states(state)), np.asarray(relay_states(rebuilt))):
            return None
    return k


# -- targets (period index, time in period) ---------------------------------------------------
def _params(system: Any, phi0: float, t_base: float, taylor: bool = True) -> np.ndarray:
    zeta = float(system.damping_ratio)
    omega = float(system.frequency)
    amp_a, amp_b = particular_amplitudes(zeta, omega)
    return kern.make_params(zeta, omega, float(system.coupling), phi0, amp_a, amp_b, t_base, taylor)


# -- generic engine (Python, any piecewise-constant operator) -----------------------------------
class _GenericEngine:
    """Same event loop as the kernel, thresholds from ``operator.switching(state)``."""

    def __init__(self, system: Any, par: np.ndarray, q: float, v: float, opstate: Any) -> None:
        self.op = system.operator
        self.par = par
        self.q = float(q)
        self.v = float(v)
        self.tau = 0.0
        self.n = 0
        self.opstate = opstate
        self.n_switches = 0
        self.switches: list[tuple[float, float, float, float]] = []

    @property
    def output(self) -> float:
        return float(self.op.output(self.opstate))

    def advance(
        self, tau_stop: float, y: np.ndarray | None = None, ntan: int = 0, record: bool = False
    ) -> None:
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
            hc, direction = kern.scan_crossing(
                par,
                force,
                self.q,
                self.v,
                c,
                s,
                self.tau,
                horizon,
                float(sw.upper),
                float(sw.lower),
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
                kern._tangent_update(y, ntan, m00, m01, m10, m11, pq, pv)
            self.v = v1
            if direction == 0:
                self.q = q1
                self.tau = tau_stop
                return
            self.tau += hh
            if direction > 0:
                self.q = float(sw.upper)
                _, self.opstate = self.op.apply(np.array([self.q]), self.opstate)
            else:
                self.q = float(sw.lower)
                below = np.nextafter(self.q, -np.inf)
                _, self.opstate = self.op.apply(np.array([below]), self.opstate)
            jump = self.output - m_old
            if y is not None:
                if self.v == 0.0 and coupling * jump != 0.0:
                    t = par[kern.P_TBASE] + self.n * par[kern.P_T] + self.tau
                    raise GrazingError(_grazing_message(float(t)))
                sal = coupling * jump / self.v if coupling * jump != 0.0 else 0.0
                y[1, :ntan] += sal * y[0, :ntan]
            self.n_switches += 1
            if record:
                t = par[kern.P_TBASE] + self.n * par[kern.P_T] + self.tau
                self.switches.append((t, self.q, self.v, jump))

    def wrap(self) -> None:
        self.tau = 0.0
        self.n += 1

    def run_targets(self, tgt_n, tgt_tau, out, record, y=None, ntan=0, on_target=None):
        period = self.par[kern.P_T]
        for i in range(tgt_n.size):
            while self.n < tgt_n[i]:
                self.advance(period, y, ntan, record)
                self.wrap()
            self.advance(float(tgt_tau[i]), y, ntan, record)
            if out is not None:
                out[i] = (self.q, self.v, self.output)
            if on_target is not None:
                on_target(i)


# -- shared preparation -----------------------------------------------------------------------
@dataclass
class _Run:
    plan: EqualWidthPlan | None
    par: np.ndarray
    st: np.ndarray | None
    ist: np.ndarray | None
    engine: _GenericEngine | None

    def final(self, system: Any) -> tuple[float, float, float, Any, int]:
        """(q, v, tau, operator state, n_switches)."""
        if self.engine is not None:
            e = self.engine
            return e.q, e.v, e.tau, e.opstate, e.n_switches
        q = float(self.st[kern.S_Q])
        state = _state_from_index(system.operator, self.plan, int(self.ist[kern.I_K]), q)
        return (
            q,
            float(self.st[kern.S_V]),
            float(self.st[kern.S_TAU]),
            state,
            int(self.ist[kern.I_NSW]),
        )

    def final_state(self, system: Any) -> OscillatorState:
        q, v, tau, opstate, _ = self.final(system)
        n = self.engine.n if self.engine is not None else int(self.ist[kern.I_N])
        period = float(self.par[kern.P_T])
        phi0 = float(self.par[kern.P_PHI0])
        # wrap to [0, 2π) like the play path (math.fmod keeps the sign: φ < 0 for phi0 < 0)
        phi = wrap_phase(phi0 + float(system.frequency) * tau)
        return OscillatorState(
            q=q,
            v=v,
            phi=phi,
            operator_state=opstate,
            t=float(self.par[kern.P_TBASE]) + n * period + tau,
        )


def _prepare(
    system: Any,
    q0: float,
    v0: float,
    phi0: float,
    operator_state: Any,
    t_base: float,
    engine: str,
    taylor: bool = True,
) -> _Run:
    if engine not in ("auto", "kernel", "generic"):
        raise ValueError(f"engine must be 'auto', 'kernel' or 'generic', got {engine!r}")
    q0 = float(q0)
    v0 = float(v0)
    if not (math.isfinite(q0) and math.isfinite(v0) and math.isfinite(phi0)):
        raise ValueError("q0, v0 and phi0 must be finite")
    par = _params(system, phi0, t_base, taylor)
    op = system.operator
    plan = equal_width_plan(op) if engine != "generic" else None
    k = None
    if plan is not None:
        k = _index_from_state(op, plan, q0, operator_state)
    if plan is None or k is None:
        if engine == "kernel":
            raise ValueError("engine='kernel' needs an equal-width relay system in a prefix state")
        opstate = op.initial_state(q0) if operator_state is None else operator_state
        _, opstate = op.apply(np.array([q0]), opstate)
        return _Run(None, par, None, None, _GenericEngine(system, par, q0, v0, opstate))
    st = np.array([q0, v0, 0.0, math.cos(phi0), math.sin(phi0)])
    ist = np.array([k, 0, 0], dtype=np.int64)
    return _Run(plan, par, st, ist, None)


def _run_targets(run: _Run, tgt_n, tgt_tau, record: bool) -> tuple[np.ndarray, np.ndarray]:
    """Drive either engine through the targets; returns samples (q, v, M) and switches."""
    out = np.empty((tgt_n.size, 3))
    if run.engine is not None:
        run.engine.run_targets(tgt_n, tgt_tau, out, record)
        sw = np.array(run.engine.switches, dtype=float).reshape(-1, 4)
        return out, sw
    plan = run.plan
    chunks = []
    cap = 1 << 16 if record else 1
    i = 0
    while True:
        sw = np.empty((cap, 4))
        cnt = np.zeros(1, dtype=np.int64)
        status, i = kern.run_targets(
            run.par,
            plan.up,
            plan.down,
            plan.mval,
            run.st,
            run.ist,
            tgt_n,
            tgt_tau,
            i,
            out,
            record,
            sw,
            cnt,
        )
        if record:
            chunks.append(sw[: cnt[0]].copy())
        if status == 0:
            break
        cap = min(cap * 2, 1 << 22)
    swa = np.concatenate(chunks) if chunks else np.empty((0, 4))
    return out, swa


def _switch_array(sw: np.ndarray) -> np.ndarray:
    rec = np.empty(sw.shape[0], dtype=SWITCH_DTYPE)
    rec["time"], rec["q"], rec["v"], rec["jump"] = sw.T if sw.size else ([],) * 4
    return rec


# -- the engine ------------------------------------------------------------------------------
class RelayEngine(Engine):
    """Event-driven engine for piecewise-constant operators (see the module docstring).

    ``method``: ``"auto"`` (the compiled kernel when the thresholds nest, else the generic
    path), ``"nested"`` (require the kernel) or ``"generic"`` (the Python reference path through
    ``switching()``/``apply()``). ``taylor=False`` disables the short-hop Taylor expansion
    (exact propagator everywhere; a cross-check).
    """

    name = "relay"

    def __init__(
        self, system: Any, state: OscillatorState, method: str = "auto", taylor: bool = True
    ) -> None:
        super().__init__(system, state)
        methods = {"auto": "auto", "nested": "kernel", "kernel": "kernel", "generic": "generic"}
        if method not in methods:
            raise ValueError(f"method must be one of {sorted(methods)}, got {method!r}")
        self._run = _prepare(
            system,
            state.q,
            state.v,
            float(state.phi),
            state.operator_state,
            float(state.t),
            methods[method],
            taylor,
        )
        self.name = "relay generic" if self._run.engine is not None else "relay kernel"
        self._period = float(self._run.par[kern.P_T])
        self._chunks: list[np.ndarray] = []
        self._y: np.ndarray | None = None
        self._ntan = 0
        self._mp = kern.taylor_matrix_coefficients(float(system.damping_ratio))

    # -- motion
    @property
    def elapsed(self) -> float:
        run = self._run
        if run.engine is not None:
            return run.engine.n * self._period + run.engine.tau
        return int(run.ist[kern.I_N]) * self._period + float(run.st[kern.S_TAU])

    def _output(self) -> float:
        run = self._run
        if run.engine is not None:
            return run.engine.output
        return float(run.plan.mval[int(run.ist[kern.I_K])])

    def _qv(self) -> tuple[float, float]:
        run = self._run
        if run.engine is not None:
            return run.engine.q, run.engine.v
        return float(run.st[kern.S_Q]), float(run.st[kern.S_V])

    def advance(
        self, times: np.ndarray | float, out: np.ndarray | None = None, record: bool = False
    ) -> None:
        times = np.atleast_1d(np.asarray(times, dtype=np.float64))
        tgt_n, tgt_tau = split_times(times, self._period)
        run = self._run
        if self._y is None:
            o, sw = _run_targets(run, tgt_n, tgt_tau, record)
            if out is not None:
                out[:, :3] = o
            if record and sw.size:
                self._chunks.append(sw)
            return
        if record:
            raise ValueError("record=True with the tangent flow on is not supported")
        y, ntan = self._y, self._ntan
        for i in range(tgt_n.size):
            n1, t1 = tgt_n[i : i + 1], tgt_tau[i : i + 1]
            if run.engine is not None:
                run.engine.run_targets(n1, t1, None, False, y, ntan)
            else:
                kern.run_tangent(
                    run.par,
                    run.plan.up,
                    run.plan.down,
                    run.plan.mval,
                    run.st,
                    run.ist,
                    n1,
                    t1,
                    np.zeros(1),
                    np.zeros(1, dtype=np.bool_),
                    0,
                    y,
                    ntan,
                    self._mp,
                    np.zeros(3),
                    np.zeros((0, 3)),
                    np.zeros(1, dtype=np.int64),
                    False,
                )
                if not np.all(np.isfinite(y)):
                    # the kernel applies sal = inf at v* = 0; report it instead of NaN
                    raise GrazingError(_grazing_message())
            if out is not None:
                q, v = self._qv()
                out[i, :3] = (q, v, self._output())

    def state(self) -> OscillatorState:
        return self._run.final_state(self.system)

    def records(self) -> dict[str, np.ndarray]:
        run = self._run
        if run.engine is not None:
            sw = np.array(run.engine.switches, dtype=float).reshape(-1, 4)
        else:
            sw = np.concatenate(self._chunks) if self._chunks else np.empty((0, 4))
        return {"switches": _switch_array(sw)}

    @property
    def n_events(self) -> int:
        run = self._run
        if run.engine is not None:
            return int(run.engine.n_switches)
        return int(run.ist[kern.I_NSW])

    # -- tangent flow
    def start_tangent(self, include_phase: bool = False) -> None:
        self._ntan = 3 if include_phase else 2
        self._y = np.zeros((3, 3))
        for j in range(self._ntan):
            self._y[j, j] = 1.0

    @property
    def tangent_space(self) -> tuple[str, ...]:
        return ("q", "v", "phi")[: self._ntan]

    def deviations(self) -> np.ndarray:
        if self._y is None:
            raise RuntimeError("start_tangent() first")
        return self._y[: self._ntan, : self._ntan].copy()

    def set_deviations(self, y: np.ndarray) -> None:
        if self._y is None:
            raise RuntimeError("start_tangent() first")
        y = np.asarray(y, dtype=np.float64)
        if y.shape != (self._ntan, self._ntan):
            raise ValueError(
                f"deviations must have shape {(self._ntan, self._ntan)}, got {y.shape}"
            )
        self._y[: self._ntan, : self._ntan] = y

    def rank_bound(self) -> int:
        # relay systems carry no memory directions; the saltation has determinant 1
        return self._ntan
