"""Disorder ensembles of the dimer-coupled oscillator (paper fig:dim, fig:sap, fig:mag,
fig:mag_his).

One task is one disorder realization ``SpinDimerEnsemble.random(N, p, R, J, seed)`` at one
coupling C: its Lyapunov spectrum in the Poincaré section (q, v) and ``D_KY``, the box-counting
dimension ``D_BC`` of the section points (q, v) (the superposition of all sheets, as the paper),
and the time-averaged magnetization ``M_T``. Tasks run through
:func:`~analysis.experiments.execution.run_tasks` (process pool or Dask cluster, SQLite store,
resume); :func:`aggregate_ensemble`
reduces them per (N, C) to means, ``SAP[D]``, ``VAR[M]``, the regular count (``D_KY = 0``) and
the empirical PDFs.
"""

from __future__ import annotations

import inspect
import math
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from analysis.dynamics.bifurcation import section_period
from analysis.dynamics.dimensions import box_counting_dimension, kaplan_yorke_dimension
from analysis.dynamics.lyapunov import LANES
from analysis.dynamics.statistics import (
    empirical_pdf,
    magnetization_variance,
    self_averaging_parameter,
)
from analysis.experiments.execution import Batching, run_tasks, spawn_seeds
from analysis.experiments.models import build_operator, canonical_model_name
from analysis.experiments.one_pass import one_pass_measurements, one_pass_measurements_many
from analysis.experiments.parameters import (
    DAMPING_RATIO,
    DEFAULT_Q0,
    FREQUENCY,
    SPIN_COUPLING,
    SPREAD,
    V0,
    WIDTH,
    WIDTH_SPREAD,
)
from analysis.experiments.store import ResultStore
from hysteresis._validation import (
    MAX_MAGNITUDE,
    bounded_work,
    finite_array,
    nonnegative_integer,
    positive_integer,
    positive_scalar,
    scalar_in_open_interval,
    time_window,
)
from hysteresis.spin_dimers import MAX_SPINS
from oscillators import MAX_PERIODS, ForcedOscillator

__all__ = [
    "EXPERIMENT",
    "ensemble_task",
    "ensemble_tasks",
    "run_ensemble",
    "aggregate_ensemble",
    "EnsemblePoint",
    "realization_seeds",
    "ensemble_batch",
    "section_dimension",
    "validate_ensemble",
]

EXPERIMENT = "ensemble-dimers"
#: paper Table I: loop width p, centre spread R, spin coupling J


def realization_seeds(base_seed: int, spins: int, realizations: int) -> list[int]:
    """Disorder seeds of the realizations at N spins: ``spawn_seeds`` from a base derived from
    ``(base_seed, N)``. Different N get independent disorder; different couplings C at the same
    N share it (the same realizations are followed across C)."""

    base_seed = nonnegative_integer(base_seed, "base_seed")
    spins = positive_integer(spins, "spins")
    base = int(np.random.SeedSequence([base_seed, spins]).generate_state(1, np.uint64)[0])
    return spawn_seeds(base >> 1, realizations)


def section_dimension(
    q: np.ndarray, v: np.ndarray, max_fill: float, min_boxes: float
) -> tuple[float, float, int]:
    """(D_BC, its stderr, period): 0 for a periodic section, nan if no scaling region."""

    period = section_period(q, v)
    if period > 0:
        return 0.0, 0.0, period
    try:
        res = box_counting_dimension(
            np.column_stack([q, v]), max_fill=max_fill, min_boxes=min_boxes
        )
    except ValueError:
        return float("nan"), float("nan"), 0
    return float(res.dimension), float(res.stderr), 0


def disorder_system(
    model: str,
    spins: int,
    seed: int,
    coupling: float,
    width: float,
    spread: float,
    spin_coupling: float,
    width_spread: float,
    damping_ratio: float,
    frequency: float,
) -> ForcedOscillator:
    """The forced oscillator with one realization of a disorder model of the registry
    (``dimers``: N spins with spin coupling J; ``preisach``: N relays with half-width spread
    σ_r), ``seed`` its disorder seed; the one place ensembles build their systems."""
    model = canonical_model_name(model)
    params: dict[str, Any] = dict(spins=spins, seed=seed, width=width, spread=spread)
    if model == "dimers":
        params["spin_coupling"] = spin_coupling
    elif model == "preisach":
        params["width_spread"] = width_spread
    else:
        raise ValueError(
            f"model must be 'dimers' or 'preisach' (models with disorder), got {model!r}"
        )
    operator = build_operator(model, **params)
    return ForcedOscillator(operator, coupling, damping_ratio=damping_ratio, frequency=frequency)


def ensemble_task(
    spins: int,
    coupling: float,
    seed: int,
    t_end: float,
    transient: float,
    width: float = WIDTH,
    spread: float = SPREAD,
    spin_coupling: float = SPIN_COUPLING,
    damping_ratio: float = DAMPING_RATIO,
    frequency: float = FREQUENCY,
    q0: float = DEFAULT_Q0,
    v0: float = V0,
    box_max_fill: float = 0.1,
    box_min_boxes: float = 8.0,
    keep_section: bool = False,
    model: str = "dimers",
    width_spread: float = WIDTH_SPREAD,
) -> dict:
    """One disorder realization at one coupling: λ's, D_KY, D_BC and M_T, in one pass.

    ``spins`` = N, ``coupling`` = C, ``seed`` the disorder seed of
    ``SpinDimerEnsemble.random(N, width=p, spread=R, spin_coupling=J, seed)``. One integration
    with the tangent flow (:func:`one_pass_measurements`) gives the Lyapunov spectrum (q, v;
    phase neglected as in the paper), the Poincaré section and ``M_T``, all over the whole
    forcing periods in ``[transient, t_end]``. ``D_BC`` is 0 for a periodic section, else
    :func:`~analysis.dynamics.dimensions.box_counting_dimension` with ``max_fill=box_max_fill`` and
    ``min_boxes=box_min_boxes`` (relax them for short runs with few section points), nan if no
    scaling region is found. Top-level so that it runs in process pools.

    ``model`` is a name of the model registry (:mod:`analysis.experiments.models`) with
    disorder (``dimers``, the default, or ``preisach``: random relays with half-width spread
    ``width_spread``);
    ``spins`` is then its number of spins/relays.
    """
    system = disorder_system(
        model, spins, seed, coupling, width, spread, spin_coupling, width_spread,
        damping_ratio, frequency,
    )  # fmt: skip
    measured = one_pass_measurements(system, t_end, transient, q0, v0)
    return _task_result(measured, box_max_fill, box_min_boxes, keep_section)


def _task_result(measured: tuple, box_max_fill: float, box_min_boxes: float,
                 keep_section: bool) -> dict:  # fmt: skip
    """:func:`ensemble_task`'s result dict from :func:`one_pass_measurements`' values."""
    ly, q, v, m_t, window = measured
    exponents = np.asarray(ly.exponents, dtype=float)
    d_bc, d_bc_err, period = section_dimension(q, v, box_max_fill, box_min_boxes)
    out: dict[str, Any] = {
        "exponents": exponents,
        "max_exponent": float(exponents[0]),
        "kaplan_yorke": float(kaplan_yorke_dimension(exponents)),
        "box_counting": d_bc,
        "box_counting_stderr": d_bc_err,
        "section_period": int(period),
        "section_points": int(q.size),
        "magnetization": float(m_t),
        "window": float(window),
        "switches": int(ly.n_switches),
    }
    if keep_section:
        out["section_q"] = q
        out["section_v"] = v
    return out


#: the smallest ensembles whose realizations share vector lanes (:func:`ensemble_batch`): at
#: N = 1000 the lanes gain nothing (few fast hops per period), from N = 2000 on they do
#: (benchmarks/bench_lanes.py)
LANE_MIN_SPINS = 2000


def _full_task(task: Mapping[str, Any]) -> dict:
    bound = inspect.signature(ensemble_task).bind(**task)
    bound.apply_defaults()
    return dict(bound.arguments)


def _lane_key(task: Mapping[str, Any]) -> tuple | None:
    """What realizations must share to run side by side (everything but the seed); None for
    a task that runs alone (fewer than :data:`LANE_MIN_SPINS` spins)."""
    full = _full_task(task)
    if full["spins"] < LANE_MIN_SPINS:
        return None
    return tuple(sorted((k, v) for k, v in full.items() if k != "seed"))


def ensemble_batch(tasks: Sequence[Mapping[str, Any]]) -> list[dict]:
    """:func:`ensemble_task` of several tasks in one call, each result bit for bit
    ``ensemble_task(**task)``: realizations that differ only in their seed (N ≥
    :data:`LANE_MIN_SPINS`) run side by side in the vector units
    (:func:`one_pass_measurements_many`), the others one after the other. How
    :func:`~analysis.experiments.execution.run_tasks` runs a batch of ensemble tasks
    (``ensemble_task.batching``)."""
    results: list[dict | None] = [None] * len(tasks)
    groups: dict[tuple | None, list[int]] = {}
    for i, task in enumerate(tasks):
        groups.setdefault(_lane_key(task), []).append(i)
    for key, members in groups.items():
        if key is None or len(members) == 1:
            for i in members:
                results[i] = ensemble_task(**tasks[i])
            continue
        full = [_full_task(tasks[i]) for i in members]
        systems = [
            disorder_system(
                f["model"],
                f["spins"],
                f["seed"],
                f["coupling"],
                f["width"],
                f["spread"],
                f["spin_coupling"],
                f["width_spread"],
                f["damping_ratio"],
                f["frequency"],
            )  # fmt: skip
            for f in full
        ]
        f = full[0]
        measured = one_pass_measurements_many(systems, f["t_end"], f["transient"], f["q0"], f["v0"])
        for i, m in zip(members, measured, strict=True):
            results[i] = _task_result(m, f["box_max_fill"], f["box_min_boxes"], f["keep_section"])
    return results  # type: ignore[return-value]


ensemble_task.batching = Batching(run=ensemble_batch, size=LANES, key=_lane_key)  # type: ignore[attr-defined]


#: most tasks one ensemble may ask for (N values × couplings × realizations)
MAX_TASKS = 1_000_000


def validate_ensemble(
    spins_list: Any,
    couplings: Any,
    realizations: Any,
    base_seed: Any,
    t_end: Any,
    transient: Any,
    **task_kwargs: Any,
) -> tuple[list[int], list[float], int, int, float, float, dict]:
    """Check every ensemble argument up front, before any task reaches a worker process.

    Returns the converted values; raises ``ValueError``/``TypeError`` naming the parameter: an
    odd or too small spin count (``spins``), unknown task options, a width outside
    ``(0, 2 spin_coupling)``, ``t_end <= transient``, or more than :data:`MAX_TASKS` tasks or
    :data:`MAX_PERIODS` forcing periods per task (refused, not started).
    """

    if isinstance(spins_list, str | bytes) or not isinstance(spins_list, Iterable):
        raise TypeError(f"spins must be a sequence of even integers, got {spins_list!r}")
    spins = [positive_integer(n, "spins", minimum=2) for n in spins_list]
    if not spins:
        raise ValueError("spins must name at least one ensemble size")
    for n in spins:
        if n % 2:
            raise ValueError(f"spins must be even (the spins come in dimers), got {n}")
        bounded_work(n, "spins", MAX_SPINS, "spins")
    cs = finite_array(couplings, "couplings", ndim=1, max_abs=MAX_MAGNITUDE).tolist()
    realizations = positive_integer(realizations, "realizations")
    base_seed = nonnegative_integer(base_seed, "base_seed")
    bounded_work(len(spins) * len(cs) * realizations, "realizations", MAX_TASKS, "tasks")
    t_end, transient = time_window(t_end, transient)
    allowed = set(inspect.signature(ensemble_task).parameters) - {
        "spins",
        "coupling",
        "seed",
        "t_end",
        "transient",
    }
    unknown = sorted(set(task_kwargs) - allowed)
    if unknown:
        raise TypeError(f"unknown ensemble task options {unknown}; allowed: {sorted(allowed)}")
    spin_coupling = positive_scalar(
        task_kwargs.get("spin_coupling", SPIN_COUPLING), "spin_coupling", MAX_MAGNITUDE
    )
    scalar_in_open_interval(task_kwargs.get("width", WIDTH), "width", 0.0, 2 * spin_coupling)
    positive_scalar(task_kwargs.get("spread", SPREAD), "spread", MAX_MAGNITUDE)
    frequency = positive_scalar(task_kwargs.get("frequency", FREQUENCY), "frequency", MAX_MAGNITUDE)
    zeta = task_kwargs.get("damping_ratio", DAMPING_RATIO)
    scalar_in_open_interval(zeta, "damping_ratio", 0.0, 1.0)
    periods = t_end * frequency / (2.0 * math.pi)
    bounded_work(periods, "t_end", MAX_PERIODS, "forcing periods per task")
    return spins, cs, realizations, base_seed, t_end, transient, task_kwargs


def ensemble_tasks(
    spins_list: Sequence[int],
    couplings: Sequence[float],
    realizations: int,
    base_seed: int,
    t_end: float,
    transient: float,
    **task_kwargs: Any,
) -> list[dict]:
    """The task dicts of an ensemble, ordered by N, then C, then realization (every argument
    checked first by :func:`validate_ensemble`)."""
    spins_list, couplings, realizations, base_seed, t_end, transient, task_kwargs = (
        validate_ensemble(
            spins_list, couplings, realizations, base_seed, t_end, transient, **task_kwargs
        )
    )
    tasks = []
    for n in spins_list:
        seeds = realization_seeds(base_seed, int(n), realizations)
        for c in couplings:
            for s in seeds:
                tasks.append(
                    dict(
                        spins=int(n),
                        coupling=float(c),
                        seed=s,
                        t_end=float(t_end),
                        transient=float(transient),
                        **task_kwargs,
                    )
                )
    return tasks


@dataclass(frozen=True)
class EnsemblePoint:
    """Statistics over the realizations at one (N, C)."""

    spins: int
    coupling: float
    realizations: int
    mean_kaplan_yorke: float
    sap_kaplan_yorke: float
    mean_box_counting: float
    sap_box_counting: float
    mean_magnetization: float
    var_magnetization: float
    regular_count: int
    mean_max_exponent: float
    kaplan_yorke: np.ndarray
    box_counting: np.ndarray
    magnetization: np.ndarray
    max_exponent: np.ndarray

    def to_json(self) -> dict:
        """Summary as a JSON-ready dict (nan -> None)."""

        def f(x: float) -> float | None:
            return None if not np.isfinite(x) else float(x)

        return {
            "spins": self.spins,
            "coupling": self.coupling,
            "realizations": self.realizations,
            "mean_kaplan_yorke": f(self.mean_kaplan_yorke),
            "sap_kaplan_yorke": f(self.sap_kaplan_yorke),
            "mean_box_counting": f(self.mean_box_counting),
            "sap_box_counting": f(self.sap_box_counting),
            "mean_magnetization": f(self.mean_magnetization),
            "var_magnetization": f(self.var_magnetization),
            "regular_count": self.regular_count,
            "mean_max_exponent": f(self.mean_max_exponent),
        }

    def pdf(self, field: str = "magnetization", bins: int | Sequence[float] = 30):
        """Empirical PDF of a per-realization field (paper fig:mag_his for M_T)."""

        return empirical_pdf(getattr(self, field), bins)


def _sap(values: np.ndarray) -> float:
    vals = values[np.isfinite(values)]
    if vals.size == 0 or np.mean(vals) == 0.0:
        return float("nan")
    return self_averaging_parameter(vals)


def aggregate_ensemble(
    records: Iterable[tuple[Mapping[str, Any], Mapping[str, Any]]],
) -> list[EnsemblePoint]:
    """Reduce ``(params, results)`` pairs to one :class:`EnsemblePoint` per (N, C).

    ``D_BC`` that could not be fitted (nan) is left out of its mean and SAP; a SAP whose mean
    is 0 (every realization regular) is nan.
    """
    groups: dict[tuple[int, float], list[Mapping[str, Any]]] = {}
    for params, results in records:
        key = (int(params["spins"]), float(params["coupling"]))
        groups.setdefault(key, []).append(results)
    points = []
    for (n, c), res in sorted(groups.items()):
        dky = np.array([r["kaplan_yorke"] for r in res], dtype=float)
        dbc = np.array(
            [np.nan if r["box_counting"] is None else r["box_counting"] for r in res], dtype=float
        )
        m = np.array([r["magnetization"] for r in res], dtype=float)
        lam = np.array([r["max_exponent"] for r in res], dtype=float)
        finite_bc = dbc[np.isfinite(dbc)]
        points.append(
            EnsemblePoint(
                spins=n,
                coupling=c,
                realizations=len(res),
                mean_kaplan_yorke=float(np.mean(dky)),
                sap_kaplan_yorke=_sap(dky),
                mean_box_counting=float(np.mean(finite_bc)) if finite_bc.size else float("nan"),
                sap_box_counting=_sap(dbc),
                mean_magnetization=float(np.mean(m)),
                var_magnetization=magnetization_variance(m),
                regular_count=int(np.count_nonzero(dky == 0.0)),
                mean_max_exponent=float(np.mean(lam)),
                kaplan_yorke=dky,
                box_counting=dbc,
                magnetization=m,
                max_exponent=lam,
            )
        )
    return points


def run_ensemble(
    spins_list: Sequence[int],
    couplings: Sequence[float],
    realizations: int,
    base_seed: int,
    t_end: float,
    transient: float,
    store: ResultStore | str | os.PathLike | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = False,
    allow_version_mismatch: bool = False,
    **task_kwargs: Any,
) -> list[EnsemblePoint]:
    """Run (or resume) the ensemble and aggregate it per (N, C).

    Every (N, C, realization) is one task of :func:`ensemble_task` (experiment
    ``"ensemble-dimers"``); ``store``/``workers``/``scheduler`` as in :func:`run_tasks`;
    ``progress`` shows a progress bar (off by default); ``allow_version_mismatch`` as in
    :func:`run_tasks`. ``task_kwargs`` go to every task (see
    :func:`ensemble_task`; ``model="preisach"`` runs random-relay ensembles).
    """
    tasks = ensemble_tasks(
        spins_list, couplings, realizations, base_seed, t_end, transient, **task_kwargs
    )
    results = run_tasks(
        EXPERIMENT,
        tasks,
        ensemble_task,
        store=store,
        workers=workers,
        scheduler=scheduler,
        progress=progress,
        allow_version_mismatch=allow_version_mismatch,
    )
    return aggregate_ensemble(zip(tasks, results, strict=True))
