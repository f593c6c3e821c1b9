"""One integration, three measurements: the Lyapunov spectrum, the Poincaré section and the
exact time average ``M_T`` of a forced oscillator's output (the disorder ensembles' task,
:mod:`analysis.experiments.ensemble`; the lattice study), and the same without the tangent
flow (:func:`section_and_magnetization`, the independent check).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from analysis.dynamics.lyapunov import TangentStepper, lyapunov_spectra, lyapunov_spectrum
from analysis.experiments.parameters import DEFAULT_Q0, V0
from hysteresis._validation import positive_integer

__all__ = [
    "QR_PERIODS",
    "one_pass_measurements",
    "one_pass_measurements_many",
    "section_and_magnetization",
]

#: forcing periods per QR step of an ensemble task (see :func:`one_pass_measurements`)
QR_PERIODS = 8


def section_and_magnetization(
    system: Any,
    t_end: float,
    transient: float,
    q0: float = DEFAULT_Q0,
    v0: float = V0,
    chunk_periods: int = 50,
) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Poincaré section (q, v) at φ = 0 and the exact time average of M over the same window.

    The window runs over whole forcing periods ``[P0·T, P1·T]`` with ``P0 = ceil(transient/T)``
    and ``P1 = floor(t_end/T)``. ``M`` is piecewise constant, so its average is exact from the
    switches: over a chunk of length Δ starting with output ``M0``,
    ``∫M dt = M0·Δ + Σ_j ΔM_j·(Δ − t_j)``. The trajectory is integrated in chunks of
    ``chunk_periods`` periods so memory stays bounded (N = 20 000 spins switch ~10⁴ times per
    period). Returns ``(q, v, M_T, window_length)``.
    """
    period = float(system.period)
    p0, p1 = _window_periods(system, t_end, transient)
    start = system.poincare_section(1, p0, q0, v0)
    q, v, opstate = start.final.q, start.final.v, start.final.operator_state
    qs: list[np.ndarray] = []
    vs: list[np.ndarray] = []
    integral = 0.0
    remaining = p1 - p0
    while remaining > 0:
        n = min(chunk_periods, remaining)
        length = n * period
        traj = system.trajectory(length, q, v, opstate, sample_dt=period)
        # samples at 0, T, ..., nT: the section points are all but the last (next chunk's first)
        qs.append(np.asarray(traj.q[:n]))
        vs.append(np.asarray(traj.v[:n]))
        sw = traj.switches
        integral += float(traj.M[0]) * length
        if sw.size:
            integral += float(np.sum(sw["jump"] * (length - sw["time"])))
        f = traj.final
        q, v, opstate = f.q, f.v, f.operator_state
        remaining -= n
    window = (p1 - p0) * period
    return np.concatenate(qs), np.concatenate(vs), integral / window, window


def _window_periods(system: Any, t_end: float, transient: float) -> tuple[int, int]:
    """Whole forcing periods ``[P0, P1]`` inside ``[transient, t_end]``."""
    period = float(system.period)
    p0 = int(math.ceil(transient / period - 1e-12))
    p1 = int(math.floor(t_end / period + 1e-12))
    if p1 - p0 < 1:
        raise ValueError(
            f"t_end={t_end} - transient={transient} must cover at least one forcing period"
        )
    return p0, p1


def one_pass_measurements(
    system: Any,
    t_end: float,
    transient: float,
    q0: float = DEFAULT_Q0,
    v0: float = V0,
    operator_state: Any = None,
    magnetization: bool = True,
    progress: bool = False,
    qr_periods: int = QR_PERIODS,
) -> tuple[Any, np.ndarray, np.ndarray, float, float]:
    """Lyapunov spectrum, Poincaré section and ``M_T`` from one integration with tangent flow.

    The window is the whole forcing periods ``[P0·T, P1·T]`` in ``[transient, t_end]`` (as
    :func:`section_and_magnetization`). The Benettin loop of
    :func:`~analysis.dynamics.lyapunov.lyapunov_spectrum` re-orthonormalises every ``qr_periods``
    periods; its stepper samples ``(q, v)`` at every period boundary in the same engine calls
    (``TangentStepper(sample_dt=T)``), and the observer collects them and reads the exact
    ``∫M dt`` from the engine (``Engine.output_integral``) at both ends of the window, so
    nothing is integrated twice. Returns ``(lyapunov_result, q, v, M_T, window_length)``;
    ``M_T`` is nan with ``magnetization=False`` (for engines without an exact output integral,
    e.g. continuous operators). ``operator_state`` is the initial memory (default: rising from
    negative saturation to ``q0``); ``progress`` shows the Lyapunov loop's progress bar.

    Why several periods per QR step: at small N the Python work of one QR step costs more than
    the integration of one period; the deviation vectors separate like
    ``exp((λ1 − λ2)·Δt)``, ``e^(0.2·8·2π) ≈ 2·10⁴`` for the paper's ensembles, far from losing
    the second direction in double precision (the exponents are the same in exact arithmetic
    for any QR interval; a test compares with one QR step per period).
    """

    qr_periods = positive_integer(qr_periods, "qr_periods")
    stepper, observe, finish, window_end, window_start = _one_pass(system, t_end, transient,
                                                                   magnetization)  # fmt: skip
    ly = lyapunov_spectrum(
        system,
        window_end,
        window_start,
        q0,
        v0,
        operator_state,
        progress=progress,
        renormalize_dt=qr_periods * float(system.period),
        stepper=stepper,
        observer=observe,
    )
    return finish(ly)


def one_pass_measurements_many(
    systems: Sequence[Any],
    t_end: float,
    transient: float,
    q0: float = DEFAULT_Q0,
    v0: float = V0,
    qr_periods: int = QR_PERIODS,
) -> list[tuple[Any, np.ndarray, np.ndarray, float, float]]:
    """:func:`one_pass_measurements` of several systems with the same forcing period, each
    result bit for bit the system's alone: systems on nested relay tables that differ only in
    their tables (disorder realizations at one N and C) run side by side in the vector units
    (:func:`~analysis.dynamics.lyapunov.lyapunov_spectra`)."""
    qr_periods = positive_integer(qr_periods, "qr_periods")
    if not systems:
        return []
    period = float(systems[0].period)
    if any(float(s.period) != period for s in systems):
        raise ValueError("systems must share their forcing period (the same window)")
    parts = [_one_pass(s, t_end, transient, True) for s in systems]
    lys = lyapunov_spectra(
        list(systems), parts[0][3], parts[0][4], q0, v0, renormalize_dt=qr_periods * period,
        steppers=[p[0] for p in parts], observers=[p[1] for p in parts],
    )  # fmt: skip
    return [p[2](ly) for p, ly in zip(parts, lys, strict=True)]


def _one_pass(system: Any, t_end: float, transient: float, magnetization: bool) -> tuple:
    """``(stepper, observer, finish, window end, window start)`` of
    :func:`one_pass_measurements`: ``finish(lyapunov_result)`` gives its return value."""
    period = float(system.period)
    p0, p1 = _window_periods(system, t_end, transient)
    n = p1 - p0
    points: list[np.ndarray] = []
    integral = [np.nan, np.nan]

    def observe(stepper: Any) -> None:
        if not points:  # after the transient: the first section point, start of the window
            q, v, _ = stepper.sample
            points.append(np.array([[0.0, q, v, 0.0]]))
            if magnetization:
                integral[0] = stepper.engine.output_integral()
        else:
            points.append(stepper.samples)
            if magnetization:
                integral[1] = stepper.engine.output_integral()

    # it reads only the samples and the integral: it may be called once per stretch of QR
    # intervals (lyapunov_spectrum's compiled loop), the samples then hold the whole stretch
    observe.batches = True  # type: ignore[attr-defined]

    def finish(ly: Any) -> tuple[Any, np.ndarray, np.ndarray, float, float]:
        rows = np.concatenate(points)
        if rows.shape[0] != n + 1:  # one sample per period boundary; else a bug here
            raise RuntimeError(f"expected {n + 1} section points, got {rows.shape[0]}")
        window = n * period
        # samples at P0..P1: the section points are P0..P1-1, as section_and_magnetization
        m_t = float((integral[1] - integral[0]) / window)
        return ly, rows[:n, 1].copy(), rows[:n, 2].copy(), m_t, window

    return TangentStepper(system, sample_dt=period), observe, finish, p1 * period, p0 * period
