"""The output context shared by the figure builders of ``hyst paper`` (the run sizes live in
:mod:`analysis.experiments.parameters`)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from analysis._json import to_json
from analysis.experiments.execution import run_tasks
from analysis.experiments.parameters import SIZES, RunSize

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

        # strict JSON: non-finite numbers as "inf"/"-inf"/"nan", as the CLI's --json
        path.write_text(to_json(payload, indent=2))
        return path

    @property
    def task_workers(self) -> int | None:
        """Workers for task sweeps: smoke tasks take milliseconds, so they run in this process
        (a process pool, and loading the numba caches in every worker, would cost more)."""
        return 1 if self.workers is None and self.size.name == "smoke" else self.workers

    def run(self, experiment: str, tasks: list[dict], func: Callable[..., Any]) -> list[dict]:
        """Run independent tasks through :func:`analysis.experiments.execution.run_tasks` with
        this run's results store, workers and scheduler (parallel, and resumable on a rerun)."""

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
