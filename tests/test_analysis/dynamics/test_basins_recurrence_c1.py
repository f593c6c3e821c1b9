"""The recurrence mapper at C = 1, ζ = 0.1 against the full section classification.

Found (6 × 6 trial, every start "undecided" before): with the sections' default budget
(``max_periods = transient + periods``, 100 steps) no start could declare an attractor, which
takes ``mx_chk_fnd_att = 100`` recurrences after its first revisit; ``basins`` now gives the
recurrence mapper ``max(periods, mx_chk_fnd_att + mx_chk_loc_att)`` steps by default. Second,
the play + relays sum has a period-1 and a period-2 orbit 0.003–0.009 apart in (q, v, M):
cells of 0.05 hold both (the mapper merges them); cells of 0.002 separate them.
"""

from __future__ import annotations

import numpy as np
import pytest

from analysis.dynamics.basins import BasinGrid, RecurrenceSettings, basins
from analysis.experiments.models import build_operator
from oscillators import ForcedOscillator

GRID = BasinGrid((-2.0, 2.0), (-2.0, 2.0), 6)


def _agreement(a, b) -> float:
    """Fraction of starts whose attractors agree (kind and period; labels matched by them)."""
    key_a = [(x["kind"], x.get("period")) for x in a.attractors]
    key_b = [(x["kind"], x.get("period")) for x in b.attractors]
    return float(np.mean([key_a[i] == key_b[j] for i, j in zip(a.labels, b.labels, strict=True)]))


def test_erf_play_at_c1_is_decided_and_agrees_with_sections():
    system = ForcedOscillator(build_operator("erf-play"), 1.0, damping_ratio=0.1)
    fast = basins(system, GRID, method="recurrences")
    full = basins(system, GRID, method="sections")
    assert all(a["kind"] != "undecided" for a in fast.attractors)
    assert [(a["kind"], a["period"]) for a in fast.attractors] == [("periodic", 1)]
    assert _agreement(fast, full) == 1.0
    # one start finds and locates the fixed point (100 + 1000 steps), the others hit its cell
    assert np.sort(fast.steps)[-2] <= 5


def test_budget_below_the_recurrence_threshold_leaves_starts_undecided():
    system = ForcedOscillator(build_operator("erf-play"), 1.0, damping_ratio=0.1)
    bm = basins(system, GRID.starts()[:2], method="recurrences", max_periods=200)
    assert [a["kind"] for a in bm.attractors] == ["undecided"]


@pytest.mark.slow
def test_play_plus_relays_needs_cells_below_the_orbits_distance():
    op = build_operator("0.7*erf-play + 0.3*preisach", spins=100)
    system = ForcedOscillator(op, 1.0, damping_ratio=0.1)
    full = basins(system, GRID, method="sections")
    assert sorted(a["period"] for a in full.attractors) == [1, 2]
    coarse = basins(system, GRID, method="recurrences")
    fine = basins(
        system, GRID, method="recurrences", recurrence=RecurrenceSettings(cell_size=0.002)
    )
    assert len(coarse.attractors) == 1  # both orbits in one cell of 0.05
    assert _agreement(coarse, full) < 0.9
    assert _agreement(fine, full) == 1.0
