"""Fit a Prandtl–Ishlinskii model to actuator data and compensate with its exact inverse.

    python examples/compensate_actuator.py [--out out/examples] [--smoke]

The "actuator" is a hysteretic operator the fit does not know, of the piezo-actuator kind
(rate-independent, non-saturating in the working range): a continuum of plays, 80 widths in
(0, 2.5] with weights ``∝ exp(−p/0.8)``, plus a linear term and an offset, measured with noise
— none of its widths is on the fitted lattice. (A saturating actuator is outside the
Prandtl–Ishlinskii class, whose Preisach density is uniform along ``s``; fit it with
:func:`analysis.identification.fitting.fit_preisach_record` instead.) Steps:

1. excite it with an amplitude-modulated sine (the identification record), split the record
   in time (70 % training, 30 % validation) and fit Prandtl–Ishlinskii weights by constrained
   least squares (:func:`analysis.identification.fitting.fit_prandtl_ishlinskii`); print the
   validation error;
2. for a desired output trajectory, compute the command through the fitted model's exact
   inverse (``PrandtlIshlinskii.inverse``) and drive the actuator with it;
3. compare the tracking error with and without compensation, and write a figure.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from analysis.identification.fitting import fit_prandtl_ishlinskii  # noqa: E402
from hysteresis import PrandtlIshlinskii  # noqa: E402

NOISE = 0.005


class Actuator:
    """``y = 0.1 + 0.25 u + Σ_k w_k F_{p_k}[u]``, 80 plays, ``w_k ∝ exp(−p_k/0.8)``."""

    def __init__(self) -> None:
        widths = np.linspace(2.5 / 80, 2.5, 80)
        weights = np.exp(-widths / 0.8)
        weights *= 0.5 / weights.sum()
        self.op = PrandtlIshlinskii(np.r_[0.0, widths], np.r_[0.25, weights])

    def __call__(self, u: np.ndarray, rng: np.random.Generator | None = None) -> np.ndarray:
        y, _ = self.op.apply(u)
        out = 0.1 + y
        if rng is not None:
            out = out + rng.normal(0.0, NOISE, u.size)
        return out


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        epilog="The defaults are the full size (about 5 s on a quiet machine).",
    )
    parser.add_argument("--out", default="out/examples", help="output directory")
    parser.add_argument("--smoke", action="store_true", help="short records (for tests)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    actuator = Actuator()

    n = 2000 if args.smoke else 8000
    t = np.arange(n)
    u = 3.0 * np.sin(2 * np.pi * t / 250) * (0.55 + 0.45 * np.sin(2 * np.pi * t / 1900))
    u[0] = -3.0  # start from (negative) saturation, as the play's initial state assumes
    y = actuator(u, rng)
    widths = np.linspace(0.2, 3.0, 15)
    fit = fit_prandtl_ishlinskii(u, y, widths, train_fraction=0.7)
    print(
        f"PI fit: {widths.size + 1} plays, train RMS {fit.train_rms:.4f}, "
        f"validation RMS {fit.validation_rms:.4f} (noise {NOISE})"
    )

    # compensation of a desired trajectory through the exact inverse
    m = 600 if args.smoke else 2000
    s = np.arange(m)
    y_ref = 0.1 + 0.9 * np.sin(2 * np.pi * s / 300) * np.exp(-s / (2.0 * m))
    inverse = fit.model.inverse()
    u_cmd, _ = inverse.apply(y_ref - fit.offset)  # consistent default states (PI docstring)
    y_comp = actuator(u_cmd)
    gain = (actuator(np.array([3.0]))[0] - actuator(np.array([-3.0]))[0]) / 6.0
    u_naive = (y_ref - 0.1) / gain  # linear inversion of the actuator's major-loop gain
    y_naive = actuator(u_naive)
    skip = 300  # after the first period: both start from the same state
    err_comp = float(np.sqrt(np.mean((y_comp - y_ref)[skip:] ** 2)))
    err_naive = float(np.sqrt(np.mean((y_naive - y_ref)[skip:] ** 2)))
    print(
        f"tracking RMS: linear inversion {err_naive:.4f}, PI inverse {err_comp:.4f} "
        f"({err_naive / err_comp:.1f}x smaller)"
    )

    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    axes[0].plot(u[fit.n_train :], y[fit.n_train :], ".", ms=1, label="validation data")
    axes[0].plot(u[fit.n_train :], fit.predict(u)[fit.n_train :], "-", lw=0.6, label="PI fit")
    axes[0].set_xlabel("u")
    axes[0].set_ylabel("y")
    axes[0].legend(fontsize=8)
    axes[1].plot(s, y_ref, "k-", lw=1, label="desired")
    axes[1].plot(s, y_naive, "-", lw=0.8, label=f"linear inversion (RMS {err_naive:.3f})")
    axes[1].plot(s, y_comp, "-", lw=0.8, label=f"PI inverse (RMS {err_comp:.3f})")
    axes[1].set_xlabel("sample")
    axes[1].legend(fontsize=8)
    path = out / "compensate_actuator.png"
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)
    print("figure:", path)


if __name__ == "__main__":
    main()
