"""A design option measured, not used by the library: eight realizations of the dimer ensemble
as SIMD lanes of the relay kernel's fast short hop, against the kernel run one realization after
the other (the baseline, same run).

Why: at N ≥ 5000 almost every switch of ``hyst paper --full``'s ensemble is a fast hop
(97 % at N = 20 000), about 35 ns each, and two realizations interleaved in one scalar loop
gain nothing (the hop is not latency-bound). The fast hop is branch-free arithmetic
(:func:`oscillators.engines._relay_kernels.fast_hop`), so eight independent realizations can
take it side by side in the vector units.

The lane loop (``_lanes``): per round, every active lane computes its fast-hop candidate in one
vectorized loop (``_vector_round``, the library's ``fast_hop`` and ``fast_propagator`` inlined);
then, lane by lane, an accepted candidate is committed (the nested table switch, the sliding
test and the saltation of the tangent, as ``settle_switch``), and a lane whose candidate failed
takes the library's full ``hop`` (Taylor hop or exact flight, or the stop at the period end).
Each lane keeps its own period clock: a lane that reaches the end of its forcing period wraps
and goes on, so lanes with fewer switches per period do not idle until the slowest one
finishes (in lockstep by period the vector rounds were half empty at N = 20 000).

What LLVM needs to vectorize the round (each measured on this code): all lane data in one flat
array, rows of ``LANES`` at constant offsets (with one array per quantity the loop vectorizer
gives up: "too many memory checks needed"); both thresholds loaded and then selected (a load
from a selected address is an "unsafe indirect dependence"); ``&`` rather than ``and`` (no
branches); ``error_model="numpy"`` (no ZeroDivisionError branch for ``1/v``).

Checks: in the runs measured here the lanes ended with the same switch counts, and (q, v)
agree to rounding over short runs; they are not bit for bit the one-by-one run: LLVM fuses the
vector code's multiply-adds differently, a last bit of a hop time or of ∫M dt differs now and
then (first seen after a few periods at N = 20 000), and the chaotic trajectories then separate
from there, as two runs on different CPUs do. A library version would have to take the lane
code for every realization (a lane's arithmetic does not depend on the other lanes) to keep
results independent of how tasks are batched. ``state_identical`` reports the comparison,
``max_dq`` the largest difference of q, ``tangent_max_rel_diff`` the first tangent column's
relative difference. The last
line is one JSON object.

    python benchmarks/bench_lanes.py [--spins 1000 5000 20000] [--coupling 2.9 4.0]
                                     [--periods 40] [--repeats 5]
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

import numpy as np
from numba import njit

from analysis.dynamics.lyapunov import TangentStepper
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
from oscillators.engines import _relay_kernels as kern

LANES = 8
#: rows of the flat lane array (row r holds lane j at r * LANES + j)
Q, V, TAU, COS, SIN, UP, DN, MV, IM, A0, A1, B0, B1, PQ, PJ = range(15)
#: the round's candidates and the active flag
HF, V1, C1, S1, NA0, NA1, NB0, NB1, THETA, OK, ACT = range(15, 26)
ROWS = 26


@njit(fastmath={"contract"}, error_model="numpy", cache=True)
def _vector_round(coefs, zeta, omega, coupling, h_small, tau_stop, w, n_lanes):
    """Fast-hop candidates of all lanes (no branches: one vector loop)."""
    for j in range(n_lanes):
        q = w[Q * LANES + j]
        v = w[V * LANES + j]
        c = w[COS * LANES + j]
        s = w[SIN * LANES + j]
        up = w[UP * LANES + j]
        down = w[DN * LANES + j]
        theta = max(up, down) if v > 0.0 else min(up, down)  # up > down always
        gap = theta - q
        force = coupling * w[MV * LANES + j]
        horizon = tau_stop - w[TAU * LANES + j]
        ok, hf, v1, c1, s1 = kern.fast_hop(coefs, omega, h_small, q, v, c, s, force, gap, horizon)
        g, gd = kern.fast_propagator(coefs, hf)
        m00 = gd + 2.0 * zeta * g
        a0 = w[A0 * LANES + j]
        a1 = w[A1 * LANES + j]
        b0 = w[B0 * LANES + j]
        b1 = w[B1 * LANES + j]
        active = w[ACT * LANES + j] != 0.0
        ok = ok & active & (v != 0.0) & (abs(gap) < h_small * abs(v))
        w[HF * LANES + j] = hf
        w[V1 * LANES + j] = v1
        w[C1 * LANES + j] = c1
        w[S1 * LANES + j] = s1
        w[NA0 * LANES + j] = m00 * a0 + g * b0
        w[NA1 * LANES + j] = m00 * a1 + g * b1
        w[NB0 * LANES + j] = -g * a0 + gd * b0
        w[NB1 * LANES + j] = -g * a1 + gd * b1
        w[THETA * LANES + j] = theta
        w[OK * LANES + j] = 1.0 if ok else 0.0


@njit(fastmath={"contract"}, cache=True)
def _lanes(par, mp, tf, groups, w, k, nsw, periods):
    """Every lane through ``periods`` forcing periods (nested tables, tangent on, 2 columns)."""
    e = np.empty(kern.ORDER + 1)
    coefs = kern.hop_coefficients(mp)
    zeta = par[kern.P_ZETA]
    omega = par[kern.P_OMEGA]
    coupling = par[kern.P_C]
    h_small = par[kern.P_HS]
    slide = par[kern.P_SL]
    period = par[kern.P_T]
    c0 = np.cos(par[kern.P_PHI0])
    s0 = np.sin(par[kern.P_PHI0])
    done = np.zeros(LANES, dtype=np.int64)
    rounds = 0
    for j in range(LANES):
        w[ACT * LANES + j] = 1.0
    while True:
        _vector_round(coefs, zeta, omega, coupling, h_small, period, w, LANES)
        rounds += 1
        n_active = 0
        for j in range(LANES):
            if w[ACT * LANES + j] == 0.0:
                continue
            n_active += 1
            mv = w[MV * LANES + j]
            if w[OK * LANES + j] != 0.0:
                hf = w[HF * LANES + j]
                d = 1 if w[V * LANES + j] > 0.0 else -1
                q = w[THETA * LANES + j]
                v = w[V1 * LANES + j]
                c = w[C1 * LANES + j]
                s = w[S1 * LANES + j]
                a0 = w[NA0 * LANES + j]
                a1 = w[NA1 * LANES + j]
                b0 = w[NB0 * LANES + j]
                b1 = w[NB1 * LANES + j]
                w[IM * LANES + j] += mv * hf
                w[TAU * LANES + j] += hf
            else:
                d, q, v, tau, c, s, a0, a1, _, b0, b1, _, im = kern.hop(
                    par, coefs, mp, e, w[Q * LANES + j], w[V * LANES + j], w[TAU * LANES + j],
                    w[COS * LANES + j], w[SIN * LANES + j], w[UP * LANES + j],
                    w[DN * LANES + j], mv, period, True, 2, w[A0 * LANES + j],
                    w[A1 * LANES + j], 0.0, w[B0 * LANES + j], w[B1 * LANES + j], 0.0, 0.0,
                    0.0, 0.0, w[IM * LANES + j],
                )  # fmt: skip
                w[TAU * LANES + j] = tau
                w[IM * LANES + j] = im
            w[Q * LANES + j] = q
            w[V * LANES + j] = v
            w[COS * LANES + j] = c
            w[SIN * LANES + j] = s
            w[A0 * LANES + j] = a0
            w[A1 * LANES + j] = a1
            w[B0 * LANES + j] = b0
            w[B1 * LANES + j] = b1
            if d == 0:  # the end of this lane's period: wrap (kern._wrap); done after the last
                done[j] += 1
                w[TAU * LANES + j] = 0.0
                w[COS * LANES + j] = c0
                w[SIN * LANES + j] = s0
                if done[j] >= periods:
                    w[ACT * LANES + j] = 0.0
                continue
            # the nested table switch (kern._table_switch, kind 0)
            row = j * (3 * groups + 1)
            k_old = k[j]
            kn = k_old + d
            k[j] = kn
            w[UP * LANES + j] = tf[row + kn] if kn < groups else np.inf
            w[DN * LANES + j] = tf[row + groups + kn - 1] if kn > 0 else -np.inf
            mv_new = tf[row + 2 * groups + kn]
            jump = mv_new - tf[row + 2 * groups + k_old]
            w[MV * LANES + j] = mv_new
            nsw[j] += 1
            # kern.settle_switch: a sliding motion ends this benchmark's lane (not expected)
            if jump == -w[PJ * LANES + j] and q == w[PQ * LANES + j] and jump != 0.0:
                a_now = c - q - 2.0 * zeta * v + coupling * mv_new
                a_before = a_now - coupling * jump
                if d * a_before > 0.0 and d * a_now < 0.0 and 2.0 * abs(v) <= slide * abs(a_now):
                    raise RuntimeError("a lane entered a sliding motion")
            w[PQ * LANES + j] = q
            w[PJ * LANES + j] = jump
            if coupling * jump != 0.0:
                sal = coupling * jump / v
                w[B0 * LANES + j] = b0 + sal * a0
                w[B1 * LANES + j] = b1 + sal * a1
        if n_active == 0:
            return rounds


@njit(cache=True)
def _one_by_one(par, kind, tf, ti, bits, lay, st, ist, y, mp, periods):
    """The baseline: the library's event loop, period by period."""
    e = np.empty(kern.ORDER + 1)
    sw = np.zeros((1, 4))
    sw_count = np.zeros(1, dtype=np.int64)
    for _ in range(periods):
        status = kern.advance_table(
            par, kind, tf, ti, bits, lay, st, ist, par[kern.P_T], True, y, 2, e, mp, False, sw,
            sw_count,
        )  # fmt: skip
        if status != 0:
            raise RuntimeError("the baseline stopped early")
        kern._wrap(par, st, ist)


#: the lane rows and the kernel state entries they mirror
_STATE = ((Q, kern.S_Q), (V, kern.S_V), (TAU, kern.S_TAU), (COS, kern.S_COS), (SIN, kern.S_SIN),
          (UP, kern.S_UP), (DN, kern.S_DN), (MV, kern.S_MV), (IM, kern.S_IM), (PQ, kern.S_PQ),
          (PJ, kern.S_PJ))  # fmt: skip


def _realizations(spins: int, coupling: float, transient: float) -> list[tuple]:
    """Kernel arrays of LANES realizations after ``transient`` (tangent flow on)."""
    out = []
    for seed in realization_seeds(SEED, spins, LANES):
        system = disorder_system(
            "dimers", spins, seed, coupling, WIDTH, SPREAD, SPIN_COUPLING, WIDTH_SPREAD,
            DAMPING_RATIO, FREQUENCY,
        )  # fmt: skip
        stepper = TangentStepper(system, sample_dt=system.period)
        stepper.reinit(None, transient)
        kind, par, tf, ti, bits, lay, st, ist, y, ntan, mp = stepper.engine.kernel_arrays()[:11]
        if kind != kern.KIND_NESTED or ntan != 2:
            raise RuntimeError("the benchmark expects nested tables and two tangent columns")
        ist[kern.I_MAXSW] = 2**62
        out.append((par, kind, tf, ti, bits, lay, st, ist, y, mp))
    return out


def measure(spins: int, coupling: float, periods: int, repeats: int) -> dict:
    base = _realizations(spins, coupling, transient=1000.0)
    par, mp = base[0][0], base[0][9]
    groups = int(base[0][5][0])
    if any(not np.array_equal(r[0], par) or int(r[5][0]) != groups for r in base):
        raise RuntimeError("the lanes need one parameter set and one table size")
    tf = np.concatenate([r[2] for r in base])
    t_one, t_lanes = [], []
    for _ in range(repeats + 1):  # the first pass compiles / loads
        runs = [tuple(a.copy() if isinstance(a, np.ndarray) else a for a in r) for r in base]
        t0 = time.perf_counter()
        for r in runs:
            _one_by_one(*r, periods)
        t_one.append(time.perf_counter() - t0)
        w = np.zeros(ROWS * LANES)
        for j, r in enumerate(base):
            st, y = r[6], r[8]
            for row, col in _STATE:
                w[row * LANES + j] = st[col]
            w[A0 * LANES + j], w[A1 * LANES + j] = y[0, 0], y[0, 1]
            w[B0 * LANES + j], w[B1 * LANES + j] = y[1, 0], y[1, 1]
        k = np.array([r[7][kern.I_K] for r in base])
        nsw = np.array([r[7][kern.I_NSW] for r in base])
        t0 = time.perf_counter()
        rounds = _lanes(par, mp, tf, groups, w, k, nsw, periods)
        t_lanes.append(time.perf_counter() - t0)
    switches = int(
        sum(r[7][kern.I_NSW] - b[7][kern.I_NSW] for r, b in zip(runs, base, strict=True))
    )
    max_dq = max(abs(w[Q * LANES + j] - r[6][kern.S_Q]) for j, r in enumerate(runs))
    same_state = all(
        w[row * LANES + j] == r[6][col] or (np.isnan(w[row * LANES + j]) and np.isnan(r[6][col]))
        for j, r in enumerate(runs)
        for row, col in _STATE
    ) and all(k[j] == r[7][kern.I_K] and nsw[j] == r[7][kern.I_NSW] for j, r in enumerate(runs))
    # the first tangent column's difference relative to its norm (without re-orthonormalisation
    # the second column's own part shrinks like exp((λ2 - λ1) t) and says nothing)
    tangent_rel = max(
        np.hypot(w[A0 * LANES + j] - r[8][0, 0], w[B0 * LANES + j] - r[8][1, 0])
        / np.hypot(r[8][0, 0], r[8][1, 0])
        for j, r in enumerate(runs)
    )
    one = statistics.median(t_one[1:])
    lanes = statistics.median(t_lanes[1:])
    return {
        "spins": spins,
        "coupling": coupling,
        "switches": switches,
        "ns_per_switch_one_by_one": one / switches * 1e9,
        "ns_per_switch_lanes": lanes / switches * 1e9,
        "speedup": one / lanes,
        "lanes_per_round": switches / rounds,
        "state_identical": bool(same_state),
        "max_dq": float(max_dq),
        "tangent_max_rel_diff": float(tangent_rel),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spins", type=int, nargs="+", default=[1000, 5000, 20000])
    ap.add_argument("--coupling", type=float, nargs="+", default=[2.9, 4.0])
    ap.add_argument("--periods", type=int, default=40)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    rows = []
    for n in args.spins:
        for c in args.coupling:
            r = measure(n, c, args.periods, args.repeats)
            rows.append(r)
            print(
                f"N={n:6d} C={c:3.1f}  one by one {r['ns_per_switch_one_by_one']:6.1f} ns/switch"
                f"  lanes {r['ns_per_switch_lanes']:6.1f}  speedup {r['speedup']:4.2f}x"
                f"  lanes busy {r['lanes_per_round']:.1f}/{LANES}"
                f"  state identical {r['state_identical']} (max |dq| {r['max_dq']:.1e})"
                f"  tangent rel diff {r['tangent_max_rel_diff']:.1e}",
                flush=True,
            )
    print(json.dumps({"lanes": LANES, "periods": args.periods, "rows": rows}))


if __name__ == "__main__":
    main()
