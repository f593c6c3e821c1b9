"""Per disorder realization, the attractor the paper's initial condition reaches.

One task is one realization of a model with disorder (``dimers``: ``SpinDimerEnsemble.random(N,
p, R, J, seed)``; ``preisach``: N random relays) at one coupling C, with the realization seeds
of the ensembles (:func:`~analysis.experiments.ensemble.realization_seeds`, so the same
realizations as ``hyst ensemble``). From ``(q0, v0)`` the section is classified as in the basins
(:func:`~analysis.dynamics.attractors.section_run`): a periodic orbit is refined once
(:func:`~analysis.dynamics.attractors.periodic_attractor`: period, Floquet multipliers,
stability, transient length); an aperiodic one gets ``λ_max`` with its finite-time error and
``D_KY`` (:func:`~analysis.dynamics.attractors.lyapunov_estimate`) and is ``chaotic`` when
``λ_max`` exceeds twice its error, ``undecided`` otherwise; a run that leaves the divergence
bound is ``divergent``. Tasks run through :func:`~analysis.experiments.execution.run_tasks`
(workers, Dask, the resumable store, progress).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

import numpy as np

from analysis.dynamics.attractors import (
    APERIODIC,
    PERIODIC,
    lyapunov_estimate,
    periodic_attractor,
    section_run,
    start_state,
)
from analysis.experiments.ensemble import MAX_TASKS, disorder_system, realization_seeds
from analysis.experiments.execution import run_tasks
from analysis.experiments.parameters import (
    DAMPING_RATIO,
    DEFAULT_Q0,
    FREQUENCY,
    SPIN_COUPLING,
    SPREAD,
    V0,
    WIDTH,
    WIDTH_SPREAD,
)
from analysis.experiments.store import ResultStore
from hysteresis._validation import (
    MAX_MAGNITUDE,
    bounded_work,
    finite_array,
    nonnegative_integer,
    positive_integer,
)

__all__ = ["EXPERIMENT", "realization_attractor", "realization_attractors"]

EXPERIMENT = "realization-attractors"


def realization_attractor(
    spins: int,
    coupling: float,
    seed: int,
    transient: int,
    periods: int,
    max_periods: int,
    lyapunov_periods: int = 2000,
    tolerance: float = 1e-6,
    max_period: int = 32,
    model: str = "dimers",
    width: float = WIDTH,
    spread: float = SPREAD,
    spin_coupling: float = SPIN_COUPLING,
    width_spread: float = WIDTH_SPREAD,
    damping_ratio: float = DAMPING_RATIO,
    frequency: float = FREQUENCY,
    q0: float = DEFAULT_Q0,
    v0: float = V0,
) -> dict:
    """One realization: the attractor ``(q0, v0)`` reaches (module docstring). Top-level, so
    that it runs in process pools. Returns ``kind`` and, when periodic, ``period``,
    ``multipliers`` (n × 2: re, im), ``tangent_space``, ``stable``, ``residual``,
    ``transient``; when aperiodic, ``max_exponent``, ``max_exponent_error``, ``kaplan_yorke``."""
    system = disorder_system(
        model, spins, seed, coupling, width, spread, spin_coupling, width_spread,
        damping_ratio, frequency,
    )  # fmt: skip
    run = section_run(
        system,
        start_state(system, q0, v0),
        transient,
        periods,
        max_periods=max_periods,
        tolerance=tolerance,
        max_period=max_period,
        keep_state=True,
    )
    if run.status == PERIODIC:
        orbit = periodic_attractor(system, run.final, run.period)
        mult = np.asarray(orbit["multipliers"])
        return {
            "kind": "periodic",
            "period": run.period,
            "transient": run.transient,
            "multipliers": np.column_stack([mult.real, mult.imag]),
            "max_abs_multiplier": float(np.max(np.abs(mult))),
            "tangent_space": list(orbit["tangent_space"]),
            "stable": orbit["stable"],
            "residual": orbit["residual"],
        }
    if run.status == APERIODIC:
        est = lyapunov_estimate(system, run.final, lyapunov_periods)
        chaotic = est["max_exponent"] > 2.0 * est["max_exponent_error"]
        return {
            "kind": "chaotic" if chaotic else "undecided",
            "max_exponent": est["max_exponent"],
            "max_exponent_error": est["max_exponent_error"],
            "kaplan_yorke": est["kaplan_yorke"],
            "exponents": est["exponents"],
        }
    return {"kind": "divergent"}


def realization_attractors(
    spins_list: Sequence[int],
    couplings: Sequence[float],
    realizations: int,
    base_seed: int,
    *,
    transient: int = 500,
    periods: int = 100,
    max_periods: int | None = None,
    lyapunov_periods: int = 2000,
    store: ResultStore | str | os.PathLike | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = False,
    allow_version_mismatch: bool = False,
    **task_kwargs: Any,
) -> list[dict]:
    """The attractor of every realization: records with ``spins``, ``coupling``, ``seed`` and the
    result of :func:`realization_attractor`, ordered by N, then C, then realization.

    ``transient``, ``periods``, ``max_periods`` as :func:`~analysis.dynamics.basins.basins`
    (default ``max_periods``: ``transient + periods``); ``task_kwargs`` go to every task
    (``model``, ``width``, ``spread``, ``spin_coupling``, ``width_spread``, ``damping_ratio``,
    ``frequency``, ``q0``, ``v0``, ``tolerance``, ``max_period``).
    """
    spins = [positive_integer(n, "spins", minimum=1) for n in spins_list]
    cs = finite_array(couplings, "couplings", ndim=1, max_abs=MAX_MAGNITUDE).tolist()
    realizations = positive_integer(realizations, "realizations")
    base_seed = nonnegative_integer(base_seed, "base_seed")
    transient = nonnegative_integer(transient, "transient")
    periods = positive_integer(periods, "periods", minimum=2)
    total = transient + periods if max_periods is None else max_periods
    total = positive_integer(total, "max_periods", minimum=transient + periods)
    bounded_work(len(spins) * len(cs) * realizations, "realizations", MAX_TASKS, "tasks")
    tasks = []
    for n in spins:
        for c in cs:
            for s in realization_seeds(base_seed, n, realizations):
                tasks.append(
                    dict(
                        spins=n,
                        coupling=float(c),
                        seed=s,
                        transient=transient,
                        periods=periods,
                        max_periods=total,
                        lyapunov_periods=lyapunov_periods,
                        **task_kwargs,
                    )
                )
    results = run_tasks(
        EXPERIMENT,
        tasks,
        realization_attractor,
        store=store,
        workers=workers,
        scheduler=scheduler,
        progress=progress,
        allow_version_mismatch=allow_version_mismatch,
    )
    return [
        {"spins": t["spins"], "coupling": t["coupling"], "seed": t["seed"], **r}
        for t, r in zip(tasks, results, strict=True)
    ]
