"""Width disorder: continuum Preisach models with a spread of loop widths against finite N.

    python examples/width_disorder.py [--out out/examples] [--full | --smoke] [--workers K]
        [--t-end T] [--realizations R]

The same study as ``hyst width-disorder`` (see its help and README "What the reproduction
finds"), through the library: :func:`analysis.experiments.width_disorder.run_study`. By
default a small run (under a minute on a quiet machine: σ_r ∈ {0.05, 0.2}, C ∈ {2.9, 4}, one
initial condition, t = 2000; finite N = 1000 with 10 realizations) that shows every quantity
with its finite-time errors; ``--full`` runs the study's sizes (σ_r ∈ {0.0125 … 0.4}, three
initial conditions, t = 2·10⁴, transient 160 periods; finite N ∈ {10³, 5·10³, 2·10⁴} with 100
realizations each: hours on two cores), resumable through ``OUT/results.sqlite``, then
:func:`~analysis.experiments.width_disorder_plot.plot_study`. For every (C, σ_r) it gives the
spectrum with memory directions and its neutral exponents, the exponents without long-lived
memory, D_KY of both and D_BC of the section; σ_r = 0 is the erf play. ``--smoke`` runs a tiny
configuration (seconds).
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

from analysis._json import to_json
from analysis.experiments.width_disorder import run_study
from analysis.experiments.width_disorder_plot import plot_study

SMALL = dict(
    width_spreads=(0.05, 0.2),
    t_end=2000.0,
    transient_periods=50,
    initial_conditions=1,
    section_t_end=4000.0,
    blocks=4,
    spins=(1000,),
    realizations=10,
    finite_t_end=2000.0,
    finite_transient_periods=50,
)
SMOKE = dict(
    t_end=10 * 2 * math.pi,
    transient_periods=2,
    section_t_end=12 * 2 * math.pi,
    initial_conditions=1,
    blocks=4,
    spins=(40,),
    realizations=2,
    finite_t_end=10 * 2 * math.pi,
    finite_transient_periods=2,
)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/examples", help="output directory")
    size = parser.add_mutually_exclusive_group()
    size.add_argument("--full", action="store_true", help="the study's sizes (hours)")
    size.add_argument("--smoke", action="store_true", help="tiny sizes (for tests)")
    parser.add_argument("--workers", type=int, default=1, help="worker processes")
    parser.add_argument("--t-end", type=float, default=None, help="continuum run length")
    parser.add_argument("--realizations", type=int, default=None, help="finite-N realizations")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    overrides = {} if args.full else dict(SMOKE) if args.smoke else dict(SMALL)
    if args.t_end is not None:
        overrides["t_end"] = args.t_end
    if args.realizations is not None:
        overrides["realizations"] = args.realizations
    record = run_study(
        "quick" if args.smoke else "full",
        store=out / "results.sqlite",
        workers=args.workers,
        **overrides,
    )
    (out / "width_disorder.json").write_text(to_json(record, indent=1) + "\n")
    plot_study(json.loads(to_json(record)), out / "width_disorder.png")
    for p in record["continuum"]:
        print(
            f"C = {p['coupling']:g}, sigma_r = {p['width_spread']:<6g}: "
            f"lambda_1 = {p['lambda_max'][0]:+.4f}, D_KY = {p['kaplan_yorke'][0]:.3f}, "
            f"neutral = {p['neutral']}, D_BC = {p['box_counting'][0]:.3f}"
        )
    print(f"wrote {out / 'width_disorder.png'} and {out / 'width_disorder.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
