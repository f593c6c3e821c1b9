"""Run the figure builders in order and write the report."""

from __future__ import annotations

import json
import sys
import time
import traceback
from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path

from analysis.paper.context import SIZES, Claim, FigureSpec, PaperContext
from analysis.store import StoreError

__all__ = ["FigureSpec", "FIGURES", "check_only", "figure_labels", "run_paper", "write_report"]


def _figures() -> list[FigureSpec]:
    from analysis.paper import figures_dynamics as dyn
    from analysis.paper import figures_ensembles as ens
    from analysis.paper import figures_identification as ident
    from analysis.paper import figures_operators as ops

    return [*ops.FIGURES, *ident.FIGURES, *dyn.FIGURES, *ens.FIGURES]


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


def run_paper(
    out: str | Path,
    size: str = "quick",
    store: str | Path | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    only: Sequence[str] | None = None,
    progress: bool = False,
    allow_version_mismatch: bool = False,
) -> dict:
    """Build every figure (or those whose label is in ``only``) and write the report.

    Returns the report dictionary ``{"claims": [...], "figures": [...], "size": ...}``. A figure
    whose builder raises is recorded with its traceback in ``errors`` and the others still run.
    Every argument is checked before any figure is built (an unknown label in ``only`` or
    ``workers < 1`` raises ``ValueError``); ``progress`` prints a line per figure (its number
    of the total, its time and the time so far) and a progress bar per task sweep (counts, rate,
    ETA); off by default. A results store that cannot be used (damaged, foreign, or holding
    results of other code versions without ``allow_version_mismatch``) raises
    :class:`~analysis.store.StoreError` for the whole run instead of failing figure by figure.
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
    claims: list[Claim] = []
    figures: list[dict] = []
    errors: list[dict] = []
    selected = [spec for spec in _figures() if not only or spec.label in only]
    run_start = time.perf_counter()
    for k, spec in enumerate(selected, 1):
        start = time.perf_counter()
        if progress:
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
            if progress:
                print(f"[hyst paper] {spec.label} FAILED: {exc!r}", file=sys.stderr, flush=True)
            continue
        for c in new:
            claims.append(c if c.figure else Claim(**{**asdict(c), "figure": spec.label}))
        seconds = time.perf_counter() - start
        figures.append({"label": spec.label, "title": spec.title, "seconds": round(seconds, 2)})
        if progress:
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
    write_report(ctx, report)
    return report


def write_report(ctx: PaperContext, report: dict) -> None:
    ctx.write_json("report.json", report)
    lines = [
        "# Reproduction report",
        "",
        f"Run size: `{report['size']['name']}` (all knobs at the end of this file).",
        "",
        "| figure | claim | paper | measured | run | verdict |",
        "|---|---|---|---|---|---|",
    ]
    for c in report["claims"]:
        cells = [c["figure"], c["claim"], c["paper"], c["measured"], c["run"], c["verdict"]]
        lines.append("| " + " | ".join(str(x).replace("|", "\\|") for x in cells) + " |")
    n_agree = sum(c["verdict"] == "agree" for c in report["claims"])
    lines += ["", f"{n_agree} of {len(report['claims'])} claims agree.", ""]
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
