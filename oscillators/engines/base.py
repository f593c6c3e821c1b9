"""The engine seam: one interface between the forced oscillator and every integrator.

:class:`~oscillators.system.ForcedOscillator` knows an operator only through its contract
(:mod:`hysteresis.base`). It asks the operator once what it can hand over and picks the engine
from the answer (:func:`select_engine`), never by ``isinstance`` on operator classes:

* ``operator.piecewise_constant`` -> :class:`~oscillators.engines.relay.RelayEngine`
  (exact event-driven integration: closed-form propagation between switches, saltation
  ``C·ΔM/v*`` at each switch; an O(1) kernel when the thresholds nest, an O(log N) heap kernel
  for arbitrary relays);
* ``operator.compiled_play()`` not ``None`` -> the compiled play-limit engine
  (:class:`~oscillators.engines.play.PlayEngine`; plain play and
  ``GeneralizedPlay.erf``: the paper's thermodynamic limit, a fast path);
* ``operator.compiled_flow()`` not ``None`` -> the compiled continuous engine
  (:class:`~oscillators.engines.compiled_continuous.CompiledContinuousEngine`;
  Prandtl–Ishlinskii, continuous Preisach: the generic engine's physics in a numba kernel);
* any other continuous operator -> the generic continuous engine
  (:class:`~oscillators.engines.continuous.ContinuousEngine`) over
  ``operator.branch_flow(state, direction)`` (also reachable for the operators above with
  ``engine_options={"method": "generic"}``, the reference).

Everything above an engine — trajectories, Poincaré sections, the stroboscopic map, flow-map
Jacobians (:mod:`oscillators.system`) and the one Benettin/QR loop of
:mod:`analysis.dynamics.lyapunov` — is written once against :class:`Engine`.

Engine contract
---------------
An engine is a mutable integrator of one trajectory of the coupled system started from an
:class:`~oscillators.results.OscillatorState` (time ``t0``, phase ``φ0``). Time is measured as
*elapsed time since the start*; engines keep it internally as (period index, time in period) or
in any other exact way, so the forcing phase ``φ0 + Ω·elapsed`` never loses digits.

Motion
    ``advance(times, out=None, record=False)`` moves through the sorted elapsed times (each
    ``>=`` the current one); row ``i`` of ``out`` receives ``(q, v, M)`` at ``times[i]`` and
    the extra sampled columns named by :attr:`Engine.sample_columns` after the first three.
    With ``record`` every event (relay switch; wall hit or reversal; ...) is kept for
    :meth:`Engine.records`. ``state()`` is the full :class:`OscillatorState` now.
    ``output_integral()`` is ``∫ M dt`` since the start where the engine can give it exactly
    (relay engines; time averages such as the paper's ``M_T`` come from it in the same pass as
    the tangent flow), else ``NotImplementedError``.
Tangent flow (:class:`TangentFlow`, a second base an engine adds)
    ``start_tangent(include_phase)`` switches the variational flow on with the identity as
    deviation vectors. :attr:`TangentFlow.tangent_space` names the rows of the deviation matrix:
    ``("q", "v"[, "phi"], *memory)`` where ``memory`` are the operator's memory directions
    (none for relays; ``"w"`` for the play; the wagon positions of a Prandtl–Ishlinskii
    operator; the remembered extrema of a continuous Preisach staircase, a number that changes
    along the orbit). ``deviations()`` returns the current matrix (rows as in ``tangent_space``
    now, one column per tracked vector), ``set_deviations(y)`` replaces it (same shape), and
    ``rank_bound()`` is an upper bound of the rank of the tangent map since the last
    ``start_tangent``/``set_deviations`` that is known *structurally* (from events, not from
    round-off): a play wall hit resets ``δw := δq`` and removes the ``w`` direction, a wiped-out
    extremum removes its direction. The QR loop records exactly ``-inf`` for the directions
    beyond that bound (the paper's ``λ = -∞``) instead of the log of a round-off remainder.

What every engine shares lives here, in :class:`Engine`: the clock (period index and time in the
period, the forcing phase, ``elapsed``), the checks of requested times (one tolerance,
:data:`TIME_TOLERANCE`) and the divergence test (one bound, the system's
``ForcedOscillator.divergence_bound``); the tangent bookkeeping (the flow is on, the shape of
``set_deviations``) lives in :class:`TangentFlow`. An engine writes five motion members
(``_clock``, ``_advance``, ``state``, ``records``, ``n_events``) and, with a tangent flow, five
more (``_start_tangent``, ``tangent_space``, ``_deviations``, ``_set_deviations``,
``_rank_bound``). This module never imports an engine; :mod:`oscillators.engines.select`
does.

Engines raise :class:`DivergenceError` when the state becomes non-finite or runs away, and
:class:`GrazingError` (piecewise-constant operators) when a switch happens at a turning point
while the tangent flow is on. Work per ``advance`` call is bounded, proportional to the
advanced time: :class:`SwitchBudgetError` (relay engines, :data:`SWITCHES_PER_RELAY_AND_TIME`;
a chattering towards a sliding motion that does not settle within it: :class:`SlidingError`)
and :class:`StepBudgetError` (play kernel and continuous engine, :data:`STEPS_PER_TIME`).
Filippov sliding on a relay threshold is integrated (:mod:`oscillators.engines._sliding`).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from typing import Any

import numpy as np

from hysteresis._validation import real_array
from oscillators.engines._compilation import first_use_notice
from oscillators.results import OscillatorState

__all__ = [
    "DivergenceError",
    "Engine",
    "GrazingError",
    "SLIDE_EXCURSION",
    "STEPS_PER_TIME",
    "STEP_BUDGET_FLOOR",
    "StepBudgetError",
    "SWITCH_BUDGET_FLOOR",
    "SWITCHES_PER_RELAY_AND_TIME",
    "SlidingError",
    "SwitchBudgetError",
    "SWITCH_DTYPE",
    "TIME_TOLERANCE",
    "TangentFlow",
    "require_tangent_flow",
    "TangentFlowOff",
    "split_times",
    "step_budget",
    "switch_budget",
    "grazing_message",
    "wrap_phase",
]

#: Relative tolerance of :meth:`Engine.advance` for a requested time before the current one
#: (``t < now - TIME_TOLERANCE·max(1, |now|)`` is refused; later rounding is accepted).
TIME_TOLERANCE = 1e-12
#: Fields of ``records()["switches"]`` of piecewise-constant engines (and of
#: ``Trajectory.switches``): time, q, v and the jump ΔM of the output.
SWITCH_DTYPE = np.dtype([("time", "f8"), ("q", "f8"), ("v", "f8"), ("jump", "f8")])


class DivergenceError(RuntimeError):
    """The coupled system left every bounded region (non-finite or runaway state).

    Raised instead of returning numbers computed from a diverged orbit. ``time`` is the
    (absolute) time at which it was detected, ``cause`` a short explanation.
    """

    def __init__(self, message: str, time: float | None = None) -> None:
        super().__init__(message)
        self.time = time


class GrazingError(ValueError):
    """A switch at a turning point (``v* = 0``) while the tangent flow is propagated.

    The grazing rule makes a maximum that reaches an upper threshold switch; the saltation
    ``C·ΔM/v*`` of that switch is infinite, so the flow map is not differentiable on this orbit
    and Lyapunov exponents / Jacobians are undefined. A ``ValueError`` subclass so that callers
    reporting bad input also report this.
    """


#: Work bound of the event-driven engines: switches allowed per relay and per unit of time
#: (times ``max(1, Ω)``) in one ``advance`` call, plus :data:`SWITCH_BUDGET_FLOOR` per call.
#: Ordinary motion switches a relay about ``Ω/π`` times per unit time; beyond this budget the
#: call stops with :class:`SlidingError` (chattering on a threshold) or
#: :class:`SwitchBudgetError`, so no call runs (or records switches) without bound.
SWITCHES_PER_RELAY_AND_TIME = 1000
#: Switches every ``advance`` call may make whatever its length (see above).
SWITCH_BUDGET_FLOOR = 10_000


def switch_budget(n_relays: int, omega: float, span: float) -> int:
    """Switches one ``advance`` call spanning ``span`` time units may make
    (:data:`SWITCHES_PER_RELAY_AND_TIME` per relay and unit of time, at least
    :data:`SWITCH_BUDGET_FLOOR`)."""
    b = SWITCH_BUDGET_FLOOR + SWITCHES_PER_RELAY_AND_TIME * max(1, n_relays) * max(
        1.0, omega
    ) * max(span, 0.0)
    return int(min(b, 2.0**62))


def grazing_message(t: float | None = None) -> str:
    """The one sentence of a :class:`GrazingError` (at time ``t`` when known)."""
    where = f" at t = {t!r}" if t is not None else ""
    return (
        f"grazing switch{where}: a threshold was reached exactly at a turning point (v* = 0), "
        "so the saltation C·ΔM/v* is infinite and the tangent flow is undefined on this orbit; "
        "perturb the initial condition or the parameters"
    )


class SwitchBudgetError(RuntimeError):
    """An ``advance`` call exceeded the switch budget (:data:`SWITCHES_PER_RELAY_AND_TIME`).

    ``time`` is the absolute time at which the budget ran out, ``budget`` the number of
    switches the call was allowed.
    """

    def __init__(self, message: str, time: float | None = None, budget: int | None = None):
        super().__init__(message)
        self.time = time
        self.budget = budget


#: Relay engines: a chattering across a zero-width threshold that pushes in from both sides
#: is set on the Filippov sliding set ``q = θ, v = 0`` once an excursion lasts at most
#: ``SLIDE_EXCURSION/ρ`` (``ρ = max(1, Ω, 2ζ)``), i.e. ``|v| <= ½|q''|·SLIDE_EXCURSION/ρ``;
#: that change of ``v`` is the error of entering the slide (:mod:`oscillators.engines._sliding`).
SLIDE_EXCURSION = 1e-3


class SlidingError(ValueError):
    """A chattering towards a Filippov sliding motion that did not settle within the budget.

    The relay engines integrate sliding motions (:mod:`oscillators.engines._sliding`): the
    chattering across a zero-width threshold is set on the sliding set once its excursions are
    short (:data:`SLIDE_EXCURSION`). This error is left for a call whose switch budget runs out
    while the flow pushes into a threshold from both sides before that happened (the
    chattering decays too slowly, e.g. at very weak damping). ``time`` is the absolute time,
    ``threshold`` the value of q.
    """

    def __init__(self, message: str, time: float | None = None, threshold: float | None = None):
        super().__init__(message)
        self.time = time
        self.threshold = threshold


#: Work bound of the stepping engines (play kernel, continuous engine): steps and events
#: allowed per unit of time (times ``max(1, Ω, 2ζ)``) in one ``advance`` call, plus
#: :data:`STEP_BUDGET_FLOOR` per call; beyond it the call stops with :class:`StepBudgetError`.
#: Ordinary motion takes a few hundred steps per unit time (the play kernel's fixed DOP853 step
#: is 0.05/max(1, Ω); solve_ivp at rtol 1e-11 a few dozen), so the bound only ends runaway work.
STEPS_PER_TIME = 100_000
#: Steps and events every ``advance`` call of a stepping engine may make whatever its length.
STEP_BUDGET_FLOOR = 100_000


class StepBudgetError(RuntimeError):
    """An ``advance`` call of a stepping engine exceeded its work budget
    (:data:`STEPS_PER_TIME`). ``time`` is the absolute time at which it ran out, ``budget``
    the number of steps and events the call was allowed."""

    def __init__(self, message: str, time: float | None = None, budget: int | None = None):
        super().__init__(message)
        self.time = time
        self.budget = budget


def step_budget(omega: float, zeta: float, span: float) -> int:
    """Steps and events one ``advance`` call of a stepping engine spanning ``span`` may make."""
    b = STEP_BUDGET_FLOOR + STEPS_PER_TIME * max(1.0, omega, 2.0 * zeta) * max(span, 0.0)
    return int(min(b, 2.0**62))


def wrap_phase(phi: float) -> float:
    """``phi`` mod 2π in [0, 2π)."""
    two_pi = 2.0 * math.pi
    wrapped = math.fmod(phi, two_pi)
    if wrapped < 0.0:
        wrapped += two_pi
    # fmod of a tiny negative number plus 2π rounds to exactly 2π
    return 0.0 if wrapped >= two_pi else wrapped


#: Arrays of at most this many values are checked and split in plain Python: the few targets
#: of one Lyapunov QR step cost 2x less than through numpy's per-call overhead (measured,
#: benchmarks/bench_ensemble.py's "engine Python per QR step"); the same bits either way.
SHORT_ARRAY = 64


def split_times(times: np.ndarray, period: float) -> tuple[np.ndarray, np.ndarray]:
    """Elapsed times as (period index, time within the period in [0, T))."""
    times = np.asarray(times, dtype=np.float64)
    if times.ndim == 1 and times.size <= SHORT_ARRAY:
        ns, taus = [], []
        for t in times.tolist():  # the numpy lines below, value by value
            n = math.floor(t / period)
            tau = t - float(n) * period
            if tau >= period:
                n, tau = n + 1, 0.0
            elif tau < 0.0:
                tau = 0.0
            ns.append(n)
            taus.append(tau)
        return np.array(ns, dtype=np.int64), np.array(taus, dtype=np.float64)
    n = np.floor(times / period).astype(np.int64)
    tau = times - n * period
    fix = tau >= period
    n[fix] += 1
    tau[fix] = 0.0
    tau[tau < 0.0] = 0.0
    return n, tau


class Engine(ABC):
    """Integrator of one trajectory of a :class:`~oscillators.system.ForcedOscillator`: the
    motion contract.

    A subclass implements five members: :meth:`_clock`, :meth:`_advance`, :meth:`state`,
    :meth:`records` and :attr:`n_events` (see the module docstring for the contract);
    :attr:`sample_columns` and :meth:`output_integral` have defaults. An engine with a tangent
    flow also derives from :class:`TangentFlow` (every engine of this package does). Engines are
    created by :meth:`ForcedOscillator.engine`.

    The clock: an engine reports its time as (period index ``n``, time ``tau`` since the start
    of that period) through :meth:`_clock`; ``elapsed = n·T + tau`` and the forcing phase
    ``φ0 + Ω·tau`` (mod 2π) follow here, so the phase never loses digits on long runs. The
    public :meth:`advance` checks the requested times and ``out`` here, always, then calls the
    engine's :meth:`_advance`.
    """

    #: Short name reported in results (``"relay kernel"``, ``"play kernel"``, ...).
    name: str = "engine"
    #: The module of the engine's compiled kernels (its first use warns while numba compiles
    #: them, :mod:`oscillators.engines._compilation`); ``None`` for a Python engine.
    kernel_module: str | None = None

    def __init__(self, system: Any, state: OscillatorState) -> None:
        first_use_notice(type(self).kernel_module, type(self).name)
        self.system = system
        self.start = state
        self._omega = float(system.frequency)
        self._period = 2.0 * math.pi / self._omega
        self._phi0 = float(state.phi)
        self._one_time = np.zeros(1)  # the single target of a float advance (see advance)

    @classmethod
    def check_system(cls, system: Any) -> None:
        """Refuse, at the system's construction, parameters or an operator this engine class
        cannot integrate (default: no requirement)."""
        return None

    # -- the clock -----------------------------------------------------------------------------
    @abstractmethod
    def _clock(self) -> tuple[int, float]:
        """(period index, time since the start of that period) now."""

    @property
    def period(self) -> float:
        """Forcing period T = 2π/Ω."""
        return self._period

    @property
    def elapsed(self) -> float:
        """Time since the start state."""
        n, tau = self._clock()
        return n * self._period + tau

    def phase(self) -> float:
        """Forcing phase now, in [0, 2π)."""
        return wrap_phase(self._phi0 + self._omega * self._clock()[1])

    def _check_first_time(self, first: float) -> None:
        """Refuse a first requested time before now (beyond :data:`TIME_TOLERANCE`)."""
        now = self.elapsed
        if first < now - TIME_TOLERANCE * max(1.0, abs(now)):
            raise ValueError(f"times must be >= the current elapsed time {now!r}, got {first!r}")

    def _target_times(self, times: np.ndarray | float) -> np.ndarray:
        """``times`` as a checked 1-D array: finite, sorted, not before now (may be empty)."""
        if (
            type(times) is np.ndarray
            and times.ndim == 1
            and times.dtype == np.float64
            and 0 < times.size <= SHORT_ARRAY
        ):
            values = times.tolist()  # the checks below, in plain Python (see SHORT_ARRAY)
            if not all(map(math.isfinite, values)):
                raise ValueError("times must be finite")
            if any(b < a for a, b in zip(values[:-1], values[1:], strict=True)):
                raise ValueError("times must be sorted")
            self._check_first_time(values[0])
            return times
        times = real_array(times, "times")
        if times.ndim > 1:
            raise ValueError("times must be a scalar or a 1-D array")
        times = np.atleast_1d(times)
        if times.size == 0:
            return times
        if not np.all(np.isfinite(times)):
            raise ValueError("times must be finite")
        if np.any(np.diff(times) < 0.0):
            raise ValueError("times must be sorted")
        self._check_first_time(float(times[0]))
        return times

    def _check_out(self, out: np.ndarray | None, n_rows: int) -> None:
        if out is not None and (out.ndim != 2 or out.shape[0] != n_rows or out.shape[1] < 3):
            raise ValueError(f"out must have shape ({n_rows}, >= 3), got {out.shape}")

    # -- divergence ----------------------------------------------------------------------------
    def check_finite(self, values: np.ndarray, times: np.ndarray | None = None) -> None:
        """Raise :class:`DivergenceError` if ``values`` (rows of states, first columns q and v)
        are not finite or have run away (above the system's ``divergence_bound``).

        ``times`` (elapsed, one per row) locate the first bad row in the message.
        """
        values = np.asarray(values, dtype=np.float64)
        bound = self.system.divergence_bound
        if values.size <= 4 * SHORT_ARRAY and all(  # False for NaN: the full test below
            abs(x) <= bound for x in values.ravel().tolist()
        ):
            return
        good = np.isfinite(values) & (np.abs(values) <= bound)
        if good.all():
            return
        rows = good.reshape(values.shape[0], -1).all(axis=1) if values.ndim > 1 else good
        first = int(np.argmin(rows)) if values.ndim > 1 else 0
        elapsed = self.elapsed if times is None else float(np.asarray(times)[first])
        t = self.start.t + elapsed
        raise DivergenceError(
            f"the motion diverged by t = {t:.6g} (non-finite or |q|, |v| > "
            f"{bound:.0e}) for {self.system!r}; "
            "an unbounded operator with C·slope >= 1 is a positive-feedback instability",
            time=t,
        )

    # -- motion --------------------------------------------------------------------------------
    @property
    def sample_columns(self) -> tuple[str, ...]:
        """Names of the columns :meth:`advance` writes: ``("q", "v", "M", ...)``."""
        return ("q", "v", "M")

    def advance(
        self, times: np.ndarray | float, out: np.ndarray | None = None, record: bool = False
    ) -> None:
        """Move through the sorted elapsed ``times``; fill ``out`` rows (see module docstring).

        The checks of ``times`` and ``out`` live here, once; engines implement :meth:`_advance`.
        A float ``times`` (one target: the Lyapunov stepper's call once per QR interval) is
        checked as a scalar and handed over in a reused one-element array, without the array
        validation.
        """
        if type(times) is float:
            if not math.isfinite(times):
                raise ValueError("times must be finite")
            self._check_first_time(times)
            self._check_out(out, 1)
            one = self._one_time
            one[0] = times
            self._advance(one, out, bool(record))
            return
        times = self._target_times(times)
        if times.size == 0:
            return
        self._check_out(out, times.size)
        self._advance(times, out, bool(record))

    @abstractmethod
    def _advance(self, times: np.ndarray, out: np.ndarray | None, record: bool) -> None:
        """:meth:`advance` after the checks: ``times`` a non-empty sorted 1-D array not before
        now (read it during the call, do not keep it: the base reuses a one-element array),
        ``out`` ``None`` or of ``(times.size, >= 3)``."""

    @abstractmethod
    def state(self) -> OscillatorState:
        """The full state now (operator state included)."""

    @abstractmethod
    def records(self) -> dict[str, np.ndarray]:
        """Events recorded while ``record`` was on, as structured arrays by kind.

        Piecewise-constant engines give ``{"switches": time, q, v, jump}``; the play engines
        ``{"events": time, q, v, kind, w}`` (kind +1 the input leaves the play onto a wall,
        -1 it enters the play).
        """

    def output_integral(self) -> float:
        """``∫ M dt`` over the elapsed time (for exact time averages of the output).

        Engines that cannot give it exactly raise ``NotImplementedError`` (the relay engine
        accumulates it per hop; continuous engines would need a quadrature of ``M``).
        """
        raise NotImplementedError(
            f"the {self.name} engine does not accumulate the time integral of the output M"
        )

    @property
    @abstractmethod
    def n_events(self) -> int:
        """Number of events (switches, wall hits, reversals) since the start."""


class TangentFlow(ABC):
    """The tangent (variational) flow an engine adds to its motion: ``class MyEngine(TangentFlow,
    Engine)``.

    What Lyapunov spectra (:mod:`analysis.dynamics.lyapunov`), flow-map Jacobians
    (:meth:`ForcedOscillator.jacobian <oscillators.system.ForcedOscillator.jacobian>`) and
    periodic orbits need; an engine that only moves (:class:`Engine`) does without it. The
    checks live here, once: :meth:`start_tangent` records the number of tracked vectors
    (``_ntan``, 0 while the flow is off, which the engine's integration reads);
    :meth:`deviations`, :meth:`set_deviations` and :meth:`rank_bound` check that the flow is on
    and the shape of what is set, then call the engine's ``_deviations``, ``_set_deviations``,
    ``_rank_bound``. An engine implements those three, ``_start_tangent`` and
    :attr:`tangent_space` (module docstring: the meaning of each).
    """

    #: tracked tangent vectors; 0: the tangent flow is off (set by :meth:`start_tangent`)
    _ntan: int = 0

    def start_tangent(self, include_phase: bool = False) -> None:
        """Switch the variational flow on; deviations := identity on :attr:`tangent_space`."""
        self._ntan = self._start_tangent(bool(include_phase))

    @abstractmethod
    def _start_tangent(self, include_phase: bool) -> int:
        """Set the deviations to the identity; returns the number of tracked vectors."""

    @property
    @abstractmethod
    def tangent_space(self) -> tuple[str, ...]:
        """Names of the rows of :meth:`deviations` now."""

    def deviations(self) -> np.ndarray:
        """Current deviation vectors as columns (a copy)."""
        self._need_tangent()
        return self._deviations()

    def set_deviations(self, y: np.ndarray) -> None:
        """Replace the deviation vectors (same shape as :meth:`deviations`)."""
        self._need_tangent()
        y = np.asarray(y, dtype=np.float64)
        shape = (len(self.tangent_space), self._ntan)
        if y.shape != shape:
            raise ValueError(f"deviations must have shape {shape}, got {y.shape}")
        self._set_deviations(y)

    def rank_bound(self) -> int:
        """Structural bound of the tangent map's rank since the last start/set (see module)."""
        self._need_tangent()
        return self._rank_bound()

    @abstractmethod
    def _deviations(self) -> np.ndarray:
        """The deviation matrix (rows :attr:`tangent_space`, ``_ntan`` columns), a copy."""

    @abstractmethod
    def _set_deviations(self, y: np.ndarray) -> None:
        """Replace the deviations by ``y`` (shape checked)."""

    @abstractmethod
    def _rank_bound(self) -> int:
        """The structural rank bound since the last start/set (module docstring)."""

    def _need_tangent(self) -> None:
        if self._ntan == 0:
            raise TangentFlowOff("the tangent flow is off: call start_tangent() first")


def require_tangent_flow(engine: Engine, consequence: str) -> TangentFlow:
    """``engine`` itself if it has a tangent flow, else a one-sentence ``TypeError`` ending in
    ``consequence`` (what the caller cannot do without it)."""
    if not isinstance(engine, TangentFlow):
        raise TypeError(
            f"the {engine.name} engine has no tangent flow (it does not derive from "
            f"oscillators.engines.TangentFlow), so {consequence}"
        )
    return engine


class TangentFlowOff(RuntimeError, ValueError):
    """Deviations asked for before :meth:`TangentFlow.start_tangent` (a ``RuntimeError`` and, as
    the relay engine raised before, a ``ValueError``)."""
