"""Bifurcation diagrams of forced oscillators with hysteresis (paper fig:bif_0, fig:bif).

For each value of a parameter (the coupling C, or Ω, ζ) the Poincaré section at φ = 0 is
recorded after a transient, and optionally the largest Lyapunov exponent. With continuation
(the paper's procedure) the final state of one value — (q, v) at φ = 0 and the operator's
memory — is the initial state of the next, so the parameter is swept along an attractor in the
order the values are given (the paper steps C downward).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from analysis.dynamics.lyapunov import lyapunov_spectrum
from analysis.dynamics.periods import smallest_period
from hysteresis._progress import progress_bar
from hysteresis._validation import (
    bounded_work,
    finite_array,
    finite_scalar,
    positive_integer,
    real_array,
)
from oscillators import DEFAULT_Q0, DEFAULT_V0

#: most parameter values in one sweep
MAX_VALUES = 1_000_000
#: most forcing periods one sweep may integrate (values × (n_periods + transient_periods))
MAX_SWEEP_PERIODS = 1_000_000_000

__all__ = [
    "BifurcationDiagram",
    "bifurcation_diagram",
    "distinct_points",
    "orbit_period",
    "section_period",
]


def _real(x: Any, name: str, size: int | None = None) -> np.ndarray:
    arr = real_array(x, name).ravel()
    if size is not None and arr.size != size:
        raise ValueError(f"{name} must have the length of q ({size}), got {arr.size}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite (a diverged run has no section points)")
    return arr


def distinct_points(q: np.ndarray, v: np.ndarray | None = None, tolerance: float = 1e-6) -> int:
    """Number of distinct points of a Poincaré section (a periodic orbit of period P has P).

    Two points are the same when they differ by at most ``tolerance`` in every coordinate
    (``q`` alone, or ``q`` and ``v``). Points are grouped greedily in order of ``q``: a new
    group starts where a point is farther than ``tolerance`` from every group opened so far
    within ``tolerance`` in q. A chaotic or quasi-periodic section gives as many groups as
    points (up to near coincidences).
    """
    qa = _real(q, "q")
    pts = qa[:, None] if v is None else np.column_stack([qa, _real(v, "v", qa.size)])
    if pts.shape[0] == 0:
        return 0
    if not tolerance >= 0 or not np.isfinite(tolerance):
        raise ValueError(f"tolerance must be >= 0, got {tolerance}")
    order = np.argsort(pts[:, 0], kind="stable")
    pts = pts[order]
    reps: list[np.ndarray] = []
    start = 0  # index into reps of the first group still within tolerance in q
    for p in pts:
        while start < len(reps) and p[0] - reps[start][0] > tolerance:
            start += 1
        if not any(np.all(np.abs(p - r) <= tolerance) for r in reps[start:]):
            reps.append(p)
    return len(reps)


def orbit_period(
    q: np.ndarray,
    v: np.ndarray | None = None,
    tolerance: float = 1e-6,
    max_period: int | None = None,
) -> int:
    """Smallest P with ``|x_{i+P} − x_i| <= tolerance`` for every i (x = q or (q, v)); 0 if no
    P up to ``max_period`` (default: half the number of points) fits — chaos or a longer period.
    :func:`~analysis.dynamics.periods.smallest_period` (absolute tolerance) of validated
    section coordinates.
    """
    qa = _real(q, "q")
    pts = qa[:, None] if v is None else np.column_stack([qa, _real(v, "v", qa.size)])
    return smallest_period(pts, tolerance, max_period)


def section_period(q: np.ndarray, v: np.ndarray, relative_tolerance: float = 1e-7) -> int:
    """:func:`orbit_period` of a Poincaré section (q, v) with a tolerance relative to its extent
    (at least 1; :func:`~analysis.dynamics.periods.smallest_period` with
    ``relative_to="extent"``): the period test of ensembles, the paper figures and
    ``hyst dimension``.
    """
    qa = _real(q, "q")
    pts = np.column_stack([qa, _real(v, "v", qa.size)])
    return smallest_period(pts, relative_tolerance, relative_to="extent")


@dataclass(frozen=True)
class BifurcationDiagram:
    """Poincaré points and largest Lyapunov exponent per parameter value.

    Attributes
    ----------
    parameter:
        Name of the swept parameter (``"coupling"``, ``"frequency"``, ``"damping_ratio"``).
    values:
        Parameter values in sweep order, shape (n_values,).
    q, v:
        Poincaré section q(φ = 0), v(φ = 0): shape (n_values, n_periods).
    M:
        Output of the operator at the section points, same shape.
    max_exponent:
        λ_max per value (nan where not computed).
    exponents:
        Full spectra per value, shape (n_values, k) (nan where not computed).
    final_states:
        State at the end of each value's section (what continuation passes on).
    """

    parameter: str
    values: np.ndarray
    q: np.ndarray
    v: np.ndarray
    M: np.ndarray
    max_exponent: np.ndarray
    exponents: np.ndarray
    final_states: tuple

    def period_counts(self, tolerance: float = 1e-6, use_velocity: bool = True) -> np.ndarray:
        """:func:`distinct_points` of each value's section."""
        return np.array(
            [
                distinct_points(self.q[i], self.v[i] if use_velocity else None, tolerance)
                for i in range(self.values.size)
            ]
        )

    def periods(self, tolerance: float = 1e-6) -> np.ndarray:
        """:func:`orbit_period` of each value's section (0: none found)."""
        return np.array(
            [orbit_period(self.q[i], self.v[i], tolerance) for i in range(self.values.size)]
        )

    def save(self, path: str | Path) -> Path:
        """Write the arrays to an ``.npz`` file (no states)."""
        path = Path(path)
        np.savez_compressed(
            path,
            parameter=np.array(self.parameter),
            values=self.values,
            q=self.q,
            v=self.v,
            M=self.M,
            max_exponent=self.max_exponent,
            exponents=self.exponents,
        )
        return path


def bifurcation_diagram(
    make_system: Callable[[float], Any],
    parameter_values: Sequence[float] | np.ndarray,
    n_periods: int,
    transient_periods: int,
    continuation: bool = True,
    lyapunov: bool = True,
    lyapunov_t_end: float = 1000.0,
    q0: float = DEFAULT_Q0,
    v0: float = DEFAULT_V0,
    operator_state: Any = None,
    parameter: str = "coupling",
    progress: bool = False,
) -> BifurcationDiagram:
    """Sweep a parameter in the given order and record the Poincaré section at each value.

    Parameters
    ----------
    make_system:
        ``value -> ForcedOscillator``, e.g. ``lambda c: ForcedOscillator(dimers, c)``. Every
        system must share the operator (continuation passes the operator state on).
    parameter_values:
        Values in sweep order (the paper: C stepped downward).
    n_periods, transient_periods:
        Section points recorded per value, after this many forcing periods.
    continuation:
        Start each value from the previous value's final state (q, v at φ = 0 and operator
        memory); otherwise every value starts from ``(q0, v0, operator_state)``.
    lyapunov:
        Also compute the spectrum over ``lyapunov_t_end`` time units, started on the attractor
        (from the end of the section); ``max_exponent`` is its largest exponent.
    q0, v0, operator_state:
        Initial condition of the first value (and of all values without continuation).
    parameter:
        Name of the swept parameter (labels only).
    progress:
        Show a progress bar over the values (off by default; the CLI turns it on).
    """

    if not callable(make_system):
        raise TypeError(f"make_system must be a callable value -> system, got {make_system!r}")
    values = finite_array(parameter_values, "parameter_values", ndim=1)
    n_periods = positive_integer(n_periods, "n_periods")
    transient_periods = positive_integer(transient_periods, "transient_periods", minimum=0)
    # refuse up front what cannot finish: the sweep integrates values × periods
    bounded_work(values.size, "parameter_values", MAX_VALUES, "parameter values")
    bounded_work(
        values.size * (n_periods + transient_periods),
        "n_periods",
        MAX_SWEEP_PERIODS,
        "forcing periods in the sweep",
    )
    lyapunov_t_end = finite_scalar(lyapunov_t_end, "lyapunov_t_end")
    if lyapunov and not lyapunov_t_end > 0:
        raise ValueError(f"lyapunov_t_end must be > 0, got {lyapunov_t_end}")
    q0 = finite_scalar(q0, "q0")
    v0 = finite_scalar(v0, "v0")
    if not isinstance(parameter, str):
        raise TypeError(
            f"parameter must be a string (the swept parameter's name), got {parameter!r}"
        )
    qs = np.empty((values.size, n_periods))
    vs = np.empty_like(qs)
    ms = np.empty_like(qs)
    lam_max = np.full(values.size, np.nan)
    spectra: list[np.ndarray | None] = []
    finals = []
    state_q, state_v, state_op = float(q0), float(v0), operator_state
    for i, value in enumerate(
        progress_bar(values, desc=f"bifurcation {parameter}", disable=not progress)
    ):
        system = make_system(float(value))
        sec = system.poincare_section(n_periods, transient_periods, state_q, state_v, state_op)
        qs[i], vs[i], ms[i] = sec.q, sec.v, sec.M
        finals.append(sec.final)
        if lyapunov:
            ly = lyapunov_spectrum(
                system,
                float(lyapunov_t_end),
                0.0,
                sec.final.q,
                sec.final.v,
                sec.final.operator_state,
                progress=False,
            )
            lam_max[i] = ly.max_exponent
            spectra.append(np.asarray(ly.exponents, dtype=float))
        else:
            spectra.append(None)
        if continuation:
            # the section ends at φ = 0 mod 2π, so (q, v, memory) is a valid start at φ = 0
            state_q, state_v, state_op = sec.final.q, sec.final.v, sec.final.operator_state
    width = max((s.size for s in spectra if s is not None), default=0)
    exps = np.full((values.size, width), np.nan)
    for i, s in enumerate(spectra):
        if s is not None:
            exps[i, : s.size] = s
    return BifurcationDiagram(
        parameter=parameter,
        values=values,
        q=qs,
        v=vs,
        M=ms,
        max_exponent=lam_max,
        exponents=exps,
        final_states=tuple(finals),
    )
