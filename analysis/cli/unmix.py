"""``hyst unmix``: FORC unmixing of a sample series (end-members and proportions).

The files of ``--input`` (files, and directories searched for FORC files by content) are read
and identified with one smoothing, put on a common ``(B_c, B_u)`` lattice and unmixed by
:func:`~analysis.identification.unmixing.unmix_forc`; the command writes the figures
(:mod:`analysis.identification.unmixing_plots`), ``summary.csv`` (one row per file: its
proportions and intervals, or why it was left out) and ``summary.json`` (the whole report:
the evidence for the number of end-members, the lattice, the proportions, the files left out).
A file that cannot be read is reported (progress on stderr, its row in the summary) and the
others go on.
"""

from __future__ import annotations

import argparse
import csv
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from analysis.cli._identify_batch import forc_input_files
from analysis.cli._identify_measured import add_uncertainty_options, smoothing_words
from analysis.cli._options import add_output_options
from analysis.cli._output import emit, prepare_out, progress_enabled, to_json
from analysis.cli._parsing import CliError, add_subcommand, int_at_least, library_errors
from analysis.identification.forc_io import FORMATS
from analysis.identification.plots import FORCINEL
from analysis.identification.unmixing import DEFAULT_MAX_END_MEMBERS, NORMALIZE, unmix_forc
from analysis.identification.unmixing_plots import figure_unmixing

__all__ = ["register", "run"]

#: library parameter -> the option of this command that carries it
OPTIONS = {
    "inputs": "--input",
    "n_components": "--components",
    "end_members": "--end-members",
    "normalize": "--normalize",
    "smoothing": "--smoothing",
    "n_boot": "--bootstrap",
    "max_end_members": "--max-components",
    "format": "--format",
}


def register(subparsers: Any) -> None:
    p = add_subcommand(
        subparsers,
        "unmix",
        help="unmix a series of FORC files into end-members and proportions (FORC-PCA)",
        description="Read every FORC file of --input (files, or directories searched for FORC "
        "files), identify each with one smoothing (VARIFORC by default) and its standard "
        "errors, put the diagrams on a common (Bc, Bu) lattice (the overlap of all; a file "
        "that does not overlap is left out), normalise them, and unmix them: principal "
        "components, the number of end-members from the noise (or --components), the "
        "end-members as the largest simplex of samples (or --end-members), every sample's "
        "proportions with bootstrap intervals. Writes OUT/summary.csv, OUT/summary.json and "
        "the figures (PC scores with the simplex, the end-members' FORC diagrams, the "
        "proportions as stacked bars) as PNG and PDF, and OUT/unmix.npz.",
    )
    g = p.add_argument_group("unmixing")
    g.add_argument(
        "--input",
        type=Path,
        nargs="+",
        required=True,
        metavar="PATH",
        help="FORC files and/or directories (searched recursively by content; files no reader "
        "recognises are listed as skipped)",
    )
    g.add_argument(
        "--components",
        type=int_at_least(1, 64),
        default=None,
        metavar="K",
        help="number of end-members (K - 1 principal components); default: the smallest whose "
        "residuals are consistent with the diagrams' standard errors",
    )
    g.add_argument(
        "--max-components",
        type=int_at_least(1, 64),
        default=DEFAULT_MAX_END_MEMBERS,
        metavar="K",
        help="the largest number of end-members the automatic choice considers",
    )
    g.add_argument(
        "--end-members",
        nargs="+",
        default=None,
        metavar="SAMPLE",
        help="the samples that are the end-members, by file name or by position in the input "
        "list (1-based); default: the samples spanning the largest simplex (N-FINDR)",
    )
    g.add_argument(
        "--normalize",
        choices=NORMALIZE,
        default="moment",
        help="divide each diagram by its saturation moment (moment), its irreversible mass on "
        "the common region (irreversible), the header's sample mass or volume, or nothing",
    )
    g.add_argument(
        "--smoothing",
        nargs="+",
        default=["variforc"],
        metavar="SF",
        help="smoothing of every file: 'variforc' (Egli 2013, PmagPy/FORCinel defaults), "
        "'auto', or a factor SF or two (SF_R SF_S, grid steps); files on finer grids are "
        "smoothed with half-widths scaled to the coarsest step (one smoothing in mT)",
    )
    g.add_argument(
        "--format",
        choices=FORMATS,
        default="auto",
        help="--input format (auto: detected per file)",
    )
    add_uncertainty_options(_Renamed(g))
    add_output_options(p, writes="summary.csv, summary.json, the figures and unmix.npz")
    p.set_defaults(func=run)


class _Renamed:
    """The shared ``--bootstrap``/``--bootstrap-seed``/``--cmap`` options with this command's
    help (``hyst identify``'s speak of the peak); ``--uncertainty`` is not offered (always)."""

    def __init__(self, group: Any) -> None:
        self.group = group

    def add_argument(self, *names: str, **kwargs: Any) -> None:
        if names[0] == "--uncertainty":
            return
        if names[0] == "--bootstrap":
            kwargs["help"] = "replicates of the proportions' bootstrap (>= 20; default 200)"
        elif names[0] == "--bootstrap-seed":
            kwargs["help"] = "seed of the proportions' bootstrap (>= 0; default 0)"
        elif names[0] == "--cmap":
            kwargs["help"] = "colour map of the end-members' FORC diagrams (default: FORCinel)"
        self.group.add_argument(*names, **kwargs)


def _end_members(words: list[str] | None, files: list[Path]) -> list[int] | None:
    """``--end-members`` as input indices (0-based): file names or 1-based positions."""
    if words is None:
        return None
    names = [f.name for f in files]
    out = []
    for w in words:
        if w in names:
            if names.count(w) > 1:
                raise CliError(f"argument --end-members: {w!r} names {names.count(w)} files")
            out.append(names.index(w))
        elif w.isdigit() and 1 <= int(w) <= len(files):
            out.append(int(w) - 1)
        else:
            raise CliError(
                f"argument --end-members: {w!r} is neither a file of --input nor a position in "
                f"[1, {len(files)}]"
            )
    return out


def run(args: argparse.Namespace) -> int:
    t0 = time.perf_counter()
    files, skipped = forc_input_files(list(args.input))
    smoothing = smoothing_words(args.smoothing)
    end_members = _end_members(args.end_members, files)
    out = prepare_out(args)
    show = progress_enabled(args)

    def progress(k: int, n: int, label: str, status: str) -> None:
        if show or status != "ok":  # a failure is always said, and the batch goes on
            print(f"[{k}/{n}] {label}: {status}", file=sys.stderr, flush=True)

    notes: list[str] = []
    with warnings.catch_warnings(record=True) as caught, library_errors(OPTIONS, "--input"):
        warnings.simplefilter("always")
        result = unmix_forc(
            files,
            n_components=args.components,
            end_members=end_members,
            normalize=args.normalize,
            smoothing=smoothing,
            labels=[_label(f, files) for f in files],
            file_format=args.format,
            n_boot=200 if args.bootstrap is None else args.bootstrap,
            seed=0 if args.bootstrap_seed is None else args.bootstrap_seed,
            max_end_members=args.max_components,
            progress=progress,
        )
    for note in caught:
        text = str(note.message)
        if text not in notes:
            notes.append(text)
            print(f"hyst unmix: note: {text}", file=sys.stderr)
    paths = figure_unmixing(result, out, cmap=args.cmap or FORCINEL, title=_title(result))
    report = result.as_dict()
    report.update(
        files=[str(f) for f in files],
        skipped=[{"file": str(p), "reason": why} for p, why in skipped],
        notes=notes,
        smoothing=smoothing if isinstance(smoothing, str) else list(_pair(smoothing)),
        figures=[str(p) for p in paths],
        seconds=time.perf_counter() - t0,
    )
    _write_summary(out, result, files, skipped, report)
    m = result.n_components
    test = {row["end_members"]: row for row in result.component_test}
    row = test.get(m)
    chi2 = ""
    if row is not None and np.isfinite(row["chi2"]) and np.isfinite(row["bound"]):
        chi2 = f" (χ² {row['chi2']:.3g} <= {row['bound']:.3g})"
    elif row is not None:  # as many end-members as samples: nothing left to test
        chi2 = " (no χ² test: as many end-members as samples)"
    left_out = f"; {len(result.excluded)} left out" if result.excluded else ""
    lines = [
        f"{result.n_samples} samples on a common lattice of {int(result.mask.sum())} nodes "
        f"(step {result.step:.4g}){left_out}; {m} end-members ({result.chosen_by}){chi2}",
        f"wrote {out / 'summary.csv'}, {out / 'summary.json'} and "
        f"{', '.join(p.name for p in paths)}",
    ]
    emit(args, report, lines)
    return 0


def _label(path: Path, files: list[Path]) -> str:
    """The file name, or the path when two inputs share a name."""
    return path.name if sum(f.name == path.name for f in files) == 1 else str(path)


def _pair(smoothing: Any) -> tuple[float, float]:
    return (smoothing, smoothing) if isinstance(smoothing, float) else tuple(smoothing)


def _title(result: Any) -> str:
    return (
        f"FORC unmixing: {result.n_samples} samples, {result.n_components} end-members, "
        f"normalised by {result.normalize}"
    )


def _write_summary(
    out: Path, result: Any, files: list[Path], skipped: list[tuple[Path, str]], report: dict
) -> None:
    """``summary.csv`` (a row per file, in the order of the inputs) and ``summary.json``."""
    m = result.n_components
    columns = ["file", "status", "reason"]
    for k in range(1, m + 1):
        columns += [f"p{k}", f"p{k}_lo", f"p{k}_hi"]
    columns += ["simplex_distance", "end_member"]
    rows_by_index = {row["input_index"]: row for row in result.summary_rows()}
    vertices = (
        {result.end_member_samples[k]: k for k in range(m)} if result.end_member_samples else {}
    )
    reasons = dict(result.excluded)
    rows = []
    for k, path in enumerate(files):
        label = _label(path, files)
        if k in rows_by_index:
            row = dict(rows_by_index[k])
            row.pop("input_index")
            row.pop("sample")
            r = result.input_indices.index(k)
            row.update(file=str(path), status="ok", reason="")
            row["end_member"] = f"EM{vertices[r] + 1}" if r in vertices else ""
        else:
            row = {"file": str(path), "status": "left out", "reason": reasons.get(label, "")}
        rows.append(row)
    rows += [{"file": str(p), "status": "skipped", "reason": why} for p, why in skipped]
    with open(out / "summary.csv", "w", newline="", encoding="utf-8") as fh:
        writer = csv.DictWriter(fh, fieldnames=columns, restval="")
        writer.writeheader()
        writer.writerows(rows)
    (out / "summary.json").write_text(to_json(report, indent=2) + "\n")
