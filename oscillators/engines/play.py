"""Forced oscillator with a play / generalized play: the paper's thermodynamic limit.

System (paper eqs. eom_2, prob_mag, real_play)::

    q'' + 2ζ q' + q = cos φ + C f(w),   φ' = Ω,   w = play output of q (width p)

with ``f(w) = erf(w / (√2 R))`` for ``GeneralizedPlay.erf(p, R)``, ``f(w) = w`` for the plain
``PlayOperator`` and, for a ``GeneralizedPlay`` with a user shape that saturates (e.g. ``tanh``),
the piecewise cubic Hermite table of :mod:`hysteresis.shape_table` (``|f − table| <= 1e-10`` of
the output range; the engine integrates the table). ``ζ`` = ``damping_ratio``, ``Ω`` =
``frequency``, ``C`` = ``coupling``.

Exact segmentation
------------------
* **Inside the play** (``|q - w| < p/2``, or on a wall moving inward) ``w`` is frozen and the
  force ``C f(w)`` is constant: the motion is the analytic solution of the linear oscillator.
  The instant the input reaches a wall ``q = w ± p/2`` is found by root finding on it. Steps
  cannot hide a hit: on each scan step the cubic Hermite interpolant of ``q`` plus the rigorous
  bound ``max|q''''| h⁴/384`` (every derivative of the free motion is bounded by its amplitude
  because the eigenvalues have modulus 1) decides whether a wall is reachable; reachable
  intervals are bisected (left half first) down to 1e-3, where extrema are located by Newton on
  ``v`` and the hit by Newton on ``q - wall``.
* **On a wall moving outward** (``w = q ∓ p/2``) the equation ``q'' = -2ζv - q + cos φ +
  C f(q ∓ p/2)`` is smooth and nonlinear: fixed-step 8th-order Dormand–Prince (``h = 0.05``;
  over 60 time units of the chaotic C = 2.9 case the event times agree with ``solve_ivp(DOP853,
  rtol=1e-13)`` to 1e-10, limited by the reference, and change by 1.5e-11 when h is 0.02). The
  reversal ``v = 0`` where the input re-enters the play is bracketed on the step and located by
  Newton, each iterate being one RK8 step from the step start (full RK8 accuracy).

Tangent flow (paper appendix)
-----------------------------
Extended perturbation ``δy = (δq, δv, δφ, δw)``. Inside: ``W0`` (δw, δφ frozen; δv' gets
``C f'(w(t_i')) δw``), integrated exactly. On a wall: ``W1`` (``δw' = δv``), integrated with the
same RK8 stages as the state. Entering the play (reversal, ``v = 0``): the vector fields inside and
on the wall coincide there, so the saltation matrix is ``V_in = I``. Leaving the play at a wall
hit: the standard saltation ``S = I + (F⁺ - F⁻) nᵀ / (n·F⁻)`` with ``n = ∇(q - w ∓ p/2)``,
``F⁺ - F⁻ = (0, 0, 0, v)`` (the force ``C f(w)`` is continuous at the hit, only ``ẇ`` jumps from 0
to ``v``) gives exactly the paper's ``V_out``: ``δw := δq``, (δq, δv, δφ) unchanged — no
time-lag correction in (q, v). The tests check this against finite differences of the
stroboscopic map.

Lyapunov spectrum: the one Benettin/QR loop of :mod:`analysis.dynamics.lyapunov` drives
:class:`PlayEngine`. ``V_out`` has rank k-1 (kernel: the pure-δw direction), so after an exit
the last diagonal element of R is exactly 0; the engine reports it through ``rank_bound()`` and
the loop records ``log R_kk = -inf`` structurally (the paper's ``λ_4 = -∞``), not the log of a
round-off remainder.

Invariant used in the tests: on a wall the tangent flow restricted to ``{δw = δq}`` has trace
``-2ζ``; inside, the (δq, δv) map from an entry (time ``t_e``) to the next exit (``Δ`` later) is
``Φ(Δ) + κ (I - Φ(Δ)) e1 e1ᵀ`` (``κ = C f'(w)``) with determinant
``e^{-2ζΔ} (1 - κ) + κ Φ22(Δ)``, ``Φ22(Δ) = e^{-ζΔ}(cos ω_dΔ - ζ/ω_d sin ω_dΔ)``. Hence

    λ1 + λ2 = -2ζ + lim (1/T) Σ_inside segments log|1 - κ + κ e^{2ζΔ} Φ22(Δ)|,

computable from the event list alone; for ``C = 0`` it is ``-2ζ`` (exponents ``-ζ, -ζ``).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from hysteresis._validation import finite_scalar
from oscillators.engines import _play_kernels as _k
from oscillators.engines.base import (
    STEPS_PER_TIME,
    Engine,
    StepBudgetError,
    TangentFlow,
    step_budget,
)
from oscillators.linear import particular_amplitudes
from oscillators.parameters import check_closed_form
from oscillators.results import OscillatorState

__all__ = ["EVENT_DTYPE", "PlayEngine", "make_parameters"]

#: Fields of ``Trajectory.events``: kind +1 = the input leaves the play onto a wall (hit),
#: -1 = it enters the play (reversal on a wall); ``w`` is the wagon position at the event.
EVENT_DTYPE = np.dtype([("time", "f8"), ("q", "f8"), ("v", "f8"), ("kind", "i1"), ("w", "f8")])

#: RK8 step on a wall and scan step inside the play (time units).
OUTSIDE_STEP = 0.05
INSIDE_STEP = 0.2
_EPS = np.finfo(np.float64).eps


# --------------------------------------------------------------------------------------------
# parameters and initial state
# --------------------------------------------------------------------------------------------
def _shape_code(operator: Any) -> tuple[float, float, np.ndarray | None]:
    """(kind, spread, table array) from the operator's ``compiled_play()``: 0 identity, 1 erf,
    2 a tabulated shape (:class:`hysteresis.shape_table.ShapeTable`)."""
    spec = operator.compiled_play()
    if spec is None:
        raise ValueError(
            f"{operator!r} has no compiled play description (compiled_play() is None); the "
            "generic continuous engine integrates it"
        )
    if spec.shape == "identity":
        return _k.SHAPE_IDENTITY, 1.0, None
    if spec.shape == "erf":
        return _k.SHAPE_ERF, float(spec.spread), None
    if spec.shape == "table" and spec.table is not None:
        return _k.SHAPE_TABLE, 1.0, spec.table.kernel_array()
    raise ValueError(
        f"compiled play shape must be 'identity', 'erf' or 'table' (with a table), got "
        f"{spec.shape!r}"
    )


def make_parameters(
    system: Any,
    phi0: float = 0.0,
    outside_step: float = OUTSIDE_STEP,
    inside_step: float = INSIDE_STEP,
) -> np.ndarray:
    """Flat parameter array of the kernels (layout in :mod:`oscillators.engines._play_kernels`)."""
    kind, spread, table = _shape_code(system.operator)
    zeta = finite_scalar(system.damping_ratio, "damping_ratio")
    omega = finite_scalar(system.frequency, "frequency")
    coupling = finite_scalar(system.coupling, "coupling")
    width = finite_scalar(system.operator.compiled_play().width, "width")
    phi0 = finite_scalar(phi0, "phi0")
    if not 0.0 <= zeta < 1.0:
        raise ValueError(
            f"damping_ratio must lie in [0, 1) for the play-limit flow (underdamped), got {zeta}"
        )
    if not omega > 0.0:
        raise ValueError(f"frequency must be > 0, got {omega}")
    if width < 0.0:
        raise ValueError(f"width must be >= 0, got {width}")
    if kind == _k.SHAPE_ERF and not spread > 0.0:
        raise ValueError(f"spread must be > 0, got {spread}")
    check_closed_form(zeta, omega)
    amp_a, amp_b = particular_amplitudes(zeta, omega)
    par = np.zeros(_k.P_TABLE if table is None else _k.P_TABLE + table.size)
    if table is not None:
        par[_k.P_TABLE :] = table
    par[_k.P_ZETA] = zeta
    par[_k.P_OMEGA] = omega
    par[_k.P_C] = coupling
    par[_k.P_HP] = 0.5 * width
    par[_k.P_SHAPE] = kind
    par[_k.P_SPREAD] = spread
    par[_k.P_PHI0] = phi0
    # the RK8 step's local error scales as (ρh)^9 with ρ = max(1, Ω) (ζ < 1): the step
    # shrinks with the forcing frequency; unchanged for Ω <= 1
    par[_k.P_H_OUT] = outside_step / max(1.0, omega)
    par[_k.P_H_IN] = inside_step
    par[_k.P_AMP_A] = amp_a
    par[_k.P_AMP_B] = amp_b
    par[_k.P_OMEGA_D] = math.sqrt(1.0 - zeta**2)
    par[_k.P_AMP] = math.hypot(amp_a, amp_b)
    par[_k.P_ERF_SCALE] = 1.0 / (math.sqrt(2.0) * spread)
    par[_k.P_ERF_SLOPE] = math.sqrt(2.0 / math.pi) / spread
    return par


def _shape_value(par: np.ndarray, w: np.ndarray | float) -> np.ndarray:
    """The kernel's shape ``f(w)`` (the same arithmetic: :func:`_play_kernels.shape`)."""
    w = np.asarray(w, dtype=np.float64)
    return _k.shape_values(par, np.ascontiguousarray(w.ravel())).reshape(w.shape)


def _initial_state(
    par: np.ndarray, q0: Any, v0: Any, w0: Any, operator_state: Any
) -> tuple[np.ndarray, bool]:
    """State array [t, q, v, w, mode] and whether the start is on a wall moving outward."""
    q0 = finite_scalar(q0, "q0")
    v0 = finite_scalar(v0, "v0")
    hp = par[_k.P_HP]
    if operator_state is not None:
        if w0 is not None:
            raise ValueError("give either w0 or operator_state, not both")
        w0 = getattr(operator_state, "position", None)
        if w0 is None:
            raise ValueError("operator_state must be a PlayState (attribute 'position' = w)")
    w0 = q0 - hp if w0 is None else finite_scalar(w0, "w0")
    gap = q0 - w0
    tol = 8.0 * _EPS * max(abs(q0), abs(w0), hp, 1.0)
    if abs(gap) > hp + tol:
        raise ValueError(f"w0 must satisfy |q0 - w0| <= width/2 = {hp} (got q0={q0}, w0={w0})")

    def accel(side: float) -> float:
        w = q0 - side * hp
        zeta, phi0, coupling = par[_k.P_ZETA], par[_k.P_PHI0], par[_k.P_C]
        return -2.0 * zeta * v0 - q0 + math.cos(phi0) + coupling * float(_shape_value(par, w))

    mode = 0.0
    if gap >= hp - tol:  # right wall: w = q - p/2
        w0 = q0 - hp
        if v0 > 0.0 or (v0 == 0.0 and accel(1.0) > 0.0):
            mode = 1.0
    if mode == 0.0 and gap <= -hp + tol:  # left wall: w = q + p/2
        w0 = q0 + hp
        if v0 < 0.0 or (v0 == 0.0 and accel(-1.0) < 0.0):
            mode = -1.0
    if hp == 0.0 and mode == 0.0:  # zero width: always on a wall
        mode = 1.0 if accel(1.0) >= 0.0 else -1.0
        w0 = q0 - mode * hp
    st = np.array([0.0, q0, v0, w0, mode])
    return st, mode != 0.0


def _events_array(ev: np.ndarray) -> np.ndarray:
    arr = np.empty(ev.shape[0], dtype=EVENT_DTYPE)
    arr["time"] = ev[:, 0]
    arr["q"] = ev[:, 1]
    arr["v"] = ev[:, 2]
    arr["kind"] = ev[:, 3].astype(np.int8)
    arr["w"] = ev[:, 4]
    return arr


# --------------------------------------------------------------------------------------------
# the engine
# --------------------------------------------------------------------------------------------
class PlayEngine(TangentFlow, Engine):
    """Compiled play-limit engine: plain play, ``GeneralizedPlay.erf`` (the paper's limit) and
    a ``GeneralizedPlay`` with a tabulated user shape.

    Tangent space ``(q, v[, phi], w)``. Between the loop's re-orthonormalisations ``V_out``
    (``δw := δq`` at a wall hit) is applied as a plain matrix; every wall hit since the last
    :meth:`set_deviations` lowers :meth:`rank_bound` by one (the ``w`` direction is gone), so the
    QR loop records the paper's ``λ = -∞`` structurally.
    """

    name = "play kernel"
    kernel_module = "oscillators.engines._play_kernels"

    @classmethod
    def check_system(cls, system: Any) -> None:
        """Refuse parameters the kernel does not integrate (checked at construction)."""
        make_parameters(system)

    def __init__(self, system: Any, state: OscillatorState, saltation: bool = True) -> None:
        super().__init__(system, state)
        if not isinstance(saltation, bool):
            raise TypeError(f"saltation must be a bool, got {saltation!r}")
        self._par = make_parameters(system, float(state.phi))
        opstate = state.operator_state
        if getattr(opstate, "position", None) is None:
            raise TypeError(
                f"operator_state must be a PlayState (attribute 'position' = w), got "
                f"{type(opstate).__name__}"
            )
        self._st, self._on_wall = _initial_state(self._par, state.q, state.v, None, opstate)
        self._T = np.zeros((4, 0))
        self._diag = np.zeros(4)
        self._work = _k.make_work(0)
        # [accumulate event counts, qr_mode]: 0 applies V_out as a plain matrix; 2 omits it (a
        # diagnostic showing that the saltation is needed, ``saltation=False``)
        self._flags = np.array([1, 0 if saltation else 2], dtype=np.int64)
        self._events: list[np.ndarray] = []
        self._n_events = 0
        self._rows: list[int] = []
        self._exits_at_set = 0.0
        self._w_reset = False

    @property
    def sample_columns(self) -> tuple[str, ...]:
        return ("q", "v", "M", "w")

    def _clock(self) -> tuple[int, float]:
        # the kernel counts time from the start as one float (period index 0): elapsed and the
        # forcing phase are computed from it exactly as the kernel does
        return 0, float(self._st[0])

    def _advance(self, times: np.ndarray, out: np.ndarray | None, record: bool) -> None:
        buf = np.empty((times.size, 3))
        span = float(times[-1] - self._st[0]) if times.size else 0.0
        cap = int(20.0 * max(span, 0.0) + 100) if record else 0
        while True:
            saved = (self._st.copy(), self._T.copy(), self._diag.copy())
            ev = np.empty((cap, 5))
            cnt = np.zeros(1, dtype=np.int64)
            _k.sample_kernel(
                self._par,
                self._st,
                times,
                buf,
                self._T,
                self._diag,
                ev,
                cnt,
                self._flags,
                self._work,
            )
            budget = step_budget(self._omega, 0.0, span)
            if cnt[0] > budget:  # bounded work: events per call (the wall steps are fixed)
                raise StepBudgetError(
                    f"step budget exceeded by t = {self.start.t + self._st[0]:.6g}: {cnt[0]} "
                    f"events in one advance call, more than the cap of {STEPS_PER_TIME} per unit "
                    "time (oscillators.engines.base.STEPS_PER_TIME)",
                    time=float(self.start.t + self._st[0]),
                    budget=budget,
                )
            if not record or cnt[0] <= cap:
                break
            self._st[:], self._T[:], self._diag[:] = saved
            cap = int(cnt[0]) + 100
        self._n_events += int(cnt[0])
        if record:
            self._events.append(ev[: cnt[0]].copy())
        if out is not None:
            out[:, 0] = buf[:, 0]
            out[:, 1] = buf[:, 1]
            out[:, 2] = _shape_value(self._par, buf[:, 2])
            if out.shape[1] > 3:
                out[:, 3] = buf[:, 2]

    def state(self) -> OscillatorState:
        st = self._st
        q, v = float(st[1]), float(st[2])
        self.check_finite(np.array([q, v]))  # the operator builds finite states only
        return OscillatorState(
            q=q,
            v=v,
            phi=self.phase(),
            operator_state=self.system.operator.state(position=float(st[3]), input=q),
            t=float(self.start.t + st[0]),
        )

    def records(self) -> dict[str, np.ndarray]:
        ev = np.concatenate(self._events) if self._events else np.empty((0, 5))
        return {"events": _events_array(ev)}

    @property
    def n_events(self) -> int:
        return self._n_events

    # -- tangent flow
    def _start_tangent(self, include_phase: bool) -> int:
        self._rows = [0, 1, 2, 3] if include_phase else [0, 1, 3]
        k = len(self._rows)
        self._T = np.zeros((4, k))
        for j, r in enumerate(self._rows):
            self._T[r, j] = 1.0
        self._work = _k.make_work(k)
        self._exits_at_set = float(self._diag[0])
        self._w_reset = False
        if self._st[4] != 0.0:
            # on a wall moving outward: w is slaved from the start (one-sided derivative)
            _k.leave_play(self._T, int(self._flags[1]))
            self._w_reset = True
        return k

    @property
    def tangent_space(self) -> tuple[str, ...]:
        return ("q", "v", "phi", "w") if len(self._rows) == 4 else ("q", "v", "w")

    def _deviations(self) -> np.ndarray:
        return self._T[self._rows, :].copy()

    def _set_deviations(self, y: np.ndarray) -> None:
        self._T[:] = 0.0
        self._T[self._rows, :] = y
        self._exits_at_set = float(self._diag[0])
        self._w_reset = False

    def _rank_bound(self) -> int:
        lost = self._w_reset or self._diag[0] > self._exits_at_set
        return len(self._rows) - (1 if lost else 0)
