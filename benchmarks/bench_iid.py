"""CPU time of one realization of the iid-input reference (``analysis.experiments.iid``).

One task: ``SpinDimerEnsemble.random(N, p=2, R=1, J=2, seed)`` driven by ``--steps`` iid
Gaussian inputs (std 2) from all spins down relaxed at ``u_0``, and its time average ``M_T``.
Two paths, both measured in this run (CPU seconds per task, ``time.process_time``, median of
``--repeats`` runs of ``--realizations`` tasks each):

* ``general``: the path before the nested drive (the baseline) — ``ensemble.apply``, the general
  discrete Preisach kernel, O(1 + relays switched) per input, O(N) for iid inputs;
* ``nested``: ``iid_task`` as it is — ``NestedPlan.drive``, O(log N) per input.

Printed per N: both times, their ratio and the largest ``|ΔM_T|`` between the paths over the
realizations; then the estimated CPU of the iid reference of ``hyst paper --full`` (its
``iid_spins`` × ``iid_realizations`` tasks of ``iid_steps`` inputs, from the times measured here,
sizes not in ``--spins`` measured too). The last line is one JSON object with every figure.

    python benchmarks/bench_iid.py [--spins 3000 10000 20000] [--steps 10000]
        [--realizations 4] [--repeats 3]
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

import numpy as np

from analysis.experiments.iid import iid_inputs, iid_task
from analysis.experiments.models import build_operator
from analysis.experiments.parameters import SIZES, SPIN_COUPLING, SPREAD, WIDTH

INPUT_STD = 2.0
INPUT_SEED = 12345


def general_task(spins: int, n_steps: int, seed: int, input_seed: int) -> dict:
    """``iid_task`` before the nested drive: the general Preisach kernel."""
    ensemble = build_operator(
        "dimers", spins=spins, seed=seed, width=WIDTH, spread=SPREAD, spin_coupling=SPIN_COUPLING
    )
    u = iid_inputs(n_steps, INPUT_STD, input_seed)
    outputs, _ = ensemble.apply(u, ensemble.initial_state(float(u[0])))
    return {"magnetization": float(np.asarray(outputs, dtype=float).mean())}


def cpu_per_task(task, spins: int, steps: int, realizations: int, repeats: int):
    """(median CPU seconds per task, the magnetizations of the realizations)."""
    task(spins, steps, 0, INPUT_SEED)  # compile / warm up
    runs = []
    mags = []
    for _ in range(repeats):
        start = time.process_time()
        mags = [task(spins, steps, s + 1, INPUT_SEED)["magnetization"] for s in range(realizations)]
        runs.append((time.process_time() - start) / realizations)
    return statistics.median(runs), np.array(mags)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spins", type=int, nargs="+", default=[3000, 10000, 20000])
    ap.add_argument("--steps", type=int, default=10000)
    ap.add_argument("--realizations", type=int, default=4)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    full = SIZES["full"]

    def nested_task(spins, steps, seed, input_seed):
        return iid_task(spins=spins, n_steps=steps, seed=seed, input_seed=input_seed)

    rows = {}
    for n in sorted(set(args.spins) | set(full.iid_spins)):
        t_old, m_old = cpu_per_task(general_task, n, args.steps, args.realizations, args.repeats)
        t_new, m_new = cpu_per_task(nested_task, n, args.steps, args.realizations, args.repeats)
        rows[n] = {
            "general_s": t_old,
            "nested_s": t_new,
            "ratio": t_old / t_new,
            "max_abs_dM_T": float(np.max(np.abs(m_old - m_new))),
        }
        shown = "" if n in args.spins else "  (for the full-run estimate)"
        print(
            f"N = {n:6d}: general {t_old * 1e3:8.2f} ms, nested {t_new * 1e3:6.2f} ms per task "
            f"= {t_old / t_new:6.1f} x; max |dM_T| = {rows[n]['max_abs_dM_T']:.1e}{shown}"
        )
    # the full run's tasks have iid_steps inputs; the time per task is linear in the steps
    scale = full.iid_steps / args.steps
    before = sum(rows[n]["general_s"] for n in full.iid_spins) * full.iid_realizations * scale
    after = sum(rows[n]["nested_s"] for n in full.iid_spins) * full.iid_realizations * scale
    print(
        f"hyst paper --full iid reference ({len(full.iid_spins)} N x {full.iid_realizations} "
        f"realizations x {full.iid_steps} steps): {before:.0f} s -> {after:.1f} s CPU "
        f"({before / after:.0f} x)"
    )
    print(
        json.dumps(
            {
                "steps": args.steps,
                "realizations": args.realizations,
                "repeats": args.repeats,
                "per_spins": {str(n): rows[n] for n in sorted(rows)},
                "ratio": {str(n): rows[n]["ratio"] for n in args.spins},
                "full_iid_cpu_s_before": before,
                "full_iid_cpu_s_after": after,
            }
        )
    )


if __name__ == "__main__":
    main()
