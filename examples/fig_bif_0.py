"""Bifurcation diagram of the oscillator driven by one spin dimer, C stepped down (fig:bif_0).

    python examples/fig_bif_0.py [--out out/examples] [--smoke] [--couplings 200]

N = 2, J = 2, b = (1, -1) (α = 1, β = -1, p = 2); Table II: ζ = 0.05, Ω = 1, q0 = -1, v0 = 0.1.
C is stepped downward from 10 to 0.5; each value starts from the final state of the previous one
(continuation: oscillator and spins). Top: the section q(φ = 0); bottom: the largest Lyapunov
exponent λ_max, computed on the attractor with the saltation-matrix tangent flow. Regular orbits
have λ_max = -ζ; the paper reports a period-adding cascade from C = 9 downward.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from analysis.dynamics.bifurcation import bifurcation_diagram  # noqa: E402
from hysteresis import SpinDimerEnsemble  # noqa: E402
from oscillators import ForcedOscillator  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        epilog="The defaults are the full size (about 5 s on a quiet machine).",
    )
    parser.add_argument("--out", default="out/examples", help="output directory")
    parser.add_argument("--smoke", action="store_true", help="tiny sizes (for tests)")
    parser.add_argument("--couplings", type=int, default=200, help="number of C values")
    parser.add_argument("--periods", type=int, default=60, help="section points per C")
    parser.add_argument("--transient", type=int, default=200, help="periods dropped per C")
    parser.add_argument("--lyapunov-time", type=float, default=2000.0, help="λ_max run length")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.smoke:
        args.couplings, args.periods, args.transient, args.lyapunov_time = 6, 10, 10, 50.0

    dimer = SpinDimerEnsemble(np.array([[1.0, -1.0]]), spin_coupling=2.0)
    couplings = np.linspace(10.0, 0.5, args.couplings)  # downward, as in the paper
    diagram = bifurcation_diagram(
        lambda c: ForcedOscillator(dimer, c, damping_ratio=0.05, frequency=1.0),
        couplings,
        n_periods=args.periods,
        transient_periods=args.transient,
        continuation=True,
        lyapunov=True,
        lyapunov_t_end=args.lyapunov_time,
        q0=-1.0,
        v0=0.1,
        progress=not args.smoke,
    )
    periods = diagram.periods(tolerance=1e-6)
    for c, lam, k in zip(diagram.values, diagram.max_exponent, periods, strict=True):
        print(
            f"C = {c:6.3f}  λ_max = {lam:+.4f}  period {k if k else '> ' + str(args.periods // 2)}"
        )
    diagram.save(out / "fig_bif_0.npz")

    fig, (ax0, ax1) = plt.subplots(2, 1, figsize=(7, 5.5), sharex=True)
    ax0.plot(np.repeat(diagram.values, args.periods), diagram.q.ravel(), ",k", ms=1)
    ax0.set_ylabel("q(φ = 0)")
    ax0.set_title("N = 2, J = 2, b = (1, -1); C stepped downward with continuation", fontsize=9)
    ax1.plot(diagram.values, diagram.max_exponent, "-", color="tab:red", lw=1)
    ax1.axhline(0.0, color="grey", lw=0.5)
    ax1.axhline(-0.05, color="grey", lw=0.5, ls=":")  # -ζ: regular orbits
    ax1.set_xlabel("C")
    ax1.set_ylabel("$λ_{max}$")
    path = out / "fig_bif_0.png"
    fig.savefig(path, dpi=130, bbox_inches="tight")
    print("wrote", path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
