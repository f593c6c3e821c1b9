"""Where one start ends: the section run, its period, its transient, and the attractor's measures.

The pieces that :mod:`analysis.dynamics.basins` (many starts) and
:mod:`analysis.experiments.realizations` (one start per disorder realization) share:

* :func:`section_run` — the Poincaré (stroboscopic) section of one start at ``φ = 0``, from the
  start itself (point 0) through ``transient + periods`` forcing periods (extended by
  ``periods`` at a time up to ``max_periods`` while no period shows), without the tangent
  flow. The measured window (the last ``periods`` points) gives the section period ``k``
  (:func:`~analysis.dynamics.periods.smallest_period`: the smallest ``k <= max_period`` with
  ``|x_{i+k} − x_i| <= tolerance`` in every coordinate over the whole window, so the cycle is
  seen at least twice when ``max_period <= periods/2``); the transient length is the first
  section index ``j`` from which ``|x_{i+k} − x_i| <= tolerance`` holds for every later ``i``
  (the start has come within the tolerance of its final cycle and stays there:
  :func:`~analysis.dynamics.periods.transient_length`). A run that
  leaves the divergence bound is ``divergent``; one without a period is ``aperiodic``.
* :func:`periodic_attractor` — the one place where a cycle found on the section is turned into
  a refined periodic orbit with its Floquet multipliers
  (:func:`~analysis.dynamics.periodic_orbits.refine_periodic_orbit`).
* :func:`lyapunov_estimate` — ``λ_max`` with its finite-time error and ``D_KY`` on an aperiodic
  attractor.
* :func:`same_cycle` — whether two cycles are the same orbit (cyclic shifts included).

Section coordinates are the engine's sample columns: ``(q, v, M)`` and, for play-type memory,
``w`` (the play's state), so two points agree only when the memory agrees too.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from analysis.dynamics.dimensions import kaplan_yorke_dimension
from analysis.dynamics.floquet import floquet_exponents, floquet_multipliers, is_stable
from analysis.dynamics.lyapunov import lyapunov_spectrum
from analysis.dynamics.periodic_orbits import OrbitNotFoundError, refine_periodic_orbit
from analysis.dynamics.periods import smallest_period, transient_length
from hysteresis._validation import finite_scalar, nonnegative_integer, positive_integer
from oscillators import MAX_PERIODS, DivergenceError, OscillatorState

__all__ = [
    "APERIODIC",
    "DIVERGENT",
    "PERIODIC",
    "SectionRun",
    "cycle_period",
    "lyapunov_estimate",
    "periodic_attractor",
    "same_cycle",
    "section_run",
    "start_state",
]

#: status codes of a :class:`SectionRun`
PERIODIC, APERIODIC, DIVERGENT = 1, 0, -1


@dataclass(frozen=True)
class SectionRun:
    """The section of one start.

    Attributes
    ----------
    status:
        :data:`PERIODIC`, :data:`APERIODIC` or :data:`DIVERGENT`.
    period:
        Section period k in forcing periods (0 unless periodic).
    transient:
        Forcing periods before the section stays within the tolerance of its final cycle
        (−1 unless periodic).
    cycle:
        The last k section points, shape (k, d) (empty unless periodic).
    tail:
        The last ``tail`` section points, shape (m, d) (empty if divergent).
    columns:
        Names of the d coordinates (the engine's sample columns).
    final:
        The state at the end of the run (``None`` unless asked for, or divergent).
    """

    status: int
    period: int
    transient: int
    cycle: np.ndarray
    tail: np.ndarray
    columns: tuple[str, ...]
    final: OscillatorState | None = None


def start_state(system: Any, q0: float, v0: float, w0: float | None = None) -> OscillatorState:
    """The state ``(q0, v0)`` at φ = 0 with the operator's default memory (rising from negative
    saturation to q0) or, with ``w0``, the play-type memory ``operator.state(position=w0,
    input=q0)``."""
    q0 = finite_scalar(q0, "q0")
    v0 = finite_scalar(v0, "v0")
    if w0 is None or (isinstance(w0, float) and math.isnan(w0)):
        return system.initial_state(q0, v0)
    w0 = finite_scalar(w0, "w0")
    if getattr(system.operator, "compiled_play", lambda: None)() is None:
        raise ValueError(
            f"w0 needs a play-type operator (operator.state(position, input)), not "
            f"{system.operator!r}"
        )
    return system.initial_state(q0, v0, system.operator.state(position=w0, input=q0))


#: the section's period test (:func:`~analysis.dynamics.periods.smallest_period`, absolute
#: tolerance) under the name the basins used first
cycle_period = smallest_period


def section_run(
    system: Any,
    state: OscillatorState,
    transient: int,
    periods: int,
    *,
    max_periods: int | None = None,
    tolerance: float = 1e-6,
    max_period: int = 32,
    tail: int = 16,
    keep_state: bool = False,
) -> SectionRun:
    """Integrate one start (at φ = 0) and classify its section (module docstring).

    The first check comes after ``transient + periods`` forcing periods, on the last ``periods``
    section points; while no period is found the run goes on by ``periods`` at a time, checking
    the last ``periods`` points each time, up to ``max_periods`` in all (default: no extension).
    ``tolerance`` is absolute in every section coordinate; ``max_period <= periods // 2``;
    ``tail`` section points are kept.
    """
    transient = nonnegative_integer(transient, "transient")
    periods = positive_integer(periods, "periods", minimum=2)
    max_period = positive_integer(max_period, "max_period")
    tail = positive_integer(tail, "tail")
    tolerance = finite_scalar(tolerance, "tolerance")
    if not tolerance > 0:
        raise ValueError(f"tolerance must be > 0, got {tolerance}")
    if max_period > periods // 2:
        raise ValueError(
            f"max_period must be <= periods // 2 = {periods // 2} (a cycle is seen twice), "
            f"got {max_period}"
        )
    first = transient + periods
    total = first if max_periods is None else nonnegative_integer(max_periods, "max_periods")
    if total < first:
        raise ValueError(f"max_periods must be >= transient + periods = {first}, got {total}")
    if total > MAX_PERIODS:
        raise ValueError(f"max_periods must be <= {MAX_PERIODS:.0e}, got {total}")
    eng = system.engine(state)
    columns = tuple(eng.sample_columns)
    out = np.empty((total + 1, len(columns)))
    done, target, k = -1, first, 0
    while True:
        times = np.arange(done + 1, target + 1, dtype=float) * system.period
        try:
            eng.advance(times, out[done + 1 : target + 1])
            system.check_finite(eng, out[done + 1 : target + 1, :2], times)
        except DivergenceError:
            empty = np.empty((0, len(columns)))
            return SectionRun(DIVERGENT, 0, -1, empty, empty, columns, None)
        done = target
        k = smallest_period(out[done + 1 - periods : done + 1], tolerance, max_period)
        if k or done >= total:
            break
        target = min(total, done + periods)
    pts = out[: done + 1]
    final = eng.state() if keep_state else None
    tail_pts = pts[-min(tail, done + 1) :].copy()
    if k == 0:
        return SectionRun(APERIODIC, 0, -1, np.empty((0, len(columns))), tail_pts, columns, final)
    return SectionRun(
        PERIODIC, k, transient_length(pts, k, tolerance), pts[-k:].copy(), tail_pts, columns, final
    )


def same_cycle(a: np.ndarray, b: np.ndarray, tolerance: float) -> bool:
    """Whether cycles ``a`` and ``b`` (k × d section points in orbit order) are the same orbit:
    some cyclic shift of ``a`` lies within ``tolerance`` of ``b`` in every coordinate."""
    return bool(match_cycles(a[None], b, tolerance)[0])


def match_cycles(cycles: np.ndarray, orbit: np.ndarray, tolerance: float) -> np.ndarray:
    """For cycles of shape (n, k, d): whether each is ``orbit`` (k × d) up to a cyclic shift,
    within ``tolerance`` in every coordinate (vectorised :func:`same_cycle`)."""
    if cycles.shape[1:] != orbit.shape:
        return np.zeros(cycles.shape[0], dtype=bool)
    k = orbit.shape[0]
    hit = np.zeros(cycles.shape[0], dtype=bool)
    for s in range(k):
        rolled = np.roll(orbit, s, axis=0)
        hit |= np.all(np.abs(cycles - rolled[None]) <= tolerance, axis=(1, 2))
    return hit


def periodic_attractor(system: Any, state: OscillatorState, period: int) -> dict:
    """The periodic orbit next to ``state`` (the end of a run whose section repeats with period
    ``period`` within the tolerance), refined once: the basins' one call of
    :func:`analysis.dynamics.periodic_orbits.refine_periodic_orbit` (Newton on
    ``P^k(x) − x`` with the exact Jacobian, to ``|F| <= 1e-10·max(1, |x|)``).

    Returns ``points`` (k × d: the section columns of the refined orbit, from one more run of
    k periods), ``columns``, ``multipliers`` (complex, by decreasing modulus; a reset memory
    direction exactly 0), ``tangent_space``, ``exponents`` (``log|μ|/(k·T)``), ``stable``,
    ``residual`` and ``refined`` (True). Memory the orbit never moves (a wagon inside its play,
    an old remembered extremum) is frozen: its multiplier is exactly 1 and ``stable`` judges
    the other directions (see :mod:`analysis.dynamics.periodic_orbits`). If Newton does not
    converge (:class:`~analysis.dynamics.periodic_orbits.OrbitNotFoundError`), the orbit is the
    run's own cycle, the
    multipliers the eigenvalues of the Jacobian of ``P^k`` at ``state``, ``refined`` is False
    and ``refinement_error`` says why.
    """
    period = positive_integer(period, "period")
    extra: dict[str, Any]
    try:
        orbit = refine_periodic_orbit(system, state, period)
    except OrbitNotFoundError as exc:
        jac, labels = system.jacobian(period * system.period, state, include_phase=False)
        mult = floquet_multipliers(jac)[0]
        start = state
        extra = {
            "multipliers": mult,
            "tangent_space": tuple(labels),
            "exponents": floquet_exponents(mult, period * system.period),
            "stable": is_stable(mult),
            "refined": False,
            "refinement_error": str(exc).splitlines()[0],
        }
    else:
        start = orbit.start
        extra = {
            "multipliers": orbit.multipliers,
            "tangent_space": tuple(orbit.tangent_space),
            "exponents": orbit.exponents,
            "stable": orbit.stable,
            "residual": float(orbit.residual),
            "refined": True,
        }
    eng = system.engine(start)
    columns = tuple(eng.sample_columns)
    times = np.arange(period + 1, dtype=float) * system.period
    out = np.empty((period + 1, len(columns)))
    eng.advance(times, out)
    system.check_finite(eng, out[:, :2], times)
    if not extra["refined"]:
        keep = [i for i, c in enumerate(columns) if c != "M"]
        extra["residual"] = float(np.max(np.abs(out[-1, keep] - out[0, keep])))
    return {"points": out[:-1].copy(), "columns": columns, **extra}


def lyapunov_estimate(
    system: Any, state: OscillatorState, periods: int, segments: int = 10
) -> dict:
    """``λ_max`` with its finite-time error and ``D_KY`` on the attractor through ``state``.

    The run of ``periods`` forcing periods is cut into ``segments`` consecutive segments
    (each continues the previous one's state; :func:`~analysis.dynamics.lyapunov.lyapunov_spectrum`
    with one QR step per period); the estimate is the mean of the segment spectra and the error
    of ``λ_max`` the standard error of the segment means, ``std/√segments`` (batch means: the
    segment estimates are nearly independent when a segment is much longer than the
    correlation time). Each segment restarts its deviation vectors, which aligns them within a
    few periods (a bias of order ``1/segment length``, below the error for the default
    200-period segments). Returns ``max_exponent``, ``max_exponent_error``, ``exponents``,
    ``tangent_space``, ``kaplan_yorke``.
    """
    periods = positive_integer(periods, "periods")
    segments = positive_integer(segments, "segments", minimum=2)
    if periods < segments:
        raise ValueError(f"periods must be >= segments = {segments}, got {periods}")
    seg_t = (periods // segments) * system.period
    spectra = []
    labels: tuple[str, ...] = ()
    for _ in range(segments):
        ly = lyapunov_spectrum(system, seg_t, 0.0, state=state)
        spectra.append(np.asarray(ly.exponents, dtype=float))
        labels = ly.tangent_space
        state = ly.final
    spec = np.vstack(spectra)
    with np.errstate(invalid="ignore"):
        mean = np.where(np.all(np.isfinite(spec), axis=0), spec.mean(axis=0), -np.inf)
    lam = spec[:, 0]
    return {
        "max_exponent": float(lam.mean()),
        "max_exponent_error": float(lam.std(ddof=1) / math.sqrt(segments)),
        "exponents": mean,
        "tangent_space": labels,
        "kaplan_yorke": float(kaplan_yorke_dimension(mean)),
        "final": state,
    }
