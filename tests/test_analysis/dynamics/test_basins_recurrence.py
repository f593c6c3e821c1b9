"""The recurrence mapper (issue 27): labels against the full-budget classification, a closed-form
attractor, the safeguards (divergence, the box, max_steps), joining the chunks' attractors, and a
stored run that resumes.

The coexistence case is the erf-play limit at C = 1.78: a period-3 orbit and a chaotic attractor
(λ_max ≈ 0.13), both with basins around the paper's start (docs/basins/erf_C1.78).
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from analysis.dynamics.attractors import match_cycles
from analysis.dynamics.basins import BasinGrid, RecurrenceSettings, basins
from analysis.dynamics.recurrence import merge_attractors
from analysis.experiments.execution import run_tasks
from analysis.experiments.models import build_operator
from hysteresis import PlayOperator, Relay
from oscillators import ForcedOscillator

GRID = BasinGrid((-2.0, 0.0), (-0.9, 1.1), 10)
RUN = dict(transient=0, periods=100, max_periods=2000, lyapunov_periods=500)


def _same(a: dict, b: dict) -> bool:
    """Whether two attractor records are the same attractor (one chaotic attractor here)."""
    if a["kind"] != b["kind"]:
        return False
    if a["kind"] == "periodic":
        pa, pb = np.asarray(a["points"]), np.asarray(b["points"])
        return a["period"] == b["period"] and bool(match_cycles(pa[None], pb, 1e-4)[0])
    return True


@pytest.fixture(scope="module")
def coexisting():
    system = ForcedOscillator(build_operator("erf-play"), 1.78)
    full = basins(system, GRID, **RUN)
    fast = basins(system, GRID, method="recurrences", **RUN)
    return system, full, fast


def test_labels_agree_with_the_full_budget_classification(coexisting):
    _, full, fast = coexisting
    # the chunk's first starts run before any attractor is known: finding the chaotic one at
    # cells of 0.05 takes about the budget, so those still undecided run once more at the end
    assert sorted(a["kind"] for a in fast.attractors) == ["chaotic", "periodic"]
    assert {a["kind"] for a in full.attractors} == {"chaotic", "periodic"}
    # each start's attractor as the full map names it (its chaotic cloud may come in pieces)
    to_full = [{a["label"] for a in full.attractors if _same(a, b)} for b in fast.attractors]
    agree = [int(x) in to_full[int(y)] for x, y in zip(full.labels, fast.labels, strict=True)]
    # the bar: 99 % of the starts (here: at most one of 100)
    assert np.mean(agree) >= 0.99
    per = next(a for a in fast.attractors if a["kind"] == "periodic")
    chaos = next(a for a in fast.attractors if a["kind"] == "chaotic")
    assert per["period"] == 3 and per["refined"] and per["residual"] < 1e-9
    assert chaos["max_exponent"] > 2 * chaos["max_exponent_error"] > 0
    # most starts stop long before the budget: on attractor or basin cells
    assert fast.settings["stops"]["attractor cells"] + fast.settings["stops"]["basin cells"] > 90
    assert np.median(fast.steps) < 0.1 * RUN["max_periods"]


def test_every_periodic_label_is_reproduced_by_a_direct_run(coexisting):
    """A start the mapper put on the period-3 orbit, run by ``poincare_section`` for the whole
    budget, repeats that orbit's (q, v) points (cyclic shift, 1e-4)."""
    system, _, fast = coexisting
    per = next(a for a in fast.attractors if a["kind"] == "periodic")
    orbit = np.asarray(per["points"])[:, :2]
    mine = np.flatnonzero(fast.labels == per["label"])
    assert mine.size
    for i in mine:
        q0, v0, _ = fast.starts[i]
        sec = system.poincare_section(3, 2000, q0, v0)
        assert match_cycles(np.column_stack([sec.q, sec.v])[None], orbit, 1e-4)[0], (q0, v0)


def test_linear_fixed_point_is_the_closed_form():
    """C = 0: every start ends on the forced response x* = Re(e^{iΩt}/(1 − Ω² + 2iζΩ)) at
    φ = 0; one period-1 attractor, found once (100 recurrences + 1000 locate steps), every
    later start labelled by its cells long before the budget."""
    zeta, omega = 0.05, 1.0
    system = ForcedOscillator(Relay(100.0, -100.0), 0.0, zeta, omega)
    d = 1.0 - omega**2 + 2j * zeta * omega
    x_star = np.array([(1 / d).real, (1j * omega / d).real])
    starts = [[1.0, 0.5], [-2.0, 1.0], [0.5, -1.5], [3.0, 3.0]]
    bm = basins(system, starts, method="recurrences", transient=0, periods=20, max_periods=4000)
    assert [a["kind"] for a in bm.attractors] == ["periodic"]
    (a,) = bm.attractors
    assert a["period"] == 1 and np.all(bm.labels == 0)
    np.testing.assert_allclose(np.asarray(a["points"])[0, :2], x_star, atol=1e-10)
    assert bm.settings["stops"]["new attractor"] == 1
    assert np.all(bm.steps[1:] < bm.steps[0])


def test_divergent_lost_and_undecided_starts():
    with pytest.warns(RuntimeWarning, match="positive-feedback"):
        runaway = ForcedOscillator(PlayOperator(2.0), 1.5)
    bm = basins(runaway, [[0.0, 0.0], [5.0, 0.0]], method="recurrences", transient=0, periods=20)
    assert [(a["kind"], a["count"]) for a in bm.attractors] == [("divergent", 2)]
    system = ForcedOscillator(build_operator("erf-play"), 1.78)
    # a box the orbit never enters: lost after mx_chk_lost steps outside, undecided
    box = RecurrenceSettings(box=((5.0, 6.0), (5.0, 6.0), (5.0, 6.0)), mx_chk_lost=5)
    bm = basins(system, [[-1.0, 0.1]], method="recurrences", recurrence=box, **RUN)
    assert [a["kind"] for a in bm.attractors] == ["undecided"] and bm.steps[0] == 5
    # recurrences never enough within max_steps: undecided at the budget
    never = RecurrenceSettings(mx_chk_fnd_att=10_000)
    bm = basins(system, [[-1.0, 0.1]], method="recurrences", recurrence=never, **RUN)
    assert [a["kind"] for a in bm.attractors] == ["undecided"]
    assert bm.steps[0] == RUN["max_periods"]


def test_chunks_attractors_sharing_a_cell_are_joined():
    cells_a = np.array([[0, 0, 0], [1, 0, 0]])
    cells_b = np.array([[5, 5, 5]])
    cells_c = np.array([[1, 0, 0], [2, 2, 2]])  # shares (1, 0, 0) with the first
    results = [
        {"cells": np.vstack([cells_a, cells_b]), "cell_counts": np.array([2, 1])},
        {"cells": cells_c, "cell_counts": np.array([2])},
    ]
    group_of, members = merge_attractors(results)
    assert group_of[0].tolist() == [0, 1] and group_of[1].tolist() == [0]
    assert members == [[(0, 0), (1, 0)], [(0, 1)]]


def test_stored_chunks_resume_to_identical_labels(tmp_path, coexisting):
    system, _, fast = coexisting
    settings = RecurrenceSettings(chunk=40)
    runner = functools.partial(run_tasks, "basins", store=tmp_path / "s.sqlite", workers=1)
    kw = dict(method="recurrences", recurrence=settings, **RUN)
    first = basins(system, GRID, executor=runner, **kw)
    calls = []

    def counting(tasks, func):
        calls.append(len(tasks))
        return runner(tasks, func)

    again = basins(system, GRID, executor=counting, **kw)
    np.testing.assert_array_equal(again.labels, first.labels)
    np.testing.assert_array_equal(again.steps, first.steps)
    assert calls == [3]  # three chunks of at most 40 starts, all read from the store
    # smaller chunks (three cell grids) still find the same two attractors
    assert sorted(a["kind"] for a in first.attractors) == sorted(a["kind"] for a in fast.attractors)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        (dict(cell_size=0.0), "cell_size"),
        (dict(mx_chk_att=0), "mx_chk_att"),
        (dict(box=((0.0, 1.0),)), "box"),
        (dict(path_basins=1), "path_basins"),
    ],
)
def test_bad_settings_are_refused(kwargs, message):
    with pytest.raises((ValueError, TypeError), match=message):
        RecurrenceSettings(**kwargs)
