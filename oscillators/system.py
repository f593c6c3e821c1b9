"""The forced oscillator coupled to a hysteresis operator, as a system object.

Paper eq. (eom_2): ``q'' + 2ζ q' + q = cos φ + C·M[q]``, ``φ' = Ω``, state
``x = (q, v = q', φ)`` plus the operator's memory (its state object). The system holds the
parameters and the operator; it asks the operator's contract once which engine integrates it
(:func:`oscillators.engines.select_engine`) and writes every derived map once on top of the
:class:`~oscillators.engines.base.Engine` interface: trajectories, Poincaré (stroboscopic)
sections, the stroboscopic map and flow-map Jacobians. Lyapunov spectra live in
:mod:`analysis.dynamics.lyapunov`.

Every driver checks the state it reports: a non-finite or runaway state raises
:class:`~oscillators.engines.base.DivergenceError` naming the time, never a number.
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np

from hysteresis._progress import progress_bar
from hysteresis._validation import nonnegative_integer, positive_integer
from hysteresis.base import Hysteron, HysteronState
from oscillators.engines import (
    DivergenceError,
    Engine,
    describe_engine,
    require_tangent_flow,
    select_engine,
    wrap_phase,
)
from oscillators.engines.base import SWITCH_DTYPE
from oscillators.parameters import (
    DEFAULT_DAMPING_RATIO,
    DEFAULT_FREQUENCY,
    DEFAULT_Q0,
    DEFAULT_V0,
    MAX_PERIODS,
    MAX_SAMPLES,
    check_coupling,
    check_oscillator,
    real_parameter,
)
from oscillators.results import OscillatorState, PoincareSection, Trajectory

__all__ = ["ForcedOscillator"]


class ForcedOscillator:
    """Driven damped oscillator with hysteretic feedback ``C·M[q]``.

    Parameters
    ----------
    operator:
        Any :class:`~hysteresis.base.Hysteron` whose contract hands over what an engine needs
        (``relay_table()`` for piecewise-constant operators, ``branch_flow()`` for continuous
        ones). Checked here, not first at integration time.
    coupling:
        C, strength of the hysteresis force (finite, any sign, ``|C| <= 1e6``).
    damping_ratio:
        ζ in [0, 1e6]; the compiled play-limit engine needs ζ < 1 (underdamped closed form).
    frequency:
        Ω in [1e-6, 1e6], the excitation frequency (Table II: 1.0). ζ = 0 with Ω = 1 (undamped
        resonance) is rejected.

    Notes
    -----
    An operator with unbounded output and slope ``s`` on a branch gives the stiffness
    ``1 − C·s`` there; for ``C·s >= 1`` the coupled motion is a positive-feedback instability
    (the plain play at ``C >= 1``). Such systems (``C·max_slope >= 1`` with the operator's
    :attr:`~hysteresis.base.Hysteron.max_slope`, slope 1 assumed when it is ``None``) are
    accepted with a ``RuntimeWarning`` and any run that diverges raises
    :class:`~oscillators.engines.base.DivergenceError`.
    """

    #: ``|q|`` or ``|v|`` above this counts as diverged (:meth:`check_finite`), in every engine
    divergence_bound = 1e12

    def __init__(
        self,
        operator: Hysteron,
        coupling: float,
        damping_ratio: float = DEFAULT_DAMPING_RATIO,
        frequency: float = DEFAULT_FREQUENCY,
    ) -> None:
        if not isinstance(operator, Hysteron):
            raise TypeError(f"operator must be a Hysteron, got {type(operator).__name__}")
        coupling = check_coupling(coupling)
        zeta, omega = check_oscillator(damping_ratio, frequency)
        self._operator = operator
        self._coupling = coupling
        self._zeta = zeta
        self._omega = omega
        # the engine class, once, from the operator's contract; it refuses what it cannot
        # integrate (parameters, an incomplete contract) here, without integrating
        self._engine_cls = select_engine(operator)
        self._engine_cls.check_system(self)
        lo, hi = operator.output_range
        if math.isinf(lo) or math.isinf(hi):
            slope = operator.max_slope
            known = slope is not None
            slope = float(slope) if known else 1.0
            if coupling * slope >= 1.0:
                warnings.warn(
                    f"{operator!r} has an unbounded output; with coupling C = {coupling} and "
                    f"largest branch slope {slope:g}{'' if known else ' (assumed)'}, "
                    f"C·slope = {coupling * slope:g} >= 1: the stiffness 1 − C·slope vanishes "
                    "or turns negative on that branch (positive-feedback instability): runs may "
                    "diverge and then raise DivergenceError",
                    RuntimeWarning,
                    stacklevel=2,
                )

    # -- parameters --------------------------------------------------------------------------
    @property
    def operator(self) -> Hysteron:
        """The hysteresis operator M."""
        return self._operator

    @property
    def coupling(self) -> float:
        """C, the strength of the hysteretic force."""
        return self._coupling

    @property
    def damping_ratio(self) -> float:
        """ζ."""
        return self._zeta

    @property
    def frequency(self) -> float:
        """Ω."""
        return self._omega

    @property
    def period(self) -> float:
        """Forcing period T = 2π/Ω."""
        return 2.0 * math.pi / self._omega

    @property
    def engine_class(self) -> type[Engine]:
        """The engine chosen for the operator (from its contract)."""
        return self._engine_cls

    @property
    def engine_description(self) -> str:
        """The engine's name, and why a composite runs on the generic engine where it does."""
        name = getattr(self._engine_cls, "name", self._engine_cls.__name__)
        return describe_engine(name, self._operator)

    def __repr__(self) -> str:
        return (
            f"ForcedOscillator({self._operator!r}, coupling={self._coupling!r}, "
            f"damping_ratio={self._zeta!r}, frequency={self._omega!r})"
        )

    # -- states and engines --------------------------------------------------------------------
    def initial_state(
        self,
        q0: float = DEFAULT_Q0,
        v0: float = DEFAULT_V0,
        operator_state: HysteronState | None = None,
        phi0: float = 0.0,
        t0: float = 0.0,
    ) -> OscillatorState:
        """The full state at ``t0``; ``operator_state=None`` means ``initial_state(q0)``.

        The paper's initial condition (Table II) is ``q0 = -1, v0 = 0.1`` with the operator
        rising from negative saturation to ``q0`` (all spins down, then relaxed; the play's
        ``w0 = q0 − p/2``). Any other memory is passed as an explicit operator state, e.g.
        ``play.state(position=w0, input=q0)``.
        """
        q0 = real_parameter(q0, "q0")
        v0 = real_parameter(v0, "v0")
        phi0 = real_parameter(phi0, "phi0")
        t0 = real_parameter(t0, "t0")
        if operator_state is None:
            operator_state = self._operator.initial_state(q0)
        return OscillatorState(
            q=q0, v=v0, phi=wrap_phase(phi0), operator_state=operator_state, t=t0
        )

    def engine(self, state: OscillatorState | None = None, **engine_options: Any) -> Engine:
        """A fresh engine started from ``state`` (default: :meth:`initial_state`)."""
        if state is None:
            state = self.initial_state()
        if not isinstance(state, OscillatorState):
            raise TypeError(f"state must be an OscillatorState, got {type(state).__name__}")
        return self._engine_cls(self, state, **engine_options)

    def check_finite(
        self, engine: Engine, values: np.ndarray, times: np.ndarray | None = None
    ) -> None:
        """Raise :class:`DivergenceError` if ``values`` (rows of states just computed, first
        columns q and v) are not finite or have run away (``|q|`` or ``|v|`` above
        :attr:`divergence_bound`): :meth:`Engine.check_finite`, the one divergence test.

        ``times`` (elapsed, one per row) locate the first bad row in the message.
        """
        engine.check_finite(values, times)

    # -- derived maps --------------------------------------------------------------------------
    def trajectory(
        self,
        t_end: float,
        q0: float = DEFAULT_Q0,
        v0: float = DEFAULT_V0,
        operator_state: HysteronState | None = None,
        sample_dt: float = 0.01,
        phi0: float = 0.0,
        *,
        engine_options: dict | None = None,
        progress: bool = False,
    ) -> Trajectory:
        """Samples every ``sample_dt`` on [0, t_end] (and at ``t_end``) plus every event.

        ``switches`` lists the relay switches (time, q, v, jump) of piecewise-constant
        operators; ``events`` the wall hits / reversals of play-type engines; ``w`` the sampled
        wagon position where the engine reports it.
        """
        t_end = real_parameter(t_end, "t_end")
        sample_dt = real_parameter(sample_dt, "sample_dt")
        if not t_end > 0.0:
            raise ValueError(f"t_end must be > 0, got {t_end}")
        if not sample_dt > 0.0:
            raise ValueError(f"sample_dt must be > 0, got {sample_dt}")
        n = int(math.floor(t_end / sample_dt * (1.0 + 1e-12))) + 1
        if n > MAX_SAMPLES:
            raise ValueError(
                f"t_end / sample_dt = {t_end / sample_dt:.3g} samples exceeds the limit "
                f"{MAX_SAMPLES:.0e}; increase sample_dt"
            )
        self._check_periods(t_end, "t_end")
        start = self.initial_state(q0, v0, operator_state, phi0)
        eng = self.engine(start, **(engine_options or {}))
        times = np.arange(n) * sample_dt
        if t_end - times[-1] > 1e-9 * sample_dt:
            times = np.append(times, t_end)
        out = self._sample(eng, times, record=True, progress=progress, desc="trajectory")
        cols = eng.sample_columns
        rec = eng.records()
        return Trajectory(
            t=start.t + times,
            q=out[:, 0].copy(),
            v=out[:, 1].copy(),
            phi=np.mod(start.phi + self._omega * times, 2.0 * math.pi),
            M=out[:, 2].copy(),
            switches=_switches(rec),
            final=eng.state(),
            w=out[:, cols.index("w")].copy() if "w" in cols else None,
            events=rec.get("events"),
            slides=rec.get("slides"),
        )

    def poincare_section(
        self,
        n_periods: int,
        transient_periods: int = 0,
        q0: float = DEFAULT_Q0,
        v0: float = DEFAULT_V0,
        operator_state: HysteronState | None = None,
        *,
        engine_options: dict | None = None,
        progress: bool = False,
    ) -> PoincareSection:
        """Stroboscopic section at φ = 0 mod 2π: the states at ``t = (transient_periods + i)·T``,
        ``i = 0..n_periods-1``, of the orbit started at φ = 0 (so without transient the first
        point is the initial state)."""
        n_periods = positive_integer(n_periods, "n_periods")
        transient_periods = nonnegative_integer(transient_periods, "transient_periods")
        if n_periods + transient_periods > MAX_PERIODS:
            raise ValueError(
                f"n_periods + transient_periods must be <= {MAX_PERIODS:.0e}, got "
                f"{n_periods + transient_periods}"
            )
        self._check_periods((n_periods + transient_periods) * self.period, "n_periods")
        eng = self.engine(self.initial_state(q0, v0, operator_state), **(engine_options or {}))
        times = (transient_periods + np.arange(n_periods)) * self.period
        if transient_periods > 0:
            self._sample(eng, np.array([transient_periods * self.period]), False, progress, "")
        out = self._sample(eng, times, record=False, progress=progress, desc="Poincaré section")
        cols = eng.sample_columns
        return PoincareSection(
            q=out[:, 0].copy(),
            v=out[:, 1].copy(),
            M=out[:, 2].copy(),
            final=eng.state(),
            w=out[:, cols.index("w")].copy() if "w" in cols else None,
            n_switches=eng.n_events,
        )

    def stroboscopic_map(
        self, state: OscillatorState, *, engine_options: dict | None = None
    ) -> OscillatorState:
        """The state one forcing period T after ``state`` (any phase)."""
        eng = self.engine(state, **(engine_options or {}))
        self._sample(eng, np.array([self.period]), False, False, "")
        return eng.state()

    def jacobian(
        self,
        duration: float,
        state: OscillatorState | None = None,
        include_phase: bool = True,
        *,
        engine_options: dict | None = None,
    ) -> tuple[np.ndarray, tuple[str, ...]]:
        """Derivative of the flow map over ``duration`` (tangent flow, no re-orthonormalisation).

        Returns the matrix (rows: the tangent space at the end, columns: at the start) and the
        row labels, e.g. ``("q", "v", "phi")`` for relays or ``("q", "v", "phi", "w")`` for the
        play. A start on a play wall moving outward is a wall hit at t = 0 (one-sided
        derivative: the ``w`` column is then ``δw := δq``).
        """
        duration = real_parameter(duration, "duration")
        if not duration > 0.0:
            raise ValueError(f"duration must be > 0, got {duration}")
        self._check_periods(duration, "duration")
        eng = self.engine(state, **(engine_options or {}))
        require_tangent_flow(eng, "the flow map has no Jacobian here")
        eng.start_tangent(bool(include_phase))
        eng.advance(np.array([duration]))
        y = eng.deviations()
        self.check_finite(eng, np.array([eng.state().q, eng.state().v]))
        if not np.all(np.isfinite(y)):
            raise DivergenceError(
                f"the tangent flow is not finite after t = {duration} for {self!r}", duration
            )
        return y, eng.tangent_space

    # -- helpers -------------------------------------------------------------------------------
    def _check_periods(self, duration: float, name: str) -> None:
        if duration / self.period > MAX_PERIODS:
            raise ValueError(
                f"{name} spans {duration / self.period:.3g} forcing periods (T = "
                f"{self.period:.3g}); at most {MAX_PERIODS:.0e} are allowed"
            )

    def _sample(
        self, eng: Engine, times: np.ndarray, record: bool, progress: bool, desc: str
    ) -> np.ndarray:
        """Advance ``eng`` through ``times`` in chunks, checking every chunk for divergence."""
        out = np.empty((times.size, len(eng.sample_columns)))
        n_chunks = max(1, min(200, times.size // 2000))
        bounds = np.linspace(0, times.size, n_chunks + 1).astype(int)
        bar = None
        if progress and desc:
            bar = progress_bar(total=times.size, desc=desc, unit="pt", leave=False)
        for i0, i1 in zip(bounds[:-1], bounds[1:], strict=True):
            if i1 <= i0:
                continue
            eng.advance(times[i0:i1], out[i0:i1], record)
            self.check_finite(eng, out[i0:i1, :2], times[i0:i1])
            if bar is not None:
                bar.update(i1 - i0)
        if bar is not None:
            bar.close()
        return out


def _switches(records: dict) -> np.ndarray:
    """The relay switches of a run: the relay engines' own record, or the events at which a
    composite's relays switched (kind 2 of the continuous engines' events)."""
    if "switches" in records:
        return records["switches"]
    events = records.get("events")
    out = np.empty(0, dtype=SWITCH_DTYPE)
    if events is not None and events.dtype.names and "jump" in events.dtype.names:
        hits = events[events["jump"] != 0.0]
        out = np.empty(hits.size, dtype=SWITCH_DTYPE)
        for name in ("time", "q", "v", "jump"):
            out[name] = hits[name]
    return out
