"""Basins of attraction: where each start of a grid (or any list) of initial conditions ends.

Plain reading of :func:`basins`::

    for every chunk of starts (one task of the ensemble machinery: workers, Dask, the
    resumable store, progress):
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
Fractions come with the 95 % Wilson score interval
(:func:`~analysis.dynamics.statistics.wilson_interval`). A grid over (q0, w0) (play-type
memory) has starts outside the play's band ``|q0 − w0| <= p/2``: they are no states, labelled
−1 and left out of the fractions.
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Sequence
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
from analysis.dynamics.statistics import wilson_interval
from analysis.experiments.execution import run_tasks
from hysteresis._validation import (
    MAX_MAGNITUDE,
    bounded_work,
    finite_array,
    finite_scalar,
    nonnegative_integer,
    positive_integer,
)

__all__ = ["EXPERIMENT", "BasinGrid", "BasinMap", "basin_chunk", "basins", "MAX_STARTS"]

EXPERIMENT = "basins"
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


def basins(
    system: Any,
    starts: BasinGrid | Sequence[Sequence[float]] | np.ndarray,
    *,
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
    store: Any = None,
    system_key: str | None = None,
    workers: int | None = 1,
    scheduler: str | None = None,
    progress: bool = False,
    allow_version_mismatch: bool = False,
) -> BasinMap:
    """Classify where every start ends (module docstring) and collect the basins.

    Parameters
    ----------
    system:
        A :class:`~oscillators.system.ForcedOscillator` (shipped to the workers as is).
    starts:
        A :class:`BasinGrid`, or rows ``(q0, v0)`` (default memory) or ``(q0, v0, w0)``
        (play-type memory; nan: default).
    transient, periods, max_periods:
        Forcing periods integrated before the measured window, and in it (``periods >= 2``);
        a start without a period goes on ``periods`` at a time up to ``max_periods`` in all
        (default ``transient + periods``: no extension), so long transients get resolved while
        a start that settles early stops early.
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
        Starts per task.
    store, workers, scheduler, progress, allow_version_mismatch:
        As :func:`~analysis.experiments.execution.run_tasks` (experiment ``"basins"``). With a
        store, ``system_key`` (a string naming the operator and its parameters, C, ζ, Ω: it
        keys the stored tasks) is required.
    """
    pts, grid = _as_starts(starts)
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
    if store is not None and not isinstance(system_key, str):
        raise ValueError(
            "system_key must name the system (operator and parameters, C, zeta, Omega) when a "
            "store is given: it keys the stored tasks"
        )
    max_periods = transient + periods if max_periods is None else max_periods
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
    tasks = [
        dict(starts=pts[i : i + chunk].tolist(), system_key=system_key or "", **settings)
        for i in range(0, pts.shape[0], chunk)
    ]
    clock = time.perf_counter()
    results = run_tasks(
        EXPERIMENT,
        tasks,
        functools.partial(basin_chunk, system=system),
        store=store,
        workers=workers,
        scheduler=scheduler,
        progress=progress,
        allow_version_mismatch=allow_version_mismatch,
    )
    timings = {"sections_s": time.perf_counter() - clock}
    clock = time.perf_counter()
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
    settings.update(match_tolerance=match_tolerance, lyapunov_periods=lyapunov_periods)

    def rerun(i: int) -> Any:
        q0, v0, w0 = pts[i]
        state = start_state(system, q0, v0, None if math.isnan(w0) else w0)
        return section_run(
            system,
            state,
            transient,
            periods,
            max_periods=max_periods,
            tolerance=tolerance,
            max_period=max_period,
            tail=tail,
            keep_state=True,
        )

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
            same = [
                a["label"]
                for a in attractors
                if a["kind"] == "periodic"
                and a["period"] == k
                and match_cycles(a["points"][None], orbit["points"], match_tolerance)[0]
            ]
            label = same[0] if same else len(attractors)
            if not same:
                attractors.append({"label": label, "kind": "periodic", "period": int(k), **orbit})
            labels[members[hit]] = label
            open_ &= ~hit
    # -- aperiodic: one Lyapunov run per attractor candidate --------------------------------------
    ap_idx = np.flatnonzero(status == APERIODIC)
    ap_tails = tails.reshape(ap_idx.size, -1, 2) if ap_idx.size else np.empty((0, tail, 2))
    open_ = np.ones(ap_idx.size, dtype=bool)
    tried = 0
    while open_.any() and tried < max_aperiodic:
        tried += 1
        first = int(np.flatnonzero(open_)[0])
        state = rerun(int(ap_idx[first])).final
        # the cloud first (no tangent flow): a continuation that settles needs no λ_max
        cloud, settled = _cloud(system, state, lyapunov_periods, cloud_bins, periods, max_period)
        hit = open_ & _in_cloud(cloud, ap_tails)
        chaotic = False
        if hit[first] and not settled:
            est = lyapunov_estimate(system, state, lyapunov_periods)
            del est["final"]
            chaotic = est["max_exponent"] > 2.0 * est["max_exponent_error"]
        if not chaotic:
            # a chaotic transient (its continuation settles), or no significant λ_max > 0
            undecided.append(int(ap_idx[first]))
            open_[first] = False
            continue
        label = len(attractors)
        attractors.append({"label": label, "kind": "chaotic", **est})
        labels[ap_idx[hit]] = label
        open_ &= ~hit
    undecided.extend(int(i) for i in ap_idx[open_])
    for kind, idx in (("divergent", np.flatnonzero(status == DIVERGENT)), ("undecided", undecided)):
        if len(idx):
            labels[np.asarray(idx)] = len(attractors)
            attractors.append({"label": len(attractors), "kind": kind})
    n_valid = int(np.count_nonzero(labels >= 0))
    for a in attractors:
        mine = labels == a["label"]
        count = int(np.count_nonzero(mine))
        lo, hi = wilson_interval(count, n_valid)
        a.update(count=count, fraction=count / n_valid, interval=[lo, hi])
        a["interval_method"] = "Wilson score, 95 %"
        if a["kind"] == "periodic":
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
    )


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
