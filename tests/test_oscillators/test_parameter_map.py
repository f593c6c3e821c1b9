"""Parameter map (issue 21): every closed-form engine against an independent reference over
ζ ∈ {0, 1e-12, 0.05, 1, 10, 1000}, Ω ∈ {0.01, 0.7, 1 − 1e-14, 1, 1 + 1e-14, 100},
C ∈ {−2, 0.5}, or a refusal naming the limit.

References. Relays (a single ``Relay`` and a small ``PreisachModel.from_relays``): this file's
own ``scipy.integrate.solve_ivp`` (DOP853, or Radau for ζ >= 10 where the system is stiff) at
rtol = atol = 1e-12 with terminal events at the next up / down threshold, the relays flipped
by hand at each event. Plays (``PlayOperator(2)``, ``GeneralizedPlay.erf(2, 1)``): the
toolkit's generic ``ContinuousEngine`` (adaptive DOP853 on the operator's ``branch_flow``,
rtol = atol = 1e-13; it shares no code with the play kernel's closed-form scan).

Tolerance. The reference's local error 1e-12 accumulates over at most ~1e4 steps of a
contracting or neutrally stable flow (|q| = O(1)-O(10) on these horizons) and each event time
carries ~1e-12 error, moved into q by at most |C ΔM| δt² / 2 ≪ 1e-12; the closed forms add
~20 ε/√D per flight (√D >= 1e-6 by ``RESONANCE_LIMIT``, far above it on this grid). Hence
``TOL = 1e-7 · max(1, |q|)`` leaves a margin of >= 10 over what the references guarantee.
"""

from __future__ import annotations

import math
from decimal import Decimal, getcontext

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from hysteresis import GeneralizedPlay, PlayOperator, PreisachModel, Relay
from oscillators import ForcedOscillator
from oscillators.engines.continuous import ContinuousEngine
from oscillators.linear import hom_matrix

ZETAS = (0.0, 1e-12, 0.05, 1.0, 10.0, 1000.0)
OMEGAS = (0.01, 0.7, 1.0 - 1e-14, 1.0, 1.0 + 1e-14, 100.0)
COUPLINGS = (-2.0, 0.5)
T_END = 6.0
TIMES = np.array([0.5, 1.7, 3.1, 4.6, T_END])
TOL = 1e-7


def _operator(name):
    if name == "relay":
        return Relay(0.3, -0.4)
    if name == "preisach":
        return PreisachModel.from_relays(
            np.array([-0.5, 0.2, 0.6, 1.1]), np.array([-0.9, -0.3, 0.1, -0.2]),
            np.array([0.1, 0.2, 0.3, 0.4]),
        )  # fmt: skip
    if name == "play":
        return PlayOperator(2.0)
    return GeneralizedPlay.erf(2.0, 1.0)


def _relay_reference(osc, times):
    """solve_ivp with terminal events at the next thresholds; relays flipped by hand."""
    table = osc.operator.relay_table()
    alpha = np.asarray(table.alpha, dtype=float)
    beta = np.asarray(table.beta, dtype=float)
    state = osc.initial_state()
    y_rel = np.asarray(osc.engine(state).relay_outputs(), dtype=float).copy()
    zeta, omega, c = osc.damping_ratio, osc.frequency, osc.coupling
    method = "Radau" if zeta >= 10.0 else "DOP853"
    t, x = 0.0, np.array([state.q, state.v])
    out = np.empty((times.size, 2))
    k = 0
    while k < times.size:
        m = table.output(y_rel)
        down = y_rel <= 0
        a_next = alpha[down].min() if down.any() else np.inf
        b_next = beta[~down].max() if (~down).any() else -np.inf

        def rhs(s, z, m=m):
            return [z[1], -2.0 * zeta * z[1] - z[0] + math.cos(omega * s) + c * m]

        def up_ev(s, z, a=a_next):
            return z[0] - a

        def dn_ev(s, z, b=b_next):
            return z[0] - b

        up_ev.terminal, up_ev.direction = True, 1
        dn_ev.terminal, dn_ev.direction = True, -1
        sol = solve_ivp(
            rhs, (t, times[-1]), x, method=method, rtol=1e-12, atol=1e-12,
            events=(up_ev, dn_ev), dense_output=True,
        )  # fmt: skip
        t_stop = sol.t[-1]
        while k < times.size and times[k] <= t_stop:
            out[k] = sol.sol(times[k])
            k += 1
        if sol.status != 1:
            break
        t, x = t_stop, sol.y[:, -1].copy()
        if sol.t_events[0].size:
            x[0] = a_next
            y_rel[alpha == a_next] = 1.0
        else:
            x[0] = b_next
            y_rel[(beta == b_next) & ~down] = -1.0
    return out[:, 0]


def _play_reference(osc, times):
    eng = ContinuousEngine(osc, osc.initial_state(), rtol=1e-13, atol=1e-13, max_step=0.05)
    out = np.empty((times.size, len(eng.sample_columns)))
    eng.advance(times, out)
    return out[:, 0]


def _refusal(zeta, omega):
    """The expected refusal message for the closed-form engines, or None."""
    if zeta == 0.0 and omega == 1.0:
        return "undamped resonance"
    if math.hypot((1 - omega) * (1 + omega), 2 * zeta * omega) < 1e-6:
        return "too close to resonance.*RESONANCE_LIMIT"
    return None


def _case(name, zeta, omega, coupling):
    msg = _refusal(zeta, omega)
    if msg is None and name in ("play", "erf") and zeta >= 1.0:
        msg = r"damping_ratio must lie in \[0, 1\)"
    if msg is not None:
        with pytest.raises(ValueError, match=msg):
            ForcedOscillator(_operator(name), coupling, zeta, omega)
        return None
    osc = ForcedOscillator(_operator(name), coupling, zeta, omega)
    q = osc.trajectory(T_END, sample_dt=0.1).q
    got = np.interp(TIMES, np.arange(q.size) * 0.1, q)
    # sample times are on the grid (multiples of 0.1): interp returns the sample itself
    if name in ("relay", "preisach"):
        ref = _relay_reference(osc, TIMES)
    else:
        ref = _play_reference(osc, TIMES)
    err = np.max(np.abs(got - ref) / np.maximum(1.0, np.abs(ref)))
    print(f"MAPERR {name} {zeta:g} {omega!r} {coupling:g} {err:.2e}")
    assert err < TOL, (name, zeta, omega, coupling, err)


def _grid(names, slow):
    """All (operator, ζ, Ω, C); the solve_ivp references of stiff (ζ >= 10) or fast-forced
    (Ω = 100) relay cases take seconds each and are marked slow."""
    return [
        pytest.param(
            n,
            z,
            w,
            c,
            id=f"{n}-z{z:g}-w{w!r}-C{c:g}",
            marks=[pytest.mark.slow] if slow and (z >= 10.0 or w >= 100.0) else [],
        )  # fmt: skip
        for n in names
        for z in ZETAS
        for w in OMEGAS
        for c in COUPLINGS
    ]


@pytest.mark.parametrize(("name", "zeta", "omega", "coupling"), _grid(("relay", "preisach"), True))
def test_relay_map(name, zeta, omega, coupling):
    _case(name, zeta, omega, coupling)


@pytest.mark.parametrize(("name", "zeta", "omega", "coupling"), _grid(("play", "erf"), False))
def test_play_map(name, zeta, omega, coupling):
    _case(name, zeta, omega, coupling)


def test_strong_damping_relay():
    """Issue 21: at ζ = 1000 the long Taylor hop used to run ρh = 40 (q = 47.44, not −0.999)."""
    osc = ForcedOscillator(Relay(50, -50), coupling=0.5, damping_ratio=1000, frequency=0.7)
    ref = _relay_reference(osc, np.array([5.0]))[0]
    assert abs(osc.trajectory(5.0).q[-1] - ref) < 1e-9
    jac, _ = osc.jacobian(0.005)
    assert abs(jac[1, 1]) < 1e-4  # exact entry ≈ 4.5e-5 (was 1342.6)


def test_overdamped_propagator_no_cancellation():
    """Φ(h) at ζ up to 1e6 against its eigen form in 60-digit decimal arithmetic: the slow
    eigenvalue −1/(ζ + √(ζ² − 1)) and expm1 keep it to a few ulp of ‖Φ‖ (ω_h − ζ lost 1e-4
    relative at ζ = 1e6)."""
    getcontext().prec = 60
    for zeta in (1.0 + 1e-12, 1.5, 1e3, 1e6):
        for h in (1e-9, 1e-4, 0.3, 5.0, 100.0):
            z, t = Decimal(zeta), Decimal(h)
            wh = ((z - 1) * (z + 1)).sqrt()
            l1, l2 = -z + wh, -z - wh
            a, b = (l1 * t).exp(), (l2 * t).exp()
            ref = [
                (-l2 * a + l1 * b) / (l1 - l2),
                (a - b) / (l1 - l2),
                (l1 * a - l2 * b) / (l1 - l2),
            ]
            m00, m01, _, m11 = hom_matrix(h, zeta)
            scale = max(abs(x) for x in ref)
            err = (
                max(abs(Decimal(x) - r) for x, r in zip((m00, m01, m11), ref, strict=True)) / scale
            )
            assert err < 1e-13, (zeta, h, float(err))
