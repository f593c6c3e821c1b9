"""The stretch of a continued branch over which its periodic orbit is stable, and what ends it.

A branch of :func:`~analysis.dynamics.continuation.continue_orbit` is a sequence of orbits in
the order they were continued, each with its Floquet multipliers. From the branch's first point
the orbit is (linearly) stable while every multiplier that is not frozen memory lies inside the
unit circle, ``max |μ| < 1`` (:attr:`~analysis.dynamics.branch.BranchPoint.max_abs_multiplier`);
the first point with ``max |μ| >= 1`` ends the stable stretch. The bifurcation that ends it is
the last event located before that point (a fold, a period doubling, a torus bifurcation or a
grazing, :class:`~analysis.dynamics.branch.ContinuationEvent`), known to the continuation's
``locate_tolerance``; the stretch's extreme parameter is known to the continuation step (it is
a branch point, not the located event).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from analysis.dynamics.continuation import Continuation

__all__ = ["StableRange", "stable_range"]


@dataclass(frozen=True)
class StableRange:
    """What :func:`stable_range` measured on one branch.

    Attributes
    ----------
    extreme_stable_parameter:
        The farthest parameter of the stable stretch in the continuation's direction.
    ended_by, event_parameter, event_max_abs_multiplier:
        The kind, located parameter and ``max |μ|`` (over all its multipliers) of the event
        that ends the stretch: the last event before the first unstable point; ``None`` when
        the branch stays stable to its end (or no event was located before it turned unstable).
    stop_reason:
        Why the continuation stopped (:attr:`Continuation.stop_reason`).
    events:
        ``(kind, parameter)`` of every event of the branch, in order.
    """

    extreme_stable_parameter: float
    ended_by: str | None
    event_parameter: float | None
    event_max_abs_multiplier: float | None
    stop_reason: str
    events: tuple[tuple[str, float], ...]

    def to_record(self) -> dict[str, Any]:
        """The JSON keys of the report's periodic-orbit evidence (the attributes; ``events`` a
        list of ``(kind, parameter)`` pairs)."""
        return {
            "extreme_stable_parameter": self.extreme_stable_parameter,
            "ended_by": self.ended_by,
            "event_parameter": self.event_parameter,
            "event_max_abs_multiplier": self.event_max_abs_multiplier,
            "stop_reason": self.stop_reason,
            "events": list(self.events),
        }


def stable_range(branch: Continuation, direction: float) -> StableRange:
    """The stable stretch of ``branch`` from its first point (module docstring).

    ``direction`` is the sign of the continuation (+1 upward, −1 downward in the parameter;
    only its sign is used): a branch that turns back past its start at a fold keeps the side it
    was continued to, so the extreme is the largest stable parameter going up and the smallest
    going down. A branch whose first point is already unstable has the first point as its
    stretch (and the last event at or before it, if any, as what ends it).
    """
    if not isinstance(branch, Continuation):
        raise TypeError(f"branch must be a Continuation, got {type(branch).__name__}")
    if not (isinstance(direction, int | float) and math.isfinite(direction) and direction != 0):
        raise ValueError(f"direction must be a finite non-zero number, got {direction!r}")
    pts = branch.points
    if not pts:
        raise ValueError("branch must hold at least one point")
    end = next((i for i, p in enumerate(pts) if p.max_abs_multiplier >= 1.0), len(pts))
    stretch = [p.parameter for p in pts[: max(end, 1)]]
    sign = math.copysign(1.0, direction)
    extreme = max(stretch) if sign > 0 else min(stretch)
    ending = [e for e in branch.events if e.index <= end] if end < len(pts) else []
    event = ending[-1] if ending else None
    return StableRange(
        extreme_stable_parameter=float(extreme),
        ended_by=event.kind if event else None,
        event_parameter=float(event.parameter) if event else None,
        event_max_abs_multiplier=float(np.max(np.abs(event.multipliers))) if event else None,
        stop_reason=branch.stop_reason,
        events=tuple((e.kind, float(e.parameter)) for e in branch.events),
    )
