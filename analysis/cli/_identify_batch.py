"""``hyst identify --input DIR`` (or several files): the batch loop, its progress and its
summary (``summary.csv``, ``summary.json``). One file is identified by
:func:`analysis.cli.identify._one_file` (passed in, a module-level function so that worker
processes can run it); a file that fails is recorded and the batch goes on.
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

from analysis.cli._output import emit, prepare_out, progress_enabled, to_json
from analysis.cli._parsing import CliError
from analysis.identification.forc_io import find_forc_files

__all__ = ["SUMMARY_COLUMNS", "forc_input_files", "input_files", "run_batch"]

#: columns of summary.csv
SUMMARY_COLUMNS = (
    "file",
    "status",
    "format",
    "n_curves",
    "peak_bc_mT",
    "peak_bu_mT",
    "peak_bc_lo_mT",
    "peak_bc_hi_mT",
    "peak_bu_lo_mT",
    "peak_bu_hi_mT",
    "peak_rho",
    "peak_rho_se",
    "rho_unit",
    "irreversible_mass",
    "irreversible_mass_se",
    "irreversible_mass_bcbu",
    "mass_unit",
    "ms",
    "mrs",
    "bc_mT",
    "bcr_mT",
    "smoothing",
    "warnings",
)


def input_files(paths: list[Path]) -> list[Path]:
    """The files of ``--input``: files as given, directories by their regular, non-hidden
    files (sorted, not recursive); one-line errors naming the option."""
    files: list[Path] = []
    for path in paths:
        if path.is_dir():
            found = sorted(p for p in path.iterdir() if p.is_file() and not p.name.startswith("."))
            if not found:
                raise CliError(f"argument --input: {path}: a directory without files")
            files += found
        elif not path.exists():
            raise CliError(f"argument --input: {path}: no such file")
        else:
            files.append(path)
    return files


def forc_input_files(paths: list[Path]) -> tuple[list[Path], list[tuple[Path, str]]]:
    """The files of ``--input`` with directories searched recursively for FORC files by content
    (:func:`~analysis.identification.forc_io.find_forc_files`): ``(files, skipped)``, files as
    given first in order, the skipped files of the directories with a one-line reason each.
    One-line errors naming the option (no such file, a directory without FORC files)."""
    files: list[Path] = []
    skipped: list[tuple[Path, str]] = []
    for path in paths:
        if path.is_dir():
            found, passed = find_forc_files(path)
            if not found:
                why = f"; {passed[0][0].name}: {passed[0][1]}" if passed else ""
                raise CliError(
                    f"argument --input: {path}: no FORC file in the directory ({len(passed)} "
                    f"files skipped{why})"
                )
            files += found
            skipped += passed
        elif not path.exists():
            raise CliError(f"argument --input: {path}: no such file")
        else:
            files.append(path)
    return files, skipped


#: the summary's precision: a value with a standard error to the decade of the error's second
#: significant digit, a field in mT to :data:`FIELD_DECIMALS` decimals (0.01 mT, below any
#: instrument's field step), any other number to :data:`SIGNIFICANT_DIGITS` digits
FIELD_DECIMALS = 2
SIGNIFICANT_DIGITS = 4


def rounded(value: Any, se: Any = None, decimals: int | None = None) -> Any:
    """``value`` rounded for the summary (:data:`FIELD_DECIMALS`, :data:`SIGNIFICANT_DIGITS`);
    blanks and non-numbers pass through."""
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
        return value
    if decimals is not None:
        return round(float(value), decimals)
    if isinstance(se, (int, float)) and math.isfinite(se) and se > 0:
        return round(float(value), 1 - int(math.floor(math.log10(se))))
    if value == 0:
        return 0.0
    return float(f"{value:.{SIGNIFICANT_DIGITS}g}")


def _summary_row(rep: dict[str, Any]) -> dict[str, Any]:
    def pair(key: str, k: int) -> Any:
        v = rep.get(key)
        return v[k] if v else ""

    if rep.get("smoothing_method") == "variforc":
        smoothing = "variforc sc={sc0:g}/{sc1:g} sb={sb0:g}/{sb1:g} lambda={lam:g}".format(
            **rep["variforc"]
        )
        if rep.get("smoothing_choice"):
            smoothing += " (auto)"
    elif rep.get("smoothing_factor"):
        smoothing = "SF={:g}/{:g}".format(*rep["smoothing_factor"])
    else:
        smoothing = ""
    # the report's own warnings (identify.json "warnings": an aborted run's coverage, a
    # negative mass) first; then the reader's notes they do not already quote
    warnings = list(rep.get("warnings", []))
    quoted = " ".join(warnings)
    warnings += [n for n in rep.get("notes", []) if n not in quoted]
    if rep.get("complete") is False and not warnings:
        warnings.append("incomplete measurement")
    if rep.get("error"):
        warnings.append(rep["error"])
    hyst = rep.get("hysteresis") or {}
    mass_se, rho_se = rep.get("irreversible_mass_se"), rep.get("peak_rho_se")
    f = FIELD_DECIMALS
    return {
        "file": rep["input"],
        "status": rep["status"],
        "format": rep.get("format", ""),
        "n_curves": rep.get("n_curves", ""),
        "peak_bc_mT": rounded(rep.get("peak_bc_mT", ""), decimals=f),
        "peak_bu_mT": rounded(rep.get("peak_bu_mT", ""), decimals=f),
        "peak_bc_lo_mT": rounded(pair("peak_bc_interval_mT", 0), decimals=f),
        "peak_bc_hi_mT": rounded(pair("peak_bc_interval_mT", 1), decimals=f),
        "peak_bu_lo_mT": rounded(pair("peak_bu_interval_mT", 0), decimals=f),
        "peak_bu_hi_mT": rounded(pair("peak_bu_interval_mT", 1), decimals=f),
        "peak_rho": rounded(rep.get("peak_rho", ""), rho_se),
        "peak_rho_se": rounded(rho_se if rho_se is not None else ""),
        "rho_unit": rep.get("rho_unit", ""),
        "irreversible_mass": rounded(rep.get("irreversible_mass", ""), mass_se),
        "irreversible_mass_se": rounded(mass_se if mass_se is not None else ""),
        "irreversible_mass_bcbu": rounded(
            rep.get("irreversible_mass_bcbu", ""), None if mass_se is None else 0.5 * mass_se
        ),
        "mass_unit": rep.get("mass_unit", ""),
        "ms": rounded(hyst.get("ms", "")),
        "mrs": rounded(hyst.get("mrs", "")),
        "bc_mT": rounded(hyst.get("bc_mT", ""), decimals=f),
        "bcr_mT": rounded(hyst.get("bcr_mT", ""), decimals=f),
        "smoothing": smoothing,
        "warnings": "; ".join(warnings),
    }


def run_batch(
    args: argparse.Namespace,
    files: list[Path],
    one_file: Callable[..., dict[str, Any]],
    skipped: list[tuple[Path, str]] | None = None,
) -> int:
    """Every file into ``OUT/<stem>/``, progress on stderr, ``summary.csv`` and
    ``summary.json``; a file that fails is recorded and the batch goes on (exit status 2 and one
    line at the end if any failed). ``skipped`` (from :func:`forc_input_files`): files of the
    directories that are no FORC files, listed as rows of status ``skipped`` (the reason in
    ``warnings``) and under ``skipped`` in ``summary.json``; they do not fail the batch."""
    out = prepare_out(args)
    stems: dict[str, int] = {}
    targets = []
    for path in files:
        stem = path.stem.replace(".", "_") or "file"
        stems[stem] = stems.get(stem, 0) + 1
        targets.append(out / (stem if stems[stem] == 1 else f"{stem}_{stems[stem]}"))
    show = progress_enabled(args)
    t0 = time.perf_counter()
    reports: list[dict[str, Any]] = []
    if args.workers == 1:
        results = (one_file(args, p, o) for p, o in zip(files, targets, strict=True))
        for k, rep in enumerate(results, 1):
            reports.append(rep)
            if show:
                print(f"[{k}/{len(files)}] {rep['input']}: {rep['status']}", file=sys.stderr)
    else:
        with ProcessPoolExecutor(max_workers=args.workers) as pool:
            futures = [
                pool.submit(one_file, args, p, o) for p, o in zip(files, targets, strict=True)
            ]
            for k, fut in enumerate(futures, 1):
                rep = fut.result()
                reports.append(rep)
                if show:
                    print(f"[{k}/{len(files)}] {rep['input']}: {rep['status']}", file=sys.stderr)
    rows = [_summary_row(r) for r in reports]
    skips = [{"file": str(p), "reason": why} for p, why in skipped or []]
    rows += [{"file": k["file"], "status": "skipped", "warnings": k["reason"]} for k in skips]
    with open(out / "summary.csv", "w", newline="", encoding="utf-8") as fh:
        writer = csv.DictWriter(fh, fieldnames=SUMMARY_COLUMNS, restval="")
        writer.writeheader()
        writer.writerows(rows)
    failed = [r for r in reports if r["status"] != "ok"]
    summary = {
        "n_files": len(files),
        "n_failed": len(failed),
        "workers": args.workers,
        "seconds": time.perf_counter() - t0,
        "files": rows,
        "reports": reports,
    }
    if skipped is not None:
        summary["n_skipped"] = len(skips)
        summary["skipped"] = skips
    (out / "summary.json").write_text(to_json(summary, indent=2) + "\n")
    lines = [
        f"{len(files)} files, {len(files) - len(failed)} identified, {len(failed)} failed"
        + (f"; {len(skips)} files skipped (no FORC file)" if skips else ""),
        f"wrote {out / 'summary.csv'}, {out / 'summary.json'} and one folder per file",
    ]
    emit(args, summary, lines)
    if failed:
        raise CliError(
            f"argument --input: {len(failed)} of {len(files)} files failed (first: "
            f"{failed[0]['error']}); see {out / 'summary.json'}"
        )
    return 0
