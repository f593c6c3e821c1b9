"""Data-only FORC files (:func:`read_blocks`, :func:`write_blocks`): two columns, no header.

Rows of two numbers (separated by a comma, a semicolon, tabs or spaces), one point each, in
measurement order; a blank line ends a block (the data section of an instrument export, saved
without its header). Lines starting with ``#`` are comments. Before the first row the data
section of a MicroMag export keeps its column titles: a names line (``Field  Moment``, either
order: it sets ``columns``, and a different ``columns=`` is refused) and a units line
(``(T)  (Am²)``: fields and moments are then converted to mT and A·m², an unknown unit is
refused; without it the units are unknown, as written). The line ``MicroMag 2900/3900 Data
File ends`` ends the data. ``columns`` otherwise says which column is which
(``"field,moment"``, the default, or ``"moment,field"``).

Blocks are read in one of two layouts, told apart block by block:

* **one block per curve** (PMC/MicroMag FORC data): a block of one point is a calibration point
  (a FORC has at least two points; the instruments measure one before every curve); every
  other block is a curve whose first point is its reversal field;
* **one block per segment** (the data section of a "Multiple segments" irregular FORC export,
  :mod:`~analysis.identification.forc_files.segments`, saved without its script): the
  reversal point is a block of one point, and every ramp of the curve a block that starts
  where the block before it ended (the same commanded field measured again). A block of two or
  more points continues the curve before it when that is a reversal point (one point below the
  calibration field) and the block does not fall, or when that is a curve whose last field
  the block's first field repeats (within :data:`SAME_FIELD` of the largest field, or closer
  than half the block's first step). Points of a joined curve measured one after another at
  one field (within :data:`SAME_FIELD`) are averaged, as the segments reader averages the
  points of one commanded field; without the commanded fields, two points whose commanded
  fields lie close to that tolerance can be grouped otherwise than with the script (in the
  pyFORC examples: 0 of 40 curves of the shipped export, one point in 4 of 99 and 4 of 119
  curves of two larger ones). The calibration field is the largest one-point field; a block
  lying at it (a ramp at saturation before the first curve) and, among segments, a falling
  block (the sweep back at the end of the run) are skipped and counted in the notes.

The convention follows the direction of the fields (rising: Pike, falling: Mayergoyz). A
remanence script's data section alone (blocks alternating zero and the field) is not
recognised as such: without the script the zero-field points cannot be told from a curve, and
the reader refuses the falling blocks. Errors name the line, as for every reader.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from analysis.identification.curves import ReversalCurves
from analysis.identification.forc_files.common import (
    END_MARK,
    FIELD_UNITS,
    MOMENT_UNITS,
    MicroMagData,
    bracketed_units,
    check_curve,
    check_magnitudes,
    decode,
    infer_convention,
    parse_float,
    unit_factor,
)

__all__ = ["read_blocks", "write_blocks", "COLUMN_LAYOUTS", "is_blocks_row", "skip_titles"]

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


def skip_titles(lines: list[str]) -> tuple[int, str | None, list[str] | None]:
    """Column titles before the first data row (``#`` comments and blank lines aside): at most
    a names line (``Field  Moment``, either order) and a units line (``(T)  (Am²)``), as the
    data section of a MicroMag export writes them. Returns the index of the first line after
    them, the column order they name (or ``None``) and the units in the file's column order (or
    ``None``: no units line)."""
    k = 0
    while k < len(lines) and (not lines[k].strip() or lines[k].lstrip().startswith("#")):
        k += 1
    words = [w.lower() for w in _tokens(lines[k])] if k < len(lines) else []
    if sorted(words) != ["field", "moment"]:
        return k, None, None
    units = bracketed_units(lines[k + 1]) if k + 1 < len(lines) else []
    if len(units) == 2 and not is_blocks_row(lines[k + 1]):
        return k + 2, ",".join(words), units
    return k + 1, ",".join(words), None


def _factors(units: list[str] | None, columns: str, lineno: int) -> tuple[float, float] | None:
    """Factors of the titles' units (file column order) to mT and A·m², or ``None``."""
    if units is None:
        return None
    field, moment = units if columns == "field,moment" else units[::-1]
    f_fac, m_fac = unit_factor(field, FIELD_UNITS), unit_factor(moment, MOMENT_UNITS)
    if f_fac is None or m_fac is None:
        raise ValueError(
            f"line {lineno}: cannot tell the units ({field}) and ({moment}) (fields: "
            f"{', '.join(FIELD_UNITS)}; moments: {', '.join(MOMENT_UNITS)})"
        )
    return f_fac, m_fac


#: fields closer than this fraction of the file's largest field are one field measured again
#: (the tolerance the segments reader applies to the commanded fields of a script)
SAME_FIELD = 1e-3


def _mean(group: list[tuple[float, float, int]]) -> tuple[float, float, int]:
    return (
        float(np.mean([p[0] for p in group])),
        float(np.mean([p[1] for p in group])),
        group[0][2],
    )


def _join(blocks: list[list[tuple[float, float, int]]]) -> tuple[list[list], int, int]:
    """Blocks with the continuation blocks joined to the curve before them (module docstring):
    ``(blocks, number of joins, points skipped)``; the points of a joined curve measured one
    after another at one field (within :data:`SAME_FIELD`) are averaged into one, as the
    segments reader averages the points of one commanded field."""
    tol = SAME_FIELD * max(abs(p[0]) for b in blocks for p in b)
    singles = [b[0][0] for b in blocks if len(b) == 1]
    h_cal = max(singles) if singles else None  # the calibration field: the top single point
    out: list[list[list[tuple[float, float, int]]]] = []  # per block: groups of points
    joins = skipped = 0
    for b in blocks:
        if len(b) > 1 and h_cal is not None and all(abs(p[0] - h_cal) <= tol for p in b):
            skipped += len(b)  # a ramp at the calibration field: no reversal before it
            continue
        if joins and len(b) > 1 and b[1][0] < b[0][0] - tol:
            skipped += len(b)  # among segments: a falling sweep (back to zero after the run)
            continue
        if len(b) < 2 or not out or not _continues(b, out[-1], h_cal, tol):
            out.append([[p] for p in b])
            continue
        joins += 1
        out[-1][-1].append(b[0])  # the block starts where the one before ended
        for p in b[1:]:
            if abs(p[0] - out[-1][-1][-1][0]) <= tol:
                out[-1][-1].append(p)
            else:
                out[-1].append([p])
    return [[_mean(g) for g in groups] for groups in out], joins, skipped


def _continues(block: list, before: list[list], h_cal: float | None, tol: float) -> bool:
    """Whether ``block`` (two or more points) continues ``before`` (groups of points): a
    reversal point (a single point below the calibration field) is followed by the ramp that
    starts at it (rising, or level within ``tol``); a curve by a block whose first field
    repeats its last one (within ``tol``, or closer than half the block's first step)."""
    last = before[-1][-1][0]
    if len(before) == 1 and len(before[0]) == 1:
        return abs(last - h_cal) > tol and block[1][0] >= block[0][0] - tol
    gap = abs(block[0][0] - last)
    return gap <= tol or gap < (block[1][0] - block[0][0]) / 2


def read_blocks(path: str | Path, columns: str | None = None) -> MicroMagData:
    """Read a data-only FORC file (module docstring) into :class:`MicroMagData`."""
    if columns is not None and columns not in COLUMN_LAYOUTS:
        raise ValueError(f"columns must be one of {COLUMN_LAYOUTS}, got {columns!r}")
    lines = decode(path).splitlines()
    first, named, units = skip_titles(lines)
    if named is not None and columns is not None and named != columns:
        raise ValueError(f"columns={columns!r}, but the column titles name {named!r}")
    columns = columns or named or "field,moment"
    factors = _factors(units, columns, first)
    f_fac, m_fac = factors if factors is not None else (None, None)
    h_col = 0 if columns == "field,moment" else 1
    blocks: list[list[tuple[float, float, int]]] = []
    current: list[tuple[float, float, int]] | None = None
    written: list[tuple[float, float]] = []
    for lineno, raw in enumerate(lines[first:], start=first + 1):
        line = raw.strip()
        if line.startswith("#"):
            continue
        if line == END_MARK:
            break
        if not line:
            current = None
            continue
        tokens = _tokens(line)
        if len(tokens) != 2:
            raise ValueError(f"line {lineno}: expected 2 columns ({columns}), got {len(tokens)}")
        h = parse_float(tokens[h_col], lineno, "field")
        m = parse_float(tokens[1 - h_col], lineno, "moment")
        written.append((h, m))
        if current is None:
            current = []
            blocks.append(current)
        current.append((h * (f_fac or 1.0), m * (m_fac or 1.0), lineno))
    if not blocks:
        raise ValueError(f"{path}: no data rows")
    check_magnitudes(
        [("field", [w[0] for w in written]), ("moment", [w[1] for w in written])],
        [p[2] for b in blocks for p in b],
    )
    joined, n_joined, n_skipped = _join(blocks)
    cal = [b for b in joined if len(b) == 1]
    curves = [(b[0][0], [p[0] for p in b], [p[1] for p in b], [p[2] for p in b]) for b in joined]
    curves = [c for c in curves if len(c[1]) > 1]
    if not curves:
        raise ValueError(f"{path}: no curve of two or more points (only single-point blocks)")
    conv = infer_convention(curves)
    seen: dict[float, int] = {}
    for rev, h, _, lns in curves:
        check_curve(rev, h, lns, conv)
        if rev in seen:
            raise ValueError(
                f"line {lns[0]}: reversal field {rev} also starts the curve at line {seen[rev]}"
            )
        seen[rev] = lns[0]
    units = "units as written" if f_fac is None else "units from the column titles"
    notes = [f"data-only file, columns {columns}, {units}"]
    if n_joined:
        notes.append(
            f"{n_joined} blocks continue the curve before them (segments of an irregular FORC "
            "protocol sharing their end points; each shared point averaged)"
        )
    if n_skipped:
        notes.append(
            f"{n_skipped} points outside the curves skipped (blocks at the calibration field, "
            "a falling sweep among the segments)"
        )
    if cal:
        notes.append(f"{len(cal)} single-point blocks taken as calibration points")
    return MicroMagData(
        ReversalCurves(
            np.array([c[0] for c in curves]),
            tuple(np.array(c[1]) for c in curves),
            tuple(np.array(c[2]) for c in curves),
            conv,
        ),
        calibration_moments=np.array([b[0][1] for b in cal]) if cal else None,
        calibration_fields=np.array([b[0][0] for b in cal]) if cal else None,
        field_unit=None if f_fac is None else "mT",
        moment_unit=None if m_fac is None else "A·m²",
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
