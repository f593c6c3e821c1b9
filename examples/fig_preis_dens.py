"""Preisach density of N spin dimers and of their limit, the erf play (paper fig:preis_dens).

    python examples/fig_preis_dens.py [--out out/examples] [--smoke] [--spins 20000 --step 0.1]

Both operators are driven through first-order reversal curves on a regular grid (rise from
negative saturation to α, fall to β); the mixed second differences of the Everett function give
the exact mass of every grid cell. The paper's density is μ(r, s) = N(s; 0, R²) δ(r − p/2):
a ridge at r = p/2 with Gaussian centres. Printed: total mass, centre and spread of the ridge in
r, and the sup distance of the s-marginal CDF to the Gaussian (for the dimers next to the
Kolmogorov 95 % bound 1.36/sqrt(N/2) of a sample of N/2 loop centres).
See examples/identify_density.py for the FORC-file (MicroMag) round trip.
"""

from __future__ import annotations

import argparse

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402

from analysis.identification import compare_with_ridge, identify_preisach  # noqa: E402
from analysis.identification.plots import figure_preisach_density  # noqa: E402
from hysteresis import GeneralizedPlay, SpinDimerEnsemble  # noqa: E402

WIDTH, SPREAD, COUPLING = 2.0, 1.0, 2.0  # p, R, J


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        epilog="The defaults are the full size (about 5 s on a quiet machine).",
    )
    parser.add_argument("--out", default="out/examples", help="output directory")
    parser.add_argument("--smoke", action="store_true", help="tiny sizes (for tests)")
    parser.add_argument("--spins", type=int, default=20000, help="N")
    parser.add_argument("--step", type=float, default=0.1, help="grid step Δ")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    spins, step = (400, 0.25) if args.smoke else (args.spins, args.step)

    play = GeneralizedPlay.erf(WIDTH, SPREAD)
    dimers = SpinDimerEnsemble.random(spins, WIDTH, SPREAD, COUPLING, seed=args.seed)
    th = dimers.thresholds()
    # grid large enough for every relay of the ensemble and the play's Gaussian tails (5R)
    saturation = max(5 * SPREAD + WIDTH / 2, float(np.max(np.abs([th.alpha, th.beta]))) + step)

    limit = identify_preisach(play, step, saturation)
    finite = identify_preisach(dimers, step, saturation, progress=not args.smoke)
    for name, ident, centres in (("erf play", limit, None), (f"N={spins}", finite, th.centre)):
        c = compare_with_ridge(ident, WIDTH, SPREAD, centres=centres)
        line = (
            f"{name:9s} mass {c.total_mass:.6f}  r centre {c.r_centre:.4f} (p/2 = {WIDTH / 2:g})"
            f"  sup|G - Gauss| {c.s_cdf_distance_gaussian:.4f}"
        )
        if c.kolmogorov_bound is not None:
            line += f"  (Kolmogorov 95 % bound {c.kolmogorov_bound:.4f})"
        print(line)
    paths = figure_preisach_density(
        limit, finite, WIDTH, SPREAD, args.out, finite_label=f"N = {spins}"
    )
    print("wrote", ", ".join(str(p) for p in paths))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
