"""When a continued branch has closed its loop — the stop rules of
:func:`~analysis.dynamics.continuation.continue_orbit` — and the continuity test they and the
re-detection past a grazing share.

Two rules, either ends the branch: the branch passes its start (or a piece's first point)
again, in the same direction, at the same orbit (:func:`returned_to`: independent of how well
events were located, and it stops before any event is met a second time); or an event is
found again at the same orbit, or (odd operators) its symmetric partner's
(:func:`loop_closed`). An event found again is not reported twice.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from analysis.dynamics.branch import (
    FAILURES,
    BranchPoint,
    BranchProblem,
    ContinuationEvent,
    same_sequence,
)
from analysis.dynamics.orbit_coordinates import StateCoordinates

__all__ = ["CONTINUITY", "Mark", "loop_closed", "returned_to", "within"]

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
) -> tuple[str, list[ContinuationEvent]] | None:
    """``(stop reason, repeats)`` if one of the ``new`` events is one already ``found``
    (:func:`_same_event`) or, for a ``symmetric`` system, its partner's (:func:`_mirror`);
    else ``None``. ``repeats`` are the new events that are earlier ones found again: they are
    not reported twice (a partner's event is another orbit's, and is). The reason names the
    event; ``{}`` stands for the parameter's name."""
    new = [b for b in new if b is not None]
    repeats = [b for b in new if any(_same_event(a, b, tol) for a in found)]
    if repeats:
        return f"the branch returned to the {_named(repeats[0])} already found (a closed loop)", (
            repeats
        )
    for b in new:
        for a in found:
            if symmetric and _mirror(prob, a, b, tol):
                return (
                    f"the branch reached the symmetric partner of the {_named(a)} already found "
                    "(a closed loop up to x -> -x with a half-period shift)",
                    [],
                )
    return None


def _named(e: ContinuationEvent) -> str:
    return f"{e.kind} at {{}} = {e.parameter:.10g}"


@dataclass
class Mark:
    """A point a closed branch must come back to: the start, or a piece's first point after a
    grazing; ``heading`` the sign of ``dλ`` with which the branch leaves it, ``turned`` whether
    the branch has moved against ``heading`` since (it comes back in the same direction only
    after two folds)."""

    point: BranchPoint
    heading: float
    turned: bool = False


def returned_to(
    prob: BranchProblem, marks: list[Mark], a: BranchPoint, b: BranchPoint
) -> BranchPoint | None:
    """The branch's point at a mark's parameter if the step ``a -> b`` passes that mark again:
    the same period, coordinates and sequence, moving as it left the mark after turning back,
    with the mark's λ in ``(a.λ, b.λ]``, and the orbit there (Newton at the mark's λ from the
    chord ``a -> b``, which stays on the step's sheet) the mark's within :data:`CONTINUITY`.
    Another sheet at the same λ lies O(1) away, or ``O(sqrt(δλ))`` at a distance ``δλ`` from a
    fold. Updates the marks' ``turned``."""
    step = b.parameter - a.parameter
    for mark in marks:
        m = mark.point
        if mark.heading * step < 0.0:
            mark.turned = True
            continue
        if not mark.turned or step == 0.0 or not 0.0 < (m.parameter - a.parameter) / step <= 1.0:
            continue
        if m.period != a.period or m.point.size != a.point.size:
            continue
        if not same_sequence(m.sequence, a.sequence):
            continue
        back = _between(prob, a, b, m.parameter)
        if back is not None and within(back.point - m.point, m.point):
            return back
    return None


def _between(prob: BranchProblem, a: BranchPoint, b: BranchPoint, lam: float):
    """The orbit at ``lam`` (between ``a.λ`` and ``b.λ``) on the arc ``a -> b``: Newton at
    fixed λ from the chord's point there (``x(λ)`` may be far from ``a``'s or ``b``'s orbit
    after a fold); None if it fails."""
    d = prob.coords.dimension
    t = (lam - a.parameter) / (b.parameter - a.parameter)
    z_pred = np.append(a.point + t * (b.point - a.point), lam)
    got = prob.correct(z_pred, np.append(np.zeros(d), 1.0), a.state, False)
    if got is None:
        return None
    try:
        return prob.point(got[0][:d], lam, got[1])
    except FAILURES:
        return None
