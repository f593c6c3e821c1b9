"""Read and write first-order reversal curve (FORC) data: CSV, MicroMag and Lake Shore exports.

The readers return :class:`analysis.identification.ReversalCurves` (:func:`read_csv`,
:func:`read_forc`) or :class:`MicroMagData` (curves plus calibration points, header, units;
:func:`read_micromag`, :func:`read_lakeshore_csv`, :func:`read_forc_file` with format detection);
identify with :func:`analysis.identification.identify_from_curves`. Every reader either returns
the data set (an aborted instrument run is returned as far as it was measured, flagged
``complete=False``) or raises a one-line :class:`ValueError` naming the (1-based) line that is
wrong and what was expected: missing or inconsistent header fields, ragged rows, non-numeric
values, NaN/inf, absurd values (beyond 1e30, or a million robust spreads from the median of the
file's fields or moments: :func:`~analysis.identification.forc_files.common.check_magnitudes`),
curves that do not start at their reversal field or whose fields are not monotone, Lake Shore
rows out of measurement order, unknown units, or an export variant that is not supported.
Text is decoded as UTF-8 or else cp1252/Latin-1 (UTF-16/UTF-32 with a byte-order mark as
such), never with a ``UnicodeDecodeError``; binary, compressed or BOM-less UTF-16 content is
refused as ``"PATH: not a text FORC file (WHAT)"``, and with format detection a text file that
is none of the formats as ``"PATH: not a FORC file this toolkit recognises; ..."``.

Irregular FORC protocols written as MicroMag "Direct moment vs. field; Multiple segments"
exports are reconstructed from their segment script by
:mod:`~analysis.identification.forc_files.segments` (format ``"segments"``, detected from
line 2); remanence FORC scripts (every point measured again at zero field) by
:mod:`~analysis.identification.forc_files.remanence`, as curves of
``kind="remanence"`` with the in-field moments in :attr:`MicroMagData.in_field_curves`. Files
that are no FORC measurement are refused in one line saying what they are not: MicroMag
hysteresis-loop and remanence-curve exports (line 2), Lake Shore exports whose field rises on
fewer than two stretches (a loop, a remanence curve), binary content and empty files.
Data-only files (two columns, a blank line after every curve or segment, no header but the
column titles and units a MicroMag data section keeps, the MicroMag end marker; ``columns=``
``"field,moment"`` or ``"moment,field"``) are read by
:mod:`~analysis.identification.forc_files.blocks` (format ``"blocks"``).
:func:`find_forc_files` searches a folder for the files :func:`detect_format` recognises.

Formats (one module each in :mod:`analysis.identification.forc_files`):
:mod:`~analysis.identification.forc_files.csv_format` (three columns
``reversal_field, field, moment``), :mod:`~analysis.identification.forc_files.micromag` (the
MicroMag 2900/3900 FORC text export, Series 0015/0016) and
:mod:`~analysis.identification.forc_files.lakeshore` (Lake Shore 8600 FORC CSV); each module
states what its reader assumes. :func:`detect_format` tells them apart.

Drift correction (``drift_correction=``): the calibration moments, measured at the same field
before every curve, sample the instrument's drift. ``"multiplicative"`` (or ``True``) scales,
``"additive"`` shifts every point to the first calibration moment, with the drift interpolated
linearly in measurement order (file position) between consecutive calibration points and held
constant after the last; the calibration field's own drift is neglected. Off by default.
Asked of a file without calibration points it is not applied, with a one-line ``UserWarning``;
the data-only and "Multiple segments" readers read calibration points but do not correct
drift, and refuse it when the file has them.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

from analysis.identification.curves import ReversalCurves
from analysis.identification.forc_files.blocks import (
    is_blocks_row,
    read_blocks,
    skip_titles,
    write_blocks,
)
from analysis.identification.forc_files.common import (
    DATA_LINE,
    END_MARK,
    DriftMode,
    MicroMagData,
    decode,
    drift_mode,
    warn_no_calibration,
)
from analysis.identification.forc_files.csv_format import read_csv, write_csv
from analysis.identification.forc_files.lakeshore import read_lakeshore_csv
from analysis.identification.forc_files.micromag import (
    check_variant,
    read_micromag,
    write_micromag,
)
from analysis.identification.forc_files.segments import (
    SEGMENTS_TITLE,
    read_segments,
    write_segments,
)
from analysis.identification.memory import check_memory, estimate_read_bytes

__all__ = [
    "read_csv",
    "write_csv",
    "read_micromag",
    "write_micromag",
    "read_lakeshore_csv",
    "MicroMagData",
    "read_forc",
    "read_forc_file",
    "detect_format",
    "find_forc_files",
    "read_blocks",
    "write_blocks",
    "read_segments",
    "write_segments",
]

FORMATS = ("auto", "csv", "micromag", "lakeshore", "blocks", "segments")
#: the formats :func:`detect_format` recognises, as its refusal names them
KNOWN_FORMATS = (
    "MicroMag 2900/3900 FORC text export (line 1 starts with 'MicroMag'), "
    "Lake Shore 8600 FORC CSV (a column-title row naming a field and a moment column with "
    "units, then data rows), three-column CSV 'reversal_field,field,moment' or a data-only "
    "file (two columns field,moment, a blank line after every curve)"
)

_UNIT_CELL = re.compile(r"[\[(][^\])]*[\])]")


def _content(lines: list[str]) -> list[str]:
    return [raw.strip() for raw in lines if raw.strip() and not raw.lstrip().startswith("#")]


def detect_format(path: str | Path) -> str:
    """``"micromag"`` (first line starts with ``MicroMag``), ``"lakeshore"`` (before any data,
    a column-title row with one cell naming a field and another naming a moment, each with a
    unit in brackets or parentheses, followed by a data row), ``"csv"`` (the first line that is
    not blank or a ``#`` comment, or the one after it, is a ``number, ...`` data row),
    ``"blocks"`` (two numbers per row, no header) or ``"segments"`` (a MicroMag "Multiple
    segments" export: irregular or remanence FORC protocols).

    An empty (or blank) file is refused as ``"PATH: an empty file (no text), not a FORC
    file"``.

    Raises a one-line ``ValueError`` for a file that is none of these (``"PATH: not a FORC
    file ..."`` naming the known formats) or not text at all (``"PATH: not a text FORC file
    (WHAT)"``, from the decoding).
    """
    text = decode(path, head=True)  # the first 64 KiB tell the format
    if not text.strip():
        text = decode(path)  # blank so far: the whole file decides
    if not text.strip():
        raise ValueError(f"{path}: an empty file (no text), not a FORC file")
    lines = text.splitlines()[:200]
    if lines and lines[0].lstrip().startswith("MicroMag"):
        if len(lines) > 1 and lines[1].strip() == SEGMENTS_TITLE:
            return "segments"
        return "micromag"
    for k, raw in enumerate(lines):
        if DATA_LINE.match(raw.strip()):
            break
        # titles with units: "Field (µ0H) [T]", "Moment (m) [A·m²]", in two different cells,
        # followed by a data row
        cells = [c.lower() for c in raw.split(",") if _UNIT_CELL.search(c)]
        fields = {i for i, c in enumerate(cells) if "field" in c}
        moments = {i for i, c in enumerate(cells) if "moment" in c}
        after = _content(lines[k + 1 :])[:1]
        if any(i != j for i in fields for j in moments) and after and DATA_LINE.match(after[0]):
            return "lakeshore"
    content = _content(lines)
    rows = [line for line in _content(lines[skip_titles(lines)[0] :]) if line != END_MARK]
    if rows and all(is_blocks_row(line) for line in rows[:50]):
        return "blocks"  # two numbers per row, no header (column titles at most): data only
    if not content or any(DATA_LINE.match(line) for line in content[:2]):
        return "csv"
    raise ValueError(f"{path}: not a FORC file this toolkit recognises; it reads {KNOWN_FORMATS}")


def find_forc_files(folder: str | Path) -> tuple[list[Path], list[tuple[Path, str]]]:
    """The files under ``folder`` (recursively) that :func:`detect_format` recognises, and the
    others with a one-line reason each: ``(recognised, skipped)``, both sorted by path.

    Recognition sniffs the content (the first 64 KiB: the title line, a column-title row, the
    first data rows), not the name; MicroMag exports of a variant the readers refuse (line 2:
    a hysteresis loop, a remanence curve) are skipped. It does not read a file through, so a
    recognised file can still be refused by its reader (an error naming its line). Hidden
    files and folders (names starting with ``.``) are not searched; symbolic links to folders
    are not followed.
    Raises a one-line ``ValueError`` if ``folder`` is not a folder."""
    folder = Path(folder)
    if not folder.is_dir():
        raise ValueError(f"{folder}: not a folder")
    recognised: list[Path] = []
    skipped: list[tuple[Path, str]] = []
    for root, dirs, files in os.walk(folder):
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        for name in sorted(files):
            path = Path(root) / name
            if name.startswith(".") or not path.is_file():
                continue
            try:
                if detect_format(path) == "micromag":  # a loop or remanence-curve export?
                    check_variant(decode(path, head=True).splitlines()[:2])
            except (ValueError, OSError) as exc:
                skipped.append((path, _reason(path, exc)))
            else:
                recognised.append(path)
    return sorted(recognised), sorted(skipped)


def _reason(path: Path, exc: Exception) -> str:
    """The one-line reason of a refusal, without the path it starts with and without the list
    of known formats."""
    if isinstance(exc, OSError):
        return f"cannot read it ({exc.strerror or exc})"
    msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    if msg.startswith(f"{path}: "):
        msg = msg[len(f"{path}: ") :]
    return msg.split("; it reads ")[0]


def read_forc_file(
    path: str | Path,
    format: str = "auto",
    max_memory: float | None = None,
    drift_correction: DriftMode = False,
    **kwargs: Any,
) -> MicroMagData:
    """Read any supported FORC file into :class:`MicroMagData` (CSV files: no units).

    ``drift_correction`` (module docstring) is applied by the MicroMag and Lake Shore readers;
    asked of a file without calibration points (any format) it is not applied and a one-line
    ``UserWarning`` says so; asked of a data-only or "Multiple segments" file that has
    calibration points it is refused (those readers do not correct drift).

    A file whose estimated reading memory (:func:`~analysis.identification.memory.
    estimate_read_bytes` of its size) exceeds ``max_memory`` bytes (default
    :func:`~analysis.identification.memory.default_max_memory`) is refused with
    :class:`~analysis.identification.memory.MemoryBoundError` before it is read."""
    check_memory(estimate_read_bytes(os.path.getsize(path)), max_memory, "reading of the file")
    if format not in FORMATS:
        raise ValueError(f"format must be one of {FORMATS}, got {format!r}")
    drift = drift_mode(drift_correction)
    if format == "auto":
        format = detect_format(path)
    if format == "micromag":
        return read_micromag(path, drift_correction=drift_correction, **kwargs)
    if format == "lakeshore":
        return read_lakeshore_csv(path, drift_correction=drift_correction, **kwargs)
    if format == "csv":
        data = MicroMagData(read_csv(path, **kwargs))
    elif format == "blocks":
        data = read_blocks(path, **kwargs)
    else:
        data = read_segments(path, **kwargs)
    if drift is not None and data.calibration_moments is not None:
        raise ValueError(
            f"drift_correction={drift!r}: not implemented for {format!r} files (their "
            f"{data.calibration_moments.size} calibration points are read but not used); "
            "pass drift_correction=False"
        )
    warn_no_calibration(path, drift, False)
    return data


def read_forc(path: str | Path, format: str = "csv", **kwargs: Any) -> ReversalCurves:
    """Read reversal curves from ``path`` in ``format`` (``"auto"``, ``"csv"``,
    ``"micromag"`` or ``"lakeshore"``)."""
    return read_forc_file(path, format, **kwargs).curves
