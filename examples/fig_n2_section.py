"""Poincaré section of the oscillator driven by one spin dimer, on two sheets (fig:N=2_schema b).

    python examples/fig_n2_section.py [--out out/examples] [--smoke] [--coupling 1.0]

q'' + 2ζq' + q = cos(Ωt) + C·M[q] with M the magnetization of one dimer (N = 2, J = 2,
b = (2, 0), so α = 0, β = -2, p = 2); Table II: ζ = 0.05, Ω = 1, q0 = -1, v0 = 0.1. The section
φ = Ωt = 0 mod 2π is coloured by sheet: S1 (both spins down, M = -1) and S2 (M = +1). The paper
states no C for this figure; its point, the two sheets' section points overlapping in the
bistable region -2 < q < 0 (panel b), needs C = 1.0, the default here. At larger C (e.g.
``--coupling 4.0``, the coupling of its large-N comparison) the orbit avoids that region and
no point lies there.
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


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        epilog="The defaults are the full size (about 15 s on a quiet machine).",
    )
    parser.add_argument("--out", default="out/examples", help="output directory")
    parser.add_argument("--smoke", action="store_true", help="tiny sizes (for tests)")
    parser.add_argument("--coupling", type=float, default=1.0, help="C (paper's panel b: 1)")
    parser.add_argument("--periods", type=int, default=3000)
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    periods, transient = (50, 10) if args.smoke else (args.periods, 100)

    dimer = SpinDimerEnsemble(np.array([[2.0, 0.0]]), spin_coupling=2.0)
    th = dimer.thresholds()
    system = ForcedOscillator(dimer, args.coupling, damping_ratio=0.05, frequency=1.0)
    sec = system.poincare_section(periods, transient_periods=transient, q0=-1.0, v0=0.1)

    down = sec.M < 0
    bistable = (sec.q > th.beta[0]) & (sec.q < th.alpha[0])
    print(f"thresholds alpha = {th.alpha[0]:g}, beta = {th.beta[0]:g}")
    print(
        f"{periods} section points: {down.sum()} on S1, {(~down).sum()} on S2; in the bistable "
        f"region: {(bistable & down).sum()} on S1, {(bistable & ~down).sum()} on S2"
    )
    fig, ax = plt.subplots(figsize=(5, 4))
    ax.plot(sec.q[down], sec.v[down], "s", ms=2.5, color="tab:blue", label="$S_1$ (M = -1)")
    ax.plot(sec.q[~down], sec.v[~down], "x", ms=3, color="tab:red", label="$S_2$ (M = +1)")
    for x in (th.beta[0], th.alpha[0]):
        ax.axvline(x, color="grey", lw=0.6)
    ax.set_xlabel("q")
    ax.set_ylabel("v")
    ax.set_title(f"N=2, J=2, b=(2, 0), C={args.coupling:g}: section φ = 0", fontsize=9)
    ax.legend(fontsize=8)
    path = out / "fig_n2_section.png"
    fig.savefig(path, dpi=130, bbox_inches="tight")
    print("wrote", path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
