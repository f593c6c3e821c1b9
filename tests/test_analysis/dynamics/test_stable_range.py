"""The stable stretch of a continued branch, on hand-built branches whose answer is read off
their multipliers and events (the numbers of a real continuation are checked, slow, in
tests/test_analysis/paper/test_orbit_evidence.py)."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.dynamics.branch import BranchPoint, ContinuationEvent
from analysis.dynamics.continuation import Continuation
from analysis.dynamics.stable_range import StableRange, stable_range


def _point(c: float, mu: float, labels: tuple[str, ...] = ()) -> BranchPoint:
    mults = np.array([mu, 0.1] if not labels else [mu, 1.0], dtype=complex)
    return BranchPoint(
        parameter=c,
        period=1,
        multipliers=mults,
        point=np.zeros(2),
        sequence=(),
        state=None,
        monodromy=np.eye(2),
        multiplier_labels=labels,
    )


def _event(kind: str, c: float, index: int, mu: float = 1.0) -> ContinuationEvent:
    return ContinuationEvent(kind, c, (c - 1e-3, c + 1e-3), 1, np.array([mu, 0.2]), index=index)


def _branch(points, events=(), stop="reached stop") -> Continuation:
    return Continuation("coupling", "natural", tuple(points), tuple(events), stop)


def test_stable_to_the_end_has_no_ending_event():
    pts = [_point(c, 0.5) for c in (1.0, 1.1, 1.2, 1.3)]
    got = stable_range(_branch(pts, [_event("grazing", 1.15, 2)]), +1.0)
    assert got == StableRange(1.3, None, None, None, "reached stop", (("grazing", 1.15),))


def test_fold_ends_the_stretch_and_the_earlier_event_does_not():
    # stable at 1.0–1.2, a grazing at 1.05, a fold at 1.25 before the first unstable point 1.3
    pts = [_point(c, mu) for c, mu in ((1.0, 0.5), (1.1, 0.6), (1.2, 0.9), (1.3, 1.2))]
    events = [_event("grazing", 1.05, 1), _event("fold", 1.25, 3, mu=1.0004)]
    got = stable_range(_branch(pts, events), +0.2)
    assert got.extreme_stable_parameter == 1.2
    assert (got.ended_by, got.event_parameter) == ("fold", 1.25)
    assert got.event_max_abs_multiplier == pytest.approx(1.0004, abs=1e-15)
    # an event after the first unstable point does not end the stretch
    late = [_event("grazing", 1.05, 1), _event("fold", 1.35, 4)]
    assert stable_range(_branch(pts, late), 1.0).ended_by == "grazing"


def test_a_branch_turned_back_at_a_fold_keeps_the_side_it_was_continued_to():
    # continued downward from 1.80: stable down to 1.76, the fold at 1.7575 turns it back up
    # past the start, now unstable: the extreme is 1.76 (not the start 1.80)
    cs = (1.80, 1.79, 1.77, 1.76, 1.765, 1.79, 1.81)
    mus = (0.5, 0.6, 0.8, 0.95, 1.05, 1.3, 1.4)
    pts = [_point(c, mu) for c, mu in zip(cs, mus, strict=True)]
    got = stable_range(_branch(pts, [_event("fold", 1.7575, 4)]), -0.15)
    assert got.extreme_stable_parameter == 1.76
    assert got.ended_by == "fold"
    # the same stretch read upward would report the start
    assert stable_range(_branch(pts), 1.0).extreme_stable_parameter == 1.80


def test_frozen_multipliers_do_not_count_and_an_unstable_start_is_its_own_stretch():
    frozen = ("", "frozen: wagon")
    pts = [_point(1.0, 0.5, frozen), _point(1.1, 0.7, frozen)]  # the frozen μ = 1 is left out
    assert stable_range(_branch(pts), 1.0).extreme_stable_parameter == 1.1
    pts = [_point(1.0, 1.5), _point(0.9, 0.5)]
    got = stable_range(_branch(pts, [_event("period-doubling", 1.0, 0, mu=-1.0)]), -1.0)
    assert got.extreme_stable_parameter == 1.0
    assert got.ended_by == "period-doubling"


def test_record_keys_and_bad_input():
    pts = [_point(1.0, 0.5), _point(1.1, 1.2)]
    rec = stable_range(_branch(pts, [_event("fold", 1.05, 1)], "unstable"), 1.0).to_record()
    assert list(rec) == [
        "extreme_stable_parameter",
        "ended_by",
        "event_parameter",
        "event_max_abs_multiplier",
        "stop_reason",
        "events",
    ]
    assert rec["events"] == [("fold", 1.05)] and rec["stop_reason"] == "unstable"
    with pytest.raises(ValueError, match="direction"):
        stable_range(_branch(pts), 0.0)
    with pytest.raises(ValueError, match="branch must hold"):
        stable_range(_branch([]), 1.0)
    with pytest.raises(TypeError, match="branch must be a Continuation"):
        stable_range({"points": pts}, 1.0)
