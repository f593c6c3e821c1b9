"""``hyst basins``: basins of attraction over an N × N grid of initial conditions.

N × N starts over ``--q0-range`` and ``--v0-range`` (memory: the operator rising from negative
saturation to q0), or ``--q0-range`` and ``--w0-range`` for play-type memory (the play's wagon
position w0, every start with the velocity ``--v0``); each start is classified by its section
(:func:`analysis.dynamics.basins.basins`): a periodic orbit (refined once per orbit), a chaotic
attractor (λ_max and D_KY), divergent, or undecided; ``--method recurrences`` stops each start
once its section enters a known attractor's or basin's cells (the recurrence mapper,
:mod:`analysis.dynamics.recurrence`; ``--cell-size``). Chunks of starts run on local worker
processes or a Dask cluster (``--scheduler``) and are stored in an SQLite file as they finish; a
rerun resumes. Writes DIR/basins.png (the map coloured by attractor), DIR/basins.npz (per-start
labels, transient lengths, periods) and DIR/basins.json (the record that ``--json`` prints).

Example (the erf-play limit at C = 2.92, the paper's "some initial conditions are chaotic")::

    hyst basins --model erf-play --coupling 2.92 --grid 100 --q0-range -3 3 --w0-range -4 4
"""

from __future__ import annotations

import argparse
import functools
from typing import Any

from analysis.cli._build import (
    build_system,
    check_model_options,
    check_store,
    model_record,
    naming_divergence,
    play_type,
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
    figure_title,
    prepare_out,
    progress_enabled,
    to_json,
)
from analysis.cli._parsing import (
    CliError,
    add_subcommand,
    finite_float,
    int_at_least,
    library_errors,
    positive_float,
)
from analysis.dynamics.basins import (
    EXPERIMENT,
    MAX_STARTS,
    METHODS,
    BasinGrid,
    RecurrenceSettings,
    basins,
)
from analysis.experiments.execution import run_tasks
from analysis.experiments.store import StoreError
from oscillators import DEFAULT_V0, MAX_PERIODS

__all__ = ["register", "run"]

#: library parameter -> option, for the messages of the library's checks
_OPTIONS = {
    "transient": "--transient",
    "periods": "--periods",
    "max_periods": "--max-periods",
    "max_period": "--max-period",
    "tolerance": "--tolerance",
    "match_tolerance": "--match-tolerance",
    "lyapunov_periods": "--lyapunov-periods",
    "q0_range": "--q0-range",
    "v0_range": "--v0-range",
    "w0_range": "--w0-range",
    "v0": "--v0",
    "size": "--grid",
    "chunk": "--chunk",
    "cell_size": "--cell-size",
}


def register(subparsers: Any) -> None:
    p = add_subcommand(
        subparsers,
        "basins",
        help="basins of attraction over an N x N grid of starts (q0, v0) or (q0, w0)",
        description="Classify where every start of an N x N grid ends (periodic orbit with its "
        "period and Floquet multipliers, chaotic attractor with lambda_max and D_KY, divergent, "
        "undecided) and report each attractor's basin fraction with its 95 % Wilson interval.",
    )
    add_model_options(p, default="erf-play")
    add_oscillator_options(p)
    g = p.add_argument_group("grid")
    g.add_argument(
        "--grid",
        type=int_at_least(2, int(MAX_STARTS**0.5)),
        required=True,
        help="N, starts per axis (N x N starts)",
    )
    g.add_argument(
        "--q0-range",
        type=finite_float,
        nargs=2,
        default=[-3.0, 3.0],
        metavar=("A", "B"),
        help="initial positions q0 from A to B",
    )
    g.add_argument(
        "--v0-range",
        type=finite_float,
        nargs=2,
        default=None,
        metavar=("A", "B"),
        help="initial velocities (default -3 3 unless --w0-range is given)",
    )
    g.add_argument(
        "--w0-range",
        type=finite_float,
        nargs=2,
        default=None,
        metavar=("A", "B"),
        help="play-type models: wagon positions w0 instead of velocities (starts outside "
        "|q0 - w0| <= p/2 are no states: blank on the map)",
    )
    g.add_argument(
        "--v0",
        type=finite_float,
        default=DEFAULT_V0,
        help="the velocity of every start of a --w0-range grid",
    )
    r = p.add_argument_group("classification")
    r.add_argument(
        "--method",
        choices=METHODS,
        default="sections",
        help="sections: every start runs its section budget; recurrences: the recurrence "
        "mapper (Datseris & Wagemakers 2022) stops a start once its section enters a known "
        "attractor's or basin's cells (much faster; cells must separate the attractors, and "
        "--max-periods must let a start find a new attractor: 100 recurrences in a row after "
        "its transient, ~2000 periods for the erf play's chaotic attractors)",
    )
    r.add_argument(
        "--cell-size",
        type=positive_float,
        default=RecurrenceSettings.cell_size,
        help="recurrences: edge of the cells over (q, v, w) (play) or (q, v, M)",
    )
    add_transient_option(r, 100, integer=True)
    r.add_argument(
        "--periods",
        type=int_at_least(2, MAX_PERIODS),
        default=100,
        help="section points checked for a period after the transient",
    )
    r.add_argument(
        "--max-periods",
        type=int_at_least(2, MAX_PERIODS),
        default=None,
        help="longest run of a start without a period, extended --periods at a time "
        "(default: --transient + --periods, no extension)",
    )
    r.add_argument(
        "--max-period",
        type=int_at_least(1, 10**4),
        default=None,
        help="longest section period (default: min(32, --periods // 2))",
    )
    r.add_argument(
        "--tolerance", type=positive_float, default=1e-6, help="section period tolerance"
    )
    r.add_argument(
        "--match-tolerance",
        type=positive_float,
        default=1e-4,
        help="a start's cycle is a refined orbit within this (cyclic shifts included)",
    )
    r.add_argument(
        "--lyapunov-periods",
        type=int_at_least(10, MAX_PERIODS),
        default=2000,
        help="forcing periods of the lambda_max run on each aperiodic attractor",
    )
    r.add_argument(
        "--chunk",
        type=int_at_least(1, 10**6),
        default=None,
        help="starts per stored task (default 200; recurrences: 10000, one cell grid per task)",
    )
    add_execution_options(r)
    add_output_options(p, writes="basins.png, basins.npz, basins.json, results.sqlite")
    p.set_defaults(func=run)


def _grid(args: argparse.Namespace) -> BasinGrid:
    for option, rng in (
        ("--q0-range", args.q0_range),
        ("--v0-range", args.v0_range),
        ("--w0-range", args.w0_range),
    ):
        if rng is not None and not rng[0] < rng[1]:
            raise CliError(f"argument {option}: needs A < B, got {rng[0]:g} {rng[1]:g}")
    if args.w0_range is not None:
        if args.v0_range is not None:
            raise CliError("argument --w0-range: give --v0-range or --w0-range, not both")
        if not play_type(args):
            raise CliError(
                f"argument --w0-range: only for play-type models (erf-play, play), not {args.model}"
            )
        return BasinGrid(tuple(args.q0_range), tuple(args.w0_range), args.grid, "w0", args.v0)
    y = args.v0_range if args.v0_range is not None else [-3.0, 3.0]
    return BasinGrid(tuple(args.q0_range), tuple(y), args.grid, "v0")


def _describe(a: dict) -> str:
    frac = (
        f"{100 * a['fraction']:.1f} % [{100 * a['interval'][0]:.1f}, {100 * a['interval'][1]:.1f}]"
    )
    if a["kind"] == "periodic":
        mu = max(abs(complex(*m)) for m in a["multipliers"])
        return f"period {a['period']} (|mu|max {mu:.3g}) {frac}"
    if a["kind"] == "chaotic":
        return (
            f"chaotic (lambda_max {a['max_exponent']:.4f} +- {a['max_exponent_error']:.1g}, "
            f"D_KY {a['kaplan_yorke']:.3f}) {frac}"
        )
    return f"{a['kind']} {frac}"


def run(args: argparse.Namespace) -> int:
    check_model_options(args)
    system = build_system(args)
    grid = _grid(args)
    total = args.transient + args.periods if args.max_periods is None else args.max_periods
    if total < args.transient + args.periods:
        raise CliError(
            f"argument --max-periods: must be >= --transient + --periods = "
            f"{args.transient + args.periods}, got {total}"
        )
    if args.max_period is None:
        args.max_period = min(32, args.periods // 2)
    if args.max_period > args.periods // 2:
        raise CliError(
            f"argument --max-period: must be <= --periods // 2 = {args.periods // 2} (a cycle "
            f"is seen twice), got {args.max_period}"
        )
    if args.match_tolerance < args.tolerance:
        raise CliError("argument --match-tolerance: must be >= --tolerance")
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
    identity = {
        **model_record(args),
        "coupling": args.coupling,
        "damping_ratio": args.damping_ratio,
        "frequency": args.frequency,
    }
    announce_compilation(args)
    try:
        with library_errors(_OPTIONS, "--grid"), naming_divergence(lambda: system):
            runner = functools.partial(
                run_tasks,
                EXPERIMENT,
                store=store,
                workers=args.workers,
                scheduler=args.scheduler,
                progress=progress_enabled(args),
                allow_version_mismatch=args.allow_version_mismatch,
            )
            recurrence = None
            if args.method == "recurrences":
                recurrence = RecurrenceSettings(
                    cell_size=args.cell_size,
                    **({} if args.chunk is None else {"chunk": args.chunk}),
                )
            result = basins(
                system,
                grid,
                method=args.method,
                transient=args.transient,
                periods=args.periods,
                max_periods=total,
                tolerance=args.tolerance,
                match_tolerance=args.match_tolerance,
                max_period=args.max_period,
                lyapunov_periods=args.lyapunov_periods,
                chunk=200 if args.chunk is None else args.chunk,
                recurrence=recurrence,
                executor=runner,
                system_key=to_json(identity),
            )
    except StoreError as exc:
        raise store_error(exc) from exc
    npz = result.save(out / "basins.npz")
    png = result.plot(out / "basins.png", figure_title(args, "basins"))
    record = {**identity, **result.to_dict(), "store": str(store), "npz": npz, "png": png}
    (out / "basins.json").write_text(to_json(record, indent=2) + "\n")
    summary = "; ".join(f"{a['label']}: {_describe(a)}" for a in record["attractors"])
    emit(args, record, [f"{grid.size}x{grid.size} starts: {summary}; wrote {npz} and {png}"])
    return 0
