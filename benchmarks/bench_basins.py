"""Throughput of basin maps of the erf-play limit: starts per second on 1 and 2 workers.

A ``--grid`` × ``--grid`` map (default 200 × 200) over (q0, v0) in [-3, 3]² at C = ``--coupling``
(default 2.92), every start integrated for ``--periods`` forcing periods (default 100, no
transient, no extension) and classified by :func:`analysis.dynamics.basins.basins` (chunks of
``--chunk`` starts per task, no store), then the orbit refinement and the Lyapunov runs once per
attractor. The baseline, measured in the same run right before each setting (the load
drifts) on ``--baseline-starts`` starts of the same grid, is the plain API loop
``system.poincare_section(periods, 0, q0, v0)`` per start (serial).
Prints starts/s of each setting (overall, and in the section runs alone), its ratio to the
baseline, and the extrapolated wall time of a 1000 × 1000 map: the section runs scaled by the
number of starts (every start costs the same number of periods) plus the attractor phase
(refinements and Lyapunov runs once per attractor, independent of the grid size). The last
line is one JSON object.

``python benchmarks/bench_orbits.py --sections basins`` runs the same measurement as a section
of the orbits benchmark (the file the issue names).

    python benchmarks/bench_basins.py [--grid 200] [--periods 100] [--workers 1 2]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import time

from analysis.dynamics.basins import BasinGrid, basins
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
) -> dict:
    """The measurement (module docstring); prints one line per setting, returns the record
    (``bench_orbits.py`` runs it as its ``basins`` section)."""
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
        "model": "erf-play",
        "coupling": coupling,
        "grid": grid_size,
        "starts": int(starts.shape[0]),
        "periods": periods,
        "check": check_periods,
        "chunk": chunk,
        "cpu_count": os.cpu_count(),
        "machine": platform.machine(),
    }
    for w in workers:
        # the baseline next to each setting: the machine's other load drifts over a long run,
        # and a ratio only means something against a baseline measured under the same load
        baseline = measure_baseline()
        print(f"baseline poincare_section loop: {baseline:.1f} starts/s (median of {repeats})")
        t0 = time.perf_counter()
        bm = basins(
            system,
            grid,
            transient=0,
            periods=periods if check_periods is None else check_periods,
            max_periods=periods,
            chunk=chunk,
            workers=w,
            lyapunov_periods=2000,
        )
        wall = time.perf_counter() - t0
        rate = starts.shape[0] / wall
        sections = bm.timings["sections_s"]
        out[f"workers_{w}"] = {
            "wall_s": round(wall, 1),
            "sections_s": round(sections, 1),
            "sections_starts_per_s": round(starts.shape[0] / sections, 1),
            "attractors_s": round(bm.timings["attractors_s"], 1),
            "starts_per_s": round(rate, 1),
            "baseline_starts_per_s": round(baseline, 2),
            "ratio_to_baseline": round(rate / baseline, 2),
            # the section runs scale with the starts, the attractor phase does not
            "map_1000x1000_h": round(
                (1e6 * sections / starts.shape[0] + bm.timings["attractors_s"]) / 3600, 2
            ),
            "attractors": [
                {k: a.get(k) for k in ("kind", "period", "count", "max_exponent")}
                for a in bm.attractors
            ],
        }
        srate = starts.shape[0] / sections
        print(
            f"{w} worker(s): {rate:.1f} starts/s overall ({rate / baseline:.2f} x baseline), "
            f"{srate:.1f} starts/s in the section runs ({srate / baseline:.2f} x), "
            f"attractors {bm.timings['attractors_s']:.1f} s; 1000 x 1000 map: "
            f"{1e6 / srate / 3600 + bm.timings['attractors_s'] / 3600:.2f} h"
        )
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--grid", type=int, default=200)
    ap.add_argument("--coupling", type=float, default=2.92)
    ap.add_argument("--periods", type=int, default=100)
    ap.add_argument(
        "--check",
        type=int,
        default=None,
        help="periods of the first check (default --periods: every start runs --periods); "
        "with --check 50 a start that settled by then stops there, the others run --periods",
    )
    ap.add_argument("--chunk", type=int, default=400)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--baseline-starts", type=int, default=400)
    ap.add_argument("--repeats", type=int, default=3, help="baseline repeats (median)")
    args = ap.parse_args()

    out = measure_basins(
        args.grid,
        args.coupling,
        args.periods,
        args.check,
        args.chunk,
        args.workers,
        args.baseline_starts,
        args.repeats,
    )
    print(json.dumps(out))


if __name__ == "__main__":
    main()
