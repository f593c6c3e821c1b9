"""``hyst lattice``: the random-field Ising lattice coupled to the oscillator, and its Preisach
model.

Runs (or resumes) :func:`analysis.experiments.lattice.run_study`: per disorder R, side L,
coupling C and realization, the coupled lattice's λ_max, D_KY, D_BC, fraction of regular
realizations and Barkhausen statistics (coupled motion vs plain sweeps), and the same
measurements for the lattice's own identified Preisach model, with its operator-level error.
Every task is stored as it finishes (``--store``); a rerun resumes. Writes DIR/lattice.json
and DIR/lattice.png and answers in one line.
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from typing import Any

from analysis.cli._build import check_store, store_error
from analysis.cli._options import add_output_options, add_store_options
from analysis.cli._output import announce_compilation, emit, prepare_out, progress_enabled, to_json
from analysis.cli._parsing import (
    CliError,
    add_subcommand,
    finite_float,
    int_at_least,
    nonnegative_float,
    positive_float,
)
from analysis.experiments.lattice import EXPERIMENT, SIZES, lattice_tasks, run_study
from analysis.experiments.lattice_plot import plot_study
from analysis.experiments.store import StoreError

__all__ = ["register", "run", "answer"]


def register(subparsers: Any) -> None:
    p = add_subcommand(
        subparsers,
        "lattice",
        help="random-field Ising lattice coupled to the oscillator vs its identified Preisach "
        "model (lambda_max, D_KY, D_BC, Barkhausen statistics)",
        description="Run (or resume) the lattice study: zero-temperature random-field Ising "
        "lattices (J = 1, fields N(0, R^2)) coupled to the oscillator at each R, L, C and "
        "realization (Lyapunov spectrum, D_KY, D_BC, fraction regular, avalanche sizes of the "
        "coupled motion and of plain field sweeps), and the lattice's own Preisach model "
        "identified from its FORCs, coupled the same way. Default: a small run (about a "
        "minute on 2 cores).",
    )
    g = p.add_mutually_exclusive_group()
    for name, text in (
        ("moderate", "the docs page's run (L = 10, 20, 30; 6 realizations; 600 periods)"),
        (
            "full",
            "the issue's grid: R = 1.8, 2.16, 2.6, 3.5; L = 10, 20, 30, 50, 70, 100 (up to 10^6 "
            "spins); C = 2.9, 4; 20 realizations; 2000 periods (200 transient); 68 FORC nodes "
            "(480 tasks). Measured per realization (one R, both C) on this machine: L = 50 about "
            "10 min (25 s at 60 periods, +0.28 s a period), L = 100 2.5-3 min at 30-60 periods, "
            "about 1.3 h at 2000 (extrapolated: cost ~ N per period); over 100 CPU hours in all",
        ),
    ):
        g.add_argument(
            f"--{name}", dest="size", action="store_const", const=name, default="small", help=text
        )
    s = p.add_argument_group("sizes (override the chosen size)")
    s.add_argument("--disorders", type=nonnegative_float, nargs="+", help="R values (J = 1)")
    s.add_argument("--sides", type=int_at_least(3, 1000), nargs="+", help="lattice sides L")
    s.add_argument("--couplings", type=finite_float, nargs="+", help="oscillator couplings C")
    s.add_argument("--realizations", type=int_at_least(1, 10**5), help="realizations per (R, L)")
    s.add_argument("--periods", type=int_at_least(2, 10**6), help="forcing periods per run")
    s.add_argument("--transient-periods", type=int_at_least(1, 10**6), help="transient periods")
    s.add_argument(
        "--barkhausen-periods", type=int_at_least(1, 10**5), help="periods of avalanche record"
    )
    s.add_argument(
        "--identification-nodes",
        type=int_at_least(4, 400),
        help="FORC grid nodes over the oscillator's input range (up to ~70 a dense NNLS; "
        "above, the sparse second-difference solve: about 6-10 s per realization at 150 "
        "nodes, 15 s at 200)",
    )
    s.add_argument("--margin", type=positive_float, help="grid margin beyond the largest |q|")
    s.add_argument("--seed", type=int_at_least(0), default=0, help="base disorder seed")
    e = p.add_argument_group("execution")
    add_store_options(e)
    e.add_argument(
        "--workers",
        type=int_at_least(1, 1024),
        default=None,
        help="local worker processes (default: one per core)",
    )
    add_output_options(p, writes="lattice.json and .png, results.sqlite")
    p.set_defaults(func=run)


_FIELDS = (
    "disorders", "sides", "couplings", "realizations", "periods", "transient_periods",
    "barkhausen_periods", "identification_nodes", "margin",
)  # fmt: skip


def answer(record: dict) -> str:
    """The study's answer in one line: where the coupled lattice is chaotic, and whether its
    identified Preisach model gets the attractor type and λ_max right."""
    pts = record["points"]
    chaotic = [p for p in pts if p["lattice"]["fraction_regular"] < 1.0]
    agree = sum(p["same_attractor_type"] * p["realizations"] for p in pts)
    total = sum(p["realizations"] for p in pts)
    worst = max(pts, key=lambda p: p["operator_error_on_nodes_rms"][0])
    where = ", ".join(f"(R={p['disorder']:g}, L={p['side']}, C={p['coupling']:g})"
                      for p in chaotic[:4]) or "nowhere"  # fmt: skip
    return (
        f"lattice: chaotic realizations at {where}"
        f"{' ...' if len(chaotic) > 4 else ''}; the identified Preisach model has the lattice's "
        f"attractor type in {agree:.0f}/{total} runs, its non-Preisach error in M is largest at "
        f"R={worst['disorder']:g}, L={worst['side']} "
        f"(rms {worst['operator_error_on_nodes_rms'][0]:.3g} on grid nodes)"
    )


def run(args: argparse.Namespace) -> int:
    overrides = {}
    for name in _FIELDS:
        value = getattr(args, name)
        if value is not None:
            overrides[name] = tuple(value) if isinstance(value, list) else value
    size = replace(SIZES[args.size], **overrides)
    try:
        lattice_tasks(size, args.seed)
    except ValueError as exc:
        raise CliError(f"argument --periods: {exc}") from exc
    store = check_store(args, [EXPERIMENT])
    out = prepare_out(args)
    announce_compilation(args)
    try:
        record = run_study(
            size,
            store=store,
            workers=args.workers,
            progress=progress_enabled(args),
            allow_version_mismatch=args.allow_version_mismatch,
            seed=args.seed,
        )
    except StoreError as exc:
        raise store_error(exc) from exc
    record["store"] = str(store)
    line = answer(record)
    record["answer"] = line
    (out / "lattice.json").write_text(to_json(record, indent=1) + "\n")
    plot_study(record, out / "lattice.png")
    summary = {
        "points": len(record["points"]),
        "wall_seconds": record["wall_seconds"],
        "answer": line,
        "json": out / "lattice.json",
        "figure": out / "lattice.png",
    }
    emit(args, summary, [line])
    return 0
