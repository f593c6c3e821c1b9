"""The grid control of the lattice study: how much of the identified model's failure is the grid.

The identified model of a lattice (:func:`~analysis.experiments.lattice.identify_lattice`)
differs from the lattice by two errors: the grid staircase (thresholds moved to cell corners,
nothing resolved between nodes) and the lattice's non-Preisach part (its minor loops are not
congruent, :mod:`analysis.identification.congruency`). This control separates them with an
operator that has the staircase but no non-Preisach part: the *fine* model ``P_f`` of the
lattice (``fine_nodes`` nodes — a Preisach operator) is identified again on the study's
*coarse* grid (``coarse_nodes`` nodes over the same range), ``P_c = identify(P_f)``, and both
are coupled to the oscillator exactly like the lattice. ``P_c`` versus ``P_f`` is then a
pure grid error of the coarse grid — its attractor-type agreement and its operator-level error
along ``P_f``'s own input (raw, and on the coarse nodes, where it vanishes to the NNLS
residual) are the numbers the lattice-versus-model comparison at the coarse grid is to be read
against. One task is one realization (R, L, seed) at every coupling (the study's seeds).
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from analysis.experiments.execution import run_tasks
from analysis.experiments.lattice import (
    COMPARE_SAMPLES,
    SIZES,
    _coupled,
    _operator_error,
    _quantize,
    identify_lattice,
    lattice_seeds,
)
from analysis.experiments.parameters import DAMPING_RATIO, DEFAULT_Q0, FREQUENCY, V0
from analysis.experiments.store import ResultStore
from hysteresis import RandomFieldIsing
from hysteresis._validation import positive_integer
from oscillators import ForcedOscillator

__all__ = ["CONTROL_EXPERIMENT", "grid_control_task", "run_grid_control"]

CONTROL_EXPERIMENT = "lattice-grid-control"


def grid_control_task(
    disorder: float,
    side: int,
    seed: int,
    couplings: Sequence[float],
    periods: int,
    transient_periods: int,
    barkhausen_periods: int,
    margin: float,
    fine_nodes: int,
    coarse_nodes: int,
) -> dict:
    """One realization (module docstring): per coupling the fine and coarse models' coupled
    measurements, their agreement, and the coarse model's operator-level error along the fine
    model's input. Top-level (process pools)."""
    positive_integer(fine_nodes, "fine_nodes")
    positive_integer(coarse_nodes, "coarse_nodes")
    start = time.perf_counter()
    op = RandomFieldIsing.lattice((side,) * 3, disorder, seed=seed)
    period = 2 * math.pi / FREQUENCY
    t_end, transient = periods * period, transient_periods * period
    # the grids' range as the study's: the lattice's own coupled input over the same window
    q_max = 0.0
    for c in couplings:
        system = ForcedOscillator(op, float(c), damping_ratio=DAMPING_RATIO, frequency=FREQUENCY)
        head = system.trajectory(
            (transient_periods + barkhausen_periods) * period, DEFAULT_Q0, V0,
            sample_dt=period / COMPARE_SAMPLES,
        )  # fmt: skip
        q_max = max(q_max, float(np.max(np.abs(head.q))))
    fine, fine_info = identify_lattice(op, q_max + margin, fine_nodes)
    coarse, info = identify_lattice(fine, q_max + margin, coarse_nodes, fine_info["grid"][-1])
    out = []
    for c in couplings:
        rec_f, system, _ = _coupled(fine, float(c), t_end, transient)
        rec_c, _, _ = _coupled(coarse, float(c), t_end, transient)
        drive = np.asarray(
            system.trajectory(
                (transient_periods + barkhausen_periods) * period,
                DEFAULT_Q0,
                V0,
                sample_dt=period / COMPARE_SAMPLES,
            ).q,
            dtype=float,
        )
        same = rec_f["regular"] == rec_c["regular"] and (
            rec_f["section_period"] == rec_c["section_period"]
        )
        out.append(
            {
                "fine": {k: rec_f[k] for k in ("lambda_max", "section_period", "regular")},
                "coarse": {k: rec_c[k] for k in ("lambda_max", "section_period", "regular")},
                "same_attractor_type": bool(same),
                "operator_error": _operator_error(fine, coarse, drive),
                "operator_error_on_nodes": _operator_error(
                    fine, coarse, _quantize(drive, np.asarray(info["grid"]))
                ),
            }
        )
    return {
        "couplings": out,
        "q_max": q_max,
        "relays": [int(fine_info["relays"]), int(info["relays"])],
        "seconds": time.perf_counter() - start,
    }


def run_grid_control(
    sides: Sequence[int],
    fine_nodes: int,
    size: str = "moderate",
    store: ResultStore | str | os.PathLike | None = None,
    workers: int | None = None,
    seed: int = 0,
) -> dict:
    """Run (or resume) the control for the study's ``size`` (its disorders, couplings, periods,
    realizations and seeds) at the lattice sides ``sides``; the coarse grid is the size's
    ``identification_nodes``. Returns per (R, L, C) the fine-vs-coarse agreement (one bool per
    realization) and the coarse model's operator-level errors (raw and on its nodes)."""
    if size not in SIZES:
        raise ValueError(f"size must be one of {sorted(SIZES)}, got {size!r}")
    sz = SIZES[size]
    tasks = []
    for k in range(sz.realizations):
        for n in sides:
            for r in sz.disorders:
                tasks.append(
                    dict(
                        disorder=float(r), side=int(n),
                        seed=int(lattice_seeds(seed, n, sz.realizations)[k]),
                        couplings=[float(c) for c in sz.couplings], periods=sz.periods,
                        transient_periods=sz.transient_periods,
                        barkhausen_periods=sz.barkhausen_periods, margin=sz.margin,
                        fine_nodes=int(fine_nodes), coarse_nodes=sz.identification_nodes,
                    )
                )  # fmt: skip
    results = run_tasks(
        CONTROL_EXPERIMENT, tasks, grid_control_task, store=store, workers=workers, progress=False
    )
    groups: dict[tuple, list[Any]] = {}
    for t, res in zip(tasks, results, strict=True):
        for c, rec in zip(t["couplings"], res["couplings"], strict=True):
            groups.setdefault((t["disorder"], t["side"], c), []).append(rec)
    points = [
        {
            "disorder": r, "side": n, "coupling": c,
            "same_attractor_values": [x["same_attractor_type"] for x in recs],
            "operator_error_rms_values": [x["operator_error"]["rms"] for x in recs],
            "operator_error_on_nodes_rms_values": [
                x["operator_error_on_nodes"]["rms"] for x in recs
            ],
            "fine_section_periods": [x["fine"]["section_period"] for x in recs],
            "coarse_section_periods": [x["coarse"]["section_period"] for x in recs],
        }
        for (r, n, c), recs in sorted(groups.items())
    ]  # fmt: skip
    return {"fine_nodes": int(fine_nodes), "coarse_nodes": sz.identification_nodes,
            "points": points}  # fmt: skip
