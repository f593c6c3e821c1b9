"""The lattice study: the random-field Ising model coupled to the oscillator; its Preisach model.

The paper's ensemble of independent spin dimers is a Preisach model; the zero-temperature
random-field Ising model (:class:`hysteresis.RandomFieldIsing`, ``J = 1``, fields
``N(0, R²)`` on an ``L³`` periodic lattice) is not: its spins interact, flips trigger
avalanches and below ``R_c ≈ 2.16`` one avalanche spans the lattice. One task is one
realization ``(R, L, seed)`` (the same seed at every R: the fields are one standard-normal draw
scaled by R, common random numbers along R) at every coupling C:

* **coupled lattice**: the Lyapunov spectrum in ``(q, v)``, ``D_KY``, the section's ``D_BC``
  (0 for a periodic section) and ``M_T``, in one pass
  (:func:`~analysis.experiments.one_pass.one_pass_measurements`), then a trajectory of
  ``barkhausen_periods`` forcing periods whose switches are the avalanches of the coupled
  motion (size ``|ΔM|·N/2``; their sum is the number of spin flips);
* **plain field sweeps** of the same lattice: the major loop's rising branch (every spin flips
  once: the sizes sum to N; the largest avalanche tells whether one spans) and a periodic sweep
  between the extremes of the coupled motion's input, as many cycles as forcing periods;
* **the lattice's own Preisach model**: first-order reversal curves of the lattice on a grid
  of ``identification_nodes`` nodes over ``[−Q, Q]`` (Q the largest ``|q|`` of the coupled runs
  plus ``margin``) and one node at each saturation, identified
  (:func:`~analysis.identification.density.identify_from_curves`) and projected onto a valid
  model (:func:`~hysteresis.preisach.projection.project_identification`, what
  :meth:`PreisachModel.from_identification` does, with its residual and scale), coupled
  to the oscillator from the same initial condition (the same measurements), and both
  operators driven by the lattice trajectory's input: the operator-level error of the model,
  on the raw input (grid staircase + non-Preisach error) and on the input rounded to the grid
  nodes (where a Preisach lattice would be reproduced exactly: the non-Preisach error alone);
* **the lattice's congruency violation**
  (:func:`~analysis.identification.congruency.congruency_scan`): minor loops between the
  same extrema reached from different histories, a grid-independent measure of how far the
  lattice is from any Preisach model (0 for one).

Above ~70 nodes the projection is the sparse second-difference solve of
:mod:`hysteresis.preisach.projection` (``--identification-nodes 150``: 1–14 s a realization).

:func:`run_study` runs (or resumes: every task is stored as it finishes,
:func:`~analysis.experiments.execution.run_tasks`) a :class:`LatticeSize` and
:func:`summarize` reduces the tasks per (R, L, C) to the JSON of ``hyst lattice``.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np

from analysis.dynamics.dimensions import kaplan_yorke_dimension
from analysis.experiments.ensemble import section_dimension
from analysis.experiments.execution import run_tasks, spawn_seeds
from analysis.experiments.one_pass import one_pass_measurements
from analysis.experiments.parameters import DAMPING_RATIO, DEFAULT_Q0, FREQUENCY, V0
from analysis.experiments.store import ResultStore
from analysis.identification.congruency import congruency_scan
from analysis.identification.curves import measure_reversal_curves
from analysis.identification.density import identify_from_curves
from hysteresis import RandomFieldIsing
from hysteresis._validation import nonnegative_integer, positive_integer
from hysteresis.preisach.projection import project_identification
from oscillators import ForcedOscillator

__all__ = [
    "EXPERIMENT",
    "DISORDERS",
    "LatticeSize",
    "SIZES",
    "lattice_seeds",
    "avalanche_statistics",
    "identify_lattice",
    "lattice_task",
    "lattice_tasks",
    "run_study",
    "summarize",
]

EXPERIMENT = "lattice-study"
#: the issue's disorders (R_c ≈ 2.16 for Gaussian fields on the cubic lattice, J = 1)
DISORDERS = (1.8, 2.16, 2.6, 3.5)
#: box counting of the section (as ``hyst ensemble``'s defaults)
BOX_MAX_FILL, BOX_MIN_BOXES = 0.1, 8.0
#: samples per forcing period of the input that drives both operators (operator-level error)
COMPARE_SAMPLES = 64
#: smallest avalanche of the size-exponent fit
S_MIN = 2
#: congruency scan (:func:`~analysis.identification.congruency.congruency_scan`): loops between
#: every pair of this many nodes over ``[−a, a]``, ``a`` the larger of ``|u|`` where the major
#: loop's rising branch has flipped the fraction CONGRUENCY_QUANTILE and 1 − it of the spins
#: (the hysteretic region; capped at the coupled motion's largest ``|q|``), from this many
#: histories, sampled this many times a branch
CONGRUENCY_NODES, CONGRUENCY_HISTORIES, CONGRUENCY_SAMPLES = 9, 8, 16
CONGRUENCY_QUANTILE = 0.02


@dataclass(frozen=True)
class LatticeSize:
    """Sizes of one run (times in forcing periods; ``sides`` the lattice's L, ``L³`` spins)."""

    disorders: tuple[float, ...]
    sides: tuple[int, ...]
    couplings: tuple[float, ...]
    realizations: int
    periods: int
    transient_periods: int
    barkhausen_periods: int
    identification_nodes: int
    margin: float


#: ``small``: the default of ``hyst lattice`` (about a minute on 2 cores); ``moderate``: the
#: docs page's run; ``full``: the issue's grid
SIZES = {
    "small": LatticeSize(DISORDERS, (10, 16), (2.9, 4.0), 2, 160, 40, 20, 40, 2.0),
    "moderate": LatticeSize(DISORDERS, (10, 20, 30), (2.9, 4.0), 6, 600, 100, 40, 60, 2.0),
    "full": LatticeSize(
        DISORDERS, (10, 20, 30, 50, 70, 100), (2.9, 4.0), 20, 2000, 200, 100, 68, 2.0
    ),  # fmt: skip
}


def lattice_seeds(base_seed: int, side: int, realizations: int) -> list[int]:
    """Disorder seeds of the realizations at side L (independent across L, shared across R and
    C)."""
    base_seed = nonnegative_integer(base_seed, "base_seed")
    side = positive_integer(side, "side")
    base = int(np.random.SeedSequence([base_seed, side, 3]).generate_state(1, np.uint64)[0])
    return spawn_seeds(base >> 1, positive_integer(realizations, "realizations"))


def avalanche_statistics(sizes: Any, n_spins: int) -> dict:
    """Count, total, mean and largest size (also as a fraction of N) of avalanches, their
    histogram in powers-of-two bins, and the maximum-likelihood exponent ``τ`` of
    ``P(S) ~ S^−τ`` over ``S >= S_MIN`` (the discrete approximation of Clauset, Shalizi and
    Newman 2009, ``τ = 1 + n / Σ ln(S/(S_MIN − ½))``, standard error ``(τ − 1)/√n``): an
    effective exponent, since cutoffs bend the distribution away from R_c."""
    s = np.asarray(sizes, dtype=np.int64)
    edges = 2 ** np.arange(0, max(1, int(math.ceil(math.log2(max(n_spins, 2)))) + 2))
    hist = np.histogram(s, bins=edges)[0] if s.size else np.zeros(edges.size - 1, int)
    tail = s[s >= S_MIN].astype(float)
    tau = tau_err = float("nan")
    if tail.size >= 2:
        tau = 1.0 + tail.size / float(np.sum(np.log(tail / (S_MIN - 0.5))))
        tau_err = (tau - 1.0) / math.sqrt(tail.size)
    return {
        "count": int(s.size),
        "total": int(s.sum()),
        "mean": float(s.mean()) if s.size else float("nan"),
        "largest": int(s.max()) if s.size else 0,
        "largest_fraction": float(s.max() / n_spins) if s.size else 0.0,
        "bin_edges": edges.tolist(),
        "histogram": hist.tolist(),
        "tau": tau,
        "tau_err": tau_err,
    }


def identify_lattice(
    op: Any, half_range: float, nodes: int, saturation: float | None = None
) -> tuple[Any, dict]:
    """The lattice's Preisach model from its first-order reversal curves on ``nodes`` evenly
    spaced nodes over ``[−half_range, half_range]`` plus one node beyond each saturation (every
    input of ``[−Q, Q]`` sees the relays outside as one lump each), identified on the native
    grid and projected onto non-negative cell masses (:func:`project_identification`, i.e.
    :meth:`PreisachModel.from_identification`). Returns the model and its diagnostics: the
    grid, the Everett residual (rms and the bound ``√n·rms`` on any node), the scale ``K`` (1
    when the lattice saturates inside the grid) and the count of negative exact cell masses
    (zero for a Preisach operator). ``saturation``: the outer nodes' ``|u|`` (default: the
    lattice's, beyond every spin's threshold; give it for any other operator)."""
    if saturation is None:
        sat = float(np.max(np.abs(op.fields))) + 2 * op.max_degree * op.spin_coupling + 1.0
        sat = max(sat, half_range + 1.0)
    else:
        sat = float(saturation)
        if not (math.isfinite(sat) and sat > half_range):
            raise ValueError(f"saturation must be finite and > half_range, got {saturation!r}")
    grid = np.concatenate([[-sat], np.linspace(-half_range, half_range, nodes), [sat]])
    curves = measure_reversal_curves(op, grid, convention="mayergoyz")
    ident = identify_from_curves(curves, output_range=(-1.0, 1.0), extend=True)
    proj = project_identification(ident)
    masses = np.asarray(ident.cell_mass, dtype=float)
    finite = masses[np.isfinite(masses)]
    info = {
        "grid": grid,
        "scale": float(proj.scale),
        "residual_rms": float(proj.residual_rms),
        "residual_bound": float(proj.residual_rms * math.sqrt(proj.n_nodes)),
        "n_nodes": int(proj.n_nodes),
        "relays": int(proj.alpha.size),
        "negative_mass": float(-finite[finite < 0].sum()),
        "negative_cells": int(np.count_nonzero(finite < -1e-12)),
    }
    return proj.model(), info


def _coupled(op: Any, c: float, t_end: float, transient: float) -> tuple[dict, Any, Any]:
    system = ForcedOscillator(op, c, damping_ratio=DAMPING_RATIO, frequency=FREQUENCY)
    ly, q, v, m_t, _ = one_pass_measurements(system, t_end, transient, DEFAULT_Q0, V0)
    lam = np.asarray(ly.exponents, dtype=float)
    d_bc, d_bc_err, period = section_dimension(q, v, BOX_MAX_FILL, BOX_MIN_BOXES)
    out = {
        "exponents": lam,
        "lambda_max": float(lam[0]),
        "kaplan_yorke": float(kaplan_yorke_dimension(lam)),
        "box_counting": d_bc,
        "box_counting_stderr": d_bc_err,
        "section_period": int(period),
        "regular": bool(lam[0] < 0.0),
        "magnetization": float(m_t),
        "flips": int(ly.n_switches),
    }
    return out, system, ly.final


def _quantize(u: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """Each input replaced by the nearest grid node."""
    i = np.clip(np.searchsorted(grid, u), 1, grid.size - 1)
    left, right = grid[i - 1], grid[i]
    return np.where(u - left <= right - u, left, right)


def _operator_error(op: Any, model: Any, u: np.ndarray) -> dict:
    """rms and max of ``M_lattice − M_model`` along the input ``u`` (both from rising out of
    negative saturation to ``u[0]``)."""
    m_l, _ = op.apply(u, op.initial_state(float(u[0])))
    m_p, _ = model.apply(u, model.initial_state(float(u[0])))
    d = np.asarray(m_l) - np.asarray(m_p)
    return {"rms": float(np.sqrt(np.mean(d**2))), "max": float(np.max(np.abs(d)))}


def lattice_task(
    disorder: float,
    side: int,
    seed: int,
    couplings: Sequence[float],
    periods: int,
    transient_periods: int,
    barkhausen_periods: int,
    identification_nodes: int,
    margin: float,
) -> dict:
    """One realization at every coupling (module docstring). Top-level (process pools)."""
    start = time.perf_counter()
    op = RandomFieldIsing.lattice((side,) * 3, disorder, seed=seed)
    n = op.n_spins
    period = 2 * math.pi / FREQUENCY
    t_end, transient = periods * period, transient_periods * period
    sat = float(np.max(np.abs(op.fields))) + 6.0 + 1.0
    triggers, major, _ = op.avalanches(np.array([-sat, sat]))
    flipped = np.cumsum(major) / n
    switching = max(
        abs(float(triggers[np.searchsorted(flipped, CONGRUENCY_QUANTILE)])),
        abs(float(triggers[np.searchsorted(flipped, 1.0 - CONGRUENCY_QUANTILE)])),
    )
    out: dict[str, Any] = {"n_spins": n, "major_loop": avalanche_statistics(major, n)}
    lattice, drives = [], []
    for c in couplings:
        rec, system, final = _coupled(op, float(c), t_end, transient)
        traj = system.trajectory(
            barkhausen_periods * period, final.q, final.v, final.operator_state,
            sample_dt=period / COMPARE_SAMPLES,
        )  # fmt: skip
        coupled = np.rint(np.abs(traj.switches["jump"]) * n / 2).astype(np.int64)
        rec["barkhausen"] = avalanche_statistics(coupled, n)
        # the flips counted by the engine over the same window, in a separate integration
        sec = system.poincare_section(
            barkhausen_periods + 1, 0, final.q, final.v, final.operator_state
        )
        rec["barkhausen_flips"] = int(sec.n_switches)
        rec["slides"] = 0 if traj.slides is None else int(traj.slides.size)
        lo, hi = float(np.min(traj.q)), float(np.max(traj.q))
        sweep = np.tile([lo, hi], barkhausen_periods)
        _, swept, _ = op.avalanches(sweep, op.initial_state(lo))
        rec["sweep"] = avalanche_statistics(swept, n)
        rec["input_range"] = [lo, hi]
        lattice.append(rec)
        # the input from the start, sampled COMPARE_SAMPLES times a period (shorter: the first
        # barkhausen_periods + transient_periods periods)
        head = system.trajectory(
            (transient_periods + barkhausen_periods) * period, DEFAULT_Q0, V0,
            sample_dt=period / COMPARE_SAMPLES,
        )  # fmt: skip
        drives.append(np.asarray(head.q, dtype=float))
    q_max = max(float(np.max(np.abs(d))) for d in drives)
    ident_start = time.perf_counter()
    model, info = identify_lattice(op, q_max + margin, identification_nodes)
    info["seconds"] = time.perf_counter() - ident_start
    # the lattice's own non-Preisach part, independent of any grid: minor-loop congruency
    a = min(switching, q_max)
    cong = congruency_scan(
        op, np.linspace(-a, a, CONGRUENCY_NODES), info["grid"][-1],
        CONGRUENCY_HISTORIES, CONGRUENCY_SAMPLES,
    )  # fmt: skip
    ident_seconds = time.perf_counter() - start
    preisach = []
    for c, drive in zip(couplings, drives, strict=True):
        rec, _, _ = _coupled(model, float(c), t_end, transient)
        rec["operator_error"] = _operator_error(op, model, drive)
        rec["operator_error_on_nodes"] = _operator_error(op, model, _quantize(drive, info["grid"]))
        preisach.append(rec)
    info["grid"] = info["grid"].tolist()
    out.update(
        lattice=lattice,
        preisach=preisach,
        identification=info,
        congruency=cong,
        seconds=time.perf_counter() - start,
        seconds_to_identification=ident_seconds,
    )
    return out


def lattice_tasks(size: LatticeSize, seed: int = 0) -> list[dict]:
    """The task dicts: realization outermost (a run stopped early has every (R, L) from fewer
    realizations), then L, then R."""
    if size.periods <= size.transient_periods:
        raise ValueError(
            f"periods={size.periods} must exceed transient_periods={size.transient_periods}"
        )
    for name in ("realizations", "barkhausen_periods", "identification_nodes"):
        positive_integer(getattr(size, name), name)
    if not (math.isfinite(size.margin) and size.margin >= 0):
        raise ValueError(f"margin must be a finite number >= 0, got {size.margin!r}")
    seeds = {n: lattice_seeds(seed, n, size.realizations) for n in size.sides}
    tasks = []
    for k in range(size.realizations):
        for n in size.sides:
            for r in size.disorders:
                tasks.append(
                    dict(
                        disorder=float(r),
                        side=int(n),
                        seed=int(seeds[n][k]),
                        couplings=[float(c) for c in size.couplings],
                        periods=int(size.periods),
                        transient_periods=int(size.transient_periods),
                        barkhausen_periods=int(size.barkhausen_periods),
                        identification_nodes=int(size.identification_nodes),
                        margin=float(size.margin),
                    )
                )
    return tasks


def _mean_sem(x: Sequence[float]) -> list[float]:
    a = np.asarray(x, dtype=float)
    a = a[np.isfinite(a)]
    if a.size == 0:
        return [float("nan"), float("nan")]
    sem = float(np.std(a, ddof=1) / math.sqrt(a.size)) if a.size > 1 else float("nan")
    return [float(np.mean(a)), sem]


def _side(recs: list[dict]) -> dict:
    """Means (with standard errors) over realizations of one operator's coupled runs."""
    out = {
        key: _mean_sem([r[key] for r in recs])
        for key in ("lambda_max", "kaplan_yorke", "box_counting", "magnetization")
    }
    out["fraction_regular"] = float(np.mean([r["regular"] for r in recs]))
    out["lambda_max_values"] = [r["lambda_max"] for r in recs]
    out["section_periods"] = [r["section_period"] for r in recs]
    return out


def summarize(tasks: Sequence[dict], results: Sequence[dict], size: LatticeSize) -> dict:
    """One JSON-ready record: per (R, L, C) the coupled lattice and its identified Preisach
    model (means ± standard errors over realizations, fraction regular), the agreement of the
    two per realization, the operator-level errors, Barkhausen statistics of the coupled
    motion and of the sweeps, and per (R, L) the identification's diagnostics."""
    groups: dict[tuple[float, int], list[tuple[dict, dict]]] = {}
    for t, r in zip(tasks, results, strict=True):
        groups.setdefault((t["disorder"], t["side"]), []).append((t, r))
    points = []
    for (r_, side), items in sorted(groups.items()):
        ident = [r["identification"] for _, r in items]
        major = [r["major_loop"] for _, r in items]
        # results stored before the congruency scan existed have none (nan)
        none = {"violation": float("nan"), "mean_violation": float("nan")}
        cong = [r.get("congruency", none) for _, r in items]
        for i, c in enumerate(items[0][0]["couplings"]):
            lat = [r["lattice"][i] for _, r in items]
            pre = [r["preisach"][i] for _, r in items]
            same = [
                (a["regular"] == b["regular"]) and (a["section_period"] == b["section_period"])
                for a, b in zip(lat, pre, strict=True)
            ]
            bark = [x["barkhausen"] for x in lat]
            sweep = [x["sweep"] for x in lat]
            points.append(
                {
                    "disorder": r_,
                    "side": side,
                    "n_spins": side**3,
                    "coupling": c,
                    "realizations": len(items),
                    "lattice": _side(lat),
                    "preisach": _side(pre),
                    "same_attractor_type": float(np.mean(same)),
                    "lambda_max_difference": _mean_sem(
                        [a["lambda_max"] - b["lambda_max"] for a, b in zip(lat, pre, strict=True)]
                    ),
                    "operator_error_rms": _mean_sem([p["operator_error"]["rms"] for p in pre]),
                    "operator_error_on_nodes_rms": _mean_sem(
                        [p["operator_error_on_nodes"]["rms"] for p in pre]
                    ),
                    "operator_error_on_nodes_max": max(
                        p["operator_error_on_nodes"]["max"] for p in pre
                    ),
                    "barkhausen_flips_match": all(
                        x["barkhausen"]["total"] == x["barkhausen_flips"] for x in lat
                    ),
                    "coupled_avalanches_per_period": _mean_sem(
                        [b["count"] / size.barkhausen_periods for b in bark]
                    ),
                    "coupled_mean_size": _mean_sem([b["mean"] for b in bark]),
                    "coupled_largest_fraction": _mean_sem([b["largest_fraction"] for b in bark]),
                    "coupled_tau": _mean_sem([b["tau"] for b in bark]),
                    "sweep_mean_size": _mean_sem([b["mean"] for b in sweep]),
                    "sweep_largest_fraction": _mean_sem([b["largest_fraction"] for b in sweep]),
                    "sweep_tau": _mean_sem([b["tau"] for b in sweep]),
                    "coupled_histogram": np.sum([b["histogram"] for b in bark], axis=0).tolist(),
                    "sweep_histogram": np.sum([b["histogram"] for b in sweep], axis=0).tolist(),
                    "bin_edges": bark[0]["bin_edges"],
                    "major_largest_fraction": _mean_sem([m["largest_fraction"] for m in major]),
                    "major_tau": _mean_sem([m["tau"] for m in major]),
                    "major_histogram": np.sum([m["histogram"] for m in major], axis=0).tolist(),
                    "identification_residual_rms": _mean_sem([x["residual_rms"] for x in ident]),
                    "identification_negative_mass": _mean_sem([x["negative_mass"] for x in ident]),
                    "identification_relays": _mean_sem([x["relays"] for x in ident]),
                    "identification_scale": _mean_sem([x["scale"] for x in ident]),
                    "same_attractor_values": [bool(x) for x in same],
                    "operator_error_rms_values": [p["operator_error"]["rms"] for p in pre],
                    "operator_error_on_nodes_rms_values": [
                        p["operator_error_on_nodes"]["rms"] for p in pre
                    ],
                    "congruency_violation": _mean_sem([c["violation"] for c in cong]),
                    "congruency_mean_violation": _mean_sem([c["mean_violation"] for c in cong]),
                    "congruency_violation_values": [c["violation"] for c in cong],
                    "seconds": float(sum(r["seconds"] for _, r in items)),
                }
            )
    return {"size": asdict(size), "points": points}


def run_study(
    size: LatticeSize | str = "small",
    store: ResultStore | str | os.PathLike | None = None,
    workers: int | None = None,
    progress: bool = False,
    allow_version_mismatch: bool = False,
    seed: int = 0,
    **overrides: Any,
) -> dict:
    """Run (or resume) the study at ``size`` (a :data:`SIZES` name or a :class:`LatticeSize`,
    with ``overrides`` of its fields) and return :func:`summarize`'s record plus
    ``wall_seconds``."""
    if isinstance(size, str):
        if size not in SIZES:
            raise ValueError(f"size must be one of {sorted(SIZES)}, got {size!r}")
        size = SIZES[size]
    size = replace(size, **overrides)
    tasks = lattice_tasks(size, seed)
    start = time.perf_counter()
    results = run_tasks(
        EXPERIMENT,
        tasks,
        lattice_task,
        store=store,
        workers=workers,
        progress=progress,
        allow_version_mismatch=allow_version_mismatch,
    )
    record = summarize(tasks, results, size)
    record["wall_seconds"] = time.perf_counter() - start
    return record
