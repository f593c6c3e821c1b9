"""Run the figure builders in order and write the report."""

from __future__ import annotations

import json
import sys
import time
import traceback
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import asdict
from pathlib import Path

from analysis.experiments.store import StoreError
from analysis.paper import figures_bifurcations as bif
from analysis.paper import figures_dynamics as dyn
from analysis.paper import figures_ensembles as ens
from analysis.paper import figures_identification as ident
from analysis.paper import figures_operators as ops
from analysis.paper.basin_evidence import basin_evidence, basin_lines
from analysis.paper.context import (
    AGREE,
    DISAGREE,
    INCONCLUSIVE,
    SIZES,
    Claim,
    FigureSpec,
    PaperContext,
)
from analysis.paper.ensemble_tasks import start_ensemble_data
from analysis.paper.orbit_evidence import orbit_evidence, orbit_lines

__all__ = [
    "FigureSpec",
    "FIGURES",
    "check_only",
    "discussion",
    "figure_labels",
    "run_paper",
    "summary_line",
    "write_report",
]


def _figures() -> list[FigureSpec]:
    return [*ops.FIGURES, *ident.FIGURES, *dyn.FIGURES, *bif.FIGURES, *ens.FIGURES]


class _LazyFigures(Sequence):
    def __getitem__(self, i):  # type: ignore[override]
        return _figures()[i]

    def __len__(self) -> int:
        return len(_figures())


FIGURES: Sequence[FigureSpec] = _LazyFigures()


def figure_labels() -> list[str]:
    """The LaTeX labels of every figure ``hyst paper`` builds, in build order."""
    return [spec.label for spec in _figures()]


def check_only(only: Sequence[str] | None) -> None:
    """``ValueError`` naming ``only`` unless every label is a known figure label."""
    if only is None:
        return
    if isinstance(only, str) or len(only) == 0:
        raise ValueError(f"only must be a non-empty list of figure labels, got {only!r}")
    labels = figure_labels()
    unknown = [x for x in only if x not in labels]
    if unknown:
        raise ValueError(
            f"only: unknown figure label(s) {', '.join(map(repr, unknown))}; "
            f"choose from {', '.join(labels)}"
        )


def _evidence(
    report: dict, errors: list, key: str, name: str, compute: Callable[[], dict], progress: bool
) -> None:
    """``report[key] = compute()``, timed; an error of the run's store is raised (as for the
    figures), any other is recorded under ``errors`` and the run goes on (evidence, not a
    figure)."""
    start = time.perf_counter()
    try:
        report[key] = compute()
    except StoreError:
        raise
    except Exception as exc:
        errors.append({"figure": key, "error": repr(exc), "traceback": traceback.format_exc()})
    if progress:
        print(
            f"[hyst paper] {name} evidence in {time.perf_counter() - start:.1f} s",
            file=sys.stderr,
            flush=True,
        )


def _all_evidence(ctx: PaperContext, report: dict, errors: list, lines: bool) -> None:
    _evidence(report, errors, "orbits", "periodic-orbit", orbit_evidence, lines)
    _evidence(report, errors, "basins", "basin", lambda: basin_evidence(ctx), lines)


def run_paper(
    out: str | Path,
    size: str = "quick",
    store: str | Path | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    only: Sequence[str] | None = None,
    progress: bool = False,
    allow_version_mismatch: bool = False,
    stage_lines: bool | None = None,
) -> dict:
    """Build every figure (or those whose label is in ``only``) and write the report.

    Returns the report dictionary ``{"claims": [...], "figures": [...], "size": ...}``. A figure
    whose builder raises is recorded with its traceback in ``errors`` and the others still run.
    Every argument is checked before any figure is built (an unknown label in ``only`` or
    ``workers < 1`` raises ``ValueError``); ``stage_lines`` prints a line per figure (its number
    of the total, its time and the time so far) and per evidence stage on stderr, ``progress``
    a progress bar per task sweep (counts, rate, ETA) — for a terminal: in a log its carriage
    returns are noise, so the command line asks for the lines alone there; ``stage_lines``
    defaults to ``progress``; both off by default. A results store that cannot be used
    (damaged, foreign, or holding results of other code versions without
    ``allow_version_mismatch``) raises :class:`~analysis.experiments.store.StoreError` for the
    whole run instead of failing figure by figure.
    """
    if size not in SIZES:
        raise ValueError(f"size must be one of {sorted(SIZES)}, got {size!r}")
    check_only(only)
    if workers is not None and (
        isinstance(workers, bool) or int(workers) != workers or workers < 1
    ):
        raise ValueError(f"workers must be an integer >= 1, got {workers!r}")
    ctx = PaperContext(
        out,
        SIZES[size],
        store=store,
        workers=workers,
        scheduler=scheduler,
        progress=progress,
        allow_version_mismatch=allow_version_mismatch,
    )
    lines = progress if stage_lines is None else bool(stage_lines)
    claims: list[Claim] = []
    figures: list[dict] = []
    errors: list[dict] = []
    selected = [spec for spec in _figures() if not only or spec.label in only]
    run_start = time.perf_counter()
    # the evidence: the periodic orbits behind the disputed windows, and the basins of the
    # coexisting attractors and the realizations' attractors (the basins' tasks in the run's
    # store: written as they complete, resumed after a kill), for the Discussion
    evidence: dict = {}
    evidence_errors: list[dict] = []
    pending_evidence = not only and size != "smoke"
    ensemble_labels = {spec.label for spec in ens.FIGURES}
    overlap = (
        ctx.scheduler is None
        and ctx.task_workers != 1
        and any(spec.label in ensemble_labels for spec in selected)
    )
    if overlap:
        # the disorder ensemble (most of a full run) starts now in the background, and the
        # evidence runs before the ensemble figures wait for it: their idle cores fill
        start_ensemble_data(ctx)
    for k, spec in enumerate(selected, 1):
        if overlap and pending_evidence and spec.label in ensemble_labels:
            _all_evidence(ctx, evidence, evidence_errors, lines)
            pending_evidence = False
        start = time.perf_counter()
        if lines:
            # every task sweep inside a figure shows its own bar (counts, rate, ETA)
            print(
                f"[hyst paper] [{k}/{len(selected)}] {spec.label}: {spec.title} ...",
                file=sys.stderr,
                flush=True,
            )
        try:
            new = spec.build(ctx)
        except StoreError:  # the run's store, not this figure: every figure would fail
            raise
        except Exception as exc:  # keep going: one failing figure must not hide the others
            errors.append(
                {"figure": spec.label, "error": repr(exc), "traceback": traceback.format_exc()}
            )
            if lines:
                print(f"[hyst paper] {spec.label} FAILED: {exc!r}", file=sys.stderr, flush=True)
            continue
        for c in new:
            claims.append(c if c.figure else Claim(**{**asdict(c), "figure": spec.label}))
        seconds = time.perf_counter() - start
        figures.append({"label": spec.label, "title": spec.title, "seconds": round(seconds, 2)})
        if lines:
            total = time.perf_counter() - run_start
            print(
                f"[hyst paper] [{k}/{len(selected)}] {spec.label} done in {seconds:.1f} s "
                f"({total / 60:.1f} min so far)",
                file=sys.stderr,
                flush=True,
            )
    report = {
        "size": ctx.describe(),
        "claims": [asdict(c) for c in claims],
        "figures": figures,
        "errors": errors,
    }
    if pending_evidence:
        _all_evidence(ctx, evidence, evidence_errors, lines)
    report.update(evidence)  # after the figures in the report, wherever it was computed
    errors.extend(evidence_errors)
    write_report(ctx, report)
    return report


def summary_line(claims: Sequence[dict]) -> str:
    """``"k of n claims agree, d disagree, i inconclusive at this run size"``."""
    count = Counter(c["verdict"] for c in claims)
    return (
        f"{count[AGREE]} of {len(claims)} claims agree, {count[DISAGREE]} disagree, "
        f"{count[INCONCLUSIVE]} {INCONCLUSIVE}"
    )


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def discussion(claims: Sequence[dict]) -> list[str]:
    """Markdown lines of the report's "Discussion": one subsection per claim that does not
    agree (disagreements first, then inconclusive claims, each in report order) with the
    claim, the paper's statement, the measurement, the evidence and the reading."""
    lines = ["## Discussion", ""]
    open_claims = [c for c in claims if c.get("verdict") == DISAGREE] + [
        c for c in claims if c.get("verdict") == INCONCLUSIVE
    ]
    if not open_claims:
        return [*lines, "Every claim of this run agrees.", ""]
    lines += [
        "Every claim that does not agree, with what this run checked (evidence) and how we read "
        "it. *Inconclusive at this run size* means the run's own uncertainty (realizations, "
        "largest N, grid step, run length) straddles the claim's criterion; the criterion is "
        "the same as for the verdicts above.",
        "",
    ]
    for number, c in enumerate(open_claims, start=1):
        figure = f"`{c['figure']}`: " if c.get("figure") else ""
        lines += [
            f"### {number}. {figure}{_one_line(c['claim'])} — {c['verdict']}",
            "",
            f"- **Paper:** {_one_line(c['paper'])}",
            f"- **Measured:** {_one_line(c['measured'])}",
            f"- **Run:** {_one_line(c['run'])}",
            "- **Evidence:** "
            + (_one_line(c.get("evidence") or "") or "none recorded beyond the measurement"),
            "- **Reading:** "
            + (_one_line(c.get("explanation") or "") or "no explanation established yet."),
            "",
        ]
    return lines


def write_report(ctx: PaperContext, report: dict) -> None:
    """Write ``report.json`` (the report dictionary, to which it adds ``summary``: the verdict
    counts and the summary line) and ``report.md``: the claims table, the summary line, a
    "Discussion" of every claim that does not agree (and, when ``report["orbits"]`` holds
    :func:`~analysis.paper.orbit_evidence.orbit_evidence`, the periodic orbits behind the
    disputed windows; when ``report["basins"]`` holds
    :func:`~analysis.paper.basin_evidence.basin_evidence`, the basins and the realizations'
    attractors), failed figures, the figures and the run size. Optional ``provenance``
    lines (how and when the run was made) are printed under the title."""
    count = Counter(c["verdict"] for c in report["claims"])
    report["summary"] = {
        "claims": len(report["claims"]),
        "agree": count[AGREE],
        "disagree": count[DISAGREE],
        "inconclusive": count[INCONCLUSIVE],
        "line": summary_line(report["claims"]),
    }
    ctx.write_json("report.json", report)
    lines = [
        "# Reproduction report",
        "",
        f"Run size: `{report['size']['name']}` (all knobs at the end of this file).",
        "",
        *report.get("provenance", []),
        *([""] if report.get("provenance") else []),
        "| figure | claim | paper | measured | run | verdict |",
        "|---|---|---|---|---|---|",
    ]
    for c in report["claims"]:
        cells = [c["figure"], c["claim"], c["paper"], c["measured"], c["run"], c["verdict"]]
        lines.append("| " + " | ".join(str(x).replace("|", "\\|") for x in cells) + " |")
    lines += ["", summary_line(report["claims"]) + ".", ""]
    lines += discussion(report["claims"])
    if report.get("orbits"):
        lines += orbit_lines(report["orbits"])
    if report.get("basins"):
        lines += basin_lines(report["basins"])
    if report["errors"]:
        lines += ["## Figures that failed", ""]
        for e in report["errors"]:
            lines += [f"- `{e['figure']}`: {e['error']}"]
        lines.append("")
    lines += ["## Figures", ""]
    for f in report["figures"]:
        stem = f["label"].replace(":", "_").replace("=", "").replace("/", "_")
        picture = f": ![{f['label']}]({stem}.png)" if (ctx.out / f"{stem}.png").exists() else ""
        lines.append(f"- `{f['label']}` — {f['title']} ({f['seconds']} s){picture}")
    lines += ["", "## Run size", "", "```json", json.dumps(report["size"], indent=2), "```", ""]
    (ctx.out / "report.md").write_text("\n".join(lines))
