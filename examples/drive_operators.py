"""Drive every hysteresis operator with a decaying oscillation and plot all loops in one figure.

    python examples/drive_operators.py [--out out/examples]

Uses only the public API of ``hysteresis``. The Preisach panel is the spin-dimer ensemble's
equivalent discrete Preisach model (``SpinDimerEnsemble.to_preisach``, built with
``PreisachModel.from_relays``); it must agree with the brute-force spin flips to round-off.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hysteresis import (  # noqa: E402
    GeneralizedPlay,
    PlayOperator,
    PrandtlIshlinskii,
    Relay,
    SpinDimerEnsemble,
)


def decaying_oscillation(n: int = 4000, amplitude: float = 4.0, periods: float = 8.0) -> np.ndarray:
    """u_k = A exp(-t/T) sin(t), t in [0, 2π·periods]: nested, shrinking loops."""
    t = np.linspace(0.0, 2.0 * np.pi * periods, n)
    return amplitude * np.exp(-t / (2.0 * np.pi * periods / 2.5)) * np.sin(t)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        epilog="The defaults are the full size (about 5 s on a quiet machine).",
    )
    parser.add_argument("--out", default="out/examples", help="output directory")
    args = parser.parse_args(argv)
    out_dir = Path(args.out)
    out_dir.mkdir(parents=True, exist_ok=True)

    u = decaying_oscillation()
    dimers = SpinDimerEnsemble.random(2000, width=2.0, spread=1.0, spin_coupling=2.0, seed=1)
    pi = PrandtlIshlinskii([0.0, 1.0, 2.0, 4.0], [0.4, 0.3, 0.2, 0.1])

    panels: list[tuple[str, np.ndarray, np.ndarray, str]] = []
    panels.append(("Relay(α=1, β=-1)", u, Relay(1.0, -1.0).apply(u)[0], "y"))
    panels.append(("PlayOperator(width=2)", u, PlayOperator(2.0).apply(u)[0], "w"))
    erf_play = GeneralizedPlay.erf(2.0, 1.0)
    panels.append(("GeneralizedPlay.erf(p=2, R=1)", u, erf_play.apply(u)[0], "M"))
    m_spins, _ = dimers.simulate(u)
    panels.append(("SpinDimerEnsemble N=2000 (spin flips)", u, m_spins, "M"))
    preisach = dimers.to_preisach()
    m_preisach, _ = preisach.apply(u)
    panels.append(("PreisachModel from dimers", u, m_preisach, "M"))
    print(f"max |Preisach(u) - spin flips(u)| = {np.max(np.abs(m_preisach - m_spins)):.2e}")
    y_pi, _ = pi.apply(u)
    panels.append(("PrandtlIshlinskii", u, y_pi, "y"))
    u_back, _ = pi.inverse().apply(y_pi)
    panels.append(("inverse PI (input y, output u)", y_pi, u_back, "u"))
    print(f"max |inverse(PI(u)) - u| = {np.max(np.abs(u_back - u)):.2e}")

    ncols = 4
    nrows = -(-len(panels) // ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(4 * ncols, 3.4 * nrows), squeeze=False)
    for ax, (title, x, y, ylabel) in zip(axes.flat, panels, strict=False):
        ax.plot(x, y, lw=0.8)
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("input")
        ax.set_ylabel(ylabel)
        if title.startswith("GeneralizedPlay"):
            grid = np.linspace(x.min(), x.max(), 200)
            ax.plot(grid, erf_play.ascending(grid), "k:", lw=0.6, label="f(u - p/2)")
            ax.plot(grid, erf_play.descending(grid), "k--", lw=0.6, label="f(u + p/2)")
            ax.legend(fontsize=7)
    for ax in list(axes.flat)[len(panels) :]:
        ax.axis("off")
    fig.tight_layout()
    path = out_dir / "drive_operators.png"
    fig.savefig(path, dpi=120)
    print(f"saved {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
