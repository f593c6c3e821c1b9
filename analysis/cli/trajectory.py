"""``hyst trajectory``: integrate one system and write ``trajectory.npz`` and ``trajectory.png``."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from analysis.cli._build import (
    build_system,
    check_model_options,
    check_run_length,
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
)
from analysis.cli._output import (
    announce_compilation,
    emit,
    figure_title,
    prepare_out,
)
from analysis.cli._parsing import (
    CliError,
    add_subcommand,
    positive_float,
)

__all__ = ["register", "run"]


def register(subparsers: Any) -> None:
    p = add_subcommand(
        subparsers,
        "trajectory",
        help="integrate a trajectory, write .npz data and a PNG",
        description="Trajectory of the forced oscillator with hysteresis: samples (t, q, v, phi, "
        "M[, w]) plus the exact switch list, saved to DIR/trajectory.npz and a figure.",
    )
    add_model_options(p)
    add_oscillator_options(p)
    add_initial_options(p)
    g = p.add_argument_group("run")
    g.add_argument("--t-end", type=positive_float, default=200.0, help="end time")
    g.add_argument("--sample-dt", type=positive_float, default=0.01, help="sampling interval")
    add_output_options(p, writes="trajectory.npz, trajectory.png")
    p.set_defaults(func=run)


#: most samples the command keeps, writes to trajectory.npz and plots: stricter than the
#: library's ``oscillators.MAX_SAMPLES`` (1e8), whose arrays the command holds twice (data and
#: figure)
MAX_WRITTEN_SAMPLES = 50_000_000


def run(args: argparse.Namespace) -> int:
    check_model_options(args)
    check_run_length(args, args.t_end)
    if args.t_end / args.sample_dt > MAX_WRITTEN_SAMPLES:
        raise CliError(
            f"argument --sample-dt: t_end/sample_dt = {args.t_end / args.sample_dt:.3g} samples "
            f"exceeds the limit {MAX_WRITTEN_SAMPLES:.0e}; raise --sample-dt"
        )
    system = build_system(args)
    state = initial_operator_state(args, system.operator)
    out = prepare_out(args)
    announce_compilation(args)
    with naming_divergence(lambda: system):
        traj = system.trajectory(
            args.t_end, args.q0, args.v0, operator_state=state, sample_dt=args.sample_dt
        )
    data = {"t": traj.t, "q": traj.q, "v": traj.v, "phi": traj.phi, "M": traj.M}
    if traj.w is not None:
        data["w"] = traj.w
    for name in traj.switches.dtype.names or ():
        data[f"switch_{name}"] = traj.switches[name]
    if traj.events is not None:
        for name in traj.events.dtype.names or ():
            data[f"event_{name}"] = traj.events[name]
    record = model_record(args)
    record.update(
        coupling=args.coupling,
        damping_ratio=args.damping_ratio,
        frequency=args.frequency,
        **initial_record(args),
        t_end=args.t_end,
        sample_dt=args.sample_dt,
    )
    npz, png = out / "trajectory.npz", out / "trajectory.png"
    np.savez_compressed(npz, **data, parameters=np.array(repr(record)))
    _plot(traj, figure_title(args, "trajectory"), png)
    record.update(samples=int(traj.t.size), switches=int(traj.switches.size), npz=npz, png=png)
    emit(
        args,
        record,
        [f"wrote {npz} and {png} ({traj.t.size} samples, {traj.switches.size} switches)"],
    )
    return 0


def _plot(traj: Any, title: str, path: Path) -> None:
    import matplotlib.pyplot as plt  # drawing only; the backend stays the caller's

    fig, ax = plt.subplots(1, 3, figsize=(13, 4))
    ax[0].plot(traj.t, traj.q, lw=0.6)
    ax[0].set(xlabel="t", ylabel="q", title="position")
    ax[1].plot(traj.q, traj.v, lw=0.4)
    ax[1].set(xlabel="q", ylabel="v", title="phase portrait")
    ax[2].plot(traj.q, traj.M, lw=0.6, color="tab:red")
    ax[2].set(xlabel="q", ylabel="M", title="hysteresis")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
