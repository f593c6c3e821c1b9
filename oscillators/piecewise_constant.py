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

from hysteresis._validation import nonnegative_integer, positive_integer
from oscillators import _pc_kernels as kern
from oscillators.linear import exact_step, hom_matrix, particular_amplitudes, phase_column
from oscillators.results import OscillatorState, PoincareSection, TangentResult, Trajectory

__all__ = [
    "GrazingError",
    "EqualWidthPlan",
    "equal_width_plan",
    "pc_trajectory",
    "pc_poincare",
    "pc_tangent",
    "pc_jacobian",
    "SWITCH_DTYPE",
]

SWITCH_DTYPE = np.dtype([("time", "f8"), ("q", "f8"), ("v", "f8"), ("jump", "f8")])


class GrazingError(ValueError):
    """A switch at a turning point (``v* = 0``) while the tangent flow is propagated.

    The kernels' grazing rule (:mod:`oscillators._pc_kernels`) makes a maximum that reaches an
    upper threshold switch; the saltation ``C·ΔM/v*`` of that switch is infinite, so the flow map
    is not differentiable on this orbit and Lyapunov exponents / Jacobians are undefined. A
    ``ValueError`` subclass so that callers reporting bad input also report this.
    """


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
def _split_times(times: np.ndarray, period: float) -> tuple[np.ndarray, np.ndarray]:
    n = np.floor(times / period).astype(np.int64)
    tau = times - n * period
    fix = tau >= period
    n[fix] += 1
    tau[fix] = 0.0
    tau[tau < 0.0] = 0.0
    return n, tau


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


def _wrap_phase(phi: float) -> float:
    """``phi`` mod 2π in [0, 2π)."""
    two_pi = 2.0 * math.pi
    wrapped = math.fmod(phi, two_pi)
    if wrapped < 0.0:
        wrapped += two_pi
    # fmod of a tiny negative number plus 2π rounds to exactly 2π
    return 0.0 if wrapped >= two_pi else wrapped


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
        phi = _wrap_phase(phi0 + float(system.frequency) * tau)
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


# -- public drivers ---------------------------------------------------------------------------
def pc_trajectory(
    system: Any,
    t_end: float,
    q0: float = -1.0,
    v0: float = 0.1,
    operator_state: Any = None,
    sample_dt: float = 0.01,
    phi0: float = 0.0,
    t0: float = 0.0,
    engine: str = "auto",
    taylor: bool = True,
) -> Trajectory:
    """Samples every ``sample_dt`` on [t0, t0 + t_end] plus the exact list of switches."""
    t_end = float(t_end)
    sample_dt = float(sample_dt)
    if not math.isfinite(t_end) or t_end <= 0.0:
        raise ValueError(f"t_end must be finite and > 0, got {t_end}")
    if not math.isfinite(sample_dt) or sample_dt <= 0.0:
        raise ValueError(f"sample_dt must be finite and > 0, got {sample_dt}")
    run = _prepare(system, q0, v0, phi0, operator_state, t0, engine, taylor)
    n = int(math.floor(t_end / sample_dt + 1e-9))
    times = np.arange(n + 1) * sample_dt
    if times[-1] < t_end * (1 - 1e-12):
        times = np.append(times, t_end)
    tgt_n, tgt_tau = _split_times(times, float(run.par[kern.P_T]))
    out, sw = _run_targets(run, tgt_n, tgt_tau, True)
    omega = float(system.frequency)
    phi = np.mod(phi0 + omega * tgt_tau, 2.0 * np.pi)
    return Trajectory(
        t=t0 + times,
        q=out[:, 0],
        v=out[:, 1],
        phi=phi,
        M=out[:, 2],
        switches=_switch_array(sw),
        final=run.final_state(system),
    )


def pc_poincare(
    system: Any,
    n_periods: int,
    transient_periods: int = 0,
    q0: float = -1.0,
    v0: float = 0.1,
    operator_state: Any = None,
    engine: str = "auto",
    taylor: bool = True,
) -> PoincareSection:
    """Stroboscopic points at t = (transient_periods + i)·T, i = 0..n_periods-1 (φ = 0)."""
    n_periods = positive_integer(n_periods, "n_periods")
    transient_periods = nonnegative_integer(transient_periods, "transient_periods")
    run = _prepare(system, q0, v0, 0.0, operator_state, 0.0, engine, taylor)
    tgt_n = transient_periods + np.arange(n_periods, dtype=np.int64)
    tgt_tau = np.zeros(n_periods)
    out, _ = _run_targets(run, tgt_n, tgt_tau, False)
    _, _, _, _, nsw = run.final(system)
    return PoincareSection(
        q=out[:, 0], v=out[:, 1], M=out[:, 2], final=run.final_state(system), n_switches=nsw
    )


def pc_stroboscopic_map(
    system: Any, state: OscillatorState, engine: str = "auto"
) -> OscillatorState:
    """The state one forcing period after ``state``."""
    run = _prepare(
        system, state.q, state.v, float(state.phi), state.operator_state, float(state.t), engine
    )
    _run_targets(run, np.array([1], dtype=np.int64), np.zeros(1), False)
    return run.final_state(system)


def _tangent_targets(
    t_start: float, t_stop: float, period: float, qr_per_period: int, history_points: int
):
    dt = period / qr_per_period
    n_qr = max(1, int(math.ceil((t_stop - t_start) / dt - 1e-9)))
    times = t_start + dt * np.arange(1, n_qr + 1)
    times[-1] = t_stop
    elapsed = times - t_start
    flags = np.zeros(n_qr, dtype=np.bool_)
    idx = np.unique(np.linspace(0, n_qr - 1, min(history_points, n_qr)).round().astype(int))
    flags[idx] = True
    return times, elapsed, flags


def pc_tangent(
    system: Any,
    t_end: float,
    transient: float = 0.0,
    q0: float = -1.0,
    v0: float = 0.1,
    operator_state: Any = None,
    include_phase: bool = False,
    progress: bool = True,
    qr_per_period: int = 8,
    history_points: int = 200,
    engine: str = "auto",
    taylor: bool = True,
) -> TangentResult:
    """Lyapunov spectrum by QR (Benettin/Geist), averaged over [transient, t_end].

    Tangent space (δq, δv) — or (δq, δv, δφ) with ``include_phase`` — propagated with the closed
    form fundamental matrices of the segments and the saltation matrix at every switch.
    ``exponents`` (and the columns of ``history``) are in descending order; ``labels`` names the
    tangent-space basis, ``("q", "v")`` or ``("q", "v", "phi")``, in this fixed order — after the
    QR re-orthonormalisation an exponent is not tied to one basis direction, so ``labels`` is not
    a per-exponent tag (same convention as :func:`oscillators.play_flow.play_tangent`).

    A switch reached exactly at a turning point (grazing, ``v* = 0``) makes the saltation
    ``C·ΔM/v*`` infinite: the flow is not differentiable there and a ``FloatingPointError`` is
    raised instead of returning NaN exponents.
    """
    t_end = float(t_end)
    transient = float(transient)
    if not math.isfinite(transient) or transient < 0.0:
        raise ValueError(f"transient must be finite and >= 0, got {transient}")
    if not math.isfinite(t_end) or t_end <= transient:
        raise ValueError(f"t_end must be finite and > transient={transient}, got {t_end}")
    run = _prepare(system, q0, v0, 0.0, operator_state, 0.0, engine, taylor)
    period = float(run.par[kern.P_T])
    if transient > 0.0:
        tn, tt = _split_times(np.array([transient]), period)
        _run_targets(run, tn, tt, False)
    ntan = 3 if include_phase else 2
    labels = ("q", "v", "phi")[:ntan]
    y = np.zeros((3, 3))
    for j in range(ntan):
        y[j, j] = 1.0
    times, elapsed, flags = _tangent_targets(
        transient, t_end, period, qr_per_period, history_points
    )
    tgt_n, tgt_tau = _split_times(times, period)
    lsum = np.zeros(3)
    hist = np.zeros((int(flags.sum()), 3))
    hcount = np.zeros(1, dtype=np.int64)
    mp = kern.taylor_matrix_coefficients(float(system.damping_ratio))
    bar = _progress_bar(progress and (t_end - transient) > 2000.0, t_end - transient)
    chunk = max(1, int(200.0 / (period / qr_per_period)))
    i = 0
    while i < tgt_n.size:
        j = min(i + chunk, tgt_n.size)
        if run.engine is not None:
            eng = run.engine

            def on_target(r, _i=i):
                kern._gram_schmidt(y, ntan, lsum)
                if flags[_i + r]:
                    hist[hcount[0], :ntan] = lsum[:ntan] / elapsed[_i + r]
                    hcount[0] += 1

            eng.run_targets(tgt_n[i:j], tgt_tau[i:j], None, False, y, ntan, on_target)
        else:
            kern.run_tangent(
                run.par,
                run.plan.up,
                run.plan.down,
                run.plan.mval,
                run.st,
                run.ist,
                tgt_n[i:j],
                tgt_tau[i:j],
                elapsed[i:j],
                flags[i:j],
                0,
                y,
                ntan,
                mp,
                lsum,
                hist,
                hcount,
                True,
            )
            if not (np.all(np.isfinite(y)) and np.all(np.isfinite(lsum))):
                # the kernel applies sal = inf at v* = 0; report it instead of NaN exponents
                raise GrazingError(_grazing_message())
        if bar is not None:
            bar.update(float(elapsed[j - 1] - (elapsed[i - 1] if i > 0 else 0.0)))
        i = j
    if bar is not None:
        bar.close()
    duration = t_end - transient
    raw = lsum[:ntan] / duration
    order = np.argsort(-raw, kind="stable")
    exponents = raw[order]
    # history: the same descending order per checkpoint as the exponents (as in play_tangent)
    history = -np.sort(-hist[: hcount[0], :ntan], axis=1)
    _, _, _, _, nsw = run.final(system)
    return TangentResult(
        exponents=exponents,
        labels=labels,
        history_t=transient + elapsed[flags],
        history=history,
        n_switches=nsw,
        t_end=t_end,
        final=run.final_state(system),
        extra={
            "transient": transient,
            "qr_per_period": qr_per_period,
            "engine": "generic" if run.engine is not None else "equal-width kernel",
        },
    )


def pc_jacobian(
    system: Any,
    duration: float,
    q0: float = -1.0,
    v0: float = 0.1,
    phi0: float = 0.0,
    operator_state: Any = None,
    include_phase: bool = True,
    engine: str = "auto",
    taylor: bool = True,
) -> np.ndarray:
    """Jacobian of the flow map over ``duration`` in (q, v[, φ]) (tangent flow, no QR)."""
    run = _prepare(system, q0, v0, phi0, operator_state, 0.0, engine, taylor)
    period = float(run.par[kern.P_T])
    ntan = 3 if include_phase else 2
    y = np.zeros((3, 3))
    for j in range(ntan):
        y[j, j] = 1.0
    tn, tt = _split_times(np.array([float(duration)]), period)
    if run.engine is not None:
        run.engine.run_targets(tn, tt, None, False, y, ntan)
    else:
        mp = kern.taylor_matrix_coefficients(float(system.damping_ratio))
        kern.run_tangent(
            run.par,
            run.plan.up,
            run.plan.down,
            run.plan.mval,
            run.st,
            run.ist,
            tn,
            tt,
            np.array([float(duration)]),
            np.zeros(1, dtype=np.bool_),
            0,
            y,
            ntan,
            mp,
            np.zeros(3),
            np.zeros((0, 3)),
            np.zeros(1, dtype=np.int64),
            False,
        )
        if not np.all(np.isfinite(y)):
            raise GrazingError(_grazing_message())
    return y[:ntan, :ntan].copy()


def _progress_bar(enabled: bool, total: float):
    if not enabled:
        return None
    from tqdm.auto import tqdm

    return tqdm(total=total, unit="tu", desc="tangent flow", leave=False)
