"""``hyst bifurcation``: Poincaré projection q(φ = 0) and λ_max while a parameter is stepped.

The parameter (coupling C by default; also Ω or ζ) is stepped in the order given — the paper
steps C downward from large values — with continuation: the final state at one value starts the
next. Writes DIR/bifurcation.npz and DIR/bifurcation.png.

Example (paper fig:bif_0, one dimer with b = (1, −1), J = 2)::

    hyst bifurcation --model dimers --fields 1 -1 --start 10 --stop 0.5 --steps 200 --out bif0
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

PARAMETERS = ("coupling", "frequency", "damping_ratio")


def register(subparsers: Any) -> None:
    from analysis.cli.lyapunov import add_initial_arguments, add_model_arguments

    p = subparsers.add_parser(
        "bifurcation",
        help="bifurcation diagram (Poincaré q and lambda_max) with continuation",
        description="Step a parameter in the given order (continuation from the previous final "
        "state) and record the Poincaré section q(phi=0) and the largest Lyapunov exponent.",
    )
    add_model_arguments(p)
    add_initial_arguments(p)
    # the coupling is only needed as a fixed value when another parameter is swept
    p._option_string_actions["--coupling"].required = False
    g = p.add_argument_group("sweep")
    g.add_argument(
        "--parameter",
        choices=PARAMETERS,
        default="coupling",
        help="swept parameter (default: coupling C)",
    )
    g.add_argument(
        "--values",
        type=float,
        nargs="+",
        default=None,
        help="explicit parameter values, in sweep order",
    )
    g.add_argument("--start", type=float, default=None, help="first value of an even grid")
    g.add_argument("--stop", type=float, default=None, help="last value of an even grid")
    g.add_argument("--steps", type=int, default=100, help="number of grid values")
    g.add_argument("--periods", type=int, default=60, help="section points per value")
    g.add_argument("--transient", type=int, default=200, help="transient periods per value")
    g.add_argument(
        "--lyapunov-t",
        type=float,
        default=2000.0,
        help="time for lambda_max per value (0: no Lyapunov exponents)",
    )
    g.add_argument(
        "--no-continuation",
        action="store_true",
        help="start every value from (q0, v0) instead of the previous final state",
    )
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument("--json", action="store_true", help="print one JSON summary object")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def _values(args: argparse.Namespace) -> np.ndarray:
    if args.values is not None:
        return np.asarray(args.values, dtype=float)
    if args.start is None or args.stop is None:
        raise ValueError("give --values or both --start and --stop")
    if args.steps < 1:
        raise ValueError(f"--steps must be >= 1, got {args.steps}")
    return np.linspace(args.start, args.stop, args.steps)


def plot_diagram(diagram: Any, path: Path) -> Path:
    """Two panels: Poincaré q per value (top) and λ_max (bottom)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    has_lyap = np.any(np.isfinite(diagram.max_exponent))
    fig, axes = plt.subplots(
        2 if has_lyap else 1, 1, sharex=True, figsize=(7, 5 if has_lyap else 3)
    )
    axes = np.atleast_1d(axes)
    x = np.repeat(diagram.values, diagram.q.shape[1])
    axes[0].plot(x, diagram.q.ravel(), ".k", ms=1.0, alpha=0.6)
    axes[0].set_ylabel(r"$q(\phi=0)$")
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
    from analysis.bifurcation import bifurcation_diagram
    from analysis.cli.lyapunov import build_operator
    from oscillators import ForcedOscillator

    try:
        values = _values(args)
        if args.parameter != "coupling" and args.coupling is None:
            raise ValueError("--coupling is required when another parameter is swept")
        operator = build_operator(args)
        fixed = dict(
            coupling=args.coupling, damping_ratio=args.damping_ratio, frequency=args.frequency
        )

        def make_system(value: float) -> Any:
            params = dict(fixed)
            params[args.parameter] = value
            return ForcedOscillator(
                operator, params["coupling"], params["damping_ratio"], params["frequency"]
            )

        operator_state = None
        if args.w0 is not None:
            operator_state = make_system(float(values[0])).operator.state(args.w0, args.q0)
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
            operator_state=operator_state,
            parameter=args.parameter,
            progress=not (args.quiet or args.json),
        )
    except (ValueError, NotImplementedError) as exc:
        print(f"hyst bifurcation: error: {exc}", file=sys.stderr)
        return 2
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    npz = diagram.save(out / "bifurcation.npz")
    png = plot_diagram(diagram, out / "bifurcation.png")
    counts = diagram.period_counts(1e-6)
    lam = diagram.max_exponent
    record = {
        "parameter": args.parameter,
        "values": int(values.size),
        "first": float(values[0]),
        "last": float(values[-1]),
        "periods": args.periods,
        "transient_periods": args.transient,
        "continuation": not args.no_continuation,
        "distinct_points": counts.tolist(),
        "chaotic_values": int(np.count_nonzero(lam > 0)) if np.any(np.isfinite(lam)) else None,
        "npz": str(npz),
        "png": str(png),
    }
    if args.json:
        print(json.dumps(record))
    else:
        print(
            f"{values.size} values of {args.parameter} from {values[0]} to {values[-1]}; "
            f"wrote {npz} and {png}"
        )
    return 0
