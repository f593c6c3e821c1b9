"""CSV files of reversal curves (:func:`read_csv`, :func:`write_csv`).

Three comma-separated columns per row: ``reversal_field, field, moment``. Lines starting with
``#`` are comments; a comment ``# convention = pike`` (or ``mayergoyz``) fixes the convention. An
optional header row (the first non-comment row, if it is not numeric, e.g.
``reversal_field,field,moment``) is skipped. Consecutive rows with the same reversal field form
one curve, in measurement order; the first row of a curve is at the reversal field itself.
The convention is, in order: the ``convention`` argument, the comment, or inferred from the
direction of the fields (falling: Mayergoyz, rising: Pike).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from analysis.identification.curves import CONVENTIONS, ReversalCurves
from analysis.identification.forc_files.common import (
    check_curve,
    check_magnitudes,
    decode,
    infer_convention,
    is_number,
    parse_float,
)

__all__ = ["read_csv", "write_csv"]


def read_csv(path: str | Path, convention: str | None = None) -> ReversalCurves:
    """Read reversal curves from a CSV file (see module docstring for the format)."""
    if convention is not None and convention not in CONVENTIONS:
        raise ValueError(f"convention must be one of {CONVENTIONS} or None, got {convention!r}")
    text = decode(path)
    file_convention = None
    rows: list[tuple[float, float, float, int]] = []
    seen_data = False
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("#"):
            m = re.match(r"#\s*convention\s*[=:]\s*(\w+)", line, flags=re.IGNORECASE)
            if m:
                file_convention = m.group(1).lower()
                if file_convention not in CONVENTIONS:
                    raise ValueError(
                        f"line {lineno}: convention must be one of {CONVENTIONS}, "
                        f"got {file_convention!r}"
                    )
            continue
        tokens = [t.strip() for t in line.split(",")]
        if not seen_data and not is_number(tokens[0]):
            seen_data = True  # a header row of column names
            if len(tokens) != 3:
                raise ValueError(
                    f"line {lineno}: header must name 3 columns (reversal_field, field, moment)"
                )
            continue
        seen_data = True
        if len(tokens) != 3:
            raise ValueError(
                f"line {lineno}: expected 3 columns (reversal_field, field, moment), "
                f"got {len(tokens)}"
            )
        rev = parse_float(tokens[0], lineno, "reversal field")
        h = parse_float(tokens[1], lineno, "field")
        mom = parse_float(tokens[2], lineno, "moment")
        rows.append((rev, h, mom, lineno))
    if not rows:
        raise ValueError(f"{path}: no data rows")
    check_magnitudes(
        [
            (name, [r[k] for r in rows])
            for k, name in enumerate(("reversal field", "field", "moment"))
        ],
        [r[3] for r in rows],
    )
    curves: list[tuple[float, list[float], list[float], list[int]]] = []
    for rev, h, mom, lineno in rows:
        if curves and rev == curves[-1][0]:
            curves[-1][1].append(h)
            curves[-1][2].append(mom)
            curves[-1][3].append(lineno)
        else:
            if any(rev == c[0] for c in curves):
                raise ValueError(
                    f"line {lineno}: reversal field {rev} appears in two separate curves"
                )
            curves.append((rev, [h], [mom], [lineno]))
    conv = convention or file_convention or infer_convention(curves)
    for rev, h, _, lines in curves:
        check_curve(rev, h, lines, conv)
    return ReversalCurves(
        np.array([c[0] for c in curves]),
        tuple(np.array(c[1]) for c in curves),
        tuple(np.array(c[2]) for c in curves),
        conv,
    )


def write_csv(path: str | Path, curves: ReversalCurves, header: bool = True) -> Path:
    """Write curves as CSV rows ``reversal_field,field,moment`` (with a convention comment)."""
    path = Path(path)
    lines = [f"# convention = {curves.convention}"]
    if header:
        lines.append("reversal_field,field,moment")
    for r, h, m in zip(curves.reversal_field, curves.fields, curves.moments, strict=True):
        for hh, mm in zip(h, m, strict=True):
            lines.append(f"{float(r)!r},{float(hh)!r},{float(mm)!r}")
    path.write_text("\n".join(lines) + "\n")
    return path
