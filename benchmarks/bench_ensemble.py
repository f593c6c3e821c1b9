"""Throughput of the disorder ensemble at one paper-scale point: tasks per hour.

One task = one realization ``SpinDimerEnsemble.random(20000, 2, 1, 2, seed)`` at C = 4.0:
Lyapunov spectrum over [transient, t_end] plus the Poincaré section, D_BC and M_T over the same
window (paper scale: t_end = 2·10⁴, transient = 10³). Runs the same number of fresh tasks with
1 and with 2 local worker processes (no store) and prints tasks/hour for each; the last line is
one JSON object.

    python benchmarks/bench_ensemble.py [--tasks 4] [--t-end 20000] [--transient 1000]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time

from analysis.ensemble import ensemble_task, ensemble_tasks
from analysis.execution import run_tasks


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spins", type=int, default=20000)
    ap.add_argument("--coupling", type=float, default=4.0)
    ap.add_argument("--tasks", type=int, default=4, help="tasks per worker setting")
    ap.add_argument("--t-end", type=float, default=20000.0)
    ap.add_argument("--transient", type=float, default=1000.0)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
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
    print(json.dumps(out))


if __name__ == "__main__":
    main()
