"""Periodic orbits, Floquet multipliers and continuation of composites whose memory chart is set
through the contract (``with_memory`` / ``memory_restart``, :mod:`hysteresis.composite_memory`):
cascades ``outer[inner[u]]`` and numeric inverses, on the generic continuous engine.

Truths: the multipliers against the eigenvalues of a central-difference Jacobian of the
stroboscopic map in the coordinates ``(q, v, *memory)``; ``ln|μ_max|/T`` against the Benettin
``λ_max``; two plays in a row against the one play of the summed width (the semigroup of plays);
a continued branch against the orbit a long forward integration settles on.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from analysis.dynamics.continuation import continue_orbit
from analysis.dynamics.lyapunov import lyapunov_spectrum
from analysis.dynamics.orbit_coordinates import StateCoordinates
from analysis.dynamics.periodic_orbits import find_periodic_orbit
from hysteresis import BoucWen, Cascade, PlayOperator, PrandtlIshlinskii, StaticMap
from hysteresis.inverse import InverseOperator
from oscillators import ForcedOscillator
from tests.duhem_support import relaxing_duhem
from tests.test_analysis.dynamics.test_memory_orbits import _fd_jacobian

GENERIC = {"method": "generic"}
#: an invertible Prandtl–Ishlinskii operator (a width-0 play: min_slope 1, max_slope 2)
PI = PrandtlIshlinskii([0.0, 0.5, 1.0, 2.0], [1.0, 0.5, 0.3, 0.2])


def _sech2(u):
    return 1.0 / np.cosh(u) ** 2


#: the generalized play tanh(w): Cascade(play, StaticMap)
PLAY_TANH = Cascade(PlayOperator(1.0), StaticMap(np.tanh, _sech2))
#: two plays in a row: on every history from initial_state, one play of width 1.5
PLAY_PLAY = Cascade(PlayOperator(1.0), PlayOperator(0.5))


def _settled(system, periods: int, q0: float = 0.3, v0: float = 0.1):
    eng = system.engine(system.initial_state(q0=q0, v0=v0), **GENERIC)
    eng.advance(np.array([periods * system.period]))
    return eng.state()


def _orbit(operator, coupling: float = 0.3, periods: int = 15):
    system = ForcedOscillator(operator, coupling=coupling, damping_ratio=0.1, frequency=1.0)
    orbit = find_periodic_orbit(
        system, _settled(system, periods), transient=0, max_period=2, engine_options=GENERIC
    )
    assert orbit.period == 1
    return system, orbit


@pytest.mark.parametrize(
    ("operator", "labels"),
    [
        (PLAY_TANH, ("in:w",)),
        (InverseOperator(PI), ("w3",)),
        (InverseOperator(PI + 0.5 * StaticMap(np.tanh, _sech2)), ("0:w3",)),
    ],
    ids=["cascade-play-tanh", "inverse-pi", "inverse-pi-plus-tanh"],
)
def test_multipliers_match_finite_difference_jacobian(operator, labels):
    system, orbit = _orbit(operator)
    coords = StateCoordinates(system, orbit.start, engine_options=GENERIC)
    assert coords.kind == "memory" and coords.labels[2:] == labels
    x = coords.vector(orbit.start)
    # h = 1e-4: truncation h²/6·|P'''| ~ 1e-9, the integration's noise (rtol 1e-11) / h, and
    # the inverse's root solves (relative 8ε) / h ~ 1e-10; measured differences <= 1e-9
    jac = _fd_jacobian(system, coords, orbit.start, x, 1e-4, GENERIC)
    np.testing.assert_allclose(orbit.monodromy, jac, atol=1e-7)
    fd = np.sort_complex(np.linalg.eigvals(jac))
    np.testing.assert_allclose(np.sort_complex(orbit.multipliers), fd, atol=1e-7)


def test_two_plays_in_a_row_are_the_play_of_the_summed_width():
    """``P_0.5[P_1[u]] = P_1.5[u]`` from initial_state: the same orbit, and its multipliers
    those of the play plus zeros. The outer wagon always sits on a wall (it is the one play's
    wagon seen from the inner's), so the section lies on the boundary of the strip: the
    monodromy is the one-sided derivative into it, and the central differences of the map
    agree along the reachable direction (inner and outer wagons moved together)."""
    system, orbit = _orbit(PLAY_PLAY)
    coords = StateCoordinates(system, orbit.start, engine_options=GENERIC)
    x = coords.vector(orbit.start)
    assert coords.labels[2:] == ("in:w", "out:w")
    assert abs(abs(x[3] - x[2]) - 0.25) < 1e-12  # the outer wagon on a wall
    play = ForcedOscillator(PlayOperator(1.5), coupling=0.3, damping_ratio=0.1, frequency=1.0)
    start = replace(orbit.start, operator_state=PlayOperator(1.5).state(x[3], orbit.start.q))
    single = find_periodic_orbit(play, start, transient=0, max_period=2)
    np.testing.assert_allclose([single.start.q, single.start.v], x[:2], atol=1e-9)
    np.testing.assert_allclose(single.start.operator_state.position, x[3], atol=1e-9)
    mu = np.sort_complex(orbit.multipliers)
    expected = np.sort_complex(np.append(single.multipliers, 0.0))
    np.testing.assert_allclose(mu, expected, atol=1e-8)
    # central differences: the same multipliers, and the same derivative along the wagons.
    # At the strip's boundary a difference mixes two one-sided derivatives whose h² terms do
    # not cancel: error O(h·|P''|) ~ 1e-5 at h = 1e-4 (measured 2e-6)
    jac = _fd_jacobian(system, coords, orbit.start, x, 1e-4, GENERIC)
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(jac)), mu, atol=2e-5)
    both = np.array([0.0, 0.0, 1.0, 1.0])
    np.testing.assert_allclose(orbit.monodromy @ both, jac @ both, atol=2e-5)


def test_play_driving_bouc_wen_chart_through_the_chain_rule():
    """``Cascade(play, BoucWen)``: the outer's branch memory ``z0`` is restarted at the inner
    output ``x = w`` (``δz = g·δx + Φ·δz0``). The section finds the inner wagon dragged on its
    wall: the monodromy's column of ``in:w`` is the derivative into the strip, the outward one
    vanishes (the wagon is put back on the wall: the same state), so the central difference is
    half of it (and ``q``'s column, which moves the wall, is one-sided too); ``v``, ``z`` and
    ``q`` with the wagon, and the multipliers, agree."""
    system, orbit = _orbit(Cascade(PlayOperator(1.0), BoucWen(1.0, 0.5, 0.5, 1.0)), -0.5)
    coords = StateCoordinates(system, orbit.start, engine_options=GENERIC)
    assert coords.labels[2] == "in:w" and coords.labels[3] in ("out:z-", "out:z+")
    x = coords.vector(orbit.start)
    assert abs(abs(x[0] - x[2]) - 0.5) < 1e-12  # the inner wagon on its wall
    # h = 1e-4 on a Duhem branch (rtol 1e-12): measured differences 1e-6 (events' h² terms)
    jac = _fd_jacobian(system, coords, orbit.start, x, 1e-4, GENERIC)
    mono = orbit.monodromy
    np.testing.assert_allclose(mono[:, [1, 3]], jac[:, [1, 3]], atol=2e-5)
    np.testing.assert_allclose(0.5 * mono[:, 2], jac[:, 2], atol=2e-5)
    # q and the wagon moved together keep the wagon on its wall: no kink
    np.testing.assert_allclose(mono[:, 0] + mono[:, 2], jac[:, 0] + jac[:, 2], atol=2e-5)
    fd = np.sort_complex(np.linalg.eigvals(jac))
    np.testing.assert_allclose(np.sort_complex(orbit.multipliers), fd, atol=2e-5)


def test_exponent_matches_benettin():
    system, orbit = _orbit(InverseOperator(PI))
    assert orbit.stable
    expected = float(np.log(np.max(np.abs(orbit.multipliers))) / system.period)
    periods = 30
    got = lyapunov_spectrum(
        system, periods * system.period, state=orbit.start, engine_options=GENERIC
    ).exponents[0]
    # Benettin from a point on the orbit: the QR start contributes O(1)/t (the log of the
    # leading vector's initial projection), t = 30·2π: a few 1e-3
    assert abs(got - expected) < 4.0 / (periods * system.period)


@pytest.mark.parametrize(
    ("operator", "stop"),
    # the inverse's chart holds the forward's frozen wagons only: below C ~ 0.144 a wall hit of
    # the forward crosses the section and the chart loses a coordinate, so the range stops short
    [(PLAY_TANH, 0.5), (InverseOperator(PI), 0.2)],
    ids=["cascade-play-tanh", "inverse-pi"],
)
def test_continuation_in_coupling_matches_settled_orbits(operator, stop):
    system, orbit = _orbit(operator)
    branch = continue_orbit(
        system, orbit, 0.3, stop, step=0.1, max_points=4, engine_options=GENERIC
    )
    assert abs(branch.points[-1].parameter - stop) < 1e-12, branch.stop_reason
    point = branch.points[-1]
    settled = ForcedOscillator(operator, coupling=point.parameter, damping_ratio=0.1)
    end = _settled(settled, 40)
    got = StateCoordinates(settled, end, engine_options=GENERIC).vector(end)
    # settled to |μ_max|^40 <= 0.6^40 ~ 1e-9 of the start's distance; the integration 1e-10
    np.testing.assert_allclose(got, point.point, atol=1e-7)
    assert np.max(np.abs(point.multipliers)) < 1.0


def test_inverse_of_a_duhem_operator_is_refused_in_one_sentence():
    """Its branch memory z0 is the forward output at the branch start, which is the
    inverse's input: it does not determine the forward input."""
    system = ForcedOscillator(InverseOperator(relaxing_duhem()), coupling=0.3, damping_ratio=0.1)
    with pytest.raises(ValueError, match="does not determine its input") as info:
        StateCoordinates(system, system.initial_state(q0=0.3, v0=0.1), engine_options=GENERIC)
    assert str(info.value).count(". ") == 0


def test_cascade_with_memory_keeps_a_dragged_outer_on_its_wall():
    state = PLAY_PLAY.initial_state(0.0)  # inner w = -0.5, outer w = -0.75: both dragged up
    flow = PLAY_PLAY.branch_flow(state, 1)
    assert flow.labels == ("in:w",) and flow.driven_labels == ("out:w",)
    moved = PLAY_PLAY.with_memory(state, [0.1], 0.6, 1)  # the inner on its wall
    assert moved.inner.position == 0.1 and moved.outer.position == 0.1 - 0.25
    values, d_du, d_dm = PLAY_PLAY.memory_restart(moved, 1, 0.9)
    np.testing.assert_array_equal(values, [0.4])
    np.testing.assert_array_equal(d_du, [0.0])
    np.testing.assert_array_equal(d_dm, [[1.0]])
    # the outer frozen (after a reversal of the inner output): a coordinate, clipped to the strip
    down = PLAY_PLAY.apply(np.array([0.0, -0.2]), state)[1]
    assert PLAY_PLAY.branch_flow(down, -1).labels == ("in:w", "out:w")
    again = PLAY_PLAY.with_memory(down, [-0.5, 9.0], -0.2, -1)
    assert again.outer.position == -0.5 + 0.25
    with pytest.raises(ValueError, match="must hold 2 memory values"):
        PLAY_PLAY.with_memory(down, [0.1], -0.2, -1)


def test_inverse_with_memory_round_trip():
    inverse = InverseOperator(PI)
    _, state = inverse.apply(np.array([0.0, 1.5, 0.4]))
    flow = inverse.branch_flow(state, 1)
    again = inverse.with_memory(state, flow.memory, state.input, 1)
    np.testing.assert_allclose(again.forward.positions, state.forward.positions, atol=1e-14)
    assert again.input == state.input
    values, d_dy, d_dm = inverse.memory_restart(state, 1, state.input + 0.1)
    np.testing.assert_allclose(values, flow.memory)
    np.testing.assert_array_equal(d_dy, np.zeros(flow.n_memory))
    np.testing.assert_array_equal(d_dm, np.eye(flow.n_memory))
