"""The computations behind fig:bif_0, fig:bif and the ensemble figures, as independent tasks.

Every long computation is an independent task run through
:func:`analysis.experiments.execution.run_tasks` (process pool or Dask, results store, resume):

* a bifurcation sweep with continuation is sequential in C, so one sweep is one task
  (:func:`bifurcation_task`); the sweeps of one figure run in parallel;
* an ensemble is one task per (N, C, realization)
  (:func:`analysis.experiments.ensemble.ensemble_task`); the limit values one task per C
  (:func:`limit_dimension_task`); the iid reference one task per (N, realization)
  (:func:`analysis.experiments.iid.iid_task`).

fig:dim, fig:sap, fig:mag and fig:mag_his share one ensemble computation (:func:`ensemble_data`):
it is computed by the first of them that runs and cached for the others (keyed by output
directory, run size and seed); with a results store a second ``hyst paper`` run reads it back.
"""

from __future__ import annotations

import copy
import math
import multiprocessing
import os
from concurrent.futures import Future, ProcessPoolExecutor
from typing import Any

import numpy as np

from analysis.dynamics.bifurcation import bifurcation_diagram, section_period
from analysis.dynamics.dimensions import box_counting_dimension
from analysis.dynamics.lyapunov import lyapunov_spectrum
from analysis.experiments.ensemble import (
    EXPERIMENT,
    aggregate_ensemble,
    ensemble_task,
    ensemble_tasks,
)
from analysis.experiments.execution import end_with_client
from analysis.experiments.iid import iid_variance_scaling
from analysis.experiments.models import MODELS, build_operator, canonical_model_name
from analysis.experiments.parameters import (
    DAMPING_RATIO,
    DEFAULT_Q0,
    ENSEMBLE_COUPLINGS,
    FREQUENCY,
    SPIN_COUPLING,
    SPREAD,
    V0,
    WIDTH,
)
from analysis.experiments.store import StoreError
from analysis.paper.context import (
    PaperContext,
)
from oscillators import ForcedOscillator

__all__ = [
    "make_operator",
    "bifurcation_task",
    "limit_dimension_task",
    "ensemble_data",
    "start_ensemble_data",
    "ensemble_run_text",
    "series_of",
]


def make_operator(kind: str, spins: int, seed: int):
    """The operator of a task ``kind``: ``"dimer_pair"`` (fig:bif_0's dimer b = (1, -1)) or a
    model name of :mod:`analysis.experiments.models` (``"dimers"``, ``"erf-play"``) at the paper's
    parameters."""

    params = dict(width=WIDTH, spread=SPREAD, spin_coupling=SPIN_COUPLING)
    if kind == "dimer_pair":  # fig:bif_0: one dimer, b = (1, -1), J = 2
        return build_operator("dimers", fields=[[1.0, -1.0]], **params)
    if kind == "erf_play" or kind in MODELS:
        kind = canonical_model_name(kind)
    if kind == "dimers":
        return build_operator("dimers", spins=spins, seed=seed, **params)
    if kind == "erf-play":
        return build_operator("erf-play", **params)
    raise ValueError(f"kind must be 'dimer_pair', 'dimers' or 'erf-play', got {kind!r}")


def bifurcation_task(
    kind: str,
    c_start: float,
    c_stop: float,
    n_values: int,
    n_periods: int,
    transient: int,
    lyapunov_t: float,
    spins: int = 2,
    seed: int = 0,
) -> dict:
    """One continuation sweep ``C = linspace(c_start, c_stop, n_values)`` (in that order).

    ``kind``: ``"dimer_pair"`` (b = (1, −1), J = 2), ``"dimers"`` (``SpinDimerEnsemble.random
    (spins, 2, 1, 2, seed)``) or ``"erf-play"`` (the limit). Returns the Poincaré points q, v
    (n_values × n_periods), the spectra, λ_max and the orbit period per C (0: none found).
    """

    operator = make_operator(kind, spins, seed)
    values = np.linspace(c_start, c_stop, int(n_values))
    bd = bifurcation_diagram(
        lambda c: ForcedOscillator(operator, c, DAMPING_RATIO, FREQUENCY),
        values,
        n_periods=n_periods,
        transient_periods=transient,
        continuation=True,
        lyapunov=True,
        lyapunov_t_end=lyapunov_t,
        q0=DEFAULT_Q0,
        v0=V0,
        progress=False,
    )
    periods = [section_period(bd.q[i], bd.v[i], 1e-6) for i in range(values.size)]
    return {
        "couplings": values,
        "q": bd.q,
        "v": bd.v,
        "max_exponent": bd.max_exponent,
        "exponents": bd.exponents,
        "period": np.array(periods, dtype=int),
    }


def limit_dimension_task(
    coupling: float, t_end: float, transient: float, section_periods: int, section_transient: int
) -> dict:
    """D_KY (Lyapunov spectrum over [transient, t_end]) and D_BC (box counting of the Poincaré
    section (q, v), ``section_periods`` points after ``section_transient`` periods) of the
    erf-play limit at coupling C, from the paper's initial condition (w0 = q0 − p/2)."""

    system = ForcedOscillator(make_operator("erf-play", 0, 0), coupling, DAMPING_RATIO, FREQUENCY)
    ly = lyapunov_spectrum(system, t_end, transient, DEFAULT_Q0, V0, progress=False)
    sec = system.poincare_section(int(section_periods), int(section_transient), DEFAULT_Q0, V0)
    try:
        bc = box_counting_dimension(np.column_stack([sec.q, sec.v]))
        d_bc, d_bc_err = float(bc.dimension), float(bc.stderr)
    except ValueError:  # too few points for a scaling region (smoke sizes)
        d_bc, d_bc_err = float("nan"), float("nan")
    return {
        "exponents": np.asarray(ly.exponents, dtype=float),
        "kaplan_yorke": float(ly.kaplan_yorke),
        "box_counting": d_bc,
        "box_counting_stderr": d_bc_err,
        "section_points": int(sec.q.size),
    }


_KEY = "ensemble_data"


def ensemble_data(ctx: PaperContext) -> dict[str, Any]:
    """Ensembles at C = 2.9, 4.0, the limit values and the iid reference (computed once; if
    :func:`start_ensemble_data` started it in the background, its result)."""
    value = ctx.cache.get(_KEY)
    if isinstance(value, Future):
        ctx.cache[_KEY] = value.result()  # raises what the computation raised
    elif value is None:
        ctx.cache[_KEY] = _ensemble_data(ctx)
    return ctx.cache[_KEY]


def start_ensemble_data(ctx: PaperContext) -> None:
    """Start :func:`ensemble_data`'s computation in a process of its own (with its own worker
    pools), so that the figures before it and the evidence run meanwhile: their serial
    stretches and the tails of their short sweeps leave cores idle that the ensemble's
    thousands of tasks fill. Every task, and so every result, is the same as in a sequential
    run; both processes write the run's store (SQLite locking).

    A process, not a thread: it is forked now, while this process runs no other thread, so
    no lock (numba's compiler lock, above all) can be inherited held by a thread the child
    does not have; a thread forking worker pools beside another that loads kernels could
    deadlock them. It ends with this process (as pool workers do)."""
    if _KEY in ctx.cache or "fork" not in multiprocessing.get_all_start_methods():
        return  # (without fork the data is computed when needed, in sequence)
    child = copy.copy(ctx)
    child.cache = {}  # the context goes to the process as it is now, without the future
    pool = ProcessPoolExecutor(
        max_workers=1,
        mp_context=multiprocessing.get_context("fork"),
        initializer=end_with_client,
        initargs=(os.getpid(),),
    )
    ctx.cache[_KEY] = pool.submit(_ensemble_data_in_child, child)
    pool.shutdown(wait=False)  # the process exits after its one task


def _ensemble_data_in_child(ctx: PaperContext) -> dict[str, Any]:
    try:
        return _ensemble_data(ctx)
    except StoreError:
        raise
    except Exception as exc:  # e.g. a TaskError, whose constructor does not survive pickling
        raise RuntimeError(f"{type(exc).__name__}: {exc}") from None


def _ensemble_data(ctx: PaperContext) -> dict[str, Any]:
    s = ctx.size
    tasks = ensemble_tasks(
        s.ensemble_spins,
        ENSEMBLE_COUPLINGS,
        s.ensemble_realizations,
        ctx.seed,
        s.ensemble_t_end,
        s.ensemble_transient,
    )
    # run_ensemble would do the same; calling run_tasks here keeps the ctx's executor settings
    results = ctx.run(EXPERIMENT, tasks, ensemble_task)
    points = {
        (p.spins, p.coupling): p for p in aggregate_ensemble(zip(tasks, results, strict=True))
    }

    period = 2 * math.pi / FREQUENCY
    window_periods = int(
        math.floor(s.ensemble_t_end / period) - math.ceil(s.ensemble_transient / period)
    )
    limit_tasks = [
        {
            "coupling": c,
            "t_end": float(s.dky_t_end),
            "transient": float(s.dky_transient),
            # as many section points as one realization of the ensemble has: box counting is
            # biased by the number of points, so the comparison is like for like
            "section_periods": max(window_periods, 10),
            "section_transient": int(math.ceil(s.ensemble_transient / period)),
        }
        for c in ENSEMBLE_COUPLINGS
    ]
    limits = dict(
        zip(
            ENSEMBLE_COUPLINGS,
            ctx.run("paper-limit-dims", limit_tasks, limit_dimension_task),
            strict=True,
        )
    )
    iid = iid_variance_scaling(
        s.iid_spins,
        s.iid_steps,
        s.iid_realizations,
        ctx.seed,
        store=ctx.store_path,
        workers=ctx.task_workers,
        scheduler=ctx.scheduler,
        progress=ctx.progress,
        allow_version_mismatch=ctx.allow_version_mismatch,
    )
    return {"points": points, "limits": limits, "iid": iid, "window_periods": window_periods}


def ensemble_run_text(ctx: PaperContext) -> str:
    s = ctx.size
    return (
        f"{s.ensemble_realizations} realizations per (N, C) (paper: 500), N in "
        f"{list(s.ensemble_spins)}, t_end={s.ensemble_t_end:g}, transient="
        f"{s.ensemble_transient:g} (paper: 1e6 steps), seed {ctx.seed}"
    )


def series_of(data: dict, c: float, attr: str) -> tuple[np.ndarray, np.ndarray]:
    pts = sorted((p for (n, cc), p in data["points"].items() if cc == c), key=lambda p: p.spins)
    return np.array([p.spins for p in pts]), np.array([getattr(p, attr) for p in pts], dtype=float)
