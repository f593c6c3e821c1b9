"""Generic continuous engine: the forced oscillator with any operator that has a branch flow.

System (paper eq. eom_2)::

    q'' + 2ζ q' + q = cos(φ0 + Ω t) + C·y,   y = M[q](t)

for any operator with :meth:`~hysteresis.base.ContinuousHysteron.branch_flow`
(:class:`hysteresis.flow.BranchFlow`): plays, PI, Preisach, Duhem, composites.

Segments and events
-------------------
While the input ``q`` moves in one direction the operator follows one smooth branch
``y = y(q)``; the motion is integrated with ``scipy.integrate.solve_ivp`` (DOP853, tight
``rtol``/``atol``, engine options) with two terminal events located on the dense output: the
**reversal** ``v = 0`` (then ``v := 0`` exactly and the direction flips) and the **breakpoint**
``q = breakpoint`` of the branch (then ``q := breakpoint`` exactly: a play wall hit, a wiped-out
Preisach extremum). At every event the operator state is advanced through ``operator.apply`` to
the event input (exact: the input moved monotonically since the last event) and the next branch
is asked for. ``advance`` stops exactly at the requested times; samples in between come from the
integrator's 7th-order dense output. A state that becomes non-finite or exceeds the system's
``divergence_bound`` in ``|q|`` or ``|v|`` raises
:class:`~oscillators.engines.base.DivergenceError`.

Tangent space
-------------
Rows ``("q", "v"[, "phi"], *labels)`` where ``labels`` are the memory labels of the current
branch (:attr:`BranchFlow.labels <hysteresis.flow.BranchFlow>`: ``"w"`` for a play,
``"w0".."w{K-1}"`` for a Prandtl–Ishlinskii operator, ``"M1", "m1", ...`` for the remembered
extrema of a continuous Preisach staircase, a number that changes along the orbit). Columns: the
deviation vectors, ``k`` = the dimension at :meth:`ContinuousEngine.start_tangent`. On a segment

* ``δq' = δv``,
  ``δv' = −2ζ δv − δq − sin(φ) δφ + C (∂y/∂u δq + Σ_j ∂y/∂m_j δm_j)``, ``δφ' = 0``;
* frozen memory: ``δm_j' = 0``; slaved memory (a dragged wagon): ``δm_j = δq`` (so its term
  joins the ``δq`` coefficient, which is the branch slope ``dy/du``).

At events (saltation): where the output is continuous, ``(δq, δv, δφ)`` pass unchanged (the
vector fields of ``(q, v)`` agree on both sides); at a breakpoint where the output jumps by
``Δy`` (:attr:`BranchFlow.breakpoint_jump <hysteresis.flow.BranchFlow>`: the relays of a
composite such as ``play + relays``) the acceleration jumps by ``C·Δy`` and
``δv += C·Δy/v*·δq`` (paper eq. ``salt_matrix``; at ``v* = 0`` it is infinite:
:class:`~oscillators.engines.base.GrazingError`), with ``δq − Σ_frozen ∂u*/∂m_i δm_i`` in place
of ``δq`` where the breakpoint moves with the memory (``breakpoint_gradient``: a cascade's relay
threshold reached through its inner operator). Memory rows:

* a memory variable that becomes slaved (wall hit, paper ``V_out``) or is created (a reversal of
  a continuous Preisach input pushes an extremum) gets ``δm := δq`` (a pushed variable with a
  ``pushed_gradient``: ``δm := d_du·δq + d_dm @ δm``; one still pending from the old branch
  keeps its row);
* a variable that was *driven* on the old branch (a cascade's outer wagon dragged by the inner
  output, :mod:`hysteresis.flow` "Driven memory"; a Duhem operator's current ``z``) gets
  ``δm := d_du·δq + d_dm @ δm_old`` from the old branch's gradient at the event; it is a free
  direction only in place of free variables that leave the tangent space at that event and
  enter its gradient (a Duhem operator's ``z0``, handed to the next branch at a reversal),
  at most as many as those;
* a wiped-out extremum's row, and a newly driven variable's, is dropped; the rest is carried.

A start on a slaved branch (input on a wall, moving outward) or right at a reversal that pushes
an extremum is such an event at ``t = 0`` (the one-sided derivative into the play is wiped out),
as in the compiled play engine. :meth:`ContinuousEngine.rank_bound` is ``2`` (``3`` with the
phase) plus the number of memory directions present at the last ``start_tangent`` /
``set_deviations`` that were neither reset, removed nor driven since, capped by ``k``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from hysteresis._validation import finite_scalar, positive_scalar
from hysteresis.base import ContinuousHysteron
from hysteresis.seam import check_state, checked_apply, checked_branch_flow
from oscillators.engines.base import (
    STEPS_PER_TIME,
    DivergenceError,
    Engine,
    GrazingError,
    StepBudgetError,
    TangentFlow,
    split_times,
    step_budget,
    wrap_phase,
)
from oscillators.results import OscillatorState

__all__ = ["ContinuousEngine", "EVENT_DTYPE", "EVENT_SWITCH"]

#: Fields of ``records()["events"]``: kind +1 a breakpoint (wall hit, wipe-out), -1 a reversal,
#: +2 relays of a composite switched (the output jumped by ``jump``; 0 at the other kinds);
#: ``M`` the operator output after the event.
EVENT_DTYPE = np.dtype(
    [("time", "f8"), ("q", "f8"), ("v", "f8"), ("kind", "i1"), ("M", "f8"), ("jump", "f8")]
)
#: ``kind`` of an event at which relays switched
EVENT_SWITCH = 2

#: Longest stretch integrated by one solve_ivp call (divergence is checked between calls).
_MAX_CALL = 20.0


class ContinuousEngine(TangentFlow, Engine):
    """Engine for any operator with ``branch_flow`` (see the module docstring).

    Parameters
    ----------
    system:
        A :class:`~oscillators.system.ForcedOscillator` (``operator``, ``coupling``,
        ``damping_ratio``, ``frequency``).
    state:
        Start state; ``operator_state=None`` means ``operator.initial_state(q)``. The operator
        state's input must equal ``q``.
    rtol, atol:
        Tolerances of the DOP853 integration (state and deviations), in [1e-13, 1e-3].
    max_step:
        Largest integration step (time units, > 0).
    method:
        ``"generic"`` (or ``"auto"``): this engine is the generic path (the option exists so
        that ``engine_options={"method": "generic"}`` selects it for every continuous operator,
        also those with a compiled engine).

    Notes
    -----
    A state that is non-finite or above the system's ``divergence_bound`` raises
    :class:`DivergenceError`.
    """

    name = "continuous engine"

    def __init__(
        self,
        system: Any,
        state: OscillatorState,
        *,
        rtol: float = 1e-11,
        atol: float = 1e-11,
        max_step: float = 1.0,
        method: str = "generic",
    ) -> None:
        if method not in ("auto", "generic"):
            raise ValueError(
                f"method must be 'auto' or 'generic' for the generic continuous engine, got "
                f"{method!r}"
            )
        super().__init__(system, state)
        op = system.operator
        if not isinstance(op, ContinuousHysteron):
            raise TypeError(f"operator {type(op).__name__} provides no branch_flow()")
        self._op = op
        self._rtol = _tolerance(rtol, "rtol")
        self._atol = _tolerance(atol, "atol")
        self._max_step = positive_scalar(max_step, "max_step")
        self._zeta = finite_scalar(system.damping_ratio, "damping_ratio")
        self._coupling = finite_scalar(system.coupling, "coupling")
        self._q = finite_scalar(state.q, "state.q")
        self._v = finite_scalar(state.v, "state.v")
        self._phi0 = wrap_phase(finite_scalar(state.phi, "state.phi"))
        op_state = state.operator_state
        if op_state is None:
            op_state = op.initial_state(self._q)
        u = check_state(op_state, "given as state.operator_state")
        if abs(u - self._q) > 1e-12 * max(1.0, abs(self._q)):
            raise ValueError(f"state.operator_state.input ({u}) must equal state.q ({self._q})")
        self._op_state = op_state
        self._n = 0  # elapsed = n·T + tau, tau in [0, T)
        self._tau = 0.0
        self._events: list[tuple[float, float, float, int, float, float]] = []
        self._n_events = 0
        self._direction = self._initial_direction()
        self._flow = checked_branch_flow(op, op_state, self._direction)
        self._has_w = tuple(self._flow.labels) == ("w",)
        self._include_phase = False
        self._dqv = np.zeros((2, 0))
        self._dphi: np.ndarray | None = None
        self._dm = np.zeros((0, 0))
        self._free: set[str] = set()
        self._stuck = 0

    # -- helpers -------------------------------------------------------------------------------
    def _clock(self) -> tuple[int, float]:
        return self._n, self._tau

    def _initial_direction(self) -> int:
        if self._v > 0.0:
            return 1
        if self._v < 0.0:
            return -1
        # at rest: the sign of the acceleration (a jump at this very input was applied by the
        # operator state already, so the output of the state is the one that holds here)
        acc = (
            -self._q
            + math.cos(self._phi0)
            + self._coupling * float(self._op.output(self._op_state))
        )
        return 1 if acc >= 0.0 else -1

    def _add_time(self, s: float) -> None:
        self._tau += s
        if self._tau >= self._period:
            extra = math.floor(self._tau / self._period)
            self._n += int(extra)
            self._tau -= extra * self._period
            if self._tau >= self._period:  # rounding
                self._n += 1
                self._tau = 0.0
            if self._tau < 0.0:
                self._tau = 0.0

    def _check(self) -> None:
        self.check_finite(np.array([self._q, self._v]))

    # -- motion --------------------------------------------------------------------------------
    @property
    def sample_columns(self) -> tuple[str, ...]:
        return ("q", "v", "M", "w") if self._has_w else ("q", "v", "M")

    @property
    def n_events(self) -> int:
        return self._n_events

    def _local(self, times: np.ndarray) -> np.ndarray:
        """Elapsed ``times`` as durations from now (exact in (period, offset) form)."""
        n, tau = split_times(times, self._period)
        return (n - self._n) * self._period + (tau - self._tau)

    def _sample_row(self, q: float, v: float) -> tuple:
        flow = self._flow
        y = float(flow.output(q))
        if self._has_w:
            return (q, v, y, float(flow.memory_at(q)[0]))
        return (q, v, y)

    def _advance(self, times: np.ndarray, out: np.ndarray | None, record: bool) -> None:
        self._record = bool(record)
        chunk = 2048
        for i0 in range(0, times.size, chunk):
            block = times[i0 : i0 + chunk]
            self._run(block, None if out is None else out[i0 : i0 + block.size])

    def _run(self, times: np.ndarray, out: np.ndarray | None) -> None:
        """Integrate to ``times[-1]``, writing the samples at ``times`` into ``out``."""
        n_t, tau_t = split_times(times[-1:], self._period)
        ncol = len(self.sample_columns)
        i = 0
        # bounded work: DOP853 steps (12 right-hand sides each) plus events per call
        span = float((n_t[0] - self._n) * self._period + (tau_t[0] - self._tau))
        budget = step_budget(self._omega, self._zeta, span)
        used = 0
        while True:
            s_eval = None
            if out is not None and i < times.size:
                local = self._local(times[i:])
                # samples at (or, by rounding, before) the current time
                while i < times.size and local[0] <= 0.0:
                    out[i, :ncol] = self._sample_row(self._q, self._v)
                    i += 1
                    local = local[1:]
                s_eval = local if local.size else None
            duration = float((n_t[0] - self._n) * self._period + (tau_t[0] - self._tau))
            if duration <= 0.0:
                break
            horizon = min(duration, _MAX_CALL)
            s_done, samples, hit = self._segment(horizon, s_eval)
            used += 1 + self._last_nfev // 12
            if used > budget:
                t = self.start.t + self.elapsed + s_done
                raise StepBudgetError(
                    f"step budget exceeded at t = {t:.6g}: more than {budget} steps and events "
                    f"in one advance call, the cap of {STEPS_PER_TIME} per unit time (times "
                    "max(1, Ω, 2ζ)) plus STEP_BUDGET_FLOOR per call "
                    "(oscillators.engines.base.STEPS_PER_TIME)",
                    time=t,
                    budget=budget,
                )
            if samples is not None:
                for j in range(samples.shape[1]):
                    out[i + j, :ncol] = self._sample_row(float(samples[0, j]), float(samples[1, j]))
                i += samples.shape[1]
            if hit is None and horizon == duration:
                self._n, self._tau = int(n_t[0]), float(tau_t[0])
                self._check()
                if out is not None:
                    while i < times.size:
                        out[i, :ncol] = self._sample_row(self._q, self._v)
                        i += 1
                break
            self._add_time(s_done)
            self._check()
            if hit is not None:
                self._event(hit)

    def _segment(self, horizon: float, s_eval: np.ndarray | None):
        """Integrate the current branch for at most ``horizon``; returns (time advanced,
        samples (2, m) at the ``s_eval`` times before the stop or None, event kind or None)."""
        flow = self._flow
        d = self._direction
        zeta, omega, coupling = self._zeta, self._omega, self._coupling
        phi_s = self.phase()
        output = flow.output
        tangent = self._ntan > 0
        k = self._ntan
        y0 = [self._q, self._v]
        if tangent:
            y0 = np.concatenate([[self._q, self._v], self._dqv[0], self._dqv[1]])
            frozen = ~flow.slaved
            slaved = flow.slaved
            dm_frozen = self._dm[frozen]
            dphi = self._dphi
            constant = flow.constant_partials
            slope_c, force_c = 0.0, None
            if constant:
                d_u, d_m = flow.partials(flow.input)
                d_m = np.asarray(d_m, dtype=np.float64)
                slope_c = float(d_u) + float(np.sum(d_m[slaved]))
                force_c = d_m[frozen] @ dm_frozen

            def rhs(s, y):
                q = y[0]
                v = y[1]
                ph = phi_s + omega * s
                res = np.empty_like(y)
                res[0] = v
                res[1] = -2.0 * zeta * v - q + math.cos(ph) + coupling * output(q)
                dq = y[2 : 2 + k]
                dv = y[2 + k :]
                res[2 : 2 + k] = dv
                if constant:
                    slope, force = slope_c, force_c
                else:
                    d_u, d_m = flow.partials(q)
                    d_m = np.asarray(d_m, dtype=np.float64)
                    slope = float(d_u) + float(np.sum(d_m[slaved]))
                    force = d_m[frozen] @ dm_frozen
                acc = -2.0 * zeta * dv - dq + coupling * (slope * dq + force)
                if dphi is not None:
                    acc -= math.sin(ph) * dphi
                res[2 + k :] = acc
                return res

        else:

            def rhs(s, y):
                q = y[0]
                v = y[1]
                acc = -2.0 * zeta * v - q + math.cos(phi_s + omega * s) + coupling * output(q)
                return np.array([v, acc])

        def reversal(s, y):
            return y[1]

        reversal.terminal = True
        reversal.direction = -d
        events = [reversal]
        bp = float(flow.breakpoint)
        if math.isfinite(bp):

            def breakpoint(s, y):
                return y[0] - bp

            breakpoint.terminal = True
            breakpoint.direction = d
            events.append(breakpoint)
        t_eval = None
        if s_eval is not None:
            inside = s_eval[s_eval < horizon]  # a sample at the end comes from the final state
            if inside.size:
                # the end point is appended so that sol.y also holds the final state
                t_eval = np.append(inside, horizon)
        # scipy.integrate costs ~0.4 s at import: loaded where used (fast `hyst` start)
        from scipy.integrate import solve_ivp

        sol = solve_ivp(
            rhs,
            (0.0, horizon),
            np.asarray(y0, dtype=np.float64),
            method="DOP853",
            t_eval=t_eval,
            events=events,
            rtol=self._rtol,
            atol=self._atol,
            max_step=self._max_step,
        )
        self._last_nfev = int(sol.nfev)
        if sol.status < 0:
            raise DivergenceError(
                f"continuous engine: integration failed ({sol.message})",
                time=self.start.t + self.elapsed,
            )
        sol_t = np.asarray(sol.t, dtype=np.float64)  # an empty list if no t_eval was reached
        samples = None
        if t_eval is not None:
            samples = sol.y[:2] if sol_t.size else np.zeros((2, 0))
        hit = None
        if sol.status == 1:
            for kind, j in (("reversal", 0), ("breakpoint", 1)):
                if j < len(sol.t_events) and sol.t_events[j].size:
                    s_hit = float(sol.t_events[j][0])
                    y_hit = sol.y_events[j][0]
                    hit = kind
                    break
            if hit == "reversal" and len(events) > 1 and d * (float(y_hit[0]) - bp) >= 0.0:
                # the input passed the breakpoint and turned back inside one solver step (the
                # event is seen only by its sign at the step end): the breakpoint comes first
                sol_b = solve_ivp(
                    rhs,
                    (0.0, s_hit),
                    np.asarray(y0, dtype=np.float64),
                    method="DOP853",
                    events=[breakpoint],
                    rtol=self._rtol,
                    atol=self._atol,
                    max_step=self._max_step,
                )
                if sol_b.status == 1 and sol_b.t_events[0].size:
                    s_hit = float(sol_b.t_events[0][0])
                    y_hit = sol_b.y_events[0][0]
                    hit = "breakpoint"
            if samples is not None:
                samples = samples[:, sol_t < s_hit]
        if hit is None:
            s_hit = float(sol_t[-1])
            y_hit = sol.y[:, -1]
            if samples is not None:
                samples = samples[:, :-1]
        if samples is not None and samples.shape[1] == 0:
            samples = None
        self._store(y_hit, tangent, k)
        if hit == "reversal":
            self._v = 0.0
        elif hit == "breakpoint":
            self._q = bp
        if hit is not None:
            self._stuck = self._stuck + 1 if s_hit == 0.0 else 0
            if self._stuck > 50:
                raise RuntimeError(
                    f"continuous engine: no progress at q={self._q} (events at zero distance)"
                )
        return s_hit, samples, hit

    def _store(self, y: np.ndarray, tangent: bool, k: int) -> None:
        self._q = float(y[0])
        self._v = float(y[1])
        if tangent:
            self._dqv[0] = y[2 : 2 + k]
            self._dqv[1] = y[2 + k : 2 + 2 * k]
            self._dm[self._flow.slaved] = self._dqv[0]

    def _event(self, kind: str) -> None:
        old = self._flow
        _, self._op_state = checked_apply(self._op, np.array([self._q]), self._op_state)
        if kind == "reversal":
            self._direction = -self._direction
        self._n_events += 1
        new = checked_branch_flow(self._op, self._op_state, self._direction)
        if self._record:
            jump = old.breakpoint_jump if kind == "breakpoint" else 0.0
            code = -1 if kind == "reversal" else (EVENT_SWITCH if jump != 0.0 else 1)
            self._events.append(
                (
                    self.start.t + self.elapsed,
                    self._q,
                    self._v,
                    code,
                    float(new.output(self._q)),
                    jump,
                )
            )
        if self._ntan:
            if kind == "breakpoint" and old.breakpoint_jump != 0.0:
                self._saltation(old)
            self._reconcile(old, new)
        self._flow = new

    def _saltation(self, old: Any) -> None:
        """``δv += C·Δy/v*·(δq − Σ_frozen ∂u*/∂m_i δm_i)`` at a jump of the output (the event
        surface ``q = bp(m)``; ``breakpoint_gradient`` None: ``q = bp``)."""
        if self._v == 0.0:
            raise GrazingError(
                f"continuous engine: the output jumps at a turning point (q = {self._q}, "
                f"t = {self.start.t + self.elapsed:.6g}): the saltation C·Δy/v* is infinite, so "
                "the flow map is not differentiable on this orbit"
            )
        moved = self._dqv[0]
        grad = old.breakpoint_gradient
        if grad is not None:
            use = ~old.slaved & (grad != 0.0)
            if np.any(use):
                if not np.all(np.isfinite(grad[use])):
                    raise GrazingError(
                        f"continuous engine: the output jumps where its threshold is reached at "
                        f"zero slope (q = {self._q}, t = {self.start.t + self.elapsed:.6g}): the "
                        "event moves infinitely with the memory, so the flow map is not "
                        "differentiable on this orbit"
                    )
                moved = moved - grad[use] @ self._dm[use]
        self._dqv[1] = self._dqv[1] + (self._coupling * old.breakpoint_jump / self._v) * moved

    def _pushed_rows(self, flow: Any, dm: np.ndarray, keep: np.ndarray | None = None) -> None:
        """Rows of the variables ``flow`` pushed at its start (but those in ``keep``):
        ``δm := δq``, or from the flow's ``pushed_gradient`` (``d_du·δq + d_dm @ δm``, the
        other rows of ``dm`` already set)."""
        pushed = np.array(flow.pushed, dtype=bool)
        idx = np.flatnonzero(pushed if keep is None else pushed & ~keep)
        if idx.size == 0:
            return
        dq = self._dqv[0]
        if flow.pushed_gradient is None:
            dm[idx] = dq
            return
        d_du, d_dm = flow.pushed_gradient(self._q)
        n_pushed = int(pushed.sum())
        d_du = np.asarray(d_du, dtype=np.float64).reshape(n_pushed)
        d_dm = np.asarray(d_dm, dtype=np.float64).reshape(n_pushed, flow.n_memory)
        rows = np.flatnonzero(~keep[pushed]) if keep is not None else np.arange(n_pushed)
        dm[idx] = 0.0
        dm[idx] = d_du[rows, None] * dq[None, :] + d_dm[rows] @ dm

    def _reconcile(self, old: Any, new: Any) -> None:
        """Saltation at an event: carry, reset (δm := δq), initialise from the old branch's
        driven gradient, or drop memory rows by label (hysteresis.flow, "Driven memory")."""
        index = {lab: i for i, lab in enumerate(old.labels)}
        driven = {lab: i for i, lab in enumerate(old.driven_labels)}
        gradient = None
        # free directions that leave the tangent space here: a variable initialised from a
        # driven gradient that involves them carries them on (a Duhem operator's branch memory
        # handed from one branch to the next at a reversal), at most one each
        leaving = {lab for lab in old.labels if lab in self._free and lab not in new.labels}
        heirs: list[str] = []
        dq = self._dqv[0]
        dm = np.empty((new.n_memory, self._ntan))
        pending = np.zeros(new.n_memory, dtype=bool)
        for i, lab in enumerate(new.labels):
            j = index.get(lab)
            if new.pushed[i] and j is not None and old.pushed[j]:
                # pushed on the old branch and still pending (the value remembered has not
                # moved since: a cascade's inner output stayed constant): the same variable
                dm[i] = self._dm[j]
                pending[i] = True
            elif new.pushed[i]:
                self._free.discard(lab)  # created by the reversal: _pushed_rows below
            elif j is not None and new.slaved[i]:
                dm[i] = dq  # (re)set by V_out; already δq if it was slaved before
                if not old.slaved[j]:
                    self._free.discard(lab)
            elif j is not None:
                dm[i] = self._dm[j]  # carried (V_in = I)
            elif lab in driven and not new.slaved[i]:
                if gradient is None:
                    _, d_du, d_dm = old.driven(self._q)
                    d_du = np.asarray(d_du, dtype=np.float64).reshape(len(driven))
                    d_dm = np.asarray(d_dm, dtype=np.float64).reshape(len(driven), old.n_memory)
                    gradient = (d_du, d_dm)
                k = driven[lab]  # δm := d_du·δq + d_dm @ δm_old
                dm[i] = gradient[0][k] * dq + gradient[1][k] @ self._dm
                self._free.discard(lab)
                if any(gradient[1][k][index[m]] != 0.0 for m in leaving):
                    heirs.append(lab)
            else:
                dm[i] = dq  # created (or slaved from the start): δm := δq
                self._free.discard(lab)
        self._pushed_rows(new, dm, keep=pending)
        for lab in old.labels:
            if lab not in new.labels:
                self._free.discard(lab)  # removed, or driven from now on
        # the heirs span at most as many directions as the free variables that left
        self._free.update(heirs[: len(leaving)])
        self._dm = dm

    def state(self) -> OscillatorState:
        _, op_state = checked_apply(self._op, np.array([self._q]), self._op_state)
        return OscillatorState(
            q=self._q,
            v=self._v,
            phi=self.phase(),
            operator_state=op_state,
            t=self.start.t + self.elapsed,
        )

    def records(self) -> dict[str, np.ndarray]:
        arr = np.empty(len(self._events), dtype=EVENT_DTYPE)
        if self._events:
            ev = np.array(self._events, dtype=np.float64)
            arr["time"] = ev[:, 0]
            arr["q"] = ev[:, 1]
            arr["v"] = ev[:, 2]
            arr["kind"] = ev[:, 3].astype(np.int8)
            arr["M"] = ev[:, 4]
            arr["jump"] = ev[:, 5]
        return {"events": arr}

    # -- tangent flow --------------------------------------------------------------------------
    def _start_tangent(self, include_phase: bool) -> int:
        flow = self._flow
        self._include_phase = include_phase
        base = 3 if self._include_phase else 2
        n = flow.n_memory
        k = base + n
        eye = np.eye(k)
        self._dqv = eye[:2].copy()
        self._dphi = eye[2].copy() if self._include_phase else None
        self._dm = eye[base:].copy()
        self._free = set(flow.labels)
        at_branch_start = self._q == flow.input
        for i, lab in enumerate(flow.labels):
            if flow.slaved[i] or (flow.pushed[i] and at_branch_start):
                self._dm[i] = self._dqv[0]
                self._free.discard(lab)
        if at_branch_start:
            self._pushed_rows(flow, self._dm)
        return k

    @property
    def tangent_space(self) -> tuple[str, ...]:
        base = ("q", "v", "phi") if self._include_phase else ("q", "v")
        return base + tuple(self._flow.labels)

    def _deviations(self) -> np.ndarray:
        rows = [self._dqv]
        if self._dphi is not None:
            rows.append(self._dphi[None, :])
        dm = self._dm.copy()
        dm[self._flow.slaved] = self._dqv[0]
        rows.append(dm)
        return np.vstack(rows)

    def _set_deviations(self, y: np.ndarray) -> None:
        if not np.all(np.isfinite(y)):
            raise ValueError("deviations must be finite")
        self._dqv = y[:2].copy()
        base = 2
        if self._dphi is not None:
            self._dphi = y[2].copy()
            base = 3
        self._dm = y[base:].copy()
        slaved = self._flow.slaved
        # a slaved row is δq by definition
        self._dm[slaved] = self._dqv[0]
        self._free = {lab for i, lab in enumerate(self._flow.labels) if not slaved[i]}

    def _rank_bound(self) -> int:
        base = 3 if self._include_phase else 2
        return min(self._ntan, base + len(self._free))


def _tolerance(x: Any, name: str) -> float:
    x = finite_scalar(x, name)
    if not 1e-13 <= x <= 1e-3:
        raise ValueError(f"{name} must lie in [1e-13, 1e-3], got {x}")
    return x
