"""Read and write first-order reversal curve (FORC) data: CSV, MicroMag and Lake Shore exports.

The readers return :class:`analysis.identification.ReversalCurves` (:func:`read_csv`,
:func:`read_forc`) or :class:`MicroMagData` (curves plus calibration points, header, units;
:func:`read_micromag`, :func:`read_lakeshore_csv`, :func:`read_forc_file` with format detection);
identify with :func:`analysis.identification.identify_from_curves`. Every reader either returns
the data set (an aborted instrument run is returned as far as it was measured, flagged
``complete=False``) or raises a one-line :class:`ValueError` naming the (1-based) line that is
wrong and what was expected: missing or inconsistent header fields, ragged rows, non-numeric
values, NaN/inf, curves that do not start at their reversal field or whose fields are not
monotone, unknown units, or an export variant that is not supported. Text is decoded as UTF-8
or else cp1252/Latin-1, never with a ``UnicodeDecodeError``.

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
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from analysis.identification.curves import ReversalCurves
from analysis.identification.forc_files.common import DATA_LINE, MicroMagData, decode
from analysis.identification.forc_files.csv_format import read_csv, write_csv
from analysis.identification.forc_files.lakeshore import read_lakeshore_csv
from analysis.identification.forc_files.micromag import read_micromag, write_micromag

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
]

FORMATS = ("auto", "csv", "micromag", "lakeshore")


def detect_format(path: str | Path) -> str:
    """``"micromag"`` (first line starts with ``MicroMag``), ``"lakeshore"`` (a column-title
    row names a field and a moment column before any data), else ``"csv"``."""
    lines = decode(path).splitlines()[:200]
    if lines and lines[0].lstrip().startswith("MicroMag"):
        return "micromag"
    for raw in lines:
        low = raw.lower()
        if "field" in low and "moment" in low and ("[" in low or "(" in low):
            return "lakeshore"
        if DATA_LINE.match(raw.strip()):
            break
    return "csv"


def read_forc_file(path: str | Path, format: str = "auto", **kwargs: Any) -> MicroMagData:
    """Read any supported FORC file into :class:`MicroMagData` (CSV files: no units)."""
    if format not in FORMATS:
        raise ValueError(f"format must be one of {FORMATS}, got {format!r}")
    if format == "auto":
        format = detect_format(path)
    if format == "csv":
        return MicroMagData(read_csv(path, **kwargs))
    if format == "micromag":
        return read_micromag(path, **kwargs)
    return read_lakeshore_csv(path, **kwargs)


def read_forc(path: str | Path, format: str = "csv", **kwargs: Any) -> ReversalCurves:
    """Read reversal curves from ``path`` in ``format`` (``"auto"``, ``"csv"``,
    ``"micromag"`` or ``"lakeshore"``)."""
    return read_forc_file(path, format, **kwargs).curves
