"""Throughput of the disorder ensemble at one paper-scale point: tasks per hour.

One task = one realization ``SpinDimerEnsemble.random(20000, 2, 1, 2, seed)`` at C = 4.0:
Lyapunov spectrum, Poincaré section, D_BC and M_T over the whole forcing periods in
[transient, t_end], from one integration with the tangent flow (paper scale: t_end = 2·10⁴,
transient = 10³). Runs the same number of fresh tasks with 1 and with 2 local worker processes
(no store) and prints tasks/hour for each.

``full_paper_estimate_s`` estimates the wall time of ``hyst paper --full`` from measured task
costs: one task per (N, C) of the full ensemble set (N in the full run size, C = 2.9 and 4.0) is
timed at ``--estimate-t-end``, its cost scaled linearly to the full run length, multiplied by
the realizations and divided by the measured 2-worker rate gain; the figures without ensemble
tasks are added from the figure times of a full run's ``report.json`` (``--full-report``),
whose measured total is printed next to the estimate as ``full_paper_measured_s``. The last
line is one JSON object.

    python benchmarks/bench_ensemble.py [--tasks 4] [--t-end 20000] [--transient 1000]
        [--full-report docs/paper-full/report.json] [--no-estimate]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import time
from pathlib import Path

from analysis.experiments.ensemble import ensemble_task, ensemble_tasks
from analysis.experiments.execution import run_tasks


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spins", type=int, default=20000)
    ap.add_argument("--coupling", type=float, default=4.0)
    ap.add_argument("--tasks", type=int, default=4, help="tasks per worker setting")
    ap.add_argument("--t-end", type=float, default=20000.0)
    ap.add_argument("--transient", type=float, default=1000.0)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--no-estimate", action="store_true", help="skip full_paper_estimate_s")
    ap.add_argument(
        "--estimate-t-end", type=float, default=3000.0, help="run length of the timed tasks"
    )
    ap.add_argument("--full-report", default="docs/paper-full/report.json")
    args = ap.parse_args()

    # warm the numba caches outside the timing
    ensemble_task(args.spins, args.coupling, seed=0, t_end=50.0, transient=10.0)

    out = {
        "benchmark": "ensemble",
        "spins": args.spins,
        "coupling": args.coupling,
        "t_end": args.t_end,
        "transient": args.transient,
        "tasks": args.tasks,
        "cpu_count": os.cpu_count(),
        "python": platform.python_version(),
    }
    for i, workers in enumerate(args.workers):
        # fresh seeds for every setting (base seed differs), nothing served from a store
        tasks = ensemble_tasks(
            [args.spins], [args.coupling], args.tasks, 1000 + i, args.t_end, args.transient
        )
        start = time.perf_counter()
        results = run_tasks("bench", tasks, ensemble_task, workers=workers, progress=False)
        wall = time.perf_counter() - start
        rate = 3600.0 * len(tasks) / wall
        out[f"tasks_per_hour_{workers}_workers"] = round(rate, 1)
        out[f"wall_seconds_{workers}_workers"] = round(wall, 2)
        mean_dky = sum(r["kaplan_yorke"] for r in results) / len(results)
        print(
            f"{workers} worker(s): {len(tasks)} tasks in {wall:.1f} s = {rate:.0f} tasks/hour "
            f"(mean D_KY {mean_dky:.3f})"
        )
    if len(args.workers) >= 2:
        a, b = args.workers[:2]
        out["speedup"] = round(
            out[f"tasks_per_hour_{b}_workers"] / out[f"tasks_per_hour_{a}_workers"], 2
        )
    if not args.no_estimate:
        out.update(_full_estimate(args, out.get("speedup", 1.0)))
    print(json.dumps(out))


#: figures whose time is the ensemble's (the others reuse its stored tasks)
ENSEMBLE_FIGURES = ("fig:dim", "fig:sap", "fig:mag", "fig:mag_his")


def _full_estimate(args: argparse.Namespace, speedup: float) -> dict:
    from analysis.experiments.parameters import ENSEMBLE_COUPLINGS
    from analysis.paper.context import SIZES

    full = SIZES["full"]
    transient = 100.0
    scale = (full.ensemble_t_end) / args.estimate_t_end  # cost ~ integrated length
    serial = 0.0
    rows = []
    for n in full.ensemble_spins:
        for c in ENSEMBLE_COUPLINGS:
            times = []
            for seed in (11, 12):
                start = time.perf_counter()
                ensemble_task(n, c, seed=seed, t_end=args.estimate_t_end, transient=transient)
                times.append(time.perf_counter() - start)
            cost = statistics.median(times) * scale
            serial += cost * full.ensemble_realizations
            rows.append((n, c, cost))
            print(
                f"  full-size task N={n}, C={c}: {cost:.2f} s (scaled from {args.estimate_t_end:g})"
            )
    ensemble_s = serial / max(speedup, 1.0)
    res = {"full_ensemble_estimate_s": round(ensemble_s, 1)}
    report = Path(args.full_report)
    if report.exists():
        figs = json.loads(report.read_text())["figures"]
        other = sum(f["seconds"] for f in figs if f["label"] not in ENSEMBLE_FIGURES)
        res["full_paper_estimate_s"] = round(ensemble_s + other, 1)
        res["full_paper_measured_s"] = round(sum(f["seconds"] for f in figs), 1)
        res["full_report"] = str(report)
        print(
            f"hyst paper --full: estimate {res['full_paper_estimate_s']:.0f} s "
            f"(ensembles {ensemble_s:.0f} s from task costs + other figures {other:.0f} s from "
            f"{report}); measured {res['full_paper_measured_s']:.0f} s"
        )
    else:
        res["full_paper_estimate_s"] = None
        print(f"ensembles of hyst paper --full: {ensemble_s:.0f} s ({report} not found)")
    return res


if __name__ == "__main__":
    main()
