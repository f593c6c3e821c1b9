"""``hyst ensemble``: disorder ensembles of the dimer-coupled oscillator (paper fig:dim, fig:sap,
fig:mag, fig:mag_his).

One task per (N, C, realization) — Lyapunov spectrum, D_KY, D_BC of the section, M_T — run on a
local process pool or a Dask cluster (``--scheduler``), stored in an SQLite file as each task
finishes; a rerun resumes. Writes DIR/ensemble.json (the summary) and DIR/ensemble.npz (the
per-realization values of every point).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "ensemble",
        help="disorder ensemble: mean and SAP of D_KY and D_BC, VAR[M]",
        description="Run (or resume) an ensemble over disorder realizations and aggregate it "
        "per (N, C): means and self-averaging parameters of D_KY and D_BC, VAR[M_T], the "
        "number of regular realizations (D_KY = 0).",
    )
    p.add_argument(
        "--model",
        choices=("dimers",),
        default="dimers",
        help="operator (spin dimers with the paper's disorder)",
    )
    p.add_argument("--spins", type=int, nargs="+", required=True, help="N values")
    p.add_argument("--coupling", type=float, nargs="+", required=True, help="C values")
    p.add_argument("--realizations", type=int, required=True, help="realizations per (N, C)")
    p.add_argument("--t-end", type=float, default=20000.0, help="end time per realization")
    p.add_argument("--transient", type=float, default=1000.0, help="transient time")
    p.add_argument("--seed", type=int, default=0, help="base seed of the disorder")
    p.add_argument("--width", type=float, default=2.0, help="p, loop width")
    p.add_argument("--spread", type=float, default=1.0, help="R, spread of loop centres")
    p.add_argument("--spin-coupling", type=float, default=2.0, help="J")
    p.add_argument("--damping-ratio", type=float, default=0.05, help="zeta")
    p.add_argument("--frequency", type=float, default=1.0, help="Omega")
    p.add_argument(
        "--box-max-fill",
        type=float,
        default=0.1,
        help="box counting: largest count used, as a fraction of the section points",
    )
    p.add_argument(
        "--box-min-boxes",
        type=float,
        default=8.0,
        help="box counting: smallest number of boxes across the attractor",
    )
    p.add_argument("--store", default=None, help="SQLite results file (default DIR/results.sqlite)")
    p.add_argument("--workers", type=int, default=None, help="local worker processes")
    p.add_argument("--scheduler", default=None, help="Dask distributed scheduler address")
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from analysis.ensemble import run_ensemble

    out = Path(args.out)
    try:
        if args.realizations < 1:
            raise ValueError(f"--realizations must be >= 1, got {args.realizations}")
        if args.workers is not None and args.workers < 1:
            raise ValueError(f"--workers must be >= 1, got {args.workers}")
        out.mkdir(parents=True, exist_ok=True)
        store = args.store if args.store is not None else out / "results.sqlite"
        points = run_ensemble(
            args.spins,
            args.coupling,
            args.realizations,
            args.seed,
            args.t_end,
            args.transient,
            store=store,
            workers=args.workers,
            scheduler=args.scheduler,
            progress=not (args.quiet or args.json),
            width=args.width,
            spread=args.spread,
            spin_coupling=args.spin_coupling,
            damping_ratio=args.damping_ratio,
            frequency=args.frequency,
            box_max_fill=args.box_max_fill,
            box_min_boxes=args.box_min_boxes,
        )
    except (ValueError, ImportError) as exc:
        print(f"hyst ensemble: error: {exc}", file=sys.stderr)
        return 2
    record = {
        "model": args.model,
        "t_end": args.t_end,
        "transient": args.transient,
        "seed": args.seed,
        "store": str(store),
        "points": [pt.to_json() for pt in points],
    }
    (out / "ensemble.json").write_text(json.dumps(record, indent=2))
    arrays = {}
    for pt in points:
        tag = f"N{pt.spins}_C{pt.coupling:g}"
        for field in ("kaplan_yorke", "box_counting", "magnetization", "max_exponent"):
            arrays[f"{tag}_{field}"] = getattr(pt, field)
    np.savez_compressed(out / "ensemble.npz", **arrays)
    if args.json:
        print(json.dumps(record))
    else:
        print(
            f"{'N':>7} {'C':>6} {'K':>5} {'<D_KY>':>8} {'SAP_KY':>8} {'<D_BC>':>8} "
            f"{'SAP_BC':>8} {'VAR[M]':>10} {'regular':>7}"
        )
        for pt in points:
            print(
                f"{pt.spins:7d} {pt.coupling:6.3g} {pt.realizations:5d} "
                f"{pt.mean_kaplan_yorke:8.4f} {pt.sap_kaplan_yorke:8.4f} "
                f"{pt.mean_box_counting:8.4f} {pt.sap_box_counting:8.4f} "
                f"{pt.var_magnetization:10.3e} {pt.regular_count:7d}"
            )
        print(f"wrote {out / 'ensemble.json'} and {out / 'ensemble.npz'}")
    return 0
