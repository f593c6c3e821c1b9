"""A closed branch of a continuous Preisach system (the paper's Gaussian density, p = 2, R = 1,
σ_r = 0.2; ζ = 0.05, Ω = 1): the period-5 orbit at C = 3 lies on a loop between two folds
(C ≈ 3.1889 and C ≈ 2.9720). Continued upward with ``symmetric=True`` the branch used to go
round the loop again and again, each fold reported on every pass, because a fold located
with hyperplanes normal to the first point's tangent landed on the loop's other sheet and
the regula falsi crept for a hundred solves (a 1e-3 bracket: never "located", so the loop
rule could not fire). The loop now closes on its first return and each event is reported
once. Checks of the folds: the branch's λ-extrema, a multiplier 1 with stability changing
across, an orbit by Newton at fixed C just inside."""

from __future__ import annotations

import math

import numpy as np
import pytest

from analysis.dynamics.continuation import continue_orbit
from analysis.dynamics.periodic_orbits import (
    find_periodic_orbit,
    refine_periodic_orbit,
)
from hysteresis import ContinuousPreisachModel, PreisachModel
from oscillators import ForcedOscillator

P, R, SIGMA_R = 2.0, 1.0, 0.2
LOCATE = 1e-8  # continue_orbit's default locate_tolerance


def _density(a, b):
    r, s = 0.5 * (a - b), 0.5 * (a + b)
    width = np.exp(-0.5 * ((r - 0.5 * P) / SIGMA_R) ** 2) / (SIGMA_R * math.sqrt(2 * math.pi))
    return 0.5 * width * np.exp(-0.5 * (s / R) ** 2) / (R * math.sqrt(2 * math.pi))


def _orbit_at_3(model):
    system = ForcedOscillator(model, 3.0)
    orbit = find_periodic_orbit(system)
    assert orbit.period == 5 and orbit.stable
    return system, orbit


def _check_closed_once(branch, model):
    assert "closed loop" in branch.stop_reason, branch.stop_reason
    # every event once: no two of one kind and period at the same parameter
    for i, e in enumerate(branch.events):
        for f in branch.events[i + 1 :]:
            same = e.kind == f.kind and e.period == f.period
            assert not (same and abs(e.parameter - f.parameter) <= 1e-6), (e, f)
    folds = sorted(x.parameter for x in branch.events if x.kind == "fold")
    assert len(folds) == 2, [(e.kind, e.parameter) for e in branch.events]
    lower, upper = folds
    assert 2.95 < lower < 3.0 < upper < 3.2
    for fold in (e for e in branch.events if e.kind == "fold"):
        assert fold.bracket[1] - fold.bracket[0] <= 10 * LOCATE  # located
        # a fold bounds the branch in C: the upper fold from above, the lower from below
        outward = 1.0 if fold.parameter == upper else -1.0
        assert all(outward * (p.parameter - fold.parameter) <= 1e-6 for p in branch.points)
        # a fold of the closed-loop map (frozen extremum held): an active multiplier 1 there
        # (to O(sqrt(bracket)) ~ 1e-3; it touches 1 without crossing: this staircase map is
        # only piecewise smooth, both sheets stay stable at the upper fold). Orbits beyond the
        # fold in C exist with another frozen extremum (a family of orbits), so Newton on the
        # full state finds one there: no check
        mu = np.max(np.abs(fold.point.active_multipliers))
        assert abs(mu - 1.0) < 1e-2
        # and the inner side holds an orbit next to the fold's: Newton at fixed C from it
        inside = ForcedOscillator(model, fold.parameter - outward * 1e-4)
        o = refine_periodic_orbit(inside, fold.point.state, 5)
        assert np.max(np.abs(o.points[0, :2] - fold.point.point[:2])) < 0.1


def test_gaussian_preisach_loop_closes_once_with_each_fold_once():
    model = ContinuousPreisachModel.gaussian(P, R, SIGMA_R)
    system, orbit = _orbit_at_3(model)
    branch = continue_orbit(system, orbit, 3.0, 4.5, symmetric=True)
    print(branch.stop_reason, [(e.kind, e.parameter) for e in branch.events])
    _check_closed_once(branch, model)
    assert len(branch.points) < 60  # one pass round the loop (~30 points), not five


@pytest.mark.slow
@pytest.mark.parametrize("stop", [4.5, 2.5])
def test_from_density_preisach_loop_closes_once_both_ways(stop):
    # the tabulated model of the same law (resolution 256), upward and downward from C = 3:
    # downward the branch meets the lower fold first, and reports it (once)
    model = PreisachModel.from_density(_density, -7.0, 7.0, resolution=256)
    system, orbit = _orbit_at_3(model)
    branch = continue_orbit(system, orbit, 3.0, stop, symmetric=True)
    print(branch.stop_reason, [(e.kind, e.parameter) for e in branch.events])
    _check_closed_once(branch, model)
    first_fold = next(e for e in branch.events if e.kind == "fold")
    assert (first_fold.parameter > 3.0) == (stop > 3.0)


def _no_jumps(branch, step):
    # a step moves about ``step`` in C (the predictor's λ-move is ds, the corrector's a fraction
    # of it); the jump to the outer branch went on to C = 3.777, every point outside the loop
    for a, b in zip(branch.points, branch.points[1:], strict=False):
        assert abs(b.parameter - a.parameter) <= 2.0 * step, (a.parameter, b.parameter)
    assert max(p.parameter for p in branch.points) < 3.19


def test_long_step_does_not_jump_over_the_upper_fold():
    # step 0.06: the corrector from the predictor just below the fold (C = 3.155) used to land
    # on the outer branch at C = 3.2195, 2.9 predictor steps from its prediction, and the
    # branch ran on to C = 3.777; such a step is now refused and halved
    model = ContinuousPreisachModel.gaussian(P, R, SIGMA_R)
    system, orbit = _orbit_at_3(model)
    branch = continue_orbit(system, orbit, 3.0, 4.5, symmetric=True, step=0.06)
    print(branch.stop_reason, [(e.kind, e.parameter) for e in branch.events])
    _check_closed_once(branch, model)
    _no_jumps(branch, 0.06)


@pytest.mark.slow
@pytest.mark.parametrize("step", [0.02, 0.04, 0.08, 0.1])
def test_upper_fold_found_at_any_reasonable_step(step):
    model = ContinuousPreisachModel.gaussian(P, R, SIGMA_R)
    system, orbit = _orbit_at_3(model)
    reference = continue_orbit(system, orbit, 3.0, 4.5, symmetric=True, step=0.03)
    branch = continue_orbit(system, orbit, 3.0, 4.5, symmetric=True, step=step)
    _check_closed_once(branch, model)
    _no_jumps(branch, step)
    # the folds do not depend on the step: located to LOCATE in λ, the same to 10·LOCATE
    ref = sorted(e.parameter for e in reference.events if e.kind == "fold")
    got = sorted(e.parameter for e in branch.events if e.kind == "fold")
    assert np.allclose(got, ref, rtol=0.0, atol=1e-6), (got, ref)
