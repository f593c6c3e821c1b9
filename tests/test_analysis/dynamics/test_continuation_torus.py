"""Torus (Neimark–Sacker) detection in continuation, against direct orbit computations.

A play with negative coupling pumps energy through its hysteresis loop: along a loop the play
output w is ``q − p/2`` rising and ``q + p/2`` falling, so ``∮ w dq = −p·(q_max − q_min) < 0``
and the work ``C ∮ w dq`` the force ``C·w`` does per cycle is positive for ``C < 0`` (negative
damping, linear in the amplitude, against the viscous loss ``2ζ∮v dq``). Away from resonance
(Ω = 0.5) the forced period-1 orbit loses stability as ``C`` decreases through a complex pair
of multipliers crossing the unit circle: a Neimark–Sacker bifurcation.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.optimize import brentq

from analysis.dynamics.bifurcation import orbit_period
from analysis.dynamics.continuation import continue_orbit
from analysis.dynamics.periodic_orbits import find_periodic_orbit, refine_periodic_orbit
from hysteresis import PlayOperator
from oscillators import ForcedOscillator

WIDTH, ZETA, OMEGA = 1.0, 0.05, 0.5


def _system(coupling: float) -> ForcedOscillator:
    return ForcedOscillator(PlayOperator(WIDTH), coupling, ZETA, OMEGA)


def _section(system: ForcedOscillator, state, n: int, skip: int) -> np.ndarray:
    """(q, v) at the section after ``skip`` periods, ``n`` points."""
    eng = system.engine(state)
    eng.advance(np.array([skip * system.period]))
    out = np.empty((n, len(eng.sample_columns)))
    eng.advance((skip + np.arange(1, n + 1)) * system.period, out)
    return out[:, :2]


def test_torus_event_located_and_checked_by_direct_runs():
    start = _system(-0.3)
    orbit = find_periodic_orbit(start, transient=300, max_period=4)
    assert orbit.period == 1 and orbit.stable and not orbit.frozen
    branch = continue_orbit(start, orbit, -0.3, -0.5, step=0.02)
    tori = [e for e in branch.events if e.kind == "torus"]
    assert len(tori) == 1, [(e.kind, e.parameter) for e in branch.events]
    torus = tori[0]
    mu = torus.multipliers[np.argmax(np.abs(torus.multipliers))]
    print("torus at C =", repr(torus.parameter), "multiplier", mu, "bracket", torus.bracket)
    # a complex pair on the unit circle (not a strong resonance: arg μ far from 0, π, 2π/3, π/2)
    assert abs(mu.imag) > 0.5 and abs(abs(mu) - 1.0) < 1e-6

    # independent location: |μ| − 1 of orbits refined at fixed C, root bracketed by
    # C = −0.40 (|μ| = 0.989) and −0.45 (1.040) and found by brentq to 1e-12; |μ| is computed
    # to ~1e-9 (Newton tolerance 1e-10 times the conditioning) and d|μ|/dC ≈ −1, so the root
    # is good to ~1e-9 in C; the continuation locates within its 1e-8 bracket
    def excess(c: float) -> float:
        return refine_periodic_orbit(_system(c), orbit.start, 1).max_abs_multiplier - 1.0

    c_ns = brentq(excess, -0.45, -0.40, xtol=1e-12)
    print("direct |μ| = 1 at C =", repr(c_ns))
    assert torus.bracket[1] - torus.bracket[0] <= 1e-8
    assert abs(torus.parameter - c_ns) <= 1e-8 + 1e-9

    # just before (C_ns + 0.01, |μ| ≈ 0.99): a start 1e-3 off the orbit converges to it
    # (0.99^3000 ≈ 1e-13 of the initial offset)
    before = _system(c_ns + 0.01)
    fixed = refine_periodic_orbit(before, orbit.start, 1)
    x0 = fixed.start
    pts = _section(before, replace(x0, v=x0.v + 1e-3), 10, 3000)
    assert np.max(np.abs(pts - fixed.points[0, :2])) < 1e-10

    # just beyond (C_ns − 0.02): the same start leaves the unstable orbit for an invariant
    # closed curve: no period <= 50 (relative tolerance 1e-3 of its extent), the points go
    # round the unstable fixed point (star-shaped: every point at least 10 % of the extent
    # away from it, angular gaps below 0.1 rad with 1000 points), and neighbours in angle are
    # close (a curve, not a cloud: jumps below 5 % of the extent)
    beyond = _system(c_ns - 0.02)
    center = refine_periodic_orbit(beyond, orbit.start, 1)
    assert not center.stable
    pts = _section(beyond, replace(center.start, v=center.start.v + 1e-3), 1000, 3000)
    extent = float(np.max(np.ptp(pts, axis=0)))
    assert extent > 0.1
    assert orbit_period(pts[:, 0], pts[:, 1], 1e-3 * extent, max_period=50) == 0
    rel = pts - center.points[0, :2]
    assert np.min(np.hypot(rel[:, 0], rel[:, 1])) > 0.1 * extent
    angle = np.arctan2(rel[:, 1], rel[:, 0])
    order = np.argsort(angle)
    gaps = np.diff(np.append(angle[order], angle[order[0]] + 2.0 * np.pi))
    assert np.max(gaps) < 0.1
    ring = pts[order]
    jumps = np.hypot(*np.diff(np.vstack([ring, ring[:1]]), axis=0).T)
    assert np.max(jumps) < 0.05 * extent
