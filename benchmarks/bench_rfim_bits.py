"""Speed and memory of the 1-bit-per-spin random-field Ising lattice (hysteresis.rfim_bits).

A major loop of a periodic ``L³`` lattice (``--shape``, default 200 200 200; R = ``--disorder``,
J = 1, seed ``--seed``): all spins down, the input from ``−FAR`` up a grid of ``--steps``
inputs from ``−--umax`` to ``+--umax`` to ``+FAR``, then down the same grid to ``−FAR``
(``FAR = 8.5 R + 2dJ + 1`` lies beyond every threshold: every spin flips twice). Printed per
step: the input, M, the flips, the avalanches the scan started, the largest, the step's wall
time and the scan rate (spins per second: N / step time); at the end the total wall time, flips
per second, the process's peak resident memory (``ru_maxrss``), bytes per spin (peak resident
memory / N and the lattice's own ``nbytes`` / N), the loop's jumps (largest ΔM per branch) and
coercive fields (M = 0 by linear interpolation); with ``--png`` the loop M(u) as a PNG.

    python benchmarks/bench_rfim_bits.py [--shape 200 200 200] [--disorder 2.6] [--steps 100]
        [--umax 6] [--threads 2] [--seed 0] [--png /tmp/loop.png] [--quiet]

The last line is one JSON object with every figure (and the loop's inputs and M).
"""

from __future__ import annotations

import argparse
import json
import math
import resource
import time

import numpy as np

from hysteresis.rfim_bits import BitLattice


def peak_rss_mb() -> float:
    """Peak resident memory of this process so far (Linux: ru_maxrss in KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def coercive(u: np.ndarray, m: np.ndarray) -> float:
    """The input where ``M`` crosses 0 along a branch (linear interpolation), NaN if none."""
    for k in range(1, u.size):
        if (m[k - 1] < 0) != (m[k] < 0):
            t = -m[k - 1] / (m[k] - m[k - 1])
            return float(u[k - 1] + t * (u[k] - u[k - 1]))
    return math.nan


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--shape", type=int, nargs="+", default=[200, 200, 200])
    ap.add_argument("--disorder", type=float, default=2.6)
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--umax", type=float, default=6.0)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--png", default="")
    ap.add_argument("--quiet", action="store_true")
    args = ap.parse_args()

    # compile on a small lattice first (numba caches the kernels on disk)
    warm = BitLattice((8,) * len(args.shape), args.disorder, 1.0, args.seed, args.threads)
    warm.relax(0.0)
    warm.relax(-1.0)
    rss0 = peak_rss_mb()

    t0 = time.perf_counter()
    lat = BitLattice(tuple(args.shape), args.disorder, 1.0, args.seed, args.threads)
    n = lat.n_spins
    far = 8.5 * args.disorder + 2 * len(args.shape) + 1.0
    grid = np.linspace(-args.umax, args.umax, args.steps)
    up = np.concatenate([[-far], grid, [far]])
    inputs = np.concatenate([up, up[::-1][1:]])
    rows = []
    for k, u in enumerate(inputs):
        t = time.perf_counter()
        flips, aval, largest = lat.relax(float(u))
        dt = time.perf_counter() - t
        rows.append((float(u), lat.magnetization, flips, aval, largest, dt))
        if not args.quiet:
            print(f"{k:4d} u={u:+8.4f} M={lat.magnetization:+.6f} flips={flips:11d} "
                  f"avalanches={aval:10d} largest={largest:11d} {dt:7.2f} s "
                  f"{n / dt:.3g} spins/s", flush=True)  # fmt: skip
    wall = time.perf_counter() - t0
    u = np.array([r[0] for r in rows])
    m = np.array([r[1] for r in rows])
    flips = np.array([r[2] for r in rows])
    largest = np.array([r[4] for r in rows])
    times = np.array([r[5] for r in rows])
    half = up.size
    dm = np.abs(np.diff(m))
    result = {
        "shape": args.shape,
        "n_spins": n,
        "disorder": args.disorder,
        "steps": int(inputs.size),
        "threads": args.threads,
        "wall_s": wall,
        "flips": int(flips.sum()),
        "flips_per_s": float(flips.sum() / wall),
        "scan_spins_per_s_median": float(np.median(n / times)),
        "scan_s_median": float(np.median(times)),
        "peak_rss_mb": peak_rss_mb(),
        "peak_rss_mb_before_lattice": rss0,
        "bytes_per_spin_rss": peak_rss_mb() * 2**20 / n,
        "bytes_per_spin_lattice": lat.nbytes / n,
        "largest_jump_up": float(dm[: half - 1].max()),
        "largest_jump_down": float(dm[half - 1 :].max()),
        "largest_avalanche_root_up": int(largest[:half].max()),
        "largest_avalanche_root_down": int(largest[half:].max()),
        "coercive_up": coercive(u[:half], m[:half]),
        "coercive_down": coercive(u[half - 1 :], m[half - 1 :]),
        "inputs": u.tolist(),
        "magnetization": m.tolist(),
    }
    if args.png:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6, 4.5))
        ax.plot(u[1 : half - 1], m[1 : half - 1], ".-", ms=3, label="rising")
        ax.plot(u[half:-1], m[half:-1], ".-", ms=3, label="falling")
        ax.set_xlabel("input u (external field)")
        ax.set_ylabel("M")
        ax.set_title(f"RFIM {'×'.join(map(str, args.shape))}, R = {args.disorder}, J = 1, "
                     f"seed {args.seed}")  # fmt: skip
        ax.legend()
        ax.grid(alpha=0.3)
        fig.tight_layout()
        fig.savefig(args.png, dpi=120)
    if not args.quiet:
        r = result
        print(f"wall {wall:.1f} s, {r['flips_per_s']:.3g} flips/s, median scan "
              f"{r['scan_s_median']:.3f} s ({r['scan_spins_per_s_median']:.3g} spins/s), "
              f"peak RSS {r['peak_rss_mb']:.0f} MB = {r['bytes_per_spin_rss']:.3f} B/spin "
              f"(lattice {r['bytes_per_spin_lattice']:.3f} B/spin), largest jumps "
              f"{r['largest_jump_up']:.4f} / {r['largest_jump_down']:.4f}, coercive fields "
              f"{r['coercive_up']:.4f} / {r['coercive_down']:.4f}")  # fmt: skip
    print(json.dumps(result))


if __name__ == "__main__":
    main()
