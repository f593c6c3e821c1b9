"""InverseOperator: the numeric inverse of a continuous operator by branch inversion.

Truth: the forward operator itself (``operator.apply(inverse.apply(y))`` must give ``y`` back),
the closed-form inverse of a Prandtl–Ishlinskii operator, and closed-form initial branches
(erf, a uniform Preisach density). Tolerance: the inversion stops when Brent's bracket is
below ``4ε·|u|`` (module docstring), so ``|y(u) − y| <= 8ε·slope·|u|`` plus the forward
operator's rounding, ~1e-14 of the output scale here; the contract's 1e-10 is asserted.
"""

import math
import pickle

import numpy as np
import pytest
from scipy.special import erfinv

from hysteresis import GeneralizedPlay, PlayOperator, PrandtlIshlinskii, PreisachModel, Relay
from hysteresis.inverse import InverseOperator, InverseState
from hysteresis.preisach.continuous import ContinuousPreisachModel

ACCURACY = 1e-10
LOWER, UPPER = -1.0, 1.5
SPAN = UPPER - LOWER
BAND = 0.2


def uniform_everett(a, b):
    """Uniform density on the triangle LOWER <= β <= α <= UPPER: E = ((a − b)/SPAN)²."""
    return ((np.asarray(a) - np.asarray(b)) / SPAN) ** 2


def band_everett(a, b):
    """Uniform density on the band α − β >= BAND: no relay narrower than BAND, so every branch
    is flat for an input change of BAND after a reversal."""
    gap = np.maximum(np.asarray(a) - np.asarray(b) - BAND, 0.0)
    return (gap / (SPAN - BAND)) ** 2


def uniform_preisach():
    return PreisachModel.from_everett(uniform_everett, LOWER, UPPER)


def pi_operator():
    """Partial sums 1, 1.5, 1.2, 1.6: invertible with a negative weight."""
    return PrandtlIshlinskii([0.0, 0.5, 1.0, 2.0], [1.0, 0.5, -0.3, 0.4])


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
        (PrandtlIshlinskii([0.0, 1.0], [1.0, -2.0]), "falling"),
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
        assert np.min(slopes) >= pi.min_slope - 1e-9
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
