"""Data-only FORC files (:func:`read_blocks`, :func:`write_blocks`): no header, two columns.

Rows of two numbers (separated by a comma, a semicolon, tabs or spaces), one point each, in
measurement order; a blank line ends a curve (the data section of an instrument export, saved
without its header). ``columns`` says which column is which (``"field,moment"``, the default,
or ``"moment,field"``). A block of one point is a calibration point (a FORC has at least two
points; MicroMag and PMC exports measure one before every curve); every other block is a curve
whose first point is its reversal field. The convention follows the direction of the fields
(rising: Pike, falling: Mayergoyz). The units are unknown (as written); lines starting with
``#`` are comments. Errors name the line, as for every reader.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from analysis.identification.curves import ReversalCurves
from analysis.identification.forc_files.common import (
    MicroMagData,
    check_curve,
    check_magnitudes,
    decode,
    infer_convention,
    parse_float,
)

__all__ = ["read_blocks", "write_blocks", "COLUMN_LAYOUTS", "is_blocks_row"]

COLUMN_LAYOUTS = ("field,moment", "moment,field")
_SPLIT = re.compile(r"[,;\s]+")


def _tokens(line: str) -> list[str]:
    return [t for t in _SPLIT.split(line.strip()) if t]


def is_blocks_row(line: str) -> bool:
    """A row of exactly two numbers (what :func:`read_blocks` reads)."""
    tokens = _tokens(line)
    if len(tokens) != 2:
        return False
    try:
        [float(t) for t in tokens]
    except ValueError:
        return False
    return True


def read_blocks(path: str | Path, columns: str = "field,moment") -> MicroMagData:
    """Read a data-only FORC file (module docstring) into :class:`MicroMagData`."""
    if columns not in COLUMN_LAYOUTS:
        raise ValueError(f"columns must be one of {COLUMN_LAYOUTS}, got {columns!r}")
    h_col = 0 if columns == "field,moment" else 1
    blocks: list[tuple[list[float], list[float], list[int]]] = []
    current: tuple[list[float], list[float], list[int]] | None = None
    for lineno, raw in enumerate(decode(path).splitlines(), start=1):
        line = raw.strip()
        if line.startswith("#"):
            continue
        if not line:
            current = None
            continue
        tokens = _tokens(line)
        if len(tokens) != 2:
            raise ValueError(f"line {lineno}: expected 2 columns ({columns}), got {len(tokens)}")
        h = parse_float(tokens[h_col], lineno, "field")
        m = parse_float(tokens[1 - h_col], lineno, "moment")
        if current is None:
            current = ([], [], [])
            blocks.append(current)
        current[0].append(h)
        current[1].append(m)
        current[2].append(lineno)
    if not blocks:
        raise ValueError(f"{path}: no data rows")
    check_magnitudes(
        [
            ("field", [h for b in blocks for h in b[0]]),
            ("moment", [m for b in blocks for m in b[1]]),
        ],
        [k for b in blocks for k in b[2]],
    )
    cal = [b for b in blocks if len(b[0]) == 1]
    curves = [(b[0][0], b[0], b[1], b[2]) for b in blocks if len(b[0]) > 1]
    if not curves:
        raise ValueError(f"{path}: no curve of two or more points (only single-point blocks)")
    conv = infer_convention(curves)
    seen: dict[float, int] = {}
    for rev, h, _, lines in curves:
        check_curve(rev, h, lines, conv)
        if rev in seen:
            raise ValueError(
                f"line {lines[0]}: reversal field {rev} also starts the curve at line {seen[rev]}"
            )
        seen[rev] = lines[0]
    notes = [f"data-only file, columns {columns}, units as written"]
    if cal:
        notes.append(f"{len(cal)} single-point blocks taken as calibration points")
    return MicroMagData(
        ReversalCurves(
            np.array([c[0] for c in curves]),
            tuple(np.array(c[1]) for c in curves),
            tuple(np.array(c[2]) for c in curves),
            conv,
        ),
        calibration_moments=np.array([b[1][0] for b in cal]) if cal else None,
        calibration_fields=np.array([b[0][0] for b in cal]) if cal else None,
        notes=tuple(notes),
    )


def write_blocks(
    path: str | Path,
    curves: ReversalCurves,
    calibration: tuple[float, np.ndarray] | None = None,
    columns: str = "field,moment",
) -> Path:
    """Write curves as a data-only file: one block per curve (preceded by a calibration point
    ``(field, moments[c])`` when given), ``repr`` precision."""
    if columns not in COLUMN_LAYOUTS:
        raise ValueError(f"columns must be one of {COLUMN_LAYOUTS}, got {columns!r}")
    swap = columns == "moment,field"
    lines: list[str] = []
    for c, (h, m) in enumerate(zip(curves.fields, curves.moments, strict=True)):
        if calibration is not None:
            pair = (float(calibration[0]), float(calibration[1][c]))
            lines += [f"{pair[swap]!r},{pair[1 - swap]!r}", ""]
        for hh, mm in zip(h, m, strict=True):
            pair = (float(hh), float(mm))
            lines.append(f"{pair[swap]!r},{pair[1 - swap]!r}")
        lines.append("")
    path = Path(path)
    path.write_text("\n".join(lines))
    return path
