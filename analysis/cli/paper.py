"""``hyst paper``: reproduce every computational figure and claim of the paper."""

from __future__ import annotations

import argparse


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "paper",
        help="reproduce the paper's figures and claims (report.md, report.json)",
        description="Regenerate every computational figure of the paper as PNG, PDF and .npz "
        "and write DIR/report.md and DIR/report.json comparing each claim with the measurement.",
    )
    size = p.add_mutually_exclusive_group()
    size.add_argument(
        "--quick",
        dest="size",
        action="store_const",
        const="quick",
        help="reduced ensembles and run lengths, ~10 min on 2 cores (default)",
    )
    size.add_argument(
        "--full",
        dest="size",
        action="store_const",
        const="full",
        help="paper scale (hours; resumable through --store)",
    )
    size.add_argument(
        "--smoke",
        dest="size",
        action="store_const",
        const="smoke",
        help="tiny sizes: checks that every figure and claim is produced",
    )
    p.set_defaults(size="quick", func=run)
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument("--store", default=None, help="SQLite results file (default DIR/results.sqlite)")
    p.add_argument("--workers", type=int, default=None, help="worker processes (default: cores)")
    p.add_argument("--scheduler", default=None, help="Dask distributed scheduler address")
    p.add_argument(
        "--only",
        nargs="+",
        default=None,
        metavar="LABEL",
        help="build only these figures (LaTeX labels, e.g. fig:play)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress output")


def run(args: argparse.Namespace) -> int:
    from analysis.paper import run_paper

    report = run_paper(
        args.out,
        size=args.size,
        store=args.store,
        workers=args.workers,
        scheduler=args.scheduler,
        only=args.only,
        progress=not args.quiet,
    )
    n = len(report["claims"])
    agree = sum(c["verdict"] == "agree" for c in report["claims"])
    print(f"{agree}/{n} claims agree; report: {args.out}/report.md")
    return 1 if report["errors"] else 0
