"""Bifurcation diagrams of N = 20 000 spin dimers and of the erf-play limit (paper fig:bif).

    python examples/fig_bif.py [--out out/examples] [--smoke] [--spins 20000 --couplings 60]

One disorder realization of N dimers (p = 2, R = 1, J = 2) and its thermodynamic limit, the
generalized play M = erf(w/(√2 R)) (Table II initial conditions; the play starts at
w0 = q0 − p/2). C is stepped downward over [1.5, 4.5] with continuation. For each system:
the section q(φ = 0) and λ_max (dimers: 2-D tangent space q, v with saltation matrices;
play: 3-D tangent space q, v, w). The paper finds both systems chaotic for C in [3.8, 4.2] and
λ_max^N < 0 for C in [1.7, 1.8] and [2.5, 3.0] where λ_max^∞ > 0.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from analysis.dynamics.bifurcation import bifurcation_diagram  # noqa: E402
from hysteresis import GeneralizedPlay, SpinDimerEnsemble  # noqa: E402
from oscillators import ForcedOscillator  # noqa: E402

WIDTH, SPREAD, COUPLING_J = 2.0, 1.0, 2.0  # p, R, J


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        epilog="The defaults are the full size (about 20 s on a quiet machine).",
    )
    parser.add_argument("--out", default="out/examples", help="output directory")
    parser.add_argument("--smoke", action="store_true", help="tiny sizes (for tests)")
    parser.add_argument("--spins", type=int, default=20000, help="N")
    parser.add_argument("--seed", type=int, default=0, help="disorder seed")
    parser.add_argument("--couplings", type=int, default=60, help="number of C values")
    parser.add_argument("--periods", type=int, default=60, help="section points per C")
    parser.add_argument("--transient", type=int, default=100, help="periods dropped per C")
    parser.add_argument("--lyapunov-time", type=float, default=2000.0, help="λ_max run length")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.smoke:
        args.spins, args.couplings, args.periods, args.transient = 400, 3, 8, 5
        args.lyapunov_time = 40.0

    couplings = np.linspace(4.5, 1.5, args.couplings)
    operators = {
        f"N = {args.spins}": SpinDimerEnsemble.random(
            args.spins, WIDTH, SPREAD, COUPLING_J, seed=args.seed
        ),
        "N = ∞ (erf play)": GeneralizedPlay.erf(WIDTH, SPREAD),
    }
    fig, axes = plt.subplots(4, 1, figsize=(7, 9), sharex=True)
    for k, (name, op) in enumerate(operators.items()):
        diagram = bifurcation_diagram(
            lambda c, op=op: ForcedOscillator(op, c, damping_ratio=0.05, frequency=1.0),
            couplings,
            n_periods=args.periods,
            transient_periods=args.transient,
            lyapunov_t_end=args.lyapunov_time,
            progress=not args.smoke,
        )
        diagram.save(out / f"fig_bif_{'dimers' if k == 0 else 'limit'}.npz")
        chaotic = diagram.values[diagram.max_exponent > 0]
        print(f"{name}: λ_max > 0 at {chaotic.size} of {couplings.size} couplings", end="")
        print(f" (C in [{chaotic.min():.2f}, {chaotic.max():.2f}])" if chaotic.size else "")
        color = "tab:blue" if k == 0 else "tab:red"
        ax_q, ax_l = axes[2 * k], axes[2 * k + 1]
        ax_q.plot(np.repeat(diagram.values, args.periods), diagram.q.ravel(), ",", color=color)
        ax_q.set_ylabel("q(φ = 0)")
        ax_q.set_title(name, fontsize=9)
        ax_l.plot(diagram.values, diagram.max_exponent, "-", color=color, lw=1)
        ax_l.axhline(0.0, color="grey", lw=0.5)
        ax_l.set_ylabel("$λ_{max}$")
    axes[-1].set_xlabel("C")
    path = out / "fig_bif.png"
    fig.savefig(path, dpi=130, bbox_inches="tight")
    print("wrote", path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
