"""Forced oscillator with a play / generalized play: the paper's thermodynamic limit.

System (paper eqs. eom_2, prob_mag, real_play)::

    q'' + 2ζ q' + q = cos φ + C f(w),   φ' = Ω,   w = play output of q (width p)

with ``f(w) = erf(w / (√2 R))`` for ``GeneralizedPlay.erf(p, R)`` and ``f(w) = w`` for the plain
``PlayOperator``. ``ζ`` = ``damping_ratio``, ``Ω`` = ``frequency``, ``C`` = ``coupling``.

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

Lyapunov spectrum: Benettin/QR (modified Gram–Schmidt) every ``renormalize_dt`` and at every
exit. ``V_out`` has rank k-1 (kernel: the pure-δw direction), so after an exit the last diagonal
element of R is exactly 0: it is recorded structurally as ``log R_kk = -inf`` (the paper's
``λ_4 = -∞``), not as the log of a round-off remainder; the remainder actually found is reported
in ``extra["collapse_residual"]`` (~1e-16).

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

from hysteresis._validation import finite_scalar, nonnegative_integer, positive_integer
from oscillators import _play_kernels as _k
from oscillators.linear import particular_amplitudes
from oscillators.results import OscillatorState, PoincareSection, TangentResult, Trajectory

__all__ = [
    "play_trajectory",
    "play_poincare",
    "play_tangent",
    "play_fundamental_matrix",
    "EVENT_DTYPE",
]

#: Fields of ``Trajectory.events``: kind +1 = the input leaves the play onto a wall (hit),
#: -1 = it enters the play (reversal on a wall); ``w`` is the wagon position at the event.
EVENT_DTYPE = np.dtype([("time", "f8"), ("q", "f8"), ("v", "f8"), ("kind", "i1"), ("w", "f8")])
_SWITCH_DTYPE = np.dtype([("time", "f8"), ("q", "f8"), ("v", "f8"), ("jump", "f8")])

#: RK8 step on a wall and scan step inside the play (time units).
OUTSIDE_STEP = 0.05
INSIDE_STEP = 0.2
_EPS = np.finfo(np.float64).eps


# --------------------------------------------------------------------------------------------
# parameters and initial state
# --------------------------------------------------------------------------------------------
def _shape_code(operator: Any) -> tuple[float, float]:
    """(kind, spread) of a play-type operator: 0 identity (PlayOperator), 1 erf."""
    if not hasattr(operator, "width"):
        raise ValueError("system.operator must be a PlayOperator or GeneralizedPlay (no width)")
    kind = getattr(operator, "shape_kind", None)
    if kind is None or kind == "identity":
        return 0.0, 1.0
    if kind == "erf":
        return 1.0, float(operator.spread)
    raise NotImplementedError(
        f"play_flow integrates the plain play and GeneralizedPlay.erf only; shape_kind={kind!r} "
        "(a custom shape) has no compiled kernel"
    )


def make_parameters(
    system: Any,
    phi0: float = 0.0,
    outside_step: float = OUTSIDE_STEP,
    inside_step: float = INSIDE_STEP,
) -> np.ndarray:
    """Flat parameter array of the kernels (layout in :mod:`oscillators._play_kernels`)."""
    kind, spread = _shape_code(system.operator)
    zeta = finite_scalar(system.damping_ratio, "damping_ratio")
    omega = finite_scalar(system.frequency, "frequency")
    coupling = finite_scalar(system.coupling, "coupling")
    width = finite_scalar(system.operator.width, "width")
    phi0 = finite_scalar(phi0, "phi0")
    if not 0.0 <= zeta < 1.0:
        raise ValueError(
            f"damping_ratio must lie in [0, 1) for the play-limit flow (underdamped), got {zeta}"
        )
    if not omega > 0.0:
        raise ValueError(f"frequency must be > 0, got {omega}")
    if width < 0.0:
        raise ValueError(f"width must be >= 0, got {width}")
    if kind == 1.0 and not spread > 0.0:
        raise ValueError(f"spread must be > 0, got {spread}")
    if zeta == 0.0 and omega == 1.0:
        raise ValueError(
            "damping_ratio = 0 with frequency = 1 (undamped resonance) is not supported"
        )
    amp_a, amp_b = particular_amplitudes(zeta, omega)
    par = np.zeros(15)
    par[:15] = [
        zeta,
        omega,
        coupling,
        0.5 * width,
        kind,
        spread,
        phi0,
        outside_step,
        inside_step,
        amp_a,
        amp_b,
        math.sqrt(1.0 - zeta**2),
        math.hypot(amp_a, amp_b),
        1.0 / (math.sqrt(2.0) * spread),
        math.sqrt(2.0 / math.pi) / spread,
    ]
    return par


def _shape_value(par: np.ndarray, w: np.ndarray | float) -> np.ndarray:
    from scipy.special import erf

    w = np.asarray(w, dtype=np.float64)
    if par[4] == 1.0:
        return erf(w * par[13])
    return w.copy()


def _initial_state(
    par: np.ndarray, q0: Any, v0: Any, w0: Any, operator_state: Any
) -> tuple[np.ndarray, bool]:
    """State array [t, q, v, w, mode] and whether the start is on a wall moving outward."""
    q0 = finite_scalar(q0, "q0")
    v0 = finite_scalar(v0, "v0")
    hp = par[3]
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
        return -2.0 * par[0] * v0 - q0 + math.cos(par[6]) + par[2] * float(_shape_value(par, w))

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


def _play_state(q: float, w: float) -> Any:
    try:
        from hysteresis.play import PlayState
    except ImportError:  # pragma: no cover - play.py is part of the package
        return (w, q)
    return PlayState(float(w), float(q))


def _final_state(par: np.ndarray, st: np.ndarray) -> OscillatorState:
    phi = math.fmod(par[6] + par[1] * st[0], 2.0 * math.pi)
    if phi < 0.0:
        phi += 2.0 * math.pi
    return OscillatorState(
        q=float(st[1]),
        v=float(st[2]),
        phi=phi,
        operator_state=_play_state(st[1], st[3]),
        t=float(st[0]),
    )


def _sample(
    par: np.ndarray, st: np.ndarray, times: np.ndarray, keep_events: bool, progress: bool, desc: str
) -> tuple[np.ndarray, np.ndarray, int]:
    """Advance through ``times``; returns samples (n, 3) [q, v, w], events (m, 5), count."""
    out = np.empty((times.size, 3))
    empty_t = np.zeros((4, 0))
    logs = np.zeros(0)
    diag = np.zeros(4)
    flags = np.array([0, 1], dtype=np.int64)
    work = _k.make_work(0)
    events = []
    n_events = 0
    n_chunks = max(1, min(200, times.size // 2000))
    bounds = np.linspace(0, times.size, n_chunks + 1).astype(int)
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=times.size, desc=desc, unit="pt")
    for i0, i1 in zip(bounds[:-1], bounds[1:], strict=True):
        if i1 <= i0:
            continue
        span = times[i1 - 1] - st[0]
        cap = int(20.0 * span + 100) if keep_events else 0
        while True:
            saved = st.copy()
            ev = np.empty((cap, 5))
            cnt = np.zeros(1, dtype=np.int64)
            _k.sample_kernel(
                par, st, times[i0:i1], out[i0:i1], empty_t, logs, diag, ev, cnt, flags, work
            )
            if not keep_events or cnt[0] <= cap:
                break
            st[:] = saved
            cap = int(cnt[0]) + 100
        n_events += int(cnt[0])
        if keep_events:
            events.append(ev[: cnt[0]].copy())
        if bar is not None:
            bar.update(i1 - i0)
    if bar is not None:
        bar.close()
    ev_all = np.concatenate(events) if events else np.empty((0, 5))
    return out, ev_all, n_events


def _events_array(ev: np.ndarray) -> np.ndarray:
    arr = np.empty(ev.shape[0], dtype=EVENT_DTYPE)
    arr["time"] = ev[:, 0]
    arr["q"] = ev[:, 1]
    arr["v"] = ev[:, 2]
    arr["kind"] = ev[:, 3].astype(np.int8)
    arr["w"] = ev[:, 4]
    return arr


# --------------------------------------------------------------------------------------------
# public API
# --------------------------------------------------------------------------------------------
def play_trajectory(
    system: Any,
    t_end: float,
    q0: float = -1.0,
    v0: float = 0.1,
    w0: float | None = None,
    sample_dt: float = 0.01,
    phi0: float = 0.0,
    *,
    operator_state: Any = None,
    progress: bool = False,
) -> Trajectory:
    """Trajectory of the oscillator with a play-type operator, sampled every ``sample_dt``.

    Parameters
    ----------
    system:
        Object with ``operator`` (``PlayOperator`` or ``GeneralizedPlay.erf``), ``coupling`` (C),
        ``damping_ratio`` (ζ, in [0, 1)) and ``frequency`` (Ω).
    t_end:
        Final time (> 0); samples at ``0, sample_dt, ...`` and at ``t_end``.
    q0, v0:
        Initial position and velocity (paper: -1, 0.1).
    w0:
        Initial wagon position, ``|q0 - w0| <= p/2``; ``None`` means ``q0 - p/2`` (paper's
        ``w0 = q0 - p/2``: on the right wall). Alternatively ``operator_state`` (a ``PlayState``).
    phi0:
        Initial forcing phase φ(0); the force is ``cos(φ0 + Ω t)``.

    Returns
    -------
    Trajectory with ``w`` (wagon position), ``M = f(w)``, ``phi`` (mod 2π) and ``events``
    (structured: ``time, q, v, kind, w``; kind +1 leaving the play onto a wall, -1 entering).
    """
    t_end = finite_scalar(t_end, "t_end")
    sample_dt = finite_scalar(sample_dt, "sample_dt")
    if not t_end > 0.0:
        raise ValueError(f"t_end must be > 0, got {t_end}")
    if not sample_dt > 0.0:
        raise ValueError(f"sample_dt must be > 0, got {sample_dt}")
    par = make_parameters(system, phi0)
    st, _ = _initial_state(par, q0, v0, w0, operator_state)
    n = int(math.floor(t_end / sample_dt + 1e-9)) + 1
    times = np.arange(n) * sample_dt
    if t_end - times[-1] > 1e-9 * sample_dt:
        times = np.append(times, t_end)
    out, ev, _ = _sample(par, st, times, True, progress, "play trajectory")
    phi = np.mod(phi0 + par[1] * times, 2.0 * math.pi)
    return Trajectory(
        t=times,
        q=out[:, 0].copy(),
        v=out[:, 1].copy(),
        phi=phi,
        M=_shape_value(par, out[:, 2]),
        switches=np.empty(0, dtype=_SWITCH_DTYPE),
        final=_final_state(par, st),
        w=out[:, 2].copy(),
        events=_events_array(ev),
    )


def play_poincare(
    system: Any,
    n_periods: int,
    transient_periods: int = 0,
    q0: float = -1.0,
    v0: float = 0.1,
    w0: float | None = None,
    operator_state: Any = None,
    *,
    phi0: float = 0.0,
    progress: bool = False,
) -> PoincareSection:
    """Stroboscopic section at φ = 0 mod 2π: one point per forcing period ``T = 2π/Ω``.

    Same convention as :meth:`ForcedOscillator.poincare_section` and
    :func:`oscillators.piecewise_constant.pc_poincare`: the points are the states at the section
    times ``t_k >= 0`` numbered from 0, ``k = transient_periods + i``, ``i = 0..n_periods-1``.
    For ``phi0 = 0`` that is ``t = (transient_periods + i)·T``, so without transient the first
    point is the initial state; otherwise ``t_0 = ((-phi0) mod 2π)/Ω``. ``w`` holds the wagon
    position, ``M = f(w)``; ``n_switches`` counts wall hits plus reversals over the whole run.
    """
    n_periods = positive_integer(n_periods, "n_periods")
    transient_periods = nonnegative_integer(transient_periods, "transient_periods")
    phi0 = finite_scalar(phi0, "phi0")
    par = make_parameters(system, phi0)
    st, _ = _initial_state(par, q0, v0, w0, operator_state)
    period = 2.0 * math.pi / par[1]
    t_first = math.fmod(-phi0, 2.0 * math.pi)
    if t_first < 0.0:
        t_first += 2.0 * math.pi
    t_first /= par[1]
    # t = 0 itself is a section time when phi0 = 0: the sampler returns the start state there.
    times = t_first + np.arange(transient_periods + n_periods) * period
    out, _, n_events = _sample(par, st, times, False, progress, "play Poincaré section")
    keep = slice(transient_periods, None)
    return PoincareSection(
        q=out[keep, 0].copy(),
        v=out[keep, 1].copy(),
        M=_shape_value(par, out[keep, 2]),
        final=_final_state(par, st),
        w=out[keep, 2].copy(),
        n_switches=n_events,
    )


def _initial_frame(include_phase: bool) -> np.ndarray:
    cols = [0, 1, 2, 3] if include_phase else [0, 1, 3]
    frame = np.zeros((4, len(cols)))
    for j, r in enumerate(cols):
        frame[r, j] = 1.0
    return frame


def play_fundamental_matrix(
    system: Any,
    t_end: float,
    q0: float = -1.0,
    v0: float = 0.1,
    w0: float | None = None,
    operator_state: Any = None,
    *,
    phi0: float = 0.0,
    include_phase: bool = False,
    saltation: bool = True,
) -> tuple[np.ndarray, OscillatorState]:
    """Derivative of the flow map over ``[0, t_end]`` with respect to the initial state.

    Rows and columns are ``(q, v, w)`` (or ``(q, v, φ, w)`` with ``include_phase``). Built from
    the same segments as the trajectory: exact ``W0`` inside, RK8 ``W1`` on walls, ``V_in = I``,
    ``V_out`` (δw := δq) at every wall hit, applied as plain matrices (no re-orthonormalisation).
    A start on a wall moving outward is a wall hit at t = 0 (one-sided derivative: a δw into the
    play is wiped out), so the w column is then zero.
    """
    t_end = finite_scalar(t_end, "t_end")
    if not t_end > 0.0:
        raise ValueError(f"t_end must be > 0, got {t_end}")
    par = make_parameters(system, phi0)
    st, on_wall = _initial_state(par, q0, v0, w0, operator_state)
    T = _initial_frame(include_phase)
    logs = np.zeros(T.shape[1])
    diag = np.zeros(4)
    mode = 0 if saltation else 2
    flags = np.array([0, mode], dtype=np.int64)
    if on_wall:
        _k.leave_play(T, logs, diag, False, mode)
    ev = np.empty((0, 5))
    cnt = np.zeros(1, dtype=np.int64)
    _k.advance(par, st, t_end, T, logs, diag, ev, cnt, flags, _k.make_work(T.shape[1]))
    rows = [0, 1, 2, 3] if include_phase else [0, 1, 3]
    return T[rows, :].copy(), _final_state(par, st)


def play_tangent(
    system: Any,
    t_end: float,
    transient: float = 0.0,
    q0: float = -1.0,
    v0: float = 0.1,
    w0: float | None = None,
    operator_state: Any = None,
    include_phase: bool = False,
    progress: bool = True,
    renormalize_dt: float = 1.0,
    *,
    phi0: float = 0.0,
    record_events: bool = False,
) -> TangentResult:
    """Lyapunov spectrum of the play-limit system by the tangent flow (Benettin/QR).

    The run covers ``[0, t_end]``; the exponents are averaged over ``[transient, t_end]``. Tangent
    space ``(q, v, w)`` (paper: the phase direction neglected, δφ ≡ 0) or ``(q, v, φ, w)`` with
    ``include_phase`` (adds the exponent 0 of the phase); ``labels`` names that tangent-space basis,
    ``("q", "v", "w")`` or ``("q", "v", "phi", "w")``, in this fixed order. After the QR
    re-orthonormalisation the exponents are not tied to single basis directions, so ``labels`` is
    not a per-exponent tag. Exponents in descending order; the last is exactly ``-inf`` as soon as
    the input leaves the play after the transient (rank collapse at ``V_out``, module docstring).
    ``history`` holds the running estimates (sorted, one row per checkpoint). ``extra``:
    ``n_exits``, ``n_entries`` (after the transient), ``collapse_residual`` (largest relative
    remainder of the collapsed column, a round-off check), ``log_sums``, ``transient``,
    ``renormalize_dt``, and with ``record_events`` the wall hits / reversals of the whole run
    (``events``, as in :func:`play_trajectory`).
    """
    t_end = finite_scalar(t_end, "t_end")
    transient = finite_scalar(transient, "transient")
    renormalize_dt = finite_scalar(renormalize_dt, "renormalize_dt")
    if not transient >= 0.0:
        raise ValueError(f"transient must be >= 0, got {transient}")
    if not t_end > transient:
        raise ValueError(f"t_end must be > transient = {transient}, got {t_end}")
    if not renormalize_dt > 0.0:
        raise ValueError(f"renormalize_dt must be > 0, got {renormalize_dt}")
    par = make_parameters(system, phi0)
    st, on_wall = _initial_state(par, q0, v0, w0, operator_state)
    T = _initial_frame(include_phase)
    k = T.shape[1]
    logs = np.zeros(k)
    diag = np.zeros(4)
    recorder: list | None = [] if record_events else None
    work = _k.make_work(k)
    flags = np.array([1 if transient == 0.0 else 0, 1], dtype=np.int64)
    if on_wall:
        _k.leave_play(T, logs, diag, flags[0] != 0, 1)
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=float(t_end), desc="play tangent flow", unit="t", leave=False)
    if transient > 0.0:
        _chunked(par, st, transient, renormalize_dt, T, logs, diag, flags, work, bar, recorder)
        flags[0] = 1
    span = t_end - transient
    n_hist = int(min(500, max(1, round(span / renormalize_dt))))
    checkpoints = transient + span * np.arange(1, n_hist + 1) / n_hist
    checkpoints[-1] = t_end
    history = np.empty((n_hist, k))
    for i, t_c in enumerate(checkpoints):
        _chunked(par, st, t_c, renormalize_dt, T, logs, diag, flags, work, bar, recorder)
        history[i] = np.sort(logs / (t_c - transient))[::-1]
    if bar is not None:
        bar.close()
    exponents = np.sort(logs / span)[::-1]
    # the tangent-space basis (fixed order), not a per-exponent tag: see the docstring
    labels = ("q", "v", "phi", "w") if include_phase else ("q", "v", "w")
    extra_events = {}
    if recorder is not None:
        ev_all = np.concatenate(recorder) if recorder else np.empty((0, 5))
        extra_events["events"] = _events_array(ev_all)
    return TangentResult(
        exponents=exponents,
        labels=labels,
        history_t=checkpoints,
        history=history,
        n_switches=int(diag[0] + diag[1]),
        t_end=t_end,
        final=_final_state(par, st),
        extra={
            "n_exits": int(diag[0]),
            "n_entries": int(diag[1]),
            "collapse_residual": float(diag[2]),
            "n_collapses": int(diag[3]),
            "log_sums": logs.copy(),
            "transient": transient,
            "renormalize_dt": renormalize_dt,
            **extra_events,
        },
    )


def _chunked(par, st, t_stop, renorm, T, logs, diag, flags, work, bar, recorder) -> None:
    """Tangent kernel to ``t_stop`` in pieces of ~200 time units (progress bar updates); with a
    ``recorder`` list the events of each piece are appended (a piece whose event buffer
    overflows is redone from a snapshot with a larger buffer)."""
    cap = 0
    while st[0] < t_stop:
        t0 = st[0]
        t_next = min(t_stop, t0 + max(200.0, renorm))
        if recorder is not None:
            cap = max(cap, int(20.0 * (t_next - t0)) + 100)
            snapshot = (st.copy(), T.copy(), logs.copy(), diag.copy())
        while True:
            ev = np.empty((cap, 5))
            cnt = np.zeros(1, dtype=np.int64)
            _k.tangent_kernel(par, st, t_next, renorm, T, logs, diag, ev, cnt, flags, work)
            if recorder is None or cnt[0] <= cap:
                break
            st[:], T[:], logs[:], diag[:] = snapshot
            cap = int(cnt[0]) + 100
        if recorder is not None:
            recorder.append(ev[: cnt[0]].copy())
        if bar is not None:
            bar.update(st[0] - t0)
