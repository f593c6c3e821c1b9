"""Chaotic attractors at C = 4.0: the erf-play limit vs N = 20 000 spin dimers (fig:erf_10000).

    python examples/fig_attractors.py [--out out/examples] [--smoke] [--spins 20000]

Grey: the trajectory projected on (q, v); red: C·M(t); blue: the Poincaré section φ = 0 (for the
limit projected from (q, v, w), for the dimers the superposition of all N/2 + 1 sheets). Also
printed: the Lyapunov spectra and Kaplan–Yorke dimensions of both systems, and the
Kolmogorov–Smirnov distance between the q-distributions of the two sections.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from scipy.stats import ks_2samp  # noqa: E402

from analysis.dynamics.lyapunov import lyapunov_spectrum  # noqa: E402
from hysteresis import GeneralizedPlay, SpinDimerEnsemble  # noqa: E402
from oscillators import ForcedOscillator  # noqa: E402

WIDTH, SPREAD, COUPLING_J, C = 2.0, 1.0, 2.0, 4.0  # p, R, J, C


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        epilog="The defaults are the full size (about 5 s on a quiet machine).",
    )
    parser.add_argument("--out", default="out/examples", help="output directory")
    parser.add_argument("--smoke", action="store_true", help="tiny sizes (for tests)")
    parser.add_argument("--spins", type=int, default=20000, help="N")
    parser.add_argument("--seed", type=int, default=0, help="disorder seed")
    parser.add_argument("--periods", type=int, default=2000, help="section points")
    parser.add_argument("--lyapunov-time", type=float, default=2.0e4)
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.smoke:
        args.spins, args.periods, args.lyapunov_time = 400, 30, 200.0
    transient = 100

    systems = {
        "N = ∞ (erf play)": ForcedOscillator(GeneralizedPlay.erf(WIDTH, SPREAD), C),
        f"N = {args.spins}": ForcedOscillator(
            SpinDimerEnsemble.random(args.spins, WIDTH, SPREAD, COUPLING_J, seed=args.seed), C
        ),
    }
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharex=True, sharey=True)
    sections = []
    for ax, (name, system) in zip(axes, systems.items(), strict=True):
        sec = system.poincare_section(args.periods, transient_periods=transient, q0=-1.0, v0=0.1)
        end = sec.final  # on the attractor: continue from here
        shown = min(30, args.periods)
        traj = system.trajectory(shown * system.period, end.q, end.v, end.operator_state, 0.02)
        ly = lyapunov_spectrum(
            system, args.lyapunov_time, 0.0, end.q, end.v, end.operator_state, progress=False
        )
        print(f"{name}: λ = {np.round(ly.exponents, 4).tolist()}, D_KY = {ly.kaplan_yorke:.3f}")
        sections.append(sec.q)
        ax.plot(traj.q, traj.v, "-", color="0.8", lw=0.5)
        ax.plot(traj.q, C * traj.M, "-", color="tab:red", lw=0.8, label="C·M")
        ax.plot(sec.q, sec.v, ".", ms=1.5, color="tab:blue", label="section φ = 0")
        ax.set_title(f"{name}, C = {C:g}", fontsize=9)
        ax.set_xlabel("q")
    print(f"KS distance of the sections' q: {ks_2samp(*sections).statistic:.3f}")
    axes[0].set_ylabel("v,  C·M")
    axes[0].legend(fontsize=8, loc="upper left")
    path = out / "fig_attractors.png"
    fig.savefig(path, dpi=130, bbox_inches="tight")
    print("wrote", path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
