"""Duhem operators (hysteresis.duhem) and Bouc–Wen (hysteresis.bouc_wen) against closed forms.

* Bouc–Wen with n = 1: every piece of constant direction d and sign s of z is the exponential
  ``z = A/λ + (z0 − A/λ)·exp(−λ(u − u0))``, ``λ = β·d + γ·s`` (the zero crossing located in
  closed form too);
* ``apply`` continues exactly from a returned state, and is rate independent (a finer sampling
  of the same path gives the same outputs at the common inputs);
* the initial state (``z_max``) is the limit of a long rise from negative saturation;
* a linear Duhem operator (``g₊ = 1 − z``, ``g₋ = 1 + z``) whose branch flow (output, partials,
  the variational ``Φ = ∂Z/∂z0``, the driven gradient) is known in closed form;
* the Bouc–Wen restoring force ``α·k·u + (1 − α)·k·z`` as a sum in the operator algebra;
* bad parameters: one-line errors naming the parameter.

Tolerances: the branch ODE is integrated with DOP853 at rtol = atol = 1e-12 (hysteresis.duhem),
a few 1e-12 on branches of unit length; 1e-10 leaves a factor ~30 of margin.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from hysteresis.base import ContinuousHysteron
from hysteresis.bouc_wen import BoucWen
from hysteresis.duhem import Duhem, DuhemState
from hysteresis.static_map import StaticMap

TOL = 1e-10
A, BETA, GAMMA = 1.0, 0.5, 0.3


def bw_n1_reference(u, z0, A, beta, gamma):
    """Bouc–Wen n = 1 along the piecewise-linear path through the samples ``u`` from
    ``(u[0], z0)``: exponential pieces, the zero crossing of z solved in closed form."""
    out = [z0]
    z = z0
    for a, b in zip(u[:-1], u[1:], strict=True):
        d = 1.0 if b > a else -1.0
        pos = a
        while pos != b:
            s = math.copysign(1.0, z) if z != 0.0 else d  # at z = 0, z moves with the input
            lam = beta * d + gamma * s
            du = b - pos
            # where would z reach 0 on this exponential (if it goes there)?
            cross = None
            if z != 0.0 and lam != 0.0:
                ratio = (A / lam) / (A / lam - z)
                if ratio > 0.0:
                    t = -math.log(ratio) / lam
                    if 0.0 < t * d < du * d:
                        cross = t
            elif z != 0.0:
                t = -z / A
                if 0.0 < t * d < du * d:
                    cross = t
            if cross is None:
                z = A / lam + (z - A / lam) * math.exp(-lam * du) if lam else z + A * du
                pos = b
            else:
                z, pos = 0.0, pos + cross
        out.append(z)
    return np.array(out)


def test_bouc_wen_n1_matches_the_exponential_branches():
    bw = BoucWen(A, BETA, GAMMA, 1.0)
    assert isinstance(bw, ContinuousHysteron) and bw.z_max == pytest.approx(1.25)
    u = np.array([0.0, -0.7, -3.0, 1.5, 0.4, 2.2, -0.5, -0.1, -4.0])
    path = np.concatenate(
        [np.linspace(a, b, 7)[:-1] for a, b in zip(u[:-1], u[1:], strict=True)] + [[u[-1]]]
    )
    for z0 in (bw.z_max, 0.0, -0.4):
        y, state = bw.apply(path, bw.state(z0, 0.0))
        ref = bw_n1_reference(path, z0, A, BETA, GAMMA)
        np.testing.assert_allclose(y, ref, rtol=0, atol=TOL)
        assert state.input == path[-1] and state.z == y[-1] and state.direction == -1
    # γ = β: λ = 0 on unloading, the straight line z0 + A·du
    bw2 = BoucWen(2.0, 0.4, 0.4, 1.0)
    y, _ = bw2.apply([0.0, -0.5], bw2.initial_state(0.0))
    assert y[1] == pytest.approx(bw2.z_max - 1.0, abs=TOL)


def test_apply_continues_exactly_and_is_rate_independent():
    bw = BoucWen(1.3, 0.6, -0.2, 2.5)
    u = np.concatenate(
        [np.linspace(0, 2, 50), np.linspace(2, -1.5, 70), np.linspace(-1.5, 0.7, 40)]
    )
    y, final = bw.apply(u)
    y1, s1 = bw.apply(u[:60])
    y2, s2 = bw.apply(u[60:], s1)
    np.testing.assert_allclose(np.concatenate([y1, y2]), y, rtol=0, atol=TOL)
    assert s2.z == pytest.approx(final.z, abs=TOL)
    # the same path sampled only at its turning points, and at 997 random inputs in between
    coarse = np.array([0.0, 2.0, -1.5, 0.7])
    yc, sc = bw.apply(coarse)
    np.testing.assert_allclose(yc, y[[0, 49, 119, u.size - 1]], rtol=0, atol=TOL)
    assert sc.z == pytest.approx(final.z, abs=TOL)
    rng = np.random.default_rng(29)
    legs = [np.sort(rng.uniform(0.0, 2.0, 300)), -np.sort(rng.uniform(-2.0, 1.5, 400)),
            np.sort(rng.uniform(-1.5, 0.7, 297))]  # fmt: skip
    dense = np.concatenate([[0.0], legs[0], [2.0], legs[1], [-1.5], legs[2], [0.7]])
    yd, _ = bw.apply(dense)
    np.testing.assert_allclose(yd[[0, 301, 702, dense.size - 1]], yc, rtol=0, atol=TOL)


def test_initial_state_is_the_limit_of_a_long_rise_from_negative_saturation():
    for n in (1.0, 2.0, 3.5):
        bw = BoucWen(A, BETA, GAMMA, n)
        # falling far: z → −z_max (negative saturation)
        y, neg = bw.apply([0.0, -60.0], bw.state(0.0, 0.0))
        assert y[-1] == pytest.approx(-bw.z_max, abs=1e-9)
        # rising from there: z → z_max, which initial_state gives at every u0
        y, _ = bw.apply([-60.0, 0.0, 1.0], neg)
        assert y[1] == pytest.approx(bw.z_max, abs=1e-9)
        init = bw.initial_state(1.0)
        assert init == DuhemState(bw.z_max, 1.0, 1) and bw.output(init) == bw.z_max
    assert BoucWen(A, BETA, GAMMA).state(0.0, 0.3) == DuhemState(0.0, 0.3, 0)


def linear_duhem(**kwargs):
    """``g₊ = 1 − z``, ``g₋ = 1 + z``: branches ``1 + (z0 − 1)e^{−(u−u0)}`` rising and
    ``−1 + (z0 + 1)e^{u−u0}`` falling."""
    return Duhem(
        lambda u, z: 1.0 - z,
        lambda u, z: 1.0 + z,
        rising_partials=lambda u, z: (0.0, -1.0),
        falling_partials=lambda u, z: (0.0, 1.0),
        **kwargs,
    )


def test_linear_duhem_branch_flow_in_closed_form():
    op = linear_duhem()
    # initial state: the rising curve through the origin, 1 − e^{−u}
    assert op.initial_state(0.8).z == pytest.approx(1.0 - math.exp(-0.8), abs=TOL)
    assert op.initial_state(-0.5).z == pytest.approx(1.0 - math.exp(0.5), abs=TOL)
    state = op.state(0.2, 0.3)
    for d, label, other in ((1, "z-", "z+"), (-1, "z+", "z-")):
        flow = op.branch_flow(state, d)
        assert flow.labels == (label,) and flow.driven_labels == (other,)
        assert flow.memory[0] == 0.2 and math.isinf(flow.breakpoint)
        for u in (0.3, 0.31, 1.7, -0.4, 3.0):  # either side of u0: the stages look behind
            e = math.exp(-d * (u - 0.3))
            z = d * (1.0 + (0.2 * d - 1.0) * e)
            assert flow.output(u) == pytest.approx(z, abs=TOL)
            d_u, d_m = flow.partials(u)
            assert d_u == pytest.approx(1.0 - d * z, abs=TOL)  # g_d(u, Z)
            assert d_m[0] == pytest.approx(e, abs=TOL)  # Φ = ∂Z/∂z0
            values, d_du, d_dm = flow.driven(u)
            assert values[0] == pytest.approx(z, abs=TOL)
            # the reversed branch's coordinate: g_d − g_{−d} = (1 − dZ) − (1 + dZ)
            assert d_du[0] == pytest.approx(-2.0 * d * z, abs=TOL)
            assert d_dm[0, 0] == pytest.approx(e, abs=TOL)
        # vectorised
        uu = np.array([[0.3, 1.0], [2.0, -1.0]])
        assert flow.output(uu).shape == (2, 2) and flow.partials(uu)[1].shape == (2, 2, 1)
    # the driven gradient against central differences of apply: moving the reversal u* moves
    # the falling branch's value at u_e < u* by Φ₋(u_e)·(g₊ − g₋), Φ₋ = e^{u_e − u*}
    flow = op.branch_flow(state, 1)
    h, us, ue = 1e-5, 1.4, 0.5

    def after_reversal_at(turn):
        return op.apply([0.3, turn, ue], state)[0][-1]

    fd = (after_reversal_at(us + h) - after_reversal_at(us - h)) / (2 * h)
    assert math.exp(ue - us) * flow.driven(us)[1][0] == pytest.approx(fd, abs=1e-8)


def test_output_map_and_generic_bouc_wen():
    bw = BoucWen(A, BETA, GAMMA, 2.0)

    def g(d):
        return lambda u, z: A - abs(z) ** 2 * (BETA * d * np.sign(z) + GAMMA)

    def dg(d):
        return lambda u, z: (0.0, -2.0 * abs(z) * (BETA * d + GAMMA * np.sign(z)))

    generic = Duhem(
        g(1),
        g(-1),
        rising_partials=dg(1),
        falling_partials=dg(-1),
        output=lambda u, z: u + z**2,
        output_partials=lambda u, z: (1.0, 2.0 * z),
        kinks=(0.0,),
    )
    u = np.array([0.0, 1.0, -2.0, 0.5])
    z, _ = bw.apply(u, bw.state(0.1, 0.0))
    y, final = generic.apply(u, generic.state(0.1, 0.0))
    np.testing.assert_allclose(y, u + z**2, rtol=0, atol=TOL)
    flow = generic.branch_flow(final, -1)
    d_u, d_m = flow.partials(0.5)
    zf = final.z
    assert d_u == pytest.approx(1.0 + 2.0 * zf * g(-1)(0.5, zf), abs=TOL)
    assert d_m[0] == pytest.approx(2.0 * zf, abs=TOL)


def test_restoring_force_is_a_sum_in_the_operator_algebra():
    alpha, k = 0.3, 2.0
    bw = BoucWen(A, BETA, GAMMA, 1.0)
    force = alpha * k * StaticMap(np.positive, np.ones_like) + (1 - alpha) * k * bw
    u = np.array([0.0, 1.0, -1.2, 0.4])
    y, _ = force.apply(u)
    z, _ = bw.apply(u)
    np.testing.assert_allclose(y, alpha * k * u + (1 - alpha) * k * z, rtol=0, atol=TOL)
    flow = force.branch_flow(force.initial_state(0.0), -1)
    assert flow.labels == ("1:z+",) and flow.driven_labels == ("1:z-",)


@pytest.mark.parametrize(
    ("args", "name"),
    [
        ((0.0, 0.5, 0.3), "A"),
        ((1.0, 0.5, 0.3, 0.5), "n"),
        ((1.0, 0.2, -0.3), "beta \\+ gamma"),
        ((1.0, -0.1, 0.3), "beta"),
        ((1.0, "0.5", 0.3), "beta"),
    ],
)
def test_bad_parameters_name_themselves(args, name):
    with pytest.raises((ValueError, TypeError), match=f"^{name}"):
        BoucWen(*args)


def test_bad_states_and_functions():
    bw = BoucWen(A, BETA, GAMMA)
    with pytest.raises(ValueError, match="z must lie in"):
        bw.state(1.3, 0.0)
    with pytest.raises(TypeError, match="rising must be a callable"):
        Duhem(1.0, lambda u, z: 0.0, rising_partials=None, falling_partials=None)
    with pytest.raises(TypeError, match="output and output_partials"):
        linear_duhem(output=lambda u, z: z)
    with pytest.raises(TypeError, match="state must be a DuhemState"):
        bw.apply([0.0], state=object())
