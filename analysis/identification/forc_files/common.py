"""What the FORC file readers share: the data set they return (:class:`MicroMagData`), text
decoding, numbers with line numbers in the errors, curve checks, calibration points and the
drift correction (described in :mod:`analysis.identification.forc_io`).

Apart from :class:`MicroMagData` and ``DriftMode`` these are helpers of the readers in
:mod:`analysis.identification.forc_files`.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from analysis.identification.curves import ReversalCurves

__all__ = ["MicroMagData", "DriftMode"]

NUM = r"[+\-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+\-]?\d+)?"
#: a ``field,moment`` data line
DATA_LINE = re.compile(rf"^\s*{NUM}\s*,\s*\S")
NUM_START = re.compile(rf"^\s*({NUM})")
CAL_REL_TOL = 0.05
CAL_ABS_TOL_MT = 5.0  # the measured calibration field drifts by a few mT
DriftMode = str | bool | None


def parse_float(token: str, lineno: int, what: str) -> float:
    try:
        value = float(token)
    except ValueError:
        raise ValueError(f"line {lineno}: {what} {token.strip()!r} is not a number") from None
    if not math.isfinite(value):
        raise ValueError(f"line {lineno}: {what} must be finite, got {token.strip()!r}")
    return value


def check_curve(rev: float, fields: list[float], lines: list[int], convention: str) -> None:
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


def infer_convention(curves: list[tuple[float, list[float], list[float], list[int]]]) -> str:
    for _, h, _, _ in curves:
        if len(h) >= 2:
            return "mayergoyz" if h[1] < h[0] else "pike"
    raise ValueError("cannot infer the convention (every curve has one point); pass convention=")


def is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


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


def decode(path: str | Path) -> str:
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


def drift_mode(drift_correction: DriftMode) -> str | None:
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


def header_number(text: str, lineno: int, key: str, integer: bool) -> float | int | None:
    """Leading number of a header value (``N/A`` → None)."""
    if text.strip().upper().startswith("N/A"):
        return None
    m = NUM_START.match(text)
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


def apply_drift(
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


def build_curves(
    blocks: list[list[tuple[float, float, int]]],
    h_cal: float | None,
    drift: str | None,
    max_curves: int | None,
    abs_tol: float = 0.0,
) -> tuple[ReversalCurves, np.ndarray | None, np.ndarray | None]:
    """Split blocks into calibration points and Pike curves; validate; correct drift."""
    cal_m, cal_h, cal_t, cal_lines = [], [], [], []
    curves: list[list[tuple[float, float, int]]] = []
    tol = max(CAL_REL_TOL * abs(h_cal), abs_tol) if h_cal is not None else 0.0
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
            check_curve(block[0][0], [p[0] for p in block], [p[2] for p in block], "pike")
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
        check_curve(h[0], h, ln, "pike")
        revs.append(h[0])
        fields_.append(np.array(h))
        moments.append(np.array([p[1] for p in block]))
        times.append(np.array(ln, dtype=float))
    cm = np.array(cal_m)
    moments = apply_drift(drift, moments, times, cm, np.array(cal_t, dtype=float), cal_lines)
    rc = ReversalCurves(np.array(revs), tuple(fields_), tuple(moments), "pike")
    return rc, (cm if cal_m else None), (np.array(cal_h) if cal_h else None)
