"""Bouc–Wen (a Duhem operator) coupled to the forced oscillator through the generic continuous
engine, against independent truths.

* the trajectory of the classic Bouc–Wen oscillator ``q'' + 2ζq' + q + k·z = cos Ωt`` (C = −k)
  against an event-driven ``solve_ivp`` integration of ``(q, v, z)`` written here, with
  ``ż = v·g_{sign v}(z)``, the direction flipped at ``v = 0`` and the kink ``z = 0`` of
  ``|z|ⁿ`` as an event; the same for the restoring force ``α·k·q + (1 − α)·k·z`` as a sum in
  the operator algebra;
* the Jacobian of the stroboscopic map (``system.jacobian``: the branch memory ``z0`` frozen,
  its reversal reinitialised from the driven gradient) against central differences of
  ``system.stroboscopic_map``, in the coordinates ``(q, v, φ, z0)`` with ``z0`` the value of the
  current branch at its start (converted here by integrating the branch ODE independently).

Tolerances: both integrations run at rtol = atol = 1e-12 (the engine's branch ODE too), so
trajectories agree to ~1e-9 over 40 time units; 1e-7 is the issue's bar. Central differences
with step 1e-6 of maps integrated to ~1e-11 carry errors ~1e-5 relative at worst.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from hysteresis.bouc_wen import BoucWen
from hysteresis.static_map import StaticMap
from oscillators.engines import ContinuousEngine
from oscillators.engines.select import GenericEngineWarning
from oscillators.results import OscillatorState
from oscillators.system import ForcedOscillator

ZETA, OMEGA = 0.05, 1.0
TIGHT = {"rtol": 1e-12, "atol": 1e-12}
# the generic engine over the branch flow (the compiled Duhem engine has its own tests)
GENERIC = {"method": "generic", **TIGHT}
BW = BoucWen(1.0, 0.5, 0.3, 1.5)
FD_STEP = 1e-6
FD_TOLERANCE = 1e-5


def g(bw, z, d):
    """Bouc–Wen's dz/du, written out independently of the operator."""
    return bw.A - abs(z) ** bw.n * (bw.beta * d * np.sign(z) + bw.gamma)


def reference_trajectory(bw, force, coupling, times, q0, v0, z0):
    """``(q, v, z)`` at ``times`` by solve_ivp in t with events ``v = 0`` (reversal: the
    direction flips) and ``z = 0`` (the kink of |z|ⁿ: restart)."""
    t, y = 0.0, np.array([q0, v0, z0])
    d = 1 if v0 > 0 else -1
    out = np.empty((times.size, 3))
    done = 0
    while done < times.size:

        def rhs(s, x, d=d):
            acc = -2 * ZETA * x[1] - x[0] + math.cos(OMEGA * s) + coupling * force(x[0], x[2])
            return [x[1], acc, x[1] * g(bw, x[2], d)]

        def reversal(s, x):
            return x[1]

        def kink(s, x):
            return x[2]

        reversal.terminal, reversal.direction = True, -d
        kink.terminal = True
        events = [reversal] if y[2] == 0.0 else [reversal, kink]
        sol = solve_ivp(
            rhs, (t, times[-1]), y, method="DOP853", dense_output=True, events=events, **TIGHT
        )
        t_end = sol.t[-1]
        upto = np.searchsorted(times, t_end, side="right") if sol.status == 1 else times.size
        out[done:upto] = sol.sol(times[done:upto]).T
        done = upto
        t, y = t_end, sol.y[:, -1].copy()
        if sol.status == 1 and sol.t_events[0].size:
            y[1], d = 0.0, -d
        elif sol.status == 1:
            y[2] = 0.0
    return out


@pytest.mark.parametrize("kind", ["bouc-wen", "restoring force"])
def test_trajectory_against_an_independent_integration(kind):
    alpha, k = 0.4, 0.8
    if kind == "bouc-wen":
        op, coupling = BW, -k

        def force(q, z):
            return z

    else:
        op = alpha * k * StaticMap(np.positive, np.ones_like) + (1 - alpha) * k * BW
        coupling = -1.0

        def force(q, z):
            return alpha * k * q + (1 - alpha) * k * z

    with warnings.catch_warnings():  # the sum says it runs on the generic engine
        warnings.simplefilter("ignore", GenericEngineWarning)
        system = ForcedOscillator(op, coupling=coupling, damping_ratio=ZETA, frequency=OMEGA)
    assert isinstance(system.engine(method="generic"), ContinuousEngine)
    traj = system.trajectory(40.0, sample_dt=0.05, engine_options=GENERIC)
    ref = reference_trajectory(BW, force, coupling, traj.t, -1.0, 0.1, BW.z_max)
    assert np.max(np.abs(traj.q - ref[:, 0])) < 1e-7
    assert np.max(np.abs(traj.v - ref[:, 1])) < 1e-7
    M_ref = np.array([force(q, z) for q, z in ref[:, [0, 2]]])
    assert np.max(np.abs(traj.M - M_ref)) < 1e-7
    assert np.sum(traj.events["kind"] == -1) >= 8  # reversals happened


def branch_value(bw, d, u_a, z_a, u_b):
    """``z`` at ``u_b`` on the branch of direction ``d`` through ``(u_a, z_a)`` (either side),
    integrated in u independently of the operator, restarted at the kink z = 0."""
    while u_a != u_b:

        def kink(u, x):
            return x[0]

        kink.terminal = True
        sol = solve_ivp(
            lambda u, x: [g(bw, x[0], d)],
            (u_a, u_b),
            [z_a],
            method="DOP853",
            events=None if z_a == 0.0 else [kink],
            **TIGHT,
        )
        u_a, z_a = float(sol.t[-1]), float(sol.y[0, -1])
        if sol.status == 1:
            z_a = 0.0
    return z_a


def test_jacobian_against_central_differences_of_the_stroboscopic_map():
    system = ForcedOscillator(BW, coupling=-0.8, damping_ratio=ZETA, frequency=OMEGA)
    pre = system.engine(system.initial_state(), **GENERIC)
    pre.advance(np.array([30.0]), record=True)
    events = pre.records()["events"]
    t_rev = events["time"][events["kind"] == -1][2]
    warm = system.engine(system.initial_state(), **GENERIC)
    warm.advance(np.array([t_rev + 0.3]))
    start = warm.state()
    d0 = 1 if start.v > 0 else -1
    q_s, z_s = start.q, start.operator_state.z

    eng = system.engine(start, **GENERIC)
    eng.start_tangent(include_phase=True)
    labels0 = eng.tangent_space
    eng.advance(np.array([system.period]), record=True)
    jac, labels1 = eng.deviations(), eng.tangent_space
    assert labels0 == ("q", "v", "phi", "z-" if d0 > 0 else "z+")
    jac_api, _ = system.jacobian(system.period, start, engine_options=GENERIC)
    np.testing.assert_array_equal(jac_api, jac)
    ev = eng.records()["events"]
    assert np.sum(ev["kind"] == -1) >= 1  # the driven gradient was used at a reversal
    end = eng.state()
    d1 = 1 if end.v > 0 else -1
    q_r = float(ev["q"][ev["kind"] == -1][-1])  # where the last branch began
    assert labels1[3] == ("z-" if d1 > 0 else "z+")

    def build(x):
        # z0 is the branch's value at q_s: the state at q holds the branch's value there
        z = branch_value(BW, d0, q_s, float(x[3]), float(x[0]))
        return OscillatorState(float(x[0]), x[1], x[2], BW.state(z, float(x[0]), d0))

    def read(state):
        z0 = branch_value(BW, d1, state.q, state.operator_state.z, q_r)
        return np.array([state.q, state.v, state.phi, z0])

    x0 = np.array([q_s, start.v, start.phi, z_s])
    cols = []
    for j in range(4):
        xp, xm = x0.copy(), x0.copy()
        xp[j] += FD_STEP
        xm[j] -= FD_STEP
        fp = read(system.stroboscopic_map(build(xp), engine_options=GENERIC))
        fm = read(system.stroboscopic_map(build(xm), engine_options=GENERIC))
        cols.append((fp - fm) / (2 * FD_STEP))
    fd = np.array(cols).T
    np.testing.assert_allclose(jac, fd, rtol=0, atol=FD_TOLERANCE * np.max(np.abs(fd)))
    # the memory direction survives the reversals (z0 handed on as a free coordinate)
    assert eng.rank_bound() == 4 == np.linalg.matrix_rank(jac, tol=1e-8)
