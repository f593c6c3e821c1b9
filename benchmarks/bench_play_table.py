"""Speed of a tabulated play shape on the compiled play kernel (issue 18).

Seconds per 1000 time units with the tangent flow (``lyapunov_spectrum``, QR every period), at
C = 2, ζ = 0.05, Ω = 1, width 2, median of 3 runs each, all measured in this run:

* ``erf_play_s_per_1000tu_tangent``: ``GeneralizedPlay.erf(2, 1)``, the closed-form erf kernel
  (the baseline);
* ``tanh_play_s_per_1000tu_tangent``: ``GeneralizedPlay(2, tanh, sech²)``, the same kernel on the
  shape's cubic Hermite table (:mod:`hysteresis.shape_table`);
* ``tanh_play_generic_s_per_1000tu_tangent``: the same operator on the generic continuous engine
  (``solve_ivp`` per branch, rtol 1e-11; a shorter run).

The last line is one JSON object with these and the ratios to the erf kernel.

    python benchmarks/bench_play_table.py [--time 2000] [--generic-time 100]
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

import numpy as np

from analysis.dynamics.lyapunov import lyapunov_spectrum
from hysteresis.play import GeneralizedPlay
from oscillators import ForcedOscillator
from oscillators.engines.continuous import ContinuousEngine

ZETA, OMEGA, COUPLING, WIDTH = 0.05, 1.0, 2.0, 2.0


def sech2(w):
    return 1.0 / np.cosh(np.clip(np.asarray(w), -350.0, 350.0)) ** 2


class _GenericTanh(GeneralizedPlay):
    """The tanh play without its compiled description (the generic engine's baseline)."""

    def compiled_play(self):
        return None


def seconds_per_1000(operator, t_run: float, repeats: int = 3) -> float:
    system = ForcedOscillator(operator, COUPLING, ZETA, OMEGA)
    lyapunov_spectrum(system, min(t_run, 20.0))  # compile / warm up
    runs = []
    for _ in range(repeats):
        start = time.perf_counter()
        lyapunov_spectrum(system, t_run)
        runs.append(1000.0 * (time.perf_counter() - start) / t_run)
    return statistics.median(runs)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--time", type=float, default=2000.0)
    parser.add_argument("--generic-time", type=float, default=100.0)
    args = parser.parse_args()
    tanh = GeneralizedPlay(WIDTH, np.tanh, sech2, name="tanh")
    generic = _GenericTanh(WIDTH, np.tanh, sech2, name="tanh")
    assert ForcedOscillator(generic, COUPLING).engine_class is ContinuousEngine
    erf_s = seconds_per_1000(GeneralizedPlay.erf(WIDTH, 1.0), args.time)
    tanh_s = seconds_per_1000(tanh, args.time)
    generic_s = seconds_per_1000(generic, args.generic_time)
    table = tanh.shape_table()
    print(f"erf play kernel: {erf_s:.4f} s per 1000 tu (tangent)")
    print(
        f"tanh play, table of {table.knots} knots (error {table.error:.2g}): {tanh_s:.4f} s "
        f"per 1000 tu = {tanh_s / erf_s:.2f} x the erf kernel"
    )
    print(f"tanh play, generic engine: {generic_s:.2f} s per 1000 tu = {generic_s / erf_s:.0f} x")
    print(
        json.dumps(
            {
                "erf_play_s_per_1000tu_tangent": erf_s,
                "tanh_play_s_per_1000tu_tangent": tanh_s,
                "tanh_play_generic_s_per_1000tu_tangent": generic_s,
                "tanh_play_vs_erf_play": tanh_s / erf_s,
                "tanh_play_generic_vs_erf_play": generic_s / erf_s,
                "tanh_table_knots": table.knots,
            }
        )
    )


if __name__ == "__main__":
    main()
