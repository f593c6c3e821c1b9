"""Basins of attraction: where each start of a grid (or any list) of initial conditions ends.

Plain reading of :func:`basins`::

    for every chunk of starts (one task, run by the caller's executor):
        for every start: section_run (no tangent flow) -> periodic (k, cycle, transient),
                         aperiodic (tail points) or divergent
    periodic starts:   while one is unlabelled: refine the orbit of the first one once
                       (periodic_attractor), give its label to every start whose cycle is that
                       orbit up to a cyclic shift within match_tolerance (an orbit equal to one
                       already found joins its label)
    aperiodic starts:  while one is unlabelled (at most max_aperiodic times): continue the
                       first one for lyapunov_periods and record the continuation's section
                       cloud (q, v) on a cloud_bins² grid; if the continuation has not settled
                       on a cycle and the start's own tail lies in the cloud, λ_max ± error and
                       D_KY on the same continuation (lyapunov_estimate); if λ_max exceeds twice
                       its error it is a chaotic attractor, and every start whose tail points
                       lie in the cloud's cells or their neighbours (90 % of them at least) gets
                       its label; else that start is undecided (a chaotic transient, a slow
                       approach, a quasi-periodic motion or a period above max_period: a longer
                       max_periods may resolve it)
    the rest:          "undecided"; divergent starts: "divergent"

So the orbit refinement and the Lyapunov run happen once per attractor, not once per start.

``method="recurrences"`` replaces the per-start budget by the recurrence mapper of
:mod:`analysis.dynamics.recurrence` (Datseris & Wagemakers 2022): a start stops as soon as its
section enters the cells of a known attractor or of its basin, new attractors are found by
recurrences on the cell grid; each attractor found is classified once as above (its finder's
state: section run, refined orbit or λ_max and D_KY). ``transients`` are then not measured (−1);
``steps`` holds the periods each start ran.

Execution is the caller's: the chunks of starts are tasks ``func(**task)`` handed to an
``executor`` (:func:`run_chunks`: serial, a ``concurrent.futures.Executor``, or a callable such
as a store-backed :func:`analysis.experiments.execution.run_tasks`, which the command line and
the report pass to keep their resumable store); this module imports no store.
Fractions come with the 95 % Wilson score interval
(:func:`~analysis.dynamics.statistics.wilson_interval`). A grid over (q0, w0) (play-type
memory) has starts outside the play's band ``|q0 − w0| <= p/2``: they are no states, labelled
−1 and left out of the fractions.
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from analysis.dynamics.attractors import (
    APERIODIC,
    DIVERGENT,
    PERIODIC,
    lyapunov_estimate,
    match_cycles,
    periodic_attractor,
    section_run,
    start_state,
)
from analysis.dynamics.basin_map import MAX_STARTS, BasinGrid, BasinMap
from analysis.dynamics.bifurcation import section_period
from analysis.dynamics.recurrence import (
    DIVERGED,
    NO_STATE,
    RecurrenceSettings,
    merge_attractors,
    recurrence_chunk,
    representative_state,
)
from analysis.dynamics.statistics import wilson_interval
from hysteresis._validation import (
    MAX_MAGNITUDE,
    bounded_work,
    finite_array,
    finite_scalar,
    nonnegative_integer,
    positive_integer,
)
from oscillators import DivergenceError

__all__ = [
    "EXPERIMENT",
    "BasinGrid",
    "BasinMap",
    "MAX_STARTS",
    "METHODS",
    "RecurrenceSettings",
    "basin_chunk",
    "basins",
    "run_chunks",
]

EXPERIMENT = "basins"
#: ``sections``: every start runs its section budget; ``recurrences``: the recurrence mapper
METHODS = ("sections", "recurrences")
#: label of a grid point that is no state (w0 outside the play's band)
NOT_A_STATE = -1
#: share of a start's tail points that must lie in an aperiodic attractor's cloud
CLOUD_SHARE = 0.9


def basin_chunk(
    *,
    system: Any,
    starts: Sequence[Sequence[float]],
    transient: int,
    periods: int,
    max_periods: int,
    tolerance: float,
    max_period: int,
    tail: int,
    system_key: str = "",
) -> dict:
    """One task: :func:`~analysis.dynamics.attractors.section_run` for each start ``(q0, v0,
    w0)`` (w0 nan: default memory). ``system_key`` only names the system in the task's key.

    Returns arrays: ``status`` (1 periodic, 0 aperiodic, −1 divergent, −2 no state), ``period``,
    ``transient``, ``cycles`` (the cycles' points, concatenated in start order), ``tails``
    (``tail`` (q, v) points of every aperiodic start, concatenated).
    """
    pts = np.asarray(starts, dtype=float).reshape(-1, 3)
    n = pts.shape[0]
    status = np.zeros(n, dtype=np.int8)
    period = np.zeros(n, dtype=np.int32)
    trans = np.full(n, -1, dtype=np.int32)
    cycles: list[np.ndarray] = []
    tails: list[np.ndarray] = []
    width = None
    for i, (q0, v0, w0) in enumerate(pts):
        try:
            state = start_state(system, q0, v0, None if math.isnan(w0) else w0)
        except ValueError:
            status[i] = -2
            continue
        run = section_run(
            system,
            state,
            transient,
            periods,
            max_periods=max_periods,
            tolerance=tolerance,
            max_period=max_period,
            tail=tail,
        )
        width = len(run.columns)
        status[i], period[i], trans[i] = run.status, run.period, run.transient
        if run.status == PERIODIC:
            cycles.append(run.cycle)
        elif run.status == APERIODIC:
            tails.append(run.tail[:, :2])
    d = width or 3
    return {
        "status": status,
        "period": period,
        "transient": trans,
        "cycles": np.concatenate(cycles) if cycles else np.empty((0, d)),
        "tails": np.concatenate(tails) if tails else np.empty((0, 2)),
    }


def _as_starts(starts: Any) -> tuple[np.ndarray, BasinGrid | None]:
    if isinstance(starts, BasinGrid):
        return starts.starts(), starts
    arr = np.asarray(starts, dtype=float)
    if arr.ndim != 2 or arr.shape[1] not in (2, 3) or arr.shape[0] == 0:
        raise ValueError(
            f"starts must be a BasinGrid or rows (q0, v0) or (q0, v0, w0), got shape {arr.shape}"
        )
    if arr.shape[1] == 2:
        arr = np.column_stack([arr, np.full(arr.shape[0], np.nan)])
    finite_array(arr[:, :2], "starts", ndim=2, max_abs=MAX_MAGNITUDE)
    bounded_work(arr.shape[0], "starts", MAX_STARTS, "starts")
    return arr, None


def run_chunks(executor: Any, tasks: list[dict], func: Callable[..., dict]) -> list[dict]:
    """``func(**task)`` for every task, in task order, on ``executor``: ``None`` (serially
    here), a :class:`concurrent.futures.Executor` (anything with ``submit`` and ``map``; ``func``
    must then be picklable), or a callable ``runner(tasks, func) -> results`` — e.g.
    ``functools.partial(analysis.experiments.execution.run_tasks, "basins", store=...)``, which
    stores every task and resumes. Execution is the caller's choice, as in Attractors.jl."""
    if executor is None:
        return [func(**t) for t in tasks]
    if hasattr(executor, "submit") and hasattr(executor, "map"):
        return list(executor.map(functools.partial(_call, func), tasks))
    if callable(executor):
        results = list(executor(tasks, func))
        if len(results) != len(tasks):
            raise ValueError(f"executor returned {len(results)} results for {len(tasks)} tasks")
        return results
    raise TypeError(
        "executor must be None, a concurrent.futures.Executor or a callable (tasks, func) -> "
        f"results, got {type(executor).__name__}"
    )


def _call(func: Callable[..., dict], task: dict) -> dict:
    return func(**task)


def basins(
    system: Any,
    starts: BasinGrid | Sequence[Sequence[float]] | np.ndarray,
    *,
    method: str = "sections",
    transient: int = 100,
    periods: int = 100,
    max_periods: int | None = None,
    tolerance: float = 1e-6,
    match_tolerance: float = 1e-4,
    max_period: int | None = None,
    lyapunov_periods: int = 2000,
    max_aperiodic: int = 8,
    cloud_bins: int = 64,
    tail: int = 16,
    chunk: int = 200,
    recurrence: RecurrenceSettings | None = None,
    executor: Any = None,
    system_key: str = "",
) -> BasinMap:
    """Classify where every start ends (module docstring) and collect the basins.

    Parameters
    ----------
    system:
        A :class:`~oscillators.system.ForcedOscillator` (shipped to the workers as is).
    starts:
        A :class:`BasinGrid`, or rows ``(q0, v0)`` (default memory) or ``(q0, v0, w0)``
        (play-type memory; nan: default).
    method:
        ``"sections"`` (every start runs its section budget and is classified by its own
        section) or ``"recurrences"`` (the recurrence mapper of
        :mod:`analysis.dynamics.recurrence`: a start stops once its section enters a known
        attractor's or basin's cells; the attractors it finds are classified here as below).
    transient, periods, max_periods:
        Forcing periods integrated before the measured window, and in it (``periods >= 2``);
        a start without a period goes on ``periods`` at a time up to ``max_periods`` in all
        (default ``transient + periods``: no extension), so long transients get resolved while
        a start that settles early stops early. ``recurrences``: a start skips ``transient``
        periods, then runs at most ``max_periods − transient`` (its ``max_steps``; default
        ``max(periods, mx_chk_fnd_att + mx_chk_loc_att)``, the budget in which a start can
        declare and locate an attractor — the starts that meet known cells stop in a few
        periods, so it costs only the ones that find attractors); ``periods``
        and ``max_periods`` are also the section run that classifies each attractor found.
    tolerance:
        Absolute tolerance of the section period (every section coordinate).
    match_tolerance:
        Absolute tolerance within which a start's cycle is a refined orbit (cyclic shifts
        included); larger than ``tolerance`` because a cycle repeating within ``tolerance`` is
        within ``tolerance/(1 − |μ|)`` of its orbit.
    max_period:
        Longest section period detected (``<= periods // 2``; default ``min(32, periods // 2)``).
    lyapunov_periods, max_aperiodic, cloud_bins, tail:
        The aperiodic attractors: length of the Lyapunov run (10 segments), the most attractor
        candidates tried, the cells per axis of the section cloud, the tail points per start.
    chunk:
        Starts per task (``sections``; ``recurrences`` takes ``recurrence.chunk``).
    recurrence:
        The recurrence mapper's knobs (default :class:`RecurrenceSettings()`).
    executor:
        Where the tasks run (:func:`run_chunks`): ``None`` serially, an ``Executor``, or a
        callable ``(tasks, func) -> results`` such as a store-backed ``run_tasks`` (resume).
    system_key:
        A string naming the system (operator and its parameters, C, ζ, Ω), put into every task:
        a runner that stores tasks keys them by it.
    """
    pts, grid = _as_starts(starts)
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    transient = nonnegative_integer(transient, "transient")
    periods = positive_integer(periods, "periods", minimum=2)
    max_period = min(32, periods // 2) if max_period is None else max_period
    max_period = positive_integer(max_period, "max_period")
    if max_period > periods // 2:
        raise ValueError(f"max_period must be <= periods // 2 = {periods // 2}, got {max_period}")
    tolerance = finite_scalar(tolerance, "tolerance")
    match_tolerance = finite_scalar(match_tolerance, "match_tolerance")
    if not (tolerance > 0 and match_tolerance >= tolerance):
        raise ValueError(
            f"tolerance must be > 0 and match_tolerance >= tolerance, got {tolerance}, "
            f"{match_tolerance}"
        )
    lyapunov_periods = positive_integer(lyapunov_periods, "lyapunov_periods", minimum=10)
    max_aperiodic = nonnegative_integer(max_aperiodic, "max_aperiodic")
    cloud_bins = positive_integer(cloud_bins, "cloud_bins", minimum=4)
    tail = positive_integer(tail, "tail")
    chunk = positive_integer(chunk, "chunk")
    if not isinstance(system_key, str):
        raise TypeError(f"system_key must be a string, got {type(system_key).__name__}")
    recurrence = RecurrenceSettings() if recurrence is None else recurrence
    if not isinstance(recurrence, RecurrenceSettings):
        raise TypeError(f"recurrence must be a RecurrenceSettings, got {type(recurrence).__name__}")
    if max_periods is None:
        # recurrences: a start must be able to declare an attractor (mx_chk_fnd_att
        # recurrences after its first revisit) and locate it; with the sections' default
        # (periods = 100 = mx_chk_fnd_att) no start ever could, and every one was undecided
        find = recurrence.mx_chk_fnd_att + recurrence.mx_chk_loc_att
        max_periods = transient + (max(periods, find) if method == "recurrences" else periods)
    max_periods = positive_integer(max_periods, "max_periods", minimum=transient + periods)
    valid = _valid_starts(system, pts, grid)
    settings = dict(
        transient=transient,
        periods=periods,
        max_periods=max_periods,
        tolerance=tolerance,
        max_period=max_period,
        tail=tail,
    )
    run = functools.partial(_rerun, system, pts, settings)
    classify = dict(
        match_tolerance=match_tolerance,
        lyapunov_periods=lyapunov_periods,
        max_aperiodic=max_aperiodic,
        cloud_bins=cloud_bins,
    )
    clock = time.perf_counter()
    if method == "recurrences":
        tasks = [
            dict(
                starts=pts[i : i + recurrence.chunk].tolist(),
                transient=transient,
                max_steps=max_periods - transient,
                system_key=system_key,
                **recurrence.task(),
            )
            for i in range(0, pts.shape[0], recurrence.chunk)
        ]
        results = run_chunks(executor, tasks, functools.partial(recurrence_chunk, system=system))
        timings = {"sections_s": time.perf_counter() - clock}
        clock = time.perf_counter()
        labels, attractors, steps, extra = _label_recurrences(
            system, pts, results, recurrence.chunk, settings, classify
        )
        settings.update(
            method=method,
            match_tolerance=match_tolerance,
            lyapunov_periods=lyapunov_periods,
            recurrence=recurrence.task(),
            **extra,
        )
        trans = np.full(pts.shape[0], -1, dtype=np.int32)
        period = np.array(
            [attractors[x].get("period", 0) if x >= 0 else 0 for x in labels], dtype=np.int32
        )
    else:
        tasks = [
            dict(starts=pts[i : i + chunk].tolist(), system_key=system_key, **settings)
            for i in range(0, pts.shape[0], chunk)
        ]
        results = run_chunks(executor, tasks, functools.partial(basin_chunk, system=system))
        timings = {"sections_s": time.perf_counter() - clock}
        clock = time.perf_counter()
        labels, attractors, period, trans = _label_sections(
            system, results, valid, run, settings, classify
        )
        settings.update(match_tolerance=match_tolerance, lyapunov_periods=lyapunov_periods)
        steps = None
    n_valid = int(np.count_nonzero(labels >= 0))
    for a in attractors:
        mine = labels == a["label"]
        count = int(np.count_nonzero(mine))
        lo, hi = wilson_interval(count, n_valid)
        a.update(count=count, fraction=count / n_valid, interval=[lo, hi])
        a["interval_method"] = "Wilson score, 95 %"
        if a["kind"] == "periodic" and method == "sections":
            t = trans[mine]
            a.update(transient_median=float(np.median(t)), transient_max=int(t.max()))
    timings["attractors_s"] = time.perf_counter() - clock
    return BasinMap(
        timings=timings,
        starts=pts,
        labels=labels,
        transients=np.where(labels >= 0, trans, -1),
        periods=period,
        attractors=attractors,
        grid=grid,
        settings=settings,
        steps=steps,
    )


def _rerun(system: Any, pts: np.ndarray, settings: dict, i: int) -> Any:
    """Start ``i``'s section run again, keeping its final state."""
    q0, v0, w0 = pts[i]
    state = start_state(system, q0, v0, None if math.isnan(w0) else w0)
    return section_run(system, state, keep_state=True, **settings)


def _label_sections(
    system: Any,
    results: list[dict], valid: np.ndarray, rerun: Callable[[int], Any], settings: dict,
    classify: dict,
) -> tuple[np.ndarray, list[dict], np.ndarray, np.ndarray]:  # fmt: skip
    """Labels of the ``sections`` method (module docstring): one refinement per periodic
    orbit, one Lyapunov run per aperiodic attractor candidate."""
    match_tolerance = classify["match_tolerance"]
    status = np.concatenate([np.asarray(r["status"]) for r in results])
    period = np.concatenate([np.asarray(r["period"]) for r in results])
    trans = np.concatenate([np.asarray(r["transient"]) for r in results])
    # a chunk without a periodic start has an empty (0, 3) block: leave those out
    blocks = [np.asarray(r["cycles"]) for r in results if len(r["cycles"])]
    cycles = np.concatenate(blocks) if blocks else np.empty((0, 3))
    tails = np.concatenate([np.asarray(r["tails"]).reshape(-1, 2) for r in results])
    status[~valid] = -2
    labels = np.full(status.size, NOT_A_STATE, dtype=np.int32)
    attractors: list[dict] = []
    # -- periodic: one refinement per orbit ------------------------------------------------------
    per_idx = np.flatnonzero(status == PERIODIC)
    offsets = np.concatenate([[0], np.cumsum(period[status == PERIODIC])])
    d = cycles.shape[1] if cycles.size else 3
    undecided: list[int] = []
    for k in np.unique(period[per_idx]):
        sel = np.flatnonzero(period[per_idx] == k)
        cyc = np.stack([cycles[offsets[j] : offsets[j] + k] for j in sel]).reshape(-1, k, d)
        members = per_idx[sel]
        open_ = np.ones(sel.size, dtype=bool)
        while open_.any():
            first = int(np.flatnonzero(open_)[0])
            orbit = periodic_attractor(system, rerun(int(members[first])).final, int(k))
            hit = open_ & match_cycles(cyc, orbit["points"], match_tolerance)
            if not hit[first]:  # the refined orbit is not this start's cycle: no label for it
                undecided.append(int(members[first]))
                open_[first] = False
                continue
            label = _same_orbit(attractors, int(k), orbit, match_tolerance)
            if label is None:
                label = len(attractors)
                attractors.append({"label": label, "kind": "periodic", "period": int(k), **orbit})
            labels[members[hit]] = label
            open_ &= ~hit
    # -- aperiodic: one Lyapunov run per attractor candidate --------------------------------------
    ap_idx = np.flatnonzero(status == APERIODIC)
    tail = settings["tail"]
    ap_tails = tails.reshape(ap_idx.size, -1, 2) if ap_idx.size else np.empty((0, tail, 2))
    open_ = np.ones(ap_idx.size, dtype=bool)
    tried = 0
    while open_.any() and tried < classify["max_aperiodic"]:
        tried += 1
        first = int(np.flatnonzero(open_)[0])
        state = rerun(int(ap_idx[first])).final
        # the cloud first (no tangent flow): a continuation that settles needs no λ_max
        cloud, est = _chaos(system, state, settings, classify)
        hit = open_ & _in_cloud(cloud, ap_tails)
        if not (hit[first] and est is not None):
            # a chaotic transient (its continuation settles), or no significant λ_max > 0
            undecided.append(int(ap_idx[first]))
            open_[first] = False
            continue
        label = len(attractors)
        attractors.append({"label": label, "kind": "chaotic", **est})
        labels[ap_idx[hit]] = label
        open_ &= ~hit
    undecided.extend(int(i) for i in ap_idx[open_])
    _append_rest(labels, attractors, np.flatnonzero(status == DIVERGENT), undecided)
    return labels, attractors, period, trans


def _same_orbit(attractors: list[dict], k: int, orbit: dict, tol: float) -> int | None:
    """The label of a known periodic attractor that is ``orbit`` (period k, cyclic shifts)."""
    for a in attractors:
        if a["kind"] == "periodic" and a["period"] == k:
            if match_cycles(a["points"][None], orbit["points"], tol)[0]:
                return int(a["label"])
    return None


def _chaos(system: Any, state: Any, settings: dict, classify: dict) -> tuple[tuple, dict | None]:
    """The section cloud of a continuation from ``state`` and, when it has not settled and
    λ_max exceeds twice its error, the chaotic attractor's λ_max ± error and D_KY."""
    cloud, settled = _cloud(
        system,
        state,
        classify["lyapunov_periods"],
        classify["cloud_bins"],
        settings["periods"],
        settings["max_period"],
    )
    if settled:
        return cloud, None
    est = lyapunov_estimate(system, state, classify["lyapunov_periods"])
    del est["final"]
    return cloud, est if est["max_exponent"] > 2.0 * est["max_exponent_error"] else None


def _append_rest(
    labels: np.ndarray, attractors: list[dict], divergent: Sequence[int], undecided: Sequence[int]
) -> None:
    """The ``divergent`` and ``undecided`` pseudo-attractors, after the real ones."""
    for kind, idx in (("divergent", divergent), ("undecided", undecided)):
        if len(idx):
            labels[np.asarray(idx, dtype=np.int64)] = len(attractors)
            attractors.append({"label": len(attractors), "kind": kind})


def _label_recurrences(
    system: Any, pts: np.ndarray, results: list[dict], chunk: int, settings: dict,
    classify: dict,
) -> tuple[np.ndarray, list[dict], np.ndarray, dict]:  # fmt: skip
    """Labels of the ``recurrences`` method: the chunks' attractors joined where they share a
    cell (:func:`~analysis.dynamics.recurrence.merge_attractors`), each joined attractor
    classified once from the state its finder reached (a periodic orbit refined, or a chaotic
    attractor's λ_max and D_KY, as for ``sections``; else undecided)."""
    group_of, members = merge_attractors(results)
    outcome = np.concatenate([np.asarray(r["outcome"]) for r in results])
    steps = np.concatenate([np.asarray(r["steps"]) for r in results])
    stop = np.concatenate([np.asarray(r["stop"]) for r in results])
    group = np.full(outcome.size, -1, dtype=np.int64)
    for k, r in enumerate(results):
        o = np.asarray(r["outcome"])
        sel = o >= 0
        group[k * chunk + np.flatnonzero(sel)] = group_of[k][o[sel]]
    labels = np.full(outcome.size, NOT_A_STATE, dtype=np.int32)
    attractors: list[dict] = []
    clouds: list[tuple[int, tuple]] = []
    undecided = list(np.flatnonzero((outcome < 0) & (outcome != DIVERGED) & (outcome != NO_STATE)))
    for g, mem in enumerate(members):
        mine = np.flatnonzero(group == g)
        if not mine.size:
            continue
        k, local = next(((k, a) for k, a in mem if results[k]["found_by"][a] >= 0), mem[0])
        start = k * chunk + int(results[k]["found_by"][local])
        state = representative_state(system, pts[start], int(results[k]["found_steps"][local]))
        label = _classify_state(system, state, attractors, clouds, settings, classify)
        if label is None:
            undecided.extend(int(i) for i in mine)
        else:
            labels[mine] = label
    _append_rest(labels, attractors, np.flatnonzero(outcome == DIVERGED), undecided)
    states = outcome != NO_STATE
    reasons = ("new attractor", "attractor cells", "basin cells", "other")
    extra = {
        "merges": int(sum(int(r["merges"]) for r in results)),
        "stops": {name: int(np.count_nonzero(stop[states] == c)) for c, name in enumerate(reasons)},
        "steps_mean": float(steps[states].mean()) if states.any() else 0.0,
    }
    return labels, attractors, steps, extra


def _classify_state(
    system: Any, state: Any, attractors: list[dict], clouds: list[tuple[int, tuple]],
    settings: dict, classify: dict,
) -> int | None:  # fmt: skip
    """The label of the attractor through ``state`` (appended to ``attractors`` if new), or
    ``None`` (undecided): its section run, then a refined orbit or a chaos test."""
    try:
        run = section_run(system, state, keep_state=True, **{**settings, "transient": 0})
    except DivergenceError:
        return None
    if run.status == PERIODIC:
        k = run.period
        orbit = periodic_attractor(system, run.final, k)
        if not match_cycles(run.cycle[None], orbit["points"], classify["match_tolerance"])[0]:
            return None
        label = _same_orbit(attractors, k, orbit, classify["match_tolerance"])
        if label is None:
            label = len(attractors)
            attractors.append({"label": label, "kind": "periodic", "period": int(k), **orbit})
        return label
    if run.status != APERIODIC:
        return None
    tail = run.tail[None, :, :2]
    for label, cloud in clouds:
        if _in_cloud(cloud, tail)[0]:
            return label
    cloud, est = _chaos(system, run.final, settings, classify)
    if est is None or not _in_cloud(cloud, tail)[0]:
        return None
    label = len(attractors)
    attractors.append({"label": label, "kind": "chaotic", **est})
    clouds.append((label, cloud))
    return label


def _valid_starts(system: Any, pts: np.ndarray, grid: BasinGrid | None) -> np.ndarray:
    """Which starts are states; a list with a start that is none raises (a grid's band edges
    are expected and labelled)."""
    has_w = ~np.isnan(pts[:, 2])
    if not has_w.any():
        return np.ones(pts.shape[0], dtype=bool)
    spec = getattr(system.operator, "compiled_play", lambda: None)()
    if spec is None:
        raise ValueError(f"w0 needs a play-type operator, not {system.operator!r}")
    ok = ~has_w | (np.abs(pts[:, 0] - pts[:, 2]) <= 0.5 * spec.width * (1 + 1e-12))
    if grid is None and not ok.all():
        i = int(np.flatnonzero(~ok)[0])
        raise ValueError(
            f"starts[{i}]: w0 must satisfy |q0 - w0| <= p/2 = {0.5 * spec.width:g}, got "
            f"q0 = {pts[i, 0]:g}, w0 = {pts[i, 2]:g}"
        )
    return ok


def _cloud(
    system: Any, state: Any, length: int, bins: int, periods: int, max_period: int
) -> tuple[tuple, bool]:
    """Occupied (q, v) cells of the section over ``length`` periods from ``state``, dilated by
    one cell, and whether the section has settled on a cycle at its end (relative tolerance
    1e-7 of its extent, :func:`~analysis.dynamics.bifurcation.section_period` on the last
    ``periods`` points)."""
    sec = system.poincare_section(length, 0, state.q, state.v, state.operator_state)
    q, v = sec.q, sec.v
    settled = section_period(q[-periods:], v[-periods:]) > 0
    lo = np.array([q.min(), v.min()])
    hi = np.array([q.max(), v.max()])
    step = np.maximum((hi - lo) / (bins - 3), 1e-12)  # occupied cells 1..bins-2
    lo = lo - step
    cells = np.zeros((bins, bins), dtype=bool)
    iq = np.clip(((q - lo[0]) / step[0]).astype(int), 0, bins - 1)
    iv = np.clip(((v - lo[1]) / step[1]).astype(int), 0, bins - 1)
    cells[iq, iv] = True
    grown = cells.copy()
    for dq in (-1, 0, 1):
        for dv in (-1, 0, 1):
            grown |= np.roll(np.roll(cells, dq, axis=0), dv, axis=1)
    return (lo, step, grown), bool(settled)


def _in_cloud(cloud: tuple, tails: np.ndarray) -> np.ndarray:
    """Whether at least :data:`CLOUD_SHARE` of each start's tail points lie in the cloud."""
    lo, step, cells = cloud
    bins = cells.shape[0]
    iq = np.floor((tails[..., 0] - lo[0]) / step[0]).astype(np.int64)
    iv = np.floor((tails[..., 1] - lo[1]) / step[1]).astype(np.int64)
    inside = (iq >= 0) & (iq < bins) & (iv >= 0) & (iv < bins)
    hit = np.zeros(tails.shape[:2], dtype=bool)
    hit[inside] = cells[iq[inside], iv[inside]]
    return hit.mean(axis=1) >= CLOUD_SHARE if tails.shape[1] else np.zeros(len(tails), bool)
