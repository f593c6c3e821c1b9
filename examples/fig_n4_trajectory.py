"""A trajectory of the oscillator driven by two spin dimers, coloured by sheet (fig:N=4_traj).

    python examples/fig_n4_trajectory.py [--out out/examples] [--smoke] [--coupling 4.0]

N = 4 spins, J = 2, b = (2, 0, -0.5, -2.5): two dimers with loop width p = 2 and thresholds
α = (0, 2.5), β = (-2, 0.5). The magnetization takes the values -1, 0, +1 (sheets S1, S2, S3);
the exact switch events of the integrator are printed and compared with the thresholds. The
paper gives no C for this figure; C = 4.0 is the coupling of its large-N comparison.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hysteresis import SpinDimerEnsemble  # noqa: E402
from oscillators import ForcedOscillator  # noqa: E402

SHEETS = {-1.0: ("tab:purple", ":", "$S_1$"), 0.0: ("tab:green", "--", "$S_2$"),
          1.0: ("salmon", "-", "$S_3$")}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        epilog="The defaults are the full size (about 5 s on a quiet machine).",
    )
    parser.add_argument("--out", default="out/examples", help="output directory")
    parser.add_argument("--smoke", action="store_true", help="tiny sizes (for tests)")
    parser.add_argument("--coupling", type=float, default=4.0, help="C")
    parser.add_argument("--periods", type=float, default=40.0, help="length in forcing periods")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    dimers = SpinDimerEnsemble(np.array([[2.0, 0.0], [-0.5, -2.5]]), spin_coupling=2.0)
    th = dimers.thresholds()
    system = ForcedOscillator(dimers, args.coupling, damping_ratio=0.05, frequency=1.0)
    periods = 5.0 if args.smoke else args.periods
    traj = system.trajectory(periods * system.period, q0=-1.0, v0=0.1, sample_dt=0.005)

    sw = traj.switches  # structured array: time, q, v, jump
    print(f"thresholds alpha = {th.alpha.tolist()}, beta = {th.beta.tolist()}")
    up = sorted({round(float(x), 9) for x in sw["q"][sw["jump"] > 0]})
    down = sorted({round(float(x), 9) for x in sw["q"][sw["jump"] < 0]})
    print(f"{len(sw)} switches: up at q = {up}, down at q = {down}")

    fig, ax = plt.subplots(figsize=(5.5, 4))
    for m, (color, ls, name) in SHEETS.items():
        on = np.isclose(traj.M, m)
        ax.plot(np.where(on, traj.q, np.nan), np.where(on, traj.v, np.nan), ls, color=color,
                lw=1, label=f"{name} (M = {m:g})")  # fmt: skip
    ax.set_xlabel("q")
    ax.set_ylabel("v")
    ax.legend(fontsize=8)
    ax.set_title(f"N=4, J=2, b=(2, 0, -0.5, -2.5), C={args.coupling:g}", fontsize=9)
    path = out / "fig_n4_trajectory.png"
    fig.savefig(path, dpi=130, bbox_inches="tight")
    print("wrote", path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
