"""Identify the Preisach density of the erf play and of spin dimers (paper fig:preis_dens).

    python examples/identify_density.py [--out out/examples] [--smoke] [--spins 20000 --step 0.1]

Drives both operators through first-order reversal curves (rise from negative saturation to α,
fall to β), prints the exact cell-mass statistics against the paper's density
``N(s; 0, R²) δ(r − p/2)``, writes the figure (``identify_density.png``, PDF, NPZ; the paper
figure itself, ``fig_preis_dens.*``, is ``examples/fig_preis_dens.py``'s), and shows the
FORC-file round trip: Pike curves of the ensemble written as a MicroMag file, read back and
identified again.

Last, the measured-data path: the same Pike curves with measurement noise, identified on the
protocol grid with local-regression smoothing (FORC diagram ``identify_noisy_forc.png``), then
projected onto a valid discrete model (``PreisachModel.from_identification``) that reproduces
a held-out input sequence within the noise.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402

from analysis.identification import (  # noqa: E402
    ReversalCurves,  # noqa: E402
    compare_with_ridge,
    identify_from_curves,
    identify_preisach,
    measure_reversal_curves,
)
from analysis.identification.forc_io import read_micromag, write_micromag  # noqa: E402
from analysis.identification.plots import figure_forc, figure_preisach_density  # noqa: E402
from hysteresis import GeneralizedPlay, PreisachModel, SpinDimerEnsemble  # noqa: E402
from hysteresis.preisach.projection import project_identification  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        epilog="The defaults are the full size (about 5 s on a quiet machine).",
    )
    parser.add_argument("--out", default="out/examples", help="output directory")
    parser.add_argument("--smoke", action="store_true", help="tiny sizes (for tests)")
    parser.add_argument("--spins", type=int, default=20000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--step", type=float, default=0.1)
    args = parser.parse_args()
    if args.smoke:
        args.spins, args.step = 400, 0.25
    width, spread, coupling = 2.0, 1.0, 2.0
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    play = GeneralizedPlay.erf(width, spread)
    dimers = SpinDimerEnsemble.random(args.spins, width, spread, coupling, seed=args.seed)
    th = dimers.thresholds()
    saturation = max(5 * spread + width / 2, float(np.max(np.abs([th.alpha, th.beta]))))

    limit = identify_preisach(play, args.step, saturation)
    finite = identify_preisach(dimers, args.step, saturation, progress=not args.smoke)
    for name, ident, centres in (("erf play", limit, None), ("dimers", finite, th.centre)):
        cmp = compare_with_ridge(ident, width, spread, centres=centres)
        print(f"{name:9s}", {k: f"{v:.3g}" for k, v in cmp.as_dict().items() if v is not None})
    paths = figure_preisach_density(
        limit, finite, width, spread, out, stem="identify_density", finite_label=f"N = {args.spins}"
    )
    print("figure:", ", ".join(str(p) for p in paths))

    # measured-data path: Pike FORCs of the ensemble on a coarser grid, through a MicroMag file
    nodes = np.arange(-saturation, saturation + 1e-9, 0.25)
    curves = measure_reversal_curves(dimers, nodes, nodes, convention="pike", saturation=saturation)
    path = write_micromag(out / "dimers_forc.micromag", curves)
    again = identify_from_curves(read_micromag(path).curves)
    direct = identify_from_curves(curves)
    print(
        "MicroMag round trip: max |Δ cell mass| =",
        float(np.max(np.abs(again.cell_mass - direct.cell_mass))),
    )

    # measured-data path: noise, smoothing, FORC diagram, projection onto a valid model
    rng = np.random.default_rng(args.seed)
    noise = 0.01
    noisy = ReversalCurves(
        curves.reversal_field,
        curves.fields,
        tuple(m + rng.normal(0.0, noise, m.size) for m in curves.moments),
        "pike",
    )
    smooth = identify_from_curves(noisy, smoothing=2, extend=False, grid="protocol")
    bc, bu, _ = smooth.density_peak()
    print(f"noisy FORCs: peak at B_c = {bc:.3g}, B_u = {bu:.3g} (ridge at r = p/2 = {width / 2:g})")
    figure_forc(
        smooth,
        out,
        "identify_noisy_forc",
        title="dimers + noise",
        field_unit=None,
        moment_unit=None,
    )
    raw = identify_from_curves(noisy, grid="native")  # exact cell masses on the nodes
    proj = project_identification(raw)
    model = PreisachModel.from_identification(raw)
    k, idx = nodes.size // 2, []
    for d in rng.integers(-6, 7, 400):  # held-out input: a clipped random walk on the nodes
        k = min(max(k + int(d), 0), nodes.size - 1)
        idx.append(k)
    u = nodes[np.array(idx)]
    err = np.sqrt(np.mean((proj.scale * model.apply(u)[0] - dimers.apply(u)[0]) ** 2))
    print(f"projected model: {model.n_relays} relays, held-out RMS {err:.4f} (noise {noise})")


if __name__ == "__main__":
    main()
