"""``hyst poincare``: stroboscopic section φ = 0; writes ``poincare.npz`` and ``poincare.png``."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

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
from analysis.cli._output import (
    announce_compilation,
    emit,
    figure_title,
    prepare_out,
)
from analysis.cli._parsing import (
    add_subcommand,
    int_at_least,
)

__all__ = ["register", "run"]


def register(subparsers: Any) -> None:
    p = add_subcommand(
        subparsers,
        "poincare",
        help="Poincare (stroboscopic) section, write .npz data and a PNG",
        description="Points (q, v, M[, w]) at t = (transient + i) T, i = 0..periods-1, saved to "
        "DIR/poincare.npz and a scatter plot in the q-v plane.",
    )
    add_model_options(p)
    add_oscillator_options(p)
    add_initial_options(p)
    g = p.add_argument_group("run")
    g.add_argument(
        "--periods", type=int_at_least(1, 10**8), default=2000, help="number of section points"
    )
    add_transient_option(g, 100, "--transient-periods", integer=True)
    add_output_options(p, writes="poincare.npz, poincare.png")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    check_model_options(args)
    system = build_system(args)
    state = initial_operator_state(args, system.operator)
    out = prepare_out(args)
    announce_compilation(args)
    with naming_divergence(lambda: system):
        sec = system.poincare_section(
            args.periods, args.transient, args.q0, args.v0, operator_state=state
        )
    data = {"q": sec.q, "v": sec.v, "M": sec.M}
    if sec.w is not None:
        data["w"] = sec.w
    record = model_record(args)
    record.update(
        coupling=args.coupling,
        damping_ratio=args.damping_ratio,
        frequency=args.frequency,
        **initial_record(args),
        periods=args.periods,
        transient_periods=args.transient,
    )
    npz, png = out / "poincare.npz", out / "poincare.png"
    np.savez_compressed(npz, **data, parameters=np.array(repr(record)))
    _plot(sec, figure_title(args, "Poincaré section φ = 0"), png)
    record.update(points=int(sec.q.size), npz=npz, png=png)
    emit(args, record, [f"wrote {npz} and {png} ({sec.q.size} points)"])
    return 0


def _plot(sec: Any, title: str, path: Path) -> None:
    import matplotlib.pyplot as plt  # drawing only; the backend stays the caller's

    fig, ax = plt.subplots(figsize=(6.5, 5))
    sc = ax.scatter(sec.q, sec.v, c=sec.M, s=2, cmap="coolwarm", lw=0)
    fig.colorbar(sc, ax=ax, label="M")
    ax.set(xlabel="q", ylabel="v")
    ax.set_title(title, fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
