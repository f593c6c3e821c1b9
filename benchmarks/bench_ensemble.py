"""Throughput of the disorder ensemble at one paper-scale point, and where ``hyst paper --full``
spends its time.

One task = one realization ``SpinDimerEnsemble.random(20000, 2, 1, 2, seed)`` at C = 4.0:
Lyapunov spectrum, Poincaré section, D_BC and M_T over the whole forcing periods in
[transient, t_end], from one integration with the tangent flow (paper scale: t_end = 2·10⁴,
transient = 10³). Runs the same number of fresh tasks with 1 and with 2 local worker processes
(no store) and prints tasks/hour for each.

Then (unless ``--no-estimate``) the profile of fig:dim, whose one shared computation
(``analysis.paper.ensemble_tasks.ensemble_data``) is nearly all of a full run: ``--reps`` tasks
of every kind of the full run are timed in this process at full size, each split into its
components by timing wrappers around the functions that do the work, and the components are
added up over the full run's task list (method: ``full_run_profile``).
``full_paper_estimate_s`` is that model's fig:dim time plus the other figures and the basin
evidence as measured in ``--full-report``; the same report's measured total is printed next to
it as ``full_paper_measured_s``. The last line is one JSON object.

    python benchmarks/bench_ensemble.py [--tasks 4] [--t-end 20000] [--transient 1000]
        [--reps 2] [--full-report docs/paper-full/report.json] [--no-estimate]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import time
from pathlib import Path

from analysis.experiments.ensemble import ensemble_task, ensemble_tasks
from analysis.experiments.execution import run_tasks


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spins", type=int, default=20000)
    ap.add_argument("--coupling", type=float, default=4.0)
    ap.add_argument("--tasks", type=int, default=4, help="tasks per worker setting")
    ap.add_argument("--t-end", type=float, default=20000.0)
    ap.add_argument("--transient", type=float, default=1000.0)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--no-estimate", action="store_true", help="skip full_paper_estimate_s")
    ap.add_argument("--reps", type=int, default=2, help="timed tasks of each kind (profile)")
    ap.add_argument("--full-report", default="docs/paper-full/report.json")
    args = ap.parse_args()

    # warm the numba caches outside the timing
    ensemble_task(args.spins, args.coupling, seed=0, t_end=50.0, transient=10.0)

    out = {
        "benchmark": "ensemble",
        "spins": args.spins,
        "coupling": args.coupling,
        "t_end": args.t_end,
        "transient": args.transient,
        "tasks": args.tasks,
        "cpu_count": os.cpu_count(),
        "python": platform.python_version(),
    }
    for i, workers in enumerate(args.workers):
        # fresh seeds for every setting (base seed differs), nothing served from a store
        tasks = ensemble_tasks(
            [args.spins], [args.coupling], args.tasks, 1000 + i, args.t_end, args.transient
        )
        start = time.perf_counter()
        results = run_tasks("bench", tasks, ensemble_task, workers=workers, progress=False)
        wall = time.perf_counter() - start
        rate = 3600.0 * len(tasks) / wall
        out[f"tasks_per_hour_{workers}_workers"] = round(rate, 1)
        out[f"wall_seconds_{workers}_workers"] = round(wall, 2)
        mean_dky = sum(r["kaplan_yorke"] for r in results) / len(results)
        print(
            f"{workers} worker(s): {len(tasks)} tasks in {wall:.1f} s = {rate:.0f} tasks/hour "
            f"(mean D_KY {mean_dky:.3f})"
        )
    if len(args.workers) >= 2:
        a, b = args.workers[:2]
        out["speedup"] = round(
            out[f"tasks_per_hour_{b}_workers"] / out[f"tasks_per_hour_{a}_workers"], 2
        )
    if not args.no_estimate:
        out.update(full_run_profile(args.reps, out.get("speedup", 1.0), args.full_report))
    print(json.dumps(out))


# -- where a full run's time goes ----------------------------------------------------------------

#: figures whose time is fig:dim's shared computation (the others reuse its stored tasks)
ENSEMBLE_FIGURES = ("fig:dim", "fig:sap", "fig:mag", "fig:mag_his")
#: the issue's target for ``hyst paper --full`` on two cores
TARGET_S = 900.0
#: functions timed inside the tasks: (module, class or "", attribute, component). Times are
#: exclusive (a timed call inside another is subtracted from it); a task's untimed rest is its
#: root's component ("ensemble: other Python" = task function, Lyapunov loop, observer)
_TIMED = (
    ("analysis.experiments.ensemble", "", "ensemble_task", "ensemble: other Python"),
    ("analysis.experiments.ensemble", "", "disorder_system", "ensemble: operator, engine setup"),
    ("oscillators.system", "ForcedOscillator", "initial_state", "ensemble: operator, engine setup"),
    ("oscillators.system", "ForcedOscillator", "engine", "ensemble: operator, engine setup"),
    ("oscillators.engines._relay_kernels", "", "run_nested", "ensemble: relay kernel"),
    ("oscillators.engines._relay_kernels", "", "run_heap", "ensemble: relay kernel"),
    ("analysis.dynamics.lyapunov", "TangentStepper", "step", "ensemble: engine Python per QR step"),
    ("analysis.dynamics.lyapunov", "", "_qr_step", "ensemble: QR"),
    ("analysis.experiments.ensemble", "", "section_period", "ensemble: section period test"),
    ("analysis.experiments.ensemble", "", "box_counting_dimension", "ensemble: box counting"),
    ("analysis.experiments.iid", "", "iid_task", "iid: other"),
    ("hysteresis.preisach._kernels", "", "discrete_apply", "iid: Preisach kernel"),
    ("analysis.paper.ensemble_tasks", "", "limit_dimension_task", "limit tasks (erf-play)"),
)


class _Timers:
    """Exclusive CPU time of this process per component of the functions in :data:`_TIMED`
    while active (CPU time, not wall time: on the shared machine another process's load then
    changes the shares little)."""

    def __init__(self) -> None:
        self.acc: dict[str, float] = {}
        self._stack: list[list[float]] = []  # [start, time in timed children]
        self._saved: list[tuple[object, str, object]] = []

    def __enter__(self) -> _Timers:
        import importlib

        for module, cls, name, label in _TIMED:
            owner = importlib.import_module(module)
            owner = getattr(owner, cls) if cls else owner
            original = getattr(owner, name, None)
            if original is None:
                raise RuntimeError(f"{module}.{cls or ''}{'.' if cls else ''}{name} is gone")
            self._saved.append((owner, name, original))
            setattr(owner, name, self._wrap(original, label))
        return self

    def __exit__(self, *exc: object) -> None:
        for owner, name, original in reversed(self._saved):
            setattr(owner, name, original)
        self._saved.clear()

    def _wrap(self, func, label):
        stack, acc = self._stack, self.acc

        def timed(*args, **kwargs):
            frame = [time.process_time(), 0.0]
            stack.append(frame)
            try:
                return func(*args, **kwargs)
            finally:
                stack.pop()
                total = time.process_time() - frame[0]
                acc[label] = acc.get(label, 0.0) + total - frame[1]
                if stack:
                    stack[-1][1] += total

        return timed

    def take(self) -> dict[str, float]:
        """The times since the last call, and start afresh."""
        out = dict(self.acc)
        self.acc.clear()
        return out


def _mean_components(run, reps: int, timers: _Timers) -> tuple[dict[str, float], float]:
    """Mean component times of ``reps`` calls ``run(i)`` and their mean switch count."""
    timers.take()
    switches = 0.0
    for i in range(reps):
        switches += float(run(i).get("switches", 0))
    return {k: v / reps for k, v in timers.take().items()}, switches / reps


def _pool_costs() -> tuple[float, float]:
    """(CPU seconds of the client process per task of a pool run with a store, CPU seconds of a
    fresh worker's numba load).

    The first: 80 small ensemble tasks through ``run_tasks`` with two workers and a store,
    the client's own CPU time (submitting, unpickling, the SQLite writes) per task. The second:
    a fresh interpreter's first task minus its second (the cached kernels' load, which every new
    worker pool pays once, in both workers at the same time).
    """
    import subprocess
    import sys
    import tempfile

    small = [dict(spins=100, coupling=4.0, seed=s, t_end=200.0, transient=10.0) for s in range(80)]
    with tempfile.TemporaryDirectory() as tmp:
        start = time.process_time()
        run_tasks("bench", small, ensemble_task, store=Path(tmp) / "s.sqlite", workers=2,
                  progress=False)  # fmt: skip
        per_task = (time.process_time() - start) / len(small)
    probe = (
        "import time\nfrom analysis.experiments.ensemble import ensemble_task as f\n"
        "a = time.process_time(); f(100, 4.0, seed=1, t_end=50.0, transient=10.0)\n"
        "b = time.process_time(); f(100, 4.0, seed=2, t_end=50.0, transient=10.0)\n"
        "print((b - a) - (time.process_time() - b))\n"
    )
    root = str(Path(__file__).resolve().parents[1])  # this checkout, as in this process
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([root, os.environ.get("PYTHONPATH", "")]))
    cold = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, env=env,
                          check=True)  # fmt: skip
    return per_task, float(cold.stdout.split()[-1])


def full_run_profile(reps: int, speedup: float, full_report: str) -> dict:
    """Where fig:dim's time goes, from ``reps`` timed tasks of every kind of the full run.

    Method: every (N, C) of the full ensemble and every N of the iid reference is timed on its
    first ``reps`` realizations of the full run (the same seeds and sizes), split into the
    components of :data:`_TIMED` (CPU time of this process); the two limit tasks once. A
    component's time in the full run is its mean per task × the number of such tasks ÷ the
    2-worker speed-up ``speedup`` measured before (the limits: the longer one, they run side by
    side), plus the client's CPU time per task (submitting, unpickling, storing: it shares the
    two cores with the workers, so half of it) and per worker pool the numba load of fresh
    workers (three pools: ensemble, limits, iid). Shares of this model, applied to the measured
    fig:dim seconds of ``full_report``, say where the full run's time went; the machine's load
    mostly cancels in them (the absolute model does not: it is this run's conditions).
    """
    # the task functions are called through their modules: the timers wrap those attributes
    import analysis.experiments.ensemble as ensemble
    import analysis.experiments.iid as iid
    import analysis.paper.ensemble_tasks as paper_tasks
    from analysis.experiments.parameters import ENSEMBLE_COUPLINGS, FREQUENCY, SEED
    from analysis.paper.context import SIZES

    full = SIZES["full"]
    speedup = max(speedup, 1.0)
    parts: dict[str, float] = {}
    kernel_s = switches_all = 0.0
    print(f"profile of the full run's fig:dim ({reps} tasks of each kind, full size):")
    with _Timers() as timers:
        for n in full.ensemble_spins:
            seeds = ensemble.realization_seeds(SEED, n, reps)
            for c in ENSEMBLE_COUPLINGS:
                comp, switches = _mean_components(
                    lambda i, n=n, c=c, seeds=seeds: ensemble.ensemble_task(
                        n,
                        c,
                        seed=seeds[i],
                        t_end=full.ensemble_t_end,
                        transient=full.ensemble_transient,
                    ),
                    reps,
                    timers,
                )
                count = full.ensemble_realizations
                for k, v in comp.items():
                    parts[k] = parts.get(k, 0.0) + v * count / speedup
                kernel = comp.get("ensemble: relay kernel", 0.0)
                kernel_s += kernel * count
                switches_all += switches * count
                total = sum(comp.values())
                dims = comp.get("ensemble: box counting", 0.0)
                dims += comp.get("ensemble: section period test", 0.0)
                print(
                    f"  N={n:5d} C={c}: {total:.3f} s/task, {switches:.3g} switches, kernel "
                    f"{1e9 * kernel / max(switches, 1.0):.0f} ns/switch = {kernel / total:.0%}, "
                    f"box counting + period test {dims / total:.0%}"
                )
        for n in full.iid_spins:
            tasks = iid.iid_tasks(n, full.iid_steps, reps, iid._seed_for(SEED, n))
            comp, _ = _mean_components(
                lambda i, tasks=tasks: iid.iid_task(**tasks[i]), reps, timers
            )
            for k, v in comp.items():
                parts[k] = parts.get(k, 0.0) + v * full.iid_realizations / speedup
            print(f"  iid N={n:5d}: {sum(comp.values()):.3f} s/task")
        # the limit tasks of ensemble_data: as many section points as one realization
        period = 2.0 * math.pi / FREQUENCY
        skip = math.ceil(full.ensemble_transient / period)
        points = max(math.floor(full.ensemble_t_end / period) - skip, 10)
        limits = []
        for c in ENSEMBLE_COUPLINGS:
            timers.take()
            paper_tasks.limit_dimension_task(c, full.dky_t_end, full.dky_transient, points, skip)
            limits.append(sum(timers.take().values()))
        parts["limit tasks (erf-play)"] = max(limits)
    per_task, cold = _pool_costs()
    n_tasks = len(full.ensemble_spins) * len(ENSEMBLE_COUPLINGS) * full.ensemble_realizations
    n_tasks += len(full.iid_spins) * full.iid_realizations + len(ENSEMBLE_COUPLINGS)
    parts["pool, pickling, store (client)"] = per_task * n_tasks / 2.0
    parts["new worker pools (numba load)"] = 3 * cold
    model = sum(parts.values())
    res: dict = {
        "fig_dim_model_s": round(model, 1),
        "speedup_used": round(speedup, 2),
        "kernel_ns_per_switch": round(1e9 * kernel_s / max(switches_all, 1.0), 1),
    }
    report = Path(full_report)
    measured_dim = other = None
    if report.exists():
        data = json.loads(report.read_text())
        figs = data["figures"]
        measured_dim = sum(f["seconds"] for f in figs if f["label"] in ENSEMBLE_FIGURES)
        other = sum(f["seconds"] for f in figs if f["label"] not in ENSEMBLE_FIGURES)
        other += float(data.get("basins", {}).get("seconds") or 0.0)
    print("fig:dim by component (model s in this run, share"
          + (f", of the full run's {measured_dim:.0f} s)" if measured_dim else ")"))  # fmt: skip
    for k, v in sorted(parts.items(), key=lambda kv: -kv[1]):
        line = f"  {k:40s} {v:8.1f} s  {v / model:6.1%}"
        if measured_dim:
            line += f"  {v / model * measured_dim:7.1f} s"
        print(line)
    res["fig_dim_components_s"] = {k: round(v, 2) for k, v in parts.items()}
    res["full_ensemble_estimate_s"] = round(model, 1)
    if measured_dim is None:
        res["full_paper_estimate_s"] = None
        print(f"fig:dim model: {model:.0f} s ({report} not found)")
        return res
    res["full_paper_estimate_s"] = round(model + other, 1)
    res["full_paper_measured_s"] = round(measured_dim + other, 1)
    res["full_report"] = str(report)
    # On the full run's scale (this run's model shares of its measured fig:dim seconds): what
    # the relay kernel would have to reach for the target, everything else as it is now
    kernel_full = parts.get("ensemble: relay kernel", 0.0) / model * measured_dim
    budget = TARGET_S - other - (measured_dim - kernel_full)
    factor = kernel_full / budget if budget > 0 else None  # None: not reachable by the kernel
    res["kernel_speedup_for_target"] = None if factor is None else round(factor, 2)
    print(
        f"hyst paper --full: estimate {res['full_paper_estimate_s']:.0f} s (fig:dim {model:.0f} s "
        f"modelled here + other figures and basin evidence {other:.0f} s from {report}); "
        f"measured {res['full_paper_measured_s']:.0f} s. On the measured run's scale the relay "
        f"kernel is {kernel_full:.0f} s of fig:dim's {measured_dim:.0f} s: {TARGET_S:.0f} s "
        + (f"needs it {factor:.2f}x faster" if factor else "is out of the kernel's reach")
        + " with everything else unchanged"
    )
    return res


if __name__ == "__main__":
    main()
