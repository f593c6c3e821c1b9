"""Speed of the event-driven oscillator integrator (paper Table II parameters, C = 4.0).

Measures, for N = 20 000 spin dimers (seed 0): switches per second and seconds per 1000 time
units for a trajectory alone (Poincaré run, no sampling) and with the tangent flow (Lyapunov
spectrum); the same for the erf-play limit; and a baseline in the same run: scipy's solve_ivp
(DOP853, rtol = atol = 1e-10) with terminal events on the nearest thresholds of the same kind of
dimer system (smaller N; compared per switch). The last line is one JSON object.

Three figures with the tangent flow: ``switches_per_s_tangent`` (``lyapunov_spectrum`` with its
default QR every forcing period), ``switches_per_s_tangent_qr8`` (QR every 8 periods, the
ensemble tasks' cadence) and ``switches_per_s_tangent_kernel`` (the kernel alone, one engine
call, no QR). These five dimer measurements run interleaved (round-robin, 5 rounds, medians), so
that a slow spell of the shared VM affects them alike. The ``ns_*`` keys split a switch's cost
into kernel, tangent flow and QR loop; they are differences of medians, so on a noisy machine a
small one can come out negative.

General discrete Preisach models (:func:`general_preisach`): 10 000 relays with centres N(0, 1)
and half-widths U(0.5, 1.5) (seed 0, equal weights), C = 4, switches per second of the heap
kernel WITH the tangent flow (Lyapunov spectrum, median of 3 runs) against the generic
per-switch Python path (``engine_options={"method": "generic"}``) measured in the same run; and
the heap kernel on the dimers next to the nested O(1) kernel.

    python benchmarks/bench_oscillator.py [--spins 20000] [--time 2000] [--baseline-spins 2000]
        [--general-relays 10000] [--general-baseline-time 15] [--continuous-only]

Continuous operators (:func:`continuous_engine_figures`, also alone with ``--continuous-only``):
seconds per 1000 time units with the tangent flow of the erf play, PI with 10 plays, continuous
Preisach (grid 256 and Gaussian, the latter also with its Everett function by the 48-node
quadrature, the path before the bi-quintic table), the tanh play and the generic engine on the
grid-256 model, measured interleaved in one run, with ratios to the erf-play kernel.

``--gaussian-lyapunov T``: only ``lyapunov_spectrum`` of the Gaussian width-disorder model
(p = 2, R = 1, σ_r = 0.2, C = 4) to t = T, with the table and with the quadrature, seconds each
(:func:`gaussian_lyapunov_figures`).
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import time

import numpy as np
from scipy.integrate import solve_ivp

from analysis.dynamics.lyapunov import lyapunov_spectrum
from hysteresis.play import GeneralizedPlay
from hysteresis.preisach import PreisachModel
from hysteresis.spin_dimers import SpinDimerEnsemble
from oscillators import ForcedOscillator

ZETA, OMEGA, P, R, J, Q0, V0 = 0.05, 1.0, 2.0, 1.0, 2.0, -1.0, 0.1


def baseline(n_spins: int, c: float, t_end: float) -> tuple[int, float]:
    """solve_ivp with events, dimers switched by hand; returns (switches, seconds)."""
    ens = SpinDimerEnsemble.random(n_spins, P, R, J, seed=0)
    b1, b2 = ens.fields[:, 0], ens.fields[:, 1]
    alpha, beta = J - b1, -J - b2
    up = alpha <= Q0
    t, y, n = 0.0, np.array([Q0, V0]), 0
    start = time.perf_counter()
    while t < t_end:
        m = np.mean(np.where(up, 1.0, -1.0))
        nu = np.min(alpha[~up]) if np.any(~up) else np.inf
        nd = np.max(beta[up]) if np.any(up) else -np.inf

        def rhs(s, x, m=m):
            return [x[1], -2 * ZETA * x[1] - x[0] + math.cos(OMEGA * s) + c * m]

        def e_up(s, x, a=nu):
            return x[0] - a

        def e_dn(s, x, b=nd):
            return x[0] - b

        e_up.terminal = e_dn.terminal = True
        e_up.direction, e_dn.direction = 1, -1
        sol = solve_ivp(
            rhs, (t, t_end), y, method="DOP853", rtol=1e-10, atol=1e-10, events=[e_up, e_dn]
        )
        if sol.status != 1:
            break
        if sol.t_events[0].size:
            t, y = sol.t_events[0][0], sol.y_events[0][0]
            up[alpha == nu] = True
        else:
            t, y = sol.t_events[1][0], sol.y_events[1][0]
            up[beta == nd] = False
        n += 1
    return n, time.perf_counter() - start


def _median_rate(run, repeats: int = 3) -> tuple[float, int, float]:
    """Median over ``repeats`` of (switches/s, switches, seconds) of ``run() -> n_switches``."""
    rates = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        n = run()
        dt = time.perf_counter() - t0
        rates.append((n / dt, n, dt))
    rates.sort()
    return rates[len(rates) // 2]


def general_preisach(
    n_relays: int, c: float, t_run: float, baseline_time: float, dimers: ForcedOscillator
) -> dict:
    """Heap kernel (any relays) with the tangent flow vs the generic Python path, same run."""
    rng = np.random.default_rng(0)
    centre = rng.normal(0.0, 1.0, n_relays)
    half = rng.uniform(0.5, 1.5, n_relays)
    model = PreisachModel.from_relays(centre + half, centre - half)
    sysm = ForcedOscillator(model, c, ZETA, OMEGA)
    heap = {"method": "heap"}
    lyapunov_spectrum(sysm, 10.0, engine_options=heap)  # compile
    n_periods = int(round(t_run / (2 * math.pi / OMEGA)))

    def tangent() -> int:
        return lyapunov_spectrum(sysm, t_run, engine_options=heap).n_switches

    def trajectory() -> int:
        return sysm.poincare_section(n_periods + 1, engine_options=heap).n_switches

    def generic() -> int:
        opts = {"method": "generic"}
        return lyapunov_spectrum(sysm, baseline_time, engine_options=opts).n_switches

    def dimers_heap() -> int:
        return lyapunov_spectrum(dimers, t_run, engine_options=heap).n_switches

    rate, n_sw, dt = _median_rate(tangent)
    rate_traj, _, _ = _median_rate(trajectory)
    base, n_b, dt_b = _median_rate(generic)
    lyapunov_spectrum(dimers, 10.0, engine_options=heap)
    rate_dimers, _, _ = _median_rate(dimers_heap, 1)
    print(
        f"general Preisach, {n_relays} relays (half-widths U(0.5, 1.5)), C={c}, heap kernel: "
        f"{n_sw} switches in {dt:.3f} s = {rate:.3e} switches/s with tangent flow "
        f"({1000 * dt / t_run:.4f} s per 1000 tu), {rate_traj:.3e} switches/s trajectory"
    )
    print(
        f"  baseline generic Python path with tangent: {n_b} switches in {dt_b:.2f} s = "
        f"{base:.3e} switches/s; ratio (heap kernel / generic) = {rate / base:.0f}"
    )
    print(f"  heap kernel on the dimers (with tangent): {rate_dimers:.3e} switches/s")
    return {
        "general_preisach_relays": n_relays,
        "general_preisach_switches_per_s": rate,
        "general_preisach_trajectory_switches_per_s": rate_traj,
        "general_preisach_s_per_1000tu_tangent": 1000 * dt / t_run,
        "general_preisach_baseline_switches_per_s": base,
        "general_preisach_ratio": rate / base,
        "dimers_heap_switches_per_s_tangent": rate_dimers,
    }


def _interleaved(runs: dict, rounds: int = 5) -> dict:
    """Median wall time and the last result of every ``run()`` in ``runs``, measured in
    ``rounds`` round-robin rounds (A, B, C, A, B, C, ...), so that a slow spell of the shared
    machine hits every variant alike and their ratios stay meaningful."""
    times: dict = {name: [] for name in runs}
    last: dict = {}
    for _ in range(rounds):
        for name, run in runs.items():
            t0 = time.perf_counter()
            last[name] = run()
            times[name].append(time.perf_counter() - t0)
    return {name: (statistics.median(times[name]), last[name]) for name in runs}


def _dimer_figures(sysm, t_run: float, n_periods: int) -> dict:
    """The dimer measurements, interleaved: a trajectory (Poincaré run), the Lyapunov spectrum
    with QR every forcing period (the default) and every 8 periods (the ensemble tasks'
    cadence), and the kernel alone in one engine call without and with the tangent flow.
    Returns medians (seconds) and switch counts, and the per-switch split: kernel, tangent flow
    in the kernel, Python QR loop."""
    period = sysm.period
    state = sysm.initial_state(-1.0, 0.1)

    def one_call(tangent: bool) -> int:
        eng = sysm.engine(state)
        if tangent:
            eng.start_tangent(False)
        eng.advance(t_run)
        return eng.n_events

    m = _interleaved(
        {
            "trajectory": lambda: sysm.poincare_section(n_periods + 1).n_switches,
            "tangent": lambda: lyapunov_spectrum(sysm, t_run, progress=False),
            "tangent_qr8": lambda: lyapunov_spectrum(
                sysm, t_run, renormalize_dt=8 * period, progress=False
            ),
            "kernel": lambda: one_call(False),
            "kernel_tangent": lambda: one_call(True),
        }
    )
    dt_k, n_k = m["kernel"]
    dt_kt, n_kt = m["kernel_tangent"]
    dt_tan, res = m["tangent"]
    dt_8, r8 = m["tangent_qr8"]
    ns = 1e9
    return {
        "dt_traj": m["trajectory"][0],
        "sw_traj": m["trajectory"][1],
        "dt_tan": dt_tan,
        "result": res,
        "switches_per_s_tangent_kernel": n_kt / dt_kt,
        "switches_per_s_tangent_qr8": r8.n_switches / dt_8,
        "ns_trajectory_kernel": ns * dt_k / n_k,
        "ns_tangent_in_kernel": ns * (dt_kt / n_kt - dt_k / n_k),
        "ns_qr_every_period": ns * (dt_tan / res.n_switches - dt_kt / n_kt),
        "ns_qr_every_8_periods": ns * (dt_8 / r8.n_switches - dt_kt / n_kt),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spins", type=int, default=20000)
    ap.add_argument("--coupling", type=float, default=4.0)
    ap.add_argument("--time", type=float, default=2000.0, help="time units per measurement")
    ap.add_argument("--baseline-spins", type=int, default=2000)
    ap.add_argument("--baseline-time", type=float, default=30.0)
    ap.add_argument("--general-relays", type=int, default=10000)
    ap.add_argument("--general-baseline-time", type=float, default=15.0)
    ap.add_argument(
        "--gaussian-lyapunov",
        type=float,
        default=None,
        metavar="T",
        help="only lyapunov_spectrum of the Gaussian model to t = T, table vs quadrature",
    )
    ap.add_argument(
        "--continuous-only",
        action="store_true",
        help="only the continuous operators (continuous_engine_figures), as one JSON line",
    )
    args = ap.parse_args()
    c, t_run = args.coupling, args.time
    if args.gaussian_lyapunov is not None:
        print(json.dumps(gaussian_lyapunov_figures(c, args.gaussian_lyapunov)))
        return
    if args.continuous_only:
        print(json.dumps({"coupling": c, **continuous_engine_figures(c)}))
        return
    period = 2 * math.pi / OMEGA
    n_periods = int(round(t_run / period))
    t_run = n_periods * period

    sysm = ForcedOscillator(SpinDimerEnsemble.random(args.spins, P, R, J, seed=0), c, ZETA, OMEGA)
    sysm.poincare_section(3)  # compile
    lyapunov_spectrum(sysm, 10.0, progress=False)
    profile = _dimer_figures(sysm, t_run, n_periods)
    dt_traj, sw_traj = profile["dt_traj"], profile["sw_traj"]
    dt_tan, res = profile["dt_tan"], profile["result"]
    sw_tan = res.n_switches
    print(
        f"dimers N={args.spins}, C={c}: trajectory {sw_traj} switches in {dt_traj:.3f} s "
        f"= {sw_traj / dt_traj:.3e} switches/s, {1000 * dt_traj / t_run:.4f} s per 1000 tu"
    )
    print(
        f"  with tangent flow: {sw_tan} switches in {dt_tan:.3f} s = {sw_tan / dt_tan:.3e} "
        f"switches/s, {1000 * dt_tan / t_run:.4f} s per 1000 tu; lambda = {res.exponents}"
    )

    print(
        f"  kernel alone with tangent flow (no QR): "
        f"{profile['switches_per_s_tangent_kernel']:.3e} switches/s; "
        f"QR every 8 periods: {profile['switches_per_s_tangent_qr8']:.3e} switches/s"
    )
    print(
        "  per switch: "
        + ", ".join(f"{k} {v:.0f} ns" for k, v in profile.items() if k.startswith("ns_"))
    )

    lim = ForcedOscillator(GeneralizedPlay.erf(P, R), c, ZETA, OMEGA)
    t_lim = min(t_run, 500.0)
    lim.poincare_section(2)
    t0 = time.perf_counter()
    lim.poincare_section(int(t_lim / period) + 1)
    dt_lim = time.perf_counter() - t0
    lim_s = 1000 * dt_lim / (int(t_lim / period) * period)
    t0 = time.perf_counter()
    lres = lyapunov_spectrum(lim, t_lim, progress=False)
    dt_limt = time.perf_counter() - t0
    lim_tan_s = 1000 * dt_limt / t_lim
    print(
        f"erf-play limit: {lim_s:.3f} s per 1000 tu (trajectory), {lim_tan_s:.3f} s per 1000 tu "
        f"(tangent); lambda = {lres.exponents}"
    )

    n_b, dt_b = baseline(args.baseline_spins, c, args.baseline_time)
    base = n_b / dt_b
    ratio = (sw_tan / dt_tan) / base
    print(
        f"baseline solve_ivp+events, N={args.baseline_spins}: {n_b} switches in {dt_b:.2f} s = "
        f"{base:.3e} switches/s; ratio (kernel with tangent / baseline) = {ratio:.0f}"
    )
    general = general_preisach(args.general_relays, c, t_run, args.general_baseline_time, sysm)
    print(
        json.dumps(
            {
                "spins": args.spins,
                "coupling": c,
                "time_units": t_run,
                "switches_per_s": sw_traj / dt_traj,
                "switches_per_s_tangent": sw_tan / dt_tan,
                "switches_per_s_tangent_qr8": profile["switches_per_s_tangent_qr8"],
                "switches_per_s_tangent_kernel": profile["switches_per_s_tangent_kernel"],
                **{k: v for k, v in profile.items() if k.startswith("ns_")},
                "s_per_1000tu": 1000 * dt_traj / t_run,
                "s_per_1000tu_tangent": 1000 * dt_tan / t_run,
                "baseline_spins": args.baseline_spins,
                "baseline_switches_per_s": base,
                "ratio": ratio,
                "limit_s_per_1000tu": lim_s,
                "limit_tangent_s_per_1000tu": lim_tan_s,
                **general,
                **continuous_engine_figures(c, lim_tan_s),
            }
        )
    )


def continuous_engine_figures(c: float, erf_play_tangent_s: float | None = None) -> dict:
    """Seconds per 1000 time units WITH the tangent flow (``lyapunov_spectrum``, QR every
    period) of every continuous operator on the engine its contract selects, next to the
    compiled erf-play kernel measured in the same rounds (interleaved, median of 3; ratio =
    operator / erf play):

    * ``erf_play``: ``GeneralizedPlay.erf(p, R)`` (compiled play kernel), coupling ``c``;
    * ``pi10``: a 10-play Prandtl–Ishlinskii operator (widths 0.4 ... 4.0, equal weights 0.1,
      coupling 0.8 < 1/Σweights so that the walls stay stable);
    * ``continuous_preisach``: a continuous Preisach model tabulated on a 256 grid by
      ``from_density`` (density N(s; 0, R²)·N(r; p/2, 0.2²)), coupling ``c``, and
      ``continuous_preisach_gaussian``: ``ContinuousPreisachModel.gaussian(p, R, 0.2)``;
    * ``continuous_preisach_gaussian_quadrature``: the same Gaussian model with its compiled
      Everett function replaced by the 48-node Gauss–Legendre quadrature (kind 0, what the
      engine evaluated before the bi-quintic table; :func:`_quadrature_gaussian`);
    * ``tanh_play``: ``GeneralizedPlay`` with the user shape tanh, coupling 2;
    * ``continuous_preisach_generic``: the grid-256 model on the generic engine
      (``engine_options={"method": "generic"}``), the baseline.

    Run lengths differ (the generic engine is slow); each figure is normalised per 1000 tu.
    ``erf_play_tangent_s`` (the main run's figure) is only printed for comparison. The Gaussian
    model's figure is also given as ``gaussian_preisach_s_per_1000tu_tangent`` (issue 18's key).
    """
    from hysteresis import ContinuousPreisachModel, PrandtlIshlinskii, PreisachModel

    def density(a, b):
        r, s = 0.5 * (a - b), 0.5 * (a + b)
        width = np.exp(-0.5 * ((r - 0.5 * P) / 0.2) ** 2) / (0.2 * math.sqrt(2 * math.pi))
        return 0.5 * width * np.exp(-0.5 * (s / R) ** 2) / (R * math.sqrt(2 * math.pi))

    grid = PreisachModel.from_density(density, -7.0, 7.0, resolution=256)
    tanh = GeneralizedPlay(P, np.tanh, lambda w: 1.0 / np.cosh(w) ** 2)
    generic = {"method": "generic"}
    cases = {
        "erf_play": (GeneralizedPlay.erf(P, R), c, 1000.0, {}),
        "pi10": (PrandtlIshlinskii(np.linspace(0.4, 4.0, 10), np.full(10, 0.1)), 0.8, 1000.0, {}),
        "continuous_preisach": (grid, c, 200.0, {}),
        "continuous_preisach_gaussian": (ContinuousPreisachModel.gaussian(P, R, 0.2), c, 200.0, {}),
        "continuous_preisach_gaussian_quadrature": (_quadrature_gaussian(0.2), c, 200.0, {}),
        "tanh_play": (tanh, 2.0, 100.0, {}),
        "continuous_preisach_generic": (grid, c, 10.0, generic),
    }
    runs, engines = {}, {}
    for name, (operator, coupling, t_run, options) in cases.items():
        system = ForcedOscillator(operator, coupling, ZETA, OMEGA)
        engines[name] = type(system.engine(**options)).__name__
        if engines[name] == "ContinuousEngine":
            # the generic engine: seconds per time unit, a short run suffices
            t_run = min(t_run, 10.0)
            cases[name] = (operator, coupling, t_run, options)
        # compile (and warm caches) outside the timing
        lyapunov_spectrum(system, min(t_run, 10.0), engine_options=options, progress=False)

        def run(system=system, t_run=t_run, options=options):
            return lyapunov_spectrum(system, t_run, engine_options=options, progress=False)

        runs[name] = run
    timed = _interleaved(runs, rounds=3)
    base = 1000.0 * timed["erf_play"][0] / cases["erf_play"][2]
    figures = {}
    for name, (seconds, res) in timed.items():
        sec = 1000.0 * seconds / cases[name][2]
        figures[f"{name}_s_per_1000tu_tangent"] = sec
        figures[f"{name}_engine"] = engines[name]
        if name != "erf_play":
            figures[f"{name}_vs_erf_play"] = sec / base
        print(
            f"{name} ({engines[name]}): {sec:.4f} s per 1000 tu with tangent flow (median of 3, "
            f"{cases[name][2]:g} tu each) = {sec / base:.1f} x the erf-play kernel; "
            f"lambda = {np.round(res.exponents[:3], 4)}"
        )
    figures["gaussian_preisach_s_per_1000tu_tangent"] = figures[
        "continuous_preisach_gaussian_s_per_1000tu_tangent"
    ]
    figures["gaussian_preisach_vs_erf_play"] = figures["continuous_preisach_gaussian_vs_erf_play"]
    figures["gaussian_table_speedup_vs_quadrature"] = (
        figures["continuous_preisach_gaussian_quadrature_s_per_1000tu_tangent"]
        / figures["continuous_preisach_gaussian_s_per_1000tu_tangent"]
    )
    if erf_play_tangent_s is not None:
        print(f"  (erf-play kernel in the main run: {erf_play_tangent_s:.4f} s per 1000 tu)")
    return figures


def _quadrature_gaussian(width_spread: float):
    """``ContinuousPreisachModel.gaussian(p, R, width_spread)`` whose compiled Everett function
    (what the compiled engine integrates) is the 48-node quadrature, kind 0 — the engine's
    path before the bi-quintic table (its vectorised methods read the same attribute, its
    scalar fast paths keep the table: the two differ by <= 1e-12, immaterial for a timing)."""
    from hysteresis import ContinuousPreisachModel
    from hysteresis.preisach.gaussian import gaussian_everett

    model = ContinuousPreisachModel.gaussian(P, R, width_spread)
    model._compiled_everett = gaussian_everett(P, R, width_spread, 48).compiled()
    return model


def gaussian_lyapunov_figures(c: float, t_end: float, rounds: int = 3) -> dict:
    """Seconds of ``lyapunov_spectrum`` (default options) to ``t_end`` of the Gaussian
    width-disorder model (p, R, σ_r = 0.2) at coupling ``c``: the bi-quintic table and the
    48-node quadrature (:func:`_quadrature_gaussian`), interleaved, median of ``rounds``."""
    from hysteresis import ContinuousPreisachModel

    runs = {}
    for name, model in (
        ("table", ContinuousPreisachModel.gaussian(P, R, 0.2)),
        ("quadrature", _quadrature_gaussian(0.2)),
    ):
        system = ForcedOscillator(model, c, ZETA, OMEGA)
        lyapunov_spectrum(system, 10.0, progress=False)  # compile outside the timing

        def run(system=system):
            return lyapunov_spectrum(system, t_end, progress=False)

        runs[name] = run
    timed = _interleaved(runs, rounds=rounds)
    figures = {"coupling": c, "t_end": t_end}
    for name, (seconds, res) in timed.items():
        figures[f"gaussian_lyapunov_{name}_s"] = seconds
        figures[f"gaussian_lyapunov_{name}_exponents"] = [float(x) for x in res.exponents[:3]]
        print(f"lyapunov_spectrum to t = {t_end:g}, Gaussian model ({name}): {seconds:.2f} s")
    figures["speedup"] = timed["quadrature"][0] / timed["table"][0]
    return figures


if __name__ == "__main__":
    main()
