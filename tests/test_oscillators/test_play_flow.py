"""Play-limit trajectories (oscillators.engines.play) against independent scipy integrations.

The reference integrates the same piecewise system with ``solve_ivp`` (DOP853) and its event
location: inside the play with the constant force ``C f(w)`` until ``q = w ± p/2``; on a wall with
``w = q ∓ p/2`` until ``v = 0``. It shares no code with the module under test.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import erf

from hysteresis.play import GeneralizedPlay, PlayOperator, PlayState
from oscillators import ForcedOscillator
from oscillators.engines.play import EVENT_DTYPE
from oscillators.results import PoincareSection, Trajectory

ZETA = 0.05


@dataclass
class System:
    operator: Any
    coupling: float
    damping_ratio: float = ZETA
    frequency: float = 1.0


def erf_play(coupling: float, width: float = 2.0, spread: float = 1.0, **kw) -> System:
    return System(GeneralizedPlay.erf(width, spread), coupling, **kw)


def _oscillator(system: System) -> ForcedOscillator:
    return ForcedOscillator(
        system.operator, system.coupling, system.damping_ratio, system.frequency
    )


def play_trajectory(
    system, t_end, q0=-1.0, v0=0.1, w0=None, sample_dt=0.01, phi0=0.0, operator_state=None
) -> Trajectory:
    """The former play_trajectory(w0=...) through the engine seam: w0 is an operator state."""
    if w0 is not None:
        if operator_state is not None:
            raise ValueError("give either w0 or operator_state")
        operator_state = system.operator.state(w0, q0)
    return _oscillator(system).trajectory(t_end, q0, v0, operator_state, sample_dt, phi0)


def play_poincare(system, n_periods, transient_periods=0, q0=-1.0, v0=0.1) -> PoincareSection:
    return _oscillator(system).poincare_section(n_periods, transient_periods, q0, v0)


def _shape(system: System):
    op = system.operator
    if getattr(op, "shape_kind", None) == "erf":
        scale = math.sqrt(2.0) * op.spread
        return lambda w: erf(w / scale)
    return lambda w: w


def reference(system: System, t_end, q0, v0, w0, rtol=1e-12):
    """Event-driven solve_ivp reference: list of events (t, q, v, kind, w) and final (q, v, w)."""
    zeta, om, C = system.damping_ratio, system.frequency, system.coupling
    hp = system.operator.width / 2
    f = _shape(system)
    t, q, v, w = 0.0, q0, v0, w0
    mode = 0
    if abs(q - w - hp) < 1e-14 and v > 0:
        mode = 1
    if abs(q - w + hp) < 1e-14 and v < 0:
        mode = -1
    events = []
    opts = dict(method="DOP853", rtol=rtol, atol=rtol)
    while t < t_end:
        if mode == 0:
            force = C * f(w)

            def rhs(s, y, force=force):
                return [y[1], -2 * zeta * y[1] - y[0] + math.cos(om * s) + force]

            def up(s, y, w=w):
                return y[0] - (w + hp)

            def dn(s, y, w=w):
                return y[0] - (w - hp)

            up.terminal, up.direction = True, 1
            dn.terminal, dn.direction = True, -1
            sol = solve_ivp(rhs, (t, t_end), [q, v], events=[up, dn], **opts)
            if sol.status == 1:
                which = 0 if len(sol.t_events[0]) else 1
                t = sol.t_events[which][0]
                q, v = sol.y_events[which][0]
                mode = 1 if which == 0 else -1
                events.append((t, q, v, 1, w))
            else:
                t, q, v = t_end, sol.y[0, -1], sol.y[1, -1]
        else:
            side = mode

            def rhs(s, y, side=side):
                acc = -2 * zeta * y[1] - y[0] + math.cos(om * s) + C * f(y[0] - side * hp)
                return [y[1], acc]

            def rev(s, y):
                return y[1]

            rev.terminal, rev.direction = True, -side
            sol = solve_ivp(rhs, (t, t_end), [q, v], events=[rev], **opts)
            if sol.status == 1:
                t = sol.t_events[0][0]
                q, v = sol.y_events[0][0]
                w = q - side * hp
                mode = 0
                events.append((t, q, v, -1, w))
            else:
                t, q, v = t_end, sol.y[0, -1], sol.y[1, -1]
                w = q - side * hp
    return np.array(events).reshape(-1, 5), (q, v, w)


# --------------------------------------------------------------------------------------------
def test_inside_segment_is_the_exact_linear_solution():
    # a very wide play: the input never reaches a wall, the force C f(w0) is constant
    for omega, zeta in [(1.0, 0.05), (0.7, 0.2), (2.3, 0.0)]:
        system = erf_play(2.0, width=60.0, damping_ratio=zeta, frequency=omega)
        q0, v0, w0 = 0.3, -0.4, 1.0
        tr = play_trajectory(system, 60.0, q0=q0, v0=v0, w0=w0, sample_dt=0.5)
        force = 2.0 * erf(w0 / math.sqrt(2.0))

        def rhs(t, y, zeta=zeta, omega=omega, force=force):
            return [y[1], -2 * zeta * y[1] - y[0] + math.cos(omega * t) + force]

        sol = solve_ivp(
            rhs, (0, 60), [q0, v0], t_eval=tr.t, method="DOP853", rtol=1e-13, atol=1e-13
        )
        assert tr.events.size == 0
        np.testing.assert_allclose(tr.q, sol.y[0], atol=1e-9)
        np.testing.assert_allclose(tr.v, sol.y[1], atol=1e-9)
        assert np.all(tr.w == w0)


@pytest.mark.parametrize(
    ("system", "q0", "v0", "w0"),
    [
        (erf_play(1.9), -1.0, 0.1, -2.0),
        (erf_play(2.9), -1.0, -0.1, -2.0),
        (erf_play(4.0), -1.0, 0.1, -1.5),
        (erf_play(2.0, width=0.6, spread=0.5, damping_ratio=0.1, frequency=1.3), 0.2, 0.0, 0.1),
        (System(PlayOperator(2.0), 0.4), -1.0, 0.1, -2.0),
    ],
)
def test_wall_hits_and_reversals_match_solve_ivp(system, q0, v0, w0):
    t_end = 5 * 2 * math.pi / system.frequency
    ref_events, ref_final = reference(system, t_end, q0, v0, w0)
    tr = play_trajectory(system, t_end, q0=q0, v0=v0, w0=w0, sample_dt=0.25)
    ev = tr.events
    assert ev.dtype == EVENT_DTYPE
    assert len(ev) == len(ref_events) >= 6
    assert set(ev["kind"]) == {1, -1}
    np.testing.assert_array_equal(ev["kind"], ref_events[:, 3].astype(int))
    np.testing.assert_allclose(ev["time"], ref_events[:, 0], atol=1e-8)
    np.testing.assert_allclose(ev["q"], ref_events[:, 1], atol=1e-8)
    np.testing.assert_allclose(ev["v"], ref_events[:, 2], atol=1e-8)
    np.testing.assert_allclose(ev["w"], ref_events[:, 4], atol=1e-8)
    np.testing.assert_allclose([tr.q[-1], tr.v[-1], tr.w[-1]], ref_final, atol=1e-8)
    # at a reversal the velocity is zero; at a hit the input is on the wall, moving outward
    entries = ev[ev["kind"] == -1]
    hits = ev[ev["kind"] == 1]
    assert np.all(entries["v"] == 0.0)
    hp = system.operator.width / 2
    np.testing.assert_allclose(np.abs(hits["q"] - hits["w"]), hp, atol=1e-12)
    assert np.all(np.sign(hits["v"]) == np.sign(hits["q"] - hits["w"]))


@pytest.mark.parametrize("offset", [1e-7, -1e-7, 1e-11])
def test_no_hit_missed_or_invented_near_grazing(offset):
    # The first maximum of q (found by solve_ivp without walls) protrudes by 1e-7 beyond the
    # right wall (offset > 0) or stays 1e-7 short of it (offset < 0); the scan step is 0.2,
    # so the decision rests on the Hermite bound and the bisection, not on the grid.
    zeta, C, q0, v0, w0 = 0.05, 1.0, 0.0, 0.5, -0.5
    force = C * erf(w0 / math.sqrt(2.0))

    def rhs(t, y):
        return [y[1], -2 * zeta * y[1] - y[0] + math.cos(t) + force]

    def vzero(t, y):
        return y[1]

    vzero.direction = -1
    sol = solve_ivp(rhs, (0, 10), [q0, v0], events=[vzero], rtol=1e-13, atol=1e-13,
                    method="DOP853")  # fmt: skip
    t_max, q_max = sol.t_events[0][0], sol.y_events[0][0][0]
    half = q_max - offset - w0
    system = System(GeneralizedPlay.erf(2 * half, 1.0), C)
    tr = play_trajectory(system, t_max + 0.3, q0=q0, v0=v0, w0=w0, sample_dt=0.05)
    if offset > 0:
        assert len(tr.events) >= 1 and tr.events["kind"][0] == 1
        # the hit precedes the maximum by about sqrt(2 offset / |a|); the wagon is pushed by the
        # protrusion and the input re-enters at (almost) the same maximum
        assert t_max - 1e-2 < tr.events["time"][0] < t_max
        assert tr.events["kind"][1] == -1
        assert abs(tr.events["time"][1] - t_max) < 1e-6
        assert abs((tr.events["w"][1] - w0) - offset) < 1e-3 * offset + 1e-13
    else:
        assert len(tr.events) == 0
        assert np.all(tr.w == w0)


def test_start_on_the_right_wall():
    system = erf_play(2.9)
    # moving inward: inside at once, the wagon stays at -2 until the input hits a wall
    tr = play_trajectory(system, 10.0, q0=-1.0, v0=-0.1, w0=-2.0, sample_dt=0.01)
    first = tr.events[0]
    assert first["kind"] == 1
    before = tr.t < first["time"]
    assert np.all(tr.w[before] == -2.0)
    # moving outward: on the wall, w = q - p/2 until the reversal v = 0
    tr = play_trajectory(system, 10.0, q0=-1.0, v0=0.1, w0=-2.0, sample_dt=0.01)
    first = tr.events[0]
    assert first["kind"] == -1 and first["v"] == 0.0
    before = tr.t <= first["time"]
    np.testing.assert_allclose(tr.w[before], tr.q[before] - 1.0, atol=1e-14)
    assert np.all(np.diff(tr.q[before]) > 0)
    # at rest on the wall with the force pushing outward (a = 2 - 2.9 erf(sqrt 2) < 0 here,
    # so choose C = 1: a = 2 - erf(sqrt 2) > 0): the wagon is dragged along
    tr = play_trajectory(erf_play(1.0), 0.5, q0=-1.0, v0=0.0, w0=-2.0, sample_dt=0.01)
    np.testing.assert_allclose(tr.w, tr.q - 1.0, atol=1e-14)
    assert tr.q[-1] > -1.0
    # ... and with the force pulling inward (C = 2.9) it stays inside
    tr = play_trajectory(system, 0.5, q0=-1.0, v0=0.0, w0=-2.0, sample_dt=0.01)
    assert np.all(tr.w == -2.0) and tr.q[-1] < -1.0


def test_start_on_the_left_wall_moving_outward_matches_reference():
    system = erf_play(2.9)
    ref_events, ref_final = reference(system, 20.0, 1.0, -0.3, 2.0)
    tr = play_trajectory(system, 20.0, q0=1.0, v0=-0.3, w0=2.0)
    assert tr.events["kind"][0] == -1
    np.testing.assert_allclose(tr.events["time"], ref_events[:, 0], atol=1e-8)
    np.testing.assert_allclose([tr.q[-1], tr.v[-1], tr.w[-1]], ref_final, atol=1e-8)


def test_zero_width_is_the_smooth_oscillator():
    # p = 0: w = q always and the force is C erf(q / sqrt 2), a smooth ODE
    system = erf_play(3.0, width=0.0)
    tr = play_trajectory(system, 40.0, q0=-1.0, v0=0.1, sample_dt=0.5)

    def rhs(t, y):
        return [y[1], -2 * ZETA * y[1] - y[0] + math.cos(t) + 3.0 * erf(y[0] / math.sqrt(2))]

    sol = solve_ivp(rhs, (0, 40), [-1.0, 0.1], t_eval=tr.t, method="DOP853", rtol=1e-13,
                    atol=1e-13)  # fmt: skip
    np.testing.assert_allclose(tr.q, sol.y[0], atol=1e-8)
    np.testing.assert_allclose(tr.w, tr.q, atol=1e-13)


def test_wagon_follows_the_play_operator_of_the_sampled_input():
    # Independent bookkeeping check: H1's PlayOperator driven by the sampled q gives w up to
    # the sampling error of the extrema (|a| dt^2 / 2 ~ 1e-6 for dt = 1e-3).
    system = erf_play(2.9)
    tr = play_trajectory(system, 40.0, q0=-1.0, v0=0.1, sample_dt=1e-3)
    play = PlayOperator(2.0)
    w, _ = play.apply(tr.q, play.initial_state(tr.q[0]))
    np.testing.assert_allclose(tr.w, w, atol=2e-5)
    np.testing.assert_allclose(tr.M, erf(tr.w / math.sqrt(2.0)), atol=1e-15)
    assert isinstance(tr, Trajectory) and tr.switches.size == 0


def test_trajectory_conventions_and_final_state():
    system = erf_play(2.9)
    tr = play_trajectory(system, 10.05, sample_dt=0.1, phi0=0.3)
    assert tr.t[0] == 0.0 and tr.t[-1] == 10.05
    np.testing.assert_allclose(np.cos(tr.phi), np.cos(0.3 + tr.t), atol=1e-12)
    assert tr.final.q == tr.q[-1] and tr.final.v == tr.v[-1] and tr.final.t == 10.05
    assert isinstance(tr.final.operator_state, PlayState)
    assert tr.final.operator_state.position == tr.w[-1]
    # continuing from the final state reproduces one long run
    long = play_trajectory(system, 20.0, sample_dt=0.1)
    half = play_trajectory(system, 10.0, sample_dt=0.1)
    f = half.final
    rest = play_trajectory(
        system, 10.0, q0=f.q, v0=f.v, phi0=f.phi, operator_state=f.operator_state, sample_dt=0.1
    )
    np.testing.assert_allclose([rest.q[-1], rest.v[-1], rest.w[-1]],
                               [long.q[-1], long.v[-1], long.w[-1]], atol=1e-9)  # fmt: skip


def test_poincare_section_is_the_stroboscopic_sample():
    system = erf_play(4.0)
    period = 2 * math.pi
    # points at t = (transient_periods + i)·T, i = 0..5: the samples at 4T..9T
    sec = play_poincare(system, 6, transient_periods=4)
    tr = play_trajectory(system, 9 * period, sample_dt=period)
    assert isinstance(sec, PoincareSection)
    np.testing.assert_allclose(sec.q, tr.q[4:10], atol=1e-10)
    np.testing.assert_allclose(sec.v, tr.v[4:10], atol=1e-10)
    np.testing.assert_allclose(sec.w, tr.w[4:10], atol=1e-10)
    np.testing.assert_allclose(sec.M, erf(sec.w / math.sqrt(2)), atol=1e-15)
    assert sec.n_switches == len(tr.events)
    # without transient the first point is the initial state (t = 0)
    start = play_poincare(system, 2)
    assert (start.q[0], start.v[0], start.w[0]) == (-1.0, 0.1, -2.0)
    np.testing.assert_allclose([start.q[1], start.v[1]], [tr.q[1], tr.v[1]], atol=1e-10)


def test_bad_input_is_rejected():
    system = erf_play(2.9)
    with pytest.raises(ValueError, match="position"):
        play_trajectory(system, 1.0, q0=0.0, w0=1.5)
    with pytest.raises(ValueError, match="damping_ratio"):
        play_trajectory(erf_play(2.9, damping_ratio=1.5), 1.0)
    with pytest.raises(ValueError, match="frequency"):
        play_trajectory(erf_play(2.9, frequency=0.0), 1.0)
    with pytest.raises(ValueError, match="t_end"):
        play_trajectory(system, -1.0)
    with pytest.raises(ValueError, match="either"):
        play_trajectory(system, 1.0, w0=-1.5, operator_state=PlayState(-1.5, -1.0))
    with pytest.raises(ValueError, match="n_periods"):
        play_poincare(system, 0)
    # non-integer counts are rejected, not truncated
    with pytest.raises(ValueError, match="n_periods"):
        play_poincare(system, 2.5)
    with pytest.raises(ValueError, match="transient_periods"):
        play_poincare(system, 2, transient_periods=1.5)
    with pytest.raises(ValueError, match="transient_periods"):
        play_poincare(system, 2, transient_periods=-1)


def test_operator_state_is_accepted():
    system = erf_play(2.9)
    a = play_trajectory(system, 15.0, q0=-1.0, v0=0.1, w0=-1.5)
    b = play_trajectory(system, 15.0, q0=-1.0, v0=0.1, operator_state=PlayState(-1.5, -1.0))
    np.testing.assert_array_equal(a.q, b.q)


@pytest.mark.parametrize("width", [0.01, 0.5, 2.0, 5.0])
def test_parameter_sweep_keeps_the_play_constraints(width):
    for coupling in [0.0, 1.0, 2.5, 4.0, 8.0]:
        system = erf_play(coupling, width=width)
        tr = play_trajectory(system, 300.0, sample_dt=0.05)
        kind = tr.events["kind"]
        assert np.all(kind[1:] != kind[:-1])  # hits and reversals alternate
        assert np.max(np.abs(tr.q - tr.w)) <= width / 2 + 1e-12
        ev = tr.events
        np.testing.assert_allclose(np.abs(ev["q"] - ev["w"]), width / 2, atol=1e-12)
        # the wagon only moves while the input drags it: after a reversal w stays at the value
        # of that event; after a hit the input is on the wall, w = q -+ p/2
        last = np.searchsorted(ev["time"], tr.t, side="right") - 1
        after = last >= 0
        inside = after & (kind[np.maximum(last, 0)] == -1)
        assert np.all(tr.w[inside] == ev["w"][last[inside]])
        dragged = after & (kind[np.maximum(last, 0)] == 1)
        np.testing.assert_allclose(np.abs(tr.q[dragged] - tr.w[dragged]), width / 2, atol=1e-12)
