"""C¹ bicubic Hermite Everett tables (kind 1) against a density with a closed-form Everett
function, with the error bounds derived in :mod:`hysteresis.preisach.everett_table`."""

import math
import pickle

import numpy as np
import pytest

from hysteresis.preisach import PreisachModel
from hysteresis.preisach._everett_kernels import everett_eval

LO, UP = -2.0, 3.0
# density μ(α, β) = c e^α on the triangle: E(a, b) = c((a − b)e^a − e^a + e^b), mass 1
C = 1.0 / ((UP - LO) * math.exp(UP) - (math.exp(UP) - math.exp(LO)))
K_VALUE, K_GRADIENT = 0.02296, 0.2575  # the |a − b|³ constants of the module docstring


def density(a, b):
    return C * np.exp(a) + 0.0 * b


def everett(a, b):
    return C * ((a - b) * np.exp(a) - (np.exp(a) - np.exp(b)))


def gradient(a, b):
    return C * (a - b) * np.exp(a), -C * (np.exp(a) - np.exp(b))


def _bounds(h):
    """(off-diagonal value, gradient; diagonal value, gradient) bounds for this density:
    ∂⁴E/∂a⁴ = c e^a (a − b + 3), ∂⁴E/∂b⁴ = c e^b, ∂⁵E/∂a∂b⁴ = 0; μ₁ − μ₂ = c e^α."""
    e_up = C * math.exp(UP)
    d4a = e_up * (UP - LO + 3.0)
    d4b = e_up
    b4 = h**4 / 384 * (d4a + d4b)
    grad = h**3 * (math.sqrt(3) / 216 * d4a + 3 / 384 * d4b)
    kappa = (e_up + h * e_up) / 12.0
    return b4, grad, K_VALUE * kappa * h**3 + 2 * b4, K_GRADIENT * kappa * h**2


def _sample(n, rng, count=40000):
    a = rng.uniform(LO, UP, count)
    b = rng.uniform(LO, UP, count)
    a, b = np.maximum(a, b), np.minimum(a, b)
    h = (UP - LO) / n
    diag = np.floor((a - LO) / h) == np.floor((b - LO) / h)
    return a, b, diag


def _check_against_closed_form(e, ga, gb, a, b, diag, h, gradient_slack=0.0):
    off_v, off_g, diag_v, diag_g = _bounds(h)
    err = np.abs(e - everett(a, b))
    ea, eb = gradient(a, b)
    gerr = np.maximum(np.abs(ga - ea), np.abs(gb - eb))
    assert err[~diag].max() <= off_v
    assert gerr[~diag].max() <= off_g + gradient_slack
    assert err[diag].max() <= diag_v
    # the O(h³) remainder of the diagonal gradient bound: at most the off-diagonal h³ term
    assert gerr[diag].max() <= diag_g + off_g + gradient_slack


@pytest.mark.parametrize("n", [32, 128])
def test_from_density_table_within_bound(n):
    model = PreisachModel.from_density(density, LO, UP, resolution=n)
    a, b, diag = _sample(n, np.random.default_rng(n))
    e = model.everett(a, b)
    ga, gb = model.everett_gradient(a, b)
    _check_against_closed_form(e, ga, gb, a, b, diag, (UP - LO) / n)


def test_from_density_error_orders():
    """Fourth order off the diagonal, third order in the diagonal cells (value)."""
    errors = []
    for n in (32, 64):
        model = PreisachModel.from_density(density, LO, UP, resolution=n)
        a, b, diag = _sample(n, np.random.default_rng(5))
        err = np.abs(model.everett(a, b) - everett(a, b))
        errors.append((err[~diag].max(), err[diag].max()))
    assert errors[0][0] / errors[1][0] > 2**3.5
    assert errors[0][1] / errors[1][1] > 2**2.5


def test_table_is_one_c1_function():
    model = PreisachModel.from_density(density, LO, UP, resolution=16)
    h = (UP - LO) / 16
    rng = np.random.default_rng(2)
    # the gradient is the derivative of E: central differences with step d; rounding
    # eps·max|E|/d = 2.2e-10 (|E| <= 1), truncation d²/6·M3 with M3 <= ~10·max|E|/h³ = 3e2
    # for the cubic pieces (h = 0.31): 5e-11; a bound of 1e-9
    a = rng.uniform(LO + 0.1, UP - 0.1, 2000)
    b = a - rng.uniform(0.0, 2.0, 2000)
    b = np.maximum(b, LO + 0.1)
    d = 1e-6
    ga, gb = model.everett_gradient(a, b)
    fa = (model.everett(a + d, b) - model.everett(a - d, b)) / (2 * d)
    fb = (model.everett(a, b + d) - model.everett(a, b - d)) / (2 * d)
    keep = a - b > 2 * d
    np.testing.assert_allclose(fa[keep], ga[keep], rtol=0, atol=1e-9)
    np.testing.assert_allclose(fb[keep], gb[keep], rtol=0, atol=1e-9)
    # C¹ across cell edges: value and gradient continuous (a jump of rounding only: the
    # pieces agree exactly on the edge; 2e-13 apart they differ by <= 2e-13·max|∇E| + eps)
    x = LO + h * np.arange(1, 16)
    for other in (LO + 0.37 * h, LO + 3.5 * h):
        left, right = x - 1e-13, x + 1e-13
        keep = left > other
        for f in (model.everett, lambda u, v: model.everett_gradient(u, v)[0]):
            np.testing.assert_allclose(f(left[keep], other), f(right[keep], other), atol=1e-11)
    # E vanishes on the diagonal (no jump at a reversal): E(x + s, x) -> 0 with s
    x = np.linspace(LO, UP - 1e-3, 777)
    assert np.max(np.abs(model.everett(x + 1e-12, x))) < 1e-15
    assert np.all(model.everett(x, x) == 0.0)


def test_from_density_mass_and_saturation():
    model = PreisachModel.from_density(density, LO, UP, resolution=24)
    assert model.everett(UP, LO) == 1.0
    out, _ = model.apply([LO - 1.0, UP + 1.0, LO - 1.0])
    assert out[1] == 1.0 and out[2] == -1.0


def test_compiled_everett_of_density_model_is_its_own_function():
    model = PreisachModel.from_density(density, LO, UP, resolution=20)
    c = model.compiled_everett()
    assert c.kind == 1 and c.table.shape == (21, 21, 4)
    rng = np.random.default_rng(3)
    a = rng.uniform(LO - 1, UP + 1, 300)
    b = rng.uniform(LO - 1, UP + 1, 300)
    e = model.everett(a, b)
    ga, gb = model.everett_gradient(a, b)
    got = np.array(
        [everett_eval(c.kind, c.params, c.table, x, y) for x, y in zip(a, b, strict=True)]
    )
    np.testing.assert_array_equal(got[:, 0], e)
    np.testing.assert_array_equal(got[:, 1], ga)
    np.testing.assert_array_equal(got[:, 2], gb)
    back = pickle.loads(pickle.dumps(model))
    np.testing.assert_array_equal(back.everett(a, b), e)


@pytest.mark.parametrize("with_gradient", [True, False])
def test_from_everett_table_within_bound(with_gradient):
    model = PreisachModel.from_everett(everett, LO, UP, gradient if with_gradient else None)
    n = 64
    c = model.compiled_everett(resolution=n)
    assert c is model.compiled_everett(resolution=n)  # built once
    a, b, diag = _sample(n, np.random.default_rng(7), 5000)
    got = np.array(
        [everett_eval(c.kind, c.params, c.table, x, y) for x, y in zip(a, b, strict=True)]
    )
    # nodal data by differences (everett_function_table): gradient error ~ε^{2/3}·|E'''| and
    # E_ab error ~ε^{1/2} (entering multiplied by h²/16), a 1e-9 allowance on the gradient
    _check_against_closed_form(
        got[:, 0], got[:, 1], got[:, 2], a, b, diag, (UP - LO) / n, gradient_slack=1e-9
    )
    # the model itself still evaluates the user's function
    np.testing.assert_array_equal(model.everett(a, b), everett(a, b))
    # the table is not pickled (rebuilt on demand)
    assert "_compiled_tables" not in pickle.loads(pickle.dumps(model)).__dict__


def test_compiled_everett_resolution_validation():
    model = PreisachModel.from_density(density, LO, UP, resolution=8)
    with pytest.raises(ValueError, match="resolution"):
        model.compiled_everett(resolution=16)
    user = PreisachModel.from_everett(everett, LO, UP)
    with pytest.raises(ValueError, match="resolution"):
        user.compiled_everett(resolution=1)
