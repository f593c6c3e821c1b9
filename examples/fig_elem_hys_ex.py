"""Energies of the four states of one spin dimer and its loop (paper fig:elem_hys_ex).

    python examples/fig_elem_hys_ex.py [--out out/examples] [--smoke]

J = 2, b = (2, 1). The energy H(σ1, σ2) = -J σ1σ2 - σ1(q + b1) - σ2(q + b2) of each state is a
straight line in q; the loop's thresholds α = J - b1 = 0 and β = -J - b2 = -3 sit where the
energetically favourable single-spin-flip neighbour changes. A random input walk shows that the
state (↓, ↑) is never reached by single-spin-flip dynamics.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hysteresis import SpinDimerEnsemble  # noqa: E402

COUPLING, B1, B2 = 2.0, 2.0, 1.0
STATES = {"↓↓": (-1, -1), "↓↑": (-1, 1), "↑↓": (1, -1), "↑↑": (1, 1)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        epilog="The defaults are the full size (about 5 s on a quiet machine).",
    )
    parser.add_argument("--out", default="out/examples", help="output directory")
    parser.add_argument("--smoke", action="store_true", help="tiny sizes (for tests)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    dimer = SpinDimerEnsemble(np.array([[B1, B2]]), COUPLING)
    th = dimer.thresholds()
    q = np.linspace(-6.0, 4.0, 201 if args.smoke else 1001)
    energies = {k: np.array([dimer.energy(np.array(s), x) for x in q]) for k, s in STATES.items()}
    u = np.concatenate([q, q[::-1][1:]])
    m, _ = dimer.simulate(u)

    # visit states with a bounded random walk, one input at a time
    rng = np.random.default_rng(args.seed)
    walk = 4.0 * np.tanh(np.cumsum(rng.normal(0.0, 0.3, 500 if args.smoke else 20000)) / 8) - 1
    seen, spins = set(), None
    for x in walk:
        _, spins = dimer.simulate(np.array([x]), spins=spins)
        seen.add(tuple(int(s) for s in spins))
    names = {v: k for k, v in STATES.items()}
    print(f"alpha = {th.alpha[0]:g}, beta = {th.beta[0]:g}, width p = {th.width[0]:g}")
    print("metastable states reached by the random walk:", sorted(names[s] for s in seen))

    fig, (ax0, ax1) = plt.subplots(2, 1, figsize=(5.5, 6), sharex=True)
    for k, e in energies.items():
        ax0.plot(q, e, label=k)
    ax0.set_ylabel("H(σ1, σ2)")
    ax0.legend(fontsize=8, ncol=4)
    ax0.set_title(f"J={COUPLING:g}, b=({B1:g}, {B2:g}): α={th.alpha[0]:g}, β={th.beta[0]:g}")
    ax1.plot(u, m, "k:", lw=1.5)
    for x in (th.alpha[0], th.beta[0]):
        ax1.axvline(x, color="grey", lw=0.5)
    ax1.set_xlabel("q")
    ax1.set_ylabel("M")
    path = out / "fig_elem_hys_ex.png"
    fig.savefig(path, dpi=130, bbox_inches="tight")
    print("wrote", path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
