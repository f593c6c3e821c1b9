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
                       first one for lyapunov_periods (lyapunov_estimate: λ_max ± error, D_KY)
                       and record the continuation's section cloud (q, v) on a cloud_bins²
                       grid; if λ_max exceeds twice its error and the continuation has not
                       settled on a cycle, it is a chaotic attractor, and every start whose
                       tail points lie in the cloud's cells or their neighbours (90 % of them
                       at least) gets its label; else that start is undecided (a chaotic
                       transient, a slow approach, a quasi-periodic motion or a period above
                       max_period: a longer max_periods may resolve it)
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
from dataclasses import dataclass, field
from pathlib import Path
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
from analysis.dynamics.bifurcation import section_period
from analysis.dynamics.statistics import wilson_interval
from analysis.experiments.execution import run_tasks
from analysis.experiments.parameters import V0
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
#: most starts of one basin map
MAX_STARTS = 10_000_000
#: label of a grid point that is no state (w0 outside the play's band)
NOT_A_STATE = -1
#: share of a start's tail points that must lie in an aperiodic attractor's cloud
CLOUD_SHARE = 0.9


@dataclass(frozen=True)
class BasinGrid:
    """An ``size × size`` grid of starts: q0 along x, and v0 (``axis="v0"``) or the play's
    wagon position w0 (``axis="w0"``, with the fixed velocity ``v0``) along y.

    :meth:`starts` lists them row by row (y outer, q0 inner): ``labels.reshape(size, size)``
    is the map with y along the rows.
    """

    q0_range: tuple[float, float]
    y_range: tuple[float, float]
    size: int
    axis: str = "v0"
    v0: float = V0

    def __post_init__(self) -> None:
        positive_integer(self.size, "size", minimum=2)
        bounded_work(self.size * self.size, "size", MAX_STARTS, "starts")
        if self.axis not in ("v0", "w0"):
            raise ValueError(f"axis must be 'v0' or 'w0', got {self.axis!r}")
        for name, rng in (("q0_range", self.q0_range), (f"{self.axis}_range", self.y_range)):
            lo, hi = (finite_scalar(x, name, MAX_MAGNITUDE) for x in rng)
            if not lo < hi:
                raise ValueError(f"{name} must be (low, high) with low < high, got {rng}")
        finite_scalar(self.v0, "v0", MAX_MAGNITUDE)

    @property
    def q0_values(self) -> np.ndarray:
        return np.linspace(*self.q0_range, self.size)

    @property
    def y_values(self) -> np.ndarray:
        return np.linspace(*self.y_range, self.size)

    def starts(self) -> np.ndarray:
        """Rows ``(q0, v0, w0)``; ``w0`` is nan (default memory) on a (q0, v0) grid."""
        q, y = np.meshgrid(self.q0_values, self.y_values)
        if self.axis == "v0":
            return np.column_stack([q.ravel(), y.ravel(), np.full(q.size, np.nan)])
        return np.column_stack([q.ravel(), np.full(q.size, float(self.v0)), y.ravel()])

    def to_dict(self) -> dict:
        return {
            "q0_range": list(self.q0_range),
            f"{self.axis}_range": list(self.y_range),
            "size": self.size,
            "axis": self.axis,
            **({"v0": self.v0} if self.axis == "w0" else {}),
        }


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


@dataclass(frozen=True)
class BasinMap:
    """Per-start labels and the attractors they reach.

    ``labels[i]`` is the index into :attr:`attractors` (−1: no state); ``transients[i]`` the
    forcing periods before start i stayed within the tolerance of its cycle (−1 unless
    periodic). Each attractor is a dict with ``label``, ``kind`` (``periodic``, ``chaotic``,
    ``aperiodic``, ``divergent``, ``undecided``), ``count``, ``fraction``, ``interval`` (95 %
    Wilson score interval) and what it is (period, points, multipliers; or λ_max with its
    error and D_KY); ``transient_median``/``transient_max`` for periodic ones.
    """

    starts: np.ndarray
    labels: np.ndarray
    transients: np.ndarray
    periods: np.ndarray
    attractors: list[dict]
    grid: BasinGrid | None = None
    settings: dict = field(default_factory=dict)
    #: wall times: ``sections_s`` (the tasks: every start's section run) and ``attractors_s``
    #: (labelling: the refinements and Lyapunov runs once per attractor)
    timings: dict = field(default_factory=dict)

    def label_grid(self) -> np.ndarray:
        """``labels`` as the ``size × size`` map (y along rows); grids only."""
        if self.grid is None:
            raise ValueError("label_grid needs a BasinGrid (the starts were a list)")
        return self.labels.reshape(self.grid.size, self.grid.size)

    def to_dict(self) -> dict:
        """JSON-ready summary (attractors with complex multipliers as [re, im] pairs)."""
        out = []
        for a in self.attractors:
            rec = {}
            for k, v in a.items():
                if k == "multipliers":
                    rec[k] = [[float(m.real), float(m.imag)] for m in np.asarray(v)]
                elif isinstance(v, np.ndarray):
                    rec[k] = v.tolist()
                else:
                    rec[k] = v
            out.append(rec)
        return {
            "starts": int(self.labels.size),
            "valid_starts": int(np.count_nonzero(self.labels >= 0)),
            **({"grid": self.grid.to_dict()} if self.grid is not None else {}),
            **self.settings,
            "attractors": out,
        }

    def save(self, path: str | Path) -> Path:
        """Per-start arrays to an ``.npz``: starts, labels, transients, periods (+ the grid)."""
        path = Path(path)
        extra = {}
        if self.grid is not None:
            extra = {"q0_values": self.grid.q0_values, "y_values": self.grid.y_values}
            extra["label_grid"] = self.label_grid()
        np.savez_compressed(
            path,
            starts=self.starts,
            labels=self.labels,
            transients=self.transients,
            periods=self.periods,
            **extra,
        )
        return path

    def plot(self, path: str | Path, title: str | None = None) -> Path:
        """The basin map coloured by attractor (grids; a list: its starts as points) and, for a
        grid with periodic starts, a second panel with each start's transient length."""
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from matplotlib.colors import BoundaryNorm, ListedColormap, LogNorm
        from matplotlib.patches import Patch

        n = len(self.attractors)
        base = plt.get_cmap("tab10" if n <= 10 else "tab20")
        colours = ["white"] + [base(i % base.N) for i in range(n)]
        cmap = ListedColormap(colours)
        norm = BoundaryNorm(np.arange(-1.5, n + 0.5), cmap.N)
        with_transients = self.grid is not None and np.any(self.transients >= 0)
        fig, axes = plt.subplots(
            1, 2 if with_transients else 1, figsize=(12 if with_transients else 6.5, 5)
        )
        axes = np.atleast_1d(axes)
        ax = axes[0]
        if self.grid is not None:
            g = self.grid
            extent = (*g.q0_range, *g.y_range)
            ax.imshow(
                self.label_grid(),
                origin="lower",
                extent=extent,
                aspect="auto",
                cmap=cmap,
                norm=norm,
                interpolation="nearest",
            )
            for a in axes:
                a.set_ylabel("$w_0$" if g.axis == "w0" else "$v_0$")
                a.set_xlabel("$q_0$")
        else:
            ax.scatter(self.starts[:, 0], self.starts[:, 1], c=self.labels, cmap=cmap, norm=norm)
            ax.set_ylabel("$v_0$")
            ax.set_xlabel("$q_0$")
        handles = [Patch(color=colours[a["label"] + 1], label=_legend(a)) for a in self.attractors]
        ax.legend(handles=handles, fontsize=7, loc="upper right", framealpha=0.8)
        if with_transients:
            t = np.ma.masked_less(self.transients.reshape(g.size, g.size).astype(float), 0)
            im = axes[1].imshow(
                t + 1.0,
                origin="lower",
                extent=extent,
                aspect="auto",
                cmap="viridis",
                norm=LogNorm(vmin=1.0, vmax=max(2.0, float(t.max()) + 1.0)),
                interpolation="nearest",
            )
            fig.colorbar(im, ax=axes[1], label="transient + 1 (forcing periods)")
            axes[1].set_title("periods until the section repeats within the tolerance", fontsize=8)
        if title:
            ax.set_title(title, fontsize=8)
        fig.tight_layout()
        fig.savefig(path, dpi=150)
        plt.close(fig)
        return Path(path)


def _legend(a: dict) -> str:
    frac = f"{100 * a['fraction']:.1f} %"
    if a["kind"] == "periodic":
        return f"period {a['period']} ({frac})"
    if a["kind"] in ("chaotic", "aperiodic"):
        return f"{a['kind']}, λ = {a['max_exponent']:.3f} ({frac})"
    return f"{a['kind']} ({frac})"


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
