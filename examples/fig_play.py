"""The generalized play: the spin-dimer system's thermodynamic limit (paper fig:play).

    python examples/fig_play.py [--out out/examples] [--smoke]

For N → ∞ dimers with loop width p and Gaussian loop centres (spread R) the magnetization is
M = erf(w/(√2 R)), w the wagon position of a mechanical play of width p (Eq. play). Driven along
a major loop and then back and forth inside it, M follows the envelopes f+(q) = erf((q − p/2)/(√2R))
(rising) and f−(q) = erf((q + p/2)/(√2R)) (falling) and runs flat in between (degenerate inner
loops). The right panel overlays N = 2000 spin dimers with the same p and R.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hysteresis import GeneralizedPlay, SpinDimerEnsemble  # noqa: E402

WIDTH, SPREAD = 2.0, 1.0  # p, R


def drive(points: list[float], step: float) -> np.ndarray:
    """Piecewise-linear input through the given turning points."""
    parts = [np.array([points[0]])]
    for a, b in zip(points[:-1], points[1:], strict=True):
        n = max(int(abs(b - a) / step), 1)
        parts.append(np.linspace(a, b, n + 1)[1:])
    return np.concatenate(parts)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        epilog="The defaults are the full size (about 10 s on a quiet machine).",
    )
    parser.add_argument("--out", default="out/examples", help="output directory")
    parser.add_argument("--smoke", action="store_true", help="tiny sizes (for tests)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    play = GeneralizedPlay.erf(WIDTH, SPREAD)
    u = drive([-5, 5, -5, 1.5, -0.5, 2.5, -2.0], step=0.05 if args.smoke else 0.01)
    m, _ = play.apply(u)
    grid = np.linspace(-5, 5, 401)
    inside = np.all(m >= play.ascending(u) - 1e-12) and np.all(m <= play.descending(u) + 1e-12)
    print(f"output stays between the envelopes f+ <= M <= f-: {bool(inside)}")

    dimers = SpinDimerEnsemble.random(200 if args.smoke else 2000, WIDTH, SPREAD, 2.0, args.seed)
    m_dimers, _ = dimers.apply(u)
    print(f"max |M_dimers - M_play| along the drive: {np.max(np.abs(m_dimers - m)):.3f}")

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    for ax in axes:
        ax.plot(grid, play.ascending(grid), "r--", lw=1, label="$f_+$ (ascending)")
        ax.plot(grid, play.descending(grid), "b--", lw=1, label="$f_-$ (descending)")
        ax.set_xlabel("q")
    axes[0].plot(u, m, "k-", lw=1, label="M[q], erf play")
    axes[1].plot(u, m_dimers, "-", color="tab:green", lw=1, label=f"N = {dimers.n_spins} dimers")
    axes[0].set_ylabel("M")
    axes[0].set_title(f"generalized play, p = {WIDTH:g}, R = {SPREAD:g}", fontsize=9)
    axes[1].set_title("the same drive, finite N", fontsize=9)
    for ax in axes:
        ax.legend(fontsize=8)
    path = out / "fig_play.png"
    fig.savefig(path, dpi=130, bbox_inches="tight")
    print("wrote", path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
