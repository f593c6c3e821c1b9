"""``hyst dimension``: Kaplan–Yorke and box-counting dimension of one attractor.

D_KY from the Lyapunov spectrum in the Poincaré section (phase neglected, as the paper): the
attractor's, as ``hyst lyapunov`` reports it (memory-frozen where neutral memory directions
exist, :func:`analysis.dynamics.attractor_dimension.attractor_dimension`, the full-space value
alongside); D_BC
from the section points (q, v) with the automatic scaling region. Writes DIR/dimension.png
(section and log-log fit) and DIR/dimension.npz.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

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
    figure_title,
    prepare_out,
    progress_enabled,
)
from analysis.cli._parsing import (
    CliError,
    add_subcommand,
    int_at_least,
    positive_float,
)
from analysis.cli.lyapunov import dimension_lines
from analysis.dynamics.attractor_dimension import attractor_dimension
from analysis.dynamics.bifurcation import section_period
from analysis.dynamics.dimensions import box_counting_dimension
from analysis.dynamics.lyapunov import lyapunov_spectrum
from analysis.experiments.one_pass import one_pass_measurements

__all__ = ["register", "run"]


def _fraction(text: str) -> float:
    value = positive_float(text)
    if value > 1:
        raise argparse.ArgumentTypeError(f"must lie in (0, 1], got {text!r}")
    return value


def _at_least_one(text: str) -> float:
    value = positive_float(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, got {text!r}")
    return value


def register(subparsers: Any) -> None:
    p = add_subcommand(
        subparsers,
        "dimension",
        help="Kaplan-Yorke and box-counting dimension of an attractor",
        description="D_KY from the Lyapunov spectrum and D_BC of the Poincare section (q, v).",
    )
    add_model_options(p)
    add_oscillator_options(p)
    add_initial_options(p)
    g = p.add_argument_group("run")
    g.add_argument(
        "--t-end",
        type=positive_float,
        default=20000.0,
        help="end time of the run; without --points the spectrum and the section come from "
        "one integration over the whole forcing periods in [transient, t_end]",
    )
    add_transient_option(g, 160.0)
    g.add_argument(
        "--points",
        type=int_at_least(2, 10**8),
        default=None,
        help="section points for D_BC (default: the whole periods in [transient, t_end])",
    )
    g.add_argument(
        "--max-fill",
        type=_fraction,
        default=0.1,
        help="box counting: largest count used, as a fraction of the points, in (0, 1]",
    )
    g.add_argument(
        "--min-boxes",
        type=_at_least_one,
        default=8.0,
        help="box counting: smallest number of boxes across the attractor (>= 1)",
    )
    add_output_options(p, writes="dimension.npz, dimension.png")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    check_model_options(args)
    system = build_system(args)
    transient = check_transient(args, args.t_end)
    transient_periods = int(np.ceil(args.transient - 1e-12))
    n = args.points
    if n is None:
        n = int(np.floor(args.t_end / system.period)) - transient_periods
        if n < 2:
            raise CliError(
                "argument --t-end: [transient, t_end] holds fewer than 2 forcing periods; "
                "lengthen --t-end or give --points"
            )
    state = initial_operator_state(args, system.operator)
    out = prepare_out(args)
    announce_compilation(args)
    with naming_divergence(lambda: system):
        ly, sec = _measure(args, system, transient, transient_periods, n, state)
        dim = attractor_dimension(
            system, ly.t_end, ly.transient, args.q0, args.v0, operator_state=state, spectrum=ly
        )
    points = np.column_stack([sec.q, sec.v])
    period = section_period(sec.q, sec.v)
    bc, bc_error = None, ""
    if period > 0:
        bc_error = f"periodic section (period {period}): D_BC = 0"
    else:
        try:
            bc = box_counting_dimension(points, max_fill=args.max_fill, min_boxes=args.min_boxes)
        except ValueError as exc:
            bc_error = str(exc)
    record = model_record(args)
    record.update(
        coupling=args.coupling,
        damping_ratio=args.damping_ratio,
        frequency=args.frequency,
        **initial_record(args),
        t_end=args.t_end,
        transient=transient,
        transient_periods=args.transient,
        exponents=list(ly.exponents),
        **dim.to_record(),
        section_points=int(n),
        section_period=int(period),
        box_counting=(0.0 if period > 0 else None) if bc is None else float(bc.dimension),
        box_counting_stderr=None if bc is None else float(bc.stderr),
        box_counting_region=None
        if bc is None
        else [float(bc.sizes[bc.region[0]]), float(bc.sizes[bc.region[1] - 1])],
    )
    if bc is None:
        record["box_counting_error"] = bc_error
    arrays = dict(q=sec.q, v=sec.v, exponents=ly.exponents)
    if bc is not None:
        arrays.update(sizes=bc.sizes, counts=bc.counts, region=np.array(bc.region))
    npz, png = out / "dimension.npz", out / "dimension.png"
    np.savez_compressed(npz, **arrays)
    _plot(sec, bc, figure_title(args, "dimension"), png)
    record.update(npz=npz, png=png)
    lines = [
        "exponents " + ", ".join(f"{x:.5f}" for x in ly.exponents),
        *(line.strip() for line in dimension_lines(dim)),
        f"D_BC: no scaling region ({bc_error})"
        if bc is None
        else f"D_BC = {bc.dimension:.4f} +- {bc.stderr:.4f} from {n} section points",
        f"wrote {npz} and {png}",
    ]
    emit(args, record, lines)
    return 0


def _measure(
    args: argparse.Namespace,
    system: Any,
    transient: float,
    transient_periods: int,
    n: int,
    state: Any,
) -> tuple[Any, Any]:
    """The Lyapunov spectrum and the Poincaré section of ``n`` points after the transient."""
    if args.points is None:
        # one integration: spectrum and section over the whole forcing periods in the window
        ly, sq, sv, _, _ = one_pass_measurements(
            system,
            args.t_end,
            transient,
            args.q0,
            args.v0,
            operator_state=state,
            magnetization=False,
            progress=progress_enabled(args),
        )
        return ly, SimpleNamespace(q=sq, v=sv)
    ly = lyapunov_spectrum(
        system,
        t_end=args.t_end,
        transient=transient,
        q0=args.q0,
        v0=args.v0,
        operator_state=state,
        progress=progress_enabled(args),
    )
    return ly, system.poincare_section(n, transient_periods, args.q0, args.v0, operator_state=state)


def _plot(sec: Any, bc: Any, title: str, path: Path) -> None:
    import matplotlib.pyplot as plt  # drawing only; the backend stays the caller's

    fig, axes = plt.subplots(1, 2, figsize=(9, 4.3))
    axes[0].plot(sec.q, sec.v, ".k", ms=1.0)
    axes[0].set_xlabel("q")
    axes[0].set_ylabel("v")
    axes[0].set_title(r"Poincaré section $\phi = 0$", fontsize=9)
    if bc is not None:
        x = np.log(1.0 / bc.sizes)
        y = np.log(bc.counts)
        i, j = bc.region
        axes[1].plot(x, y, "o", mfc="none")
        axes[1].plot(
            x[i:j],
            bc.intercept + bc.dimension * x[i:j],
            "-r",
            label=f"$D_{{BC}}$ = {bc.dimension:.3f}",
        )
        axes[1].set_xlabel(r"$\log(1/\epsilon)$")
        axes[1].set_ylabel(r"$\log N(\epsilon)$")
        axes[1].legend()
    else:
        axes[1].set_axis_off()
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)
