"""``hyst width-disorder``: the width-disorder study, continuum and finite N.

Runs (or resumes) :func:`analysis.experiments.width_disorder.run_study`: the continuous
Preisach model ``N(s;0,R²)·N(r;p/2,σ_r²)`` at each σ_r and C from several initial conditions
(spectrum with memory directions, block errors, neutral exponents, live memory, the exponents
without long-lived memory, D_KY, D_BC of the section), the erf play as reference, and the
finite-N ensembles of the registry model ``preisach``. Every task is stored as it finishes
(``--store``); a rerun resumes. Writes DIR/width_disorder.json and DIR/width_disorder.png.
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path
from typing import Any

from analysis.cli._build import check_store, store_error
from analysis.cli._options import add_output_options, add_store_options
from analysis.cli._output import announce_compilation, emit, prepare_out, progress_enabled, to_json
from analysis.cli._parsing import CliError, add_subcommand, int_at_least, positive_float
from analysis.experiments.ensemble import EXPERIMENT
from analysis.experiments.store import StoreError
from analysis.experiments.width_disorder import (
    EXPERIMENT_CONTINUUM,
    SIZES,
    continuum_tasks,
    run_study,
)
from analysis.experiments.width_disorder_plot import plot_study

__all__ = ["register", "run"]


def register(subparsers: Any) -> None:
    p = add_subcommand(
        subparsers,
        "width-disorder",
        help="width-disorder study: continuum Preisach vs finite N (D_KY, D_BC, neutral memory)",
        description="Run (or resume) the width-disorder study: the continuous Preisach model "
        "with Gaussian half-widths at each sigma_r and C (Lyapunov spectrum with memory "
        "directions and block errors, neutral exponents, live memory, the exponents without "
        "long-lived memory, D_KY, D_BC of the section), the erf play as reference, and the "
        "finite-N ensembles of the 'preisach' model. Default: the issue's full sizes.",
    )
    p.add_argument(
        "--quick",
        dest="size",
        action="store_const",
        const="quick",
        default="full",
        help="a tiny configuration that checks every step (seconds to a minute)",
    )
    g = p.add_argument_group("sizes (override the chosen size)")
    g.add_argument(
        "--part",
        choices=("both", "continuum", "finite"),
        default="both",
        help="run the continuum, the finite-N ensembles, or both",
    )
    g.add_argument("--t-end", type=positive_float, default=None, help="continuum run length")
    g.add_argument(
        "--section-t-end",
        type=positive_float,
        default=None,
        help="continue the continuum's Poincare section without tangent flow to this time",
    )
    g.add_argument(
        "--initial-conditions",
        type=int_at_least(1, 1000),
        default=None,
        help="initial conditions per continuum point (the first is the paper's)",
    )
    g.add_argument(
        "--projection-periods",
        type=int_at_least(1, 10**5),
        nargs="+",
        default=None,
        help="projection intervals P (forcing periods) of the exponents without older memory",
    )
    g.add_argument(
        "--width-spreads",
        type=positive_float,
        nargs="+",
        default=None,
        help="sigma_r values > 0 (sigma_r = 0, the erf play / equal widths, is always run)",
    )
    g.add_argument(
        "--spins",
        type=int_at_least(2, 10**7),
        nargs="+",
        default=None,
        help="finite N: numbers of relays (even)",
    )
    g.add_argument(
        "--realizations",
        type=int_at_least(1, 10**6),
        nargs="+",
        default=None,
        help="finite N: realizations per (N, sigma_r, C): one count, or one per --spins value",
    )
    e = p.add_argument_group("execution")
    add_store_options(e)
    e.add_argument(
        "--finite-store",
        type=Path,
        default=None,
        help="SQLite file of the finite-N ensembles (default: --store); e.g. the store of "
        "'hyst ensemble --model preisach' runs with the same options",
    )
    e.add_argument(
        "--workers",
        type=int_at_least(1, 1024),
        default=None,
        help="local worker processes (default: one per core)",
    )
    add_output_options(p, writes="width_disorder.json and .png, results.sqlite")
    p.set_defaults(func=run)


_OVERRIDES = (
    ("t_end", "t_end"),
    ("section_t_end", "section_t_end"),
    ("initial_conditions", "initial_conditions"),
    ("projection_periods", "projection_periods"),
    ("width_spreads", "width_spreads"),
    ("spins", "spins"),
    ("realizations", "realizations"),
)


def run(args: argparse.Namespace) -> int:
    overrides: dict[str, Any] = {}
    for option, field in _OVERRIDES:
        value = getattr(args, option)
        if value is not None:
            overrides[field] = tuple(value) if isinstance(value, list) else value
    if "spins" in overrides:
        odd = [n for n in overrides["spins"] if n % 2]
        if odd:
            raise CliError(f"argument --spins: must be even, got {odd[0]}")
    size = replace(SIZES[args.size], **overrides)
    if "realizations" in overrides:
        counts = overrides["realizations"]
        if len(counts) == 1:
            size = replace(size, realizations=counts[0])
        elif len(counts) != len(size.spins):
            raise CliError(
                f"argument --realizations: give one count or one per N ({len(size.spins)}), "
                f"got {len(counts)}"
            )
    try:
        continuum_tasks(size)
    except ValueError as exc:
        option = "--section-t-end" if str(exc).startswith("section_t_end") else "--t-end"
        raise CliError(f"argument {option}: {exc}") from exc
    parts = ("continuum", "finite") if args.part == "both" else (args.part,)
    store = check_store(args, [EXPERIMENT_CONTINUUM])
    finite_args = argparse.Namespace(**{**vars(args), "store": args.finite_store or store})
    finite_store = check_store(finite_args, [EXPERIMENT])
    out = prepare_out(args)
    announce_compilation(args)
    try:
        record = run_study(
            size,
            store=store,
            finite_store=finite_store,
            workers=args.workers,
            progress=progress_enabled(args),
            allow_version_mismatch=args.allow_version_mismatch,
            parts=parts,
        )
    except StoreError as exc:
        raise store_error(exc) from exc
    record["store"] = str(store)
    record["finite_store"] = str(finite_store)
    (out / "width_disorder.json").write_text(to_json(record, indent=1) + "\n")
    plot_study(record, out / "width_disorder.png")
    n_runs = sum(len(p["runs"]) for p in record["continuum"])
    summary = {
        "continuum_points": len(record["continuum"]),
        "continuum_runs": n_runs,
        "finite_points": len(record["finite"]),
        "wall_seconds": record["wall_seconds"],
        "json": out / "width_disorder.json",
        "figure": out / "width_disorder.png",
    }
    emit(
        args,
        summary,
        [
            f"width-disorder: {len(record['continuum'])} continuum points ({n_runs} runs), "
            f"{len(record['finite'])} finite-N points; wrote {out / 'width_disorder.json'} "
            f"and {out / 'width_disorder.png'}"
        ],
    )
    return 0
