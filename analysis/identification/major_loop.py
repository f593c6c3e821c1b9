"""Hysteresis parameters of the major loop, read from the FORC measurement itself.

First-order reversal curves hold the major loop (Pike convention, fields in the data's unit):

* the **upper (descending) branch** is the set of reversal points ``M(H_r, H_r)`` (each curve
  starts where the descent from positive saturation stopped);
* the **lower (ascending) branch** is the curve of the lowest reversal field (from the most
  negative field, taken as negative saturation);
* the **backfield remanence** after a reversal at ``H_r`` is the moment of that curve at
  ``H = 0`` (the field returned to zero), ``M_d(H_r) = M(H_r, 0)``.

From them, with ``M_0 = (M_top + M_bottom)/2`` the loop's vertical offset (``M_top``: the
upper branch at the highest field, ``M_bottom``: the lower branch at the lowest field):

* ``M_s = (M_top − M_bottom)/2``: half the loop's height at the extreme fields (no slope
  correction: a paramagnetic or diamagnetic slope at high field is part of it);
* ``M_rs = (M_upper(0) − M_lower(0))/2``: the remanence, mean of both branches at ``H = 0``;
* ``B_c``: the mean of ``|H|`` where the two branches cross ``M_0`` (linear interpolation);
* ``B_cr``: ``−H_r`` where the backfield remanence crosses ``M_0`` — only if curves reach
  ``H = 0`` on both sides of the crossing (else ``None``).

Remanence FORCs (``kind="remanence"``) hold no in-field loop: ``M_s`` and ``B_c`` are
``None``; their first points are the backfield remanence ``M_rem(H_r, H_r)``, giving ``B_cr``
and, at the highest reversal field, ``M_rs``. Mayergoyz curves are read through
:meth:`~analysis.identification.ReversalCurves.mirrored` (the mirror image has the same
parameters). For a Preisach model with the density ``N(s; 0, R²) δ(r − p/2)`` every one of them
is known in closed form (``M_s = 1``, ``M_rs = 2Φ(p/2R) − 1``, ``B_c = B_cr = p/2``; tested).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from analysis.identification.curves import ReversalCurves

__all__ = ["HysteresisParameters", "hysteresis_parameters"]


@dataclass(frozen=True)
class HysteresisParameters:
    """``M_s``, ``M_rs`` (moment unit), ``B_c``, ``B_cr`` (field unit); ``None`` where the data
    do not allow it; ``M_rs/M_s`` and ``B_cr/B_c`` (the Day plot's ratios) as properties."""

    ms: float | None
    mrs: float | None
    bc: float | None
    bcr: float | None

    @property
    def mrs_ms(self) -> float | None:
        return self.mrs / self.ms if self.mrs is not None and self.ms else None

    @property
    def bcr_bc(self) -> float | None:
        return self.bcr / self.bc if self.bcr is not None and self.bc else None

    def as_dict(self) -> dict:
        return {**asdict(self), "mrs_ms": self.mrs_ms, "bcr_bc": self.bcr_bc}


def _at(x: np.ndarray, y: np.ndarray, x0: float) -> float | None:
    """``y`` at ``x0`` by linear interpolation (``x`` ascending), ``None`` outside the range."""
    if x.size < 2 or not x[0] <= x0 <= x[-1]:
        return None
    return float(np.interp(x0, x, y))


def _crossing(x: np.ndarray, y: np.ndarray, level: float) -> float | None:
    """The ``x`` where ``y`` crosses ``level``, linear between the bracketing points (the
    crossing nearest the middle of the sign changes, robust to a noisy point); ``None`` if
    ``y − level`` keeps one sign."""
    d = y - level
    change = np.nonzero(np.sign(d[:-1]) * np.sign(d[1:]) <= 0)[0]
    change = change[(d[change] != 0) | (d[change + 1] != 0)]
    if change.size == 0:
        return None
    k = int(change[change.size // 2])
    if d[k] == d[k + 1]:
        return float(x[k])
    return float(x[k] + (x[k + 1] - x[k]) * d[k] / (d[k] - d[k + 1]))


def hysteresis_parameters(curves: ReversalCurves) -> HysteresisParameters:
    """The major loop's ``M_s``, ``M_rs``, ``B_c`` and ``B_cr`` from FORC data (module
    docstring); ``ValueError`` for fewer than two curves."""
    if not isinstance(curves, ReversalCurves):
        raise TypeError(f"curves must be ReversalCurves, got {type(curves).__name__}")
    if curves.n_curves < 2:
        raise ValueError(f"curves must hold at least 2 curves, got {curves.n_curves}")
    if curves.convention != "pike":
        curves = curves.mirrored()
    order = np.argsort(curves.reversal_field, kind="stable")
    hr = np.asarray(curves.reversal_field, dtype=float)[order]
    fields = [np.asarray(curves.fields[k], dtype=float) for k in order]
    moments = [np.asarray(curves.moments[k], dtype=float) for k in order]
    first = np.array([m[0] for m in moments])  # the upper branch (or backfield remanence)
    if curves.kind == "remanence":
        offset = 0.0  # a remanence has no loop offset to remove
        bcr = _crossing(hr, first, offset)
        mrs = float(first[-1]) if hr[-1] >= 0.0 else None
        return HysteresisParameters(None, mrs, None, None if bcr is None else -bcr)
    low_h, low_m = fields[0], moments[0]  # the lower branch: the lowest reversal's curve
    m_top, m_bottom = float(first[-1]), float(low_m[0])
    offset = 0.5 * (m_top + m_bottom)
    ms = 0.5 * (m_top - m_bottom)
    up0, low0 = _at(hr, first, 0.0), _at(low_h, low_m, 0.0)
    mrs = 0.5 * (up0 - low0) if up0 is not None and low0 is not None else None
    c_up, c_low = _crossing(hr, first, offset), _crossing(low_h, low_m, offset)
    bc = 0.5 * (abs(c_up) + abs(c_low)) if c_up is not None and c_low is not None else None
    # backfield remanence: each curve (H_r < 0) at H = 0
    rem = [(h0, _at(f, m, 0.0)) for h0, f, m in zip(hr, fields, moments, strict=True) if h0 < 0]
    rem = [(h0, v) for h0, v in rem if v is not None]
    bcr = None
    if len(rem) >= 2:
        x, y = np.array(rem).T
        cross = _crossing(x, y, offset)
        bcr = None if cross is None else -cross
    for name, v in (("ms", ms), ("bc", bc)):
        if v is not None and not math.isfinite(v):
            raise ValueError(f"curves: the major loop's {name} is not finite (non-finite data)")
    return HysteresisParameters(ms, mrs, bc, bcr)
