"""``hyst orbit``: the periodic orbit a start settles on, refined by Newton, and its Floquet
multipliers.

After ``--transient`` forcing periods from (q0, v0[, w0]) the period k (forcing periods, at most
``--max-period``) is detected from the stroboscopic points and the orbit refined by Newton on
P^k(x) − x with the engine's exact Jacobian (:func:`analysis.dynamics.periodic_orbits.
find_periodic_orbit`). Writes DIR/orbit.json (the record that ``--json`` prints): ``period``,
``multipliers`` as [re, im] pairs, ``exponents`` log|μ|/(k·T) (``"-inf"`` for a reset memory
direction), ``tangent_space``, ``residual``, ``stable``, ``stability`` (``"stable"``,
``"unstable"`` or ``"neutral"``: a multiplier on the unit circle within round-off), and
``frozen`` (labels of the memory the orbit never moves: a family parameter, multiplier exactly
1, not counted in ``stable``) with
``multiplier_labels`` (``"frozen: <label>"``, ``"reset"`` or ``""`` per multiplier).

Example (the erf-play limit in the paper's periodic window)::

    hyst orbit --model erf-play --coupling 3.85 --json
"""

from __future__ import annotations

import argparse
from typing import Any

from analysis.cli._build import (
    build_system,
    check_model_options,
    initial_operator_state,
    initial_record,
    model_record,
    naming_divergence,
)
from analysis.cli._options import (
    add_initial_options,
    add_model_options,
    add_oscillator_options,
    add_output_options,
    add_transient_option,
)
from analysis.cli._output import announce_compilation, emit, prepare_out, write_record
from analysis.cli._parsing import add_subcommand, int_at_least, positive_float
from analysis.dynamics.periodic_orbits import MAX_ORBIT_PERIOD, find_periodic_orbit

__all__ = ["register", "run", "add_orbit_options", "start_state"]


def add_orbit_options(group: Any) -> None:
    """``--transient`` (forcing periods), ``--max-period``, ``--tolerance``."""
    add_transient_option(group, 100, integer=True)
    group.add_argument(
        "--max-period",
        type=int_at_least(1, MAX_ORBIT_PERIOD),
        default=64,
        help="largest period searched, in forcing periods",
    )
    group.add_argument(
        "--tolerance",
        type=positive_float,
        default=1e-10,
        help="Newton stops at |P^k(x) - x| <= tolerance * max(1, |x|)",
    )


def start_state(args: argparse.Namespace, system: Any) -> Any:
    """The start state from --q0, --v0 (and --w0 for play-type models)."""
    op_state = initial_operator_state(args, system.operator)
    return system.initial_state(args.q0, args.v0, op_state)


def register(subparsers: Any) -> None:
    p = add_subcommand(
        subparsers,
        "orbit",
        help="periodic orbit (Newton) and its Floquet multipliers",
        description="Detect the period of the orbit a start settles on and refine it by Newton "
        "on P^k(x) - x with the exact Jacobian (saltations, memory rows); print its Floquet "
        "multipliers and exponents.",
    )
    add_model_options(p)
    add_oscillator_options(p)
    add_initial_options(p)
    add_orbit_options(p.add_argument_group("orbit"))
    add_output_options(p, writes="orbit.json, the --json record")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    check_model_options(args)
    system = build_system(args)
    state = start_state(args, system)
    out = prepare_out(args)
    announce_compilation(args)
    with naming_divergence(lambda: system):
        orbit = find_periodic_orbit(
            system,
            state,
            transient=args.transient,
            max_period=args.max_period,
            tolerance=args.tolerance,
        )
    record: dict[str, Any] = model_record(args)
    record.update(
        coupling=args.coupling,
        damping_ratio=args.damping_ratio,
        frequency=args.frequency,
        **initial_record(args),
        transient_periods=args.transient,
        **orbit.to_dict(),
    )
    write_record(out, "orbit.json", record)
    mults = ", ".join(f"{abs(m):.6g}" for m in orbit.multipliers)
    frozen = f", frozen ({', '.join(orbit.frozen)})" if orbit.frozen else ""
    emit(
        args,
        record,
        [
            f"model {args.model}, C = {args.coupling}: period {orbit.period}, "
            f"{orbit.stability}, |multipliers| = ({mults}) on "
            f"({', '.join(orbit.tangent_space)}){frozen}, residual {orbit.residual:.2e}; "
            f"wrote {record['json']}"
        ],
    )
    return 0
