"""What the FORC file readers share: the data set they return (:class:`MicroMagData`), text
decoding, numbers with line numbers in the errors, curve checks, calibration points and the
drift correction (described in :mod:`analysis.identification.forc_io`).

Apart from :class:`MicroMagData` and ``DriftMode`` these are helpers of the readers in
:mod:`analysis.identification.forc_files`.
"""

from __future__ import annotations

import inspect
import math
import re
import warnings
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
#: the last line of a MicroMag export (also ending the data sections saved without a header)
END_MARK = "MicroMag 2900/3900 Data File ends"
CAL_ABS_TOL_MT = 5.0  # the measured calibration field drifts by a few mT
DriftMode = str | bool | None
#: field units (lower case, spaces removed) to mT, moment units to A·m², as column titles and
#: header values write them (``[T]``, ``(Am²)``, ``(emu)``, ``0.5 T``)
FIELD_UNITS = {"t": 1e3, "mt": 1.0, "oe": 0.1, "a/m": 4e-4 * math.pi, "ka/m": 0.4 * math.pi}
MOMENT_UNITS = {"a·m²": 1.0, "am²": 1.0, "am2": 1.0, "a·m2": 1.0, "emu": 1e-3}
_UNIT_IN_BRACKETS = re.compile(r"[\[(]([^\])]*)[\])]")


def unit_factor(unit: str, table: dict[str, float]) -> float | None:
    """The factor of ``unit`` (as written: case, spaces and ``^2`` for ``²`` do not matter) in
    ``table`` (:data:`FIELD_UNITS` or :data:`MOMENT_UNITS`), or ``None``."""
    key = unit.strip().lower().replace("^2", "²").replace(" ", "")
    return table.get(key)


def bracketed_units(text: str) -> list[str]:
    """The units written in brackets or parentheses in ``text``, in order
    (``"Field (µ0H) [T]"`` -> ``["µ0H", "T"]``)."""
    return _UNIT_IN_BRACKETS.findall(text)


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
    in_field_curves:
        For remanence FORCs (``curves.kind == "remanence"``): the moments measured in the
        field at the same points, as in-field curves; else ``None``.
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
    in_field_curves: ReversalCurves | None = None


#: leading bytes of the binary and compressed formats a FORC file gets mistaken for
_MAGIC = (
    (b"\x1f\x8b", "gzip-compressed data; decompress it first"),
    (b"PK\x03\x04", "a zip archive or Office document; extract or export the FORC text file"),
    (b"PK\x05\x06", "an empty zip archive"),
    (b"BZh", "bzip2-compressed data; decompress it first"),
    (b"\xfd7zXZ\x00", "xz-compressed data; decompress it first"),
    (b"\x28\xb5\x2f\xfd", "zstd-compressed data; decompress it first"),
    (b"7z\xbc\xaf\x27\x1c", "a 7-Zip archive; extract the FORC text file"),
    (b"\x89PNG\r\n\x1a\n", "a PNG image"),
    (b"\xff\xd8\xff", "a JPEG image"),
    (b"GIF8", "a GIF image"),
    (b"II*\x00", "a TIFF image"),
    (b"MM\x00*", "a TIFF image"),
    (b"%PDF-", "a PDF document"),
    (
        b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1",
        "a legacy Office document (e.g. .xls); export it as text",
    ),
    (b"\x89HDF\r\n\x1a\n", "an HDF5 file"),
)
#: byte-order marks of UTF-32/UTF-16 (UTF-32 first: its LE mark starts with UTF-16's)
_BOMS = (
    (b"\xff\xfe\x00\x00", "utf-32"),
    (b"\x00\x00\xfe\xff", "utf-32"),
    (b"\xff\xfe", "utf-16"),
    (b"\xfe\xff", "utf-16"),
)
_SNIFF = 65536  # bytes (characters) examined for the binary checks
#: C0 control characters that text files do hold (tab, LF, VT, FF, CR, DOS end-of-file)
_TEXT_CONTROLS = frozenset("\t\n\v\f\r\x1a")


def _not_text(path: str | Path, what: str) -> ValueError:
    return ValueError(f"{path}: not a text FORC file ({what})")


def _binary_kind(raw: bytes) -> str | None:
    """What a file that is not text is (magic number, NUL bytes), or ``None``."""
    for magic, what in _MAGIC:
        if raw.startswith(magic):
            if magic == b"BZh" and not raw[4:10] == b"1AY&SY":
                continue  # "BZh" alone could start a text line
            return what
    head = raw[:_SNIFF]
    nul = head.find(b"\x00")
    if nul < 0:
        return None
    even, odd = head[0::2], head[1::2]
    if odd and odd.count(0) > 0.9 * len(odd) and even.count(0) < 0.1 * len(even):
        return "UTF-16 text without a byte-order mark; save it as UTF-8"
    if even and even.count(0) > 0.9 * len(even) and odd.count(0) < 0.1 * len(odd):
        return "UTF-16 text without a byte-order mark; save it as UTF-8"
    return f"binary data: NUL byte at offset {nul}"


def decode(path: str | Path, head: bool = False) -> str:
    """File text: UTF-8 if valid, else cp1252 (Latin-1 for bytes cp1252 leaves undefined);
    UTF-16 and UTF-32 with a byte-order mark are decoded as such.

    Raises a one-line ``ValueError`` ``"PATH: not a text FORC file (WHAT)"`` for content that
    is not text: a compressed, archive, image or document format (by its magic number), NUL
    bytes (UTF-16 without a byte-order mark is named as such), more than 30 % non-ASCII bytes
    in a file that is not UTF-8, or more than 1 % control characters (tab, line ends, form
    feed and the DOS end-of-file mark excepted); the first 64 KiB decide.

    ``head=True`` decodes only the first 64 KiB (up to their last complete line): enough to
    tell a format, without reading a large file.
    """
    with open(path, "rb") as fh:
        raw = fh.read(_SNIFF + 1) if head else fh.read()
    cut = head and len(raw) > _SNIFF
    if cut:
        raw = raw[:_SNIFF]
        if not raw.startswith(tuple(bom for bom, _ in _BOMS)):
            raw = raw[: raw.rfind(b"\n") + 1] or raw  # whole lines (and whole characters)
    text = None
    for bom, codec in _BOMS:
        if raw.startswith(bom):
            try:
                text = raw.decode(codec, errors="ignore" if cut else "strict")
            except UnicodeDecodeError:
                raise _not_text(
                    path, f"{codec.upper()} byte-order mark, but not {codec.upper()}"
                ) from None
            text = text.lstrip("\ufeff")
            break
    if text is None:
        kind = _binary_kind(raw)
        if kind is not None:
            raise _not_text(path, kind)
        try:
            text = raw.decode("utf-8-sig")
        except UnicodeDecodeError:
            head = raw[:_SNIFF]
            high = sum(b >= 0x80 for b in head)
            if high > 0.3 * len(head):
                raise _not_text(
                    path,
                    f"binary data: not UTF-8 and {100 * high / len(head):.0f} % non-ASCII bytes",
                ) from None
            try:
                text = raw.decode("cp1252")
            except UnicodeDecodeError:
                text = raw.decode("latin-1")
    head_text = text[:_SNIFF]
    controls = sum(ch < " " and ch not in _TEXT_CONTROLS for ch in head_text)
    if "\x00" in head_text or controls > 0.01 * len(head_text):
        raise _not_text(path, "binary data: control characters")
    return text


#: a value farther than this many robust spreads from the file's median is refused (see
#: :func:`check_magnitudes`)
ABSURD_SPREADS = 1e6
#: no field (mT, Oe, T, A/m) or moment (A·m², emu) of any instrument comes near this
ABSURD_MAGNITUDE = 1e30


def check_magnitudes(columns: list[tuple[str, list[float] | np.ndarray]], lines: list[int]) -> None:
    """Refuse absurd values: one line naming the first one in file order.

    ``columns`` are ``(name, values)`` of one quantity each (fields, moments: every point,
    calibration points included) as written in the file, ``lines`` the points' line numbers.
    A value is absurd when its magnitude exceeds :data:`ABSURD_MAGNITUDE`, or when it lies more
    than :data:`ABSURD_SPREADS` robust spreads from its column's median, the spread being the
    larger of the interquartile range and the median magnitude (a quarter of the points may be
    wild before it moves). Measured moments stay within a few saturation moments and fields
    within the saturation (or calibration) field, a spread or two from the median; an exponent
    typed wrong (``E+06`` for ``E-06``) is 10¹² away.
    """
    first: tuple[int, str] | None = None
    for name, col in columns:
        values = np.asarray(col, dtype=float)
        if values.size == 0:
            continue
        med = float(np.median(values))
        q25, q75 = np.percentile(values, [25.0, 75.0])
        spread = max(float(q75 - q25), float(np.median(np.abs(values))))
        huge = np.abs(values) > ABSURD_MAGNITUDE
        far = np.abs(values - med) > ABSURD_SPREADS * spread if spread > 0 else huge
        bad = np.flatnonzero(huge | far)
        if bad.size == 0 or (first is not None and lines[bad[0]] >= first[0]):
            continue
        k = int(bad[0])
        if huge[k]:
            why = f"beyond {ABSURD_MAGNITUDE:.0e} in magnitude"
        else:
            why = (
                f"more than {ABSURD_SPREADS:.0e} times the spread ({spread:.3g}) of the file's "
                f"{name}s from their median ({med:.3g})"
            )
        first = (int(lines[k]), f"line {lines[k]}: {name} {values[k]:.6g} is absurd: {why}")
    if first is not None:
        raise ValueError(first[1])


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


_READERS = ("analysis.identification.forc_files", "analysis.identification.forc_io")


def warn_no_calibration(path: str | Path, drift: str | None, has_calibration: bool) -> None:
    """One-line warning when a drift correction was asked of a file without calibration
    points: the curves are returned uncorrected (nothing in the file samples the drift)."""
    if drift is None or has_calibration:
        return
    # point the warning at the first caller outside the readers (read_forc_file or a reader)
    level, frame = 1, inspect.currentframe()
    while frame is not None and frame.f_globals.get("__name__", "").startswith(_READERS):
        level, frame = level + 1, frame.f_back
    warnings.warn(
        f"{path}: drift_correction={drift!r} not applied: the file has no calibration points",
        stacklevel=level,
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
