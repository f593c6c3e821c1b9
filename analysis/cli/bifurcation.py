"""``hyst bifurcation``: Poincaré projection q(φ = 0) and λ_max while a parameter is stepped.

The parameter (coupling C by default; also Ω or ζ) is stepped in the order given — the paper
steps C downward from large values — with continuation: the final state at one value starts the
next. Writes DIR/bifurcation.npz and DIR/bifurcation.png.

Example (paper fig:bif_0, one dimer with b = (1, −1), J = 2)::

    hyst bifurcation --model dimers --fields 1 -1 --start 10 --stop 0.5 --steps 200 --out bif0
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from analysis.cli._build import (
    build_operator,
    build_system,
    check_model_options,
    check_run_length,
    initial_operator_state,
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
    finite_float,
    int_at_least,
    nonnegative_float,
)
from analysis.dynamics.bifurcation import bifurcation_diagram

__all__ = ["register", "run", "plot_diagram"]

PARAMETERS = ("coupling", "frequency", "damping_ratio")


def register(subparsers: Any) -> None:
    p = add_subcommand(
        subparsers,
        "bifurcation",
        help="bifurcation diagram (Poincaré q and lambda_max) with continuation",
        description="Step a parameter in the given order (continuation from the previous final "
        "state) and record the Poincaré section q(phi=0) and the largest Lyapunov exponent.",
    )
    add_model_options(p)
    # the coupling is only needed as a fixed value when another parameter is swept
    add_oscillator_options(p, coupling="optional")
    add_initial_options(p)
    g = p.add_argument_group("sweep")
    g.add_argument("--parameter", choices=PARAMETERS, default="coupling", help="swept parameter")
    g.add_argument(
        "--values",
        type=finite_float,
        nargs="+",
        default=None,
        help="explicit parameter values, in sweep order (instead of --start/--stop/--steps)",
    )
    g.add_argument("--start", type=finite_float, default=None, help="first value of an even grid")
    g.add_argument("--stop", type=finite_float, default=None, help="last value of an even grid")
    g.add_argument(
        "--steps", type=int_at_least(1, 10**6), default=100, help="number of grid values"
    )
    g.add_argument(
        "--periods", type=int_at_least(1, 10**7), default=60, help="section points per value"
    )
    add_transient_option(g, 200, integer=True)
    g.add_argument(
        "--lyapunov-t",
        type=nonnegative_float,
        default=2000.0,
        help="time for lambda_max per value (0: no Lyapunov exponents)",
    )
    g.add_argument(
        "--no-continuation",
        action="store_true",
        help="start every value from (q0, v0) instead of the previous final state",
    )
    add_output_options(p, writes="bifurcation.npz, bifurcation.png")
    p.set_defaults(func=run)


def _values(args: argparse.Namespace) -> np.ndarray:
    if args.values is not None:
        if args.start is not None or args.stop is not None:
            raise CliError("argument --values: give --values or --start/--stop, not both")
        return np.asarray(args.values, dtype=float)
    if args.start is None or args.stop is None:
        raise CliError("argument --start/--stop: give --values or both --start and --stop")
    return np.linspace(args.start, args.stop, args.steps)


def plot_diagram(diagram: Any, path: Path, title: str | None = None) -> Path:
    """Two panels: Poincaré q per value (top) and λ_max (bottom)."""
    import matplotlib.pyplot as plt  # drawing only; the backend stays the caller's

    has_lyap = np.any(np.isfinite(diagram.max_exponent))
    fig, axes = plt.subplots(
        2 if has_lyap else 1, 1, sharex=True, figsize=(7, 5 if has_lyap else 3)
    )
    axes = np.atleast_1d(axes)
    x = np.repeat(diagram.values, diagram.q.shape[1])
    axes[0].plot(x, diagram.q.ravel(), ".k", ms=1.0, alpha=0.6)
    axes[0].set_ylabel(r"$q(\phi=0)$")
    if title:
        axes[0].set_title(title, fontsize=8)
    if has_lyap:
        axes[1].plot(diagram.values, diagram.max_exponent, "-", lw=0.8)
        axes[1].axhline(0.0, color="grey", lw=0.5)
        axes[1].set_ylabel(r"$\lambda_{\max}$")
    axes[-1].set_xlabel(diagram.parameter)
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return path


def run(args: argparse.Namespace) -> int:
    check_model_options(args)
    values = _values(args)
    check_run_length(args, args.lyapunov_t, "--lyapunov-t")
    if args.parameter != "coupling" and args.coupling is None:
        raise CliError("argument --coupling: required when another parameter is swept")
    if args.parameter == "coupling" and args.coupling is not None:
        raise CliError("argument --coupling: the swept parameter is given by --values/--start")
    operator = build_operator(args)
    fixed = dict(coupling=args.coupling, damping_ratio=args.damping_ratio, frequency=args.frequency)

    built: list[Any] = []  # the sweep builds one system per value, in order: the last runs

    def make_system(value: float) -> Any:
        params = dict(fixed)
        params[args.parameter] = value
        ns = argparse.Namespace(**{**vars(args), **params})
        built.append(build_system(ns, operator=operator))
        return built[-1]

    # every value must give a valid system: check them all before the sweep starts
    option = "--values" if args.values is not None else "--start/--stop"
    for v in values:
        try:
            make_system(float(v))
        except CliError as exc:
            raise CliError(f"argument {option}: {args.parameter} = {v:g}: {exc}") from exc
    state = initial_operator_state(args, operator)
    out = prepare_out(args)
    announce_compilation(args)
    with naming_divergence(lambda: built[-1]):
        diagram = bifurcation_diagram(
            make_system,
            values,
            args.periods,
            args.transient,
            continuation=not args.no_continuation,
            lyapunov=args.lyapunov_t > 0,
            lyapunov_t_end=max(args.lyapunov_t, 1e-9),
            q0=args.q0,
            v0=args.v0,
            operator_state=state,
            parameter=args.parameter,
            progress=progress_enabled(args),
        )
    npz = diagram.save(out / "bifurcation.npz")
    title = figure_title(args, f"bifurcation in {args.parameter}")
    png = plot_diagram(diagram, out / "bifurcation.png", title)
    counts = diagram.period_counts(1e-6)
    lam = diagram.max_exponent
    record = model_record(args)
    record.update(
        parameter=args.parameter,
        values=int(values.size),
        first=float(values[0]),
        last=float(values[-1]),
        coupling=args.coupling,
        damping_ratio=args.damping_ratio,
        frequency=args.frequency,
        periods=args.periods,
        transient_periods=args.transient,
        continuation=not args.no_continuation,
        distinct_points=counts.tolist(),
        chaotic_values=int(np.count_nonzero(lam > 0)) if np.any(np.isfinite(lam)) else None,
        npz=npz,
        png=png,
    )
    emit(
        args,
        record,
        [
            f"{values.size} values of {args.parameter} from {values[0]} to {values[-1]}; "
            f"wrote {npz} and {png}"
        ],
    )
    return 0
