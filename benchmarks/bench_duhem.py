"""Bouc–Wen and Jiles–Atherton coupled to the oscillator: the compiled Duhem engine against the
erf-play kernel.

For each case the time of ``system.poincare_section(--periods)`` (after a warm-up call that
compiles and leaves the transient) is measured, and in the same run the erf play's
(``GeneralizedPlay.erf``, the registry's ``erf-play``, on the play kernel) at the same
coupling; the ratio ``t(Duhem) / t(erf play)`` per forcing period is the figure of merit (the
issue's target: within 5). The median of ``--repeats`` runs, interleaved so that a drift of the
machine's load hits all alike. Cases (ζ = 0.05, Ω = 1):

* ``bouc-wen n=1``, ``bouc-wen n=1.5``, ``bouc-wen n=2``: ``BoucWen(1, 0.5, 0.3, n)`` at
  ``C = −0.8`` (the classic oscillator ``q'' + 2ζq' + q + 0.8·z = cos t``); ``n = 1.5`` pays
  for the graded steps at the kink ``z = 0``;
* ``jiles-atherton``: ``JilesAtherton(ms=1, a=0.5, k=0.4, c=0.2, alpha=0.1)`` at ``C = 0.5``
  (one implicit solve of the output map per right-hand side, warm-started at the linear
  prediction from the previous one);
* ``bouc-wen python``: the Bouc–Wen oscillator (n = 1) on the generic engine
  (``engine_options={"method": "generic"}``), over ``--python-periods`` periods: what the
  compiled path saves.

    python benchmarks/bench_duhem.py [--periods 200] [--repeats 5] [--python-periods 3]
                                     [--clock wall|cpu]

``--clock cpu`` times with the process's CPU time (``time.process_time``) instead of the wall
clock: on a machine shared with other jobs the wall-clock ratio drifts with their load
(measured 4.2–5.2 for one build), the CPU-time one much less.

The last line is one JSON object with the times per period and the ratios.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

from analysis.experiments.models import build_operator
from hysteresis import BoucWen, JilesAtherton
from oscillators import ForcedOscillator

ZETA, OMEGA = 0.05, 1.0


CLOCKS = {"wall": time.perf_counter, "cpu": time.process_time}
clock = time.perf_counter


def period_time(system: ForcedOscillator, periods: int, options: dict | None = None) -> float:
    """Seconds per forcing period of one Poincaré section (compiled and warmed up before)."""
    start = clock()
    system.poincare_section(periods, engine_options=options)
    return (clock() - start) / periods


def cases() -> dict[str, tuple]:
    """name -> (operator, coupling)."""
    return {
        "bouc-wen n=1": (BoucWen(1.0, 0.5, 0.3, 1.0), -0.8),
        "bouc-wen n=1.5": (BoucWen(1.0, 0.5, 0.3, 1.5), -0.8),
        "bouc-wen n=2": (BoucWen(1.0, 0.5, 0.3, 2.0), -0.8),
        "jiles-atherton": (JilesAtherton(ms=1.0, a=0.5, k=0.4, c=0.2, alpha=0.1), 0.5),
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--periods", type=int, default=200)
    parser.add_argument("--python-periods", type=int, default=3)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--clock", choices=sorted(CLOCKS), default="wall")
    args = parser.parse_args()
    global clock
    clock = CLOCKS[args.clock]

    erf = build_operator("erf-play")
    pairs = {}
    for name, (op, coupling) in cases().items():
        system = ForcedOscillator(op, coupling=coupling, damping_ratio=ZETA, frequency=OMEGA)
        baseline = ForcedOscillator(erf, coupling=coupling, damping_ratio=ZETA, frequency=OMEGA)
        pairs[name] = (system, baseline)
    for system, baseline in pairs.values():
        system.poincare_section(5, 20)  # compile, then run the same transient as measured
        baseline.poincare_section(5, 20)
    samples = {name: ([], []) for name in pairs}
    for _ in range(args.repeats):
        for name, (system, baseline) in pairs.items():
            samples[name][0].append(period_time(system, args.periods))
            samples[name][1].append(period_time(baseline, args.periods))
    result: dict = {"periods": args.periods, "repeats": args.repeats, "clock": args.clock}
    for name, (system, _) in pairs.items():
        duhem = statistics.median(samples[name][0])
        play = statistics.median(samples[name][1])
        ratio = duhem / play
        print(
            f"{name:>15}: {duhem * 1e6:.0f} µs/period ({system.engine_description}), erf play "
            f"{play * 1e6:.0f} µs/period; ratio {ratio:.2f}"
        )
        result[name] = {"s_per_period": duhem, "erf_play_s_per_period": play, "ratio": ratio}
    system = pairs["bouc-wen n=1"][0]
    generic = {"method": "generic"}
    system.poincare_section(1, engine_options=generic)
    python = statistics.median(
        period_time(system, args.python_periods, generic) for _ in range(max(1, args.repeats // 2))
    )
    speedup = python / result["bouc-wen n=1"]["s_per_period"]
    print(
        f"{'python':>15}: Bouc–Wen on the generic engine {python * 1e3:.1f} ms/period, "
        f"{speedup:.0f}x the compiled path"
    )
    result["bouc_wen_python_s_per_period"] = python
    result["compiled_over_python"] = speedup
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
