"""Periodic orbits: time to find (detect + Newton-refine) a period-k orbit, against a baseline
measured in the same run.

Section ``orbits`` — for each case (N = 20 000 dimers, the erf-play limit):

* ``find_s``: :func:`~analysis.dynamics.periodic_orbits.find_periodic_orbit` (transient,
  ``2·max_period`` detection periods, Newton with the tangent flow, the final orbit pass);
* ``baseline_s``: a plain stroboscopic integration (``poincare_section``) of the same
  ``transient + 2·max_period`` periods, no tangent flow;
* ``refine_s``: :func:`~analysis.dynamics.periodic_orbits.refine_periodic_orbit` from the
  detected start point; ``shot_s``: one ``P^k`` with the tangent flow (one Newton evaluation);
* ratios ``find_over_baseline`` and ``refine_over_shot`` (how many P^k evaluations Newton and
  the final pass cost).

Each time is the median of ``--repeats`` runs after a warm-up (numba caches). The last line is
one JSON object. Further sections add a function to :data:`SECTIONS`.

Section ``basins`` — the erf-play basin map of ``hyst basins`` (``--basin-grid``² starts, 100
periods each) in starts/s on 1 and 2 workers against the plain ``poincare_section`` loop, and
the extrapolated 1000 × 1000 map time (``benchmarks/bench_basins.py``, which also runs alone).

    python benchmarks/bench_orbits.py [--repeats 5] [--sections orbits]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import time
from collections.abc import Callable

from bench_basins import measure_basins  # the sibling script (benchmarks/ is on sys.path)

from analysis.dynamics.periodic_orbits import find_periodic_orbit, refine_periodic_orbit, shoot
from hysteresis import GeneralizedPlay, SpinDimerEnsemble
from oscillators import ForcedOscillator

#: (name, system builder, transient periods, max_period): N = 20 000 dimers (seed 2: a
#: period-10 orbit at C = 3.85) and the erf-play limit in its period-5 window
CASES = (
    (
        "dimers N=20000 seed=2 C=3.85",
        lambda: ForcedOscillator(SpinDimerEnsemble.random(20000, 2.0, 1.0, 2.0, seed=2), 3.85),
        200,
        32,
    ),
    ("erf-play C=3.85", lambda: ForcedOscillator(GeneralizedPlay.erf(2.0, 1.0), 3.85), 100, 64),
)


def _median_time(fn: Callable[[], object], repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def bench_orbits(args: argparse.Namespace) -> dict:
    """Section ``orbits``: find / refine against the plain integration and one P^k."""
    rows = []
    for name, build, transient, max_period in CASES:
        system = build()
        orbit = find_periodic_orbit(system, transient=transient, max_period=max_period)  # warm
        k = orbit.period
        find_s = _median_time(
            lambda s=system, tr=transient, mp=max_period: find_periodic_orbit(
                s, transient=tr, max_period=mp
            ),
            args.repeats,
        )
        baseline_s = _median_time(
            lambda s=system, tr=transient, mp=max_period: s.poincare_section(2 * mp, tr),
            args.repeats,
        )
        refine_s = _median_time(
            lambda s=system, o=orbit: refine_periodic_orbit(s, o.start, o.period), args.repeats
        )
        shot_s = _median_time(lambda s=system, o=orbit: shoot(s, o.start, o.period), args.repeats)
        rows.append(
            {
                "case": name,
                "period": k,
                "stable": orbit.stable,
                "newton_iterations": len(orbit.residuals) - 1,
                "find_s": find_s,
                "baseline_s": baseline_s,
                "find_over_baseline": find_s / baseline_s,
                "refine_s": refine_s,
                "shot_s": shot_s,
                "refine_over_shot": refine_s / shot_s,
            }
        )
        print(
            f"{name}: period {k}, find {find_s:.3f} s = {find_s / baseline_s:.2f} x the plain "
            f"integration of the same periods ({baseline_s:.3f} s); refine {refine_s:.3f} s = "
            f"{refine_s / shot_s:.1f} P^k evaluations ({shot_s:.4f} s each)"
        )
    return {"orbits": rows}


def bench_basin_maps(args: argparse.Namespace) -> dict:
    """Section ``basins``: the erf-play basin map (``--basin-grid``² starts, 100 periods each,
    C = 2.92) in starts/s on ``--basin-workers`` workers, against the plain
    ``poincare_section`` loop (:func:`bench_basins.measure_basins`)."""
    return {
        "basins": measure_basins(
            args.basin_grid, 2.92, 100, None, 400, args.basin_workers, 400, min(args.repeats, 3)
        )
    }


#: section name -> function(args) -> dict merged into the JSON record
SECTIONS: dict[str, Callable[[argparse.Namespace], dict]] = {
    "orbits": bench_orbits,
    "basins": bench_basin_maps,
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5, help="runs per timing (median)")
    ap.add_argument("--sections", nargs="+", default=list(SECTIONS), choices=list(SECTIONS))
    ap.add_argument("--basin-grid", type=int, default=200, help="basins: starts per axis")
    ap.add_argument("--basin-workers", type=int, nargs="+", default=[1, 2], help="basins: workers")
    args = ap.parse_args()
    out: dict = {
        "benchmark": "orbits",
        "cpu_count": os.cpu_count(),
        "python": platform.python_version(),
        "repeats": args.repeats,
    }
    for name in args.sections:
        out.update(SECTIONS[name](args))
    print(json.dumps(out))


if __name__ == "__main__":
    main()
