"""``hyst continuation``: a periodic orbit continued in a parameter, with its bifurcations.

The orbit the start settles on at ``--start`` (as ``hyst orbit`` finds it) is continued to
``--stop`` (:func:`analysis.dynamics.continuation.continue_orbit`): folds, period doublings and
tori from the Floquet multipliers, grazings (switching-sequence changes) located by bisection to
``--locate-tolerance``. Writes DIR/continuation.json (the record that ``--json`` prints):
``branch`` (points with ``parameter``, ``period``, ``max_abs_multiplier``) and ``events`` (each
with ``kind`` in fold, period-doubling, torus, grazing, and ``parameter``).

Example (paper fig:bif_0: the onset of the N = 2 period-adding cascade, closed form C = 9)::

    hyst continuation --model dimers --fields 1 -1 --start 9.5 --stop 8.9 --json
"""

from __future__ import annotations

import argparse
from typing import Any

from analysis.cli._build import (
    build_operator,
    build_system,
    check_model_options,
    initial_record,
    model_record,
    naming_divergence,
)
from analysis.cli._options import (
    add_initial_options,
    add_model_options,
    add_oscillator_options,
    add_output_options,
)
from analysis.cli._output import announce_compilation, emit, prepare_out, write_record
from analysis.cli._parsing import (
    CliError,
    add_subcommand,
    finite_float,
    int_at_least,
    positive_float,
)
from analysis.cli.orbit import add_orbit_options, start_state
from analysis.dynamics.continuation import MAX_POINTS, METHODS, continue_orbit
from analysis.dynamics.periodic_orbits import find_periodic_orbit

__all__ = ["register", "run"]

PARAMETERS = ("coupling", "frequency", "damping_ratio")


def register(subparsers: Any) -> None:
    p = add_subcommand(
        subparsers,
        "continuation",
        help="continue a periodic orbit in a parameter; folds, period doublings, grazings",
        description="Find the periodic orbit at --start (as hyst orbit) and continue it to "
        "--stop: Floquet multipliers along the branch, fold / period-doubling / torus "
        "bifurcations and grazings (switching-sequence changes) located on the way.",
    )
    add_model_options(p)
    add_oscillator_options(p, coupling="optional")
    add_initial_options(p)
    g = p.add_argument_group("continuation")
    g.add_argument("--parameter", choices=PARAMETERS, default="coupling", help="parameter")
    g.add_argument("--start", type=finite_float, required=True, help="first parameter value")
    g.add_argument("--stop", type=finite_float, required=True, help="last parameter value")
    g.add_argument(
        "--steps",
        type=int_at_least(1, 10**6),
        default=50,
        help="largest step = |stop - start| / steps (smaller near events)",
    )
    g.add_argument("--method", choices=METHODS, default="auto", help="continuation method")
    g.add_argument(
        "--max-points", type=int_at_least(1, MAX_POINTS), default=2000, help="most branch points"
    )
    g.add_argument(
        "--locate-tolerance",
        type=positive_float,
        default=1e-8,
        help="width in the parameter to which events are located",
    )
    g.add_argument(
        "--symmetric",
        action="store_true",
        help="the model is odd (x -> -x with a half-period shift maps orbits to orbits): stop "
        "where the branch reaches the symmetric partner of an event found before",
    )
    add_orbit_options(g)
    add_output_options(p, writes="continuation.json, the --json record")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    check_model_options(args)
    if args.parameter != "coupling" and args.coupling is None:
        raise CliError("argument --coupling: required when another parameter is continued")
    if args.parameter == "coupling" and args.coupling is not None:
        raise CliError("argument --coupling: the continued parameter is given by --start/--stop")
    if args.start == args.stop:
        raise CliError("argument --start/--stop: start and stop must differ")
    operator = build_operator(args)
    fixed = dict(coupling=args.coupling, damping_ratio=args.damping_ratio, frequency=args.frequency)

    built: list[Any] = []  # the continuation builds one system per value, in order

    def make_system(value: float) -> Any:
        ns = argparse.Namespace(**{**vars(args), **fixed, args.parameter: value})
        built.append(build_system(ns, operator=operator))
        return built[-1]

    for option, value in (("--start", args.start), ("--stop", args.stop)):
        try:
            make_system(value)
        except CliError as exc:
            raise CliError(f"argument {option}: {args.parameter} = {value:g}: {exc}") from exc
    system = make_system(args.start)
    out = prepare_out(args)
    announce_compilation(args)
    with naming_divergence(lambda: built[-1]):
        orbit = find_periodic_orbit(
            system,
            start_state(args, system),
            transient=args.transient,
            max_period=args.max_period,
            tolerance=args.tolerance,
        )
        branch = continue_orbit(
            make_system,
            orbit,
            args.start,
            args.stop,
            parameter=args.parameter,
            method=args.method,
            step=abs(args.stop - args.start) / args.steps,
            max_points=args.max_points,
            tolerance=args.tolerance,
            locate_tolerance=args.locate_tolerance,
            transient=args.transient,
            max_period=args.max_period,
            symmetric=args.symmetric,
        )
    record: dict[str, Any] = model_record(args)
    record.update(
        damping_ratio=args.damping_ratio,
        frequency=args.frequency,
        coupling=args.coupling,
        **initial_record(args),
        start=args.start,
        stop=args.stop,
        transient_periods=args.transient,
        **branch.to_dict(),
    )
    write_record(out, "continuation.json", record)
    events = ", ".join(f"{e.kind} at {e.parameter:.10g}" for e in branch.events) or "none"
    emit(
        args,
        record,
        [
            f"{len(branch.points)} points of {args.parameter} from {args.start} toward "
            f"{args.stop} ({branch.method}; {branch.stop_reason}); events: {events}; "
            f"wrote {record['json']}"
        ],
    )
    return 0
