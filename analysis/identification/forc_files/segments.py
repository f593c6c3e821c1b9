"""MicroMag "Direct moment vs. field; Multiple segments" exports of irregular FORC protocols.

An irregular FORC protocol (fields spaced unevenly, e.g. evenly in moment) is written as a
script of segments and the points they measured (:func:`read_segments`, :func:`write_segments`).
Layout, as the instrument writes it: line 1 ``MicroMag 2900/3900 Data File ...``, line 2
``Direct moment vs. field; Multiple segments``, a header of ``key  value`` lines (``Units of
measure`` cgs / SI / Hybrid SI as for FORC files), then the ``SCRIPT`` table, one row per segment
``number, averaging time, initial field, field increment, final field, pause, final index``
(``final index``: the number of data points measured up to the end of the segment), then the
data rows ``field, moment`` in measurement order (blank lines between segments).

The FORCs are reconstructed from the script (the commanded fields), the data keep their
measured fields:

* a segment with zero increment measures one point at its field: at the calibration field (the
  largest such field) a calibration point, elsewhere the reversal point that starts a new curve;
* a rising segment (final > initial) measures its points at ``initial + k·increment`` and
  continues the current curve; consecutive segments share their end points, so points measured
  twice at one commanded field are averaged (field and moment);
* a falling segment (the sweep from saturation to the next reversal field), a rising one at
  the calibration field or before the first reversal point measure nothing that belongs to a
  curve and are skipped (counted in the notes).

Remanence FORCs (every field point followed by a point measured back at zero field, written
as single-point segments commanded at 0, or as ramps ``0 -> B -> 0`` measuring both their ends
as the instrument's own scripts do) are recognised from the script (two or more single-point
segments at 0) and reconstructed by :mod:`~analysis.identification.forc_files.remanence`: the
curves are the zero-field moments at the fields of their field points
(``curves.kind == "remanence"``), the in-field moments are kept as
:attr:`MicroMagData.in_field_curves`. In an in-field script a point whose measured field is
farther than 10 % of the calibration field from its commanded field (a zero-field point inside
a rising segment) is refused. Errors name the line.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from analysis.identification.curves import ReversalCurves
from analysis.identification.forc_files.common import (
    DATA_LINE,
    MicroMagData,
    check_curve,
    check_magnitudes,
    decode,
    parse_float,
)
from analysis.identification.forc_files.remanence import (
    is_remanence_script,
    measures_ramps,
    reconstruct_ramps,
    reconstruct_remanence,
    remanence_curves,
)

__all__ = ["read_segments", "write_segments", "SEGMENTS_TITLE"]

SEGMENTS_TITLE = "Direct moment vs. field; Multiple segments"
_UNITS = {"cgs": (0.1, 1e-3), "si": (1e3, 1.0), "hybrid si": (1e3, 1.0)}  # to mT, A·m²
_ROW = re.compile(r"^\s*\d+\s*,")


def read_segments(path: str | Path) -> MicroMagData:
    """Read a "Multiple segments" export into :class:`MicroMagData` (module docstring)."""
    lines = decode(path).splitlines()
    if len(lines) < 2 or not lines[0].lstrip().startswith("MicroMag"):
        raise ValueError("line 1: not a MicroMag export")
    if lines[1].strip() != SEGMENTS_TITLE:
        raise ValueError(f"line 2: expected {SEGMENTS_TITLE!r}")
    units = None
    script: list[tuple[float, float, float, int, int]] = []  # initial, step, final, index, line
    data: list[tuple[float, float, int]] = []
    for lineno, raw in enumerate(lines[2:], start=3):
        line = raw.strip()
        if line.lower().startswith("units of measure"):
            units = line[len("units of measure") :].strip().lower()
        elif _ROW.match(line) and line.count(",") == 6:
            cells = line.split(",")
            initial = parse_float(cells[2], lineno, "initial field")
            step = parse_float(cells[3], lineno, "field increment")
            final = parse_float(cells[4], lineno, "final field")
            index = int(parse_float(cells[6], lineno, "final index"))
            script.append((initial, step, final, index, lineno))
        elif DATA_LINE.match(line) and line.count(",") == 1:
            h, m = line.split(",")
            data.append((parse_float(h, lineno, "field"), parse_float(m, lineno, "moment"), lineno))
    if not script:
        raise ValueError(
            f"line 2: a '{SEGMENTS_TITLE}' export without its SCRIPT table of segments (number, "
            "averaging time, initial field, increment, final field, pause, final index): the "
            "curves cannot be reconstructed"
        )
    if units not in _UNITS:
        raise ValueError(f"{path}: 'Units of measure' must be cgs, SI or Hybrid SI, got {units!r}")
    if script[-1][3] != len(data):
        raise ValueError(
            f"line {script[-1][4]}: the script ends at data index {script[-1][3]}, the file "
            f"holds {len(data)} data points"
        )
    check_magnitudes(
        [("field", [d[0] for d in data]), ("moment", [d[1] for d in data])], [d[2] for d in data]
    )
    f_fac, m_fac = _UNITS[units]
    single = [s[0] for s in script if s[1] == 0.0 and s[0] == s[2]]
    if not single:
        raise ValueError(f"{path}: no single-point segment (calibration or reversal point)")
    h_cal = max(single, key=abs)
    tol = 1e-3 * abs(h_cal)
    if is_remanence_script(script):
        return _read_remanence(path, script, data, units, h_cal, tol)
    curves: list[dict[float, list[tuple[float, float, int]]]] = []
    cal_h, cal_m = [], []
    start = 0
    skipped = 0
    for initial, step, final, index, lineno in script:
        points = data[start:index]
        if index < start:
            raise ValueError(f"line {lineno}: final index {index} goes back (was {start})")
        start = index
        if step == 0.0 and initial == final:
            if len(points) != 1:
                raise ValueError(f"line {lineno}: a single-point segment measured {len(points)}")
            if abs(initial - h_cal) <= tol:
                cal_h.append(points[0][0])
                cal_m.append(points[0][1])
            else:
                curves.append({initial: [points[0]]})
        elif final > initial:
            if not points or not curves or abs(initial - h_cal) <= tol:
                skipped += len(points)  # at saturation, or before the first reversal point
                continue
            n = len(points)
            commanded = initial + step * np.arange(n) if n > 1 else np.array([initial])
            if n > 1 and abs(commanded[-1] - final) > tol:
                raise ValueError(
                    f"line {lineno}: {n} points from {initial} by {step} do not end at {final}"
                )
            for c, p in zip(commanded, points, strict=True):
                if abs(p[0] - c) > 0.1 * abs(h_cal):
                    raise ValueError(
                        f"line {p[2]}: measured field {p[0]} is far from the script's {c} (a "
                        "remanence FORC writes its zero-field points as single-point segments "
                        "at 0, not inside a rising segment)"
                    )
                curves[-1].setdefault(_key(float(c), curves[-1], tol), []).append(p)
        elif points:
            skipped += len(points)  # a falling sweep that measured points: not part of a FORC
    rev, fields, moments = [], [], []
    for curve in curves:
        keys = sorted(curve)
        h = [float(np.mean([p[0] for p in curve[k]])) * f_fac for k in keys]
        m = [float(np.mean([p[1] for p in curve[k]])) * m_fac for k in keys]
        check_curve(h[0], h, [curve[k][0][2] for k in keys], "pike")
        rev.append(h[0])
        fields.append(np.array(h))
        moments.append(np.array(m))
    if not rev:
        raise ValueError(f"{path}: no FORC in the script")
    notes = (
        f"irregular FORC protocol: {len(rev)} curves reconstructed from {len(script)} segments"
        + (f"; {skipped} points at saturation or outside the curves skipped" if skipped else ""),
    )
    curves = ReversalCurves(np.array(rev), tuple(fields), tuple(moments), "pike")
    return _data(curves, units, h_cal, cal_h, cal_m, notes=notes)


def _data(
    curves: ReversalCurves, units: str, h_cal: float, cal_h: list, cal_m: list, **extra: Any
) -> MicroMagData:
    """The record of a segments export: ``curves`` (already in mT and A·m²) and the
    calibration points converted from the file's ``units``; ``extra``: the remaining
    :class:`MicroMagData` fields (notes, completeness, in-field curves)."""
    f_fac, m_fac = _UNITS[units]
    return MicroMagData(
        curves,
        calibration_field=h_cal * f_fac,
        calibration_moments=np.array(cal_m) * m_fac if cal_m else None,
        calibration_fields=np.array(cal_h) * f_fac if cal_h else None,
        field_unit="mT",
        moment_unit="A·m²",
        units_of_measure={"cgs": "cgs", "si": "SI", "hybrid si": "Hybrid SI"}[units],
        **extra,
    )


def _read_remanence(
    path: str | Path, script: list, data: list, units: str, h_cal: float, tol: float
) -> MicroMagData:
    """A remanence FORC script (:mod:`~analysis.identification.forc_files.remanence`)."""
    f_fac, m_fac = _UNITS[units]
    ramps = measures_ramps(script)
    if ramps:
        # the calibration points are the single-point segments at zero field
        h_top = max(max(abs(s[0]), abs(s[2])) for s in script)
        h_cal = 0.0
        result = reconstruct_ramps(script, data, 1e-3 * h_top)
    else:
        result = reconstruct_remanence(script, data, h_cal, tol)
    curves, cal_h, cal_m, _, notes, skipped, complete = result
    if not curves:
        raise ValueError(f"{path}: no remanence FORC in the script")
    rem, in_field = remanence_curves(curves, f_fac, m_fac)
    summary = (
        f"remanence FORC protocol: {rem.n_curves} curves of zero-field moments reconstructed "
        f"from {len(script)} segments"
        + (
            " (ramps measuring both ends; points measured one after another at one commanded "
            "field averaged)"
            if ramps
            else ""
        )
        + (f"; {skipped} points outside the curves skipped" if skipped else "")
    )
    return _data(
        rem,
        units,
        h_cal,
        cal_h,
        cal_m,
        complete=complete,
        notes=(summary, *notes),
        in_field_curves=in_field,
    )


def _key(field: float, curve: dict, tol: float) -> float:
    """The commanded field ``field`` as a key of ``curve`` (equal within ``tol``: the end of
    one segment is the start of the next)."""
    for k in curve:
        if abs(k - field) <= tol:
            return k
    return field


def write_segments(
    path: str | Path,
    curves: ReversalCurves,
    calibration_field: float,
    calibration_moments: np.ndarray,
    remanence: ReversalCurves | None = None,
) -> Path:
    """Write Pike curves (Hybrid SI: fields in T, moments in A·m²) as a "Multiple segments"
    irregular-FORC export: per curve a calibration point, the sweep down to the reversal field,
    the reversal point, then one rising segment between consecutive fields of the curve (two
    points each: both ends, so every inner field is measured twice, as the instrument does).

    With ``remanence`` (the zero-field moments at the same points, ``kind="remanence"``) the
    export is a remanence FORC script instead: per curve a calibration point, the sweep down to
    the reversal field, then for every field of the curve a ramp to it, a single-point segment
    there (the in-field moment of ``curves``), a ramp to zero and a single-point segment at 0
    (the zero-field moment of ``remanence``)."""
    if curves.convention != "pike":
        raise ValueError("a Multiple-segments FORC export holds Pike curves")
    if remanence is not None:
        same = remanence.n_curves == curves.n_curves and all(
            np.array_equal(a, b) for a, b in zip(remanence.fields, curves.fields, strict=True)
        )
        if not same or remanence.kind != "remanence":
            raise ValueError("remanence must be remanence curves at the fields of curves")
    rows, data = [], []

    def segment(initial: float, step: float, final: float, points: list) -> None:
        data.append(points)
        rows.append((initial, step, final, sum(len(d) for d in data)))

    for c, (h, m) in enumerate(zip(curves.fields, curves.moments, strict=True)):
        segment(
            calibration_field, 0.0, calibration_field, [(calibration_field, calibration_moments[c])]
        )
        segment(calibration_field, calibration_field - h[0], h[0], [])
        if remanence is not None:
            for k in range(h.size):
                if k and h[k] != 0.0:
                    segment(0.0, abs(h[k]), h[k], [])
                segment(h[k], 0.0, h[k], [(h[k], m[k])])
                if h[k] != 0.0:
                    segment(h[k], abs(h[k]), 0.0, [])
                segment(0.0, 0.0, 0.0, [(0.0, remanence.moments[c][k])])
            continue
        segment(h[0], 0.0, h[0], [(h[0], m[0])])
        for k in range(h.size - 1):
            segment(h[k], h[k + 1] - h[k], h[k + 1], [(h[k], m[k]), (h[k + 1], m[k + 1])])
    out = [
        "MicroMag 2900/3900 Data File (Series 0016.002)",
        SEGMENTS_TITLE,
        "",
        "INSTRUMENT",
        "Units of measure                Hybrid SI",
        "",
        "SCRIPT",
        f"Number of segments              {len(rows)}",
        f"Number of data                  {rows[-1][3]}",
        "",
    ]
    for k, (a, s, b, idx) in enumerate(rows, 1):
        out.append(
            f"{k:07d},+200.0000E-03,{a * 1e-3:+.15E},{s * 1e-3:+.15E},"
            f"{b * 1e-3:+.15E},+200.0000E-03,{idx:07d}"
        )
    out += ["", "    Field         Moment", "     (T)          (Am²)"]
    for points in data:
        if points:
            out += [f"{h * 1e-3:+.15E},{m:+.15E}" for h, m in points]
            out.append("")
    out.append("MicroMag 2900/3900 Data File ends")
    path = Path(path)
    path.write_text("\r\n".join(out) + "\r\n", encoding="utf-8")
    return path
