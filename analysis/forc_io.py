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
The Princeton Measurements (Lake Shore) MicroMag 2900/3900 AGM/VSM FORC text export. What the
reader assumes, from the instrument's public file description and the files FORC software
reads (FORCinel, VARIFORC, FORCsensei):

* **Text.** UTF-8 if the file decodes as such, else cp1252 (a superset of Latin-1 for the
  printable range: ``Am²``, ``µ``, ``°`` in unit lines); LF or CRLF line ends.
* **Title.** Line 1 starts with ``MicroMag``; line 2 names the measurement. Only
  ``First-order reversal curves`` is read; ``Direct moment vs. field; Multiple segments``
  (irregular or remanence FORC protocols), remanence curves and hysteresis loops are refused
  with a one-line ``ValueError`` naming the variant. A line after the title that starts with
  digits but is not a ``field,moment`` pair (the date/time line of Series 0016) is header.
* **Header.** ``Key value`` (two or more spaces or a tab), ``Key = value`` or ``Key: value``
  lines, in both generations: short keys of Series 0015 (``NCrv``/``NForc``, ``NData``,
  ``HCal``, ``HSat``) and the long keys of Series 0016 (``Number of FORCs``, ``Number of
  data``, ``Calibration field``, ``Saturation field``); section titles (``INSTRUMENT``,
  ``SETTINGS``) and ``N/A`` values are ignored. The number of curves is required; the number
  of data points is optional (a count with or without calibration points is accepted). Values
  are numbers in any float format (``+1.000000E+00``), possibly followed by a unit.
* **Units** (``Units of measure``): ``cgs`` — fields in Oe, moments in emu; ``SI`` and
  ``Hybrid SI`` — fields as µ0H in T, moments in A·m². Fields are returned in mT and moments in
  A·m² (1 Oe ↔ 0.1 mT, 1 emu = 10⁻³ A·m²); :attr:`MicroMagData.field_unit` says so. Without the
  key the values are returned as written (``field_unit = None``).
* **Data.** ``field,moment`` lines (a third column, e.g. temperature or time, is ignored), in
  blocks separated by blank lines; column-title lines (``Field, Moment``, ``(Oe)  (emu)``)
  before the first block are skipped. A one-point block whose field lies within 5 % of
  ``HCal`` or, when the units are known, within 5 mT (the measured calibration field drifts
  by a few mT) is a calibration (drift) point, unless the block before it was one too (then it
  is the one-point curve reversing at HCal); every other block is a curve, a Pike FORC
  starting at its reversal field with rising fields. Reading stops at the end marker
  ``MicroMag 2900/3900 Data File ends``.
* **Aborted measurements.** Fewer curves or points than the header announces (a last curve
  cut short, no end marker) are read; :attr:`MicroMagData.complete` is then ``False`` and
  :attr:`MicroMagData.notes` says what is missing. More curves than announced is an error.

Drift correction (``drift_correction=``): the calibration moments, measured at the same field
before every curve, sample the instrument's drift. ``"multiplicative"`` (or ``True``) scales,
``"additive"`` shifts every point to the first calibration moment, with the drift interpolated
linearly in measurement order (file position) between consecutive calibration points and held
constant after the last; the calibration field's own drift is neglected. Off by default.

Lake Shore 8600 FORC CSV (:func:`read_lakeshore_csv`)
----------------------------------------------------
Assumed layout (stated, not taken from a vendor specification): optional ``key,value`` header
rows, then one column-title row naming a field column and a moment column with their units in
brackets or parentheses (``Field (µ0H) [T]``, ``Moment (m) [A·m²]``; a ``Time Stamp [s]``
column is allowed), then one data row per point in measurement order with no blank lines.
Units ``T``, ``mT``, ``Oe``, ``A/m`` (fields) and ``A·m²``/``Am²``, ``emu`` (moments) are
converted to mT and A·m². Curves are split where the field falls; a single point within 5 % of
the calibration field (header ``Calibration field``, else the first point when it is followed
by a fall) is a calibration point, usable for the same drift correction.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from analysis.identification import ReversalCurves

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
    text = _decode(path)
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
    """Contents of a FORC file: the curves (Pike), calibration points, header, units.

    Attributes
    ----------
    curves:
        The reversal curves (Pike convention), converted to ``field_unit``/``moment_unit``.
    calibration_field:
        Nominal calibration field (header ``HCal``), converted, or ``None``.
    calibration_moments:
        Moment of every calibration point in file order, or ``None``.
    header:
        Every header ``key: value`` pair as text.
    field_unit, moment_unit:
        ``"mT"`` and ``"A·m²"`` when the file states its units, else ``None`` (as written).
    units_of_measure:
        The file's own ``Units of measure`` value (``cgs``, ``SI``, ``Hybrid SI``) or ``None``.
    complete:
        ``False`` for an aborted measurement (fewer curves/points than announced).
    notes:
        Human-readable remarks (what was missing, which correction was applied).
    calibration_fields:
        Measured field of every calibration point (converted), or ``None``.
    """

    curves: ReversalCurves
    calibration_field: float | None = None
    calibration_moments: np.ndarray | None = None
    header: dict[str, str] = field(default_factory=dict)
    field_unit: str | None = None
    moment_unit: str | None = None
    units_of_measure: str | None = None
    complete: bool = True
    notes: tuple[str, ...] = ()
    calibration_fields: np.ndarray | None = None


_NUM = r"[+\-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+\-]?\d+)?"
_DATA_LINE = re.compile(rf"^\s*{_NUM}\s*,\s*\S")
_NUM_START = re.compile(rf"^\s*({_NUM})")
_KEY_VALUE = re.compile(r"^([A-Za-z][^=:\t]*?)\s*(?:=|:|\t|\s{2,})\s*(\S.*)$")
_KEYS = {
    "n_curves": ("ncrv", "nforc", "number of forcs", "number of curves"),
    "n_data": ("ndata", "number of data"),
    "h_cal": ("hcal", "calibration field"),
    "h_sat": ("hsat", "saturation field"),
    "units": ("units of measure",),
}
# field factor to mT, moment factor to A·m², by "Units of measure"
_UNIT_SYSTEMS = {"cgs": (0.1, 1e-3), "si": (1e3, 1.0), "hybrid si": (1e3, 1.0)}
_REFUSED = (
    (
        "multiple segments",
        "MicroMag 'Direct moment vs. field; Multiple segments' export "
        "(irregular or remanence FORC protocol)",
    ),
    ("remanence", "MicroMag remanence-curve export"),
    ("hysteresis loop", "MicroMag hysteresis-loop export"),
)
_CAL_REL_TOL = 0.05
_CAL_ABS_TOL_MT = 5.0  # the measured calibration field drifts by a few mT
DriftMode = str | bool | None


def _decode(path: str | Path) -> str:
    """File text: UTF-8 if valid, else cp1252 (Latin-1 for bytes cp1252 leaves undefined)."""
    raw = Path(path).read_bytes()
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        pass
    try:
        return raw.decode("cp1252")
    except UnicodeDecodeError:
        return raw.decode("latin-1")


def _drift_mode(drift_correction: DriftMode) -> str | None:
    if drift_correction in (None, False):
        return None
    if drift_correction is True:
        return "multiplicative"
    if drift_correction in ("multiplicative", "additive"):
        return str(drift_correction)
    raise ValueError(
        "drift_correction must be False, True, 'multiplicative' or 'additive', "
        f"got {drift_correction!r}"
    )


def _header_number(text: str, lineno: int, key: str, integer: bool) -> float | int | None:
    """Leading number of a header value (``N/A`` → None)."""
    if text.strip().upper().startswith("N/A"):
        return None
    m = _NUM_START.match(text)
    if not m:
        kind = "non-negative integer" if integer else "finite number"
        raise ValueError(f"line {lineno}: header field {key} must be a {kind}, got {text!r}")
    val = float(m.group(1))
    if integer:
        if val != int(val) or val < 0:
            raise ValueError(
                f"line {lineno}: header field {key} must be a non-negative integer, got {text!r}"
            )
        return int(val)
    if not math.isfinite(val):
        raise ValueError(f"line {lineno}: header field {key} must be a finite number")
    return val


def _apply_drift(
    mode: str | None,
    moments: list[np.ndarray],
    times: list[np.ndarray],
    cal_moments: np.ndarray,
    cal_times: np.ndarray,
    cal_lines: list[int],
) -> list[np.ndarray]:
    """Linear-in-time drift correction to the first calibration moment."""
    if mode is None or cal_moments.size == 0:
        return moments
    if mode == "multiplicative" and np.any(cal_moments == 0.0):
        k = int(np.flatnonzero(cal_moments == 0.0)[0])
        raise ValueError(f"line {cal_lines[k]}: calibration moment 0 cannot correct drift")
    out = []
    for m, t in zip(moments, times, strict=True):
        drift = np.interp(t, cal_times, cal_moments)  # constant outside the calibration times
        if mode == "multiplicative":
            out.append(m * (cal_moments[0] / drift))
        else:
            out.append(m - (drift - cal_moments[0]))
    return out


def _build_curves(
    blocks: list[list[tuple[float, float, int]]],
    h_cal: float | None,
    drift: str | None,
    max_curves: int | None,
    abs_tol: float = 0.0,
) -> tuple[ReversalCurves, np.ndarray | None, np.ndarray | None]:
    """Split blocks into calibration points and Pike curves; validate; correct drift."""
    cal_m, cal_h, cal_t, cal_lines = [], [], [], []
    curves: list[list[tuple[float, float, int]]] = []
    tol = max(_CAL_REL_TOL * abs(h_cal), abs_tol) if h_cal is not None else 0.0
    previous_cal = False
    for block in blocks:
        # calibration points never come in pairs: a second one-point block at HCal is the
        # one-point curve whose reversal field is the calibration field
        is_cal = (
            h_cal is not None
            and len(block) == 1
            and abs(block[0][0] - h_cal) <= tol
            and not previous_cal
        )
        previous_cal = is_cal
        if is_cal:
            cal_h.append(block[0][0])
            cal_m.append(block[0][1])
            cal_t.append(block[0][2])
            cal_lines.append(block[0][2])
        else:
            _check_curve(block[0][0], [p[0] for p in block], [p[2] for p in block], "pike")
            curves.append(block)
            if max_curves is not None and len(curves) > max_curves:
                raise ValueError(
                    f"line {block[0][2]}: the header announces {max_curves} curves but the "
                    "file holds more"
                )
    if not curves:
        raise ValueError("no reversal curves in the file (only calibration points)")
    revs, fields_, moments, times = [], [], [], []
    seen: dict[float, int] = {}
    for block in curves:
        h = [p[0] for p in block]
        ln = [p[2] for p in block]
        if h[0] in seen:
            raise ValueError(
                f"line {ln[0]}: reversal field {h[0]} repeats the curve at line {seen[h[0]]}"
            )
        seen[h[0]] = ln[0]
        _check_curve(h[0], h, ln, "pike")
        revs.append(h[0])
        fields_.append(np.array(h))
        moments.append(np.array([p[1] for p in block]))
        times.append(np.array(ln, dtype=float))
    cm = np.array(cal_m)
    moments = _apply_drift(drift, moments, times, cm, np.array(cal_t, dtype=float), cal_lines)
    rc = ReversalCurves(np.array(revs), tuple(fields_), tuple(moments), "pike")
    return rc, (cm if cal_m else None), (np.array(cal_h) if cal_h else None)


def read_micromag(path: str | Path, drift_correction: DriftMode = False) -> MicroMagData:
    """Read a MicroMag FORC text file (Series 0015/0016; see the module docstring).

    Parameters
    ----------
    path:
        The file.
    drift_correction:
        ``False`` (default), ``True``/``"multiplicative"`` or ``"additive"``: linear drift
        correction from the calibration points (module docstring).

    Returns
    -------
    MicroMagData
        Curves in mT and A·m² when the file states its units.

    Raises
    ------
    ValueError
        One line: the line number and what was expected, or the name of a refused variant.
    """
    drift = _drift_mode(drift_correction)
    lines = _decode(path).splitlines()
    if not lines:
        raise ValueError(f"{path}: empty file")
    if len(lines) > 1:
        kind = lines[1].strip().lower()
        for needle, name in _REFUSED:
            if needle in kind:
                raise ValueError(
                    f"line 2: {name} is not supported; export the measurement as "
                    "'First-order reversal curves'"
                )
    header: dict[str, str] = {}
    where: dict[str, int] = {}
    names: dict[str, str] = {}
    first_data = None
    for idx, raw in enumerate(lines):
        line = raw.strip()
        if idx > 0 and _DATA_LINE.match(line):
            first_data = idx
            break
        m = _KEY_VALUE.match(line)
        if m and idx > 0:
            key = m.group(1).strip()
            header[key] = m.group(2).strip()
            where[key.lower()] = idx + 1
            names[key.lower()] = key
    if first_data is None:
        raise ValueError(f"{path}: no data lines (a data line is 'field,moment')")
    lower = {k.lower(): v for k, v in header.items()}

    def value(name: str, integer: bool) -> Any:
        for k in _KEYS[name]:
            if k in lower:
                return _header_number(lower[k], where[k], names[k], integer)
        return None

    n_curves = value("n_curves", True)
    if n_curves is None:
        raise ValueError(
            f"line {first_data + 1}: missing header field NCrv (or NForc, Number of FORCs) "
            "before the first data line"
        )
    n_data = value("n_data", True)
    h_cal = value("h_cal", False)
    units = None
    for k in _KEYS["units"]:
        if k in lower:
            units = lower[k].strip()
            break
    f_fac, m_fac = 1.0, 1.0
    if units is not None:
        key = units.lower()
        if key not in _UNIT_SYSTEMS:
            raise ValueError(
                f"line {where['units of measure']}: Units of measure "
                f"must be cgs, SI or Hybrid SI, got {units!r}"
            )
        f_fac, m_fac = _UNIT_SYSTEMS[key]

    blocks: list[list[tuple[float, float, int]]] = []
    current: list[tuple[float, float, int]] = []
    ended = False
    for idx in range(first_data, len(lines)):
        lineno = idx + 1
        line = lines[idx].strip()
        if not line:
            if current:
                blocks.append(current)
                current = []
            continue
        if line.startswith("MicroMag") and "ends" in line:
            ended = True
            break
        tokens = [t.strip() for t in line.split(",")]
        if len(tokens) not in (2, 3):
            raise ValueError(
                f"line {lineno}: expected 'field,moment' (optionally a third column), "
                f"got {len(tokens)} columns"
            )
        h = _float(tokens[0], lineno, "field") * f_fac
        mom = _float(tokens[1], lineno, "moment") * m_fac
        if len(tokens) == 3 and tokens[2]:
            _float(tokens[2], lineno, "third column")
        current.append((h, mom, lineno))
    if current:
        blocks.append(current)
    cal = h_cal * f_fac if h_cal is not None else None
    # with known units a calibration field drifting by a few mT is recognised at any HCal
    curves, cal_m, cal_h = _build_curves(
        blocks, cal, drift, n_curves, _CAL_ABS_TOL_MT if units else 0.0
    )
    notes = []
    complete = True
    n_cal = 0 if cal_m is None else cal_m.size
    if curves.n_curves < n_curves:
        complete = False
        notes.append(f"header announces {n_curves} curves, the file holds {curves.n_curves}")
    if n_data is not None and n_data not in (curves.n_points, curves.n_points + n_cal):
        if n_data > curves.n_points + n_cal:
            complete = False
            notes.append(
                f"header announces {n_data} points, the file holds {curves.n_points} curve "
                f"points and {n_cal} calibration points"
            )
        else:
            key = "ndata" if "ndata" in where else "number of data"
            raise ValueError(
                f"line {where[key]}: header {names[key]} = "
                f"{n_data} but the file holds {curves.n_points} curve points "
                f"(+{n_cal} calibration points)"
            )
    if not ended and complete:
        notes.append("no end marker")
    if drift is not None and cal_m is not None:
        notes.append(f"{drift} drift correction from {cal_m.size} calibration points")
    return MicroMagData(
        curves,
        cal,
        cal_m,
        header,
        field_unit="mT" if units else None,
        moment_unit="A·m²" if units else None,
        units_of_measure=units,
        complete=complete,
        notes=tuple(notes),
        calibration_fields=cal_h,
    )


_FIELD_UNITS = {"t": 1e3, "mt": 1.0, "oe": 0.1, "a/m": 4e-4 * math.pi, "ka/m": 0.4 * math.pi}
_MOMENT_UNITS = {"a·m²": 1.0, "am²": 1.0, "am2": 1.0, "a·m2": 1.0, "a m²": 1.0, "emu": 1e-3}


def _column_unit(title: str, table: dict[str, float], lineno: int, what: str) -> float:
    units = re.findall(r"[\[(]([^\])]*)[\])]", title)
    for u in reversed(units):
        key = u.strip().lower().replace("^2", "²").replace(" ", "")
        for name, fac in table.items():
            if key == name.replace(" ", ""):
                return fac
    raise ValueError(
        f"line {lineno}: cannot tell the unit of the {what} column {title!r} "
        f"(expected one of {', '.join(table)} in brackets)"
    )


def read_lakeshore_csv(path: str | Path, drift_correction: DriftMode = False) -> MicroMagData:
    """Read a Lake Shore 8600-series FORC CSV export (layout assumed in the module docstring).

    Returns the same :class:`MicroMagData` as :func:`read_micromag` (fields in mT, moments in
    A·m²; Pike curves split where the field falls; calibration points recognised by field).
    """
    drift = _drift_mode(drift_correction)
    lines = _decode(path).splitlines()
    header: dict[str, str] = {}
    header_line: dict[str, int] = {}
    title_line = None
    for idx, raw in enumerate(lines):
        cells = [c.strip().strip('"') for c in raw.split(",")]
        low = [c.lower() for c in cells]
        if any("field" in c for c in low) and any("moment" in c for c in low):
            title_line = idx
            break
        if len(cells) >= 2 and cells[0]:
            header[cells[0].rstrip(":")] = cells[1]
            header_line[cells[0].rstrip(":")] = idx + 1
    if title_line is None:
        raise ValueError(
            f"{path}: no column-title row naming a field and a moment column "
            "(Lake Shore 8600 FORC CSV)"
        )
    titles = [c.strip().strip('"') for c in lines[title_line].split(",")]
    ln_t = title_line + 1
    i_h = next(i for i, c in enumerate(titles) if "field" in c.lower())
    i_m = next(i for i, c in enumerate(titles) if "moment" in c.lower())
    f_fac = _column_unit(titles[i_h], _FIELD_UNITS, ln_t, "field")
    m_fac = _column_unit(titles[i_m], _MOMENT_UNITS, ln_t, "moment")
    pts: list[tuple[float, float, int]] = []
    for idx in range(title_line + 1, len(lines)):
        line = lines[idx].strip()
        if not line:
            continue
        cells = [c.strip() for c in line.split(",")]
        if len(cells) != len(titles):
            raise ValueError(
                f"line {idx + 1}: expected {len(titles)} columns like the title row, "
                f"got {len(cells)}"
            )
        pts.append(
            (
                _float(cells[i_h], idx + 1, "field") * f_fac,
                _float(cells[i_m], idx + 1, "moment") * m_fac,
                idx + 1,
            )
        )
    if not pts:
        raise ValueError(f"{path}: no data rows after the column titles (line {ln_t})")
    h_cal: float | None = None
    for k, v in header.items():
        if k.lower().startswith("calibration field"):
            num = _header_number(v, header_line[k], k, False)
            if num is not None:
                unit = (
                    _column_unit(k + " " + v, _FIELD_UNITS, header_line[k], "calibration")
                    if ("[" in k or "(" in k)
                    else f_fac
                )
                h_cal = num * unit
    # calibration points: near HCal, reached by a jump up (> 2 field steps) and followed by a
    # fall (or the end); curves: split where the field falls
    h = np.array([p[0] for p in pts])
    rises = np.diff(h)
    step = float(np.median(rises[rises > 0])) if np.any(rises > 0) else 0.0
    if h_cal is None and h.size > 1 and h[1] < h[0]:
        h_cal = float(h[0])
    blocks: list[list[tuple[float, float, int]]] = []
    for i, p in enumerate(pts):
        is_cal = (
            h_cal is not None
            and abs(p[0] - h_cal) <= max(_CAL_REL_TOL * abs(h_cal), _CAL_ABS_TOL_MT)
            and (i == 0 or p[0] - h[i - 1] > 2 * step)
            and (i == h.size - 1 or h[i + 1] < p[0])
        )
        if is_cal or not blocks or p[0] < blocks[-1][-1][0] or blocks[-1][-1][3]:
            blocks.append([])
        blocks[-1].append((*p, is_cal))
    blocks = [[q[:3] for q in b] for b in blocks]
    curves, cal_m, cal_h = _build_curves(blocks, h_cal, drift, None, _CAL_ABS_TOL_MT)
    notes = []
    if drift is not None and cal_m is not None:
        notes.append(f"{drift} drift correction from {cal_m.size} calibration points")
    return MicroMagData(
        curves,
        h_cal,
        cal_m,
        header,
        field_unit="mT",
        moment_unit="A·m²",
        units_of_measure=None,
        complete=True,
        notes=tuple(notes),
        calibration_fields=cal_h,
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


FORMATS = ("auto", "csv", "micromag", "lakeshore")


def detect_format(path: str | Path) -> str:
    """``"micromag"`` (first line starts with ``MicroMag``), ``"lakeshore"`` (a column-title
    row names a field and a moment column before any data), else ``"csv"``."""
    lines = _decode(path).splitlines()[:200]
    if lines and lines[0].lstrip().startswith("MicroMag"):
        return "micromag"
    for raw in lines:
        low = raw.lower()
        if "field" in low and "moment" in low and ("[" in low or "(" in low):
            return "lakeshore"
        if _DATA_LINE.match(raw.strip()):
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
