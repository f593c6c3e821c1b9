"""The period of a Poincaré section: one test, ``|x_{i+k} − x_i| <= tolerance``.

A section ``x_0, x_1, …, x_{n−1}`` (points of one or more coordinates) has period ``k`` when
every pair ``k`` apart agrees within the tolerance in every coordinate, i.e. when its *return
distance* ``max_i |x_{i+k} − x_i|_∞`` is at most the tolerance. Every period test of the
toolkit is this one, with three choices made explicit as parameters of
:func:`smallest_period`:

* the tolerance is absolute, or relative to the section's ``extent`` (its largest
  peak-to-peak range over the coordinates, at least 1: a cycle's scale, for the sections
  whose size depends on the parameters) or to its ``magnitude`` (``max|x|``, at least 1: for a
  refined orbit whose points are known to round-off relative to their size);
* the candidates are ``1 … max_period`` (default ``n // 2``: the cycle seen at least twice),
  or only the divisors of a given length (a closed orbit of ``k`` points repeats after a
  divisor of ``k``, never after another lag);
* the answer is the *smallest* fitting period, 0 when none fits (chaos, quasi-periodic motion,
  a longer period, a transient still decaying).

Beside it: :func:`return_distances` (the distance itself for every lag: the closest return
when no period fits) and :func:`transient_length` (from which point on a period holds).

NaN coordinates are allowed and never agree with anything (an orbit point whose memory has
another structure is "not the same point").
"""

from __future__ import annotations

import math

import numpy as np

from hysteresis._validation import nonnegative_integer, positive_integer, real_array

__all__ = [
    "RELATIVE_TO",
    "return_distances",
    "section_extent",
    "smallest_period",
    "transient_length",
]

#: what a tolerance may be relative to: ``None`` (absolute), the section's ``"extent"`` or its
#: ``"magnitude"`` (see :func:`smallest_period`)
RELATIVE_TO = (None, "extent", "magnitude")


def _points(points: np.ndarray) -> np.ndarray:
    """``points`` as an (n, d) float array (a 1-D section is one coordinate)."""
    pts = points if isinstance(points, np.ndarray) and points.dtype == np.float64 else None
    if pts is None:
        pts = real_array(points, "points")
    if pts.ndim == 1:
        return pts[:, None]
    if pts.ndim != 2:
        raise ValueError(f"points must be 1-D or 2-D (n points × d coordinates), got {pts.ndim}-D")
    return pts


def section_extent(points: np.ndarray) -> float:
    """``max(ptp(x_1), …, ptp(x_d), 1)``: the largest peak-to-peak range of a coordinate, at
    least 1 (the scale of a section's cycle; 1 keeps a tolerance meaningful for a section that
    has shrunk to a point)."""
    pts = _points(points)
    return max(*(float(np.ptp(pts[:, j])) for j in range(pts.shape[1])), 1.0)


def _scale(pts: np.ndarray, relative_to: str | None) -> float:
    if relative_to is None:
        return 1.0
    if relative_to == "extent":
        return section_extent(pts)
    # "magnitude"; a NaN coordinate makes np.max NaN and max(1.0, nan) is 1.0
    return max(1.0, float(np.max(np.abs(pts))))


def smallest_period(
    points: np.ndarray,
    tolerance: float,
    max_period: int | None = None,
    *,
    relative_to: str | None = None,
    divisors_of: int | None = None,
) -> int:
    """The smallest ``k`` with ``|x_{i+k} − x_i| <= tol`` in every coordinate for every ``i``;
    0 if no candidate fits.

    Plain reading::

        for k in 1 .. min(max_period, n − 1):
            if divisors_of is None or divisors_of % k == 0:
                if max_i |x_{i+k} − x_i|_∞ <= tol: return k
        return 0

    The pairs of the last point are checked first for every k at once: a k whose last pair
    already differs is out (most of them on an aperiodic section), so the full check runs only
    for the others (the same answer, faster).

    Parameters
    ----------
    points:
        The section, shape (n,) or (n, d), in orbit order.
    tolerance:
        ``tol`` itself (``relative_to=None``), or its factor: ``tol = tolerance · scale``.
    max_period:
        Largest candidate (default ``n // 2``: the cycle is seen at least twice); never more
        than ``n − 1`` (a lag needs a pair).
    relative_to:
        ``None`` (absolute), ``"extent"`` (scale :func:`section_extent`) or ``"magnitude"``
        (scale ``max(1, max|x|)``).
    divisors_of:
        Only candidates that divide this number (the length of a closed orbit).
    """
    pts = _points(points)
    tol = float(tolerance)
    if not (tol >= 0.0 and math.isfinite(tol)):
        raise ValueError(f"tolerance must be finite and >= 0, got {tolerance}")
    if relative_to not in RELATIVE_TO:
        raise ValueError(f"relative_to must be one of {RELATIVE_TO}, got {relative_to!r}")
    n = pts.shape[0]
    top = n // 2 if max_period is None else nonnegative_integer(max_period, "max_period")
    if divisors_of is not None:
        divisors_of = positive_integer(divisors_of, "divisors_of")
    top = min(top, n - 1)
    if top < 1:
        return 0
    if relative_to is not None:
        tol = tol * _scale(pts, relative_to)
    last = np.all(np.abs(pts[-1] - pts[-2 : -top - 2 : -1]) <= tol, axis=1)
    for k in np.flatnonzero(last) + 1:
        if divisors_of is not None and divisors_of % k:
            continue
        if np.all(np.abs(pts[k:] - pts[:-k]) <= tol):
            return int(k)
    return 0


def return_distances(points: np.ndarray, max_period: int) -> np.ndarray:
    """``max_i |x_{i+k} − x_i|_∞`` for ``k = 1 … max_period`` (entry ``k − 1``): how close the
    section comes back after k points. :func:`smallest_period` is the first k whose distance
    is within the tolerance; the argmin is the closest return."""
    pts = _points(points)
    max_period = positive_integer(max_period, "max_period")
    if max_period > pts.shape[0] - 1:
        raise ValueError(
            f"max_period must be <= the number of points - 1 = {pts.shape[0] - 1}, got {max_period}"
        )
    return np.array([np.max(np.abs(pts[k:] - pts[:-k])) for k in range(1, max_period + 1)])


def transient_length(points: np.ndarray, period: int, tolerance: float) -> int:
    """The first index ``j`` with ``|x_{i+k} − x_i| <= tolerance`` (every coordinate) for every
    ``i >= j``, ``k = period``: the section has come within the tolerance of its cycle and
    stays there (0: from the start)."""
    pts = _points(points)
    k = positive_integer(period, "period")
    bad = np.any(np.abs(pts[k:] - pts[:-k]) > tolerance, axis=1)
    idx = np.flatnonzero(bad)
    return int(idx[-1] + 1) if idx.size else 0
