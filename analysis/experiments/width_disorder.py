"""The width-disorder study: Preisach models with a spread of loop widths, continuum and finite N.

The paper's thermodynamic limit has all elementary loops of one width p (the ridge
``δ(r − p/2)``; the erf play). Here the half-widths spread, ``N(r; p/2, σ_r²)`` cut at r >= 0:

* **continuum** (N = ∞): :meth:`ContinuousPreisachModel.gaussian` (registry ``preisach-gauss``)
  at each σ_r and coupling C, from several seeded initial conditions
  (:func:`continuum_task`, experiment :data:`EXPERIMENT_CONTINUUM`): the Lyapunov spectrum with
  the memory directions (the remembered extrema), its finite-time errors from block averages
  and the number of neutral exponents (:mod:`analysis.dynamics.memory`), the live memory
  directions sampled every forcing period, the exponents without long-lived memory
  (:func:`~analysis.dynamics.memory.memory_frozen_exponents`, one or more projection
  intervals), ``D_KY`` of both, and the box-counting dimension of the Poincaré section in
  ``(q, v)`` and ``(q, v, M)``, the section continued without tangent flow up to
  ``section_t_end``. σ_r = 0 is the erf play (registry ``erf-play``), the reference.
* **finite N** (N → ∞): the registry model ``preisach`` (N relays drawn from the same density)
  through the ensemble machinery (:func:`~analysis.experiments.ensemble.run_ensemble`, one call
  per σ_r into the same store): mean ``D_KY`` and ``D_BC``, their SAP, the fraction of regular
  realizations, VAR[M].

Every task is stored as it finishes (a killed run resumes) and no number depends on the engine
that integrates it (:func:`oscillators.engines.select_engine` picks it). :func:`run_study` runs
both parts and :func:`summarize` reduces them to the JSON of ``docs/width_disorder/``.
"""

from __future__ import annotations

import itertools
import math
import os
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np

from analysis.dynamics.dimensions import box_counting_dimension, kaplan_yorke_dimension
from analysis.dynamics.lyapunov import lyapunov_spectrum
from analysis.dynamics.memory import (
    exponent_block_errors,
    memory_frozen_exponents,
    neutral_count,
)
from analysis.experiments.ensemble import EXPERIMENT as ENSEMBLE_EXPERIMENT
from analysis.experiments.ensemble import ensemble_tasks, run_ensemble
from analysis.experiments.execution import run_tasks
from analysis.experiments.models import build_operator
from analysis.experiments.parameters import (
    DAMPING_RATIO,
    DEFAULT_Q0,
    FREQUENCY,
    SPREAD,
    V0,
    WIDTH,
)
from analysis.experiments.store import ResultStore
from analysis.experiments.store_format import task_key
from hysteresis._validation import as_generator, nonnegative_integer, positive_integer
from oscillators import ForcedOscillator

__all__ = [
    "EXPERIMENT_CONTINUUM",
    "StudySize",
    "SIZES",
    "initial_conditions",
    "continuum_task",
    "continuum_tasks",
    "run_continuum",
    "run_finite",
    "run_study",
    "summarize",
]

EXPERIMENT_CONTINUUM = "width-disorder-continuum"
#: box counting of the ensemble tasks (as ``hyst ensemble``'s defaults)
BOX_MAX_FILL, BOX_MIN_BOXES = 0.1, 8.0


@dataclass(frozen=True)
class StudySize:
    """Sizes of one run of the study (times in time units, transients in forcing periods)."""

    couplings: tuple[float, ...]
    width_spreads: tuple[float, ...]
    t_end: float
    transient_periods: int
    initial_conditions: int
    section_t_end: float
    blocks: int
    projection_periods: tuple[int, ...]
    spins: tuple[int, ...]
    realizations: int | tuple[int, ...]
    finite_t_end: float
    finite_transient_periods: int


SPREADS = (0.0125, 0.025, 0.05, 0.1, 0.2, 0.4)
#: ``full``: the issue's sizes; ``quick``: a tiny configuration that checks every step (seconds)
SIZES = {
    "full": StudySize(
        couplings=(2.9, 4.0),
        width_spreads=SPREADS,
        t_end=20000.0,
        transient_periods=160,
        initial_conditions=3,
        section_t_end=100000.0,
        blocks=10,
        projection_periods=(1, 8),
        spins=(1000, 5000, 20000),
        realizations=100,
        finite_t_end=20000.0,
        finite_transient_periods=160,
    ),
    "quick": StudySize(
        couplings=(4.0,),
        width_spreads=(0.2,),
        t_end=30 * 2 * math.pi,
        transient_periods=5,
        initial_conditions=2,
        section_t_end=60 * 2 * math.pi,
        blocks=4,
        projection_periods=(1,),
        spins=(200,),
        realizations=3,
        finite_t_end=40 * 2 * math.pi,
        finite_transient_periods=5,
    ),
}


def initial_conditions(n: int, seed: int = 0) -> list[tuple[float, float]]:
    """``n`` initial conditions ``(q0, v0)``: the paper's ``(−1, 0.1)`` first, then draws
    ``q0 ~ U(−1.5, 1.5)``, ``v0 ~ U(−1, 1)`` from ``seed`` (the memory: rising from negative
    saturation to q0)."""
    n = positive_integer(n, "initial_conditions")
    rng = as_generator(nonnegative_integer(seed, "seed"))
    out = [(float(DEFAULT_Q0), float(V0))]
    for _ in range(n - 1):
        out.append((float(rng.uniform(-1.5, 1.5)), float(rng.uniform(-1.0, 1.0))))
    return out


def _operator(width_spread: float) -> Any:
    if width_spread == 0.0:
        return build_operator("erf-play", width=WIDTH, spread=SPREAD)
    return build_operator("preisach-gauss", width=WIDTH, spread=SPREAD, width_spread=width_spread)


def _dimension(points: np.ndarray) -> tuple[float, float]:
    """(D_BC, stderr) of section points; nan if no scaling region (too few points)."""
    try:
        res = box_counting_dimension(points, max_fill=BOX_MAX_FILL, min_boxes=BOX_MIN_BOXES)
    except ValueError:
        return float("nan"), float("nan")
    return float(res.dimension), float(res.stderr)


def continuum_task(
    coupling: float,
    width_spread: float,
    q0: float,
    v0: float,
    t_end: float,
    transient: float,
    section_t_end: float,
    blocks: int,
    projection_periods: Sequence[int],
) -> dict:
    """One (C, σ_r, initial condition) of the continuum (see the module docstring).

    The spectrum runs with one QR step per forcing period over the whole periods in
    ``[transient, t_end]`` (``transient`` and ``t_end`` should be multiples of T); the observer
    records the section point ``(q, v, M)`` and the number of live memory directions
    (``len(tangent_space) − 2``) at every period. The section is continued from the final
    state without tangent flow to ``section_t_end`` (if longer). Top-level (process pools).
    """
    system = ForcedOscillator(
        _operator(float(width_spread)), coupling, damping_ratio=DAMPING_RATIO, frequency=FREQUENCY
    )
    period = float(system.period)
    section: list[np.ndarray] = []
    live: list[int] = []

    def observe(stepper: Any) -> None:
        section.append(stepper.sample)
        live.append(len(stepper.tangent_space) - 2)

    start = time.perf_counter()
    n_qr = int(round((t_end - transient) / period))
    res = lyapunov_spectrum(
        system,
        t_end,
        transient,
        q0,
        v0,
        observer=observe,
        history_points=max(n_qr, blocks),
    )
    spectrum_seconds = time.perf_counter() - start
    exps = np.asarray(res.exponents, dtype=float)
    errs = exponent_block_errors(res, blocks)
    pts = np.asarray(section[:-1])  # periods P0 .. P1 − 1
    start = time.perf_counter()
    extra = int(math.floor((section_t_end - t_end) / period + 1e-9))
    if extra > 0:
        f = res.final
        sec = system.poincare_section(extra + 1, 0, f.q, f.v, f.operator_state)
        pts = np.vstack([pts, np.column_stack([sec.q, sec.v, sec.M])[:-1]])
    section_seconds = time.perf_counter() - start
    d_qv, d_qv_err = _dimension(pts[:, :2])
    d_qvm, d_qvm_err = _dimension(pts)
    frozen, frozen_ky, zeroed = [], [], []
    start = time.perf_counter()
    for p in projection_periods:
        fr = memory_frozen_exponents(system, t_end, transient, q0, v0, projection_periods=int(p))
        frozen.append(fr.exponents)
        frozen_ky.append(kaplan_yorke_dimension(fr.exponents))
        zeroed.append(fr.zeroed_mean)
    frozen_seconds = time.perf_counter() - start
    live_arr = np.asarray(live, dtype=np.int64)
    return {
        "exponents": exps,
        "exponent_errors": errs,
        "kaplan_yorke": float(kaplan_yorke_dimension(exps)),
        "neutral": neutral_count(exps, errs),
        "finite_exponents": int(np.count_nonzero(np.isfinite(exps))),
        "tangent_space": list(res.tangent_space),
        "n_collapses": int(res.extra["n_collapses"]),
        "engine": str(res.extra["engine"]),
        "live_memory": live_arr,
        "frozen_exponents": np.asarray(frozen, dtype=float).reshape(-1, 2),
        "frozen_kaplan_yorke": [float(x) for x in frozen_ky],
        "frozen_zeroed": [float(x) for x in zeroed],
        "box_counting": d_qv,
        "box_counting_stderr": d_qv_err,
        "box_counting_qvm": d_qvm,
        "box_counting_qvm_stderr": d_qvm_err,
        "section_points": int(pts.shape[0]),
        "section": pts,
        "spectrum_seconds": spectrum_seconds,
        "section_seconds": section_seconds,
        "frozen_seconds": frozen_seconds,
    }


def continuum_tasks(size: StudySize, seed: int = 0) -> list[dict]:
    """Task dicts of the continuum: σ_r = 0 (the erf play) and every σ_r, per initial
    condition and C (``t_end`` and the transient rounded to whole forcing periods)."""
    period = 2 * math.pi / FREQUENCY
    transient = size.transient_periods * period
    t_end = math.floor(size.t_end / period + 1e-9) * period
    if not t_end > transient:
        raise ValueError(f"t_end={size.t_end} must exceed the transient ({transient:g})")
    if size.section_t_end < size.t_end:
        # the section runs on from the spectrum's end: a shorter one would be cut to t_end
        raise ValueError(
            f"section_t_end={size.section_t_end:g} must be >= t_end={size.t_end:g} (the "
            "section continues the spectrum's run)"
        )
    tasks = []
    # initial condition outermost: a run stopped early has every (C, σ_r) from fewer of them
    for q0, v0 in initial_conditions(size.initial_conditions, seed):
        for c in size.couplings:
            for s in (0.0, *size.width_spreads):
                tasks.append(
                    dict(
                        coupling=float(c),
                        width_spread=float(s),
                        q0=q0,
                        v0=v0,
                        t_end=float(t_end),
                        transient=float(transient),
                        section_t_end=float(size.section_t_end),
                        blocks=int(size.blocks),
                        projection_periods=[int(p) for p in size.projection_periods],
                    )
                )
    return tasks


def run_continuum(
    size: StudySize,
    store: ResultStore | str | os.PathLike | None = None,
    workers: int | None = None,
    progress: bool = False,
    allow_version_mismatch: bool = False,
    seed: int = 0,
) -> list[tuple[dict, dict]]:
    """Run (or resume) the continuum tasks; returns ``(params, results)`` pairs."""
    tasks = continuum_tasks(size, seed)
    results = run_tasks(
        EXPERIMENT_CONTINUUM,
        tasks,
        continuum_task,
        store=store,
        workers=workers,
        progress=progress,
        allow_version_mismatch=allow_version_mismatch,
    )
    return list(zip(tasks, results, strict=True))


def run_finite(
    size: StudySize,
    store: ResultStore | str | os.PathLike | None = None,
    workers: int | None = None,
    progress: bool = False,
    allow_version_mismatch: bool = False,
    seed: int = 0,
) -> list[dict]:
    """The finite-N ensembles (registry model ``preisach``), one :func:`run_ensemble` per
    (σ_r, N) (σ_r = 0 included: equal widths) into the same store, with ``size.realizations``
    realizations (one count, or one per N); returns one summary row per (σ_r, N, C). The task
    options are those of ``hyst ensemble --model preisach`` with its defaults, so that an
    ensemble started by that command is resumed here."""
    transient = size.finite_transient_periods * 2 * math.pi / FREQUENCY
    per_n = size.realizations
    if isinstance(per_n, int):
        per_n = (per_n,) * len(size.spins)
    if len(per_n) != len(size.spins):
        raise ValueError(
            f"realizations must be one count or one per N ({len(size.spins)}), got {per_n}"
        )
    rows = []
    # one ensemble per (σ_r, N): the disorder seeds depend on (seed, N) only, so this is the
    # same set of tasks as one call over every N
    sizes = list(zip(size.spins, per_n, strict=True))
    for s, (n, count) in itertools.product((0.0, *size.width_spreads), sizes):
        args = ([n], list(size.couplings), count, seed, size.finite_t_end, transient)
        kw = dict(
            damping_ratio=DAMPING_RATIO,
            frequency=FREQUENCY,
            box_max_fill=BOX_MAX_FILL,
            box_min_boxes=BOX_MIN_BOXES,
            width=WIDTH,
            spread=SPREAD,
            model="preisach",
            width_spread=float(s),
        )
        points = run_ensemble(
            *args,
            store=store,
            workers=workers,
            progress=progress,
            allow_version_mismatch=allow_version_mismatch,
            **kw,
        )
        seconds = _task_seconds(store, ensemble_tasks(*args, **kw))
        for pt in points:
            row = {"width_spread": float(s), **pt.to_json()}
            row["task_seconds"] = seconds.get((pt.spins, pt.coupling))
            row["fraction_regular"] = pt.regular_count / pt.realizations
            row["kaplan_yorke_values"] = pt.kaplan_yorke
            row["box_counting_values"] = pt.box_counting
            rows.append(row)
    return rows


def _task_seconds(
    store: ResultStore | str | os.PathLike | None, tasks: list[dict]
) -> dict[tuple[int, float], float]:
    """Summed wall time of the stored ensemble tasks per (N, C) (as measured in the worker)."""
    if store is None:
        return {}
    own = not isinstance(store, ResultStore)
    st = ResultStore(store) if own else store
    try:
        out: dict[tuple[int, float], float] = {}
        for t in tasks:
            wall = st.get(task_key(ENSEMBLE_EXPERIMENT, t)).wall_time
            key = (int(t["spins"]), float(t["coupling"]))
            out[key] = out.get(key, 0.0) + float(wall or 0.0)
        return out
    finally:
        if own:
            st.close()


def _mean_sem(x: Sequence[float]) -> tuple[float, float]:
    a = np.asarray(x, dtype=float)
    a = a[np.isfinite(a)]
    if a.size == 0:
        return float("nan"), float("nan")
    sem = float(np.std(a, ddof=1) / math.sqrt(a.size)) if a.size > 1 else float("nan")
    return float(np.mean(a)), sem


def summarize(
    continuum: Sequence[tuple[dict, dict]], finite: Sequence[dict], size: StudySize
) -> dict:
    """One JSON-ready record: the continuum per (C, σ_r) with its initial conditions, and the
    finite-N rows. Means over initial conditions carry their standard error (sem)."""
    groups: dict[tuple[float, float], list[tuple[dict, dict]]] = {}
    for params, res in continuum:
        groups.setdefault((params["coupling"], params["width_spread"]), []).append((params, res))
    points = []
    for (c, s), items in sorted(groups.items()):
        runs = []
        for params, r in items:
            lam = np.asarray(r["exponents"], dtype=float)
            live = np.asarray(r["live_memory"])
            runs.append(
                {
                    "q0": params["q0"],
                    "v0": params["v0"],
                    "exponents": lam.tolist(),
                    "exponent_errors": np.asarray(r["exponent_errors"], dtype=float).tolist(),
                    "kaplan_yorke": r["kaplan_yorke"],
                    "neutral": r["neutral"],
                    "finite_exponents": r["finite_exponents"],
                    "tangent_space": r["tangent_space"],
                    "live_memory_mean": float(np.mean(live)),
                    "live_memory_min": int(np.min(live)),
                    "live_memory_max": int(np.max(live)),
                    "frozen_exponents": np.asarray(r["frozen_exponents"]).tolist(),
                    "frozen_kaplan_yorke": r["frozen_kaplan_yorke"],
                    "box_counting": r["box_counting"],
                    "box_counting_stderr": r["box_counting_stderr"],
                    "box_counting_qvm": r["box_counting_qvm"],
                    "section_points": r["section_points"],
                    "engine": r["engine"],
                    "seconds": r["spectrum_seconds"] + r["section_seconds"] + r["frozen_seconds"],
                }
            )
        lam1 = [x["exponents"][0] for x in runs]
        lam2 = [x["exponents"][1] for x in runs]
        point = {
            "coupling": c,
            "width_spread": s,
            "runs": runs,
            "lambda_max": _mean_sem(lam1),
            "lambda_2": _mean_sem(lam2),
            "kaplan_yorke": _mean_sem([x["kaplan_yorke"] for x in runs]),
            "neutral": [x["neutral"] for x in runs],
            "live_memory_mean": float(np.mean([x["live_memory_mean"] for x in runs])),
            "box_counting": _mean_sem([x["box_counting"] for x in runs]),
            "box_counting_qvm": _mean_sem([x["box_counting_qvm"] for x in runs]),
            "seconds": float(sum(x["seconds"] for x in runs)),
        }
        for i, p in enumerate(size.projection_periods):
            point[f"frozen_P{p}_lambda_2"] = _mean_sem([x["frozen_exponents"][i][1] for x in runs])
            point[f"frozen_P{p}_kaplan_yorke"] = _mean_sem(
                [x["frozen_kaplan_yorke"][i] for x in runs]
            )
        points.append(point)
    finite_rows = [{k: v for k, v in row.items() if not k.endswith("_values")} for row in finite]
    return {"size": asdict(size), "continuum": points, "finite": finite_rows}


def run_study(
    size: StudySize | str = "full",
    store: ResultStore | str | os.PathLike | None = None,
    workers: int | None = None,
    progress: bool = False,
    allow_version_mismatch: bool = False,
    parts: Sequence[str] = ("continuum", "finite"),
    finite_store: ResultStore | str | os.PathLike | None = None,
    **overrides: Any,
) -> dict:
    """Run (or resume) the study at ``size`` (a :data:`SIZES` name or a :class:`StudySize`,
    with ``overrides`` of its fields) and return :func:`summarize`'s record with the wall time
    of each part (``wall_seconds``). ``finite_store`` keeps the finite-N ensembles (default:
    ``store``)."""
    if isinstance(size, str):
        if size not in SIZES:
            raise ValueError(f"size must be one of {sorted(SIZES)}, got {size!r}")
        size = SIZES[size]
    size = replace(size, **overrides)
    unknown = set(parts) - {"continuum", "finite"}
    if unknown or not parts:
        raise ValueError(f"parts must name 'continuum' and/or 'finite', got {list(parts)}")
    timing = {}
    continuum: list[tuple[dict, dict]] = []
    finite: list[dict] = []
    if "continuum" in parts:
        start = time.perf_counter()
        continuum = run_continuum(size, store, workers, progress, allow_version_mismatch)
        timing["continuum"] = time.perf_counter() - start
    if "finite" in parts:
        start = time.perf_counter()
        finite = run_finite(
            size,
            store if finite_store is None else finite_store,
            workers,
            progress,
            allow_version_mismatch,
        )
        timing["finite"] = time.perf_counter() - start
    record = summarize(continuum, finite, size)
    record["wall_seconds"] = timing
    return record
