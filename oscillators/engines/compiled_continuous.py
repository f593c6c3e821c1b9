"""Compiled continuous engine: Prandtl–Ishlinskii operators and continuous Preisach models.

System (paper eq. eom_2)::

    q'' + 2ζ q' + q = cos(φ0 + Ω t) + C·y,   y = M[q](t)

for every continuous operator whose contract hands over ``compiled_flow()``
(:class:`hysteresis.flow.CompiledFlow`). The physics, the events and the tangent space are those
of the generic :class:`~oscillators.engines.continuous.ContinuousEngine` (read its docstring);
only the integration is compiled (:mod:`oscillators.engines._continuous_kernels`, which holds
the plain-Python reading of the algorithm).

The algorithm in words
----------------------
While ``q`` moves one way the operator follows one smooth branch ``y(q)``:

* **Prandtl–Ishlinskii**: only the wagons dragged on their wall move; the branch is affine,
  ``y = y0 + (Σ_dragged a_i)(q − u0)`` (the slope a running sum), and its breakpoint is the next
  wall a frozen wagon meets. O(1) work per integrator stage, O(K) per event.
* **continuous Preisach**: on a branch rising from the last remembered minimum ``m`` the output
  is ``y = y(m) + 2E(q, m)`` (falling from the last maximum ``M``: ``y(M) − 2E(M, q)``), one
  Everett evaluation per right-hand side (the compiled Everett function of the model,
  :func:`hysteresis.preisach._everett_kernels.everett_eval`, with its gradient). The next
  breakpoint is the previous extremum of the same kind, whose wipe-out pops two entries of the
  staircase; a reversal pushes one. The staircase, its Everett prefix sums and their
  derivatives live in preallocated arrays, grown here when a push needs room.

The motion is integrated with fixed-step 8th-order Dormand–Prince (step ``h = step/ρ``,
``ρ = max(1, Ω, 2ζ, √(|C|·S))`` with ``S`` a bound of the branch slopes, default
``step = 0.05`` as the play kernel on its walls), the tangent columns with the same stages. A
step that contains the reversal ``v = 0`` or the breakpoint ``q = bp`` (sign at the step end;
a dip of ``v`` through zero inside the step by the cubic Hermite interpolant) is cut at the
event, located by safeguarded Newton on the step's own RK8 map (full RK8 accuracy); then
``v := 0`` or ``q := bp`` exactly, the direction flips at a reversal and the branch is rebuilt.
A tabulated (C¹ bicubic) Everett function has kinks on its grid lines: a step ends on the next
line of the moving input (predicted from ``q + vτ + aτ²/2``), and exactly (Newton) on a support
bound, where the branch slope jumps and each step takes it on the side it moves into.

A composite with relays (plays + relays): while every play is frozen the motion hops in closed
form from relay switch to switch (the relay kernel's hop; the walls are thresholds too, every
turning point an event); while a play is pushed and no tangent is carried, each relay threshold
is landed on by the branch's Taylor polynomial (:mod:`oscillators.engines._frozen_hops`), one
after the other in a lean loop (:mod:`oscillators.engines._relay_landings`).

Tangent space and saltations: rows ``("q", "v"[, "phi"], *labels)`` with the labels of the
generic engine (``w0 .. w{K-1}``; ``M1, m1, M2, ...``), the same saltations (a wagon that
becomes dragged or an extremum pushed at a reversal: ``δm := δq``; a wiped-out extremum's row
dropped) and the same :meth:`~CompiledContinuousEngine.rank_bound`.

``engine_options={"method": "generic"}`` builds the generic engine instead (the reference the
tests compare with); its other options (``rtol``, ``atol``, ``max_step``) pass through.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from oscillators.engines import _continuous_kernels as _k
from oscillators.engines import _continuous_layout as _lay
from oscillators.engines import _frozen_hops as _fh
from oscillators.engines import _relay_landings as _rl
from oscillators.engines.base import (
    STEPS_PER_TIME,
    DivergenceError,
    GrazingError,
    StepBudgetError,
    split_times,
    step_budget,
)
from oscillators.engines.compiled_rk8 import (
    DEFAULT_STEP,
    METHODS,
    CompiledRK8Engine,
)
from oscillators.engines.continuous import EVENT_DTYPE
from oscillators.results import OscillatorState

__all__ = ["CompiledContinuousEngine", "METHODS"]

#: events kept per kernel call before the buffer is drained
_EVENT_BUFFER = 4096
#: smallest staircase capacity (entries; doubled when a push needs room)
_MIN_CAPACITY = 64


def _slope_bound(spec: Any) -> float:
    """A bound of the branch slopes ``|dy/du|`` from the compiled description: ``Σ|a_i|`` of
    a Prandtl–Ishlinskii operator, twice the largest nodal gradient of a tabulated (kind 1)
    Everett function; 0 (not used) for the Gaussian width-disorder model (quadrature or
    separable table), whose slopes are O(1/R)."""
    if spec.kind == "prandtl_ishlinskii":
        # an erf play's steepest slope is 1/(R√(2π)), at w = 0
        spreads = np.asarray(spec.spreads)
        safe = np.where(spreads > 0.0, spreads, 1.0)
        gain = np.where(spreads > 0.0, 1.0 / (safe * math.sqrt(2.0 * math.pi)), 1.0)
        return float(np.sum(np.abs(spec.weights) * gain))
    table = np.asarray(spec.everett.table)
    if spec.everett.kind == _k.KIND_TABLE and table.size:
        return 2.0 * float(np.max(np.abs(table[..., 1:3])))
    return 0.0


class CompiledContinuousEngine(CompiledRK8Engine):
    """Compiled engine for operators with ``compiled_flow()`` (see the module docstring).

    Parameters
    ----------
    system:
        A :class:`~oscillators.system.ForcedOscillator`.
    state:
        Start state; ``operator_state=None`` means ``operator.initial_state(q)``. The operator
        state's input must equal ``q``.
    method:
        ``"auto"`` or ``"compiled"`` (this engine), ``"generic"``: the generic
        :class:`~oscillators.engines.continuous.ContinuousEngine` (the reference path).
    step:
        RK8 step in time units for ρ = 1 (divided by ``ρ = max(1, Ω, 2ζ, √(|C|·S))``, module
        docstring), in (0, 0.2].
    **generic_options:
        ``rtol``, ``atol``, ``max_step`` of the generic engine (``method="generic"`` only).
    """

    name = "compiled continuous engine"
    kernel_module = "oscillators.engines._continuous_kernels"

    def __init__(
        self,
        system: Any,
        state: OscillatorState,
        method: str = "auto",
        step: float = DEFAULT_STEP,
    ) -> None:
        super().__init__(system, state)
        op = system.operator
        spec = op.compiled_flow()
        if spec is None:
            raise TypeError(f"operator {op!r} has no compiled_flow(): use the generic engine")
        self._op = op
        self._spec = spec
        step, coupling, q, v, t0 = self._start(system, state, step)
        zeta = self._zeta
        # the RK8 step's local error scales as (ρh)^9: ρ = the largest rate of the linearised
        # motion (forcing, damping, the stiffness C·slope of the steepest branch)
        rho = max(1.0, self._omega, 2.0 * zeta, math.sqrt(abs(coupling) * _slope_bound(spec)))
        self._rho = rho
        self._par = np.zeros(_lay.N_PAR)
        self._par[_k.P_ZETA] = zeta
        self._par[_k.P_OMEGA] = self._omega
        self._par[_k.P_C] = coupling
        self._par[_k.P_PHI0] = self._phi0
        self._par[_k.P_H] = step / rho
        self._par[_k.P_PERIOD] = self._period
        self._par[_k.P_BOUND] = float(system.divergence_bound)
        self._par[_k.P_T0] = t0
        op_state = state.operator_state
        if op_state is None:
            op_state = op.initial_state(q)
        u = getattr(op_state, "input", None)
        if u is not None and abs(float(u) - q) > 1e-12 * max(1.0, abs(q)):
            raise ValueError(f"state.operator_state.input ({float(u)}) must equal state.q ({q})")
        self._ist = np.zeros(_lay.N_IST, dtype=np.int64)
        self._st = np.zeros(_lay.N_ST)
        self._st[1] = q
        self._st[2] = v
        self._include_phase = False
        self._events: list[np.ndarray] = []
        self._ev = np.zeros((0, 6))
        self._F = np.zeros((3, 0))
        self._work = _k.make_work(0)
        # the initial direction: the sign of v, at rest that of the acceleration
        if v != 0.0:
            d = 1 if v > 0.0 else -1
        else:
            acc = -q + math.cos(self._phi0) + coupling * float(op.output(op_state))
            d = 1 if acc >= 0.0 else -1
        self._ist[0] = d
        empty = np.zeros(0)
        if spec.kind == "prandtl_ishlinskii":
            self._ist[9] = _k.OP_PI
            self._hw = np.array(spec.half_widths, dtype=np.float64)
            self._wt = np.array(spec.weights, dtype=np.float64)
            positions = op_state.positions if spec.positions is None else spec.positions(op_state)
            self._pos = np.array(positions, dtype=np.float64)
            if self._pos.shape != self._hw.shape:
                raise ValueError("operator_state.positions do not match the operator's plays")
            self._slv = np.zeros(self._hw.size, dtype=np.int8)
            self._free = np.zeros(self._hw.size, dtype=np.int8)
            self._stack = self._prefix = self._dlo = self._dhi = empty
            # the kernel's view of the shapes: 1/(√2 R) per play (0: identity), and room for
            # the list of dragged erf plays (count, then weight, d·r, 1/(√2 R) each)
            spreads = np.asarray(spec.spreads, dtype=np.float64)
            scale = np.zeros(spreads.size)
            np.divide(1.0, math.sqrt(2.0) * spreads, out=scale, where=spreads > 0.0)
            self._et = scale.reshape(1, 1, -1)
            self._ep = np.zeros(1 + 3 * self._hw.size)
            self._Y = np.zeros((3 + self._hw.size, 0))
            self._relays(spec, op_state)
            self._branch()
        else:
            everett = spec.everett
            self._ist[9] = _k.OP_PREISACH
            self._ist[10] = int(everett.kind)
            self._ep = np.array(everett.params, dtype=np.float64)
            self._et = np.array(everett.table, dtype=np.float64)
            self._hw = self._wt = self._pos = empty
            self._slv = self._free = np.zeros(0, dtype=np.int8)
            extrema = np.asarray(op_state.extrema, dtype=np.float64)
            top = extrema.size + 1
            reversing = (d > 0) != (top % 2 == 0)
            p = top if reversing else top - 1
            cap = max(_MIN_CAPACITY, top + 4)
            self._stack = np.empty(cap)
            self._stack[:2] = (np.inf, -np.inf)
            self._stack[2 : top + 1] = extrema
            self._prefix = np.zeros(cap)
            self._dlo = np.zeros(cap)
            self._dhi = np.zeros(cap)
            self._ist[2] = p
            self._st[4] = q
            self._ist[12] = 1 if reversing else 0
            self._Y = np.zeros((3 + cap, 0))
            self._relays(spec, op_state)
            _k.preisach_init(self._ist, self._ep, self._et, self._stack, self._prefix, self._dlo,
                             self._dhi, p)  # fmt: skip
            self._branch()

    # -- helpers -------------------------------------------------------------------------------
    def _relays(self, spec: Any, op_state: Any) -> None:
        """The relays of a composite (``rel``: α, β, weight, output per relay; ``rord``: the
        orders of α and of β), none otherwise."""
        self._ist[_k.I_RPTR] = -1
        # the closed-form hops of the frozen stretches (PI with relays): the relay kernel's
        # parameters and tables (off without relays: fpar empty)
        self._fpar, self._fmp, self._fe = _fh.no_hops()
        if getattr(spec, "relay_alpha", None) is None:
            self._rel = np.zeros((0, 4))
            self._rord = np.zeros((2, 0), dtype=np.int64)
            return
        self._rel = np.column_stack(
            [spec.relay_alpha, spec.relay_beta, spec.relay_weights,
             np.asarray(spec.relay_outputs(op_state), dtype=np.float64)]
        )  # fmt: skip
        self._rord = np.vstack(
            [
                np.argsort(spec.relay_alpha, kind="stable"),
                np.argsort(spec.relay_beta, kind="stable"),
            ]
        ).astype(np.int64)
        self._st[_k.S_RELAY] = _rl.relay_output(self._rel)
        if self._ist[9] == _k.OP_PI:
            par = self._par
            kappa = float(np.max(self._et[0, 0], initial=0.0))  # the largest 1/(√2 R)
            self._fpar, self._fmp, self._fe = _fh.hop_tables(
                par[_k.P_ZETA], par[_k.P_OMEGA], par[_k.P_C], par[_k.P_PHI0], self._rho, kappa
            )

    def _branch(self) -> None:
        """Rebuild the current branch (and the tangent force) from the kernel's state."""
        if self._ist[9] == _k.OP_PI:
            _k.pi_branch(self._ist, self._st, self._hw, self._wt, self._pos, self._slv, self._Y,
                         self._F, self._ep, self._et)  # fmt: skip
        else:
            _k.preisach_branch(self._ist, self._st, self._stack, self._prefix, self._dlo,
                               self._dhi, self._Y, self._F)  # fmt: skip
        _k.merge_breakpoints(self._ist, self._st, self._rel, self._rord)

    def _grow(self) -> None:
        """Double the staircase capacity (Preisach), keeping its contents."""
        cap = 2 * self._stack.size
        for name in ("_stack", "_prefix", "_dlo", "_dhi"):
            old = getattr(self, name)
            new = np.zeros(cap)
            new[: old.size] = old
            setattr(self, name, new)
        y = np.zeros((3 + cap, self._Y.shape[1]))
        y[: self._Y.shape[0]] = self._Y
        self._Y = y

    def _clock(self) -> tuple[int, float]:
        return int(self._ist[1]), float(self._st[0])

    @property
    def n_memory(self) -> int:
        """Number of memory variables now."""
        if self._ist[9] == _k.OP_PI:
            return self._hw.size
        return int(self._ist[2]) - 1

    @property
    def n_events(self) -> int:
        return int(self._ist[3])

    # -- motion --------------------------------------------------------------------------------
    def _advance(self, times: np.ndarray, out: np.ndarray | None, record: bool) -> None:
        n_t, tau_t = split_times(times, self._period)
        buf = np.empty((times.size, 3))
        ist = self._ist
        ist[5] = 0
        ist[6] = 0
        ist[7] = 1 if record else 0
        events_before = int(ist[3])
        span = float(times[-1]) - self.elapsed if times.size else 0.0
        if record and self._ev.shape[0] == 0:
            self._ev = np.zeros((_EVENT_BUFFER, 6))
        while True:
            status = _k.run(
                self._par, ist, self._st, n_t, tau_t, buf, self._hw, self._wt, self._pos,
                self._slv, self._free, self._stack, self._prefix, self._dlo, self._dhi, self._ep,
                self._et, self._Y, self._F, self._ev, self._work, self._rel, self._rord,
                self._fpar, self._fmp, self._fe,
            )  # fmt: skip
            if record and ist[6] > 0:
                self._events.append(self._ev[: ist[6]].copy())
                ist[6] = 0
            if status == _k.DONE:
                break
            if status == _k.GROW:
                self._grow()
            elif status == _k.DIVERGED:
                self.check_finite(np.array([self._st[1], self._st[2]]))
                raise DivergenceError("compiled continuous engine: diverged")  # not reached
            elif status == _k.GRAZING:
                raise GrazingError(
                    f"compiled continuous engine: relays switch at a turning point (q = "
                    f"{self._st[1]}, t = {self.start.t + self.elapsed:.6g}): the saltation "
                    "C·Δy/v* is infinite, so the flow map is not differentiable on this orbit"
                )
            elif status == _k.STUCK:
                raise RuntimeError(
                    f"compiled continuous engine: no progress at q={self._st[1]} "
                    "(events at zero distance)"
                )
        events = int(ist[3]) - events_before
        budget = step_budget(self._omega, self._zeta, span)
        if events > budget:  # bounded work: events per call (the RK8 steps are fixed)
            raise StepBudgetError(
                f"step budget exceeded by t = {self.elapsed:.6g}: {events} events in one advance "
                f"call, more than the cap of {STEPS_PER_TIME} per unit time "
                "(oscillators.engines.base.STEPS_PER_TIME)",
                time=self.elapsed,
                budget=budget,
            )
        if out is not None:
            out[:, :3] = buf

    def _memory(self) -> np.ndarray:
        if self._ist[9] == _k.OP_PI:
            return self._pos.copy()
        return self._stack[2 : int(self._ist[2]) + 1].copy()

    def state(self) -> OscillatorState:
        q, v = float(self._st[1]), float(self._st[2])
        self.check_finite(np.array([q, v]))
        if self._ist[9] == _k.OP_PI:
            make = self._spec.make_state
            if self._rel.shape[0]:
                op_state = make(self._pos.copy(), q, self._rel[:, _lay.R_OUT].copy())
            else:
                op_state = (self._op.state if make is None else make)(self._pos.copy(), q)
        else:
            extrema = self._memory()
            if extrema.size == 0 or extrema[-1] != q:
                extrema = np.append(extrema, q)
            op_state = self._op.state_from_extrema(extrema)
        return OscillatorState(
            q=q, v=v, phi=self.phase(), operator_state=op_state, t=self.start.t + self.elapsed
        )

    def records(self) -> dict[str, np.ndarray]:
        ev = np.concatenate(self._events) if self._events else np.zeros((0, 6))
        arr = np.empty(ev.shape[0], dtype=EVENT_DTYPE)
        arr["time"] = ev[:, 0]
        arr["q"] = ev[:, 1]
        arr["v"] = ev[:, 2]
        arr["kind"] = ev[:, 3].astype(np.int8)
        arr["jump"] = ev[:, 5]
        arr["M"] = ev[:, 4]
        return {"events": arr}

    # -- tangent flow --------------------------------------------------------------------------
    def _base(self) -> int:
        return 3 if self._include_phase else 2

    def _start_tangent(self, include_phase: bool) -> int:
        self._include_phase = include_phase
        n_mem = self.n_memory
        k = self._base() + n_mem
        self._Y = np.zeros((self._Y.shape[0], k))
        rows = self._rows()
        self._Y[rows, np.arange(k)] = 1.0
        self._ist[8] = k
        self._F = np.zeros((3, k))
        self._work = _k.make_work(k)
        if self._ist[9] == _k.OP_PI:
            self._branch()  # dragged rows := δq
            self._free[:] = 1 - self._slv
        else:
            p = int(self._ist[2])
            free = n_mem
            if self._ist[12] and self._st[1] == self._st[4] and p >= 2:
                # right at a reversal that pushed the last extremum: δm := δq there
                self._Y[p + 1] = self._Y[0]
                free -= 1
            self._ist[4] = free
            self._branch()
        return k

    def _rows(self) -> np.ndarray:
        """Rows of ``Y`` that make up :meth:`deviations` now."""
        base = [0, 1, 2] if self._include_phase else [0, 1]
        return np.array(base + list(range(3, 3 + self.n_memory)), dtype=np.int64)

    @property
    def tangent_space(self) -> tuple[str, ...]:
        base = ("q", "v", "phi") if self._include_phase else ("q", "v")
        return base + tuple(self._spec.label(i) for i in range(self.n_memory))

    def _deviations(self) -> np.ndarray:
        return self._Y[self._rows()].copy()

    def _set_deviations(self, y: np.ndarray) -> None:
        if not np.all(np.isfinite(y)):
            raise ValueError("deviations must be finite")
        self._Y[:] = 0.0
        self._Y[self._rows()] = y
        if self._ist[9] == _k.OP_PI:
            self._branch()  # a dragged row is δq by definition
            self._free[:] = 1 - self._slv
        else:
            self._ist[4] = self.n_memory
            self._branch()

    def _rank_bound(self) -> int:
        if self._ist[9] == _k.OP_PI:
            free = int(np.sum(self._free))
        else:
            free = int(self._ist[4])
        return min(self._ntan, self._base() + free)
