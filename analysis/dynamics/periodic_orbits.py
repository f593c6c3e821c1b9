"""Periodic orbits of forced oscillators with hysteresis and their Floquet multipliers.

A periodic orbit of period ``k`` (forcing periods) is a fixed point of the k-th iterate of the
stroboscopic map ``P`` (section ``φ = φ0``). :func:`find_periodic_orbit`:

1. integrates a transient of whole forcing periods from the start;
2. detects a candidate period ``k <= max_period`` from ``2·max_period`` stroboscopic points
   (:func:`~analysis.dynamics.periods.smallest_period` at relative tolerances 1e-8, 1e-6,
   1e-4, 1e-3 of the section's extent, the tightest first; then, for a transient still
   decaying, the k whose points come back closest if within 5 % of the extent:
   :func:`~analysis.dynamics.periods.return_distances`);
3. refines it by Newton on ``F(x) = P^k(x) − x`` in the state coordinates
   ``x = (q, v, *memory)`` (:class:`~analysis.dynamics.orbit_coordinates.StateCoordinates`)::

       J = D P^k(x)       (the engine's tangent flow over k·T: saltations, memory rows)
       solve (J − I) Δ = −F(x);   x := x + λ Δ   (λ = 1, halved while |F| does not decrease)

   until ``|F(x)|_∞ <= tolerance · max(1, |x|_∞)`` (the explicit convergence criterion);
4. integrates the converged orbit once more, period by period: the ``k`` orbit points, the
   monodromy matrix ``J``, its eigenvalues (the Floquet multipliers), the events.

Memory coordinates
------------------
For relay-type operators the memory is the discrete relay configuration: ``x = (q, v)`` and the
configuration is carried from one iterate to the next (it is fixed along the iteration as long
as the switching sequence does not change; at convergence the configuration at the end of the
orbit must equal the one at its start). For plays and Prandtl–Ishlinskii operators the wagon
positions are coordinates, for continuous Preisach models the remembered extrema of the
staircase at the section (its length fixed: the orbit's own structure; Newton runs on the
closed-loop map of :mod:`analysis.dynamics.staircase_orbits`, since every such orbit sits on a
wipe-out border where the map of the full staircase is not smooth; its own extrema, replaced
inside the orbit, are reset directions counted there). A wagon that hits its
wall along the orbit, or an extremum wiped out and pushed again, has its perturbation reset
(``δw := δq``, the paper's ``V_out``), so its direction is mapped to zero: the monodromy matrix
has the multiplier ``μ = 0`` (exponent ``−∞``). This does **not** make Newton singular — the
Newton matrix is ``J − I``, whose eigenvalue there is ``−1``. A reduction to ``(q, v)`` would
be exact only when the section point itself lies on a wall (the memory is then slaved,
``w = q ∓ p/2``); in general ``P^k`` depends on the reset memory through the force ``C·M``
before the reset, so such memory stays a coordinate. The structural zero multipliers are
counted from the engine's ``rank_bound()`` (directions reset or removed along the orbit) and
set to exactly 0 instead of a round-off remainder.

Frozen memory
-------------
A memory coordinate that the orbit never moves — a wagon strictly inside its play for the whole
orbit, an older extremum of a Preisach staircase that the orbit does not wipe out — has the
row of the identity in ``J = D P^k`` (its value after k periods is its value before, whatever
the other coordinates: the engine carries such a row unchanged, so the test is exact). It is a
**parameter of a family of periodic orbits**, not an unknown: with ``f`` the frozen and ``r``
the remaining coordinates ``J = [[J_rr, J_rf], [0, I]]`` (``J − I`` is singular: a continuum
of orbits), so Newton runs on ``r`` only, ``(J_rr − I) Δ_r = −F_r``, with the frozen values held
where the start put them. The multipliers reported are the eigenvalues of ``J_rr`` plus exactly
``1`` for every frozen direction, labelled ``"frozen: <label>"`` in
:attr:`PeriodicOrbit.multiplier_labels` and listed in :attr:`PeriodicOrbit.frozen`; their
eigenvectors ``(−(J_rr − I)^{-1} J_rf e_f, e_f)`` are the tangents of the family. ``stable``
(and ``max_abs_multiplier``) are judged on the other multipliers: neutral memory does not make
an orbit unstable — a perturbation of frozen memory moves the motion onto a neighbouring orbit
of the family (the same neutral direction a Lyapunov spectrum shows as a zero exponent).

Results
-------
:class:`PeriodicOrbit`: ``period`` k, the orbit points (states and coordinates), multipliers
(complex, sorted by decreasing modulus) with the tangent space that labels the basis,
exponents ``log|μ|/(k·T)`` (``−inf`` for ``μ = 0``), ``stable`` (every non-frozen
``|μ| < 1`` beyond round-off) and ``stability`` (stable / unstable / neutral: a multiplier on
the unit circle within the round-off of ``D P^k``), the frozen memory (labels), the
event sequence along one orbit (relay switches or wall hits / reversals, from the engine's
records), the Newton residuals, and :meth:`PeriodicOrbit.to_dict` for JSON.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from analysis.dynamics.floquet import (
    floquet_exponents,
    floquet_multipliers,
    frozen_coordinates,
    max_abs_multiplier,
    multiplier_roundoff,
    stability,
)
from analysis.dynamics.newton import Linearization, NewtonError, newton
from analysis.dynamics.orbit_coordinates import StateCoordinates
from analysis.dynamics.periods import return_distances, section_extent, smallest_period
from analysis.dynamics.staircase_orbits import closed_loop_shot, settle_staircase
from hysteresis._validation import (
    finite_scalar,
    nonnegative_integer,
    positive_integer,
)
from oscillators import MAX_PERIODS, DivergenceError, OscillatorState
from oscillators.engines.play import OUTSIDE_STEP

__all__ = [
    "OrbitNotFoundError",
    "PeriodicOrbit",
    "event_sequence",
    "find_periodic_orbit",
    "floquet_multipliers",
    "frozen_coordinates",
    "max_abs_multiplier",
    "orbit_shooter",
    "refine_periodic_orbit",
]

#: relative tolerances (of the section's extent) at which candidate periods are detected
DETECTION_TOLERANCES = (1e-8, 1e-6, 1e-4, 1e-3)
#: largest relative mismatch ``|x_{i+k} − x_i| / extent`` of a fallback candidate period
FALLBACK_MISMATCH = 0.05
#: halvings of a Newton step whose residual does not decrease
MAX_HALVINGS = 10
#: largest allowed max_period (the detection integrates 2·max_period periods per candidate)
MAX_ORBIT_PERIOD = 10_000


class OrbitNotFoundError(RuntimeError):
    """No periodic orbit: no period up to ``max_period`` fits the stroboscopic points, or Newton
    did not reach the tolerance. ``residuals`` holds the last Newton residual sequence."""

    def __init__(self, message: str, residuals: tuple[float, ...] = ()) -> None:
        super().__init__(message)
        self.residuals = residuals


@dataclass(frozen=True)
class PeriodicOrbit:
    """A periodic orbit of the stroboscopic map and its Floquet multipliers.

    Attributes
    ----------
    period:
        k, in forcing periods.
    forcing_period:
        T = 2π/Ω.
    states:
        The k orbit points at the section (``states[0]`` the refined start).
    points:
        Their coordinates, shape (k, d), columns named by ``tangent_space``.
    tangent_space:
        ``("q", "v", *memory)``: the basis of the monodromy matrix and its eigenvectors.
    monodromy:
        ``D P^k`` at ``states[0]``, shape (d, d).
    multipliers:
        Eigenvalues of ``monodromy`` (complex), by decreasing modulus; a structurally reset
        direction is exactly 0, a frozen memory direction exactly 1 (module docstring).
    exponents:
        ``log|μ| / (k·T)`` in the order of ``multipliers`` (``-inf`` for ``μ = 0``).
    stable:
        Every ``|μ| < 1`` but the frozen directions' (exactly 1), by more than the round-off
        of its computation (``stability == "stable"``).
    events:
        The engine's records along one orbit (relay switches: time, q, v, jump; play engines:
        time, q, v, kind, ...), times measured from ``states[0]``.
    sequence:
        :func:`event_sequence` of ``events``: what changes when the orbit's switching sequence
        changes (a grazing or border collision).
    residuals:
        ``|P^k(x_n) − x_n|_∞`` of the Newton iterates (last: the accepted point).
    tolerance:
        The convergence criterion ``|F|_∞ <= tolerance · max(1, |x|_∞)``.
    eigenvectors:
        Columns: eigenvectors of ``monodromy`` in the order of ``multipliers``.
    frozen:
        Labels of the frozen memory coordinates (parameters of the family of orbits; module
        docstring), in the order of ``tangent_space``.
    multiplier_labels:
        One per multiplier: ``"frozen: <label>"`` for a frozen direction, ``"reset"`` for a
        structural zero, ``""`` otherwise.
    stability:
        ``"stable"``, ``"unstable"`` (a non-frozen ``|μ| > 1`` beyond round-off) or
        ``"neutral"`` (none beyond, one within round-off of the unit circle:
        :func:`~analysis.dynamics.floquet.multiplier_roundoff`, e.g. an undamped resonance
        where every state is periodic).
    """

    period: int
    forcing_period: float
    states: tuple[OscillatorState, ...]
    points: np.ndarray
    tangent_space: tuple[str, ...]
    monodromy: np.ndarray
    multipliers: np.ndarray
    exponents: np.ndarray
    stable: bool
    events: np.ndarray
    sequence: tuple
    residuals: tuple[float, ...]
    tolerance: float
    eigenvectors: np.ndarray = field(repr=False, default_factory=lambda: np.zeros((0, 0)))
    frozen: tuple[str, ...] = ()
    multiplier_labels: tuple[str, ...] = ()
    stability: str = ""

    @property
    def residual(self) -> float:
        """The accepted point's residual ``|P^k(x) − x|_∞``."""
        return self.residuals[-1]

    @property
    def max_abs_multiplier(self) -> float:
        """``max |μ|`` over the non-frozen multipliers (1 if every direction is frozen)."""
        return max_abs_multiplier(self.multipliers, self.multiplier_labels)

    @property
    def start(self) -> OscillatorState:
        """The refined orbit point ``states[0]``."""
        return self.states[0]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (``"-inf"`` for a reset direction's exponent)."""
        return {
            "period": self.period,
            "multipliers": [[float(m.real), float(m.imag)] for m in self.multipliers],
            "exponents": [float(e) if math.isfinite(e) else "-inf" for e in self.exponents],
            "tangent_space": list(self.tangent_space),
            "residual": float(self.residual),
            "residuals": [float(r) for r in self.residuals],
            "stable": bool(self.stable),
            "stability": self.stability,
            "max_abs_multiplier": self.max_abs_multiplier,
            "points": self.points.tolist(),
            "n_events": int(self.events.size),
            "frozen": list(self.frozen),
            "multiplier_labels": list(self.multiplier_labels),
        }


def event_sequence(events: np.ndarray) -> tuple:
    """The order of events along an orbit, as a hashable tuple.

    Relay switches: ``(sign of the jump, threshold)`` (the switch happens at ``q`` = the relay's
    threshold, rounded to 1e-9); play engines: ``(kind, side)`` with kind +1 a wall hit, −1 a
    reversal and side the sign of ``v`` just before (hits) or of the acceleration direction
    (reversals: the sign of ``q − w``); the continuous engines: ``(kind,)``, and for the
    relays of a composite (kind 2) ``(2, sign of the jump, threshold)``.
    """
    names = events.dtype.names or ()
    if "kind" in names and "jump" in names:  # the continuous engines' events
        return tuple(
            (2, int(np.sign(j)), round(float(q), 9)) if k == 2 else (int(k),)
            for k, j, q in zip(events["kind"], events["jump"], events["q"], strict=True)
        )
    if "jump" in names:
        return tuple(
            (int(np.sign(j)), round(float(q), 9))
            for j, q in zip(events["jump"], events["q"], strict=True)
        )
    if "w" in names:
        return tuple(
            (int(k), int(np.sign(q - w)))
            for k, q, w in zip(events["kind"], events["q"], events["w"], strict=True)
        )
    if "kind" in names:
        return tuple((int(k),) for k in events["kind"])
    return ()


@dataclass
class _Shot:
    """One integration of k periods with the tangent flow from a start state."""

    states: list[OscillatorState]
    jacobian: np.ndarray
    labels: tuple[str, ...]
    rank: int
    events: np.ndarray


def shoot(
    system: Any,
    state: OscillatorState,
    k: int,
    *,
    record: bool = False,
    engine_options: dict | None = None,
) -> _Shot:
    """Integrate ``k`` forcing periods from ``state`` with the tangent flow on (no phase):
    the states after each period, ``D P^k``, its labels, the structural rank bound, and (with
    ``record``) the events."""
    eng = system.engine(state, **(engine_options or {}))
    eng.start_tangent(False)
    labels0 = tuple(eng.tangent_space)
    period = system.period
    out = np.empty((1, len(eng.sample_columns)))
    states = []
    for i in range(1, k + 1):
        eng.advance(np.array([i * period]), out, record)
        eng.check_finite(out[:, :2])
        states.append(eng.state())
    jac = eng.deviations()
    if tuple(eng.tangent_space) != labels0:
        raise OrbitNotFoundError(
            f"the tangent space changed along the orbit ({labels0} -> {eng.tangent_space})"
        )
    if not np.all(np.isfinite(jac)):
        raise DivergenceError(f"the tangent flow is not finite after {k} periods of {system!r}")
    rec = eng.records() if record else {}
    events = rec.get("switches", rec.get("events"))
    if events is None:
        events = np.empty(0, dtype=[("time", "f8")])
    return _Shot(states, jac, labels0, int(eng.rank_bound()), events)


def orbit_shooter(system: Any, coords: StateCoordinates, k: int, engine_options: dict | None):
    """``state, record -> _Shot`` in ``coords``: :func:`shoot`, or for a continuous Preisach
    staircase the closed-loop map of :mod:`analysis.dynamics.staircase_orbits` (its own extrema
    are the reset directions)."""
    if coords.kind != "staircase":  # (a "memory" chart maps the engine's branch memory)

        def run_shot(state: OscillatorState, record: bool = False) -> _Shot:
            record = record or coords.kind == "memory"
            shot = shoot(system, state, k, record=record, engine_options=engine_options)
            shot.jacobian = coords.chart_jacobian(state, shot, engine_options, system)
            return shot

        return run_shot

    def run(state: OscillatorState, record: bool = False) -> _Shot:
        got = closed_loop_shot(system, state, k, coords.prefix, engine_options)
        return _Shot(got.states, got.jacobian, coords.labels, got.rank, got.events)

    return run


def _newton(
    system: Any,
    coords: StateCoordinates,
    start: OscillatorState,
    k: int,
    tolerance: float,
    max_iterations: int,
    engine_options: dict | None,
) -> tuple[OscillatorState, list[float]]:
    """Newton on ``P^k(x) − x`` from ``start`` (the damped loop of
    :func:`~analysis.dynamics.newton.newton`); returns the converged state and residuals.

    Each iterate is integrated from the relay configuration the previous one produced (the
    start's for the first); converged also needs that configuration to close on itself.
    Frozen memory (identity rows of ``D P^k``) is a parameter of the family: held, not solved
    for."""
    run = orbit_shooter(system, coords, k, engine_options)

    def evaluate(x: np.ndarray, previous: Linearization | None) -> Linearization:
        template = start if previous is None else previous.data[0].states[-1]
        try:
            shot = run(coords.state(x, template))
            r = coords.vector(shot.states[-1]) - x
        except ValueError as exc:  # the memory's structure is not that of the start
            if previous is not None:
                raise
            raise OrbitNotFoundError(f"P^{k} of the start: {exc}") from None
        return Linearization(
            residual=r,
            jacobian=lambda: shot.jacobian - np.eye(coords.dimension),
            free=np.nonzero(~frozen_coordinates(shot.jacobian))[0],
            data=(shot, template),
        )

    def closed(x: np.ndarray, ev: Linearization) -> bool:
        shot, template = ev.data
        return coords.same_memory(coords.state(x, template), shot.states[-1])

    try:
        got = newton(
            evaluate,
            coords.vector(start),
            tolerance=tolerance,
            max_iterations=max_iterations,
            scale=coords.scale,
            max_halvings=MAX_HALVINGS,
            converged=closed,
            trial_failures=(ValueError, DivergenceError),
        )
    except NewtonError as exc:
        residuals = exc.residuals
        if exc.reason == "singular":
            why = (
                f"P^{k} − I is singular at the iterate (a multiplier is 1 in the coordinates "
                "the orbit moves: a fold)"
            )
        elif exc.reason == "stalled":
            why = (
                f"Newton on P^{k}(x) − x stalled at residual {residuals[-1]:.3g} (no decrease "
                f"along the step after {MAX_HALVINGS} halvings)"
            )
        else:
            why = (
                f"Newton on P^{k}(x) − x did not reach |F| <= {tolerance:g}·max(1, |x|) in "
                f"{max_iterations} iterations (residuals "
                f"{', '.join(f'{e:.2e}' for e in residuals)})"
            )
        raise OrbitNotFoundError(why, residuals) from None
    return coords.state(got.z, got.evaluation.data[1]), got.residuals


def refine_periodic_orbit(
    system: Any,
    state: OscillatorState,
    period: int,
    *,
    tolerance: float = 1e-10,
    max_iterations: int = 30,
    engine_options: dict | None = None,
) -> PeriodicOrbit:
    """Newton-refine a guess ``state`` of a period-``period`` orbit (no transient, no period
    detection) and compute its multipliers; see the module docstring. For a continuous Preisach
    model Newton starts from the state settled ``period`` periods on
    (:func:`~analysis.dynamics.staircase_orbits.settle_staircase`), so the orbit's ``start`` is
    that much later than ``state``."""
    k = positive_integer(period, "period")
    if k > MAX_ORBIT_PERIOD:
        raise ValueError(f"period must be <= {MAX_ORBIT_PERIOD}, got {k}")
    tolerance = finite_scalar(tolerance, "tolerance")
    if not tolerance > 0.0:
        raise ValueError(f"tolerance must be > 0, got {tolerance}")
    max_iterations = nonnegative_integer(max_iterations, "max_iterations")
    if not isinstance(state, OscillatorState):
        raise TypeError(f"state must be an OscillatorState, got {type(state).__name__}")
    coords, state = _coordinates(system, state, k, engine_options)
    start, residuals = _newton(system, coords, state, k, tolerance, max_iterations, engine_options)
    return _orbit(system, coords, start, k, residuals, tolerance, engine_options)


def _point(coords: StateCoordinates, state: OscillatorState) -> np.ndarray:
    """``coords.vector(state)``; for a staircase whose length differs at this orbit point (the
    own extrema of a period-k orbit vary along it) ``(q, v)`` followed by NaN."""
    try:
        return coords.vector(state)
    except ValueError:
        if coords.kind != "staircase":
            raise
        x = np.full(coords.dimension, np.nan)
        x[:2] = state.q, state.v
        return x


def _coordinates(
    system: Any, state: OscillatorState, k: int, engine_options: dict | None
) -> tuple[StateCoordinates, OscillatorState]:
    """The coordinates of ``state`` and the Newton start: ``state`` itself, or for a continuous
    Preisach staircase the state settled k periods on
    (:func:`~analysis.dynamics.staircase_orbits.settle_staircase`) and its frozen prefix."""
    coords = StateCoordinates(system, state, engine_options)
    if coords.kind == "staircase":
        state, prefix = settle_staircase(system, state, k, engine_options)
        coords = StateCoordinates(system, state, engine_options)
        coords.prefix = prefix
    return coords, state


def _orbit(
    system: Any,
    coords: StateCoordinates,
    start: OscillatorState,
    k: int,
    residuals: list[float],
    tolerance: float,
    engine_options: dict | None,
) -> PeriodicOrbit:
    shot = orbit_shooter(system, coords, k, engine_options)(start, True)
    states = (start, *shot.states[:-1])
    points = np.array([_point(coords, s) for s in states])
    frozen = frozen_coordinates(shot.jacobian)
    n_reset = coords.dimension - shot.rank
    mu, vec, tags = floquet_multipliers(shot.jacobian, frozen, n_reset, coords.labels)
    lost = n_reset - tags.count("reset")
    if lost:
        # the structure the engine promised (a map that factors through fewer coordinates)
        # does not hold for this Jacobian: the orbit touches a border where P^k is not smooth
        # and the engine took one side's derivative (measured: a from_density Preisach orbit,
        # whose compiled and generic Jacobians are the two one-sided derivatives)
        warnings.warn(
            f"the period-{k} orbit at q = {start.q:.6g}, v = {start.v:.6g} has "
            f"{lost} structural reset direction(s) with |μ| above "
            "round-off: its stroboscopic map is not smooth there and the multipliers are one "
            "side's linearization",
            RuntimeWarning,
            stacklevel=3,
        )
    exps = floquet_exponents(mu, k * system.period)
    # D P^k is a product of one propagator per integrator step (at most the stepping engines'
    # OUTSIDE_STEP/max(1, Ω) long) and per event, and of the d coordinates' saltations
    span = k * system.period * max(1.0, 2.0 * math.pi / system.period)
    n_products = coords.dimension + shot.events.size + math.ceil(span / OUTSIDE_STEP)
    verdict = stability(mu, tags, multiplier_roundoff(shot.jacobian, mu, frozen, n_products))
    return PeriodicOrbit(
        period=k,
        forcing_period=system.period,
        states=tuple(states),
        points=points,
        tangent_space=coords.labels,
        monodromy=shot.jacobian,
        multipliers=mu,
        exponents=exps,
        stable=verdict == "stable",
        events=shot.events,
        sequence=event_sequence(shot.events),
        residuals=tuple(residuals),
        tolerance=tolerance,
        eigenvectors=vec,
        frozen=tuple(lab for lab, f in zip(coords.labels, frozen, strict=True) if f),
        multiplier_labels=tags,
        stability=verdict,
    )


def find_periodic_orbit(
    system: Any,
    state: OscillatorState | None = None,
    *,
    q0: float | None = None,
    v0: float | None = None,
    transient: int = 100,
    max_period: int = 64,
    tolerance: float = 1e-10,
    max_iterations: int = 30,
    engine_options: dict | None = None,
) -> PeriodicOrbit:
    """The periodic orbit that the motion from ``state`` settles on (see the module docstring).

    Parameters
    ----------
    system:
        A :class:`~oscillators.system.ForcedOscillator`.
    state:
        Start state (default: ``system.initial_state(q0, v0)``, the paper's initial condition
        when both are ``None``); its phase is the section's phase.
    q0, v0:
        Start position and velocity when ``state`` is ``None`` (the operator's memory from
        ``initial_state(q0)``).
    transient:
        Forcing periods integrated before the period is detected (>= 0).
    max_period:
        Largest period k searched, in forcing periods (1 .. 10 000).
    tolerance:
        Newton stops when ``|P^k(x) − x|_∞ <= tolerance · max(1, |x|_∞)`` (> 0).
    max_iterations:
        Newton iterations per candidate period (>= 0).
    engine_options:
        Passed to the engine (e.g. ``{"method": "generic"}``).

    Notes
    -----
    A candidate period detected at a loose tolerance (or the closest-return fallback) may lead
    Newton to an *unstable* orbit that the motion shadows for a while (chaotic motion near a
    periodic saddle): the result is then a genuine periodic orbit, but not an attractor —
    :attr:`PeriodicOrbit.stable` says which.

    Raises
    ------
    OrbitNotFoundError
        No period up to ``max_period`` fits the stroboscopic points (chaos, quasi-periodic
        motion, a longer period or a transient longer than ``transient``), or Newton did not
        converge for any candidate.
    """
    transient = nonnegative_integer(transient, "transient")
    max_period = positive_integer(max_period, "max_period")
    if max_period > MAX_ORBIT_PERIOD:
        raise ValueError(f"max_period must be <= {MAX_ORBIT_PERIOD}, got {max_period}")
    tolerance = finite_scalar(tolerance, "tolerance")
    if not tolerance > 0.0:
        raise ValueError(f"tolerance must be > 0, got {tolerance}")
    max_iterations = nonnegative_integer(max_iterations, "max_iterations")
    if transient + 2 * max_period > MAX_PERIODS:
        raise ValueError(
            f"transient + 2·max_period must be <= {MAX_PERIODS:.0e}, got "
            f"{transient + 2 * max_period}"
        )
    if state is None:
        kw = {}
        if q0 is not None:
            kw["q0"] = q0
        if v0 is not None:
            kw["v0"] = v0
        state = system.initial_state(**kw)
    elif q0 is not None or v0 is not None:
        raise ValueError("give either state or q0/v0, not both")
    if not isinstance(state, OscillatorState):
        raise TypeError(f"state must be an OscillatorState, got {type(state).__name__}")
    period = system.period
    eng = system.engine(state, **(engine_options or {}))
    if transient:
        eng.advance(np.array([transient * period]))
        eng.check_finite(np.array([[eng.state().q, eng.state().v]]))
    start = eng.state()
    start = OscillatorState(
        q=start.q, v=start.v, phi=state.phi, operator_state=start.operator_state, t=start.t
    )
    n = 2 * max_period
    times = (transient + np.arange(1, n + 1)) * period
    out = np.empty((n, len(eng.sample_columns)))
    eng.advance(times, out)
    eng.check_finite(out[:, :2])
    pts = np.vstack([[start.q, start.v], out[:, :2]])
    tried: list[int] = []
    failures: list[str] = []
    candidates = [
        smallest_period(pts, rel, max_period, relative_to="extent") for rel in DETECTION_TOLERANCES
    ]
    # a transient still decaying: the period whose points come back closest (below
    # FALLBACK_MISMATCH of the extent) is a candidate too; Newton decides
    mismatch = return_distances(pts, max_period) / section_extent(pts)
    best = int(np.argmin(mismatch))
    if mismatch[best] <= FALLBACK_MISMATCH:
        candidates.append(best + 1)
    for k in candidates:
        if k == 0 or k in tried:
            continue
        tried.append(k)
        try:
            orbit = refine_periodic_orbit(
                system,
                start,
                k,
                tolerance=tolerance,
                max_iterations=max_iterations,
                engine_options=engine_options,
            )
        except OrbitNotFoundError as exc:
            failures.append(f"k = {k}: {exc}")
            continue
        # the smallest divisor d of k with x_{i+d} = x_i on the refined orbit (to 1e3 times
        # Newton's tolerance relative to its size): a multiple cover of a shorter orbit
        d = smallest_period(orbit.points, 1e3 * tolerance, relative_to="magnitude", divisors_of=k)
        if 0 < d < k:
            orbit = refine_periodic_orbit(
                system,
                orbit.start,
                d,
                tolerance=tolerance,
                max_iterations=max_iterations,
                engine_options=engine_options,
            )
        return orbit
    if not tried:
        raise OrbitNotFoundError(
            f"no period <= max_period = {max_period} fits {n + 1} stroboscopic points after a "
            f"transient of {transient} forcing periods (relative tolerance up to "
            f"{DETECTION_TOLERANCES[-1]:g}): chaos, quasi-periodic motion, a longer period or a "
            "longer transient"
        )
    raise OrbitNotFoundError(
        "Newton did not converge for any candidate period: " + "; ".join(failures)
    )
