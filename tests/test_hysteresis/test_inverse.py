"""InverseOperator: the numeric inverse of a continuous operator by branch inversion.

Truth: the forward operator itself (``operator.apply(inverse.apply(y))`` must give ``y`` back),
the closed-form inverse of a Prandtl–Ishlinskii operator, and closed-form initial branches
(erf, a uniform Preisach density). Tolerance: the inversion stops when Brent's bracket is
below ``4ε·|u|`` (module docstring), so ``|y(u) − y| <= 8ε·slope·|u|`` plus the forward
operator's rounding, ~1e-14 of the output scale here; the contract's 1e-10 is asserted.
"""

import math
import pickle
from dataclasses import dataclass

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.special import erfinv

from hysteresis import GeneralizedPlay, PlayOperator, PrandtlIshlinskii, PreisachModel, Relay
from hysteresis.base import ContinuousHysteron
from hysteresis.cascade import Cascade
from hysteresis.flow import BranchFlow
from hysteresis.inverse import InverseOperator, InverseState
from hysteresis.preisach.continuous import ContinuousPreisachModel
from hysteresis.static_map import StaticMap
from oscillators.system import ForcedOscillator

ACCURACY = 1e-10
LOWER, UPPER = -1.0, 1.5
SPAN = UPPER - LOWER
BAND = 0.2


def uniform_everett(a, b):
    """Uniform density on the triangle LOWER <= β <= α <= UPPER: E = ((a − b)/SPAN)²."""
    return ((np.asarray(a) - np.asarray(b)) / SPAN) ** 2


def uniform_gradient(a, b):
    """(∂E/∂α, ∂E/∂β) of :func:`uniform_everett`."""
    slope = 2.0 * (np.asarray(a) - np.asarray(b)) / SPAN**2
    return slope, -slope


def band_everett(a, b):
    """Uniform density on the band α − β >= BAND: no relay narrower than BAND, so every branch
    is flat for an input change of BAND after a reversal."""
    gap = np.maximum(np.asarray(a) - np.asarray(b) - BAND, 0.0)
    return (gap / (SPAN - BAND)) ** 2


def uniform_preisach():
    return PreisachModel.from_everett(uniform_everett, LOWER, UPPER, uniform_gradient)


def pi_operator():
    """Partial sums 1, 1.5, 1.2, 1.6: invertible with a negative weight."""
    return PrandtlIshlinskii([0.0, 0.5, 1.0, 2.0], [1.0, 0.5, -0.3, 0.4])


def wide_pi_operator():
    """Plays wider than the oscillator's swing: reversals come with the wide wagons frozen, so
    the frozen memory's perturbations enter the driven gradients (minor loops)."""
    return PrandtlIshlinskii([0.0, 1.0, 2.5, 6.0], [1.0, 0.5, -0.3, 0.4])


def random_walk(n, scale, seed):
    return np.cumsum(np.random.default_rng(seed).normal(size=n)) * scale


def bounded_walk(n, amplitude, seed):
    """A random walk of the phase of a sine: values in [-amplitude, amplitude], many
    reversals of every size."""
    return amplitude * np.sin(random_walk(n, 0.25, seed))


def forc_path(top, lows, nested, steps=25):
    """FORC-like targets (down from ``top`` to each of ``lows`` and back) followed by nested
    minor loops through the turning points ``nested``; linear segments of ``steps`` points."""
    turns = [top]
    for low in lows:
        turns += [low, top]
    turns += list(nested)
    pieces = [np.linspace(a, b, steps)[1:] for a, b in zip(turns[:-1], turns[1:], strict=True)]
    return np.concatenate([[turns[0]], *pieces])


def relative_error(op, inv, y):
    """max |op(inv(y)) − y| over the output scale max(1, max|y|)."""
    u, _ = inv.apply(y)
    back, _ = op.apply(u)
    return float(np.max(np.abs(back - y))) / max(1.0, float(np.max(np.abs(y))))


@pytest.fixture(scope="module")
def gaussian():
    # r_lo = max(0, p/2 − 8σ_r) = 0: relays of every width down to 0, branches strictly rise
    return ContinuousPreisachModel.gaussian(width=0.5, spread=1.0, width_spread=0.2)


# -- accuracy -----------------------------------------------------------------------------------
def test_pi_random_walk_and_forc_reproduce_the_targets():
    pi = pi_operator()
    inv = InverseOperator(pi)
    y = random_walk(600, 0.4, seed=1)
    assert relative_error(pi, inv, y) <= ACCURACY
    forc = forc_path(6.0, [-5.0, -2.0, 1.0, 4.0], [5.0, -4.0, 3.0, -2.0, 1.0, 0.0, 7.0])
    assert relative_error(pi, inv, forc) <= ACCURACY


def test_pi_numeric_inverse_equals_the_closed_form():
    pi = pi_operator()
    y = random_walk(500, 0.4, seed=2)
    u, state = InverseOperator(pi).apply(y)
    exact = pi.inverse()
    u_exact, state_exact = exact.apply(y)  # consistent initial states (PI module docstring)
    scale = max(1.0, float(np.max(np.abs(u))))
    # closed form: u = Σ a'_i z_i with |a'_i| <= 1, rounding ~1e-15 per term
    np.testing.assert_allclose(u, u_exact, rtol=0.0, atol=1e-12 * scale)
    np.testing.assert_allclose(
        pi.inverse_state(state.forward).positions, state_exact.positions, atol=1e-12 * scale
    )


@pytest.mark.parametrize("kind", ["uniform", "gaussian"])
def test_preisach_minor_loops_reproduce_the_targets(kind, gaussian):
    model = uniform_preisach() if kind == "uniform" else gaussian
    inv = InverseOperator(model)
    y = bounded_walk(300, 0.9, seed=3)
    assert relative_error(model, inv, y) <= ACCURACY
    nested = [0.8, -0.7, 0.6, -0.5, 0.4, -0.3, 0.2, -0.1, 0.95, -0.95]
    forc = forc_path(0.9, [-0.8, -0.3, 0.2, 0.7], nested, steps=12)
    assert relative_error(model, inv, forc) <= ACCURACY
    # the memory is the forward operator's: the nested extrema are remembered, then wiped out
    _, state = inv.apply(forc[: 1 + 11 * 16])  # up to the turn at -0.1
    assert state.forward.extrema.size >= 8


def test_continuing_from_a_returned_state_equals_one_long_call(gaussian):
    for op, y in (
        (pi_operator(), random_walk(200, 0.4, seed=4)),
        (gaussian, bounded_walk(200, 0.9, seed=5)),
    ):
        inv = InverseOperator(op)
        whole, end = inv.apply(y)
        first, mid = inv.apply(y[:77])
        rest, end2 = inv.apply(y[77:], mid)
        np.testing.assert_array_equal(np.concatenate([first, rest]), whole)
        assert end2.input == end.input and end2.forward.input == end.forward.input
        assert inv.output(end2) == whole[-1]


# -- the contract's initial state ----------------------------------------------------------------
def test_initial_state_is_the_forward_initial_state_on_the_ascending_branch():
    # uniform Preisach: y0 = -1 + 2((u0 - LOWER)/SPAN)² on the ascending branch
    inv = InverseOperator(uniform_preisach())
    for y0 in (-0.9, -0.2, 0.0, 0.5, 0.99):
        state = inv.initial_state(y0)
        expected = LOWER + SPAN * math.sqrt((y0 + 1.0) / 2.0)
        assert state.forward.input == pytest.approx(expected, abs=8 * np.finfo(float).eps)
        assert state.input == y0
        assert state.forward.extrema.size == 1  # rising from negative saturation
    # erf play of width 0: y0 = erf(u0 / (sqrt(2) R))
    inv = InverseOperator(GeneralizedPlay.erf(0.0, 0.7))
    for y0 in (-0.999, -0.3, 0.6):
        u0 = inv.initial_state(y0).forward.input
        assert u0 == pytest.approx(math.sqrt(2.0) * 0.7 * erfinv(y0), rel=1e-12)
    # the default state of apply is initial_state(targets[0])
    pi = pi_operator()
    inv = InverseOperator(pi)
    u, _ = inv.apply([0.3, 1.0])
    assert u[0] == inv.initial_state(0.3).forward.input
    assert pi.output(pi.initial_state(u[0])) == pytest.approx(0.3, abs=1e-15)


# -- ranges -------------------------------------------------------------------------------------
def test_output_range_is_the_reachable_input_range(gaussian):
    assert InverseOperator(pi_operator()).output_range == (-math.inf, math.inf)
    lo, hi = InverseOperator(uniform_preisach()).output_range
    assert lo == pytest.approx(LOWER, abs=1e-14) and hi == pytest.approx(UPPER, abs=1e-14)
    # erf: the major loop reaches ±1 in float64 at the ends, and not a few ulps before
    p, r = 0.0, 0.5  # width 0: a wider erf play has flat branches
    lo, hi = InverseOperator(GeneralizedPlay.erf(p, r)).output_range
    scale = math.sqrt(2.0) * r
    assert math.erf((hi - p / 2) / scale) == 1.0 > math.erf((hi * (1 - 1e-15) - p / 2) / scale)
    assert math.erf((lo + p / 2) / scale) == -1.0 < math.erf((lo * (1 - 1e-15) + p / 2) / scale)


@pytest.mark.parametrize("target", [1.0, -1.0, 1.5, -7.0])
def test_targets_outside_the_open_output_range_raise(target):
    inv = InverseOperator(uniform_preisach())
    with pytest.raises(ValueError, match=r"target .* outside .* open output range \(-1.0, 1.0\)"):
        inv.apply([0.0, target])
    with pytest.raises(ValueError, match="y0"):
        inv.initial_state(target)


def test_bad_targets_and_states_raise():
    inv = InverseOperator(pi_operator())
    with pytest.raises(ValueError, match="inputs"):
        inv.apply([0.0, math.nan])
    with pytest.raises(TypeError, match="state must be a InverseState"):
        inv.apply([0.0], pi_operator().initial_state(0.0))
    other = InverseOperator(PrandtlIshlinskii([0.0, 1.0], [2.0, 1.0])).initial_state(0.5)
    with pytest.raises(ValueError, match="belongs to another operator"):
        inv.apply([0.0], other)
    with pytest.raises(TypeError, match="operator must be"):
        InverseOperator(3.0)


# -- refusals -----------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "op",
    [Relay(0.5, -0.5), PreisachModel.from_relays([0.5, 1.0], [-0.5, 0.0])],
    ids=["relay", "discrete-preisach"],
)
def test_piecewise_constant_operators_have_no_inverse(op):
    with pytest.raises(ValueError, match="has no inverse: its output jumps"):
        InverseOperator(op)


@pytest.mark.parametrize(
    ("op", "why"),
    [
        (PlayOperator(1.0), "flat"),
        (GeneralizedPlay.erf(1.0, 1.0), "flat"),
        (PrandtlIshlinskii([0.5, 1.0], [1.0, 1.0]), "flat"),  # no width-0 play
        (PrandtlIshlinskii([0.0, 1.0], [1.0, -1.0]), "flat"),  # partial sum 0
        (PrandtlIshlinskii([0.0, 1.0], [1.0, -2.0]), "decreasing"),
    ],
    ids=["play", "erf-play", "pi-no-linear-term", "pi-zero-sum", "pi-negative-sum"],
)
def test_flat_or_falling_branches_have_no_inverse(op, why):
    with pytest.raises(ValueError, match=f"has no inverse: some branch is {why}"):
        InverseOperator(op)


def test_gaussian_preisach_without_narrow_relays_has_no_inverse():
    model = ContinuousPreisachModel.gaussian(width=2.0, spread=1.0, width_spread=0.1)
    assert model.min_slope == 0.0  # r_lo = 1 - 0.8 > 0
    with pytest.raises(ValueError, match="flat over an interval"):
        InverseOperator(model)


def test_a_flat_branch_found_while_inverting_raises():
    model = PreisachModel.from_everett(band_everett, LOWER, UPPER)
    assert model.min_slope is None  # the model does not know its density near the diagonal
    inv = InverseOperator(model)
    inv.apply(np.linspace(-0.5, 0.5, 20))  # the ascending branch rises
    with pytest.raises(ValueError, match=r"branch in direction -1 is flat from input"):
        inv.apply([-0.5, 0.5, 0.4])  # after the reversal it stays flat for an input step BAND


@dataclass(frozen=True)
class _Input:
    input: float


class _StepUp(ContinuousHysteron):
    """``y = u + [u >= 0]``: slope 1 everywhere, but a jump at 0 (as a sum with a relay)."""

    def initial_state(self, u0):
        return _Input(float(u0))

    def apply(self, inputs, state=None):
        u = np.asarray(inputs, dtype=float)
        return u + (u >= 0.0), _Input(float(u[-1]))

    @property
    def output_range(self):
        return (-math.inf, math.inf)

    def branch_flow(self, state, direction):
        u0, above = state.input, state.input >= 0.0
        bp = (
            (0.0 if direction > 0 else np.nextafter(0.0, -1.0))
            if above != (direction > 0)
            else direction * math.inf
        )
        return BranchFlow(
            direction=direction,
            input=u0,
            labels=(),
            memory=np.zeros(0),
            slaved=np.zeros(0, dtype=bool),
            output=lambda u: np.asarray(u, dtype=float) + float(above),
            partials=lambda u: (1.0, np.zeros(0)),
            breakpoint=bp,
            breakpoint_jump=0.0 if math.isinf(bp) else float(direction),
        )


def negative_one(x):
    return -np.ones_like(np.asarray(x, dtype=float))


def test_a_falling_branch_found_while_inverting_raises():
    falling = Cascade(pi_operator(), StaticMap(np.negative, negative_one))
    inv = InverseOperator(falling)  # min_slope unknown
    with pytest.raises(ValueError, match="has no inverse: a branch decreases"):
        inv.apply([0.0, 1.0])


def test_a_jump_found_while_inverting_raises():
    inv = InverseOperator(_StepUp())
    np.testing.assert_allclose(inv.apply([-3.0, -1.0, -0.5])[0], [-3.0, -1.0, -0.5])
    with pytest.raises(ValueError, match=r"has no inverse: its output jumps by 1.0 at input 0.0"):
        inv.apply([-1.0, 0.5])


def test_identity_play_is_its_own_inverse():
    y = np.array([0.0, 2.5, -1.0, 1e-3])
    u, _ = InverseOperator(PlayOperator(0.0)).apply(y)
    # Brent stops on a bracket of width 4ε·max(|a|, |b|); the doubling steps put its ends
    # within 3·max|u|
    np.testing.assert_allclose(u, y, rtol=0.0, atol=12 * np.finfo(float).eps * 2.5)


# -- min_slope of the library's operators ----------------------------------------------------------
def test_min_slope_of_library_operators(gaussian):
    assert PlayOperator(1.0).min_slope == 0.0 and PlayOperator(0.0).min_slope == 1.0
    assert GeneralizedPlay.erf(1.0, 1.0).min_slope == 0.0
    assert GeneralizedPlay.erf(0.0, 1.0).min_slope is None
    assert Relay(1.0, -1.0).min_slope == 0.0
    assert gaussian.min_slope is None
    assert pi_operator().min_slope == 1.0


def test_pi_min_slope_is_the_least_branch_slope_and_decides_the_closed_form():
    rng = np.random.default_rng(7)
    for _ in range(40):
        n = int(rng.integers(1, 5))
        widths = np.concatenate([[0.0], np.cumsum(rng.uniform(0.1, 1.0, n))])
        if rng.random() < 0.25:
            widths = widths + 0.3  # no linear term
        pi = PrandtlIshlinskii(widths, rng.uniform(-0.6, 1.0, n + 1))
        # brute force: slopes along a history of growing reversals, from every branch
        u = np.concatenate([[0.0], 4.0 * np.sin(np.linspace(0.0, 12 * np.pi, 3000))])
        u *= np.linspace(0.1, 1.0, u.size)
        y, _ = pi.apply(u)
        du = np.diff(u)
        slopes = np.diff(y)[np.abs(du) > 1e-9] / du[np.abs(du) > 1e-9]
        # the least slope is taken on some step (no smaller one anywhere): min_slope is sharp
        assert np.min(slopes) == pytest.approx(pi.min_slope, abs=1e-9)
        try:
            pi.inverse()
            closed_form = True
        except ValueError:
            closed_form = False
        assert closed_form == (pi.min_slope > 0.0)


# -- pickling -----------------------------------------------------------------------------------
def test_pickled_inverse_and_state_continue_identically(gaussian):
    for op, y in (
        (pi_operator(), random_walk(60, 0.4, seed=8)),
        (uniform_preisach(), bounded_walk(60, 0.9, seed=9)),
        (gaussian, bounded_walk(60, 0.9, seed=10)),
    ):
        inv = InverseOperator(op)
        first, state = inv.apply(y[:30])
        copy = pickle.loads(pickle.dumps(inv))
        state_copy = pickle.loads(pickle.dumps(state))
        assert isinstance(state_copy, InverseState)
        np.testing.assert_array_equal(
            copy.apply(y[30:], state_copy)[0], inv.apply(y[30:], state)[0]
        )
        assert copy.output_range == inv.output_range


# -- branch flow: the inverse as an operator of the generic continuous engine -----------------
def test_pi_branch_flow_inverts_the_forward_branch_with_closed_form_partials():
    pi = pi_operator()
    inv = InverseOperator(pi)
    _, state = inv.apply([0.0, 3.0, 1.0])  # down from 3: the narrow plays dragged, wide ones not
    flow = inv.branch_flow(state, -1)
    forward = pi.branch_flow(state.forward, -1)
    frozen = ~forward.slaved
    assert flow.labels == tuple(np.array(forward.labels)[frozen])
    assert flow.driven_labels == tuple(np.array(forward.labels)[forward.slaved])
    assert flow.breakpoint == pytest.approx(forward.output(forward.breakpoint), abs=1e-15)
    # on the branch u = u0 + (y − y0)/A with A the dragged weights: ∂u/∂y = 1/A,
    # ∂u/∂w_j = −a_j/A for the frozen wagons (y = Σ a_i w_i)
    dragged = float(np.sum(pi.weights[forward.slaved]))
    for y in np.linspace(flow.breakpoint, 1.0, 5):
        assert flow.output(y) == pytest.approx(inv.apply([y], state)[0][0], abs=1e-14)
        assert flow.output(y) == pytest.approx(state.forward.input + (y - 1.0) / dragged, abs=1e-14)
        d_y, d_m = flow.partials(y)
        assert d_y == pytest.approx(1.0 / dragged, rel=1e-14)
        np.testing.assert_allclose(d_m, -pi.weights[frozen] / dragged, rtol=1e-14)
        values, d_du, d_dm = flow.driven(y)
        shift = flow.output(y) - state.forward.input
        np.testing.assert_allclose(
            values, np.asarray(forward.memory)[forward.slaved] + shift, rtol=0, atol=1e-14
        )
        np.testing.assert_allclose(d_du, 1.0 / dragged, rtol=1e-14)
        np.testing.assert_allclose(d_dm, np.tile(d_m, (d_du.size, 1)), rtol=1e-14)


def _partner_root(model, extrema, target):
    """u with the rising branch of the state after the history ``extrema`` at ``target``."""
    flow = model.branch_flow(model.state_from_extrema(extrema), 1)
    return brentq(lambda u: float(flow.output(u)) - target, flow.input, UPPER, xtol=1e-15)


def test_preisach_branch_flow_partials_match_finite_differences():
    model = uniform_preisach()
    inv = InverseOperator(model)
    extrema = [1.2, -0.6, 0.9, -0.2, 0.1]  # rising from the minimum -0.2, now at 0.1
    forward = model.state_from_extrema(extrema)
    state = InverseState(forward, model.output(forward))
    flow = inv.branch_flow(state, 1)
    assert flow.labels == ("M1", "m1", "M2", "m2") and flow.driven_labels == ()
    y = 0.5 * (state.input + flow.breakpoint)  # halfway to the wiped-out maximum 0.9
    h = 1e-5  # central differences: error ~h²·u''' + ε/h ~ 1e-10
    fd_y = (flow.output(y + h) - flow.output(y - h)) / (2 * h)
    d_y, d_m = flow.partials(y)
    assert d_y == pytest.approx(fd_y, rel=1e-6)
    for j in range(4):
        up, down = list(extrema), list(extrema)
        up[j] += h
        down[j] -= h
        fd = (_partner_root(model, up, y) - _partner_root(model, down, y)) / (2 * h)
        assert d_m[j] == pytest.approx(fd, rel=1e-6, abs=1e-9)


def test_preisach_reversal_pushes_the_input_with_the_arriving_gradient():
    model = uniform_preisach()
    inv = InverseOperator(model)
    big, low, u_star = 1.2, -0.6, 0.4  # history: up to 1.2, down to -0.6, up to 0.4
    forward = model.state_from_extrema([big, low, u_star])
    state = InverseState(forward, model.output(forward))
    flow = inv.branch_flow(state, -1)  # reversing: the forward pushes u* as "M2"
    assert flow.labels == ("M1", "m1", "M2") and flow.pushed.tolist() == [False, False, True]
    # the arriving branch y = c + 2E(u, m1), E = ((a − b)/SPAN)², with c from M1 and m1:
    # S = 4(u* − m1)/SPAN², ∂y/∂M1 = 4(m1 − LOWER)/SPAN², ∂y/∂m1 = 4(M1 − u*)/SPAN²,
    # so δu* = (δy − ∂y/∂M1 δM1 − ∂y/∂m1 δm1)/S
    d_y, d_m = flow.pushed_gradient(state.input)
    np.testing.assert_allclose(d_y, [SPAN**2 / (4 * (u_star - low))], rtol=1e-12)
    expected = [-(low - LOWER) / (u_star - low), -(big - u_star) / (u_star - low), 0.0]
    np.testing.assert_allclose(d_m, [expected], rtol=1e-12, atol=1e-15)
    # the new branch leaves u* with slope 0: the inverse's slope is infinite there
    assert flow.partials(state.input)[0] == math.inf
    # behind sinh, the forward pushes x* = sinh(u*) with its own pushed_gradient (cosh u*):
    # δx* = cosh(u*)·δu* and δu* = δy/(G'(x*)·cosh(u*)), so ∂x*/∂y = SPAN²/(4(x* − m1))
    cascade = Cascade(StaticMap(np.sinh, np.cosh), model)
    _, state = InverseOperator(cascade).apply([0.5, -0.5, 0.3])
    flow = InverseOperator(cascade).branch_flow(state, -1)
    x_star, x_low = state.forward.outer.extrema[-1], state.forward.outer.extrema[-2]
    d_y, _ = flow.pushed_gradient(state.input)
    np.testing.assert_allclose(d_y, [SPAN**2 / (4 * (x_star - x_low))], rtol=1e-10)


def test_oscillator_with_the_numeric_inverse_follows_the_closed_form_inverse():
    pi = wide_pi_operator()
    runs = []
    for op in (InverseOperator(pi), pi.inverse()):
        system = ForcedOscillator(op, 0.5, 0.1, 1.0)
        engine = system.engine(system.initial_state(0.3, 0.2), method="generic")
        engine.start_tangent(False)
        out = np.empty((1, 3))
        engine.advance(np.array([4.0 * np.pi]), out, record=True)
        runs.append((out[0], engine.deviations()[:2, :2], engine.n_events))
    (a, jac_a, n_a), (b, jac_b, n_b) = runs
    # reversals (dragged wagons freeze) and wall hits (frozen ones become driven)
    assert n_a == n_b >= 10
    # both integrate to rtol = atol = 1e-11 over ~6 periods of growth: agreement to ~1e-9
    np.testing.assert_allclose(a, b, rtol=0.0, atol=1e-8)
    # the (q, v) block of the stroboscopic map's Jacobian: memory held fixed means the same in
    # both (the closed form's plays z_i are functions of the forward wagons w_j)
    np.testing.assert_allclose(jac_a, jac_b, rtol=0.0, atol=1e-8)


def tanh_derivative(x):
    return 1.0 / np.cosh(x) ** 2


def arcsinh_derivative(x):
    return 1.0 / np.sqrt(1.0 + np.asarray(x) ** 2)


def test_generalized_prandtl_ishlinskii_cascades_are_inverted():
    pi = pi_operator()
    output_map = Cascade(pi, StaticMap(np.tanh, tanh_derivative, output_range=(-1.0, 1.0)))
    input_map = Cascade(StaticMap(np.sinh, np.cosh), pi)
    assert relative_error(output_map, InverseOperator(output_map), bounded_walk(300, 0.9, 11)) <= (
        ACCURACY
    )
    assert relative_error(input_map, InverseOperator(input_map), random_walk(300, 0.4, 12)) <= (
        ACCURACY
    )


def test_oscillator_with_an_inverted_cascade_follows_the_closed_form_inverse():
    # y = PI[sinh u] has the inverse u = asinh(PI⁻¹[y]): the forward's dragged wagons follow
    # sinh(u), so in the numeric inverse they are driven through two chain rules
    pi = wide_pi_operator()
    forward = Cascade(StaticMap(np.sinh, np.cosh), pi)
    exact = Cascade(pi.inverse(), StaticMap(np.arcsinh, arcsinh_derivative))
    runs = []
    for op in (InverseOperator(forward), exact):
        system = ForcedOscillator(op, 0.8, 0.1, 1.0)
        engine = system.engine(system.initial_state(-0.4, 0.3), method="generic")
        engine.start_tangent(False)
        out = np.empty((1, 3))
        engine.advance(np.array([4.0 * np.pi]), out)
        runs.append((out[0], engine.deviations()[:2, :2], engine.n_events))
    (a, jac_a, n_a), (b, jac_b, n_b) = runs
    assert n_a == n_b >= 10
    # (a driven gradient without its memory columns is off by ~1e-3 here)
    np.testing.assert_allclose(a, b, rtol=0.0, atol=1e-8)
    np.testing.assert_allclose(jac_a, jac_b, rtol=0.0, atol=1e-8)
