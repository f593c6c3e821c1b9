"""Kaplan–Yorke dimension of the erf-play limit vs the initial conditions (paper fig:mboa).

    python examples/fig_dky_initial_conditions.py [--out out/examples] [--full | --smoke]
        [--points 16 --t-end 1e4]

The thermodynamic limit (generalized play, p = 2, R = 1) started (a) outside the play at q0 with
w0 = q0 − p/2, (b) inside the play at q0 = −1 with w0 in (q0 − p/2, q0 + p/2), v0 = 0.1 always;
(c) C = 2.92 against q0 and (d) λ_max at C = 1.9 against q0. The paper reports D_KY^∞ in
[1.37, 1.45] (C = 2.9) and [1.42, 1.48] (C = 4.0) independent of q0 and w0, a mix of regular
(D_KY = 0) and chaotic (D_KY in [1.0, 1.5]) starts at C = 2.92, and λ_max < 0 at C = 1.9.

By default 16 starts per curve, each spectrum over t = 10⁴ (about 30 s; the D_KY ranges come
out a little wider than the paper's, finite-time error); ``--full`` runs the paper's 40 starts
over t = 2·10⁴ (about 3 min). The NPZ and the figure are rewritten after every curve.
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


#: sizes (points per curve, Lyapunov run length, transient): the default shows the phenomenon in
#: about half a minute; --full is the paper's (6 curves x 40 spectra over t = 2e4)
SMALL = (16, 1.0e4, 1.0e3)
FULL = (40, 2.0e4, 1.0e3)
SMOKE = (2, 200.0, 20.0)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        epilog="Default: 16 starts per curve over t = 10^4 (about 30 s on a quiet machine). "
        "The data (NPZ) and the figure are rewritten after every curve.",
    )
    parser.add_argument("--out", default="out/examples", help="output directory")
    size = parser.add_mutually_exclusive_group()
    size.add_argument(
        "--full",
        action="store_true",
        help="the paper's sizes: 40 starts per curve, t = 2·10⁴ (about 3 min on a quiet machine)",
    )
    size.add_argument("--smoke", action="store_true", help="tiny sizes (for tests)")
    parser.add_argument("--points", type=int, default=None, help="initial conditions per curve")
    parser.add_argument("--t-end", type=float, default=None, help="Lyapunov run length")
    parser.add_argument("--transient", type=float, default=None)
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    preset = FULL if args.full else SMOKE if args.smoke else SMALL
    points, t_end, transient = (
        given if given is not None else default
        for given, default in zip((args.points, args.t_end, args.transient), preset, strict=True)
    )
    run = (t_end, transient)

    q0s = np.linspace(-2.5, 2.5, points)
    w0s = np.linspace(-1.95, -0.05, points)  # inside the play for q0 = -1: |q0 - w0| < 1
    # (axis, key, coupling, starts (q0, w0), quantity, plot style): one curve each
    outside = [(q, q - WIDTH / 2) for q in q0s]
    inside = [(-1.0, w) for w in w0s]
    curves = [
        (0, "a_C2.9", 2.9, outside, "kaplan_yorke", {"label": "C = 2.9"}),
        (1, "b_C2.9", 2.9, inside, "kaplan_yorke", {"label": "C = 2.9"}),
        (0, "a_C4", 4.0, outside, "kaplan_yorke", {"label": "C = 4"}),
        (1, "b_C4", 4.0, inside, "kaplan_yorke", {"label": "C = 4"}),
        (2, "c_C2.92", 2.92, outside, "kaplan_yorke", {"label": "C = 2.92", "color": "tab:green"}),
        (3, "d_C1.9", 1.9, outside, "max_exponent", {"label": "C = 1.9", "color": "tab:purple"}),
    ]
    fig, axes = plt.subplots(1, 4, figsize=(15, 3.5), layout="constrained")
    labels = [("$q_0$ ($w_0 = q_0 - p/2$)", "$D_{KY}^\\infty$"),
              ("$w_0$ ($q_0 = -1$)", "$D_{KY}^\\infty$"),
              ("$q_0$ ($w_0 = q_0 - p/2$)", "$D_{KY}^\\infty$"),
              ("$q_0$ ($w_0 = q_0 - p/2$)", "$λ_{max}^\\infty$")]  # fmt: skip
    for ax, (xl, yl), tag in zip(axes, labels, "abcd", strict=True):
        ax.set_xlabel(xl)
        ax.set_ylabel(yl)
        ax.set_title(f"({tag})", fontsize=9)
    path = out / "fig_dky_initial_conditions.png"
    data: dict[str, np.ndarray] = {"q0": q0s, "w0": w0s, "t_end": np.array(t_end)}
    for axis, key, c, starts, quantity, style in curves:
        values = np.array([getattr(spectrum(c, q, w, *run), quantity) for q, w in starts])
        x = q0s if axis != 1 else w0s
        axes[axis].plot(x, values, "o-", ms=3, **style)
        axes[axis].legend(fontsize=8)
        data[key] = values
        # a long run killed half-way keeps every finished curve (data and figure)
        np.savez_compressed(out / "fig_dky_initial_conditions.npz", **data)
        fig.savefig(path, dpi=130, bbox_inches="tight")
    for c, tag in ((2.9, "C2.9"), (4.0, "C4")):
        both = np.concatenate([data[f"a_{tag}"], data[f"b_{tag}"]])
        print(f"C = {c:g}: D_KY in [{both.min():.3f}, {both.max():.3f}] over q0 and w0")
    d_c, lam_d = data["c_C2.92"], data["d_C1.9"]
    print(f"C = 2.92: {np.sum(d_c == 0)} regular, {np.sum(d_c > 0)} chaotic starts")
    print(f"C = 1.9: λ_max in [{lam_d.min():.4f}, {lam_d.max():.4f}]")
    print("wrote", path, "and", out / "fig_dky_initial_conditions.npz")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
