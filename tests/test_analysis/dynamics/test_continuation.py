"""Continuation of periodic orbits: the N = 2 dimer's cascade onset against its closed form, the
grazing location, a fold of the erf play's period-5 window checked by Newton on both sides, and
period doubling with branch switching."""

from __future__ import annotations

import json

import numpy as np
import pytest

from analysis.dynamics.continuation import continue_orbit, period_doubled_orbit
from analysis.dynamics.periodic_orbits import (
    OrbitNotFoundError,
    find_periodic_orbit,
    refine_periodic_orbit,
)
from analysis.experiments.models import build_operator
from oscillators import ForcedOscillator

#: the closed form of the N = 2 cascade onset (paper fig:bif_0, dimer b = (1, −1): a relay with
#: α = 1, β = −1): the period-1 orbit without switching has amplitude 1/(2ζ) = 10 around q = −C
#: (all spins down); its maximum −C + 10 touches α = 1 (by symmetry: the orbit around q = C
#: touches β = −1) at C = 1/(2ζ) + β = 9
ONSET = 9.0


def _dimer_pair(coupling: float) -> ForcedOscillator:
    return ForcedOscillator(build_operator("dimers", fields=[[1.0, -1.0]]), coupling)


@pytest.mark.parametrize("method", ["natural", "pseudo-arclength"])
def test_n2_cascade_onset_is_a_grazing_at_the_closed_form(method):
    system = _dimer_pair(9.5)
    orbit = find_periodic_orbit(system)
    assert orbit.period == 1 and orbit.sequence == ()  # no switch above the onset
    branch = continue_orbit(
        system, orbit, 9.5, 8.9, method=method, step=0.05, max_period=8, transient=50
    )
    grazings = [e for e in branch.events if e.kind == "grazing"]
    assert grazings, branch.stop_reason
    first = grazings[0]
    lo, hi = first.bracket
    print(method, "onset", repr(first.parameter), "bracket", first.bracket)
    # bisection to 1e-8 in C; the onset is exact (the orbit is linear, its minimum C − 10 is
    # computed to round-off), so the bracket holds 9 up to round-off (1e-12)
    assert hi - lo <= 1e-8
    assert lo - 1e-12 <= ONSET <= hi + 1e-12
    assert abs(first.parameter - ONSET) < 1e-6
    assert first.period == 1
    d = json.loads(json.dumps(branch.to_dict()))
    assert d["events"][0]["kind"] == "grazing"
    assert all({"parameter", "period", "max_abs_multiplier"} <= set(p) for p in d["branch"])


@pytest.mark.slow
def test_n2_cascade_windows_end_at_grazings_and_periods_add():
    # natural continuation below the onset walks the period-adding windows (periods re-detected
    # after each grazing); each window's end is a switching-sequence change located to 1e-8
    system = _dimer_pair(9.5)
    orbit = find_periodic_orbit(system)
    branch = continue_orbit(system, orbit, 9.5, 8.85, step=0.05, max_period=64, transient=200)
    grazings = [e for e in branch.events if e.kind == "grazing"]
    periods = [e.period for e in grazings]
    print("grazings", [(round(e.parameter, 9), e.period) for e in grazings])
    assert periods[0] == 1 and len(periods) >= 3
    # below the onset the periods of the successive windows fall by 2 (period adding)
    assert all(b - a == -2 for a, b in zip(periods[1:], periods[2:], strict=False))
    for e in grazings:
        assert e.bracket[1] - e.bracket[0] <= 1e-8
        # independent check of the location: Newton from the last orbit of the window
        # converges with the same switching sequence just inside the bracket, not beyond it
        inside = e.bracket[1] + 1e-7 if e.bracket[1] < 9.5 else None
        if inside is not None and e.period > 1:
            sys_in = _dimer_pair(inside)
            o = refine_periodic_orbit(sys_in, e.point.state, e.period)
            # a branch point's sequence also carries the relay configuration at the section
            events = [x for x in e.point.sequence if x[0] != "relays"]
            assert len(o.sequence) == len(events)


def test_fold_of_the_erf_play_window_checked_by_newton():
    # the period-5 orbit of the erf-play window ends at a fold near C = 3.8846 (paper's window
    # 3.80–3.88); on the fold a multiplier is 1
    system = ForcedOscillator(build_operator("erf-play"), 3.88)
    orbit = find_periodic_orbit(system)
    assert orbit.period == 5 and orbit.stable
    branch = continue_orbit(system, orbit, 3.88, 3.89, step=0.002, max_points=40)
    folds = [e for e in branch.events if e.kind == "fold"]
    assert folds, [(e.kind, e.parameter) for e in branch.events]
    fold = folds[0]
    print("fold at C =", repr(fold.parameter), "multipliers", fold.multipliers)
    assert fold.bracket[1] - fold.bracket[0] <= 1e-8
    # the located multiplier: μ − 1 = O(sqrt(distance to the fold)·|d²|): 1e-8 in C gives a few
    # 1e-3 at most here
    assert abs(np.max(fold.multipliers.real) - 1.0) < 1e-2
    # independent check: Newton (period 5) from the fold point converges 1e-5 below the fold
    # and finds no orbit 1e-5 above it
    below = ForcedOscillator(build_operator("erf-play"), fold.parameter - 1e-5)
    refine_periodic_orbit(below, fold.point.state, 5)
    above = ForcedOscillator(build_operator("erf-play"), fold.parameter + 1e-5)
    with pytest.raises(OrbitNotFoundError):
        o = refine_periodic_orbit(above, fold.point.state, 5, max_iterations=15)
        # a converged orbit there would have to be far from the fold point
        assert np.max(np.abs(o.points[0] - fold.point.point)) > 1e-2


def test_erf_window_lower_fold_leads_onto_the_symmetric_partner():
    # the erf play is odd, so (q, v, w)(t) -> −(q, v, w)(t + T/2) maps orbits to orbits. The
    # window's orbit continued down from C = 3.85 passes a grazing, a fold near C = 3.7575 and
    # a second grazing at the same C: there the branch carries the partner of the first
    # grazing's orbit (a distinct orbit with the same multipliers). With symmetric=True the
    # continuation stops there; without it the two are not taken for the same event.
    system = ForcedOscillator(build_operator("erf-play"), 3.85)
    orbit = find_periodic_orbit(system)
    branch = continue_orbit(system, orbit, 3.85, 3.74, step=0.005, max_points=60, symmetric=True)
    assert branch.stop_reason.startswith("the branch reached the symmetric partner")
    kinds = [e.kind for e in branch.events]
    assert kinds == ["grazing", "fold", "grazing"], kinds
    first, _, second = branch.events
    assert abs(first.parameter - second.parameter) <= 1e-7
    # independent construction of the partner: the trajectory from the first orbit (dense
    # output, not the section map) at half periods, negated, against the second orbit's
    # section points refined by Newton at the same C
    c = first.parameter
    sys_c = ForcedOscillator(build_operator("erf-play"), c)
    a = refine_periodic_orbit(sys_c, first.point.state, 5)
    b = refine_periodic_orbit(sys_c, second.point.state, 5)
    assert np.min(np.max(np.abs(a.points[:, :2] - b.points[0, :2]), axis=1)) > 0.1  # distinct
    t = sys_c.period
    traj = sys_c.trajectory(
        5 * t, a.start.q, a.start.v, a.start.operator_state, sample_dt=t / 2, phi0=a.start.phi
    )
    at = [int(np.argmin(np.abs(traj.t - (j + 0.5) * t))) for j in range(5)]
    assert np.allclose(traj.t[at], (np.arange(5) + 0.5) * t, rtol=0, atol=1e-9)
    half = -np.column_stack([traj.q[at], traj.v[at]])  # t = T/2, 3T/2, ..., 9T/2
    gap = max(np.min(np.max(np.abs(half - p), axis=1)) for p in b.points[:, :2])
    assert gap < 1e-8  # both orbits converged to 1e-10; the dense output to ~1e-11
    assert np.allclose(np.sort(np.abs(a.multipliers)), np.sort(np.abs(b.multipliers)), atol=1e-8)
    plain = continue_orbit(system, orbit, 3.85, 3.74, step=0.005, max_points=45)
    assert "closed loop" not in plain.stop_reason  # two sheets' events are not one event


@pytest.mark.slow
def test_period_doubling_and_branch_switching_on_the_erf_play():
    # on the erf play's period-5 branch continued through its folds (C = 3.85 -> 3.95) the
    # unstable part has a multiplier through −1 near C = 3.805; the period-10 orbit born there
    system = ForcedOscillator(build_operator("erf-play"), 3.85)
    orbit = find_periodic_orbit(system)
    branch = continue_orbit(system, orbit, 3.85, 3.95, step=0.005, max_points=300)
    pds = [e for e in branch.events if e.kind == "period-doubling"]
    assert pds, [(e.kind, e.parameter) for e in branch.events]
    pd = pds[0]
    assert abs(np.min(pd.multipliers.real) + 1.0) < 1e-2
    lam, doubled = period_doubled_orbit(system, pd)
    assert doubled.period == 10
    assert abs(lam - pd.parameter) < 1e-3
    # its multipliers: the square of the period-5 orbit's near the doubling (μ = −1 -> +1)
    assert abs(doubled.max_abs_multiplier - 1.0) < 0.2


def test_bad_input_is_named():
    system = _dimer_pair(9.5)
    orbit = find_periodic_orbit(system, max_period=2)
    with pytest.raises(ValueError, match="start and stop"):
        continue_orbit(system, orbit, 9.5, 9.5)
    with pytest.raises(ValueError, match="method"):
        continue_orbit(system, orbit, 9.5, 9.0, method="newton")
    with pytest.raises(ValueError, match="parameter"):
        continue_orbit(system, orbit, 9.5, 9.0, parameter="mass")
    with pytest.raises(ValueError, match="step"):
        continue_orbit(system, orbit, 9.5, 9.0, step=-1.0)


def test_a_stop_the_system_refuses_is_bad_input_at_once():
    """Continuing the frequency toward 0 crept along ever longer periods (a hang): a stop the
    system refuses is a one-line error before any branch point is computed."""
    system = _dimer_pair(9.5)
    orbit = find_periodic_orbit(system)
    with pytest.raises(ValueError, match=r"stop: frequency = 0: frequency must lie in") as info:
        continue_orbit(system, orbit, 1.0, 0.0, parameter="frequency")
    assert "\n" not in str(info.value)


def test_an_orbit_found_at_another_parameter_is_not_relabelled():
    system = _dimer_pair(9.5)
    orbit = find_periodic_orbit(system)
    with pytest.raises(ValueError, match=r"not a periodic orbit of the system at start = 9.4"):
        continue_orbit(system, orbit, 9.4, 9.0)


def test_a_failure_part_way_returns_the_branch_so_far(monkeypatch):
    """An integration that fails after a few branch points (a stand-in divergence raised by
    the fourth orbit shot of a point): the branch computed so far comes back, its stop reason
    naming the failure."""
    from analysis.dynamics import branch as branch_module
    from oscillators.engines import DivergenceError

    original = branch_module.BranchProblem.point
    calls = {"n": 0}

    def failing_point(self, *args, **kwargs):
        calls["n"] += 1
        if calls["n"] > 3:
            raise DivergenceError("stand-in failure")
        return original(self, *args, **kwargs)

    system = _dimer_pair(9.5)
    orbit = find_periodic_orbit(system)
    monkeypatch.setattr(branch_module.BranchProblem, "point", failing_point)
    branch = continue_orbit(system, orbit, 9.5, 9.45, method="natural")
    assert branch.stop_reason.startswith("failed after coupling = 9.")
    assert "DivergenceError: stand-in failure" in branch.stop_reason
    assert len(branch.points) == 3


def test_a_grazing_between_orbits_without_switches_is_found():
    """Relay(9, −50), ζ = 0.05, Ω = 1: the orbit with the relay down, q = −C + 10 sin t, grazes
    α = 9 at C = 1 exactly (closed form: amplitude 1/(2ζΩ) = 10). Neither it nor the orbit with
    the relay up has a switch, so only the relay configuration tells them apart; the branch
    must report the grazing there instead of running on along the other orbit."""
    from hysteresis import Relay

    system = ForcedOscillator(Relay(9.0, -50.0), coupling=1.5)
    branch = continue_orbit(system, find_periodic_orbit(system), 1.5, 0.5)
    grazings = [e for e in branch.events if e.kind == "grazing"]
    assert len(grazings) == 1
    assert abs(grazings[0].parameter - 1.0) <= 1e-8  # the default locate_tolerance
    above = [p for p in branch.points if p.parameter > 1.0 + 1e-8]
    assert above and all(p.sequence == (("relays", (-1,)),) for p in above)
