"""Composite operators coupled to the oscillator: a sum's Poincaré section against its parts'.

For each composite the time of ``system.poincare_section(--periods)`` (after a warm-up call
that compiles and leaves the transient) is measured for the sum and, in the same run, for each
part alone at the same coupling; the ratio ``t(sum) / Σ t(part)`` is the figure of merit (the
issue's target: within 2). The median of ``--repeats`` runs, interleaved so that a drift of the
machine's load hits all alike. Cases:

* ``mixed``: ``0.5 * erf play + 0.5 * Preisach model of --relays random relays`` (centres
  N(0, R²), half-widths N(p/2, σ_r²), the registry's ``preisach`` with ``--width-spread``),
  at C = 2: the compiled continuous engine with the relays as switching events (parts: the play
  kernel and the relay kernel);
* ``plays``: ``0.7 * PI (5 plays) + 0.3 * erf play`` at C = 1: one set of shaped plays on the
  compiled continuous engine (parts: the compiled continuous engine and the play kernel);
* ``mixed-python``: the mixed sum on the generic (Python, ``solve_ivp``) engine
  (``engine_options={"method": "generic"}``), over ``--python-periods`` periods only: what the
  compiled path saves.

    python benchmarks/bench_composites.py [--periods 200] [--repeats 5] [--relays 2000]

The last line is one JSON object with the times per period and the ratios.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
import warnings

from analysis.experiments.models import build_operator
from oscillators import ForcedOscillator
from oscillators.engines import GenericEngineWarning


def period_time(system: ForcedOscillator, periods: int, options: dict | None = None) -> float:
    """Seconds per forcing period of one Poincaré section (compiled and warmed up before)."""
    start = time.perf_counter()
    system.poincare_section(periods, engine_options=options)
    return (time.perf_counter() - start) / periods


def compare(name: str, total, parts, coupling: float, periods: int, repeats: int) -> dict:
    """Median time per period of the sum and of each part, and the ratio."""
    systems = [ForcedOscillator(op, coupling=coupling) for op in (total, *parts)]
    for s in systems:
        s.poincare_section(5, 20)  # compile, then run the same transient as measured below
    samples: list[list[float]] = [[] for _ in systems]
    for _ in range(repeats):
        for i, s in enumerate(systems):
            samples[i].append(period_time(s, periods))
    med = [statistics.median(x) for x in samples]
    ratio = med[0] / sum(med[1:])
    print(
        f"{name:>8}: sum {med[0] * 1e3:.3f} ms/period, parts "
        + " + ".join(f"{m * 1e3:.3f}" for m in med[1:])
        + f" ms/period ({systems[0].engine_description}); ratio {ratio:.1f}"
    )
    return {"sum_s_per_period": med[0], "parts_s_per_period": med[1:], "ratio": ratio}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--periods", type=int, default=200)
    parser.add_argument("--python-periods", type=int, default=3)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--relays", type=int, default=2000)
    parser.add_argument("--width-spread", type=float, default=0.5)
    args = parser.parse_args()

    erf = build_operator("erf-play")
    relays = build_operator("preisach", spins=args.relays, width_spread=args.width_spread, seed=1)
    pi = build_operator("pi", plays=5)
    mixed = compare("mixed", 0.5 * erf + 0.5 * relays, (erf, relays), 2.0, args.periods,
                    args.repeats)  # fmt: skip
    plays = compare("plays", 0.7 * pi + 0.3 * erf, (pi, erf), 0.8, args.periods, args.repeats)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GenericEngineWarning)
        system = ForcedOscillator(0.5 * erf + 0.5 * relays, coupling=2.0)
    generic = {"method": "generic"}
    system.poincare_section(1, engine_options=generic)
    python = statistics.median(
        period_time(system, args.python_periods, generic) for _ in range(max(1, args.repeats // 2))
    )
    speedup = python / mixed["sum_s_per_period"]
    print(
        f"{'python':>8}: the mixed sum on the generic engine {python * 1e3:.1f} ms/period, "
        f"{speedup:.0f}x the compiled path"
    )
    print(
        json.dumps(
            {
                "mixed": mixed,
                "plays": plays,
                "mixed_python_s_per_period": python,
                "compiled_over_python": speedup,
                "n_relays": args.relays,
                "periods": args.periods,
            }
        )
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
