"""Throughput of basin maps of the erf-play limit: starts per second against the plain section
loop, and the extrapolated time of a 1000 × 1000 map.

A ``--grid`` × ``--grid`` map (default 200 × 200) over (q0, v0) in [-3, 3]² at C = ``--coupling``
(default 2.92) by :func:`analysis.dynamics.basins.basins`:

* ``--method recurrences`` (default): the recurrence mapper (cells of 0.05 over (q, v, w),
  Attractors.jl's thresholds, chunks of 10 000 starts per task), each start running at most
  ``--max-periods`` (default 2000: long enough for a start to find the period-5 attractor
  through the chaotic transient, median ~400 periods, and locate it); most starts stop after
  12–15 periods on basin cells of earlier starts;
* ``--method sections``: every start integrated for ``--periods`` (default 100) and classified
  by its own section (the map the README's earlier numbers are for).

The baseline, measured in the same run right before and right after each setting (their mean;
the load drifts), is the plain API loop ``system.poincare_section(periods, 0, q0, v0)`` (100
periods, serial) over ``--baseline-starts`` starts of the same grid, the median of
``--repeats``. Each setting runs on 1 and/or 2 workers (``--workers``; a
``ProcessPoolExecutor`` passed as the executor).
Extrapolation to 1000 × 1000: the mapping time scales with the number of starts (per-start cost
is set by the chunk, whose size does not change with the grid) plus the attractor phase (once
per attractor, independent of the grid size). With ``--json`` the last line is one JSON object
``{"starts_per_s": ..., "baseline_starts_per_s": ..., ...}`` (the rate on the most workers
measured and its baseline; the full record on the line before).

``python benchmarks/bench_orbits.py --sections basins`` runs the ``sections`` measurement as a
section of the orbits benchmark.

    python benchmarks/bench_basins.py [--grid 200] [--workers 1 2] [--method recurrences] [--json]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import time
from concurrent.futures import ProcessPoolExecutor

from analysis.dynamics.basins import BasinGrid, RecurrenceSettings, basins
from analysis.experiments.models import build_operator
from oscillators import ForcedOscillator


def measure_basins(
    grid_size: int,
    coupling: float,
    periods: int,
    check_periods: int | None,
    chunk: int,
    workers: list[int],
    baseline_starts: int,
    repeats: int,
    *,
    method: str = "sections",
    max_periods: int | None = None,
    quiet: bool = False,
) -> dict:
    """The measurement (module docstring); prints one line per setting, returns the record
    (``bench_orbits.py`` runs it as its ``basins`` section). ``sections``: every start runs
    ``periods`` (its first check after ``check_periods``); ``recurrences``: at most
    ``max_periods`` (default ``periods``), ``chunk`` starts per cell grid."""
    system = ForcedOscillator(build_operator("erf-play"), coupling)
    grid = BasinGrid((-3.0, 3.0), (-3.0, 3.0), grid_size)
    starts = grid.starts()
    # warm the numba caches outside the timing
    system.poincare_section(2, 0, 0.0, 0.0)

    n_base = min(baseline_starts, starts.shape[0])
    step = max(1, starts.shape[0] // n_base)

    def measure_baseline() -> float:
        base = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            for q0, v0, _w in starts[::step][:n_base]:
                system.poincare_section(periods, 0, q0, v0)
            base.append(n_base / (time.perf_counter() - t0))
        return statistics.median(base)

    out = {
        "benchmark": "basins",
        "method": method,
        "model": "erf-play",
        "coupling": coupling,
        "grid": grid_size,
        "starts": int(starts.shape[0]),
        "periods": periods,
        "check": check_periods,
        "max_periods": max_periods,
        "chunk": chunk,
        "cpu_count": os.cpu_count(),
        "machine": platform.machine(),
        "load_average_1min_before": round(os.getloadavg()[0], 2),
    }
    if method == "recurrences":
        kw = dict(
            method=method,
            transient=0,
            periods=periods,
            max_periods=max_periods or periods,
            recurrence=RecurrenceSettings(chunk=chunk),
        )
    else:
        kw = dict(
            transient=0,
            periods=periods if check_periods is None else check_periods,
            max_periods=periods,
            chunk=chunk,
        )
    for w in workers:
        # the baseline next to each setting: the machine's other load drifts over a long run,
        # and a ratio only means something against a baseline measured under the same load
        baseline = measure_baseline()
        if not quiet:
            print(f"baseline poincare_section loop: {baseline:.1f} starts/s (median of {repeats})")
        t0 = time.perf_counter()
        if w == 1:
            bm = basins(system, grid, lyapunov_periods=2000, **kw)
        else:
            with ProcessPoolExecutor(w) as ex:
                bm = basins(system, grid, lyapunov_periods=2000, executor=ex, **kw)
        wall = time.perf_counter() - t0
        # and after it: the ratio uses the mean of the two (the load drifts during a setting)
        after = measure_baseline()
        if not quiet:
            print(f"baseline after the setting: {after:.1f} starts/s")
        before, baseline = baseline, 0.5 * (baseline + after)
        rate = starts.shape[0] / wall
        sections = bm.timings["sections_s"]
        per_million = 1e6 * sections / starts.shape[0] + bm.timings["attractors_s"]
        out[f"workers_{w}"] = {
            "wall_s": round(wall, 1),
            "sections_s": round(sections, 1),
            "sections_starts_per_s": round(starts.shape[0] / sections, 1),
            "attractors_s": round(bm.timings["attractors_s"], 1),
            "starts_per_s": round(rate, 1),
            "baseline_starts_per_s": round(baseline, 2),
            "baseline_before_after": [round(before, 2), round(after, 2)],
            "ratio_to_baseline": round(rate / baseline, 2),
            # the section runs scale with the starts, the attractor phase does not
            "map_1000x1000_h": round(per_million / 3600, 3),
            "map_1000x1000_min": round(per_million / 60, 1),
            "load_average_1min_after": round(os.getloadavg()[0], 2),
            "attractors": [
                {k: a.get(k) for k in ("kind", "period", "count", "max_exponent")}
                for a in bm.attractors
            ],
            **{k: bm.settings[k] for k in ("stops", "steps_mean", "merges") if k in bm.settings},
        }
        srate = starts.shape[0] / sections
        if not quiet:
            print(
                f"{w} worker(s), {method}: {rate:.1f} starts/s overall ({rate / baseline:.2f} x "
                f"baseline), {srate:.1f} starts/s mapping ({srate / baseline:.2f} x), "
                f"attractors {bm.timings['attractors_s']:.1f} s; 1000 x 1000 map: "
                f"{per_million / 60:.1f} min"
            )
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", type=int, default=200)
    ap.add_argument("--coupling", type=float, default=2.92)
    ap.add_argument("--method", choices=("recurrences", "sections"), default="recurrences")
    ap.add_argument("--periods", type=int, default=100)
    ap.add_argument(
        "--max-periods",
        type=int,
        default=2000,
        help="recurrences: the most periods a start runs (its max_steps)",
    )
    ap.add_argument(
        "--check",
        type=int,
        default=None,
        help="sections: periods of the first check (default --periods: every start runs "
        "--periods); with --check 50 a start that settled by then stops there",
    )
    ap.add_argument(
        "--chunk", type=int, default=None, help="starts per task (sections 400, recurrences 10000)"
    )
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--baseline-starts", type=int, default=400)
    ap.add_argument("--repeats", type=int, default=3, help="baseline repeats (median)")
    ap.add_argument("--json", action="store_true", help="last line: the summary JSON object")
    args = ap.parse_args()

    chunk = args.chunk or (10_000 if args.method == "recurrences" else 400)
    out = measure_basins(
        args.grid,
        args.coupling,
        args.periods,
        args.check,
        chunk,
        args.workers,
        args.baseline_starts,
        args.repeats,
        method=args.method,
        max_periods=args.max_periods,
    )
    print(json.dumps(out))
    if args.json:
        last = out[f"workers_{max(args.workers)}"]
        print(
            json.dumps(
                {
                    "starts_per_s": last["starts_per_s"],
                    "baseline_starts_per_s": last["baseline_starts_per_s"],
                    "workers": max(args.workers),
                    "ratio": last["ratio_to_baseline"],
                    "map_1000x1000_min": last["map_1000x1000_min"],
                    "method": args.method,
                }
            )
        )


if __name__ == "__main__":
    main()
