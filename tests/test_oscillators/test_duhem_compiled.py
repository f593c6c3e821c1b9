"""The compiled Duhem engine (Bouc–Wen, Jiles–Atherton) against independent truths.

* trajectories against an event-driven ``solve_ivp`` integration of ``(q, v, z)`` written here
  (``z' = v·g_{sign v}(q, z)``, the direction flipped at ``v = 0``, the kink of ``g`` an
  event: Bouc–Wen's ``z = 0`` with ``g`` written out independently, Jiles–Atherton's switch of
  ``δ_M`` through the operator's public ``slope``), and against the generic engine;
* the Jacobian of the flow map in ``(q, v, φ, z)`` against central differences of the
  engine's own map (no saltation at reversals and kinks: the field is continuous there);
* Liouville: the Lyapunov sum over a window is ``−2ζ + ⟨v·∂g/∂z⟩`` exactly (the log of the
  tangent map's determinant), with ``∂g/∂z`` written out and integrated by the reference;
* a periodic orbit of the classic Bouc–Wen oscillator (``C = −k``): its monodromy's determinant
  is the same Liouville integral over one period, and a continuation in ``C`` ends on the orbit
  found afresh there.

Tolerances: the references run at rtol = atol = 1e-12, the engine's RK8 at h = 0.05 errs by
~1e-11 over 40 time units (measured), so trajectories agree to ~1e-10; 1e-7 is the issue's bar.
Central differences with step 1e-6 of maps accurate to ~1e-11 carry errors ~1e-5 at worst.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from analysis.dynamics.continuation import continue_orbit
from analysis.dynamics.lyapunov import lyapunov_spectrum
from analysis.dynamics.periodic_orbits import find_periodic_orbit
from hysteresis import BoucWen, JilesAtherton
from hysteresis.jiles_atherton import JilesAthertonInstability
from oscillators.engines import CompiledDuhemEngine, ContinuousEngine
from oscillators.results import OscillatorState
from oscillators.system import ForcedOscillator

ZETA, OMEGA = 0.05, 1.0
TIGHT = {"rtol": 1e-12, "atol": 1e-12}
FD_STEP = 1e-6
FD_TOLERANCE = 1e-5


def bouc_wen(n: float) -> BoucWen:
    return BoucWen(1.0, 0.5, 0.3, n)


def jiles_atherton() -> JilesAtherton:
    return JilesAtherton(ms=1.0, a=0.5, k=0.4, c=0.2, alpha=0.1)


class Model:
    """``g``, ``∂g/∂z``, the output and the kink of one operator, for the reference."""

    def __init__(self, op):
        self.op = op
        self.bw = isinstance(op, BoucWen)

    def g(self, q, z, d):
        if self.bw:  # written out independently of the operator
            op = self.op
            return op.A - abs(z) ** op.n * (op.beta * d * np.sign(z) + op.gamma)
        return self.op.slope(q, z, d)

    def g_z(self, q, z, d, side):
        if self.bw:
            op = self.op
            return -op.n * abs(z) ** (op.n - 1) * (op.beta * d + op.gamma * side)
        return self.op.slope_partials(q, z, d)[1]

    def output(self, q, z):
        return z if self.bw else self.op.map_output(q, z)

    def kink(self, q, z, d):
        """Negative before the kink, positive past it (Bouc–Wen: ``z`` moving in ``d``)."""
        if self.bw:
            return d * z
        return self.g(q, z, d) - self.g(q, z, -d)


def reference(model, coupling, times, q0, v0, z0):
    """``(q, v, z, ∫ v·∂g/∂z dt)`` at ``times`` by solve_ivp in t with terminal events at the
    reversal ``v = 0`` (the direction flips) and the kink (restart; at most once per monotone
    piece: z' = A·v at z = 0, δ_M switches on only)."""
    t, y = 0.0, np.array([q0, v0, z0, 0.0])
    d = 1 if v0 > 0 else -1
    armed = model.kink(q0, z0, d) < 0.0
    out = np.empty((times.size, 4))
    done = 0
    while done < times.size:
        side = np.sign(y[2]) if y[2] != 0.0 else d  # Bouc–Wen: the side of the kink

        def rhs(s, x, d=d, side=side):
            acc = (
                -2 * ZETA * x[1] - x[0] + math.cos(OMEGA * s) + coupling * model.output(x[0], x[2])
            )
            return [x[1], acc, x[1] * model.g(x[0], x[2], d), x[1] * model.g_z(x[0], x[2], d, side)]

        def reversal(s, x):
            return x[1]

        def kink(s, x, d=d):
            return model.kink(x[0], x[2], d)

        reversal.terminal, reversal.direction = True, -d
        kink.terminal, kink.direction = True, 1
        events = [reversal, kink] if armed else [reversal]
        sol = solve_ivp(
            rhs, (t, times[-1]), y, method="DOP853", dense_output=True, events=events, **TIGHT
        )
        t_end = sol.t[-1]
        upto = np.searchsorted(times, t_end, side="right") if sol.status == 1 else times.size
        if upto > done:
            out[done:upto] = sol.sol(times[done:upto]).T
        done = upto
        t, y = t_end, sol.y[:, -1].copy()
        if sol.status == 1 and sol.t_events[0].size:
            y[1], d = 0.0, -d
            armed = model.kink(y[0], y[2], d) < 0.0
        elif sol.status == 1:
            armed = False
            if model.bw:
                y[2] = 0.0
    return out


def system_of(op, coupling):
    return ForcedOscillator(op, coupling=coupling, damping_ratio=ZETA, frequency=OMEGA)


CASES = {
    "bouc-wen n=1": (lambda: bouc_wen(1.0), -0.8),
    "bouc-wen n=1.5": (lambda: bouc_wen(1.5), -0.8),
    "bouc-wen n=2": (lambda: bouc_wen(2.0), -0.8),
    "jiles-atherton": (jiles_atherton, 0.5),
}


def test_the_contract_selects_the_compiled_engine():
    system = system_of(bouc_wen(1.0), -0.8)
    assert system.engine_class is CompiledDuhemEngine
    assert "Duhem" in system.engine_description
    assert isinstance(system.engine(method="generic"), ContinuousEngine)
    # a general Duhem operator of user functions has no compiled model: the generic engine
    assert BoucWen.compiled_model is not None
    with pytest.raises(ValueError, match="step must lie in"):
        system.engine(step=0.5)


@pytest.mark.parametrize("case", CASES)
def test_trajectory_against_an_independent_integration(case):
    make, coupling = CASES[case]
    op = make()
    system = system_of(op, coupling)
    traj = system.trajectory(40.0, sample_dt=0.05)
    start = system.initial_state()
    ref = reference(Model(op), coupling, traj.t, start.q, start.v, start.operator_state.z)
    assert np.max(np.abs(traj.q - ref[:, 0])) < 1e-7
    assert np.max(np.abs(traj.v - ref[:, 1])) < 1e-7
    m_ref = np.array([Model(op).output(q, z) for q, z in ref[:, [0, 2]]])
    assert np.max(np.abs(traj.M - m_ref)) < 1e-7
    assert np.abs(traj.final.operator_state.z - ref[-1, 2]) < 1e-7
    assert np.sum(traj.events["kind"] == -1) >= 8  # reversals happened
    eng = system.engine()
    eng.advance(40.0)
    assert eng.n_kinks >= 8  # and kinks (z = 0; δ_M switching on)


@pytest.mark.parametrize("case", ["bouc-wen n=1.5", "jiles-atherton"])
def test_compiled_against_the_generic_engine(case):
    make, coupling = CASES[case]
    system = system_of(make(), coupling)
    compiled_traj = system.trajectory(30.0, sample_dt=0.1)
    generic = system.trajectory(30.0, sample_dt=0.1, engine_options={"method": "generic", **TIGHT})
    for field in ("q", "v", "M"):
        assert np.max(np.abs(getattr(compiled_traj, field) - getattr(generic, field))) < 1e-7
    np.testing.assert_array_equal(compiled_traj.events["kind"], generic.events["kind"])
    np.testing.assert_allclose(compiled_traj.events["time"], generic.events["time"], atol=1e-7)


@pytest.mark.parametrize("case", ["bouc-wen n=1", "bouc-wen n=1.5", "jiles-atherton"])
def test_jacobian_against_central_differences(case):
    make, coupling = CASES[case]
    op = make()
    system = system_of(op, coupling)
    warm = system.engine()
    warm.advance(23.3)
    start = warm.state()
    duration = 2 * system.period
    jac, labels = system.jacobian(duration, start)
    assert labels == ("q", "v", "phi", "z")
    eng = system.engine(start)
    eng.start_tangent(include_phase=True)
    eng.advance(duration)
    assert eng.n_events >= 2 and eng.n_kinks >= 2  # reversals and kinks on the way
    assert eng.rank_bound() == 4

    def flow(x):
        state = OscillatorState(x[0], x[1], x[2], op.state(x[3], x[0]))
        e = system.engine(state)
        e.advance(duration)
        end = e.state()
        return np.array([end.q, end.v, end.phi, end.operator_state.z])

    x0 = np.array([start.q, start.v, start.phi, start.operator_state.z])
    fd = np.empty((4, 4))
    for j in range(4):
        step = np.zeros(4)
        step[j] = FD_STEP
        fd[:, j] = (flow(x0 + step) - flow(x0 - step)) / (2 * FD_STEP)
    np.testing.assert_allclose(jac, fd, rtol=0, atol=FD_TOLERANCE * np.max(np.abs(fd)))


def test_lyapunov_sum_is_the_average_divergence():
    op = bouc_wen(1.0)
    system = system_of(op, -0.8)
    transient, t_end = 2 * system.period, 12 * system.period
    res = lyapunov_spectrum(system, t_end, transient=transient)
    assert res.tangent_space == ("q", "v", "z")
    start = system.initial_state()
    ref = reference(Model(op), -0.8, np.array([transient, t_end]), start.q, start.v,
                    start.operator_state.z)  # fmt: skip
    liouville = -2 * ZETA + (ref[1, 3] - ref[0, 3]) / (t_end - transient)
    # the QR loop's Σ log|R_ii| is the log of the tangent map's determinant: exact to the
    # integrations' errors (~1e-10 over the window)
    assert abs(np.sum(res.exponents) - liouville) < 1e-8
    assert np.all(np.isfinite(res.exponents))  # nothing reset: rank 3 throughout


def test_periodic_orbit_floquet_and_continuation_of_the_bouc_wen_oscillator():
    op = bouc_wen(1.0)
    k = 0.8  # q'' + 2ζq' + q + k·z = cos t  (C = −k)
    system = system_of(op, -k)
    orbit = find_periodic_orbit(system, transient=100)
    assert orbit.period == 1 and orbit.tangent_space == ("q", "v", "z") and orbit.stable
    state = orbit.states[0]
    ref = reference(Model(op), -k, np.array([system.period]), state.q, state.v,
                    state.operator_state.z)  # fmt: skip
    assert np.max(np.abs(ref[0, :3] - orbit.points[0])) < 1e-8  # periodic for the reference too
    # Liouville over one period: det(monodromy) = exp(−2ζT + ∫ v·∂g/∂z dt)
    det = np.prod(orbit.multipliers).real
    assert det == pytest.approx(math.exp(-2 * ZETA * system.period + ref[0, 3]), rel=1e-7)
    cont = continue_orbit(system, orbit, -k, -0.6, step=0.05)
    assert cont.stop_reason == "reached stop" and not cont.events
    end = cont.points[-1]
    assert end.parameter == pytest.approx(-0.6) and end.period == 1
    fresh = find_periodic_orbit(system_of(op, -0.6), transient=100)
    np.testing.assert_allclose(end.point, fresh.points[0], atol=1e-8)
    np.testing.assert_allclose(np.sort(np.abs(end.multipliers)),
                               np.sort(np.abs(fresh.multipliers)), atol=1e-7)  # fmt: skip


def test_a_fast_jiles_atherton_relaxation_against_the_reference():
    """k = 0.05 with |v| up to ~7: M_irr relaxes at |v|/k ~ 130 per unit time, faster than
    the RK8 step resolves (h·λ ~ 6: a fixed step of 0.045 errs by 5e-4 here); the steps keep
    h·λ <= RELAX_STEP. The model never reaches its pole on these motions (the gap stays below
    k·ms/(3a): ``jiles_atherton_slope_bound``), which the reference confirms by running
    through."""
    op = JilesAtherton(ms=1.0, a=0.2, k=0.05, c=0.1, alpha=0.2)
    system = system_of(op, 0.5)
    traj = system.trajectory(40.0, sample_dt=0.05)
    start = system.initial_state()
    ref = reference(Model(op), 0.5, traj.t, start.q, start.v, start.operator_state.z)
    assert np.max(np.abs(traj.v)) > 6.0  # the fast motion happened
    assert np.max(np.abs(traj.q - ref[:, 0])) < 1e-7
    assert np.max(np.abs(traj.v - ref[:, 1])) < 1e-7
    assert np.abs(traj.final.operator_state.z - ref[-1, 2]) < 1e-7


def test_an_ill_posed_jiles_atherton_state_is_refused():
    """c = 0, M_irr = −0.9 at H = 0.3 rising: ``α(M_an − M_irr)/k = 1.88 > 1`` at the start
    (test_jiles_atherton.py): the engine refuses it with the operator's own error."""
    op = JilesAtherton(ms=1.0, a=1.0, k=0.1, c=0.0, alpha=0.2)
    system = system_of(op, 0.5)
    start = OscillatorState(0.3, 0.5, 0.0, op.state(-0.9, 0.3))
    with pytest.raises(JilesAthertonInstability, match="ill-posed") as info:
        system.engine(start)
    assert info.value.field == 0.3
