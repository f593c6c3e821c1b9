"""The iid-input reference of the paper (fig:mag(b), fig:mag_his bottom row).

The spin-dimer ensemble *without* dynamic feedback is driven by an external field that is an
independent and identically distributed sequence, ``u_k ~ N(0, σ²)``. For each disorder
realization ``SpinDimerEnsemble.random(N, width=p, spread=R, spin_coupling=J, seed)`` the
time-averaged magnetization

    M_T = (1/T) Σ_{k=1..T} M(u_k)          (= (1/N) Σ_i <σ_i>_time)

is recorded. The dimers are independent given the input, so ``M_T`` is a mean of N/2 independent
dimer averages and ``VAR[M] = mean(M_T²) − mean(M_T)²`` over realizations decays as ``N^-1``
(central limit theorem) — the reference against which the paper shows that the coupled
oscillator's magnetization does not self-average.

Input noise: by default (``common_input=True``) all realizations see the *same* input sequence,
so ``VAR[M]`` measures the disorder only and scales as ``1/N`` exactly in expectation. With
``common_input=False`` each realization draws its own input, which adds a variance ``∝ 1/T``
from the finite time average, independent of N (a floor at large N).

Default field scale ``σ = input_std = 2``: comparable to the spread of the switching fields
``α, β = s ± p/2`` with ``s ~ N(0, 1)`` and ``p = 2`` (std ≈ 1.4), so that most dimers switch
often. The paper does not state its σ.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from analysis.dynamics.statistics import PowerLawFit, magnetization_variance, power_law_fit
from analysis.experiments.execution import run_tasks, spawn_seeds
from analysis.experiments.models import build_operator
from analysis.experiments.parameters import SPIN_COUPLING, SPREAD, WIDTH
from analysis.experiments.store import ResultStore
from hysteresis._validation import (
    MAX_MAGNITUDE,
    bounded_work,
    nonnegative_integer,
    positive_integer,
    positive_scalar,
    scalar_in_open_interval,
)
from hysteresis.spin_dimers import MAX_SPINS

__all__ = [
    "iid_inputs",
    "iid_task",
    "iid_magnetization",
    "iid_tasks",
    "iid_variance_scaling",
    "IidScaling",
    "DEFAULT_INPUT_STD",
]

DEFAULT_INPUT_STD = 2.0
#: disorder of the paper (Table I): loop width p, centre spread R, spin coupling J


#: longest input sequence of one realization (8 bytes per step)
MAX_STEPS = 500_000_000
#: keyword arguments of :func:`iid_magnetization` that say how to run, not what
_RUN_OPTIONS = ("store", "workers", "scheduler", "progress", "allow_version_mismatch")


def iid_inputs(n_steps: int, input_std: float, seed: int) -> np.ndarray:
    """The iid field sequence ``u_k ~ N(0, input_std²)``, k = 1..n_steps."""

    n_steps = positive_integer(n_steps, "n_steps")
    bounded_work(n_steps, "n_steps", MAX_STEPS, "input steps")
    input_std = positive_scalar(input_std, "input_std", MAX_MAGNITUDE)
    seed = nonnegative_integer(seed, "seed")
    return np.random.default_rng(seed).normal(0.0, input_std, size=n_steps)


def iid_task(
    spins: int,
    n_steps: int,
    seed: int,
    input_seed: int,
    input_std: float = DEFAULT_INPUT_STD,
    width: float = WIDTH,
    spread: float = SPREAD,
    spin_coupling: float = SPIN_COUPLING,
    transient_steps: int = 0,
) -> dict:
    """One realization: ``M_T`` of the registry's ``dimers`` (``SpinDimerEnsemble.random(spins,
    width, spread, spin_coupling, seed)``) driven by ``iid_inputs(transient_steps + n_steps,
    input_std, input_seed)``.

    The spins start all down and relax at the first input (``initial_state(u_0)``); the first
    ``transient_steps`` outputs are not averaged. Top-level, so it runs in process pools.

    The paper's dimers have equal loop widths, so their relays nest
    (:meth:`~hysteresis.relay_table.RelayTable.nested_plan`) and are driven in O(log N) per
    input (:meth:`~hysteresis.relay_table.NestedPlan.drive`) instead of the general Preisach
    kernel's O(relays switched) — O(N) per iid input. Without a nested plan (thresholds that
    do not nest) the task falls back to ``ensemble.apply``.
    """

    n_steps = positive_integer(n_steps, "n_steps")
    transient_steps = nonnegative_integer(transient_steps, "transient_steps")
    ensemble = build_operator(
        "dimers", spins=spins, seed=seed, width=width, spread=spread, spin_coupling=spin_coupling
    )
    u = iid_inputs(n_steps + transient_steps, input_std, input_seed)
    plan = ensemble.relay_table().nested_plan()
    if plan is None:
        outputs, _ = ensemble.apply(u, ensemble.initial_state(float(u[0])))
    else:
        # index_at(u_0): the relays with alpha <= u_0 up, the start of initial_state(u_0)
        outputs, _ = plan.drive(u, plan.index_at(float(u[0])))
    outputs = np.asarray(outputs, dtype=float)[transient_steps:]
    return {"magnetization": float(outputs.mean())}


def iid_tasks(
    n_spins: int,
    n_steps: int,
    realizations: int,
    seed: int,
    *,
    input_std: float = DEFAULT_INPUT_STD,
    common_input: bool = True,
    transient_steps: int = 0,
    width: float = WIDTH,
    spread: float = SPREAD,
    spin_coupling: float = SPIN_COUPLING,
) -> list[dict]:
    """The :func:`iid_task` parameter dicts of :func:`iid_magnetization` (every argument checked
    here, before a task reaches a worker process).

    Disorder seeds are ``spawn_seeds(seed, realizations)``; the input seed is derived from
    ``seed`` too (one shared sequence if ``common_input``, else one per realization), so the
    tasks are reproducible from ``seed`` alone.
    """
    n_spins = positive_integer(n_spins, "n_spins", minimum=2)
    if n_spins % 2:
        raise ValueError(f"n_spins must be even (the spins come in dimers), got {n_spins}")
    bounded_work(n_spins, "n_spins", MAX_SPINS, "spins")
    n_steps = positive_integer(n_steps, "n_steps")
    transient_steps = nonnegative_integer(transient_steps, "transient_steps")
    bounded_work(n_steps + transient_steps, "n_steps", MAX_STEPS, "input steps")
    realizations = positive_integer(realizations, "realizations")
    bounded_work(realizations, "realizations", 1_000_000, "realizations")
    seed = nonnegative_integer(seed, "seed")
    input_std = positive_scalar(input_std, "input_std", MAX_MAGNITUDE)
    spin_coupling = positive_scalar(spin_coupling, "spin_coupling", MAX_MAGNITUDE)
    width = scalar_in_open_interval(width, "width", 0.0, 2.0 * spin_coupling)
    spread = positive_scalar(spread, "spread", MAX_MAGNITUDE)
    disorder_seeds = spawn_seeds(seed, realizations)
    # a separate branch of the seed tree for the inputs: never equal to a disorder seed stream
    input_base = int(np.random.SeedSequence([int(seed), 1]).generate_state(1, np.uint64)[0] >> 1)
    input_seeds = spawn_seeds(input_base, realizations)
    if common_input:
        input_seeds = [input_seeds[0]] * realizations
    return [
        dict(
            spins=int(n_spins),
            n_steps=int(n_steps),
            seed=s,
            input_seed=i,
            input_std=float(input_std),
            width=float(width),
            spread=float(spread),
            spin_coupling=float(spin_coupling),
            transient_steps=int(transient_steps),
        )
        for s, i in zip(disorder_seeds, input_seeds, strict=True)
    ]


def _run_iid(
    tasks: list[dict],
    store: ResultStore | str | os.PathLike | None,
    workers: int | None,
    scheduler: str | None,
    progress: bool,
    allow_version_mismatch: bool,
) -> np.ndarray:
    results = run_tasks(
        "iid",
        tasks,
        iid_task,
        store=store,
        workers=workers,
        scheduler=scheduler,
        progress=progress,
        allow_version_mismatch=allow_version_mismatch,
    )
    return np.array([r["magnetization"] for r in results])


def iid_magnetization(
    n_spins: int,
    n_steps: int,
    realizations: int,
    seed: int,
    *,
    input_std: float = DEFAULT_INPUT_STD,
    common_input: bool = True,
    transient_steps: int = 0,
    width: float = WIDTH,
    spread: float = SPREAD,
    spin_coupling: float = SPIN_COUPLING,
    store: ResultStore | str | os.PathLike | None = None,
    workers: int | None = 1,
    scheduler: str | None = None,
    progress: bool = False,
    allow_version_mismatch: bool = False,
) -> np.ndarray:
    """Time-averaged magnetization ``M_T`` for ``realizations`` disorder realizations.

    The tasks are :func:`iid_tasks` (seeds and input modes there); they go through
    :func:`run_tasks` (store, workers, scheduler, allow_version_mismatch as there; experiment
    name ``"iid"``).
    """
    tasks = iid_tasks(
        n_spins,
        n_steps,
        realizations,
        seed,
        input_std=input_std,
        common_input=common_input,
        transient_steps=transient_steps,
        width=width,
        spread=spread,
        spin_coupling=spin_coupling,
    )
    return _run_iid(tasks, store, workers, scheduler, progress, allow_version_mismatch)


def _seed_for(seed: int, n_spins: int) -> int:
    return int(np.random.SeedSequence([int(seed), n_spins]).generate_state(1, np.uint64)[0] >> 1)


@dataclass(frozen=True)
class IidScaling:
    """``VAR[M]`` per number of spins, its bootstrap-free standard error, and the power law."""

    spins: np.ndarray
    variance: np.ndarray
    variance_stderr: np.ndarray
    magnetizations: tuple[np.ndarray, ...]
    fit: PowerLawFit


def iid_variance_scaling(
    spins: Sequence[int],
    n_steps: int,
    realizations: int,
    seed: int,
    **kwargs,
) -> IidScaling:
    """``VAR[M]`` over realizations for each N in ``spins`` and the fit ``VAR[M] ∝ N^b``.

    The standard error of a sample variance is estimated as ``VAR·sqrt(2/(K−1))`` (normal
    approximation), and the log-log fit is weighted with it. Keyword arguments are those of
    :func:`iid_magnetization`. Each N gets its own base seed ``SeedSequence([seed, N])``, so
    the ensembles of different N are independent (not nested subsets of one another). The
    tasks of every N run in one :func:`run_tasks` call (one worker pool instead of one per N).
    """
    n = np.asarray(spins, dtype=int)
    run = {k: kwargs.pop(k) for k in _RUN_OPTIONS if k in kwargs}
    per_n = [iid_tasks(int(k), n_steps, realizations, _seed_for(seed, int(k)), **kwargs) for k in n]
    # one run_tasks call for every N: one worker pool, no barrier between the sizes (the same
    # tasks, so the same results and store keys as one iid_magnetization call per N)
    flat = _run_iid(
        [t for tasks in per_n for t in tasks],
        run.get("store"),
        run.get("workers", 1),
        run.get("scheduler"),
        run.get("progress", False),
        run.get("allow_version_mismatch", False),
    )
    bounds = np.cumsum([0] + [len(tasks) for tasks in per_n])
    mags = tuple(flat[a:b] for a, b in zip(bounds[:-1], bounds[1:], strict=True))
    var = np.array([magnetization_variance(m) for m in mags])
    err = var * np.sqrt(2.0 / max(realizations - 1, 1))
    fit = power_law_fit(n.astype(float), var, sigma_y=err)
    return IidScaling(spins=n, variance=var, variance_stderr=err, magnetizations=mags, fit=fit)
