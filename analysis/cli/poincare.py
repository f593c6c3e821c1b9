"""``hyst poincare``: stroboscopic section φ = 0; writes ``poincare.npz`` and ``poincare.png``."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import numpy as np

from analysis.cli.lyapunov import (
    add_initial_arguments,
    add_model_arguments,
    build_system,
    model_parameters,
    play_state,
)


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "poincare",
        help="Poincare (stroboscopic) section, write .npz data and a PNG",
        description="Points (q, v, M[, w]) at t = (transient + i) T, i = 0..periods-1, saved to "
        "DIR/poincare.npz and a scatter plot in the q-v plane.",
    )
    add_model_arguments(p)
    add_initial_arguments(p)
    p.add_argument("--periods", type=int, default=2000, help="number of section points")
    p.add_argument("--transient-periods", type=int, default=100, help="periods skipped first")
    p.add_argument("--out", type=Path, default=Path("."), help="output directory")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    try:
        system = build_system(args)
        kwargs = {"operator_state": play_state(args, system)}
        sec = system.poincare_section(
            args.periods, args.transient_periods, args.q0, args.v0, **kwargs
        )
    except (ValueError, NotImplementedError) as exc:
        print(f"hyst poincare: error: {exc}", file=sys.stderr)
        return 2
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    data = {"q": sec.q, "v": sec.v, "M": sec.M}
    if sec.w is not None:
        data["w"] = sec.w
    params = model_parameters(args)
    np.savez_compressed(out / "poincare.npz", **data, parameters=np.array(repr(params)))
    _plot(sec, params, out / "poincare.png")
    print(f"wrote {out / 'poincare.npz'} and {out / 'poincare.png'} ({sec.q.size} points)")
    return 0


def _plot(sec: Any, params: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 5))
    sc = ax.scatter(sec.q, sec.v, c=sec.M, s=2, cmap="coolwarm", lw=0)
    fig.colorbar(sc, ax=ax, label="M")
    ax.set(
        xlabel="q",
        ylabel="v",
        title=f"Poincare section, {params['model']}, C = {params['coupling']}",
    )
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
