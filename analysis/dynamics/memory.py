"""Memory directions of a Lyapunov spectrum: finite-time errors, neutral exponents, and the
exponents of the motion without long-lived memory.

A continuous Preisach staircase keeps every remembered extremum in the tangent space
(:mod:`oscillators.engines.continuous`): a reversal pushes an extremum with ``δm := δq``, which
then stays **frozen** until the extremum is wiped out. While it lives, such a direction carries
its perturbation unchanged: a Lyapunov exponent 0 (a *neutral* direction), whatever the norm. The
outermost extrema are wiped out only when the input breaks its record, so they live for times of
the order of the run, and the spectrum in ``(q, v, extrema)`` holds exponents ``≈ 0`` that say
nothing about the extent of the attractor.

Two tools separate them:

* :func:`exponent_block_errors` — the finite-time error of each exponent from block averages of
  the running estimate (batch means), so that "neutral" means ``|λ| <= 2·error``
  (:func:`neutral_count`), and the error of ``D_KY`` by the jackknife over the same batches
  (:func:`kaplan_yorke_block_error`);
* :func:`memory_frozen_exponents` — the Benettin loop of
  :func:`~analysis.dynamics.lyapunov.lyapunov_spectrum` over two deviation vectors
  (:class:`MemoryProjectionStepper`: growth measured in the ``(q, v)`` rows) in
  which every memory direction that survived a whole projection interval (carried unchanged by
  the engine, not pushed again or reset) is set to zero at the interval's end: the two
  exponents of the motion in ``(q, v)`` together with its short-lived memory (the extrema of the
  current oscillation, a play's ``w`` between wall hits), without the long-lived, neutral
  extrema.

Survival is read from a probe column, never from the memory's values: on a periodic orbit the
own extrema are pushed again every period at the same value, often bit-identical (at a border
orbit of a continuous Preisach model the base trajectory also leaves near-duplicate pairs
1e-15 .. 1e-13 apart), and a "same label, same value" test zeroed such fresh rows as if they
were frozen (the Gaussian period-3 orbit at C = 2: -0.0142 or -0.0175 instead of the Floquet
exponent -0.0338, depending on round-off of the start and of the Everett function).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from analysis.dynamics.dimensions import kaplan_yorke_dimension
from analysis.dynamics.lyapunov import LyapunovResult, TangentStepper, lyapunov_spectrum
from hysteresis._validation import positive_integer, time_window
from oscillators import DEFAULT_Q0, DEFAULT_V0, MAX_PERIODS, OscillatorState

__all__ = [
    "exponent_block_errors",
    "kaplan_yorke_block_error",
    "neutral_count",
    "memory_frozen_exponents",
    "MemoryFrozenResult",
    "MemoryProjectionStepper",
]


def _block_rates(result: LyapunovResult, blocks: int) -> tuple[np.ndarray, np.ndarray]:
    """Growth rates of the running log sums over ``blocks`` equal blocks of the window, and the
    blocks' durations (rows: blocks; see :func:`exponent_block_errors`)."""
    blocks = positive_integer(blocks, "blocks", minimum=2)
    t = np.asarray(result.history_t, dtype=float)
    hist = np.asarray(result.history, dtype=float)
    if t.size < blocks:
        raise ValueError(
            f"blocks={blocks} needs at least {blocks} running estimates, the result holds "
            f"{t.size} (use more history_points)"
        )
    elapsed = t - result.transient
    with np.errstate(invalid="ignore"):
        sums = hist * elapsed[:, None]
    edges = np.unique(np.round(np.linspace(-1, t.size - 1, blocks + 1)).astype(int))
    s = np.vstack([np.zeros((1, hist.shape[1])), sums[edges[1:]]])
    times = np.concatenate([[0.0], elapsed[edges[1:]]])
    durations = np.diff(times)
    with np.errstate(invalid="ignore"):
        rates = np.diff(s, axis=0) / durations[:, None]
    return rates, durations


def exponent_block_errors(result: LyapunovResult, blocks: int = 10) -> np.ndarray:
    """Finite-time error of each exponent from ``blocks`` batch means of its running estimate.

    Plain reading: with ``S_j(t) = λ_j(t)·(t − transient)`` the running log sum (from
    ``result.history``, which must hold at least ``blocks`` rows; run
    :func:`~analysis.dynamics.lyapunov.lyapunov_spectrum` with ``history_points`` >= the number
    of QR steps for exact block edges), the block rates are
    ``r_jb = (S_j(t_b) − S_j(t_{b−1})) / (t_b − t_{b−1})`` over ``blocks`` equal blocks of the
    window, and the error of ``λ_j`` (the mean of the ``r_jb``) is
    ``std_b(r_jb) / sqrt(blocks)``. Assumes blocks longer than the correlation time of the local
    growth rates (a forcing period or a few here). A ``-inf`` exponent has error nan.
    """
    rates, _ = _block_rates(result, blocks)
    err = np.std(rates, axis=0, ddof=1) / math.sqrt(rates.shape[0])
    err[~np.isfinite(np.asarray(result.exponents, dtype=float))] = np.nan
    return err


def kaplan_yorke_block_error(result: LyapunovResult, blocks: int = 10) -> float:
    """Finite-time error of ``D_KY`` of ``result``'s exponents: the jackknife over the
    ``blocks`` batches of :func:`exponent_block_errors`.

    Plain reading: ``D_b`` = ``kaplan_yorke_dimension`` of the exponents averaged over every
    block but ``b`` (``-inf`` exponents stay ``-inf``); the error is
    ``sqrt((B − 1)/B · Σ_b (D_b − mean_b D_b)²)``. The jackknife needs no derivative of the
    piecewise formula and keeps the correlation of the exponents (their block rates move
    together). 0 where ``D_KY`` is an integer in every batch (a regular attractor).
    """
    rates, durations = _block_rates(result, blocks)
    lam = np.asarray(result.exponents, dtype=float)
    finite = np.isfinite(lam)
    total = np.sum(durations)
    with np.errstate(invalid="ignore"):
        sums = np.nansum(rates * durations[:, None], axis=0)
    d = np.empty(rates.shape[0])
    for b in range(rates.shape[0]):
        loo = np.full(lam.size, -np.inf)
        loo[finite] = (sums[finite] - rates[b, finite] * durations[b]) / (total - durations[b])
        d[b] = kaplan_yorke_dimension(loo)
    n = d.size
    return float(math.sqrt((n - 1) / n * np.sum((d - d.mean()) ** 2)))


def neutral_count(exponents: np.ndarray, errors: np.ndarray, sigmas: float = 2.0) -> int:
    """Number of finite exponents with ``|λ_j| <= sigmas·error_j`` (zero within their error)."""
    lam = np.asarray(exponents, dtype=float)
    err = np.asarray(errors, dtype=float)
    ok = np.isfinite(lam) & np.isfinite(err)
    return int(np.count_nonzero(np.abs(lam[ok]) <= sigmas * err[ok]))


@dataclass(frozen=True)
class MemoryFrozenResult:
    """Outcome of :func:`memory_frozen_exponents`: the two exponents of the motion without its
    long-lived memory, and ``D_KY`` of them (the attractor's dimension where neutral memory
    directions make the full-space one count them; :mod:`analysis.dynamics.attractor_dimension`).

    Attributes
    ----------
    exponents:
        The two exponents, descending.
    errors:
        Their finite-time errors (:func:`exponent_block_errors` over ``blocks`` batches of the
        projection intervals; nan if the run has fewer intervals than ``blocks``).
    kaplan_yorke_error:
        Finite-time error of :attr:`kaplan_yorke` (:func:`kaplan_yorke_block_error`; nan as
        ``errors``).
    projection_periods:
        Forcing periods per projection interval.
    zeroed_mean:
        Memory directions set to zero per projection, on average (the directions that survived
        a whole interval: frozen, neutral while they live).
    t_end, transient:
        The average runs over whole intervals in ``[transient, t_end]``.
    """

    exponents: np.ndarray
    errors: np.ndarray
    kaplan_yorke_error: float
    projection_periods: int
    zeroed_mean: float
    t_end: float
    transient: float

    @property
    def kaplan_yorke(self) -> float:
        """``D_KY`` of the two exponents
        (:func:`~analysis.dynamics.dimensions.kaplan_yorke_dimension`)."""
        return kaplan_yorke_dimension(self.exponents)

    @property
    def max_exponent(self) -> float:
        """λ_max = λ_1."""
        return float(self.exponents[0])

    def __repr__(self) -> str:
        lam = ", ".join(f"{x:.5g}" for x in self.exponents)
        err = ", ".join(f"{x:.2g}" for x in self.errors)
        return (
            f"MemoryFrozenResult(exponents=[{lam}] +- [{err}], kaplan_yorke="
            f"{self.kaplan_yorke:.4f} +- {self.kaplan_yorke_error:.2g}, "
            f"projection_periods={self.projection_periods}, zeroed_mean={self.zeroed_mean:.3g}, "
            f"window=[{self.transient:g}, {self.t_end:g}])"
        )


class MemoryProjectionStepper(TangentStepper):
    """The stepper of :func:`memory_frozen_exponents` for the Benettin loop of
    :func:`~analysis.dynamics.lyapunov.lyapunov_spectrum`: two deviation vectors whose growth is
    measured in the ``(q, v)`` rows, the memory rows riding along, the long-lived ones dropped.

    To the loop it shows the tangent space ``("q", "v")``: :meth:`deviations` are the ``(q, v)``
    rows ``Y_qv`` of the two vectors (2 × 2), whose QR ``Y_qv = Q R`` the loop takes
    (``Σ += log|R_jj|``); :meth:`set_deviations` receives ``Q`` and carries every row along,
    ``Y := Y R⁻¹`` (``R = Qᵀ Y_qv``). :meth:`step` puts ``[Y, p, 0]`` into the engine (the
    probe ``p`` = 1 on every memory row), integrates, and zeroes the rows whose probe survived
    (:func:`memory_frozen_exponents`). ``zeroed`` counts them. If the engine tracks only two
    vectors (no memory row at the start), it is restarted from its state after the first
    interval in which memory appeared; :attr:`elapsed` runs on across the restart.
    """

    def __init__(self, system: Any) -> None:
        super().__init__(system)
        self._y = np.eye(2)
        self._origin = 0.0  # time of the engine's last (re)start, measured from the run's start
        self._probe = False
        self.zeroed = 0

    def reinit(self, state: OscillatorState | None = None, transient: float = 0.0) -> None:
        super().reinit(state, transient)
        self._y = np.eye(len(self.engine.tangent_space), 2)
        self._origin = 0.0
        self.zeroed = 0

    @property
    def tangent_space(self) -> tuple[str, ...]:
        """The rows the loop measures."""
        return ("q", "v")

    @property
    def elapsed(self) -> float:
        """Time since :meth:`reinit` (transient included), across restarts."""
        return self._origin + self._t

    def step_to(self, t: float) -> None:
        """Advance to the elapsed time ``t``: ``(t − origin) − t_engine`` on the current
        engine (the same rounding before and after a restart)."""
        self.step(t - self._origin - self._t)

    def step(self, dt: float) -> None:
        """One projection interval: ``[Y, p, 0]`` in, ``Y`` out with the survived rows 0."""
        eng = self.engine
        k = eng.deviations().shape[1]
        self._probe = k >= 3
        start = np.zeros((len(eng.tangent_space), k))
        start[: self._y.shape[0], :2] = self._y
        if self._probe:
            start[2:, 2] = 1.0  # the survival probe: exactly 1 on every memory row
        eng.set_deviations(start)
        super().step(dt)
        dev = eng.deviations()
        y = dev[:, :2].copy()
        if self._probe:
            survived = dev[2:, 2] == 1.0
            y[2:][survived] = 0.0
            self.zeroed += int(np.count_nonzero(survived))
        self._y = y

    def deviations(self) -> np.ndarray:
        """The ``(q, v)`` rows of the two vectors."""
        y = self._y[:2]
        if not np.all(np.isfinite(y)):
            raise RuntimeError("the two deviation vectors became degenerate or non-finite")
        return y

    def rank_bound(self) -> int:
        """Two: the QR of the ``(q, v)`` rows has no structural zero (a zero is degenerate)."""
        return 2

    def set_deviations(self, y: np.ndarray) -> None:
        """``Y := Y R⁻¹`` with ``R = Qᵀ Y_qv`` (``y`` = Q): the ``(q, v)`` block becomes
        orthonormal, the young memory rows follow it."""
        r = y.T @ self._y[:2]
        if np.any(np.diag(r) == 0.0):
            raise RuntimeError("the two deviation vectors became degenerate or non-finite")
        self._y = np.linalg.solve(r.T, self._y.T).T
        if not self._probe and self._y.shape[0] > 2:
            # the start had no memory row, so the engine tracks two vectors and no probe:
            # restart it here (every row present now was born in this interval, nothing was
            # dropped)
            self._origin += self._t
            super().reinit(self.state(), 0.0)
            if len(self.engine.tangent_space) != self._y.shape[0]:
                raise RuntimeError(
                    f"restarted tangent rows {self.engine.tangent_space} do not match the "
                    f"{self._y.shape[0]} rows before the restart"
                )


def memory_frozen_exponents(
    system: Any,
    t_end: float,
    transient: float = 0.0,
    q0: float = DEFAULT_Q0,
    v0: float = DEFAULT_V0,
    operator_state: Any = None,
    projection_periods: int = 1,
    blocks: int = 10,
) -> MemoryFrozenResult:
    """The two exponents of the motion without its long-lived memory directions.

    Plain reading (two deviation vectors, a third tracked column as the survival probe, the
    other tracked columns kept at zero)::

        reinit at the initial state, transient without tangent flow; Y := [e_q, e_v]
        every P forcing periods:
            deviations := [Y, p, 0] with the probe p = 1 on every memory row, 0 on q, v
            step;  Y = deviations[:, :2]
            rows whose probe is still exactly 1 (carried unchanged through the whole
            interval: an extremum never wiped out, a wagon that never hit a wall) := 0
            Q R = Y[q, v rows];  Σ += log|diag R|;  Y := Y R⁻¹
        λ = Σ / (n·P·T)      (n whole intervals in [transient, t_end], a remainder left out)

    The loop is :func:`~analysis.dynamics.lyapunov.lyapunov_spectrum`'s (its QR, its time
    targets, ``whole_intervals=True``); the interval's ``[Y, p, 0]``, the zeroed rows and
    ``Y R⁻¹`` are :class:`MemoryProjectionStepper`'s.

    A row pushed again or reset inside the interval holds ``δq`` of the probe column there
    (its response to the memory, generically not 1 to the last bit). If the start has no
    memory row (the engine then tracks only two vectors), the engine is restarted from its
    state after the first interval in which memory appeared (nothing is dropped there: all of
    it was born in that interval).

    Memory born inside an interval (the extrema of the current oscillation, a play's ``w`` set
    at a wall) keeps its deviation; only memory older than ``P`` periods is dropped, so the
    result is the spectrum of the motion in ``(q, v)`` with memory younger than 1–2·P periods.
    A plateau of the exponents over ``P`` separates the short-lived memory (part of the
    chaotic motion) from the long-lived, neutral extrema. The growth is measured in the
    ``(q, v)`` rows (the young memory is a bounded function of the recent ``δq``, so it does not
    change the exponential rates, while counting it in the norm would bias every interval by
    the memory it is about to drop). For a continuous operator (memory rows in the engine's
    tangent space).

    At a border orbit of a continuous Preisach model (module docstring of
    :mod:`analysis.dynamics.staircase_orbits`) the result equals the closed-loop map's Floquet
    exponents plus the boundary term ``B/t`` of the QR average (tested); the linearisation
    along the base trajectory itself holds only for perturbations below the distance to the
    border, which there is round-off: use the projection, not the full spectrum.

    ``blocks``: batches for the finite-time errors of the result (``errors``,
    ``kaplan_yorke_error``; nan if the window holds fewer projection intervals).
    """
    t_end, transient = time_window(t_end, transient)
    projection_periods = positive_integer(projection_periods, "projection_periods")
    blocks = positive_integer(blocks, "blocks", minimum=2)
    period = float(system.period)
    dt = projection_periods * period
    span = t_end - transient
    n_steps = int(math.floor(span / dt + 1e-9))
    if n_steps < 1:
        raise ValueError(
            f"t_end - transient = {span:g} is shorter than one projection interval ({dt:g})"
        )
    if t_end / period > MAX_PERIODS:
        raise ValueError(f"t_end spans more than {MAX_PERIODS:.0e} forcing periods")
    stepper = MemoryProjectionStepper(system)
    res = lyapunov_spectrum(
        system,
        t_end,
        transient,
        q0,
        v0,
        operator_state,
        renormalize_dt=dt,
        history_points=n_steps,
        stepper=stepper,
        whole_intervals=True,
    )
    if n_steps >= blocks:
        errors = exponent_block_errors(res, blocks)
        ky_error = kaplan_yorke_block_error(res, blocks)
    else:
        errors, ky_error = np.full(2, np.nan), math.nan
    return MemoryFrozenResult(
        exponents=res.exponents,
        errors=errors,
        kaplan_yorke_error=ky_error,
        projection_periods=projection_periods,
        zeroed_mean=stepper.zeroed / n_steps,
        t_end=t_end,
        transient=transient,
    )
