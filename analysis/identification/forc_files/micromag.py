"""MicroMag FORC text files (:func:`read_micromag`, :func:`write_micromag`).

The Princeton Measurements (Lake Shore) MicroMag 2900/3900 AGM/VSM FORC text export. What the
reader assumes, from the instrument's public file description and the files FORC software
reads (FORCinel, VARIFORC, FORCsensei):

* **Text.** UTF-8 if the file decodes as such, else cp1252 (a superset of Latin-1 for the
  printable range: ``Am²``, ``µ``, ``°`` in unit lines); LF or CRLF line ends.
* **Title.** Line 1 starts with ``MicroMag``; line 2 names the measurement. Only
  ``First-order reversal curves`` is read; ``Direct moment vs. field; Multiple segments``
  (irregular or remanence FORC protocols: read by
  :mod:`~analysis.identification.forc_files.segments`), remanence curves and hysteresis loops
  are refused
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

Drift correction: see :mod:`analysis.identification.forc_io`.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from analysis.identification.curves import ReversalCurves
from analysis.identification.forc_files.common import (
    CAL_ABS_TOL_MT,
    DATA_LINE,
    END_MARK,
    DriftMode,
    MicroMagData,
    build_curves,
    check_magnitudes,
    decode,
    drift_mode,
    header_number,
    parse_float,
    warn_no_calibration,
)

__all__ = ["read_micromag", "write_micromag", "check_variant"]

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


def check_variant(lines: list[str]) -> None:
    """Refuse (one line) a MicroMag export whose line 2 names a variant this reader does not
    read: a hysteresis loop, a remanence curve, a "Multiple segments" script."""
    if len(lines) > 1:
        kind = lines[1].strip().lower()
        for needle, name in _REFUSED:
            if needle in kind:
                raise ValueError(
                    f"line 2: {name} is not supported; export the measurement as "
                    "'First-order reversal curves'"
                )


def read_micromag(path: str | Path, drift_correction: DriftMode = False) -> MicroMagData:
    """Read a MicroMag FORC text file (Series 0015/0016; see the module docstring).

    Parameters
    ----------
    path:
        The file.
    drift_correction:
        ``False`` (default), ``True``/``"multiplicative"`` or ``"additive"``: linear drift
        correction from the calibration points (:mod:`analysis.identification.forc_io`).

    Returns
    -------
    MicroMagData
        Curves in mT and A·m² when the file states its units.

    Raises
    ------
    ValueError
        One line: the line number and what was expected, or the name of a refused variant.
    """
    drift = drift_mode(drift_correction)
    lines = decode(path).splitlines()
    if not lines:
        raise ValueError(f"{path}: empty file")
    check_variant(lines)
    header: dict[str, str] = {}
    where: dict[str, int] = {}
    names: dict[str, str] = {}
    first_data = None
    for idx, raw in enumerate(lines):
        line = raw.strip()
        if idx > 0 and DATA_LINE.match(line):
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
                return header_number(lower[k], where[k], names[k], integer)
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
    written: list[tuple[float, float, int]] = []  # as written, for check_magnitudes
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
        h = parse_float(tokens[0], lineno, "field")
        mom = parse_float(tokens[1], lineno, "moment")
        if len(tokens) == 3 and tokens[2]:
            parse_float(tokens[2], lineno, "third column")
        written.append((h, mom, lineno))
        current.append((h * f_fac, mom * m_fac, lineno))
    if current:
        blocks.append(current)
    check_magnitudes(
        [("field", [p[0] for p in written]), ("moment", [p[1] for p in written])],
        [p[2] for p in written],
    )
    cal = h_cal * f_fac if h_cal is not None else None
    # with known units a calibration field drifting by a few mT is recognised at any HCal
    curves, cal_m, cal_h = build_curves(
        blocks, cal, drift, n_curves, CAL_ABS_TOL_MT if units else 0.0
    )
    notes = []
    complete = True
    warn_no_calibration(path, drift, cal_m is not None)
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
    out.append(END_MARK)
    path = Path(path)
    path.write_text("\n".join(out) + "\n")
    return path
