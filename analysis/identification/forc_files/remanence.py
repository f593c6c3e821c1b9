"""Remanence FORCs in MicroMag "Multiple segments" exports: every field point of a FORC is
followed by a point measured back at zero field (remFORC: Zhao et al. 2017, "Magnetic domain
state diagnosis using hysteresis reversal curves").

The physics of the curves (which relays the zero-field moment remembers, the remanent FORC
density) is in :mod:`analysis.identification.curves`. This module reconstructs them from the
segment script that :mod:`~analysis.identification.forc_files.segments` parses:

* a script is a remanence FORC script when it holds two or more single-point segments
  commanded at exactly zero field (an in-field protocol has at most one, at a reversal field
  of 0, since reversal fields are distinct; the calibration field is never 0);
* a single-point segment at the calibration field is a calibration point and closes the
  current curve, unless an odd number of zero-field points follows it (zero-field points come
  in pairs, the field point at ``B = 0`` and its remanence point, so the odd one is the
  remanence point of a field point at the calibration field);
* any other single-point segment at a non-zero field ``B`` is a field point; it starts a new
  curve (``B`` is its reversal field ``B_a``) after a calibration point or when ``B`` is not
  above the current curve's last field, and continues the current curve otherwise;
* the single-point segment at zero field that follows a field point is its remanence point
  (a zero-field point that follows none is the field point at ``B = 0``, whose remanence
  point comes next):
  the curve gets the point ``(B measured in the field, moment measured at zero field)``; the
  in-field moment at ``B`` is kept as the companion in-field curve;
* for ``B_a <= 0`` both kinds of points are first-order: the excursion to zero field and back
  is a minor loop closed by the next, higher field (return-point memory). For ``B_a > 0`` the
  excursion to zero field goes below ``B_a`` and erases the reversal, so the in-field
  companions there are not FORC points (the zero-field moments are: nothing at zero field
  depends on ``B_a > 0``, the remanent density vanishes there either way);
* segments without points (the ramps between the fields and zero, the sweep from saturation)
  are skipped; a segment measuring several points cannot interleave zero-field points and is
  refused, as is a field point followed by another field point. A field point left without
  its zero-field point at the end of the file (an aborted run) is dropped and noted.

The instrument's own remanence scripts (tests/data/forc_public/, recognised by
:func:`measures_ramps`: ramps that measure points) measure differently and are reconstructed by
:func:`reconstruct_ramps`: every ramp ``0 -> B`` and ``B -> 0`` is one step long and measures
both its ends, and a single-point segment at zero field follows the excursion to the
saturating field that ends every curve. There

* the points of one commanded field measured one after another (the end of a ramp and the
  start of the next) are one *station*, their fields and moments averaged (the zero-field
  station after ``B`` thus averages the point at the end of the ramp back, whose field
  overshoots zero by up to about 0.5 % of ``B``, and the settled start of the next ramp);
* a station at a non-zero field is a field point; the zero-field station after it is its
  remanence point; the curve rules are those above (a new curve after a calibration point or
  when the field is not above the curve's last);
* the single-point segment at zero field (with the start of the ramp after it) is a
  calibration point, at ``calibration_field = 0`` (the remanence after saturation, measured
  before every curve); a field point at the saturating field (the largest commanded field)
  that would start a curve (the excursion before the first calibration point) has no reversal
  before it and is skipped with its zero-field point, counted in the notes;
* a measured field farther than 10 % of the largest commanded field from its commanded field
  means the data do not follow the script and is refused.
"""

from __future__ import annotations

import numpy as np

from analysis.identification.curves import ReversalCurves
from analysis.identification.forc_files.common import check_curve

__all__ = [
    "is_remanence_script",
    "measures_ramps",
    "reconstruct_remanence",
    "reconstruct_ramps",
    "remanence_curves",
]

Point = tuple[float, float, int]  # field, moment, line
Segment = tuple[float, float, float, int, int]  # initial, increment, final, final index, line


def _single(segment: Segment) -> bool:
    return segment[1] == 0.0 and segment[0] == segment[2]


def is_remanence_script(script: list[Segment]) -> bool:
    """Two or more single-point segments commanded at exactly zero field."""
    return sum(_single(s) and s[0] == 0.0 for s in script) >= 2


def reconstruct_remanence(
    script: list[Segment], data: list[Point], h_cal: float, tol: float
) -> tuple[list, list, list, list, list, int, bool]:
    """Curves of a remanence script (module docstring): ``(curves, calibration fields,
    calibration moments, calibration lines, notes, skipped points, complete)``; each curve is
    a list of ``(field point, zero-field point)`` pairs in the file's units."""
    curves: list[list[tuple[Point, Point]]] = []
    cal_h, cal_m, cal_lines = [], [], []
    pending: tuple[float, Point] | None = None  # commanded field and its in-field point
    last_commanded: float | None = None  # of the current curve, None after a calibration
    start = 0
    skipped = 0
    # zero-field points pair up as (field point at B = 0, its remanence point), so a point at
    # the calibration field followed by an odd run of zero-field points is a field point
    measuring = [k for k, s in enumerate(script) if s[3] > (script[k - 1][3] if k else 0)]
    zero_run: dict[int, int] = {}
    run = 0
    for k in reversed(measuring):
        zero_run[k] = run
        run = run + 1 if script[k][0] == 0.0 and _single(script[k]) else 0
    for k, (initial, step, final, index, lineno) in enumerate(script):
        if index < start:
            raise ValueError(f"line {lineno}: final index {index} goes back (was {start})")
        points = data[start:index]
        start = index
        if not points:
            continue  # a ramp between the fields and zero, or the sweep from saturation
        if not _single((initial, step, final, index, lineno)):
            if len(points) > 1:
                raise ValueError(
                    f"line {lineno}: a remanence FORC script measures one point per segment "
                    f"(each field point followed by a zero-field point); this segment "
                    f"measures {len(points)}"
                )
            skipped += len(points)
            continue
        if len(points) != 1:
            raise ValueError(f"line {lineno}: a single-point segment measured {len(points)}")
        p = points[0]
        if abs(initial - h_cal) <= tol and zero_run[k] % 2 == 0:
            if pending is not None:
                raise ValueError(
                    f"line {pending[1][2]}: the field point has no zero-field (remanence) point "
                    "after it"
                )
            cal_h.append(p[0])
            cal_m.append(p[1])
            cal_lines.append(p[2])
            last_commanded = None
        elif initial == 0.0 and pending is not None:
            commanded, q = pending
            if last_commanded is None or commanded <= last_commanded:
                curves.append([])
            curves[-1].append((q, p))
            last_commanded = commanded
            pending = None
        else:
            if pending is not None:
                raise ValueError(
                    f"line {pending[1][2]}: the field point has no zero-field (remanence) point "
                    "after it"
                )
            pending = (initial, p)
    notes, complete = _finish(curves, pending)
    return curves, cal_h, cal_m, cal_lines, notes, skipped, complete


def measures_ramps(script: list[Segment]) -> bool:
    """Whether the script's ramps (segments that are not single-point) measure points: the
    layout of the instrument's own remanence FORC scripts (module docstring)."""
    before = 0
    for s in script:
        if not _single(s) and s[3] > before:
            return True
        before = s[3]
    return False


def _ramp_stations(script: list[Segment], data: list[Point], tol: float, h_top: float) -> list:
    """The measuring stations of a ramp script: ``[commanded field, points, single]`` in order;
    a ramp's first point joins the station before it when commanded at the same field."""
    stations: list[list] = []
    start = 0
    for initial, step, final, index, lineno in script:
        if index < start:
            raise ValueError(f"line {lineno}: final index {index} goes back (was {start})")
        points = data[start:index]
        start = index
        if not points:
            continue  # the sweep from saturation
        single = step == 0.0 and initial == final
        if single and len(points) != 1:
            raise ValueError(f"line {lineno}: a single-point segment measured {len(points)}")
        if not single and len(points) < 2:
            raise ValueError(
                f"line {lineno}: a ramp from {initial} to {final} measured {len(points)} point; "
                "the ramps of a remanence FORC script measure both their ends"
            )
        way = 1.0 if final >= initial else -1.0
        commanded = [initial + way * abs(step) * k for k in range(len(points))]
        if abs(commanded[-1] - final) > tol:
            raise ValueError(
                f"line {lineno}: {len(points)} points from {initial} by {step} do not end at "
                f"{final}"
            )
        for k, (c, p) in enumerate(zip(commanded, points, strict=True)):
            if abs(p[0] - c) > 0.1 * h_top:
                raise ValueError(
                    f"line {p[2]}: measured field {p[0]} is far from the script's {c}: the data "
                    "do not follow the script"
                )
            if k == 0 and not single and stations and abs(stations[-1][0] - c) <= tol:
                stations[-1][1].append(p)  # the ramp starts where the segment before ended
            else:
                stations.append([c, [p], single])
    return stations


def reconstruct_ramps(
    script: list[Segment], data: list[Point], tol: float
) -> tuple[list, list, list, list, list, int, bool]:
    """Curves of a remanence script whose ramps measure their ends (module docstring), in the
    return layout of :func:`reconstruct_remanence`; each point of a curve is a station's mean
    (field, moment, line of its first point)."""
    h_top = max(max(abs(s[0]), abs(s[2])) for s in script)
    h_sat = max(max(s[0], s[2]) for s in script)  # where every curve ends, before calibration
    curves: list[list[tuple[Point, Point]]] = []
    cal_h, cal_m, cal_lines = [], [], []
    pending: tuple[float, Point, int] | None = None
    last_commanded: float | None = None
    skipped = 0
    for commanded, points, single in _ramp_stations(script, data, tol, h_top):
        p = (
            float(np.mean([q[0] for q in points])),
            float(np.mean([q[1] for q in points])),
            points[0][2],
        )
        if abs(commanded) > tol:
            if pending is not None:
                raise ValueError(
                    f"line {pending[1][2]}: the field point has no zero-field (remanence) point "
                    "after it"
                )
            pending = (commanded, p, len(points))
        elif pending is not None:
            field, q, n_q = pending
            pending = None
            if last_commanded is None and abs(field - h_sat) <= tol:
                skipped += n_q + len(points)  # a saturating excursion: no reversal before it
                continue
            if last_commanded is None or field <= last_commanded:
                curves.append([])
            curves[-1].append((q, p))
            last_commanded = field
        elif single:
            cal_h.append(p[0])
            cal_m.append(p[1])
            cal_lines.append(p[2])
            last_commanded = None
        else:
            skipped += len(points)  # at zero field before any field point
    notes, complete = _finish(curves, pending)
    return curves, cal_h, cal_m, cal_lines, notes, skipped, complete


def _finish(curves: list, pending: tuple | None) -> tuple[list[str], bool]:
    """The end of both reconstructions: a field point still waiting for its zero-field point
    means the run stopped (a note, ``complete`` false); every curve is checked."""
    notes = []
    if pending is not None:
        notes.append(
            f"the last field point (line {pending[1][2]}) has no zero-field point (the run "
            "stopped): dropped"
        )
    for curve in curves:
        fields = [q[0] for q, _ in curve]
        check_curve(fields[0], fields, [q[2] for q, _ in curve], "pike")
    return notes, pending is None


def remanence_curves(
    curves: list[list[tuple[Point, Point]]], f_fac: float, m_fac: float
) -> tuple[ReversalCurves, ReversalCurves]:
    """The remanence curves and their in-field companions, converted (``f_fac``, ``m_fac``)."""
    rev, fields, rem, inf = [], [], [], []
    for curve in curves:
        h = np.array([q[0] for q, _ in curve]) * f_fac
        rev.append(h[0])
        fields.append(h)
        rem.append(np.array([z[1] for _, z in curve]) * m_fac)
        inf.append(np.array([q[1] for q, _ in curve]) * m_fac)
    rev_a = np.array(rev)
    return (
        ReversalCurves(rev_a, tuple(fields), tuple(rem), "pike", "remanence"),
        ReversalCurves(rev_a, tuple(fields), tuple(inf), "pike", "in-field"),
    )
