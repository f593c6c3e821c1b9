"""Exact flights of the relay kernel: the scan with proven-free stretches skipped
(``scan_crossing``) against the scan sub-interval by sub-interval (``scan_flight(..., 0)``, the
baseline), on the flights of real trajectories, in the same run.

For each N: one realization of the paper's dimers (p = 2, R = 1, J = 2) at C = ``--coupling``
is run for ``--periods`` forcing periods after a transient, with its switches recorded. Every
switch starts a flight: from the threshold ``q`` with the velocity ``v`` and the output after
the switch (the nested plan's index moves by one group per switch), towards the next up and
down thresholds, to the end of the forcing period (the cadence at which the ensemble tasks
sample). The flights the kernel hands to the scan are those whose crossing is farther than the
Taylor hop's reach ``0.02/ρ`` (or that end at the period without one); both scans run over all
of them in one compiled loop, alternating, ``--repeats`` times; the figure is the median
time per flight. Both must return the same (time, direction) for every flight, bit for bit.
The last line is one JSON object.

    python benchmarks/bench_flights.py [--spins 4 10 30 100 1000] [--periods 300] [--repeats 5]
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import time

import numpy as np
from numba import njit

from analysis.experiments.ensemble import disorder_system, realization_seeds
from analysis.experiments.parameters import (
    DAMPING_RATIO,
    FREQUENCY,
    SEED,
    SPIN_COUPLING,
    SPREAD,
    WIDTH,
    WIDTH_SPREAD,
)
from hysteresis.relay_table import RelayTable
from oscillators.engines import _relay_kernels as kern
from oscillators.linear import particular_amplitudes


@njit(cache=True)
def _scan_all(par, force, q0, v0, tau0, horizon, up, down, span_max, out_t, out_d):
    omega = par[kern.P_OMEGA]
    for i in range(q0.size):
        ph = par[kern.P_PHI0] + omega * tau0[i]
        c0 = math.cos(ph)
        s0 = math.sin(ph)
        if span_max < 0:
            t, d = kern.scan_crossing(
                par, force[i], q0[i], v0[i], c0, s0, tau0[i], horizon[i], up[i], down[i]
            )
        else:
            t, d = kern.scan_flight(
                par, force[i], q0[i], v0[i], c0, s0, tau0[i], horizon[i], up[i], down[i], span_max
            )
        out_t[i] = t
        out_d[i] = d


def flights(spins: int, coupling: float, periods: int) -> tuple:
    """The flights after every switch of one trajectory: (par, arrays)."""
    seed = realization_seeds(SEED, spins, 1)[0]
    system = disorder_system(
        "dimers", spins, seed, coupling, WIDTH, SPREAD, SPIN_COUPLING, WIDTH_SPREAD,
        DAMPING_RATIO, FREQUENCY,
    )  # fmt: skip
    period = float(system.period)
    start = system.poincare_section(1, 100).final
    traj = system.trajectory(
        periods * period, start.q, start.v, start.operator_state, sample_dt=period
    )
    sw = traj.switches
    plan = RelayTable(*system.operator.relays()).nested_plan()
    up_t, down_t, mval = plan.up, plan.down, plan.mval
    g = up_t.size
    rising = sw["jump"] > 0.0
    # the index after each switch: an up switch at up[k-1], a down switch at down[k]
    k = np.where(
        rising,
        np.searchsorted(up_t, sw["q"], side="right"),
        np.searchsorted(down_t, sw["q"], side="left"),
    )
    up = np.where(k < g, up_t[np.minimum(k, g - 1)], np.inf)
    down = np.where(k > 0, down_t[np.maximum(k - 1, 0)], -np.inf)
    tau0 = np.mod(sw["time"], period)
    horizon = period - tau0
    amp_a, amp_b = particular_amplitudes(DAMPING_RATIO, FREQUENCY)
    par = kern.make_params(DAMPING_RATIO, FREQUENCY, coupling, 0.0, amp_a, amp_b, 0.0)
    force = coupling * mval[k]
    arrays = [np.ascontiguousarray(a, dtype=float) for a in (force, sw["q"], sw["v"], tau0)]
    return par, arrays + [np.ascontiguousarray(horizon), up, down]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spins", type=int, nargs="+", default=[4, 10, 30, 100, 1000])
    ap.add_argument("--coupling", type=float, default=2.9)
    ap.add_argument("--periods", type=int, default=300)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    rows = {}
    for n in args.spins:
        par, (force, q0, v0, tau0, horizon, up, down) = flights(n, args.coupling, args.periods)
        t_ref = np.empty(q0.size)
        d_ref = np.empty(q0.size, dtype=np.int64)
        _scan_all(par, force, q0, v0, tau0, horizon, up, down, 0, t_ref, d_ref)
        reach = 0.02 / max(1.0, par[kern.P_OMEGA], 2.0 * par[kern.P_ZETA])
        keep = (d_ref == 0) | (t_ref > reach)  # the flights the kernel scans
        sel = [np.ascontiguousarray(a[keep]) for a in (force, q0, v0, tau0, horizon, up, down)]
        m = int(keep.sum())
        out = {key: (np.empty(m), np.empty(m, dtype=np.int64)) for key in ("skip", "plain")}
        times: dict[str, list[float]] = {"skip": [], "plain": []}
        for _ in range(args.repeats):
            for key, span in (("plain", 0), ("skip", -1)):
                t0 = time.perf_counter()
                _scan_all(par, *sel, span, *out[key])
                times[key].append((time.perf_counter() - t0) / m)
        same = np.array_equal(out["skip"][0], out["plain"][0]) and np.array_equal(
            out["skip"][1], out["plain"][1]
        )
        if not same:
            raise RuntimeError(f"N = {n}: the scans with and without skips disagree")
        plain = statistics.median(times["plain"])
        skip = statistics.median(times["skip"])
        rows[n] = {"flights": m, "plain_us": plain * 1e6, "skip_us": skip * 1e6,
                   "ratio": plain / skip}  # fmt: skip
        print(
            f"N = {n:5d}: {m:7d} scanned flights; {plain * 1e6:6.2f} us per flight without "
            f"skips, {skip * 1e6:6.2f} us with = {plain / skip:4.2f} x; identical: {same}"
        )
    print(json.dumps({"periods": args.periods, "coupling": args.coupling, "per_spins": rows}))


if __name__ == "__main__":
    main()
