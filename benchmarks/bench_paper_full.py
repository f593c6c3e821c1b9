"""What the compiled Benettin loop (:mod:`analysis.dynamics._relay_benettin`), the compiled box
count, the relay kernel's wider fast hop (``relay.FAST_HOP``) and the overlap of the ensemble
with the other figures save on ``hyst paper --full``, and the wall estimate.

1. Before/after in the same run: every (N, C) of the full run's ensemble, ``--reps``
   realizations of its seeds at full size, each run as ``before`` (Python Benettin loop, numpy
   box count, fast hop limit 1e-3/ρ), ``compiled`` (the compiled ones; checked bit for bit
   equal to ``before``) and, if ``relay.FAST_HOP`` differs from 1e-3, ``now`` (round-off
   changes), alternating; CPU time of this process (``time.process_time``: the machine's other
   load changes it less than wall time). Medians per (N, C) × 500 realizations give fig:dim's
   ensemble CPU in each; the iid reference and the limits are timed once (unchanged).
2. The overlap: the idle core-seconds of the parts that now run beside the ensemble — per
   figure and the evidence ``2·wall − Σ task wall`` of a sequential ``hyst paper`` run (its
   report's seconds and its store's per-task wall times, ``--run``; an in-process part idles
   one core), scaled to the full run's seconds of ``--full-report``, plus the serial
   periodic-orbit evidence (14 s in the full run).
3. The wall estimate for two workers: ``--base-estimate`` (the --full wall with the current
   relay kernel before these changes, default 1140 s = 19 min: 24 min 38 s measured at f0b3c77
   less what the relay kernel's 1.48x per switch saves since), minus each saved share of
   fig:dim's CPU times fig:dim's wall now (the measured run's fig:dim seconds less that kernel
   saving, all of which is in fig:dim), minus half the idle core-seconds the overlap fills.
   The last line is one JSON object.

    python benchmarks/bench_paper_full.py [--reps 3] [--run /tmp/pq_base]
        [--full-report docs/paper-full/report.json] [--base-estimate 1140] [--base-measured 1478]
"""

from __future__ import annotations

import argparse
import json
import math
import sqlite3
import statistics
import time
from pathlib import Path

import numpy as np

import analysis.dynamics.dimensions as dimensions
import analysis.dynamics.lyapunov as lyapunov
import oscillators.engines.relay as relay
from analysis.experiments import iid
from analysis.experiments.ensemble import ensemble_task, realization_seeds
from analysis.experiments.parameters import ENSEMBLE_COUPLINGS, FREQUENCY, SEED
from analysis.paper.context import SIZES
from analysis.paper.ensemble_tasks import limit_dimension_task

ENSEMBLE_FIGURES = ("fig:dim", "fig:sap", "fig:mag", "fig:mag_his")
#: the periodic-orbit evidence of the full run (serial, in-process: no tasks, not in the
#: report's seconds; docs/paper-full/report.json's provenance gives 14 s)
ORBITS_FULL_S = 14.0
#: the relay kernel's fast short hop limit ρh before ``relay.FAST_HOP``
FORMER_FAST_HOP = 1e-3
#: the store experiments of each part of a run (the rest of a figure's time is in-process)
EXPERIMENTS = {
    "fig:mboa": ("mboa",),
    "fig:bif_0": ("paper-bif0",),
    "fig:bif": ("paper-bif",),
    "basins": ("basins", "realization-attractors"),
}


def _python_loop(*args, **kwargs):
    return 0, np.empty((0, 4))


def _numpy_box_count(*args, **kwargs):
    return -1  # box_counts then counts with numpy (_occupied), as before


def _cpu(func, *args, **kwargs):
    start = time.process_time()
    result = func(*args, **kwargs)
    return time.process_time() - start, result


def _run(config: str, n: int, c: float, kw: dict) -> tuple[float, dict]:
    """CPU time and result of one task: ``before`` (Python Benettin loop, numpy box count,
    the fast hop's former limit), ``compiled`` (the compiled ones, that limit) or ``now``."""
    saved = lyapunov.qr_intervals, dimensions._occupied_grid, relay.FAST_HOP
    if config == "before":
        lyapunov.qr_intervals, dimensions._occupied_grid = _python_loop, _numpy_box_count
    if config != "now":
        relay.FAST_HOP = FORMER_FAST_HOP
    try:
        return _cpu(ensemble_task, n, c, **kw)
    finally:
        lyapunov.qr_intervals, dimensions._occupied_grid, relay.FAST_HOP = saved


def compiled_loop_profile(reps: int) -> dict:
    full = SIZES["full"]
    configs = ["before", "compiled"] + (["now"] if relay.FAST_HOP != FORMER_FAST_HOP else [])
    total = dict.fromkeys(configs, 0.0)
    rows = []
    for n in full.ensemble_spins:
        seeds = realization_seeds(SEED, n, reps)
        for c in ENSEMBLE_COUPLINGS:
            times: dict[str, list[float]] = {k: [] for k in configs}
            for seed in seeds:
                kw = dict(seed=seed, t_end=full.ensemble_t_end, transient=full.ensemble_transient)
                results = {}
                for config in configs:
                    cpu, results[config] = _run(config, n, c, kw)
                    times[config].append(cpu)
                a, b = results["before"], results["compiled"]
                for key in a:  # the compiled loops are bit for bit the Python ones
                    if not np.array_equal(np.asarray(a[key]), np.asarray(b[key]), equal_nan=True):
                        raise AssertionError(f"N={n} C={c} seed={seed}: {key} differs")
            med = {k: statistics.median(v) for k, v in times.items()}
            for k in configs:
                total[k] += full.ensemble_realizations * med[k]
            rows.append([n, c] + [round(med[k], 4) for k in configs])
            print(f"  N={n:5d} C={c}: " + " -> ".join(f"{med[k]:.3f}" for k in configs)
                  + f" CPU s/task ({med[configs[0]] / med[configs[-1]]:.2f}x)")  # fmt: skip
    other = 0.0
    for n in full.iid_spins:
        tasks = iid.iid_tasks(n, full.iid_steps, 1, iid._seed_for(SEED, n))
        other += full.iid_realizations * _cpu(iid.iid_task, **tasks[0])[0]
    period = 2.0 * math.pi / FREQUENCY
    skip = math.ceil(full.ensemble_transient / period)
    points = max(math.floor(full.ensemble_t_end / period) - skip, 10)
    for c in ENSEMBLE_COUPLINGS:
        other += _cpu(limit_dimension_task, c, full.dky_t_end, full.dky_transient, points, skip)[0]
    base = total["before"] + other
    out = {f"ensemble_cpu_{k}_s": round(v, 1) for k, v in total.items()}
    out["iid_and_limits_cpu_s"] = round(other, 1)
    out["fig_dim_cpu_saved_fraction"] = round((total["before"] - total["compiled"]) / base, 4)
    if "now" in total:
        out["fig_dim_cpu_saved_fraction_fast_hop"] = round(
            (total["compiled"] - total["now"]) / base, 4
        )
    out["per_point"] = rows
    return out


def idle_core_seconds(run: Path) -> dict[str, float]:
    """``2·wall − Σ task wall`` per non-ensemble part of the run in ``run`` (report + store)."""
    report = json.loads((run / "report.json").read_text())
    walls = {f["label"]: float(f["seconds"]) for f in report["figures"]}
    walls["basins"] = float(report.get("basins", {}).get("seconds") or 0.0)
    with sqlite3.connect(f"file:{run / 'results.sqlite'}?mode=ro", uri=True) as db:
        busy = dict(db.execute("select experiment, sum(wall_time) from tasks group by experiment"))
    idle = {}
    for label, wall in walls.items():
        if label in ENSEMBLE_FIGURES:
            continue
        work = sum(float(busy.get(e) or 0.0) for e in EXPERIMENTS.get(label, ()))
        # in-process figures: one core computes, the other idles (work = wall)
        idle[label] = max(2.0 * wall - (work if work else wall), 0.0)
    return {"walls": walls, "idle": idle}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--run", default=None, help="output directory of a hyst paper run")
    ap.add_argument("--full-report", default="docs/paper-full/report.json")
    ap.add_argument("--base-estimate", type=float, default=1140.0)
    ap.add_argument("--base-measured", type=float, default=1478.0, help="--full-report's wall")
    args = ap.parse_args()
    ensemble_task(100, 4.0, seed=0, t_end=50.0, transient=10.0)  # numba caches, untimed
    out: dict = {"benchmark": "paper_full", "reps": args.reps}
    print("CPU per task (median): before -> compiled loops [-> fast hop FAST_HOP]:")
    out.update(compiled_loop_profile(args.reps))
    full = json.loads(Path(args.full_report).read_text())
    full_walls = {f["label"]: float(f["seconds"]) for f in full["figures"]}
    full_walls["basins"] = float(full.get("basins", {}).get("seconds") or 0.0)
    dim_s = sum(full_walls[x] for x in ENSEMBLE_FIGURES)
    dim_s -= args.base_measured - args.base_estimate  # the kernel's saving since that run
    saved_loop = out["fig_dim_cpu_saved_fraction"] * dim_s
    saved_hop = out.get("fig_dim_cpu_saved_fraction_fast_hop", 0.0) * dim_s
    saved_overlap = 0.0
    if args.run:
        run = idle_core_seconds(Path(args.run))
        scaled = {}
        for label, idle in run["idle"].items():
            wall = run["walls"][label]
            scaled[label] = idle / wall * full_walls.get(label, 0.0) if wall > 0 else 0.0
        scaled["orbits"] = ORBITS_FULL_S  # one core computes, the other idles
        saved_overlap = 0.5 * sum(scaled.values())
        out["overlap_idle_core_s_full"] = {k: round(v, 1) for k, v in scaled.items()}
    estimate = args.base_estimate - saved_loop - saved_hop - saved_overlap
    out.update(
        saved_compiled_loop_s=round(saved_loop, 1),
        saved_fast_hop_s=round(saved_hop, 1),
        saved_overlap_s=round(saved_overlap, 1),
        full_estimate_s=round(estimate, 1),
    )
    print(
        f"--full estimate: {args.base_estimate:.0f} s - {saved_loop:.0f} s (compiled loops: "
        f"{out['fig_dim_cpu_saved_fraction']:.1%} of fig:dim's {dim_s:.0f} s) - "
        f"{saved_hop:.0f} s (fast hop) - {saved_overlap:.0f} s (overlap) = {estimate:.0f} s = "
        f"{estimate / 60:.1f} min"
    )
    print(json.dumps(out))


if __name__ == "__main__":
    main()
