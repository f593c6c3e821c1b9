"""Speed and memory of the random-field Ising model (hysteresis.rfim), alone and coupled.

Figures, all measured in one run:

* ``loop``: a full hysteresis loop (from all down at −∞ to +∞ and back: every spin flips twice)
  of an ``L³`` periodic lattice (default L = 100, 10⁶ spins, R = 2.6, J = 1, seed 0) with
  ``apply`` (one relaxation at each end: no merge of the sorted lists), in ``--loop-steps``
  inputs each way (quasi-static: avalanches of their natural sizes), and with ``avalanches``
  (every avalanche's trigger and size recorded): spin flips per second (median of
  ``--repeats``), the number of avalanches, the build time, and memory
  per spin (the operator's arrays with its workspace, a state, the growth of the process's peak
  resident memory over the build and the loops, the kernels compiled before);
* ``baseline``: the same loop on an ``Lb³`` lattice (default 20³) followed by a plain numpy
  brute force — at each of ``--baseline-steps`` inputs of a sweep up and down, every unstable
  spin flipped until none is left (the tests' reference) — against the kernel on that lattice
  and inputs; ratios kernel/baseline on the small lattice and for the 10⁶-spin loop;
* ``coupled``: the oscillator (ζ = 0.05, Ω = 1, C = ``--coupling``, start q = −1, v = 0.1)
  coupled to the 10⁶-spin lattice by the compiled switching engine (``compiled_switching()``:
  the spins' sorted lists, the relay kernel's hops; every avalanche one event) over
  ``--coupled-time`` time units after ``--coupled-transient`` (by then the oscillation sweeps
  the whole loop), spin flips per second (``n_events``) and avalanches per second, median of
  ``--repeats`` consecutive windows; the relay engine's Python reference path
  (``method="generic"``) over ``--reference-time`` from the same start, for scale; next to the
  compiled relay kernel on 10⁶ spin dimers (``SpinDimerEnsemble.random``, p = 2, R = 1, J = 2,
  the paper's, nested plan) over ``--dimer-time``: relay switches per second (a dimer's two
  spins flip as one switch), median of ``--repeats`` windows. The issue's target is a lattice
  at >= 1/3 of the kernel's switches per second; the operator's own full loop (``loop``, no
  oscillator) is the ceiling of the coupled rate.

    python benchmarks/bench_rfim.py [--side 100] [--disorder 2.6] [--repeats 3] [--loop-steps 2000]
        [--baseline-side 20] [--baseline-steps 400] [--coupling 2.9] [--coupled-transient 30]
        [--coupled-time 3] [--reference-time 0.5] [--dimer-time 20]

The last line is one JSON object with every figure.
"""

from __future__ import annotations

import argparse
import json
import resource
import statistics
import time

import numpy as np

from hysteresis.rfim import RandomFieldIsing
from hysteresis.spin_dimers import SpinDimerEnsemble
from oscillators import ForcedOscillator

ZETA, OMEGA = 0.05, 1.0
#: an input beyond every threshold (|f| < 10 R for 10⁶ Gaussian fields, |J·n| <= 6)
FAR = 1e3


def peak_rss_mb() -> float:
    """Peak resident memory of this process so far (Linux: ru_maxrss in KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def full_loop(model: RandomFieldIsing, repeats: int, steps: int) -> dict:
    """Flips per second of ``apply([+FAR, -FAR])`` from all down (2N flips), median of
    ``repeats``; of a quasi-static loop (``steps`` inputs from −8 to 8 and back, then ±FAR:
    2N flips in avalanches of their natural sizes); and of the first loop with every
    avalanche recorded."""
    bottom = model.initial_state(-FAR)
    model.apply([FAR, -FAR], bottom)  # compile
    ramp = np.linspace(-8.0, 8.0, steps)
    stepped = np.concatenate([ramp, [FAR], ramp[::-1], [-FAR]])
    n = model.n_spins
    plain, quasi, recorded = [], [], []
    count = 0
    for _ in range(repeats):
        t0 = time.perf_counter()
        model.apply([FAR, -FAR], bottom)
        plain.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        model.apply(stepped, bottom)
        quasi.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        _, sizes, _ = model.avalanches([FAR, -FAR], bottom)
        recorded.append(time.perf_counter() - t0)
        assert int(sizes.sum()) == 2 * n
        count = sizes.size
    dt, dt_rec = statistics.median(plain), statistics.median(recorded)
    return {
        "loop_s": dt,
        "flips_per_s": 2 * n / dt,
        "flips_per_s_stepped": 2 * n / statistics.median(quasi),
        "loop_steps": steps,
        "flips_per_s_recorded": 2 * n / dt_rec,
        "avalanches_per_loop": count,
    }


def brute_force_rate(model: RandomFieldIsing, inputs: np.ndarray) -> tuple[float, int]:
    """(flips per second, flips) of plain numpy relaxation along ``inputs`` from all down."""
    e, f, j = model.edges(), np.asarray(model.fields), model.spin_coupling
    s = -np.ones(model.n_spins, dtype=np.int64)
    flips = 0
    t0 = time.perf_counter()
    for u in inputs:
        while True:
            n = np.zeros(s.size, dtype=np.int64)
            np.add.at(n, e[:, 0], s[e[:, 1]])
            np.add.at(n, e[:, 1], s[e[:, 0]])
            bad = ((u + (f + j * n)) >= 0.0) != (s > 0)
            k = int(bad.sum())
            if not k:
                break
            s[bad] = -s[bad]
            flips += k
    return flips / (time.perf_counter() - t0), flips


def baseline(side: int, disorder: float, steps: int) -> dict:
    """The brute force and the kernel on the same small lattice and input sweep."""
    model = RandomFieldIsing.lattice((side,) * 3, disorder, seed=0)
    half = np.linspace(-8.0, 8.0, steps // 2)
    inputs = np.concatenate([[-FAR], half, half[::-1], [-FAR]])
    rate_bf, flips = brute_force_rate(model, inputs)
    model.apply(inputs)  # compile
    t0 = time.perf_counter()
    y, _ = model.apply(inputs)
    dt = time.perf_counter() - t0
    return {
        "baseline_side": side,
        "baseline_flips": flips,
        "baseline_flips_per_s": rate_bf,
        "kernel_small_flips_per_s": flips / dt,
        "ratio_small": flips / dt / rate_bf,
    }


def coupled(
    model: RandomFieldIsing, c: float, transient: float, t_run: float, repeats: int
) -> dict:
    """Spin flips and avalanches per second of the coupled lattice (compiled switching engine),
    median of ``repeats`` consecutive windows of ``t_run``."""
    eng = ForcedOscillator(model, c, ZETA, OMEGA).engine()
    eng.advance(np.array([transient]))
    rates, cpu_rates, av_rates, flips, wall, cpu = [], [], [], 0, 0.0, 0.0
    for k in range(repeats):
        n0, a0 = eng.n_events, len(eng.records()["switches"])
        t0, c0 = time.perf_counter(), time.process_time()
        eng.advance(np.array([transient + (k + 1) * t_run]), record=True)
        dt, dc = time.perf_counter() - t0, time.process_time() - c0
        n_av = len(eng.records()["switches"]) - a0
        flips += eng.n_events - n0
        wall, cpu = wall + dt, cpu + dc
        rates.append((eng.n_events - n0) / dt)
        cpu_rates.append((eng.n_events - n0) / dc)
        av_rates.append(n_av / dt)
    return {
        "coupled_method": eng.method,
        "coupled_flips": flips,
        "coupled_flips_per_s": statistics.median(rates),
        "coupled_flips_per_cpu_s": statistics.median(cpu_rates),
        # the windows differ in activity (a quiet stretch of the orbit flips 20-40x fewer spins
        # than a sweep through the loop): all flips over all the time is the rate a run sees
        "coupled_flips_per_s_overall": flips / wall,
        "coupled_flips_per_cpu_s_overall": flips / cpu,
        "coupled_avalanches_per_s": statistics.median(av_rates),
    }


def reference(model: RandomFieldIsing, c: float, t_run: float) -> dict:
    """Spin flips per second of the relay engine's Python reference path (``Σ|ΔM|·N/2``)."""
    eng = ForcedOscillator(model, c, ZETA, OMEGA).engine(method="generic")
    t0 = time.perf_counter()
    eng.advance(np.array([t_run]), record=True)
    dt = time.perf_counter() - t0
    jumps = eng.records()["switches"]["jump"]
    return {"reference_flips_per_s": float(np.abs(jumps).sum()) * model.n_spins / 2 / dt}


def dimer_kernel(n_spins: int, c: float, t_run: float, repeats: int) -> dict:
    """Relay switches per second of the compiled kernel on ``n_spins`` spin dimers, median of
    ``repeats`` consecutive windows of ``t_run``."""
    ens = SpinDimerEnsemble.random(n_spins, 2.0, 1.0, 2.0, seed=0)
    eng = ForcedOscillator(ens, c, ZETA, OMEGA).engine()
    eng.advance(np.array([1.0]))  # plan and compile
    rates, cpu_rates = [], []
    for k in range(repeats):
        n0 = eng.n_events
        t0, c0 = time.perf_counter(), time.process_time()
        eng.advance(np.array([1.0 + (k + 1) * t_run]))
        rates.append((eng.n_events - n0) / (time.perf_counter() - t0))
        cpu_rates.append((eng.n_events - n0) / (time.process_time() - c0))
    return {
        "dimer_method": eng.method,
        "dimer_switches_per_s": statistics.median(rates),
        "dimer_switches_per_cpu_s": statistics.median(cpu_rates),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--side", type=int, default=100)
    ap.add_argument("--disorder", type=float, default=2.6)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--loop-steps", type=int, default=2000)
    ap.add_argument("--baseline-side", type=int, default=20)
    ap.add_argument("--baseline-steps", type=int, default=400)
    ap.add_argument("--coupling", type=float, default=2.9)
    ap.add_argument("--coupled-transient", type=float, default=30.0)
    ap.add_argument("--coupled-time", type=float, default=3.0)
    ap.add_argument("--reference-time", type=float, default=0.5)
    ap.add_argument("--dimer-time", type=float, default=20.0)
    args = ap.parse_args()

    full_loop(RandomFieldIsing.lattice((8, 8, 8), args.disorder, seed=0), 1, 10)  # compile first
    rss0 = peak_rss_mb()
    t0 = time.perf_counter()
    model = RandomFieldIsing.lattice((args.side,) * 3, args.disorder, seed=0)
    build = time.perf_counter() - t0
    n = model.n_spins
    loop = full_loop(model, args.repeats, args.loop_steps)
    state = model.initial_state(0.0)
    memory = {
        "operator_bytes_per_spin": model.nbytes / n,
        "state_bytes_per_spin": state.nbytes / n,
        "peak_rss_mb_delta_per_spin_bytes": (peak_rss_mb() - rss0) * 2**20 / n,
    }
    print(
        f"lattice {args.side}³ = {n} spins, R = {args.disorder}: built in {build:.2f} s; full "
        f"loop {loop['loop_s']:.3f} s = {loop['flips_per_s']:.3e} flips/s "
        f"({loop['flips_per_s_stepped']:.3e} in {args.loop_steps} steps each way, "
        f"{loop['flips_per_s_recorded']:.3e} recording {loop['avalanches_per_loop']} "
        f"avalanches); memory per spin: operator {memory['operator_bytes_per_spin']:.2f} B, "
        f"state {memory['state_bytes_per_spin']:.3f} B, peak RSS growth "
        f"{memory['peak_rss_mb_delta_per_spin_bytes']:.1f} B"
    )
    base = baseline(args.baseline_side, args.disorder, args.baseline_steps)
    base["ratio_loop"] = loop["flips_per_s"] / base["baseline_flips_per_s"]
    print(
        f"baseline numpy brute force on {args.baseline_side}³: "
        f"{base['baseline_flips_per_s']:.3e} flips/s; kernel there "
        f"{base['kernel_small_flips_per_s']:.3e} (x{base['ratio_small']:.0f}); the 10⁶ loop "
        f"x{base['ratio_loop']:.0f}"
    )
    cpl = coupled(model, args.coupling, args.coupled_transient, args.coupled_time, args.repeats)
    cpl.update(reference(model, args.coupling, args.reference_time))
    print(
        f"coupled (C = {args.coupling}, {cpl['coupled_method']} switching engine): "
        f"{cpl['coupled_flips']} flips, {cpl['coupled_flips_per_s']:.3e} flips/s, "
        f"{cpl['coupled_avalanches_per_s']:.3e} avalanches/s (Python reference path "
        f"{cpl['reference_flips_per_s']:.3e} flips/s; the operator's own loop "
        f"{loop['flips_per_s']:.3e})"
    )
    dim = dimer_kernel(n, args.coupling, args.dimer_time, args.repeats)
    ratio = cpl["coupled_flips_per_s"] / dim["dimer_switches_per_s"]
    ratio_cpu = cpl["coupled_flips_per_cpu_s"] / dim["dimer_switches_per_cpu_s"]
    ratio_overall = cpl["coupled_flips_per_cpu_s_overall"] / dim["dimer_switches_per_cpu_s"]
    print(
        f"relay kernel ({dim['dimer_method']}) on {n} dimer spins: "
        f"{dim['dimer_switches_per_s']:.3e} switches/s; lattice flips/s over kernel "
        f"switches/s = {ratio:.4f} (target >= 1/3); per CPU second "
        f"{cpl['coupled_flips_per_cpu_s']:.3e} / {dim['dimer_switches_per_cpu_s']:.3e} = "
        f"{ratio_cpu:.4f}; all the coupled windows' flips over their CPU time "
        f"{cpl['coupled_flips_per_cpu_s_overall']:.3e}: {ratio_overall:.4f}"
    )
    print(
        json.dumps(
            {
                "spins": n,
                "side": args.side,
                "disorder": args.disorder,
                "coupling": args.coupling,
                "build_s": build,
                **loop,
                **memory,
                **base,
                **cpl,
                **dim,
                "coupled_over_kernel": ratio,
                "coupled_over_kernel_cpu": ratio_cpu,
                "coupled_over_kernel_cpu_overall": ratio_overall,
            }
        )
    )


if __name__ == "__main__":
    main()
