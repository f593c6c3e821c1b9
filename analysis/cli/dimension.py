"""``hyst dimension``: Kaplan–Yorke and box-counting dimension of one attractor.

D_KY from the Lyapunov spectrum in the Poincaré section (phase neglected, as the paper), D_BC
from the section points (q, v) with the automatic scaling region. Writes DIR/dimension.png
(section and log-log fit) and DIR/dimension.npz.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np


def register(subparsers: Any) -> None:
    from analysis.cli.lyapunov import add_initial_arguments, add_model_arguments

    p = subparsers.add_parser(
        "dimension",
        help="Kaplan-Yorke and box-counting dimension of an attractor",
        description="D_KY from the Lyapunov spectrum and D_BC of the Poincare section (q, v).",
    )
    add_model_arguments(p)
    add_initial_arguments(p)
    p.add_argument("--t-end", type=float, default=20000.0, help="end time of the Lyapunov run")
    p.add_argument("--transient", type=float, default=1000.0, help="transient time")
    p.add_argument(
        "--points",
        type=int,
        default=None,
        help="section points for D_BC (default: the periods in [transient, t_end])",
    )
    p.add_argument(
        "--max-fill",
        type=float,
        default=0.1,
        help="box counting: largest count used, as a fraction of the points",
    )
    p.add_argument(
        "--min-boxes",
        type=float,
        default=8.0,
        help="box counting: smallest number of boxes across the attractor",
    )
    p.add_argument("--out", default=None, help="output directory (PNG and npz)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from analysis.bifurcation import section_period
    from analysis.cli.lyapunov import _json_float, build_system, model_parameters, play_state
    from analysis.dimensions import box_counting_dimension
    from analysis.lyapunov import lyapunov_spectrum

    try:
        system = build_system(args)
        opstate = play_state(args, system)
        ly = lyapunov_spectrum(
            system,
            args.t_end,
            args.transient,
            args.q0,
            args.v0,
            operator_state=opstate,
            progress=not (args.quiet or args.json),
        )
        transient_periods = int(np.ceil(args.transient / system.period))
        n = args.points
        if n is None:
            n = int(np.floor(args.t_end / system.period)) - transient_periods
        if n < 2:
            raise ValueError("need at least 2 section points (--points or a longer --t-end)")
        sec = system.poincare_section(n, transient_periods, args.q0, args.v0, opstate)
        points = np.column_stack([sec.q, sec.v])
        period = section_period(sec.q, sec.v)
        bc, bc_error = None, ""
        if period > 0:
            bc_error = f"periodic section (period {period}): D_BC = 0"
        else:
            try:
                bc = box_counting_dimension(
                    points, max_fill=args.max_fill, min_boxes=args.min_boxes
                )
            except ValueError as exc:
                bc_error = str(exc)
    except (ValueError, NotImplementedError) as exc:
        print(f"hyst dimension: error: {exc}", file=sys.stderr)
        return 2
    record = dict(model_parameters(args))
    record.update(
        exponents=[_json_float(x) for x in ly.exponents],
        kaplan_yorke=_json_float(ly.kaplan_yorke),
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
    if args.out is not None:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        arrays = dict(q=sec.q, v=sec.v, exponents=ly.exponents)
        if bc is not None:
            arrays.update(sizes=bc.sizes, counts=bc.counts, region=np.array(bc.region))
        np.savez_compressed(out / "dimension.npz", **arrays)
        _plot(sec, bc, out / "dimension.png")
        record["npz"] = str(out / "dimension.npz")
        record["png"] = str(out / "dimension.png")
    if args.json:
        print(json.dumps(record))
    else:
        print(
            f"D_KY = {ly.kaplan_yorke:.4f} from exponents "
            + ", ".join(f"{x:.5f}" for x in ly.exponents)
        )
        if bc is None:
            print(f"D_BC: no scaling region ({bc_error})")
        else:
            print(f"D_BC = {bc.dimension:.4f} +- {bc.stderr:.4f} from {n} section points")
    return 0


def _plot(sec: Any, bc: Any, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(9, 4))
    axes[0].plot(sec.q, sec.v, ".k", ms=1.0)
    axes[0].set_xlabel("q")
    axes[0].set_ylabel("v")
    axes[0].set_title(r"Poincaré section $\phi = 0$")
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
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)
