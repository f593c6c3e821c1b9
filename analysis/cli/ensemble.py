"""``hyst ensemble``: disorder ensembles of the dimer-coupled oscillator (paper fig:dim, fig:sap,
fig:mag, fig:mag_his).

One task per (N, C, realization) — Lyapunov spectrum, D_KY, D_BC of the section, M_T — run on a
local process pool or a Dask cluster (``--scheduler``), stored in an SQLite file as each task
finishes; a rerun resumes. Writes DIR/ensemble.json (the summary) and DIR/ensemble.npz (the
per-realization values of every point).
"""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from analysis.cli._build import (
    build_system,
    check_model_options,
    check_store,
    check_transient,
    store_error,
)
from analysis.cli._options import (
    add_execution_options,
    add_model_options,
    add_oscillator_options,
    add_output_options,
    add_transient_option,
)
from analysis.cli._output import (
    announce_compilation,
    emit,
    prepare_out,
    progress_enabled,
    to_json,
)
from analysis.cli._parsing import (
    CliError,
    add_subcommand,
    int_at_least,
    positive_float,
)
from analysis.experiments.ensemble import EXPERIMENT, run_ensemble
from analysis.experiments.store import StoreError

__all__ = ["register", "run"]

#: models with disorder realizations
ENSEMBLE_MODELS = ("dimers", "preisach")


def register(subparsers: Any) -> None:
    p = add_subcommand(
        subparsers,
        "ensemble",
        help="disorder ensemble: mean and SAP of D_KY and D_BC, VAR[M]",
        description="Run (or resume) an ensemble over disorder realizations and aggregate it "
        "per (N, C): means and self-averaging parameters of D_KY and D_BC, VAR[M_T], the "
        "number of regular realizations (D_KY = 0).",
    )
    add_model_options(p, models=ENSEMBLE_MODELS, multiple_spins=True, sums=False)
    add_oscillator_options(p, coupling="multiple")
    g = p.add_argument_group("ensemble")
    g.add_argument(
        "--realizations",
        type=int_at_least(1, 10**7),
        required=True,
        help="realizations per (N, C) (--seed is the base seed of their disorder)",
    )
    g.add_argument("--t-end", type=positive_float, default=20000.0, help="end time per realization")
    add_transient_option(g, 160.0)
    g.add_argument(
        "--box-max-fill",
        type=float_fraction,
        default=0.1,
        help="box counting: largest count used, as a fraction of the section points, in (0, 1]",
    )
    g.add_argument(
        "--box-min-boxes",
        type=positive_float,
        default=8.0,
        help="box counting: smallest number of boxes across the attractor (>= 1)",
    )
    add_execution_options(g)
    add_output_options(p, writes="ensemble.json, ensemble.npz, results.sqlite")
    p.set_defaults(func=run)


def float_fraction(text: str) -> float:
    value = positive_float(text)
    if value > 1:
        raise argparse.ArgumentTypeError(f"must lie in (0, 1], got {text!r}")
    return value


def run(args: argparse.Namespace) -> int:
    if args.fields is not None:
        raise CliError("argument --fields: an ensemble draws its disorder (no explicit fields)")
    check_model_options(args)
    if args.box_min_boxes < 1:
        raise CliError(f"argument --box-min-boxes: must be >= 1, got {args.box_min_boxes:g}")
    # every (N, C) must give a valid system: build one of each before any task runs
    for n in args.spins:
        for c in args.coupling:
            ns = argparse.Namespace(**{**vars(args), "spins": [n], "coupling": c})
            build_system(ns)
    transient = check_transient(args, args.t_end)
    if args.scheduler is not None and args.workers is not None:
        raise CliError("argument --workers: give --workers or --scheduler, not both")
    if args.scheduler is not None:
        try:
            import distributed  # noqa: F401
        except ImportError as exc:
            raise CliError(
                "argument --scheduler: needs dask.distributed "
                "(pip install 'hysteresis-toolkit[distributed]')"
            ) from exc

    store = check_store(args, [EXPERIMENT])
    out = prepare_out(args)
    model_kw: dict[str, Any] = {"width": args.width, "spread": args.spread}
    if args.model == "dimers":
        model_kw["spin_coupling"] = args.spin_coupling
    else:  # non-default models are part of the task key; dimers keep the historical keys
        model_kw.update(model=args.model, width_spread=args.width_spread)
    announce_compilation(args)
    try:
        points = run_ensemble(
            args.spins,
            args.coupling,
            args.realizations,
            args.seed,
            args.t_end,
            transient,
            store=store,
            workers=args.workers,
            scheduler=args.scheduler,
            progress=progress_enabled(args),
            allow_version_mismatch=args.allow_version_mismatch,
            damping_ratio=args.damping_ratio,
            frequency=args.frequency,
            box_max_fill=args.box_max_fill,
            box_min_boxes=args.box_min_boxes,
            **model_kw,
        )
    except StoreError as exc:  # e.g. another process damaged it, or wrote another version
        raise store_error(exc) from exc
    record = {
        "model": args.model,
        **{k: v for k, v in model_kw.items() if k != "model"},
        "damping_ratio": args.damping_ratio,
        "frequency": args.frequency,
        "t_end": args.t_end,
        "transient": transient,
        "transient_periods": args.transient,
        "seed": args.seed,
        "store": str(store),
        # the summary fields of EnsemblePoint.to_json, non-finite values kept for to_json
        "points": [{k: getattr(pt, k) for k in pt.to_json()} for pt in points],
    }
    (out / "ensemble.json").write_text(to_json(record, indent=2) + "\n")
    arrays = {}
    for pt in points:
        tag = f"N{pt.spins}_C{pt.coupling:g}"
        for field in ("kaplan_yorke", "box_counting", "magnetization", "max_exponent"):
            arrays[f"{tag}_{field}"] = getattr(pt, field)
    np.savez_compressed(out / "ensemble.npz", **arrays)
    lines = [
        f"{'N':>7} {'C':>6} {'K':>5} {'<D_KY>':>8} {'SAP_KY':>8} {'<D_BC>':>8} "
        f"{'SAP_BC':>8} {'VAR[M]':>10} {'regular':>7}"
    ]
    for pt in points:
        lines.append(
            f"{pt.spins:7d} {pt.coupling:6.3g} {pt.realizations:5d} "
            f"{pt.mean_kaplan_yorke:8.4f} {pt.sap_kaplan_yorke:8.4f} "
            f"{pt.mean_box_counting:8.4f} {pt.sap_box_counting:8.4f} "
            f"{pt.var_magnetization:10.3e} {pt.regular_count:7d}"
        )
    lines.append(f"wrote {out / 'ensemble.json'} and {out / 'ensemble.npz'}")
    emit(args, record, lines)
    return 0
