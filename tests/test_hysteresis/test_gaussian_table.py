"""The Gaussian width-disorder Everett function as a separable bi-quintic table (kind 2):
its stated error bound against an independent adaptive quadrature written here and against
the 48-node Gauss–Legendre reference, the gradient as the derivative of the same function,
and its constants, memory and cache."""

import math
import pickle

import numpy as np
import pytest
from scipy import integrate
from scipy.special import ndtr

from hysteresis.preisach import ContinuousPreisachModel
from hysteresis.preisach._everett_kernels import everett_eval
from hysteresis.preisach.gaussian import (
    EVERETT_TOLERANCE,
    PHI_DERIVATIVE_MAX,
    derivative_bound,
    gaussian_everett,
    gaussian_support,
    gaussian_table,
)

#: (p, R, σ_r): the study's extremes and a wide law cut at r = 0
PARAMETERS = [(2.0, 1.0, 0.2), (2.0, 1.0, 0.0125), (1.0, 0.7, 0.5)]


def _exact(parameters, a, b):
    """E, ∂E/∂a, ∂E/∂b by scipy's adaptive quadrature of the defining integral over r
    (independent of the table and of the Gauss–Legendre rule), normalised by E(L, −L)."""
    p, big_r, sr = parameters
    *_, r_lo, r_hi, bound = gaussian_support(*parameters)
    mu = p / 2

    def w(r):
        return math.exp(-0.5 * ((r - mu) / sr) ** 2) / (sr * math.sqrt(2 * math.pi))

    def phi(z):
        return math.exp(-0.5 * z * z) / (big_r * math.sqrt(2 * math.pi))

    integrands = (
        lambda r, a, b: w(r) * (ndtr((a - r) / big_r) - ndtr((b + r) / big_r)),
        lambda r, a, b: w(r) * phi((a - r) / big_r),
        lambda r, a, b: -w(r) * phi((b + r) / big_r),
    )

    def integral(f, a, b):
        t = min(max(0.5 * (a - b), r_lo), r_hi)
        if t <= r_lo:
            return 0.0
        points = [mu] if r_lo < mu < t else None
        return integrate.quad(
            f, r_lo, t, args=(a, b), epsabs=1e-15, epsrel=1e-13, limit=200, points=points
        )[0]

    total = integral(integrands[0], bound, -bound)
    return np.array([integral(f, a, b) / total for f in integrands])


def _points(parameters, rng, count):
    """(a, b) in the support: uniform in the band r_lo < t < r_hi, near the diagonal band's
    edge r_lo, around the clipping edge t = r_hi, far beyond it, and at the support's edges."""
    *_, r_lo, r_hi, bound = gaussian_support(*parameters)
    span = r_hi - r_lo
    t = np.concatenate(
        [
            rng.uniform(r_lo, r_hi, count),
            r_lo + span * 10.0 ** rng.uniform(-6, -1, count // 4),
            r_hi + span * rng.uniform(-1e-3, 1e-3, count // 4),
            rng.uniform(r_hi, bound, count // 4),
        ]
    )
    s = rng.uniform(-bound + t, bound - t)
    a, b = s + t, s - t
    a[:5] = bound  # on the support's edges
    b[5:10] = -bound
    return a, b


@pytest.mark.parametrize("parameters", PARAMETERS)
def test_table_within_its_bound_of_an_independent_quadrature(parameters):
    table = gaussian_table(*parameters)
    c = table.compiled
    assert table.value_bound <= EVERETT_TOLERANCE
    a, b = _points(parameters, np.random.default_rng(3), 80)
    exact = np.array([_exact(parameters, x, y) for x, y in zip(a, b, strict=True)])
    got = np.array(
        [everett_eval(c.kind, c.params, c.table, x, y) for x, y in zip(a, b, strict=True)]
    )
    # the stated interpolation bound, plus the quadratures' own error (quad's requested
    # 1e-15 absolute / 1e-13 relative on values <= 1, and the nodal cell quadratures at
    # rounding, ~1e-15): 1e-13 covers both
    assert np.max(np.abs(got[:, 0] - exact[:, 0])) <= table.value_bound + 1e-13
    assert np.max(np.abs(got[:, 1:] - exact[:, 1:])) <= table.gradient_bound + 1e-13
    # the reference 48-node Gauss–Legendre rule agrees with quad to rounding here, so with the
    # table to the same bound
    law = gaussian_everett(*parameters, nodes=48)
    assert np.max(np.abs(law.everett(a, b) - exact[:, 0])) <= 1e-13
    assert np.max(np.abs(law.everett(a, b) - got[:, 0])) <= table.value_bound + 1e-13
    for k, g in enumerate(law.gradient(a, b)):
        assert np.max(np.abs(g - got[:, 1 + k])) <= table.gradient_bound + 1e-13


@pytest.mark.parametrize("parameters", PARAMETERS)
def test_gradient_is_the_derivative_of_the_same_function(parameters):
    c = gaussian_table(*parameters).compiled
    a, b = _points(parameters, np.random.default_rng(4), 60)
    keep = (a < c.upper - 1e-3) & (b > c.lower + 1e-3)
    a, b = a[keep], b[keep]
    h = 1e-5

    def e(x, y):
        return everett_eval(c.kind, c.params, c.table, x, y)[0]

    # central differences: truncation h²/6·‖∂³E‖ with ‖∂³E‖ <= 2 Σ_k C(3, k) 2^-k N_{3-k,k}
    # (two values of F, t = (a − b)/2; /total <= 1/0.8 here), rounding 2·1e-16/h
    _, big_r, sr = parameters
    third = 2.5 * sum(
        math.comb(3, k) * 0.5**k * derivative_bound(3 - k, k, sr, big_r) for k in range(4)
    )
    # plus the jump of the gradient across the clipping line t = r_hi (of the order of the
    # interpolation error of F_t, <= the gradient bound)
    tol = h * h / 6.0 * third + 2e-16 / h + gaussian_table(*parameters).gradient_bound
    for x, y in zip(a, b, strict=True):
        _, da, db = everett_eval(c.kind, c.params, c.table, x, y)
        assert abs((e(x + h, y) - e(x - h, y)) / (2 * h) - da) <= tol
        assert abs((e(x, y + h) - e(x, y - h)) / (2 * h) - db) <= tol


def test_triangle_semantics_and_normalisation():
    model = ContinuousPreisachModel.gaussian(2.0, 1.0, 0.2)  # r_lo = 0: E grows from a = b
    assert float(model.everett(model.upper, model.lower)) == pytest.approx(1.0, abs=1e-14)
    x = np.linspace(model.lower, model.upper, 41)
    np.testing.assert_array_equal(model.everett(x, x), 0.0)
    np.testing.assert_array_equal(model.everett(x - 0.3, x), 0.0)
    narrow = ContinuousPreisachModel.gaussian(2.0, 1.0, 0.0125)  # r_lo = 0.9: no mass below
    assert float(narrow.everett(1.0, -0.79)) == 0.0
    assert narrow.everett_gradient(1.0, -0.79) == (0.0, 0.0)
    assert float(narrow.everett(1.0, -0.81)) > 0.0
    # beyond the support: clipped value, zero gradient component
    da, db = model.everett_gradient(model.upper + 1.0, 0.0)
    assert float(da) == 0.0 and float(db) < 0.0


def test_phi_derivative_maxima_and_basis_sums():
    # m_k = max |He_k(z) φ(z)| on a fine grid: the constants are upper bounds, tight to 1e-8
    z = np.linspace(-12.0, 12.0, 480_001)
    phi = np.exp(-0.5 * z * z) / math.sqrt(2 * math.pi)
    for k, m in enumerate(PHI_DERIVATIVE_MAX):
        coeffs = np.zeros(k + 1)
        coeffs[k] = 1.0
        peak = float(np.max(np.abs(np.polynomial.hermite_e.hermeval(z, coeffs) * phi)))
        assert peak <= m < peak + 1e-7
    # the quintic Hermite basis: Σ|Q_{1,p}| <= 5/16, Σ|Q_{2,p}| <= 1/32 (module docstring)
    s = np.linspace(0.0, 1.0, 10_001)
    b1 = np.abs(s - 6 * s**3 + 8 * s**4 - 3 * s**5) + np.abs(-4 * s**3 + 7 * s**4 - 3 * s**5)
    b2 = np.abs(s**2 * (1 - s) ** 3 / 2) + np.abs(s**3 * (1 - s) ** 2 / 2)
    assert np.max(b1) <= 5 / 16 + 1e-15 and np.max(b2) <= 1 / 32 + 1e-15


def test_table_memory_cache_and_pickle():
    table = gaussian_table(2.0, 1.0, 0.2)
    n_x, n_t = table.cells
    assert table.compiled.table.shape == (n_x + 1, n_t + 1, 9)
    assert table.nbytes == 72 * (n_x + 1) * (n_t + 1) < 16_000_000  # the documented ~13 MB
    assert gaussian_table(2.0, 1.0, 0.2) is table  # cached per parameter set
    model = ContinuousPreisachModel.gaussian(2.0, 1.0, 0.2)
    assert model.gaussian_table is table
    back = pickle.loads(pickle.dumps(model))
    assert back.compiled_everett() is model.compiled_everett()
    u = np.linspace(-3.0, 3.0, 50)
    np.testing.assert_array_equal(back.apply(u)[0], model.apply(u)[0])
    with pytest.raises(ValueError, match="width_spread"):
        gaussian_table(2.0, 1.0, -0.1)
    with pytest.raises(ValueError, match="width_spread/spread asks for"):
        gaussian_table(2.0, 0.01, 5.0)  # a width law 500 R wide: refused up front
