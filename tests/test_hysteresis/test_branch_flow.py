"""BranchFlow of every continuous operator against finite differences of ``apply``.

The truth is the operator's own rate-independent ``apply`` (independent of ``branch_flow``):
the flow's ``y(u)`` must be the output reached by moving the input monotonically to ``u``, its
slope and memory partials the central differences of such outputs, its breakpoint the input at
which the memory structure changes as declared (reset / removed / pushed labels).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from relay_test_support import gauss_everett_model
from scipy.special import ndtr

from hysteresis import (
    GeneralizedPlay,
    PlayOperator,
    PrandtlIshlinskii,
    PreisachModel,
)
from hysteresis.flow import BranchFlow

H = 1e-6


def _tanh_play(width=1.6):
    return GeneralizedPlay(
        width, lambda w: np.tanh(np.asarray(w)), lambda w: 1.0 / np.cosh(np.asarray(w)) ** 2
    )


def _gauss_everett_model(scale=1.3, lower=-6.0, upper=6.0):
    """Product density ∝ φ(α)φ(β) with closed-form Everett and gradient (relay_test_support)."""
    return gauss_everett_model(scale, lower, upper)


def _gauss_density_model(sigma_r=0.3, resolution=256):
    def density(a, b):
        r = 0.5 * (a - b)
        s = 0.5 * (a + b)
        rs = np.exp(-0.5 * s**2) / math.sqrt(2 * math.pi)
        rs = rs * np.exp(-0.5 * ((r - 1.0) / sigma_r) ** 2) / (sigma_r * math.sqrt(2 * math.pi))
        return 0.5 * rs

    return PreisachModel.from_density(density, -7.0, 7.0, resolution=resolution)


def _out(op, u, state):
    return float(op.apply(np.array([u]), state)[0][0])


def _check_output_and_slope(op, state, flow: BranchFlow, span: float) -> None:
    """y(u) and dy/du against apply along the branch (before the breakpoint)."""
    u0 = flow.input
    d = flow.direction
    bp = flow.breakpoint
    end = u0 + d * span
    if math.isfinite(bp):
        end = u0 + d * min(span, 0.9 * abs(bp - u0))
    for u in np.linspace(u0, end, 7)[1:]:
        assert float(flow.output(u)) == pytest.approx(_out(op, u, state), abs=1e-12)
        if abs(u - u0) > 2 * H and (not math.isfinite(bp) or abs(bp - u) > 2 * H):
            fd = (_out(op, u + H, state) - _out(op, u - H, state)) / (2 * H)
            assert float(flow.slope(u)) == pytest.approx(fd, rel=1e-6, abs=1e-7)
    # vectorised evaluation agrees with scalar evaluation
    us = np.linspace(u0, end, 4)
    d_u, d_m = flow.partials(us)
    assert np.asarray(d_m).shape == (4, flow.n_memory)
    np.testing.assert_allclose(flow.output(us), [float(flow.output(x)) for x in us], atol=1e-14)
    for i, x in enumerate(us):
        np.testing.assert_allclose(np.asarray(flow.partials(x)[1]), np.asarray(d_m)[i], atol=1e-14)


# ------------------------------------------------------------------------------------------
# play and generalized play
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("op", [PlayOperator(1.2), _tanh_play()], ids=["play", "tanh"])
def test_play_flow_inside_and_on_wall(op):
    half = op.half_width
    inside = op.state(position=0.3, input=0.3 + 0.2 * half)
    for d in (1, -1):
        flow = op.branch_flow(inside, d)
        assert flow.labels == ("w",) and not flow.slaved[0]
        assert flow.breakpoint == pytest.approx(0.3 + d * half)
        assert flow.breakpoint_resets == ("w",)
        _check_output_and_slope(op, inside, flow, 5.0)
        # ∂y/∂w against apply from states with a perturbed wagon
        u = flow.input + 0.5 * (flow.breakpoint - flow.input)
        sp = op.state(0.3 + H, inside.input)
        sm = op.state(0.3 - H, inside.input)
        fd = (_out(op, u, sp) - _out(op, u, sm)) / (2 * H)
        assert float(flow.partials(u)[1][0]) == pytest.approx(fd, rel=1e-7)
        assert float(flow.partials(u)[0]) == 0.0
        # past the breakpoint the input drags the wagon: w becomes slaved (reset, V_out)
        _, after = op.apply(np.array([flow.breakpoint + d * 0.1]), inside)
        assert op.branch_flow(after, d).slaved[0]
    wall = op.initial_state(0.5)  # on the right wall
    up = op.branch_flow(wall, 1)
    assert up.slaved[0] and up.breakpoint == np.inf and not up.reversal_pushes
    _check_output_and_slope(op, wall, up, 3.0)
    down = op.branch_flow(wall, -1)  # a reversal: nothing pushed, w frozen (V_in = I)
    assert not down.slaved[0] and not down.pushed[0]
    assert down.breakpoint == pytest.approx(0.5 - 2 * half)


# ------------------------------------------------------------------------------------------
# Prandtl–Ishlinskii
# ------------------------------------------------------------------------------------------
def test_pi_flow_against_apply():
    op = PrandtlIshlinskii([0.0, 0.6, 1.5, 2.4], [0.2, 0.3, 0.3, 0.2])
    # rise, fall, rise: a state with every kind of wagon
    _, state = op.apply(np.array([-3.0, 2.0, 0.4, 0.85]))
    for d in (1, -1):
        flow = op.branch_flow(state, d)
        assert flow.labels == ("w0", "w1", "w2", "w3")
        np.testing.assert_array_equal(flow.memory, state.positions)
        _check_output_and_slope(op, state, flow, 4.0)
        # ∂y/∂w_i for the frozen wagons against apply from perturbed states
        u = flow.input + d * 0.5 * min(1.0, abs(flow.breakpoint - flow.input))
        for i in np.flatnonzero(~flow.slaved):
            pos = np.array(state.positions)
            pos[i] += H
            sp = op.state(pos, state.input)
            pos[i] -= 2 * H
            sm = op.state(pos, state.input)
            fd = (_out(op, u, sp) - _out(op, u, sm)) / (2 * H)
            assert float(flow.partials(u)[1][i]) == pytest.approx(fd, rel=1e-7)
        # at the breakpoint exactly the declared wagons start being dragged
        if math.isfinite(flow.breakpoint):
            _, after = op.apply(np.array([flow.breakpoint + d * 1e-9]), state)
            new = op.branch_flow(after, d)
            became = {
                lab
                for lab, s0, s1 in zip(flow.labels, flow.slaved, new.slaved, strict=True)
                if s1 and not s0
            }
            assert became == set(flow.breakpoint_resets) and became


def test_pi_all_dragged_has_no_breakpoint():
    op = PrandtlIshlinskii([0.0, 1.0], [0.5, 0.5])
    flow = op.branch_flow(op.initial_state(0.0), 1)
    assert flow.breakpoint == np.inf and np.all(flow.slaved)
    assert float(flow.slope(0.3)) == pytest.approx(1.0)


# ------------------------------------------------------------------------------------------
# continuous Preisach
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("which", ["everett", "density", "gaussian-ridge"])
def test_preisach_flow_against_apply(which):
    from hysteresis import ContinuousPreisachModel

    if which == "everett":
        op = _gauss_everett_model()
    elif which == "density":
        op = _gauss_density_model()
    else:  # the separable bi-quintic Everett table with scalar fast paths
        op = ContinuousPreisachModel.gaussian(2.0, 1.0, 0.3)
    extrema = [2.0, -1.5, 1.0, -0.5, 0.3]
    state = op.state_from_extrema(extrema)
    for d in (1, -1):
        flow = op.branch_flow(state, d)
        reversing = d < 0  # the state's last move was a rise
        n = len(extrema) if reversing else len(extrema) - 1
        assert flow.labels == ("M1", "m1", "M2", "m2", "M3")[:n]
        assert bool(flow.pushed[-1]) == reversing and flow.reversal_pushes
        np.testing.assert_array_equal(flow.memory, extrema[:n])
        assert flow.breakpoint == (1.0 if d > 0 else -0.5)
        assert set(flow.breakpoint_removes) == ({"M2", "m2"} if d > 0 else {"m2", "M3"})
        if which != "density":
            _check_output_and_slope(op, state, flow, 3.0)
        else:
            # the table-interpolated Everett function is only C0 (bilinear, h = 14/256): the
            # output agrees exactly, the density-quadrature slope to O(h)
            u = flow.input + d * 0.25
            assert float(flow.output(u)) == pytest.approx(_out(op, u, state), abs=1e-12)
            h = 0.05
            fd = (_out(op, u + h, state) - _out(op, u - h, state)) / (2 * h)
            assert float(flow.slope(u)) == pytest.approx(fd, rel=0.05)
            continue
        # ∂y/∂m for every memory variable against apply from perturbed staircases
        u = flow.input + d * 0.3
        for i in range(n - (1 if reversing else 0)):
            ep = list(extrema)
            ep[i] += H
            em = list(extrema)
            em[i] -= H
            fd = (
                _out(op, u, op.state_from_extrema(ep)) - _out(op, u, op.state_from_extrema(em))
            ) / (2 * H)
            assert float(flow.partials(u)[1][i]) == pytest.approx(fd, rel=1e-6, abs=1e-9)
        # the pushed extremum (reversal at the current input): moving it moves the start point
        if reversing:
            ep = list(extrema)
            ep[-1] += H
            ep.append(extrema[-1])  # reverse at the perturbed maximum, back to the current input
            em = list(extrema)
            em[-1] -= H
            fd_total = (
                _out(op, u, op.state_from_extrema(ep)) - _out(op, u, op.state_from_extrema(em))
            ) / (2 * H)
            assert float(flow.partials(u)[1][-1]) == pytest.approx(fd_total, rel=1e-6)
        # at the breakpoint the declared extrema are wiped out
        _, after = op.apply(np.array([flow.breakpoint + d * 1e-9]), state)
        new = op.branch_flow(after, d)
        assert set(flow.labels) - set(new.labels) == set(flow.breakpoint_removes)


def test_preisach_flow_from_saturation_has_no_memory():
    op = _gauss_everett_model()
    flow = op.branch_flow(op.initial_state(-0.5), 1)
    assert flow.n_memory == 0 and flow.breakpoint == np.inf
    assert float(flow.output(0.7)) == pytest.approx(
        _out(op, 0.7, op.initial_state(-0.5)), abs=1e-12
    )


def test_branchflow_validates():
    with pytest.raises(ValueError, match="direction"):
        BranchFlow(0, 0.0, (), [], [], abs, abs, np.inf)
    with pytest.raises(ValueError, match="behind"):
        BranchFlow(1, 0.0, (), [], [], abs, abs, -1.0)
    with pytest.raises(ValueError, match="unique"):
        BranchFlow(1, 0.0, ("a", "a"), [0, 0], [0, 0], abs, abs, 1.0)
    with pytest.raises(ValueError, match="unknown"):
        BranchFlow(1, 0.0, ("a",), [0], [0], abs, abs, 1.0, breakpoint_resets=("b",))


def test_gaussian_ridge_model_everett_and_play_limit():
    from hysteresis import ContinuousPreisachModel

    model = ContinuousPreisachModel.gaussian(2.0, 1.0, 0.05)
    a = np.array([1.0, 2.0, 3.0, 0.5])
    b = np.array([-2.0, -1.0, 0.5, 0.2])
    da, db = model.everett_gradient(a, b)
    h = 1e-6
    np.testing.assert_allclose(
        da, (model.everett(a + h, b) - model.everett(a - h, b)) / (2 * h), rtol=1e-6
    )
    np.testing.assert_allclose(
        db, (model.everett(a, b + h) - model.everett(a, b - h)) / (2 * h), rtol=1e-6
    )
    assert float(model.everett(model.upper, model.lower)) == pytest.approx(1.0, abs=1e-12)
    # a narrow ridge δ(r − p/2): the major loop is the erf play's, E(a, b) = Φ(a − 1) − Φ(b + 1)
    assert float(model.everett(3.0, -0.5)) == pytest.approx(ndtr(2.0) - ndtr(0.5), abs=2e-3)
    # input-output behaviour tends to GeneralizedPlay.erf(2, 1) as σ_r -> 0
    play = GeneralizedPlay.erf(2.0, 1.0)
    u = np.concatenate([np.linspace(-8, 3, 50), np.linspace(3, -1, 30), np.linspace(-1, 2, 30)])
    y_play = play.apply(u, play.initial_state(-8.0))[0]
    errors = [
        np.max(np.abs(ContinuousPreisachModel.gaussian(2.0, 1.0, s).apply(u)[0] - y_play))
        for s in (0.2, 0.05, 0.0125)
    ]
    assert errors[0] > errors[1] > errors[2] and errors[2] < 2e-3
    with pytest.raises(ValueError, match="width_spread"):
        ContinuousPreisachModel.gaussian(2.0, 1.0, 0.0)
