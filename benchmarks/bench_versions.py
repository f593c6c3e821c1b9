"""Two checkouts of this project measured against each other in the same run.

Runs one measurement alternately in two source trees, ``pairs`` times, each in a fresh process
with that tree first on ``PYTHONPATH``, and prints the medians and the new/old ratios.
Alternating pairs keep the ratio meaningful on a shared machine whose speed drifts.

* ``--what relay`` (default): N = 20 000 dimers, seed 0, C = 4, 300 forcing periods from the
  paper's initial condition; switches per second of the trajectory (engine, no tangent flow),
  the kernel with the tangent flow (one engine call, no QR), and ``lyapunov_spectrum`` with QR
  every 8 periods and every period.
* ``--what play``: the erf-play limit at C = 2.92 (the basin benchmark's system); starts per
  second of ``poincare_section`` over 100 periods from 40 seeded starts in [-3, 3]² (a basin
  map's unit of work), and time units per second of ``lyapunov_spectrum`` to t = 2·10⁴.
* ``--what continuous``: the compiled continuous engine on the systems of
  ``bench_oscillator.py --continuous-only`` (ζ = 0.05, Ω = 1): time units per second of
  ``lyapunov_spectrum`` (tangent flow, QR every period) of the 10-play Prandtl–Ishlinskii
  operator (C = 0.8) to t = 5000, of the grid-256 continuous Preisach model and of the Gaussian
  width-disorder model (p = 2, R = 1, σ_r = 0.2; C = 4) to t = 3000 each, and of the PI
  operator's trajectory without tangent flow (``poincare_section``, 1000 periods); each the
  best of 3 runs in the child (runs of ~1 s: a 0.1 s run measured the shared machine's noise).

    git worktree add /tmp/old <commit>
    python benchmarks/bench_versions.py /tmp/old . [--pairs 5] [--what play] [--clock cpu]

The last line is one JSON object.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path


def _clock() -> float:
    """The child's clock: wall time, or with ``--clock cpu`` this process's CPU time (on a
    machine shared with other jobs the wall time also counts the waits for a core)."""
    return (
        time.process_time()
        if os.environ.get("BENCH_VERSIONS_CLOCK") == "cpu"
        else time.perf_counter()
    )


KEYS = {
    "relay": ("trajectory", "kernel_tangent", "lyapunov_qr8", "lyapunov_qr1"),
    "play": ("sections", "lyapunov"),
    "continuous": ("pi_section", "pi_lyapunov", "grid_lyapunov", "gaussian_lyapunov"),
}


def measure_play() -> dict:
    """Starts per second and Lyapunov time units per second of the erf play (child's job)."""
    import numpy as np

    from analysis import lyapunov_spectrum
    from hysteresis import GeneralizedPlay
    from oscillators import ForcedOscillator

    system = ForcedOscillator(GeneralizedPlay.erf(2.0, 1.0), 2.92)
    system.poincare_section(2, 0, 0.0, 0.0)  # compile
    lyapunov_spectrum(system, 20.0)
    starts = np.random.default_rng(1).uniform(-3.0, 3.0, size=(40, 2))
    t0 = _clock()
    for q0, v0 in starts:
        system.poincare_section(100, 0, q0, v0)
    out = {"sections": len(starts) / (_clock() - t0)}
    t0 = _clock()
    lyapunov_spectrum(system, 20000.0)
    out["lyapunov"] = 20000.0 / (_clock() - t0)
    return out


def measure_continuous() -> dict:
    """Time units per second of the compiled continuous engine (child's job)."""
    import math

    import numpy as np

    from analysis import lyapunov_spectrum
    from hysteresis import ContinuousPreisachModel, PrandtlIshlinskii, PreisachModel
    from oscillators import ForcedOscillator

    def density(a, b):  # bench_oscillator.continuous_engine_figures's grid-256 model
        r, s = 0.5 * (a - b), 0.5 * (a + b)
        width = np.exp(-0.5 * ((r - 1.0) / 0.2) ** 2) / (0.2 * math.sqrt(2 * math.pi))
        return 0.5 * width * np.exp(-0.5 * s**2) / math.sqrt(2 * math.pi)

    pi = ForcedOscillator(PrandtlIshlinskii(np.linspace(0.4, 4.0, 10), np.full(10, 0.1)), 0.8)
    grid = ForcedOscillator(PreisachModel.from_density(density, -7.0, 7.0, resolution=256), 4.0)
    gauss = ForcedOscillator(ContinuousPreisachModel.gaussian(2.0, 1.0, 0.2), 4.0)
    for system in (pi, grid, gauss):
        lyapunov_spectrum(system, 10.0, progress=False)  # compile

    def best(run) -> float:
        seconds = []
        for _ in range(3):
            t0 = _clock()
            run()
            seconds.append(_clock() - t0)
        return min(seconds)

    out = {
        "pi_section": 1000 * 2.0 * math.pi / best(lambda: pi.poincare_section(1000, 0, 0.4, -1.1))
    }
    for key, system, t_run in (
        ("pi_lyapunov", pi, 5000.0),
        ("grid_lyapunov", grid, 3000.0),
        ("gaussian_lyapunov", gauss, 3000.0),
    ):
        out[key] = t_run / best(lambda s=system, t=t_run: lyapunov_spectrum(s, t, progress=False))
    return out


def measure() -> dict:
    """Switches per second of this process's checkout (the child's job)."""
    import math

    from analysis import lyapunov_spectrum  # public path: the same in every version
    from hysteresis.spin_dimers import SpinDimerEnsemble
    from oscillators import ForcedOscillator

    sysm = ForcedOscillator(SpinDimerEnsemble.random(20000, 2.0, 1.0, 2.0, seed=0), 4.0, 0.05, 1.0)
    lyapunov_spectrum(sysm, 20.0)  # compile
    period = 2 * math.pi
    t_run = 300 * period
    out = {}
    for tangent, key in ((False, "trajectory"), (True, "kernel_tangent")):
        eng = sysm.engine(sysm.initial_state(-1.0, 0.1))
        if tangent:
            eng.start_tangent(False)
        t0 = _clock()
        eng.advance(t_run)
        out[key] = eng.n_events / (_clock() - t0)
    for dt, key in ((8 * period, "lyapunov_qr8"), (period, "lyapunov_qr1")):
        t0 = _clock()
        res = lyapunov_spectrum(sysm, t_run, renormalize_dt=dt)
        out[key] = res.n_switches / (_clock() - t0)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old", type=Path, help="source tree of the old version")
    ap.add_argument("new", type=Path, help="source tree of the new version")
    ap.add_argument("--pairs", type=int, default=5)
    ap.add_argument("--what", choices=sorted(KEYS), default="relay")
    ap.add_argument("--clock", choices=("wall", "cpu"), default="wall")
    args = ap.parse_args()
    keys = KEYS[args.what]
    rates: dict = {"old": {k: [] for k in keys}, "new": {k: [] for k in keys}}
    ratios: dict = {k: [] for k in keys}
    for _ in range(args.pairs):
        pair = {}
        for name, tree in (("old", args.old), ("new", args.new)):
            env = dict(os.environ, PYTHONPATH=str(tree.resolve()), BENCH_VERSIONS_CLOCK=args.clock)
            child = subprocess.run(
                [sys.executable, __file__, "--child", args.what],
                env=env,
                cwd=tree,
                capture_output=True,
                text=True,
                check=True,
            )
            pair[name] = json.loads(child.stdout.strip().splitlines()[-1])
            for k in keys:
                rates[name][k].append(pair[name][k])
        for k in keys:
            ratios[k].append(pair["new"][k] / pair["old"][k])
    unit = "switches/s" if args.what == "relay" else "per s"
    summary = {}
    for k in keys:
        old, new = statistics.median(rates["old"][k]), statistics.median(rates["new"][k])
        r = sorted(ratios[k])
        print(
            f"{k}: old {old:.3e}, new {new:.3e} {unit}; new/old per pair "
            + ", ".join(f"{x:.2f}" for x in r)
        )
        summary[k] = {"old": old, "new": new, "ratio_median": statistics.median(r)}
    head = {"benchmark": "versions", "what": args.what, "pairs": args.pairs, "clock": args.clock}
    print(json.dumps({**head, **summary}))


if __name__ == "__main__":
    if sys.argv[1:2] == ["--child"]:
        child = {"play": measure_play, "continuous": measure_continuous, "relay": measure}
        print(json.dumps(child[sys.argv[2] if sys.argv[2:] else "relay"]()))
    else:
        main()
