"""Disorder realizations side by side in the vector units (``one_pass_measurements_many``, the
lanes of ``oscillators/engines/_relay_lanes.py``) against the same realizations one after the
other (``one_pass_measurements``, the baseline), both measured in this run.

One measurement is the ensemble task's integration (the spectrum, the section and ``M_T`` in
one pass with the tangent flow, t ∈ [transient, t_end]) of ``LANES`` realizations of
``SpinDimerEnsemble.random(N, p=2, R=1, J=2, seed)`` at coupling C, the paper's ζ and Ω: CPU
seconds per realization (``time.process_time``), median of ``--repeats`` runs after one that
compiles. Printed per (N, C): both times, their ratio and whether every result (exponents,
switch count, section, ``M_T``) is bit for bit the same; the last line is one JSON object.

    python benchmarks/bench_lanes.py [--spins 1000 2000 5000 20000] [--coupling 2.9 4.0]
                                     [--t-end 20000] [--transient 1000] [--repeats 3]
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

import numpy as np

from analysis.dynamics.lyapunov import LANES
from analysis.experiments.ensemble import disorder_system, realization_seeds
from analysis.experiments.one_pass import one_pass_measurements, one_pass_measurements_many
from analysis.experiments.parameters import (
    DAMPING_RATIO,
    FREQUENCY,
    SEED,
    SPIN_COUPLING,
    SPREAD,
    WIDTH,
    WIDTH_SPREAD,
)


def _systems(spins: int, coupling: float) -> list:
    return [
        disorder_system(
            "dimers",
            spins,
            seed,
            coupling,
            WIDTH,
            SPREAD,
            SPIN_COUPLING,
            WIDTH_SPREAD,
            DAMPING_RATIO,
            FREQUENCY,
        )  # fmt: skip
        for seed in realization_seeds(SEED, spins, LANES)
    ]


def _fingerprint(measured: tuple) -> tuple:
    ly, q, v, m_t, window = measured
    return (ly.exponents.tobytes(), ly.n_switches, q.tobytes(), v.tobytes(), m_t, window)


def measure(spins: int, coupling: float, t_end: float, transient: float, repeats: int) -> dict:
    times: dict[str, list[float]] = {"one_by_one": [], "lanes": []}
    same = True
    for rep in range(repeats + 1):  # the first run compiles / loads the kernels
        systems = _systems(spins, coupling)
        t0 = time.process_time()
        alone = [one_pass_measurements(s, t_end, transient) for s in systems]
        t1 = time.process_time()
        systems = _systems(spins, coupling)
        t2 = time.process_time()
        together = one_pass_measurements_many(systems, t_end, transient)
        t3 = time.process_time()
        if rep:
            times["one_by_one"].append((t1 - t0) / LANES)
            times["lanes"].append((t3 - t2) / LANES)
        same &= all(
            _fingerprint(a) == _fingerprint(b) for a, b in zip(alone, together, strict=True)
        )
    med = {k: statistics.median(v) for k, v in times.items()}
    return {
        "spins": spins,
        "coupling": coupling,
        "seconds_per_realization": med,
        "speedup": med["one_by_one"] / med["lanes"],
        "bit_for_bit": bool(same),
        "mean_switches": float(np.mean([a[0].n_switches for a in alone])),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spins", type=int, nargs="+", default=[1000, 2000, 5000, 20000])
    ap.add_argument("--coupling", type=float, nargs="+", default=[2.9, 4.0])
    ap.add_argument("--t-end", type=float, default=20000.0)
    ap.add_argument("--transient", type=float, default=1000.0)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    rows = []
    for n in args.spins:
        for c in args.coupling:
            r = measure(n, c, args.t_end, args.transient, args.repeats)
            rows.append(r)
            s = r["seconds_per_realization"]
            print(
                f"N={n:6d} C={c:3.1f}  one by one {s['one_by_one']:.3f} s  lanes {s['lanes']:.3f} s"
                f"  ({r['speedup']:.2f}x)  bit for bit {r['bit_for_bit']}",
                flush=True,
            )
    print(json.dumps({"lanes": LANES, "t_end": args.t_end, "rows": rows}))


if __name__ == "__main__":
    main()
