"""``hyst paper``: reproduce every computational figure and claim of the paper."""

from __future__ import annotations

import argparse
from typing import Any

from analysis.cli._build import (
    check_store,
    store_error,
)
from analysis.cli._options import (
    add_execution_options,
    add_output_options,
)
from analysis.cli._output import (
    announce_compilation,
    emit,
    prepare_out,
    progress_enabled,
)
from analysis.cli._parsing import (
    CliError,
    add_subcommand,
)
from analysis.experiments.store import StoreError
from analysis.paper import run_paper
from analysis.paper.runner import check_only, figure_labels

__all__ = ["register", "run"]


def register(subparsers: Any) -> None:
    p = add_subcommand(
        subparsers,
        "paper",
        help="reproduce the paper's figures and claims (report.md, report.json)",
        description="Regenerate every computational figure of the paper as PNG, PDF and .npz "
        "and write DIR/report.md and DIR/report.json comparing each claim with the measurement. "
        "The models and parameters are the paper's (Tables I and II); the run size sets the "
        "lengths (transients in forcing periods).",
    )
    size = p.add_mutually_exclusive_group()
    size.add_argument(
        "--quick",
        dest="size",
        action="store_const",
        const="quick",
        help="reduced ensembles and run lengths, ~5 min on 2 cores (the default size)",
    )
    full = size.add_argument(
        "--full",
        dest="size",
        action="store_const",
        const="full",
        help=(
            "paper scale (about 12 min on two cores: 12.2 min measured; resumable through --store)"
        ),
    )
    smoke = size.add_argument(
        "--smoke",
        dest="size",
        action="store_const",
        const="smoke",
        help="tiny sizes: checks that every figure and claim is produced",
    )
    p.set_defaults(size="quick", func=run)
    full.default = smoke.default = argparse.SUPPRESS  # "(default: quick)" under --quick only
    g = p.add_argument_group("run")
    add_execution_options(g)
    g.add_argument(
        "--only",
        nargs="+",
        default=None,
        metavar="LABEL",
        help="build only these figures, one or more of the paper's LaTeX labels: "
        + ", ".join(figure_labels())
        + " (default: all)",
    )
    add_output_options(p, writes="report.md, report.json, figures, results.sqlite")


def run(args: argparse.Namespace) -> int:
    try:
        check_only(args.only)
    except ValueError as exc:
        raise CliError(f"argument --only: {str(exc).removeprefix('only: ')}") from exc
    if args.scheduler is not None and args.workers is not None:
        raise CliError("argument --workers: give --workers or --scheduler, not both")

    # a damaged or foreign store is refused up front; other code versions per experiment, when
    # a figure first uses it (a run with --only touches only its own experiments)
    check_store(args, experiments=[])
    out = prepare_out(args)
    announce_compilation(args)
    try:
        report = run_paper(
            out,
            size=args.size,
            store=args.store,
            workers=args.workers,
            scheduler=args.scheduler,
            only=args.only,
            progress=progress_enabled(args),
            allow_version_mismatch=args.allow_version_mismatch,
            # one line per stage also in a log (stderr not a terminal), where bars are noise
            stage_lines=not getattr(args, "quiet", False),
        )
    except StoreError as exc:
        raise store_error(exc) from exc
    n = len(report["claims"])
    summary = report["summary"]
    record = {
        "size": args.size,
        "claims": n,
        "agree": summary["agree"],
        "disagree": summary["disagree"],
        "inconclusive": summary["inconclusive"],
        "figures": [f["label"] for f in report["figures"]],
        "errors": [{"figure": e["figure"], "error": e["error"]} for e in report["errors"]],
        "report": out / "report.md",
    }
    emit(args, record, [f"{summary['line']}; report: {out / 'report.md'}"])
    if report["errors"]:
        failed = ", ".join(e["figure"] for e in report["errors"])
        raise RuntimeError(f"figure(s) failed: {failed} (tracebacks in {out / 'report.md'})")
    return 0
