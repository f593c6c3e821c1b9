"""Lake Shore 8600-series FORC CSV exports (:func:`read_lakeshore_csv`).

Layout, as a real 8600 export writes it (tests/data/forc_public/, software version 1.3; no
vendor specification was at hand): Latin-1 text; header rows ``key: value`` (``Saturation
field: 1.5 T``, ``Number of FORCs: 251``, ``Field step size: 1.6 mT``) under ``#`` section
titles (``#FORC MEASUREMENT``, ``##DATA TABLE ...``, skipped), or ``key,value`` rows; then the
column-title row, ``Step,Iteration,Segment,Field (µ0H) [T],Moment (m) [A·m²],Time Stamp [s],
Field Status,Moment (m) Status``; then one data row per point in measurement order, a blank
line after every segment. The column-title row is the first row (``#`` titles aside) in which
one comma-separated cell names a field and another a moment, each with a unit in brackets or
parentheses: header rows such as ``Moment X calibration field: 0.5 T`` (the moment meter's
calibration, no FORC calibration point) name both in one cell and stay header. Units ``T``,
``mT``, ``Oe``, ``A/m`` (fields) and ``A·m²``/``Am²``, ``emu`` (moments) are converted to mT and
A·m².

Curves: with a ``Segment`` column, every segment is a curve or, when it is one point within
5 % (or 5 mT) of the calibration field, a calibration point (the export alternates them; a
curve reaching the top of the protocol ends next to the calibration field and is kept apart
from the calibration point after it by its segment number alone). Without one (the assumed
minimal layout: optional ``key,value`` rows, a ``Time Stamp [s]`` column at most) curves are
split where the field falls and a calibration point is a single point near the calibration
field reached by a jump up (more than two field steps) and followed by a fall. The calibration
field is the header's ``Calibration field`` (its unit written after the number, in brackets in
the key, or the field column's), else the first point when a fall follows it. A header
``Number of FORCs`` announces the curves: fewer in the file (a run that stopped, an excerpt) is
read and flagged ``complete=False``, more is refused. The ``Step``/``Iteration`` columns are
not interpreted; rows whose status cells read other than ``GOOD`` are kept and counted in the
notes (no other status value was seen in a real export).

A file whose field rises over two or more points on fewer than two stretches (a hysteresis
loop, a remanence curve, a single sweep: no FORC measurement) is refused in one line.

Rows must be in measurement order; rows out of order are refused (not sorted) in one line
naming the first one: a numeric time stamp earlier than the row before, or (with or without
time stamps) a curve whose reversal field steps against the way the reversal fields step from
curve to curve (a FORC measurement steps them one way).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from analysis.identification.forc_files.common import (
    CAL_ABS_TOL_MT,
    CAL_REL_TOL,
    FIELD_UNITS,
    MOMENT_UNITS,
    NUM_START,
    DriftMode,
    MicroMagData,
    bracketed_units,
    build_curves,
    check_magnitudes,
    decode,
    drift_mode,
    header_number,
    parse_float,
    unit_factor,
    warn_no_calibration,
)

__all__ = ["read_lakeshore_csv"]


def _column_unit(title: str, table: dict[str, float], lineno: int, what: str) -> float:
    for u in reversed(bracketed_units(title)):
        fac = unit_factor(u, table)
        if fac is not None:
            return fac
    raise ValueError(
        f"line {lineno}: cannot tell the unit of the {what} column {title!r} "
        f"(expected one of {', '.join(table)} in brackets)"
    )


def _check_time_order(stamps: list[str], lines: list[int]) -> None:
    """Rows in measurement order: a time stamp never earlier than the row before. Stamps that
    are not all numbers (a clock time, say) are not checked."""
    try:
        times = [float(t) for t in stamps]
    except ValueError:
        return
    for k in range(1, len(times)):
        if times[k] < times[k - 1]:
            raise ValueError(
                f"line {lines[k]}: time stamp {stamps[k]} is earlier than {stamps[k - 1]} on line "
                f"{lines[k - 1]}: rows out of measurement order (sort them by the time stamp)"
            )


def _check_curve_order(curves: list[list[tuple[float, float, int, bool]]]) -> None:
    """Rows in measurement order: the reversal fields of a FORC measurement step one way from
    curve to curve (the way most steps go); the first curve that steps back is refused."""
    revs = [c[0][0] for c in curves]
    steps = np.sign(np.diff(revs))
    way = 1.0 if np.sum(steps) > 0 else -1.0
    for k in np.flatnonzero(steps != way):
        k = int(k)
        trend = "rise" if way > 0 else "fall"
        raise ValueError(
            f"line {curves[k + 1][0][2]}: a curve starts at {revs[k + 1]:.6g} mT after the curve "
            f"at {revs[k]:.6g} mT (line {curves[k][0][2]}), but the reversal fields {trend} from "
            "curve to curve: rows out of measurement order"
        )


def _title_row(cells: list[str]) -> bool:
    """A column-title row: one cell naming a field and another naming a moment, each with a
    unit in brackets or parentheses (a header line such as ``Moment X calibration field: 0.5 T``
    names both in one cell, without brackets, and is no title row)."""
    fields = {i for i, c in enumerate(cells) if bracketed_units(c) and "field" in c.lower()}
    moments = {i for i, c in enumerate(cells) if bracketed_units(c) and "moment" in c.lower()}
    return any(i != j for i in fields for j in moments)


def _header_entry(raw: str) -> tuple[str, str] | None:
    """``key,value`` or ``key: value`` (the 8600 software writes the latter), else ``None``."""
    line = raw.strip()
    colon, comma = line.find(":"), line.find(",")
    if colon > 0 and (comma < 0 or colon < comma):
        return line[:colon].strip(), line[colon + 1 :].strip()
    cells = [c.strip().strip('"') for c in line.split(",")]
    if len(cells) >= 2 and cells[0]:
        return cells[0].rstrip(":"), cells[1]
    return None


def _header_field(key: str, value: str, lineno: int, column_factor: float) -> float | None:
    """A header field value in mT: its unit written after the number (``0.3 T``), else in
    brackets in the key (``Calibration field [T]``), else the field column's unit."""
    num = header_number(value, lineno, key, False)
    if num is None:
        return None
    rest = value[NUM_START.match(value).end() :].strip()
    if rest:
        fac = unit_factor(rest, FIELD_UNITS)
        if fac is None:
            raise ValueError(f"line {lineno}: cannot tell the unit of {key} {value!r}")
        return num * fac
    if bracketed_units(key):
        return num * _column_unit(key, FIELD_UNITS, lineno, "calibration")
    return num * column_factor


def _announced_curves(header: dict[str, str], lines: dict[str, int]) -> tuple[int, int] | None:
    """The header's ``Number of FORCs`` and its line, or ``None``."""
    for k, v in header.items():
        if k.lower() in ("number of forcs", "number of curves"):
            n = header_number(v, lines[k], k, True)
            return None if n is None else (int(n), lines[k])
    return None


def read_lakeshore_csv(path: str | Path, drift_correction: DriftMode = False) -> MicroMagData:
    """Read a Lake Shore 8600-series FORC CSV export (layout assumed in the module docstring).

    Returns the same :class:`MicroMagData` as :func:`read_micromag` (fields in mT, moments in
    A·m²; Pike curves split where the field falls; calibration points recognised by field).
    """
    drift = drift_mode(drift_correction)
    lines = decode(path).splitlines()
    header: dict[str, str] = {}
    header_line: dict[str, int] = {}
    title_line = None
    for idx, raw in enumerate(lines):
        if raw.lstrip().startswith("#"):
            continue  # section titles of the 8600 export: "#FORC MEASUREMENT", "##DATA TABLE ..."
        if _title_row([c.strip().strip('"') for c in raw.split(",")]):
            title_line = idx
            break
        entry = _header_entry(raw)
        if entry is not None:
            header[entry[0]] = entry[1]
            header_line[entry[0]] = idx + 1
    if title_line is None:
        raise ValueError(
            f"{path}: no column-title row naming a field and a moment column with their units "
            "(Lake Shore 8600 FORC CSV)"
        )
    titles = [c.strip().strip('"') for c in lines[title_line].split(",")]
    ln_t = title_line + 1
    i_h = next(i for i, c in enumerate(titles) if "field" in c.lower() and bracketed_units(c))
    i_m = next(i for i, c in enumerate(titles) if "moment" in c.lower() and bracketed_units(c))
    i_status = [i for i, c in enumerate(titles) if "status" in c.lower()]
    flagged = 0  # rows with a status cell other than GOOD
    f_fac = _column_unit(titles[i_h], FIELD_UNITS, ln_t, "field")
    m_fac = _column_unit(titles[i_m], MOMENT_UNITS, ln_t, "moment")
    i_t = next((i for i, c in enumerate(titles) if "time" in c.lower()), None)
    i_seg = next((i for i, c in enumerate(titles) if c.lower() == "segment"), None)
    segments: list[str] = []
    pts: list[tuple[float, float, int]] = []
    written: list[tuple[float, float]] = []  # as written, for check_magnitudes
    stamps: list[str] = []
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
        h_w = parse_float(cells[i_h], idx + 1, "field")
        m_w = parse_float(cells[i_m], idx + 1, "moment")
        written.append((h_w, m_w))
        pts.append((h_w * f_fac, m_w * m_fac, idx + 1))
        if i_t is not None:
            stamps.append(cells[i_t])
        flagged += any(cells[i].upper() != "GOOD" for i in i_status)
        if i_seg is not None:
            segments.append(cells[i_seg])
    if not pts:
        raise ValueError(f"{path}: no data rows after the column titles (line {ln_t})")
    point_lines = [p[2] for p in pts]
    check_magnitudes(
        [("field", [w[0] for w in written]), ("moment", [w[1] for w in written])], point_lines
    )
    _check_time_order(stamps, point_lines)
    h_cal: float | None = None
    for k, v in header.items():
        if k.lower().startswith("calibration field"):
            h_cal = _header_field(k, v, header_line[k], f_fac)
    # calibration points: near HCal, reached by a jump up (> 2 field steps) and followed by a
    # fall (or the end); curves: split where the field falls
    h = np.array([p[0] for p in pts])
    rises = np.diff(h)
    step = float(np.median(rises[rises > 0])) if np.any(rises > 0) else 0.0
    if h_cal is None and h.size > 1 and h[1] < h[0]:
        h_cal = float(h[0])
    tol = max(CAL_REL_TOL * abs(h_cal), CAL_ABS_TOL_MT) if h_cal is not None else 0.0
    blocks: list[list[tuple[float, float, int, bool]]] = []
    if segments:
        # the export numbers its segments: a curve, or a calibration point (one point at HCal)
        for i, p in enumerate(pts):
            if not blocks or segments[i] != segments[i - 1]:
                blocks.append([])
            blocks[-1].append((*p, False))
        for b in blocks:
            if len(b) == 1 and h_cal is not None and abs(b[0][0] - h_cal) <= tol:
                b[0] = (*b[0][:3], True)
    for i, p in enumerate([] if segments else pts):
        is_cal = (
            h_cal is not None
            and abs(p[0] - h_cal) <= tol
            and (i == 0 or p[0] - h[i - 1] > 2 * step)
            and (i == h.size - 1 or h[i + 1] < p[0])
        )
        if is_cal or not blocks or p[0] < blocks[-1][-1][0] or blocks[-1][-1][3]:
            blocks.append([])
        blocks[-1].append((*p, is_cal))
    _check_curve_order([b for b in blocks if not b[0][3]])
    blocks = [[q[:3] for q in b] for b in blocks]
    curves, cal_m, cal_h = build_curves(blocks, h_cal, drift, None, CAL_ABS_TOL_MT)
    warn_no_calibration(path, drift, cal_m is not None)
    rising = sum(f.size >= 2 for f in curves.fields)
    if rising < 2:
        # a loop splits into one-point "curves" on its falling branch and one rising branch
        raise ValueError(
            f"{path}: not a FORC measurement: the field rises over two or more points on "
            f"{rising} stretch{'es' if rising != 1 else ''} only (a hysteresis loop, a "
            "remanence curve or a single sweep; FORCs rise once from every reversal field)"
        )
    notes = []
    complete = True
    announced = _announced_curves(header, header_line)
    if announced is not None and curves.n_curves > announced[0]:
        raise ValueError(
            f"line {announced[1]}: the header announces {announced[0]} FORCs but the file holds "
            f"{curves.n_curves}"
        )
    if announced is not None and curves.n_curves < announced[0]:
        complete = False
        notes.append(
            f"{curves.n_curves} of the {announced[0]} FORCs the header announces (the run "
            "stopped, or an excerpt)"
        )
    if flagged:
        notes.append(f"{flagged} rows with a status other than GOOD (kept as measured)")
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
        complete=complete,
        notes=tuple(notes),
        calibration_fields=cal_h,
    )
