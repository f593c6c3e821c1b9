"""``hyst lyapunov``: Lyapunov spectrum and Kaplan–Yorke dimension of one system.

The reported D_KY is the attractor's
(:func:`analysis.dynamics.attractor_dimension.attractor_dimension`): of the memory-frozen
exponents where the full spectrum holds neutral memory directions (a continuous Preisach
staircase's long-lived extrema, a frozen Prandtl–Ishlinskii wagon), else of the full spectrum;
the full-space value is reported alongside (``kaplan_yorke_full_space``) and
``kaplan_yorke_source`` says which was used.

Defaults are the paper's Tables I and II (:mod:`analysis.experiments.parameters`): ζ = 0.05,
Ω = 1, q0 = −1, v0 = 0.1, p = 2, R = 1, J = 2, N = 20 000 spins (seed 0), all spins down relaxed
at q0; for the play limit w0 = q0 − p/2.
Writes DIR/lyapunov.json (the record that ``--json`` prints).
"""

from __future__ import annotations

import argparse
from typing import Any

from analysis.cli._build import (
    build_system,
    check_model_options,
    check_transient,
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
from analysis.cli._output import (
    announce_compilation,
    emit,
    prepare_out,
    progress_enabled,
    write_record,
)
from analysis.cli._parsing import (
    add_subcommand,
    positive_float,
)
from analysis.dynamics.attractor_dimension import (
    MEMORY_FROZEN,
    AttractorDimension,
    attractor_dimension,
)
from analysis.dynamics.lyapunov import lyapunov_spectrum

__all__ = ["dimension_lines", "register", "run"]


def register(subparsers: Any) -> None:
    p = add_subcommand(
        subparsers,
        "lyapunov",
        help="Lyapunov spectrum and Kaplan-Yorke dimension",
        description="Lyapunov spectrum by the tangent flow with saltation matrices and QR "
        "(paper Sec. Lyapunov exponents); phase direction excluded unless --include-phase.",
    )
    add_model_options(p)
    add_oscillator_options(p)
    add_initial_options(p)
    g = p.add_argument_group("run")
    g.add_argument("--t-end", type=positive_float, default=10000.0, help="end time T")
    add_transient_option(g, 0.0)
    g.add_argument("--include-phase", action="store_true", help="also follow the phase direction")
    add_output_options(p, writes="lyapunov.json")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    check_model_options(args)
    system = build_system(args)  # the one system; the library checks C, zeta, Omega
    transient = check_transient(args, args.t_end)
    state = initial_operator_state(args, system.operator)
    out = prepare_out(args)
    announce_compilation(args)
    with naming_divergence(lambda: system):
        res = lyapunov_spectrum(
            system,
            t_end=args.t_end,
            transient=transient,
            q0=args.q0,
            v0=args.v0,
            operator_state=state,
            include_phase=args.include_phase,
            progress=progress_enabled(args),
            history_points=max(200, int(args.t_end / system.period) + 1),
        )
        dim = attractor_dimension(
            system,
            res.t_end,
            res.transient,
            args.q0,
            args.v0,
            operator_state=state,
            include_phase=args.include_phase,
            spectrum=res,
        )
    record: dict[str, Any] = model_record(args)
    record.update(
        coupling=args.coupling,
        damping_ratio=args.damping_ratio,
        frequency=args.frequency,
        **initial_record(args),
        exponents=list(res.exponents),
        tangent_space=list(res.tangent_space),
        **dim.to_record(),
        switches=res.n_switches,
        engine=res.extra.get("engine"),
        t_end=res.t_end,
        transient=res.transient,
        transient_periods=args.transient,
        include_phase=bool(args.include_phase),
    )
    write_record(out, "lyapunov.json", record)
    lines = [
        f"model {args.model}, C = {args.coupling}, averaged over "
        f"[{res.transient:g}, {res.t_end:g}], {res.n_switches} switches "
        f"({res.extra.get('engine')})",
        f"  tangent space ({', '.join(res.tangent_space)})",
        *(f"  lambda_{i} = {lam: .6f}" for i, lam in enumerate(res.exponents, start=1)),
        *dimension_lines(dim),
        f"wrote {record['json']}",
    ]
    emit(args, record, lines)
    return 0


def dimension_lines(dim: AttractorDimension) -> list[str]:
    """The D_KY lines of the text output (``hyst lyapunov``, ``hyst dimension``): the value
    used, and why."""
    if dim.source != MEMORY_FROZEN:
        return [
            f"  D_KY = {dim.kaplan_yorke:.4f} +- {dim.kaplan_yorke_error:.2g} ({dim.explanation})"
        ]
    lam = ", ".join(f"{x:.6f}" for x in dim.exponents)
    return [
        f"  D_KY = {dim.kaplan_yorke:.4f} +- {dim.kaplan_yorke_error:.2g} of the attractor, from "
        f"the memory-frozen exponents {lam}",
        f"  D_KY full space = {dim.kaplan_yorke_full_space:.4f}: of the spectrum with the memory "
        "directions, distorted by the neutral ones (frozen extrema or wagons, exponent 0 while "
        "they live)",
    ]
