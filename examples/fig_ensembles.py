"""Disorder ensembles of the dimer-coupled oscillator: D_KY, D_BC, SAP and VAR[M] vs N
(paper fig:dim, fig:sap, fig:mag).

    python examples/fig_ensembles.py [--out out/examples] [--full | --smoke] [--workers 2]
        [--spins 100 500 1000 5000 --realizations 50 --scheduler tcp://host:8786]

Each task is one disorder realization SpinDimerEnsemble.random(N, p=2, R=1, J=2, seed) at one
coupling C (2.9 and 4.0): its Lyapunov spectrum in (q, v), D_KY, the box-counting dimension of
the section and the time-averaged magnetization M_T
(``analysis.experiments.ensemble.ensemble_task``). The tasks run through
``analysis.experiments.execution.run_tasks`` — process pool or Dask cluster — and every result goes
to a SQLite ``ResultStore``: run the script again and finished tasks are skipped, so
a crashed or interrupted sweep resumes where it stopped. Then per (N, C): means of D_KY and D_BC,
SAP[D] = (mean(D²) − mean(D)²)/mean(D)², the number of regular realizations (D_KY = 0), and
VAR[M] = mean(M_T²) − mean(M_T)².

By default 50 realizations per (N, C) (about a minute on two cores: the trends with N show,
with wide scatter); ``--full`` runs the paper's 500 (about 10 min on two cores; every finished
task is in ``OUT/fig_ensembles.sqlite``, so an interrupted run resumes, and the default's tasks
are reused).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from analysis.experiments.ensemble import (  # noqa: E402
    EXPERIMENT,
    aggregate_ensemble,
    ensemble_task,
    ensemble_tasks,
)
from analysis.experiments.execution import run_tasks  # noqa: E402
from analysis.experiments.store import ResultStore  # noqa: E402

COUPLINGS = (2.9, 4.0)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/examples", help="output directory")
    size = parser.add_mutually_exclusive_group()
    size.add_argument(
        "--full",
        action="store_true",
        help="the paper's 500 realizations (about 10 min on two cores; resumable)",
    )
    size.add_argument("--smoke", action="store_true", help="tiny sizes (for tests)")
    parser.add_argument("--spins", type=int, nargs="+", default=[100, 500, 1000, 5000])
    parser.add_argument(
        "--realizations", type=int, default=None, help="per (N, C); default 50, --full 500"
    )
    parser.add_argument("--t-end", type=float, default=2.0e4)
    parser.add_argument("--transient", type=float, default=1.0e3)
    parser.add_argument("--seed", type=int, default=0, help="base seed of the disorder")
    parser.add_argument("--workers", type=int, default=None, help="local processes")
    parser.add_argument("--scheduler", default=None, help="Dask scheduler address")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.realizations is None:
        args.realizations = 500 if args.full else 50
    if args.smoke:
        args.spins, args.realizations, args.t_end, args.transient = [20, 60], 3, 100.0, 10.0
        args.workers = 1

    tasks = ensemble_tasks(
        args.spins, COUPLINGS, args.realizations, args.seed, args.t_end, args.transient
    )
    with ResultStore(out / "fig_ensembles.sqlite") as store:
        results = run_tasks(
            EXPERIMENT,
            tasks,
            ensemble_task,
            store=store,
            workers=args.workers,
            scheduler=args.scheduler,
            progress=not args.smoke,
        )
    points = aggregate_ensemble(zip(tasks, results, strict=True))

    print(f"{'N':>6s} {'C':>4s} {'<D_KY>':>7s} {'<D_BC>':>7s} {'SAP_KY':>7s} {'SAP_BC':>7s} "
          f"{'#reg':>5s} {'VAR[M]':>9s}")  # fmt: skip
    for p in points:
        print(
            f"{p.spins:6d} {p.coupling:4.1f} {p.mean_kaplan_yorke:7.3f} {p.mean_box_counting:7.3f}"
            f" {p.sap_kaplan_yorke:7.3f} {p.sap_box_counting:7.3f} {p.regular_count:5d}"
            f" {p.var_magnetization:9.2e}"
        )

    fig, axes = plt.subplots(1, 4, figsize=(16, 3.6))
    for c, color in zip(COUPLINGS, ("tab:green", "tab:blue"), strict=True):
        pts = [p for p in points if p.coupling == c]
        n = [p.spins for p in pts]
        axes[0].plot(n, [p.mean_kaplan_yorke for p in pts], "o-", color=color, label=f"KY, C={c}")
        axes[0].plot(n, [p.mean_box_counting for p in pts], "s--", color=color, label=f"BC, C={c}")
        axes[1].plot(n, [p.sap_kaplan_yorke for p in pts], "o-", color=color, label=f"KY, C={c}")
        axes[1].plot(n, [p.sap_box_counting for p in pts], "s--", color=color, label=f"BC, C={c}")
        axes[2].plot(n, [p.regular_count for p in pts], "o-", color=color, label=f"C={c}")
        axes[3].plot(n, [p.var_magnetization for p in pts], "o-", color=color, label=f"C={c}")
    titles = ("mean dimension", "SAP[D]", f"D_KY = 0 of {args.realizations}", "VAR[M]")
    for ax, title in zip(axes, titles, strict=True):
        ax.set_xscale("log")
        ax.set_xlabel("N")
        ax.set_title(title, fontsize=9)
        ax.legend(fontsize=7)
    for ax in (axes[1], axes[3]):
        ax.set_yscale("log")
    path = out / "fig_ensembles.png"
    fig.savefig(path, dpi=130, bbox_inches="tight")
    print("wrote", path)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
