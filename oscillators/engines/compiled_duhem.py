"""Compiled Duhem engine: Bouc–Wen and Jiles–Atherton coupled to the forced oscillator.

System (paper eq. eom_2)::

    q'' + 2ζ q' + q = cos(φ0 + Ω t) + C·y,   y = M[q](t)

for a Duhem operator (:mod:`hysteresis.duhem`) whose contract hands over ``compiled_flow()``
of kind ``"duhem"`` (:class:`hysteresis.flow.CompiledFlow`: the model id and its named
parameters; the right-hand sides live in :mod:`hysteresis._duhem_kernels`). The classic
Bouc–Wen oscillator ``q'' + 2ζq' + q + k·z = cos Ωt`` is ``C = −k``.

The algorithm in words
----------------------
The state is ``(q, v, z)`` in time: the Duhem law ``dz = g_d(q, z) dq`` becomes
``z' = g_d(q, z)·v`` with ``d = sign v``, integrated with fixed-step 8th-order Dormand–Prince
(step ``h = step/ρ``, ``ρ = max(1, Ω, 2ζ, √(|C|·S))`` with ``S`` the operator's ``max_slope``
— Jiles–Atherton's from :func:`hysteresis._duhem_kernels.jiles_atherton_slope_bound` at the
start state — default ``step = 0.05`` as in the other compiled engines; Jiles–Atherton's steps
also resolve the relaxation of ``M_irr`` and close in on its pole, where the operator's
:class:`~hysteresis.jiles_atherton.JilesAthertonInstability` is raised). The events, located
by Newton on the step's own RK8 map (:mod:`oscillators.engines._duhem_engine_kernels`): the
**reversal** ``v = 0`` (``v := 0``, ``d`` flips) and the **kink** (Bouc–Wen: ``z = 0`` of
``|z|ⁿ``, ``z := 0``; Jiles–Atherton: the switch of ``δ_M``; no RK8 step straddles it; not
counted among the events, which are the reversals, as in the generic engine).

Tangent space: rows ``("q", "v"[, "phi"], "z")``, ``z`` the *current* internal variable (the
memory of :class:`~hysteresis.duhem.DuhemState`), so that the Jacobian is the derivative of
the map ``(q, v[, φ], z) ↦ (q, v[, φ], z)`` between the engine's own states. The 3×3
variational equation (plus the phase column) runs on the RK8 stages; at a reversal and at the
kink the vector field is continuous, so the saltation is the identity (checked against finite
differences in the tests). The generic engine names the memory differently — ``z0``, the value
of the current branch at its start, ``"z-"``/``"z+"`` (:mod:`hysteresis.duhem`) — a change of
coordinates ``δz = g_d δq + Φ δz0`` that is singular as ``Φ = ∂z/∂z0 → 0`` on a long branch;
spectra and Floquet multipliers do not depend on it. Nothing is reset or removed, so
:meth:`~CompiledDuhemEngine.rank_bound` is ``3`` (``4`` with the phase), capped by the columns;
``Σλ = −2ζ + ⟨v·∂g/∂z⟩``, the time average of the divergence (Liouville).

``engine_options={"method": "generic"}`` builds the generic
:class:`~oscillators.engines.continuous.ContinuousEngine` instead (the reference).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from hysteresis._duhem_kernels import jiles_atherton_slope_bound
from hysteresis._validation import finite_scalar
from oscillators.engines import _duhem_engine_kernels as _k
from oscillators.engines.base import (
    STEPS_PER_TIME,
    DivergenceError,
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

__all__ = ["CompiledDuhemEngine", "METHODS", "MODELS"]

#: the compiled models: id -> (kernel code, parameter names in the kernel's order)
MODELS = {
    "bouc_wen": (_k.MODEL_BOUC_WEN, ("A", "beta", "gamma", "n")),
    "jiles_atherton": (_k.MODEL_JILES_ATHERTON, ("ms", "a", "k", "c", "alpha")),
}
#: events kept per kernel call before the buffer is drained
_EVENT_BUFFER = 4096


class CompiledDuhemEngine(CompiledRK8Engine):
    """Compiled engine for Duhem operators with a ``"duhem"`` ``compiled_flow()`` (module
    docstring).

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
        RK8 step in time units for ρ = 1, in (0, 0.2].
    **generic_options:
        ``rtol``, ``atol``, ``max_step`` of the generic engine (``method="generic"`` only).
    """

    name = "compiled Duhem engine"
    kernel_module = "oscillators.engines._duhem_engine_kernels"

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
        if spec is None or spec.kind != "duhem":
            raise TypeError(f"operator {op!r} has no 'duhem' compiled_flow(): use another engine")
        self._op = op
        self._spec = spec
        code, names = MODELS[spec.model]
        step, coupling, q, v, t0 = self._start(system, state, step)
        zeta = self._zeta
        self._mp = np.array([float(spec.parameters[name]) for name in names])
        if code == _k.MODEL_JILES_ATHERTON:  # the scratch slots: no previous solve yet
            self._mp = np.concatenate([self._mp, np.zeros(_k.N_JA_MP - self._mp.size)])
            self._mp[_k.M_LAST] = math.nan
        op_state = state.operator_state
        if op_state is None:
            op_state = op.initial_state(q)
        z0 = finite_scalar(spec.memory(op_state), "operator_state memory")
        slope = op.max_slope
        pole = False
        if code == _k.MODEL_JILES_ATHERTON:
            # the steepest branch of a motion from this state, or None where the pole may be
            # reached (then the steps close in on it: _duhem_engine_kernels)
            slope = jiles_atherton_slope_bound(q, z0, *self._mp[:5])
            pole = slope is None
        stiff = math.sqrt(abs(coupling) * float(slope)) if slope is not None else 0.0
        # the RK8 step's local error scales as (ρh)^9: ρ the largest rate of the linearised
        # motion (forcing, damping, the stiffness C·slope of the steepest branch)
        rho = max(1.0, self._omega, 2.0 * zeta, stiff)
        self._par = np.zeros(_k.N_PAR)
        self._par[_k.P_ZETA] = zeta
        self._par[_k.P_OMEGA] = self._omega
        self._par[_k.P_C] = coupling
        self._par[_k.P_PHI0] = self._phi0
        self._par[_k.P_H] = step / rho
        self._par[_k.P_PERIOD] = self._period
        self._par[_k.P_BOUND] = float(system.divergence_bound)
        self._par[_k.P_T0] = t0
        _k.set_trig_table(self._par, self._par[_k.P_H])
        u = getattr(op_state, "input", None)
        if u is not None and abs(float(u) - q) > 1e-12 * max(1.0, abs(q)):
            raise ValueError(f"state.operator_state.input ({float(u)}) must equal state.q ({q})")
        self._ist = np.zeros(_k.N_IST, dtype=np.int64)
        self._ist[_k.I_MODEL] = code
        self._st = np.zeros(_k.N_ST)
        self._st[_k.S_Q] = q
        self._st[_k.S_V] = v
        self._st[_k.S_Z] = z0
        self._ist[_k.I_POLE] = 1 if pole else 0
        self._include_phase = False
        self._events: list[np.ndarray] = []
        self._ev = np.zeros((0, 6))
        self._Y = np.zeros((4, 0))
        self._work = _k.make_work(0)
        # the initial direction: the sign of v, at rest that of the acceleration
        if v != 0.0:
            d = 1 if v > 0.0 else -1
        else:
            y = _k.output_now(self._ist, self._st, self._mp)
            acc = -q + math.cos(self._phi0) + coupling * float(y)
            d = 1 if acc >= 0.0 else -1
        self._ist[_k.I_DIR] = d
        # the side of the kink the state is on; a state the model cannot integrate is refused
        # before any step (Jiles–Atherton's 1 − αχ <= 0)
        _k.side_now(self._ist, self._st, self._mp, d)
        self._check_posed()

    # -- helpers -------------------------------------------------------------------------------
    def _clock(self) -> tuple[int, float]:
        return int(self._ist[_k.I_PERIOD]), float(self._st[_k.S_TAU])

    def _check_posed(self) -> None:
        """Raise the operator's own error (``Duhem.domain_error``: Jiles–Atherton's
        :class:`~hysteresis.jiles_atherton.JilesAthertonInstability`, as the generic engine's
        branch flow does) where the motion reached a point the model cannot continue past."""
        if self._ist[_k.I_BAD]:
            q, z = float(self._st[_k.S_Q]), float(self._st[_k.S_Z])
            raise self._op.domain_error(q, z, int(self._ist[_k.I_DIR]))

    @property
    def n_events(self) -> int:
        return int(self._ist[_k.I_EVENTS])

    @property
    def n_kinks(self) -> int:
        """Kinks of the slope (Bouc–Wen's ``z = 0``) landed on since the start."""
        return int(self._ist[_k.I_KINKS])

    # -- motion --------------------------------------------------------------------------------
    def _advance(self, times: np.ndarray, out: np.ndarray | None, record: bool) -> None:
        n_t, tau_t = split_times(times, self._period)
        buf = np.empty((times.size, 3))
        ist = self._ist
        ist[_k.I_SAMPLE] = 0
        ist[_k.I_NEV] = 0
        ist[_k.I_RECORD] = 1 if record else 0
        events_before = int(ist[_k.I_EVENTS])
        span = float(times[-1]) - self.elapsed if times.size else 0.0
        if record and self._ev.shape[0] == 0:
            self._ev = np.zeros((_EVENT_BUFFER, 6))
        while True:
            status = _k.run(
                self._par, ist, self._st, self._mp, n_t, tau_t, buf, self._Y, self._ev,
                self._work,
            )  # fmt: skip
            if record and ist[_k.I_NEV] > 0:
                self._events.append(self._ev[: ist[_k.I_NEV]].copy())
                ist[_k.I_NEV] = 0
            if status == _k.DONE:
                break
            if status == _k.DIVERGED:
                self.check_finite(np.array([self._st[_k.S_Q], self._st[_k.S_V]]))
                raise DivergenceError(
                    f"compiled Duhem engine: the internal variable diverged ({self._st[_k.S_Z]})",
                    time=self.start.t + self.elapsed,
                )
            if status == _k.ILL_POSED:
                self._check_posed()
            if status == _k.STUCK:
                raise RuntimeError(
                    f"compiled Duhem engine: no progress at q={self._st[_k.S_Q]} "
                    "(events at zero distance)"
                )
        events = int(ist[_k.I_EVENTS]) - events_before
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

    def state(self) -> OscillatorState:
        q, v = float(self._st[_k.S_Q]), float(self._st[_k.S_V])
        self.check_finite(np.array([q, v]))
        op_state = self._spec.make_state(float(self._st[_k.S_Z]), q, int(self._ist[_k.I_DIR]))
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
        arr["M"] = ev[:, 4]
        arr["jump"] = ev[:, 5]
        return {"events": arr}

    # -- tangent flow --------------------------------------------------------------------------
    def _rows(self) -> list[int]:
        """Rows of ``Y`` (δq, δv, δφ, δz) that make up :meth:`deviations`."""
        return [0, 1, 2, 3] if self._include_phase else [0, 1, 3]

    def _start_tangent(self, include_phase: bool) -> int:
        self._include_phase = include_phase
        rows = self._rows()
        k = len(rows)
        self._Y = np.zeros((4, k))
        self._Y[rows, np.arange(k)] = 1.0
        self._ist[_k.I_K] = k
        self._work = _k.make_work(k)
        return k

    @property
    def tangent_space(self) -> tuple[str, ...]:
        base = ("q", "v", "phi") if self._include_phase else ("q", "v")
        return base + (self._spec.label(0),)

    def _deviations(self) -> np.ndarray:
        return self._Y[self._rows()].copy()

    def _set_deviations(self, y: np.ndarray) -> None:
        if not np.all(np.isfinite(y)):
            raise ValueError("deviations must be finite")
        self._Y[:] = 0.0
        self._Y[self._rows()] = y

    def _rank_bound(self) -> int:
        # no event resets or removes a direction (module docstring)
        return min(self._ntan, len(self._rows()))
