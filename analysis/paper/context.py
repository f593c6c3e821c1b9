"""Run sizes and the output context shared by the figure builders of ``hyst paper``."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "AGREE",
    "DISAGREE",
    "INCONCLUSIVE",
    "VERDICTS",
    "RunSize",
    "SIZES",
    "Claim",
    "FigureSpec",
    "PaperContext",
    "decide",
    "reading",
    "verdict",
]

AGREE = "agree"
DISAGREE = "disagree"
#: the evidence of this run cannot decide the claim (too few realizations, too small N, a
#: confidence interval straddling the criterion, a grid coarser than the tolerance, ...)
INCONCLUSIVE = "inconclusive at this run size"
VERDICTS = (AGREE, DISAGREE, INCONCLUSIVE)


@dataclass(frozen=True)
class RunSize:
    """Every knob that sets how long the reproduction runs.

    ``full`` is the paper's scale; ``quick`` takes about five minutes on two cores; ``smoke``
    only checks that every figure and claim is produced.
    """

    name: str
    # fig:bif_0 (N = 2, b = (1, -1)): couplings stepped downward
    bif0_couplings: int = 200
    bif0_c_range: tuple[float, float] = (0.5, 10.0)
    bif0_periods: int = 60
    bif0_transient: int = 200
    bif0_lyapunov_t: float = 2000.0
    # fig:bif (N = 20 000 vs the erf-play limit)
    bif_spins: int = 20000
    bif_couplings: int = 301
    bif_c_range: tuple[float, float] = (1.5, 4.5)
    bif_periods: int = 60
    bif_transient: int = 100
    bif_lyapunov_t: float = 2000.0
    # attractors and single-system Lyapunov runs
    attractor_periods: int = 2000
    dky_t_end: float = 2.0e4
    dky_transient: float = 1.0e3
    # fig:mboa: initial conditions per panel
    mboa_points: int = 40
    # disorder ensembles (fig:dim, fig:sap, fig:mag, fig:mag_his)
    ensemble_spins: tuple[int, ...] = (100, 500, 1000, 5000, 10000, 15000, 20000)
    ensemble_realizations: int = 500
    ensemble_t_end: float = 2.0e4
    ensemble_transient: float = 1.0e3
    # iid-input reference
    iid_spins: tuple[int, ...] = (100, 300, 1000, 3000, 10000, 20000)
    iid_realizations: int = 500
    iid_steps: int = 10000
    # fig:preis_dens
    identification_spins: int = 20000
    identification_step: float = 0.1
    extra: dict = field(default_factory=dict)


_FULL = RunSize(name="full")
_QUICK = replace(
    _FULL,
    name="quick",
    bif0_couplings=200,
    bif0_periods=40,
    bif0_transient=100,
    bif0_lyapunov_t=500.0,
    bif_spins=20000,
    bif_couplings=61,
    bif_periods=40,
    bif_transient=60,
    bif_lyapunov_t=3000.0,
    attractor_periods=1000,
    dky_t_end=2.0e4,
    dky_transient=1.0e3,
    mboa_points=12,
    # t_end >= 5000: fewer than ~700 section points leave box counting no scaling region
    ensemble_spins=(100, 1000, 5000, 20000),
    ensemble_realizations=100,
    ensemble_t_end=1.0e4,
    ensemble_transient=500.0,
    iid_spins=(100, 300, 1000, 3000, 10000),
    iid_realizations=200,
    iid_steps=5000,
    identification_spins=20000,
    identification_step=0.1,
)
_SMOKE = replace(
    _QUICK,
    name="smoke",
    bif0_couplings=6,
    bif0_periods=10,
    bif0_transient=10,
    bif0_lyapunov_t=50.0,
    bif_spins=400,
    bif_couplings=3,
    bif_periods=8,
    bif_transient=5,
    bif_lyapunov_t=40.0,
    attractor_periods=30,
    dky_t_end=200.0,
    dky_transient=20.0,
    mboa_points=2,
    ensemble_spins=(20, 60),
    ensemble_realizations=3,
    ensemble_t_end=100.0,
    ensemble_transient=10.0,
    iid_spins=(20, 60, 200),
    iid_realizations=20,
    iid_steps=200,
    identification_spins=400,
    identification_step=0.25,
)

SIZES: dict[str, RunSize] = {s.name: s for s in (_SMOKE, _QUICK, _FULL)}


@dataclass(frozen=True)
class Claim:
    """One quantitative statement of the paper next to what this run measured.

    ``verdict`` is one of :data:`VERDICTS`: ``"agree"``, ``"disagree"`` or ``"inconclusive at
    this run size"`` (the criterion stays the paper's; the run's own numbers say it cannot be
    decided at this size). ``evidence`` says what was checked (run length, initial conditions,
    realizations, convergence with N, the decisive statistic and its uncertainty), built from the
    run's numbers; ``explanation`` is the reading (physics) of a claim that does not agree, empty
    for one that does. The report's discussion prints both for every claim that does not agree.
    """

    claim: str
    paper: str
    measured: str
    run: str
    verdict: str  # one of VERDICTS
    figure: str = ""
    evidence: str = ""
    explanation: str = ""

    def __post_init__(self) -> None:
        if self.verdict not in VERDICTS:
            choices = ", ".join(repr(v) for v in VERDICTS)
            raise ValueError(f"verdict must be one of {choices}, got {self.verdict!r}")
        for name in ("evidence", "explanation"):
            if not isinstance(getattr(self, name), str):
                raise TypeError(f"{name} must be a str, got {type(getattr(self, name)).__name__}")


@dataclass(frozen=True)
class FigureSpec:
    """One figure (or table) of the paper: its LaTeX label and the function that builds it."""

    label: str
    title: str
    build: Callable[[PaperContext], list[Claim]]


def verdict(ok: bool) -> str:
    """``"agree"`` if ``ok`` else ``"disagree"`` (a claim this run always decides)."""
    return AGREE if ok else DISAGREE


def decide(ok: bool, decidable: bool) -> str:
    """The verdict of a claim that this run may be unable to decide: ``"inconclusive at this run
    size"`` unless ``decidable``, else ``"agree"`` if ``ok`` else ``"disagree"``."""
    if not decidable:
        return INCONCLUSIVE
    return verdict(ok)


def reading(outcome: str, disagree: str = "", inconclusive: str = "", agree: str = "") -> str:
    """The explanation that goes with ``outcome`` (one of :data:`VERDICTS`): the reading of a
    disagreement, of an inconclusive result, or (usually empty) of an agreement."""
    if outcome not in VERDICTS:
        raise ValueError(f"outcome must be one of {VERDICTS}, got {outcome!r}")
    return {AGREE: agree, DISAGREE: disagree, INCONCLUSIVE: inconclusive}[outcome]


class PaperContext:
    """Where figures, data and the results store of one ``hyst paper`` run go."""

    def __init__(
        self,
        out: str | Path,
        size: RunSize,
        store: str | Path | None = None,
        workers: int | None = None,
        scheduler: str | None = None,
        progress: bool = False,
        seed: int = 0,
        allow_version_mismatch: bool = False,
    ) -> None:
        self.out = Path(out)
        self.out.mkdir(parents=True, exist_ok=True)
        self.size = size
        self.store_path = Path(store) if store is not None else self.out / "results.sqlite"
        self.workers = workers
        self.scheduler = scheduler
        self.progress = progress
        self.seed = seed
        self.allow_version_mismatch = allow_version_mismatch
        self.files: list[Path] = []
        #: results shared by several figures of this run (e.g. one ensemble for four figures)
        self.cache: dict[str, Any] = {}

    def save_figure(self, fig: Any, label: str, data: dict[str, Any]) -> list[Path]:
        """Write ``label``.png, .pdf and the data behind it as .npz (``fig:x`` -> ``fig_x``)."""
        import matplotlib.pyplot as plt

        stem = label.replace(":", "_").replace("=", "").replace("/", "_")
        paths = [self.out / f"{stem}.png", self.out / f"{stem}.pdf", self.out / f"{stem}.npz"]
        fig.savefig(paths[0], dpi=130, bbox_inches="tight")
        fig.savefig(paths[1], bbox_inches="tight")
        plt.close(fig)
        arrays = {k: np.asarray(v) for k, v in data.items()}
        np.savez_compressed(paths[2], **arrays)
        self.files.extend(paths)
        return paths

    def write_json(self, name: str, payload: Any) -> Path:
        path = self.out / name
        from analysis._json import to_json

        # strict JSON: non-finite numbers as "inf"/"-inf"/"nan", as the CLI's --json
        path.write_text(to_json(payload, indent=2))
        return path

    @property
    def task_workers(self) -> int | None:
        """Workers for task sweeps: smoke tasks take milliseconds, so they run in this process
        (a process pool, and loading the numba caches in every worker, would cost more)."""
        return 1 if self.workers is None and self.size.name == "smoke" else self.workers

    def run(self, experiment: str, tasks: list[dict], func: Callable[..., Any]) -> list[dict]:
        """Run independent tasks through :func:`analysis.execution.run_tasks` with this run's
        results store, workers and scheduler (parallel, and resumable on a rerun)."""
        from analysis.execution import run_tasks

        return run_tasks(
            experiment,
            tasks,
            func,
            store=self.store_path,
            workers=self.task_workers,
            scheduler=self.scheduler,
            progress=self.progress,
            allow_version_mismatch=self.allow_version_mismatch,
        )

    def describe(self) -> dict[str, Any]:
        return asdict(self.size)
