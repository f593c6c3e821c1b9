"""Read and write first-order reversal curve (FORC) data: plain CSV and MicroMag text.

Both readers return :class:`analysis.identification.ReversalCurves`; identify with
:func:`analysis.identification.identify_from_curves`. Every reader either returns the complete
data set or raises :class:`ValueError` naming the (1-based) line that is wrong: missing or
inconsistent header fields, ragged rows, non-numeric values, NaN/inf, curves that do not start
at their reversal field or whose fields are not monotone.

CSV format (:func:`read_csv`, :func:`write_csv`)
-----------------------------------------------
Three comma-separated columns per row: ``reversal_field, field, moment``. Lines starting with
``#`` are comments; a comment ``# convention = pike`` (or ``mayergoyz``) fixes the convention. An
optional header row (the first non-comment row, if it is not numeric, e.g.
``reversal_field,field,moment``) is skipped. Consecutive rows with the same reversal field form
one curve, in measurement order; the first row of a curve is at the reversal field itself.
The convention is, in order: the ``convention`` argument, the comment, or inferred from the
direction of the fields (falling: Mayergoyz, rising: Pike).

MicroMag format (:func:`read_micromag`, :func:`write_micromag`)
---------------------------------------------------------------
The Princeton Measurements MicroMag 2900/3900 FORC text export, as far as needed here (a
documented subset):

* a header of free text and ``Key = value`` (or ``Key  value``) lines, ending at the first data
  line. Required: ``NCrv`` (alias ``NForc``), the number of curves, and ``NData``, the number of
  curve points (calibration points excluded; a count that includes them is accepted too).
  Optional: ``HCal`` (calibration/drift field), ``HSat``; other keys are kept in ``meta``.
* data lines ``field,moment`` (an optional third column, temperature, is ignored), numbers in any
  float format (the instrument writes ``+1.000000E+00``); a line ``Field, Moment`` of column titles
  may precede them;
* blocks separated by blank lines. With ``HCal`` in the header the blocks alternate: a
  one-point calibration block (the drift point, measured at ``HCal`` after saturation) and a curve
  block, optionally followed by a final calibration block. Without ``HCal`` every block is a curve.
* each curve is a Pike FORC: its first point is at the reversal field ``H_r``, fields then rise.
* an optional last line ``MicroMag 2900/3900 Data File ends``.

``drift_correction=True`` scales each curve by ``M_cal,first / M_cal,curve`` (the usual
multiplicative drift correction); it is off by default.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from analysis.identification import ReversalCurves

__all__ = ["read_csv", "write_csv", "read_micromag", "write_micromag", "MicroMagData", "read_forc"]

_CONVENTIONS = ("mayergoyz", "pike")
_END_MARK = "MicroMag 2900/3900 Data File ends"


def _float(token: str, lineno: int, what: str) -> float:
    try:
        value = float(token)
    except ValueError:
        raise ValueError(f"line {lineno}: {what} {token.strip()!r} is not a number") from None
    if not math.isfinite(value):
        raise ValueError(f"line {lineno}: {what} must be finite, got {token.strip()!r}")
    return value


def _check_curve(rev: float, fields: list[float], lines: list[int], convention: str) -> None:
    """Validate one curve (first point at the reversal field, monotone fields)."""
    if not math.isclose(fields[0], rev, rel_tol=1e-9, abs_tol=1e-12):
        raise ValueError(
            f"line {lines[0]}: a curve must start at its reversal field {rev} (got field "
            f"{fields[0]})"
        )
    sign = -1.0 if convention == "mayergoyz" else 1.0
    for k in range(1, len(fields)):
        if not sign * (fields[k] - fields[k - 1]) > 0:
            direction = "decrease" if sign < 0 else "increase"
            raise ValueError(
                f"line {lines[k]}: fields must strictly {direction} along a {convention} curve "
                f"({fields[k - 1]} then {fields[k]})"
            )


def _infer_convention(curves: list[tuple[float, list[float], list[float], list[int]]]) -> str:
    for _, h, _, _ in curves:
        if len(h) >= 2:
            return "mayergoyz" if h[1] < h[0] else "pike"
    raise ValueError("cannot infer the convention (every curve has one point); pass convention=")


# ----------------------------------------------------------------------------------------------
# CSV
# ----------------------------------------------------------------------------------------------
def read_csv(path: str | Path, convention: str | None = None) -> ReversalCurves:
    """Read reversal curves from a CSV file (see module docstring for the format)."""
    if convention is not None and convention not in _CONVENTIONS:
        raise ValueError(f"convention must be one of {_CONVENTIONS} or None, got {convention!r}")
    text = Path(path).read_text()
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
                if file_convention not in _CONVENTIONS:
                    raise ValueError(
                        f"line {lineno}: convention must be one of {_CONVENTIONS}, "
                        f"got {file_convention!r}"
                    )
            continue
        tokens = [t.strip() for t in line.split(",")]
        if not seen_data and not _is_number(tokens[0]):
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
        rev = _float(tokens[0], lineno, "reversal field")
        h = _float(tokens[1], lineno, "field")
        mom = _float(tokens[2], lineno, "moment")
        rows.append((rev, h, mom, lineno))
    if not rows:
        raise ValueError(f"{path}: no data rows")
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
    conv = convention or file_convention or _infer_convention(curves)
    for rev, h, _, lines in curves:
        _check_curve(rev, h, lines, conv)
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


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


# ----------------------------------------------------------------------------------------------
# MicroMag
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class MicroMagData:
    """Contents of a MicroMag FORC file: the curves (Pike), calibration points, header."""

    curves: ReversalCurves
    calibration_field: float | None = None
    calibration_moments: np.ndarray | None = None
    header: dict[str, str] = field(default_factory=dict)


_DATA_LINE = re.compile(r"^\s*[+\-]?(\d|\.\d)")


def read_micromag(path: str | Path, drift_correction: bool = False) -> MicroMagData:
    """Read a MicroMag FORC text file (documented subset, see module docstring)."""
    lines = Path(path).read_text().splitlines()
    header: dict[str, str] = {}
    header_line: dict[str, int] = {}
    first_data = None
    for idx, raw in enumerate(lines):
        line = raw.strip()
        if _DATA_LINE.match(line) or line.lower().startswith(("nan", "+nan", "-nan")):
            first_data = idx
            break
        m = re.match(r"^([A-Za-z][\w ().\-/]*?)\s*(?:=|\s{2,}|\t)\s*(\S.*)$", line)
        if m:
            key = m.group(1).strip()
            header[key] = m.group(2).strip()
            header_line[key] = idx + 1
    if first_data is None:
        raise ValueError(f"{path}: no data lines (a data line starts with a number)")

    def header_value(keys: Sequence[str], kind: type, required: bool) -> Any:
        for k in keys:
            if k in header:
                text = header[k]
                try:
                    val = float(text)
                    if kind is int:
                        if val != int(val) or val < 0:
                            raise ValueError
                        return int(val)
                    if not math.isfinite(val):
                        raise ValueError
                    return val
                except ValueError:
                    raise ValueError(
                        f"line {header_line[k]}: header field {k} must be a "
                        f"{'non-negative integer' if kind is int else 'finite number'}, "
                        f"got {text!r}"
                    ) from None
        if required:
            raise ValueError(
                f"line {first_data + 1}: missing header field {keys[0]}"
                + (f" (or {', '.join(keys[1:])})" if len(keys) > 1 else "")
                + " before the first data line"
            )
        return None

    n_curves = header_value(("NCrv", "NForc"), int, True)
    n_data = header_value(("NData",), int, True)
    h_cal = header_value(("HCal",), float, False)

    # blocks of data lines separated by blank lines
    blocks: list[list[tuple[float, float, int]]] = []
    current: list[tuple[float, float, int]] = []
    for idx in range(first_data, len(lines)):
        lineno = idx + 1
        line = lines[idx].strip()
        if not line:
            if current:
                blocks.append(current)
                current = []
            continue
        if line.startswith(_END_MARK[:8]) and "ends" in line:
            break
        tokens = [t.strip() for t in line.split(",")]
        if len(tokens) not in (2, 3):
            raise ValueError(
                f"line {lineno}: expected 'field,moment' (optionally ',temperature'), "
                f"got {len(tokens)} columns"
            )
        h = _float(tokens[0], lineno, "field")
        mom = _float(tokens[1], lineno, "moment")
        if len(tokens) == 3:
            _float(tokens[2], lineno, "temperature")
        current.append((h, mom, lineno))
    if current:
        blocks.append(current)

    cal_moments: list[float] = []
    curve_blocks: list[list[tuple[float, float, int]]] = []
    if h_cal is not None:
        for b, block in enumerate(blocks):
            if b % 2 == 0:
                if len(block) != 1:
                    raise ValueError(
                        f"line {block[0][2]}: expected a one-point calibration block at "
                        f"HCal = {h_cal} before each curve, got {len(block)} points"
                    )
                if not math.isclose(block[0][0], h_cal, rel_tol=1e-6, abs_tol=1e-9):
                    raise ValueError(
                        f"line {block[0][2]}: calibration point field {block[0][0]} differs "
                        f"from HCal = {h_cal}"
                    )
                cal_moments.append(block[0][1])
            else:
                curve_blocks.append(block)
    else:
        curve_blocks = blocks
    if len(curve_blocks) != n_curves:
        where = curve_blocks[-1][-1][2] if curve_blocks else first_data + 1
        raise ValueError(
            f"line {where}: header NCrv = {n_curves} but the file holds {len(curve_blocks)} curves"
        )
    n_points = sum(len(b) for b in curve_blocks)
    if n_data not in (n_points, n_points + len(cal_moments)):
        raise ValueError(
            f"line {header_line.get('NData', first_data + 1)}: header NData = {n_data} but the "
            f"file holds {n_points} curve points (+{len(cal_moments)} calibration points)"
        )
    revs, fields_, moments = [], [], []
    seen: dict[float, int] = {}
    for c, block in enumerate(curve_blocks):
        h = [p[0] for p in block]
        m = np.array([p[1] for p in block])
        ln = [p[2] for p in block]
        if h[0] in seen:
            raise ValueError(
                f"line {ln[0]}: reversal field {h[0]} repeats the curve at line {seen[h[0]]}"
            )
        seen[h[0]] = ln[0]
        _check_curve(h[0], h, ln, "pike")
        if drift_correction and cal_moments:
            if cal_moments[c] == 0.0:
                raise ValueError(f"line {ln[0] - 2}: calibration moment 0 cannot correct drift")
            m = m * (cal_moments[0] / cal_moments[c])
        revs.append(h[0])
        fields_.append(np.array(h))
        moments.append(m)
    curves = ReversalCurves(np.array(revs), tuple(fields_), tuple(moments), "pike")
    return MicroMagData(
        curves,
        h_cal,
        np.array(cal_moments) if cal_moments else None,
        header,
    )


def write_micromag(
    path: str | Path,
    curves: ReversalCurves,
    calibration_field: float | None = None,
    calibration_moments: Any | None = None,
    saturation_field: float | None = None,
) -> Path:
    """Write Pike curves in the MicroMag FORC text format (the subset :func:`read_micromag` reads).

    With ``calibration_field`` a calibration point (``calibration_moments[c]``) precedes every
    curve ``c``. Mayergoyz data must be converted first (``curves.mirrored()`` for a symmetric
    operator, or measure Pike curves).
    """
    if curves.convention != "pike":
        raise ValueError(
            "MicroMag FORC files hold Pike curves (from positive saturation); got "
            f"{curves.convention!r} curves"
        )
    n = curves.n_curves
    if calibration_field is not None:
        cal = np.asarray(calibration_moments, dtype=float).reshape(-1)
        if cal.size != n or not np.all(np.isfinite(cal)):
            raise ValueError("calibration_moments must hold one finite moment per curve")
    out = [
        "MicroMag 2900/3900 Data File (Series 0016)",
        "First-order reversal curves",
        "",
        "Configuration   VSM",
        "Units           Dimensionless (hysteresis-toolkit synthetic data)",
        "",
        f"NCrv = {n}",
        f"NData = {curves.n_points}",
    ]
    if calibration_field is not None:
        out.append(f"HCal = {calibration_field:+.16E}")
    if saturation_field is not None:
        out.append(f"HSat = {saturation_field:+.16E}")
    out += ["", "Field, Moment", ""]
    order = np.argsort(curves.reversal_field)
    for c in order:
        if calibration_field is not None:
            out.append(f"{calibration_field:+.16E},{cal[c]:+.16E}")
            out.append("")
        for h, m in zip(curves.fields[c], curves.moments[c], strict=True):
            out.append(f"{h:+.16E},{m:+.16E}")
        out.append("")
    out.append(_END_MARK)
    path = Path(path)
    path.write_text("\n".join(out) + "\n")
    return path


def read_forc(path: str | Path, format: str = "csv", **kwargs: Any) -> ReversalCurves:
    """Read reversal curves from ``path`` in ``format`` (``"csv"`` or ``"micromag"``)."""
    if format == "csv":
        return read_csv(path, **kwargs)
    if format == "micromag":
        return read_micromag(path, **kwargs).curves
    raise ValueError(f"format must be 'csv' or 'micromag', got {format!r}")
