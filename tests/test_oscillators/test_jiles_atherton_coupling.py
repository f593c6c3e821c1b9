"""Jiles–Atherton coupled to the forced oscillator through the generic continuous engine: the
Jacobian of the stroboscopic map (``system.jacobian``: the branch memory ``M_irr0`` frozen, its
reversal reinitialised from the driven gradient) against central differences of
``system.stroboscopic_map``, in the coordinates ``(q, v, φ, M_irr0)`` with ``M_irr0`` the value
of the current branch at its start (converted here by integrating the branch ODE
independently), and the ill-posed model stopping a coupled run with its own error.

Tolerances as in test_duhem_coupling.py: maps integrated to ~1e-11, central differences with
step 1e-6 carry errors ~1e-5 relative at worst.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from hysteresis import JilesAtherton
from hysteresis.jiles_atherton import JilesAthertonInstability
from oscillators.results import OscillatorState
from oscillators.system import ForcedOscillator

ZETA, OMEGA = 0.05, 1.0
TIGHT = {"rtol": 1e-12, "atol": 1e-12}
JA = JilesAtherton(ms=1.0, a=0.5, k=0.4, c=0.2, alpha=0.3)
FD_STEP = 1e-6
FD_TOLERANCE = 1e-5


def branch_value(d, u_a, z_a, u_b):
    """``M_irr`` at ``u_b`` on the branch of direction ``d`` through ``(u_a, z_a)`` (either
    side), integrated in H by solve_ivp (DOP853, 1e-12), not by the operator's own path."""
    if u_a == u_b:
        return z_a
    sol = solve_ivp(
        lambda u, x: [JA.slope(u, x[0], d)], (u_a, u_b), [z_a], method="DOP853", **TIGHT
    )
    return float(sol.y[0, -1])


def test_jacobian_against_central_differences_of_the_stroboscopic_map():
    system = ForcedOscillator(JA, coupling=0.8, damping_ratio=ZETA, frequency=OMEGA)
    pre = system.engine(system.initial_state(), **TIGHT)
    pre.advance(np.array([30.0]), record=True)
    events = pre.records()["events"]
    t_rev = events["time"][events["kind"] == -1][2]
    warm = system.engine(system.initial_state(), **TIGHT)
    warm.advance(np.array([t_rev + 0.3]))
    start = warm.state()
    d0 = 1 if start.v > 0 else -1
    q_s, z_s = start.q, start.operator_state.z

    eng = system.engine(start, **TIGHT)
    eng.start_tangent(include_phase=True)
    assert eng.tangent_space == ("q", "v", "phi", "z-" if d0 > 0 else "z+")
    eng.advance(np.array([system.period]), record=True)
    jac, labels1 = eng.deviations(), eng.tangent_space
    ev = eng.records()["events"]
    assert np.sum(ev["kind"] == -1) >= 1  # the driven gradient was used at a reversal
    end = eng.state()
    d1 = 1 if end.v > 0 else -1
    q_r = float(ev["q"][ev["kind"] == -1][-1])  # where the last branch began
    assert labels1[3] == ("z-" if d1 > 0 else "z+")

    def build(x):
        z = branch_value(d0, q_s, float(x[3]), float(x[0]))
        return OscillatorState(float(x[0]), x[1], x[2], JA.state(z, float(x[0]), d0))

    def read(state):
        z0 = branch_value(d1, state.q, state.operator_state.z, q_r)
        return np.array([state.q, state.v, state.phi, z0])

    x0 = np.array([q_s, start.v, start.phi, z_s])
    cols = []
    for j in range(4):
        xp, xm = x0.copy(), x0.copy()
        xp[j] += FD_STEP
        xm[j] -= FD_STEP
        fp = read(system.stroboscopic_map(build(xp), engine_options=TIGHT))
        fm = read(system.stroboscopic_map(build(xm), engine_options=TIGHT))
        cols.append((fp - fm) / (2 * FD_STEP))
    fd = np.array(cols).T
    np.testing.assert_allclose(jac, fd, rtol=0, atol=FD_TOLERANCE * np.max(np.abs(fd)))


def test_an_ill_posed_model_stops_the_coupled_run_with_its_error():
    """c = 0, α·ms/(3a) = 2, k ≪ a: the virgin curve from the demagnetised state hits
    ``1 − αχ = 0`` at ``H* = k(1 − ln 2)`` (test_jiles_atherton.py); the oscillator pushed
    from q = 0 upward reaches it."""
    ill = JilesAtherton(ms=1.0, a=1.0, k=1e-3, c=0.0, alpha=6.0)
    system = ForcedOscillator(ill, coupling=0.1, damping_ratio=ZETA, frequency=OMEGA)
    with pytest.raises(JilesAthertonInstability) as info:
        system.trajectory(5.0, q0=0.0, v0=0.5, operator_state=ill.state(0.0, 0.0))
    assert info.value.field == pytest.approx(1e-3 * (1 - np.log(2.0)), rel=1e-3)
