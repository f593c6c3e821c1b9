"""Kaplan–Yorke dimension of the erf-play limit vs the initial conditions (paper fig:mboa).

    python examples/fig_dky_initial_conditions.py [--out out/examples] [--smoke] [--points 40]

The thermodynamic limit (generalized play, p = 2, R = 1) started (a) outside the play at q0 with
w0 = q0 − p/2, (b) inside the play at q0 = −1 with w0 in (q0 − p/2, q0 + p/2), v0 = 0.1 always;
(c) C = 2.92 against q0 and (d) λ_max at C = 1.9 against q0. The paper reports D_KY^∞ in
[1.37, 1.45] (C = 2.9) and [1.42, 1.48] (C = 4.0) independent of q0 and w0, a mix of regular
(D_KY = 0) and chaotic (D_KY in [1.0, 1.5]) starts at C = 2.92, and λ_max < 0 at C = 1.9.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from analysis.dynamics.lyapunov import lyapunov_spectrum  # noqa: E402
from hysteresis import GeneralizedPlay  # noqa: E402
from oscillators import ForcedOscillator  # noqa: E402

WIDTH, SPREAD = 2.0, 1.0  # p, R


def spectrum(coupling: float, q0: float, w0: float, t_end: float, transient: float):
    system = ForcedOscillator(GeneralizedPlay.erf(WIDTH, SPREAD), coupling, 0.05, 1.0)
    state = system.operator.state(position=w0, input=q0)  # the initial memory is the state
    return lyapunov_spectrum(
        system, t_end, transient, q0=q0, v0=0.1, operator_state=state, progress=False
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/examples", help="output directory")
    parser.add_argument("--smoke", action="store_true", help="tiny sizes (for tests)")
    parser.add_argument("--points", type=int, default=40, help="initial conditions per curve")
    parser.add_argument("--t-end", type=float, default=2.0e4, help="Lyapunov run length")
    parser.add_argument("--transient", type=float, default=1.0e3)
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.smoke:
        args.points, args.t_end, args.transient = 2, 200.0, 20.0
    run = (args.t_end, args.transient)

    q0s = np.linspace(-2.5, 2.5, args.points)
    w0s = np.linspace(-1.95, -0.05, args.points)  # inside the play for q0 = -1: |q0 - w0| < 1
    fig, axes = plt.subplots(1, 4, figsize=(15, 3.5))
    for c in (2.9, 4.0):
        d_a = [spectrum(c, q, q - WIDTH / 2, *run).kaplan_yorke for q in q0s]
        d_b = [spectrum(c, -1.0, w, *run).kaplan_yorke for w in w0s]
        axes[0].plot(q0s, d_a, "o-", ms=3, label=f"C = {c:g}")
        axes[1].plot(w0s, d_b, "o-", ms=3, label=f"C = {c:g}")
        both = np.array(d_a + d_b)
        print(f"C = {c:g}: D_KY in [{both.min():.3f}, {both.max():.3f}] over q0 and w0")
    d_c = np.array([spectrum(2.92, q, q - WIDTH / 2, *run).kaplan_yorke for q in q0s])
    lam_d = np.array([spectrum(1.9, q, q - WIDTH / 2, *run).max_exponent for q in q0s])
    print(f"C = 2.92: {np.sum(d_c == 0)} regular, {np.sum(d_c > 0)} chaotic starts")
    print(f"C = 1.9: λ_max in [{lam_d.min():.4f}, {lam_d.max():.4f}]")
    axes[2].plot(q0s, d_c, "o-", ms=3, color="tab:green", label="C = 2.92")
    axes[3].plot(q0s, lam_d, "o-", ms=3, color="tab:purple", label="C = 1.9")
    labels = [("$q_0$ ($w_0 = q_0 - p/2$)", "$D_{KY}^\\infty$"),
              ("$w_0$ ($q_0 = -1$)", "$D_{KY}^\\infty$"),
              ("$q_0$ ($w_0 = q_0 - p/2$)", "$D_{KY}^\\infty$"),
              ("$q_0$ ($w_0 = q_0 - p/2$)", "$λ_{max}^\\infty$")]  # fmt: skip
    for ax, (xl, yl), tag in zip(axes, labels, "abcd", strict=True):
        ax.set_xlabel(xl)
        ax.set_ylabel(yl)
        ax.set_title(f"({tag})", fontsize=9)
        ax.legend(fontsize=8)
    path = out / "fig_dky_initial_conditions.png"
    fig.savefig(path, dpi=130, bbox_inches="tight")
    print("wrote", path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
