"""``hyst trajectory``: integrate one system and write ``trajectory.npz`` and ``trajectory.png``."""

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
        "trajectory",
        help="integrate a trajectory, write .npz data and a PNG",
        description="Trajectory of the forced oscillator with hysteresis: samples (t, q, v, phi, "
        "M[, w]) plus the exact switch list, saved to DIR/trajectory.npz and a figure.",
    )
    add_model_arguments(p)
    add_initial_arguments(p)
    p.add_argument("--t-end", type=float, default=200.0, help="end time")
    p.add_argument("--sample-dt", type=float, default=0.01, help="sampling interval")
    p.add_argument("--out", type=Path, default=Path("."), help="output directory")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    try:
        system = build_system(args)
        kwargs = {"operator_state": play_state(args, system)}
        traj = system.trajectory(args.t_end, args.q0, args.v0, sample_dt=args.sample_dt, **kwargs)
    except (ValueError, NotImplementedError) as exc:
        print(f"hyst trajectory: error: {exc}", file=sys.stderr)
        return 2
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    data = {"t": traj.t, "q": traj.q, "v": traj.v, "phi": traj.phi, "M": traj.M}
    if traj.w is not None:
        data["w"] = traj.w
    for name in traj.switches.dtype.names or ():
        data[f"switch_{name}"] = traj.switches[name]
    if traj.events is not None:
        for name in traj.events.dtype.names or ():
            data[f"event_{name}"] = traj.events[name]
    params = model_parameters(args)
    np.savez_compressed(out / "trajectory.npz", **data, parameters=np.array(repr(params)))
    _plot(traj, params, out / "trajectory.png")
    print(
        f"wrote {out / 'trajectory.npz'} and {out / 'trajectory.png'} "
        f"({traj.t.size} samples, {traj.switches.size} switches)"
    )
    return 0


def _plot(traj: Any, params: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 3, figsize=(13, 4))
    ax[0].plot(traj.t, traj.q, lw=0.6)
    ax[0].set(xlabel="t", ylabel="q", title="position")
    ax[1].plot(traj.q, traj.v, lw=0.4)
    ax[1].set(xlabel="q", ylabel="v", title="phase portrait")
    ax[2].plot(traj.q, traj.M, lw=0.6, color="tab:red")
    ax[2].set(xlabel="q", ylabel="M", title="hysteresis")
    fig.suptitle(f"{params['model']}, C = {params['coupling']}")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
