"""Elementary hysteresis of one spin dimer (paper fig:elem_hys and Table I).

    python examples/fig_elem_hys.py [--out out/examples] [--smoke]

Two ferromagnetically coupled spins (J > 0, local fields b1 > b2) driven by a field q that rises
and falls. Depending on 2J vs b1 - b2 the dimer has an elementary hysteresis loop, a single jump
(border case) or two reversible flips. The loops come from the brute-force single-spin-flip
dynamics (``SpinDimerEnsemble.simulate``); the printed table compares the flip positions with
Table I: both spins down for q < J - b1, (up, down) for J - b1 < q < -J - b2, both up above.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hysteresis import SpinDimerEnsemble  # noqa: E402

COUPLING = 2.0  # J
CASES = {  # name: (b1, b2)
    "hysteretic, 2J > b1-b2": (2.0, 1.0),
    "border, 2J = b1-b2": (2.5, -1.5),
    "two reversible flips, 2J < b1-b2": (3.0, -3.0),
}


def flip_inputs(u: np.ndarray, m: np.ndarray) -> list[float]:
    """First grid inputs past each switch (a threshold is crossed within one input step)."""
    return [round(float(x), 3) for x in u[1:][np.diff(m) != 0]]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        epilog="The defaults are the full size (about 5 s on a quiet machine).",
    )
    parser.add_argument("--out", default="out/examples", help="output directory")
    parser.add_argument("--smoke", action="store_true", help="tiny sizes (for tests)")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    n = 121 if args.smoke else 1201  # input step 0.1 or 0.01
    up = np.linspace(-6.0, 6.0, n)
    u = np.concatenate([up, up[::-1][1:]])  # rise, then fall: one major loop

    fig, axes = plt.subplots(1, 3, figsize=(11, 3.2), sharey=True)
    step = float(up[1] - up[0])
    print(f"{'case':34s} {'J-b1':>6s} {'-J-b2':>6s}  flips rising / falling (input step {step:g})")
    for ax, (name, (b1, b2)) in zip(axes, CASES.items(), strict=True):
        dimer = SpinDimerEnsemble(np.array([[b1, b2]]), COUPLING)
        m, _ = dimer.simulate(u)
        rising, falling = m[:n], m[n - 1 :]
        ax.plot(up, rising, "-", color="tab:red", label="rising q")
        ax.plot(u[n - 1 :], falling, "--", color="tab:blue", label="falling q")
        ax.set_title(f"{name}\nb=({b1:g}, {b2:g}), J={COUPLING:g}", fontsize=9)
        ax.set_xlabel("q")
        print(
            f"{name:34s} {COUPLING - b1:6.2f} {-COUPLING - b2:6.2f}  "
            f"{flip_inputs(up, rising)} / {flip_inputs(u[n - 1 :], falling)}"
        )
    axes[0].set_ylabel("M")
    axes[0].legend(fontsize=8)
    path = out / "fig_elem_hys.png"
    fig.savefig(path, dpi=130, bbox_inches="tight")
    print("wrote", path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
