"""Periodic orbits and continuation of operators whose memory is set through the contract
(``with_memory`` / ``memory_restart``): Duhem operators (Bouc–Wen) alone and in sums.

Truths: the Floquet multipliers against the eigenvalues of a central-difference Jacobian of the
stroboscopic map in the coordinates ``(q, v, *memory)``; ``ln|μ_max|/T`` against the Benettin
``λ_max``; a continued Bouc–Wen branch against the orbit a long forward integration settles on.
"""

from __future__ import annotations

import numpy as np
import pytest

from analysis.dynamics.continuation import continue_orbit
from analysis.dynamics.lyapunov import lyapunov_spectrum
from analysis.dynamics.orbit_coordinates import StateCoordinates
from analysis.dynamics.periodic_orbits import find_periodic_orbit
from hysteresis import BoucWen, StaticMap
from oscillators import ForcedOscillator
from tests.duhem_support import relaxing_duhem

#: the Bouc–Wen operator of the tests: z_max = 1, loops of unit height
BOUC_WEN = BoucWen(1.0, 0.5, 0.5, 1.0)


def _sech2(u):
    return 1.0 / np.cosh(u) ** 2


def _settled(system, periods: int, q0: float = 0.3, v0: float = 0.1, options=None):
    eng = system.engine(system.initial_state(q0=q0, v0=v0), **(options or {}))
    eng.advance(np.array([periods * system.period]))
    return eng.state()


def _map(system, coords, template, x, options=None):
    eng = system.engine(coords.state(x, template), **(options or {}))
    eng.advance(np.array([system.period]))
    return coords.vector(eng.state())


def _fd_jacobian(system, coords, template, x, h, options=None):
    cols = []
    for j in range(x.size):
        e = np.zeros(x.size)
        e[j] = h
        cols.append(
            (
                _map(system, coords, template, x + e, options)
                - _map(system, coords, template, x - e, options)
            )
            / (2 * h)
        )
    return np.array(cols).T


@pytest.mark.parametrize(
    ("operator", "method", "kind"),
    [
        # the generic engine's rows are the branch-start z0: the contract's memory chart
        (BOUC_WEN, "generic", "memory"),
        # the compiled Duhem engine's row is the current z: the chart is the identity
        (BOUC_WEN, "auto", "duhem"),
        (
            0.5 * BOUC_WEN + 0.3 * relaxing_duhem() + 0.2 * StaticMap(np.tanh, _sech2),
            "auto",
            "memory",
        ),
    ],
    ids=["bouc-wen-generic", "bouc-wen-compiled", "two-duhem-sum"],
)
def test_multipliers_match_finite_difference_jacobian(operator, method, kind):
    options = {"method": method}
    system = ForcedOscillator(operator, coupling=-0.5, damping_ratio=0.1, frequency=1.0)
    orbit = find_periodic_orbit(
        system,
        _settled(system, 15, options=options),
        transient=0,
        max_period=2,
        engine_options=options,
    )
    assert orbit.period == 1
    coords = StateCoordinates(system, orbit.start, engine_options=options)
    assert coords.kind == kind
    x = coords.vector(orbit.start)
    # h = 1e-4: truncation h²/6·|P'''| ~ 1e-9, the integration's noise (rtol 1e-11, Duhem
    # 1e-12) / h ~ 1e-7; measured differences 4e-6 (the third derivative of the events)
    jac = _fd_jacobian(system, coords, orbit.start, x, 1e-4, options)
    np.testing.assert_allclose(orbit.monodromy, jac, atol=5e-5)
    fd = np.sort_complex(np.linalg.eigvals(jac))
    np.testing.assert_allclose(np.sort_complex(orbit.multipliers), fd, atol=5e-5)


def test_exponent_matches_benettin():
    system = ForcedOscillator(BOUC_WEN, coupling=-0.5, damping_ratio=0.1, frequency=1.0)
    orbit = find_periodic_orbit(system, _settled(system, 15), transient=0, max_period=2)
    assert orbit.stable
    expected = float(np.log(np.max(np.abs(orbit.multipliers))) / system.period)
    periods = 40
    got = lyapunov_spectrum(system, periods * system.period, state=orbit.start).exponents[0]
    # Benettin from a point on the orbit: the QR start contributes O(1)/t (the log of the
    # leading vector's initial projection), t = 40·2π: a few 1e-3
    assert abs(got - expected) < 4.0 / (periods * system.period)


@pytest.mark.slow
def test_bouc_wen_continuation_in_coupling_matches_settled_orbits():
    """``q'' + 2ζq' + q = cos t + C·z``, C from −0.5 to −0.8 (C = −k, the hysteretic
    spring): each branch point is the orbit the motion settles on."""
    system = ForcedOscillator(BOUC_WEN, coupling=-0.5, damping_ratio=0.1, frequency=1.0)
    orbit = find_periodic_orbit(system, _settled(system, 15), transient=0, max_period=2)
    branch = continue_orbit(system, orbit, -0.5, -0.8, step=0.1, max_points=6)
    assert branch.points[-1].parameter <= -0.8 + 1e-12, branch.stop_reason
    for point in branch.points[1 :: max(1, len(branch.points) // 3)]:
        settled = ForcedOscillator(
            BOUC_WEN, coupling=point.parameter, damping_ratio=0.1, frequency=1.0
        )
        end = _settled(settled, 40)
        # settled to |μ_max|^40 ~ 1e-13 of the start's distance; the integration 1e-10
        got = np.array([end.q, end.v, end.operator_state.z])
        np.testing.assert_allclose(got, point.point, atol=1e-8)
        assert np.max(np.abs(point.multipliers)) < 1.0


def test_bouc_wen_with_memory_round_trip_and_clip():
    state = BOUC_WEN.state(0.25, 0.4)
    flow = BOUC_WEN.branch_flow(state, 1)
    again = BOUC_WEN.with_memory(state, flow.memory, 0.4, 1)
    assert again.z == state.z and again.input == state.input
    assert BOUC_WEN.with_memory(state, [1.5], 0.4, -1).z == BOUC_WEN.z_max
    with pytest.raises(ValueError, match="one memory value"):
        BOUC_WEN.with_memory(state, [0.1, 0.2], 0.4, 1)
    assert (
        StaticMap(np.tanh).with_memory(StaticMap(np.tanh).initial_state(0.0), [], 2.0, 1).input
        == 2.0
    )
