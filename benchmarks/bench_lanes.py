"""A design option measured, not used by the library: eight realizations of the dimer ensemble
as SIMD lanes of the relay kernel's fast short hop, against the kernel run one realization after
the other (the baseline, same run).

Why: at N ≥ 5000 almost every switch of ``hyst paper --full``'s ensemble is a fast hop
(97 % at N = 20 000), about 35 ns each, and two realizations interleaved in one scalar loop
gain nothing (the hop is not latency-bound). The fast hop is branch-free arithmetic
(:func:`oscillators.engines._relay_kernels.fast_hop`), so eight independent realizations can
take it side by side in the vector units.

The lane loop (``_make_lanes``): per round, every active lane computes its fast-hop candidate in
one vectorized loop (``_make_round``); then, lane by lane, an accepted candidate is committed
(the nested table switch, the sliding test and the saltation of the tangent, as
``settle_switch``), and a lane whose candidate failed takes the library's full ``hop`` (Taylor
hop or exact flight, or the stop at the period end). Each lane keeps its own period clock: a
lane that reaches the end of its forcing period wraps and goes on, so lanes with fewer switches
per period do not idle until the slowest one finishes (in lockstep by period the vector rounds
were half empty at N = 20 000).

What LLVM needs to vectorize the round (each measured on this code): all lane data in one flat
array, rows of ``LANES`` at constant offsets (with one array per quantity the loop vectorizer
gives up: "too many memory checks needed"); both thresholds loaded and then selected (a load
from a selected address is an "unsafe indirect dependence"); ``&`` rather than ``and`` (no
branches); ``error_model="numpy"`` (no ZeroDivisionError branch for ``1/v``); inlined helpers
that take and return numbers only (one that stores into the lane array stops the vectorizer).

Three variants, one run:

* ``lanes``: the library's ``fast_hop`` (compiled with ``fastmath={"contract"}``) as lanes,
  against the library's event loop one realization after the other. Not bit for bit: LLVM
  picks which products to fuse into multiply-adds, differently in vector and scalar code; a
  last bit of a hop time or of ∫M dt differs now and then (first seen after a few periods at
  N = 20 000), and the chaotic trajectories separate from there, as two runs on different CPUs
  do (``state_identical``, ``max_dq``; ``tangent_max_rel_diff`` is the first tangent column's
  relative difference).
* ``fma_lanes`` / ``fma_scalar``: the same fast hop with every multiply-add written as an
  explicit fused one (``llvm.fma`` through ``numba.extending.intrinsic``), as lanes and one
  lane at a time (an opaque compiler barrier keeps that loop scalar). These agree **bit for
  bit** (``fma_lanes_identical_to_fma_scalar``): with the fusions fixed in the source, vector
  and scalar code round alike. So a library version would write ``fast_hop`` this way (its
  results change once, in the last bits), and then every realization gives the same bits
  whether it ran in a batch of lanes or alone.

The last line is one JSON object.

    python benchmarks/bench_lanes.py [--spins 1000 5000 20000] [--coupling 2.9 4.0]
                                     [--periods 40] [--repeats 5]
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

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


@intrinsic
def _fma(typingctx, a, b, c):
    """fl(a·b + c) rounded once (LLVM's llvm.fma): the same bits in scalar and vector code."""
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        d = ir.DoubleType()
        fn = builder.module.declare_intrinsic("llvm.fma", [d], ir.FunctionType(d, [d, d, d]))
        return builder.call(fn, args)

    return sig, codegen


@njit(inline="always", error_model="numpy")
def _fast_hop_fma(coefs, omega, h_small, q, v, c, s, force, gap, horizon):
    """``kern.fast_hop`` with every multiply-add written as an explicit fused one (the
    arithmetic of the library's, not its bits: there LLVM chooses which products to fuse)."""
    (
        t2q, t2v, t2f, t2c, t2s, t3q, t3v, t3f, t3c, t3s, t4q, t4v, t4f, t4c, t4s, t5q,
        t5v, t5f, t5c, t5s, t6q, t6v, t6f, t6c, t6s, g0, g1, g2, g3, g4, g5, g6, d0, d1,
        d2, d3, d4, d5, d6
    ) = coefs  # fmt: skip
    e2 = _fma(t2q, q, _fma(t2v, v, _fma(t2f, force, _fma(t2c, c, t2s * s))))
    e3 = _fma(t3q, q, _fma(t3v, v, _fma(t3f, force, _fma(t3c, c, t3s * s))))
    e4 = _fma(t4q, q, _fma(t4v, v, _fma(t4f, force, _fma(t4c, c, t4s * s))))
    e5 = _fma(t5q, q, _fma(t5v, v, _fma(t5f, force, _fma(t5c, c, t5s * s))))
    e6 = _fma(t6q, q, _fma(t6v, v, _fma(t6f, force, _fma(t6c, c, t6s * s))))
    r = 1.0 / v
    x = gap * r
    k2 = e2 * r
    k3 = e3 * r
    h0 = _fma(x * x, _fma(x, _fma(2.0 * k2, k2, -k3), -k2), x)
    hh2 = h0 * h0
    inner = _fma(e2, h0, v) + hh2 * (_fma(e4, h0, e3) + hh2 * _fma(e6, h0, e5))
    res = _fma(h0, inner, -gap)
    u = h0 * _fma(4.0 * e4 * r, hh2, _fma(3.0 * k3, h0, 2.0 * k2))
    inv = r * _fma(u * u, 1.0 - u, 1.0 - u)
    dp0 = _fma(2.0 * e2, h0, v) + hh2 * (
        _fma(4.0 * e4, h0, 3.0 * e3) + hh2 * _fma(6.0 * e6, h0, 5.0 * e5)
    )
    pp0 = _fma(6.0 * e3, h0, 2.0 * e2) + hh2 * _fma(20.0 * e5, h0, 12.0 * e4)
    xr = omega * h0
    x2 = xr * xr
    cx = _fma(-x2, _fma(-x2, 1.0 / 24.0, 0.5), 1.0)
    sx = xr * _fma(-x2, _fma(-x2, 1.0 / 120.0, 1.0 / 6.0), 1.0)
    c0r = _fma(c, cx, -(s * sx))
    s0r = _fma(s, cx, c * sx)
    dh = res * inv
    hf = h0 - dh
    av = abs(v)
    ae2 = abs(e2)
    slope = hf * _fma(
        hf, _fma(hf, _fma(hf, _fma(hf, 6.0 * abs(e6), 5.0 * abs(e5)), 4.0 * abs(e4)),
                 3.0 * abs(e3)), 2.0 * ae2,
    )  # fmt: skip
    err = _fma(abs(dh), u * u * u * u + 1e-13, dh * dh * (ae2 + 3.0 * abs(e3)) / av)
    ok = (0.0 < hf) & (hf <= horizon) & (hf < h_small) & (err <= 1e-17) & (slope < 0.5 * av)
    dphi = omega * dh
    return ok, hf, _fma(-dh, pp0, dp0), _fma(dphi, s0r, c0r), _fma(-dphi, c0r, s0r)


@njit(inline="always", error_model="numpy")
def _candidate_fma(coefs, zeta, omega, h_small, q, v, c, s, force, gap, horizon, a0, a1, b0, b1):
    """The explicit-fma fast hop and its tangent update."""
    ok, hf, v1, c1, s1 = _fast_hop_fma(coefs, omega, h_small, q, v, c, s, force, gap, horizon)
    g0, g1, g2, g3, g4, g5, g6, d0, d1, d2, d3, d4, d5, d6 = coefs[25:]
    hp2 = hf * hf
    hp4 = hp2 * hp2
    g = _fma(g1, hf, g0) + hp2 * _fma(g3, hf, g2) + hp4 * _fma(hp2, g6, _fma(g5, hf, g4))
    gd = _fma(d1, hf, d0) + hp2 * _fma(d3, hf, d2) + hp4 * _fma(hp2, d6, _fma(d5, hf, d4))
    m00 = _fma(2.0 * zeta, g, gd)
    na0 = _fma(m00, a0, g * b0)
    na1 = _fma(m00, a1, g * b1)
    nb0 = _fma(-g, a0, gd * b0)
    nb1 = _fma(-g, a1, gd * b1)
    return ok, hf, v1, c1, s1, na0, na1, nb0, nb1


@njit(inline="always", error_model="numpy", fastmath={"contract"})
def _candidate_library(
    coefs, zeta, omega, h_small, q, v, c, s, force, gap, horizon, a0, a1, b0, b1
):  # fmt: skip
    """The library's fast hop (``kern.fast_hop``) and its tangent update as ``hop`` does it."""
    ok, hf, v1, c1, s1 = kern.fast_hop(coefs, omega, h_small, q, v, c, s, force, gap, horizon)
    g, gd = kern.fast_propagator(coefs, hf)
    m00 = gd + 2.0 * zeta * g
    return (
        ok,
        hf,
        v1,
        c1,
        s1,
        m00 * a0 + g * b0,
        m00 * a1 + g * b1,
        -g * a0 + gd * b0,
        (-g * a1 + gd * b1),
    )


def _make_round(candidate, scalar: bool):
    """One round: the fast-hop candidates of all lanes. The loop has no branches, so LLVM
    vectorizes it; with ``scalar`` an opaque compiler barrier in the loop keeps it scalar (the
    same arithmetic one lane after the other). The candidate function only takes and returns
    numbers: an inlined function that stores into the lane array stops the vectorizer."""

    @njit(fastmath={"contract"}, error_model="numpy")
    def round_(coefs, zeta, omega, coupling, h_small, tau_stop, w, n_lanes):
        for j in range(n_lanes):
            if scalar:
                kern._memory_barrier()
            q = w[Q * LANES + j]
            v = w[V * LANES + j]
            up = w[UP * LANES + j]
            down = w[DN * LANES + j]
            theta = max(up, down) if v > 0.0 else min(up, down)  # up > down always
            gap = theta - q
            ok, hf, v1, c1, s1, na0, na1, nb0, nb1 = candidate(
                coefs, zeta, omega, h_small, q, v, w[COS * LANES + j], w[SIN * LANES + j],
                coupling * w[MV * LANES + j], gap, tau_stop - w[TAU * LANES + j],
                w[A0 * LANES + j], w[A1 * LANES + j], w[B0 * LANES + j], w[B1 * LANES + j],
            )  # fmt: skip
            active = w[ACT * LANES + j] != 0.0
            ok = ok & active & (v != 0.0) & (abs(gap) < h_small * abs(v))
            w[HF * LANES + j] = hf
            w[V1 * LANES + j] = v1
            w[C1 * LANES + j] = c1
            w[S1 * LANES + j] = s1
            w[NA0 * LANES + j] = na0
            w[NA1 * LANES + j] = na1
            w[NB0 * LANES + j] = nb0
            w[NB1 * LANES + j] = nb1
            w[THETA * LANES + j] = theta
            w[OK * LANES + j] = 1.0 if ok else 0.0

    return round_


def _make_lanes(round_):
    """The lane loop around one round function (compiled per round function)."""

    @njit(fastmath={"contract"})
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
            round_(coefs, zeta, omega, coupling, h_small, period, w, LANES)
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
                    if (
                        d * a_before > 0.0
                        and d * a_now < 0.0
                        and 2.0 * abs(v) <= slide * abs(a_now)
                    ):
                        raise RuntimeError("a lane entered a sliding motion")
                w[PQ * LANES + j] = q
                w[PJ * LANES + j] = jump
                if coupling * jump != 0.0:
                    sal = coupling * jump / v
                    w[B0 * LANES + j] = b0 + sal * a0
                    w[B1 * LANES + j] = b1 + sal * a1
            if n_active == 0:
                return rounds

    return _lanes


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


#: the library's fast hop as lanes; the explicit-fma fast hop as lanes and one lane at a time
VARIANTS = {
    "lanes": (_candidate_library, False),
    "fma_lanes": (_candidate_fma, False),
    "fma_scalar": (_candidate_fma, True),
}
_LOOPS: dict = {}


def _loop(name: str):
    if name not in _LOOPS:
        candidate, scalar = VARIANTS[name]
        _LOOPS[name] = _make_lanes(_make_round(candidate, scalar))
    return _LOOPS[name]


def _lane_arrays(base: list[tuple]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    w = np.zeros(ROWS * LANES)
    for j, r in enumerate(base):
        st, y = r[6], r[8]
        for row, col in _STATE:
            w[row * LANES + j] = st[col]
        w[A0 * LANES + j], w[A1 * LANES + j] = y[0, 0], y[0, 1]
        w[B0 * LANES + j], w[B1 * LANES + j] = y[1, 0], y[1, 1]
    k = np.array([r[7][kern.I_K] for r in base])
    nsw = np.array([r[7][kern.I_NSW] for r in base])
    return w, k, nsw


def _same(w: np.ndarray, k: np.ndarray, nsw: np.ndarray, w2, k2, nsw2) -> bool:
    rows = [row for row, _ in _STATE] + [A0, A1, B0, B1]
    return all(
        np.array_equal(w[r * LANES : (r + 1) * LANES], w2[r * LANES : (r + 1) * LANES],
                       equal_nan=True)
        for r in rows
    ) and np.array_equal(k, k2) and np.array_equal(nsw, nsw2)  # fmt: skip


def measure(spins: int, coupling: float, periods: int, repeats: int) -> dict:
    base = _realizations(spins, coupling, transient=1000.0)
    par, mp = base[0][0], base[0][9]
    groups = int(base[0][5][0])
    if any(not np.array_equal(r[0], par) or int(r[5][0]) != groups for r in base):
        raise RuntimeError("the lanes need one parameter set and one table size")
    tf = np.concatenate([r[2] for r in base])
    times: dict[str, list[float]] = {"one_by_one": [], **{name: [] for name in VARIANTS}}
    ends: dict[str, tuple] = {}
    for _ in range(repeats + 1):  # the first pass compiles / loads
        runs = [tuple(a.copy() if isinstance(a, np.ndarray) else a for a in r) for r in base]
        t0 = time.perf_counter()
        for r in runs:
            _one_by_one(*r, periods)
        times["one_by_one"].append(time.perf_counter() - t0)
        for name in VARIANTS:
            w, k, nsw = _lane_arrays(base)
            t0 = time.perf_counter()
            rounds = _loop(name)(par, mp, tf, groups, w, k, nsw, periods)
            times[name].append(time.perf_counter() - t0)
            ends[name] = (w, k, nsw, rounds)
    switches = int(
        sum(r[7][kern.I_NSW] - b[7][kern.I_NSW] for r, b in zip(runs, base, strict=True))
    )
    one_w, one_k, one_nsw = _lane_arrays(runs)
    w, k, nsw, rounds = ends["lanes"]
    # the first tangent column's difference relative to its norm (without re-orthonormalisation
    # the second column's own part shrinks like exp((λ2 - λ1) t) and says nothing)
    tangent_rel = max(
        np.hypot(w[A0 * LANES + j] - r[8][0, 0], w[B0 * LANES + j] - r[8][1, 0])
        / np.hypot(r[8][0, 0], r[8][1, 0])
        for j, r in enumerate(runs)
    )
    ns = {name: statistics.median(t[1:]) / switches * 1e9 for name, t in times.items()}
    return {
        "spins": spins,
        "coupling": coupling,
        "switches": switches,
        "ns_per_switch": ns,
        "speedup": ns["one_by_one"] / ns["lanes"],
        "fma_speedup": ns["fma_scalar"] / ns["fma_lanes"],
        "lanes_per_round": switches / rounds,
        "state_identical": _same(w, k, nsw, one_w, one_k, one_nsw),
        "max_dq": float(
            np.max(np.abs(w[Q * LANES : (Q + 1) * LANES] - one_w[Q * LANES : (Q + 1) * LANES]))
        ),
        "tangent_max_rel_diff": float(tangent_rel),
        "fma_lanes_identical_to_fma_scalar": _same(*ends["fma_lanes"][:3], *ends["fma_scalar"][:3]),
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
            ns = r["ns_per_switch"]
            print(
                f"N={n:6d} C={c:3.1f}  one by one {ns['one_by_one']:6.1f} ns/switch"
                f"  lanes {ns['lanes']:6.1f} ({r['speedup']:4.2f}x, busy"
                f" {r['lanes_per_round']:.1f}/{LANES}, state identical {r['state_identical']},"
                f" max |dq| {r['max_dq']:.1e}, tangent {r['tangent_max_rel_diff']:.1e})"
                f"  explicit fma: lanes {ns['fma_lanes']:6.1f}, one lane at a time"
                f" {ns['fma_scalar']:6.1f} ({r['fma_speedup']:4.2f}x, bit for bit"
                f" {r['fma_lanes_identical_to_fma_scalar']})",
                flush=True,
            )
    print(json.dumps({"lanes": LANES, "periods": args.periods, "rows": rows}))


if __name__ == "__main__":
    main()
