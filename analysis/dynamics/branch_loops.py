"""When a continued branch has closed its loop: an event found again, or (odd operators) its
symmetric partner's, at the same orbit — the stop rule of
:func:`~analysis.dynamics.continuation.continue_orbit` — and the continuity test it and the
re-detection past a grazing share.
"""

from __future__ import annotations

import numpy as np

from analysis.dynamics.branch import BranchProblem, ContinuationEvent
from analysis.dynamics.orbit_coordinates import StateCoordinates

__all__ = ["CONTINUITY", "loop_closed", "within"]

#: largest relative jump in ``(q, v)`` by which a piece re-found by Newton past a grazing may
#: continue the last orbit: a branch is continuous through a border collision and moves by
#: ``|dx/dλ|·Δλ`` with ``Δλ <= 1000`` bracket widths (``<= 1e-5`` at the default
#: ``locate_tolerance``), within 1e-3 for slopes up to 100; another orbit lies O(1) away
CONTINUITY = 1e-3


def within(d: np.ndarray, x: np.ndarray) -> bool:
    """``|d|_∞ <= CONTINUITY·max(1, |x|_∞)``: ``d`` is a continuation-sized move at ``x``."""
    return float(np.max(np.abs(d))) <= CONTINUITY * max(1.0, float(np.max(np.abs(x))))


def _comparable(a: ContinuationEvent, b: ContinuationEvent, tol: float) -> bool:
    """The same kind, period and coordinates (a staircase of another length is another
    family), both located (brackets within ``10·tol``), at the same parameter to ten bracket
    widths (at least ``10·tol``: a fold's bracket in λ can be far narrower than its location
    error)."""
    if a.kind != b.kind or a.period != b.period:
        return False
    if a.point is not None and b.point is not None and a.point.point.size != b.point.point.size:
        return False
    width = max(a.bracket[1] - a.bracket[0], b.bracket[1] - b.bracket[0])
    if width > 10.0 * tol:
        return False  # not located (its corrector failed): it cannot close a loop
    return abs(a.parameter - b.parameter) <= 10.0 * max(width, tol)


def _same_event(a: ContinuationEvent, b: ContinuationEvent, tol: float) -> bool:
    """:func:`_comparable` and at the same orbit (``(q, v)`` within :data:`CONTINUITY`): a
    branch followed continuously keeps its section point, so a genuine return meets it again
    (two events at one λ on two sheets are not a loop)."""
    if not _comparable(a, b, tol):
        return False
    return (
        a.point is None
        or b.point is None
        or within(a.point.point[:2] - b.point.point[:2], a.point.point)
    )


def _mirror(prob: BranchProblem, a: ContinuationEvent, b: ContinuationEvent, tol: float) -> bool:
    """``b`` is the event of ``a``'s symmetric partner: :func:`_comparable`, the same
    multipliers (to 1e-6), and ``b``'s orbit point is ``−x(t + T/2)`` of ``a``'s orbit, for one
    of its ``k`` half-period points (all coordinates, to :data:`CONTINUITY`)."""
    if a.point is None or b.point is None or not _comparable(a, b, tol):
        return False
    mu_a, mu_b = np.sort(np.abs(a.multipliers)), np.sort(np.abs(b.multipliers))
    if np.max(np.abs(mu_a - mu_b), initial=0.0) > 1e-6:
        return False
    system = prob.system(a.point.parameter)
    eng = system.engine(a.point.state, **(prob.eo or {}))
    x = b.point.point
    for j in range(a.period):
        eng.advance(np.array([(j + 0.5) * system.period]))
        try:
            image = -StateCoordinates(system, eng.state(), prob.eo).vector(eng.state())
        except ValueError:  # another number of memory coordinates there
            continue
        if image.size == x.size and within(image - x, x):
            return True
    return False


def loop_closed(
    prob: BranchProblem,
    new: list[ContinuationEvent | None],
    found: list[ContinuationEvent],
    tol: float,
    symmetric: bool,
) -> str | None:
    """The stop reason (``{}`` for the event's name) if one of the ``new`` events is one
    already ``found`` (:func:`_same_event`) or, for a ``symmetric`` system, its partner's
    (:func:`_mirror`); else ``None``."""
    new = [b for b in new if b is not None]
    if any(_same_event(a, b, tol) for b in new for a in found):
        return "the branch returned to {} already found (a closed loop)"
    if symmetric and any(_mirror(prob, a, b, tol) for b in new for a in found):
        return (
            "the branch reached the symmetric partner of an event already found (a closed loop "
            "up to x -> -x with a half-period shift)"
        )
    return None
