"""Lyapunov spectra of forced oscillators with hysteresis (paper Sec. "Lyapunov exponents").

One algorithm, in one place, over a small stepper interface (after ChaosTools'
``lyapunovspectrum``): :class:`TangentStepper` re-initialises a system's engine at a state,
steps it by a time interval with the tangent (variational) flow on, and reads / sets the
deviation vectors. :func:`lyapunov_spectrum` runs the Benettin/Geist QR loop on it:

    reinit(state); step(transient) without tangent; deviations := I
    repeat every Δt:  step(Δt);  Y = deviations();  Q R = Y;  Σ_j += log|R_jj|;  set(Q)
    λ_j = Σ_j / (t_end − transient)

The engines supply the physics: closed-form fundamental matrices between relay switches with the
saltation ``C·ΔM/v*`` at each switch (paper eq. salt_matrix); the play-limit linearization
(paper eqs. limit_W_0/1, ``V_in = I``, ``V_out``: ``δw := δq``); the generic continuous engine
with the operator's memory directions. The tangent space is named by the engine
(``("q", "v"[, "phi"], *memory)``), the exponents belong to no single coordinate.

Structural collapse: an engine reports through ``rank_bound()`` how many independent directions
its tangent map can have kept since the last re-orthonormalisation (a play wall hit resets
``δw := δq``; a wiped-out Preisach extremum removes its direction). The diagonal entries of R
beyond that bound are exactly zero in exact arithmetic: they are recorded as ``log R_jj = -inf``
(the paper's ``λ = -∞``), not as the log of a round-off remainder. When the number of rows of the
deviation matrix is smaller than the number of tracked vectors (memory removed), the missing
directions are -inf and their columns are continued as zero vectors. Deviation vectors that an
event set exactly to zero (a relay's Filippov slide collapses ``δq, δv``) are moved behind the
others and the QR redone (a column permutation: an orthogonal change of the interval's start
basis), so a surviving direction (the phase) keeps its exponent. Likewise a vector that depends
structurally on the ones before it (its QR residual at round-off) is moved behind them: a
neutral memory direction that never mixes with the others (a frozen wagon or remembered
extremum) keeps the start basis non-generic, and without the move a dependent vector would take
a leading slot and push the neutral exponent 0 into a -inf slot.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from analysis.dynamics._householder import _accumulate_logs, householder_qr
from analysis.dynamics._relay_benettin import LANES, qr_intervals, qr_intervals_lanes
from analysis.dynamics.dimensions import kaplan_yorke_dimension
from hysteresis._progress import progress_bar
from hysteresis._validation import finite_scalar, positive_integer, time_window
from oscillators import (
    DEFAULT_Q0,
    DEFAULT_V0,
    MAX_PERIODS,
    DivergenceError,
    Engine,
    OscillatorState,
)
from oscillators.engines import describe_engine, require_tangent_flow

__all__ = [
    "LANES",
    "LyapunovResult",
    "TangentStepper",
    "lyapunov_spectrum",
    "lyapunov_spectra",
]


@dataclass(frozen=True)
class LyapunovResult:
    """Lyapunov spectrum of one run.

    Attributes
    ----------
    exponents:
        Descending; ``-inf`` allowed (a collapsed memory direction, e.g. the play limit's ``w``).
    tangent_space:
        The basis of the tangent space the flow was started in, e.g. ``("q", "v")`` for relays
        and dimers, ``("q", "v", "w")`` for the play limit, with ``"phi"`` if the phase
        direction is included. The exponents belong to no single coordinate.
    history_t, history:
        Running estimates (rows, each sorted descending) at times ``history_t``.
    n_switches:
        Events (relay switches, wall hits and reversals) during the averaging window.
    t_end, transient:
        The average runs over ``[transient, t_end]`` (time units).
    kaplan_yorke:
        ``D_KY`` of the exponents (paper eq. kaplan_yorke).
    final:
        System state at ``t_end`` (to continue a run, e.g. along a parameter continuation).
    extra:
        ``engine``, ``renormalize_dt``, ``n_collapses`` (QR intervals with a structural rank
        drop).
    """

    exponents: np.ndarray
    tangent_space: tuple[str, ...]
    history_t: np.ndarray
    history: np.ndarray
    n_switches: int
    t_end: float
    transient: float
    kaplan_yorke: float
    final: OscillatorState
    extra: dict = field(default_factory=dict)

    @property
    def max_exponent(self) -> float:
        """λ_max = λ_1."""
        return float(self.exponents[0])


class TangentStepper:
    """A system's engine as the stepper of the Benettin loop.

    Build it once and :meth:`reinit` it for every initial condition (the engine class and the
    compiled kernels are reused).

    Parameters
    ----------
    system:
        A :class:`~oscillators.system.ForcedOscillator` (any operator).
    include_phase:
        Also follow the forcing-phase direction φ (its exponent is 0). The paper's spectrum
        neglects it (Poincaré section φ = 0).
    engine_options:
        Passed to the engine (e.g. ``{"method": "generic"}`` for relay systems).
    sample_dt:
        If given, every :meth:`step` also samples ``(t, q, v, M)`` at the multiples of
        ``sample_dt`` (elapsed time since :meth:`reinit`'s start) that it passes, and at its end,
        in the same engine call (:attr:`samples`). With ``sample_dt`` = one forcing period these
        are Poincaré section points, while the QR interval can be several periods long.
    """

    def __init__(
        self,
        system: Any,
        include_phase: bool = False,
        engine_options: dict | None = None,
        sample_dt: float | None = None,
    ) -> None:
        self.system = system
        self.include_phase = bool(include_phase)
        self.engine_options = dict(engine_options or {})
        if sample_dt is not None:
            sample_dt = finite_scalar(sample_dt, "sample_dt")
            if not sample_dt > 0.0:
                raise ValueError(f"sample_dt must be > 0, got {sample_dt}")
        self.sample_dt = sample_dt
        self._engine: Engine | None = None
        self._t = 0.0
        self._events_at_start = 0
        self._out1 = np.full((1, 3), np.nan)
        self._out = self._out1
        self._sample_times: np.ndarray | None = None

    # -- re-initialise ---------------------------------------------------------------------------
    def reinit(self, state: OscillatorState | None = None, transient: float = 0.0) -> None:
        """Start at ``state`` (default: the system's initial state), integrate ``transient``
        time units without the tangent flow, then set the deviations to the identity."""
        transient = finite_scalar(transient, "transient")
        if transient < 0.0:
            raise ValueError(f"transient must be >= 0, got {transient}")
        self._engine = require_tangent_flow(
            self.system.engine(state, **self.engine_options), "it has no Lyapunov exponents"
        )
        self._out1 = np.full((1, len(self._engine.sample_columns)), np.nan)
        self._t = 0.0
        self._advance(transient)
        self._engine.start_tangent(self.include_phase)
        self._events_at_start = self._engine.n_events

    # -- step ------------------------------------------------------------------------------------
    def step_to(self, t: float) -> None:
        """Advance to the elapsed time ``t`` (the Benettin loop's targets):
        ``step(t − elapsed)``."""
        self.step(t - self.elapsed)

    def step(self, dt: float) -> None:
        """Advance by ``dt`` with the tangent flow on."""
        t = self._t + dt
        if self.sample_dt is None:
            self._advance(float(t))
            return
        # multiples of sample_dt strictly inside (t_now, t), then t itself (a multiple that
        # coincides with t up to round-off is t)
        sd = self.sample_dt
        tol = 1e-9 * sd
        k0 = math.floor((self._t + tol) / sd) + 1
        k1 = math.ceil((t - tol) / sd) - 1
        times = np.append(sd * np.arange(k0, k1 + 1, dtype=float), t) if k1 >= k0 else None
        self._advance(t, times)

    def _advance(self, t: float, times: np.ndarray | None = None) -> None:
        eng = self.engine
        if times is None:
            # one target (every QR step without sampling): a reused buffer and a scalar
            # pre-check, because this runs once per re-orthonormalisation
            out = self._out1
            eng.advance(t, out)
            bound = self.system.divergence_bound
            if not (abs(out[0, 0]) <= bound and abs(out[0, 1]) <= bound):  # also catches NaN
                self.system.check_finite(eng, out[:, :2])
        else:
            out = np.empty((times.size, len(eng.sample_columns)))
            eng.advance(times, out)
            self.system.check_finite(eng, out[:, :2])
        self._t = t
        self._sample_times = times
        self._out = out

    def moved_to(self, t: float, rows: np.ndarray) -> None:
        """The engine was advanced to the elapsed time ``t`` outside :meth:`step` (a compiled
        Benettin loop) through the sample rows ``rows`` ``(t, q, v, M)``: they become
        :attr:`samples`."""
        self._t = t
        self._sample_times = rows[:, 0]
        self._out = rows[:, 1:]

    @property
    def sample(self) -> np.ndarray:
        """``(q, v, M)`` now (after the last :meth:`reinit` or :meth:`step`): cheap, unlike
        :meth:`state`, which builds the operator state."""
        return self._out[-1, :3].copy()

    @property
    def samples(self) -> np.ndarray:
        """Rows ``(t, q, v, M)`` sampled by the last :meth:`step` (``sample_dt``; else only its
        end point); ``t`` is the elapsed time since :meth:`reinit`'s start."""
        times = np.array([self._t]) if self._sample_times is None else self._sample_times
        return np.column_stack([times, self._out[:, :3]])

    # -- deviations ------------------------------------------------------------------------------
    @property
    def engine(self) -> Engine:
        """The current engine (after :meth:`reinit`)."""
        if self._engine is None:
            raise RuntimeError("call reinit() first")
        return self._engine

    @property
    def elapsed(self) -> float:
        """Time since :meth:`reinit` (transient included)."""
        return self._t

    @property
    def tangent_space(self) -> tuple[str, ...]:
        """Names of the rows of :meth:`deviations` now."""
        return self.engine.tangent_space

    def deviations(self) -> np.ndarray:
        """Deviation vectors (columns)."""
        return self.engine.deviations()

    def set_deviations(self, y: np.ndarray) -> None:
        """Replace the deviation vectors."""
        self.engine.set_deviations(y)

    def rank_bound(self) -> int:
        """Structural bound of the tangent map's rank since the last set (see module)."""
        return self.engine.rank_bound()

    def state(self) -> OscillatorState:
        """The full state now."""
        return self.engine.state()

    @property
    def n_events(self) -> int:
        """Events since the tangent flow was started."""
        return self.engine.n_events - self._events_at_start


#: a deviation vector whose residual after projection on the vectors before it is below this
#: fraction of its length counts as structurally dependent (module docstring). Structural
#: dependence leaves round-off, ~1e-16; two genuine directions starting orthogonal close their
#: angle only to exp(-Δλ·dt) within one interval, which stays above 1e-10 for Δλ·dt < 23.
DEPENDENT_ANGLE = 1e-10


def _defer_dependent(
    y: np.ndarray, q: np.ndarray, diag: np.ndarray, rank: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Move the deviation vectors that are structurally dependent on the ones before them (a
    residual angle below :data:`DEPENDENT_ANGLE`; a zero vector, residual 0, is one) behind
    the others, at most ``k − rank`` of them, and redo the QR; ``(y, q, diag)`` unchanged when
    the first ``rank`` slots hold independent vectors.

    Why: with the tangent rank ``rank < k`` the QR gives ``R_jj = 0`` to the vectors that depend
    on their predecessors. For a generic basis those sit in the last slots; a neutral memory
    direction that never mixes with the others (a frozen wagon or extremum, δm' = 0) keeps the
    start basis non-generic, so a dependent vector can take a leading slot and push the neutral
    direction's exponent 0 into a -inf slot. The permutation is an orthogonal change of the
    interval's start basis, as for the zero columns."""
    k = y.shape[1]
    moved = 0
    while moved < k - rank:
        norms = np.sqrt(np.sum(y[:, :rank] ** 2, axis=0))
        dependent = np.flatnonzero(diag[:rank] <= DEPENDENT_ANGLE * norms)
        if dependent.size == 0:
            break
        j = int(dependent[0])
        y = y[:, [c for c in range(k) if c != j] + [j]]
        q, diag, _ = householder_qr(np.ascontiguousarray(y))
        moved += 1
    return y, q, diag


def _qr_step(y: np.ndarray, k: int, rank: int, lsum: np.ndarray) -> tuple[np.ndarray, bool]:
    """One re-orthonormalisation: adds log|R_jj| (or -inf beyond ``rank``) to ``lsum``.

    Returns the new deviation matrix (same number of rows as ``y``, ``k`` columns) and whether a
    direction collapsed structurally in this interval.
    """
    q, diag, finite = householder_qr(y if y.flags.c_contiguous else np.ascontiguousarray(y))
    if not finite:
        raise DivergenceError("the tangent flow became non-finite (deviation vectors overflow)")
    m = q.shape[1]
    if rank < k:
        # vectors that collapsed exactly to zero (a relay slide sets δq = δv = 0) or depend on
        # their predecessors go last, so the surviving directions keep the first slots of R
        y, q, diag = _defer_dependent(y, q, diag, min(rank, m))
    collapsed = _accumulate_logs(diag, k, min(rank, m), lsum)
    if m == k:
        return q, collapsed
    new = np.zeros((y.shape[0], k))
    new[:, :m] = q
    return new, collapsed


def _running_estimates(
    sums: list[np.ndarray], times: list[float], transient: float, k: int
) -> np.ndarray:
    """Rows of exponent estimates (descending) from the running log sums at ``times``."""
    if not sums:
        return np.zeros((0, k))
    est = np.asarray(sums) / (np.asarray(times) - transient)[:, None]
    return -np.sort(-est, axis=1)


def lyapunov_spectrum(
    system: Any,
    t_end: float,
    transient: float = 0.0,
    q0: float = DEFAULT_Q0,
    v0: float = DEFAULT_V0,
    operator_state: Any = None,
    include_phase: bool = False,
    progress: bool = False,
    renormalize_dt: float | None = None,
    history_points: int = 200,
    engine_options: dict | None = None,
    *,
    state: OscillatorState | None = None,
    stepper: TangentStepper | None = None,
    observer: Callable[[TangentStepper], None] | None = None,
    whole_intervals: bool = False,
) -> LyapunovResult:
    """Lyapunov spectrum of ``system`` (a :class:`~oscillators.system.ForcedOscillator`).

    Parameters
    ----------
    t_end:
        End of the run (time units); exponents are averaged over ``[transient, t_end]``.
    transient:
        Time integrated without the tangent flow first (time units).
    q0, v0, operator_state:
        Initial condition (defaults: the paper's Table II, the operator rising from negative
        saturation to q0). For other memory pass an explicit operator state, e.g.
        ``play.state(position=w0, input=q0)``. Alternatively a full ``state``.
    include_phase:
        Also follow the forcing-phase direction φ (exponent 0).
    progress:
        tqdm progress bar (off by default; the command line turns it on).
    renormalize_dt:
        Time between re-orthonormalisations (default: one forcing period).
    history_points:
        Number of running estimates kept in ``history``.
    engine_options:
        Passed to the engine.
    stepper:
        A :class:`TangentStepper` of this system to reuse (its ``include_phase`` and
        ``engine_options`` then apply), or a variant that redefines what the loop
        orthonormalises (:meth:`~TangentStepper.deviations`, :meth:`~TangentStepper.set_deviations`,
        :meth:`~TangentStepper.rank_bound` and :attr:`~TangentStepper.tangent_space`, e.g.
        :class:`~analysis.dynamics.memory.MemoryProjectionStepper`).
    observer:
        Called as ``observer(stepper)`` once after the transient and after every
        re-orthonormalisation, so that other measurements ride on the same integration (e.g.
        with ``renormalize_dt`` = one forcing period and ``transient``, ``t_end`` on whole
        periods, ``stepper.sample`` is the Poincaré section; ``stepper.engine.output_integral()``
        gives exact time averages of ``M``). It must not move the stepper. An observer with
        the attribute ``batches = True`` may instead be called once per stretch of intervals
        that a compiled loop ran (relay kernel engines): ``stepper.samples`` then holds the
        samples of the whole stretch.
    whole_intervals:
        Cut ``[transient, t_end]`` into whole intervals of ``renormalize_dt`` and average over
        them, leaving out a remainder (at least one interval); by default the last interval
        ends at ``t_end`` (shorter if need be) and the average runs over the whole window.
    """
    run = _BenettinRun(
        system, t_end, transient, q0, v0, operator_state, include_phase, progress,
        renormalize_dt, history_points, engine_options, state, stepper, observer,
        whole_intervals,
    )  # fmt: skip
    run.run()
    return run.result()


def lyapunov_spectra(
    systems: list,
    t_end: float,
    transient: float = 0.0,
    q0: float = DEFAULT_Q0,
    v0: float = DEFAULT_V0,
    renormalize_dt: float | None = None,
    history_points: int = 200,
    *,
    steppers: list[TangentStepper] | None = None,
    observers: list[Callable[[TangentStepper], None] | None] | None = None,
) -> list[LyapunovResult]:
    """:func:`lyapunov_spectrum` of several systems over the same window, each result bit for
    bit that of the system alone.

    Why: systems on nested relay tables that differ only in their tables (the disorder
    realizations of an ensemble at one N and C) run their compiled Benettin loops side by side
    in the vector units (:func:`~analysis.dynamics._relay_benettin.qr_intervals_lanes`), about
    1.9× faster per system at N = 20 000; any other system, and any interval a lane hands
    back, runs as in :func:`lyapunov_spectrum`. ``steppers`` and ``observers`` (one per system,
    as there) are optional.
    """
    n = len(systems)
    steppers = [None] * n if steppers is None else list(steppers)
    observers = [None] * n if observers is None else list(observers)
    if len(steppers) != n or len(observers) != n:
        raise ValueError(f"give one stepper and one observer per system ({n} systems)")
    options = dict(
        q0=q0, v0=v0, operator_state=None, include_phase=False, progress=False,
        renormalize_dt=renormalize_dt, history_points=history_points, engine_options=None,
        state=None, whole_intervals=False,
    )  # fmt: skip
    runs = [
        _BenettinRun(system, t_end, transient, stepper=stepper, observer=observer, **options)
        for system, stepper, observer in zip(systems, steppers, observers, strict=True)
    ]
    lane_runs = [r for r in runs if r.compiled]
    if len(lane_runs) > 1:
        first = lane_runs[0]
        same = [r for r in lane_runs if (r.n_steps, r.dt, r.window) == (first.n_steps, first.dt,
                                                                       first.window)]  # fmt: skip
        stretches = qr_intervals_lanes(
            [r.stepper for r in same], 0, first.n_steps, first.transient, first.dt,
            first.window, [r.lsum for r in same], first.marked, [r.sums for r in same],
        )  # fmt: skip
        for r, stretch in zip(same, stretches, strict=True):
            if stretch is not None:  # else it runs alone, as in lyapunov_spectrum
                r.compiled_stretch(stretch[0])
    results = []
    for r in runs:
        r.run()
        results.append(r.result())
    return results


class _BenettinRun:
    """One run of the Benettin loop of :func:`lyapunov_spectrum` (its arguments), in steps:
    construction (checks, the transient, the first observation), :meth:`compiled_stretch`
    (intervals a compiled loop ran), :meth:`run` (the loop to the end), :meth:`result`."""

    def __init__(
        self, system, t_end, transient, q0, v0, operator_state, include_phase, progress,
        renormalize_dt, history_points, engine_options, state, stepper, observer,
        whole_intervals,
    ):  # fmt: skip
        t_end, transient = time_window(t_end, transient)
        period = float(system.period)
        if t_end / period > MAX_PERIODS:
            raise ValueError(f"t_end spans more than {MAX_PERIODS:.0e} forcing periods")
        dt = period if renormalize_dt is None else finite_scalar(renormalize_dt, "renormalize_dt")
        if not dt > 0.0:
            raise ValueError(f"renormalize_dt must be > 0, got {renormalize_dt}")
        history_points = positive_integer(history_points, "history_points")
        if stepper is None:
            stepper = TangentStepper(system, include_phase, engine_options)
        elif stepper.system is not system:
            raise ValueError("stepper belongs to another system")
        if state is None:
            state = system.initial_state(q0, v0, operator_state)
        elif operator_state is not None:
            raise ValueError("give either state or operator_state, not both")
        stepper.reinit(state, transient)
        if observer is not None:
            observer(stepper)
        self.system, self.stepper, self.observer = system, stepper, observer
        self.labels = stepper.tangent_space
        k = self.k = len(self.labels)
        span = t_end - transient
        if whole_intervals:
            n_steps = int(math.floor(span / dt + 1e-9))
            if n_steps < 1:
                raise ValueError(
                    f"t_end - transient = {span:g} is shorter than one renormalization "
                    f"interval ({dt:g})"
                )
            window = n_steps * dt
        else:
            n_steps = max(1, int(math.ceil(span / dt - 1e-9)))
            window = span
        self.t_end, self.transient, self.dt, self.window = t_end, transient, dt, window
        self.n_steps, self.whole_intervals = n_steps, whole_intervals
        self.marks = set(
            np.unique(np.linspace(0, n_steps - 1, min(history_points, n_steps)).round())
        )
        self.lsum = np.zeros(k)
        self.hist_t: list[float] = []
        self.hist: list[np.ndarray] = []
        self.n_collapses = 0
        self.bar = None
        if progress:
            self.bar = progress_bar(total=n_steps, desc="Lyapunov spectrum", unit="QR", leave=False)
        # the relay kernel runs stretches of QR intervals itself (bit for bit this loop, without
        # its Python per interval); an interval it cannot (a slide, an error) runs here
        self.compiled = (
            type(stepper) is TangentStepper
            and hasattr(stepper.engine, "kernel_arrays")
            and (observer is None or getattr(observer, "batches", False))
        )
        if self.compiled:
            self.marked = np.zeros(n_steps, dtype=np.bool_)
            self.marked[np.array(sorted(self.marks), dtype=np.int64)] = True
            self.sums = np.zeros((n_steps, k))
        self.i = self.backoff = self.skip = 0

    def compiled_stretch(self, done: int) -> None:
        """Book ``done`` intervals from ``i`` that a compiled loop ran (log sums and ``sums``
        already updated, the stepper after them): the observer, the history, the progress."""
        i = self.i
        if done and self.observer is not None:
            self.observer(self.stepper)
        for j in range(i, i + done):
            if self.marked[j]:
                last = j == self.n_steps - 1
                self.hist_t.append(self.transient + (self.window if last else (j + 1) * self.dt))
                self.hist.append(self.sums[j].copy())
        if self.bar is not None:
            self.bar.update(done)
        self.i = i + done
        # an interval the kernel left to the Python loop: a few there before trying again
        self.backoff = 0 if done else min(2 * self.backoff + 1, 64)
        self.skip = self.backoff + 1

    def run(self) -> None:
        """The loop from interval ``i`` to the end."""
        stepper, k = self.stepper, self.k
        while self.i < self.n_steps:
            if self.compiled and self.skip == 0:
                done, _ = qr_intervals(
                    stepper, self.i, self.n_steps, self.transient, self.dt, self.window,
                    self.lsum, self.marked, self.sums,
                )  # fmt: skip
                self.compiled_stretch(done)
                if self.i >= self.n_steps:
                    break
            self.skip = max(self.skip - 1, 0)
            i = self.i
            last = i == self.n_steps - 1
            target = self.transient + (self.window if last else (i + 1) * self.dt)
            stepper.step_to(target)
            y, collapsed = _qr_step(stepper.deviations(), k, stepper.rank_bound(), self.lsum)
            self.n_collapses += int(collapsed)
            stepper.set_deviations(y)
            if self.observer is not None:
                self.observer(stepper)
            if i in self.marks:  # the running sums; the estimates are formed once, at the end
                self.hist_t.append(target)
                self.hist.append(self.lsum.copy())
            if self.bar is not None:
                self.bar.update(1)
            self.i = i + 1
        if self.bar is not None:
            self.bar.close()
            self.bar = None

    def result(self) -> LyapunovResult:
        exponents = -np.sort(-self.lsum / self.window)
        stepper = self.stepper
        return LyapunovResult(
            exponents=exponents,
            tangent_space=tuple(self.labels),
            history_t=np.asarray(self.hist_t),
            history=_running_estimates(self.hist, self.hist_t, self.transient, self.k),
            n_switches=int(stepper.n_events),
            t_end=self.transient + self.window if self.whole_intervals else self.t_end,
            transient=self.transient,
            kaplan_yorke=kaplan_yorke_dimension(exponents),
            final=stepper.state(),
            extra={
                "engine": describe_engine(stepper.engine.name, self.system.operator),
                "renormalize_dt": self.dt,
                "n_collapses": self.n_collapses,
            },
        )
