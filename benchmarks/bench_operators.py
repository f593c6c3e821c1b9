"""Throughput of the discrete Preisach model against a straightforward vectorised relay update.

Run: ``python benchmarks/bench_operators.py [--steps 1000000] [--repeats 5]``

* 10 000 relays, centres ~ N(0, 1), half-widths ~ U(0, 1) (``numpy.random.default_rng(0)``);
* the paper's ensemble of 10 000 equal-width dimers,
  ``SpinDimerEnsemble.random(20000, width=2, spread=1, spin_coupling=2, seed=0).to_preisach()``;
* input: 10^6 steps of a random walk with N(0, 0.05²) increments reflected into [-4, 4].

Baseline: numpy, one array update of all relays per input step
(``up = (u >= alpha) | (up & (u >= beta))`` and ``M = 2 w·up - 1``), timed on fewer steps and
reported per step. Medians over repeats after a warm-up call (numba compilation excluded);
rates from the CPU time of this process (wall-clock rates printed too: other jobs on a shared
machine slow the wall clock, not the CPU time).
The last line is one JSON object.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from hysteresis.preisach import PreisachModel
from hysteresis.spin_dimers import SpinDimerEnsemble


def reflected_walk(n_steps: int, step: float, bound: float, seed: int) -> np.ndarray:
    """Random walk with N(0, step²) increments, reflected at ±bound (fold of the free walk)."""
    free = np.cumsum(np.random.default_rng(seed).normal(0.0, step, n_steps))
    period = 4.0 * bound
    y = np.mod(free + bound, period)
    return np.where(y > 2.0 * bound, period - y, y) - bound


def baseline(alpha, beta, weights, inputs):
    up = inputs[0] >= alpha
    out = np.empty(inputs.size)
    for k, u in enumerate(inputs):
        up = (u >= alpha) | (up & (u >= beta))
        out[k] = 2.0 * np.dot(weights, up) - 1.0
    return out


def median_rate(fn, n_steps: int, repeats: int) -> tuple[float, float]:
    """Steps per second from the median CPU time of this process (robust when other jobs share
    the cores) and from the median wall-clock time."""
    fn()  # warm-up (numba compilation, caches)
    cpu, wall = [], []
    for _ in range(repeats):
        c0, w0 = time.process_time(), time.perf_counter()
        fn()
        cpu.append(time.process_time() - c0)
        wall.append(time.perf_counter() - w0)
    return n_steps / float(np.median(cpu)), n_steps / float(np.median(wall))


def measure(model, inputs, baseline_steps: int, repeats: int) -> dict:
    rate, rate_wall = median_rate(lambda: model.apply(inputs), inputs.size, repeats)
    short = inputs[:baseline_steps]
    out_fast, _ = model.apply(short)
    out_base = baseline(model.alpha, model.beta, model.weights, short)
    agree = float(np.max(np.abs(out_fast - out_base)))
    base, base_wall = median_rate(
        lambda: baseline(model.alpha, model.beta, model.weights, short), short.size, repeats
    )
    return {
        "steps_per_s": rate,
        "baseline_steps_per_s": base,
        "wall_steps_per_s": rate_wall,
        "wall_baseline_steps_per_s": base_wall,
        "max_abs_diff": agree,
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=1_000_000)
    parser.add_argument("--baseline-steps", type=int, default=3_000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()

    rng = np.random.default_rng(0)
    n = 10_000
    centres = rng.normal(0.0, 1.0, n)
    half_widths = rng.uniform(0.0, 1.0, n)
    relays = PreisachModel.from_relays(centres + half_widths, centres - half_widths)
    dimers = SpinDimerEnsemble.random(
        20000, width=2, spread=1, spin_coupling=2, seed=0
    ).to_preisach()
    inputs = reflected_walk(args.steps, 0.05, 4.0, seed=1)

    general = measure(relays, inputs, args.baseline_steps, args.repeats)
    paper = measure(dimers, inputs, args.baseline_steps, args.repeats)
    for name, res in (("random relays", general), ("equal-width dimers", paper)):
        print(
            f"{name:>20}: PreisachModel.apply {res['steps_per_s']:.3e} steps/s, "
            f"numpy baseline {res['baseline_steps_per_s']:.3e} steps/s, "
            f"ratio {res['steps_per_s'] / res['baseline_steps_per_s']:.0f}x, "
            f"max |difference| {res['max_abs_diff']:.1e} "
            f"(wall clock: {res['wall_steps_per_s']:.3e} vs {res['wall_baseline_steps_per_s']:.3e})"
        )
    summary = {
        "steps_per_s": general["steps_per_s"],
        "dimer_steps_per_s": paper["steps_per_s"],
        "baseline_steps_per_s": general["baseline_steps_per_s"],
        "ratio": general["steps_per_s"] / general["baseline_steps_per_s"],
        "dimer_baseline_steps_per_s": paper["baseline_steps_per_s"],
        "dimer_ratio": paper["steps_per_s"] / paper["baseline_steps_per_s"],
        "wall_steps_per_s": general["wall_steps_per_s"],
        "wall_dimer_steps_per_s": paper["wall_steps_per_s"],
        "n_relays": n,
        "n_steps": args.steps,
    }
    print(json.dumps(summary))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
