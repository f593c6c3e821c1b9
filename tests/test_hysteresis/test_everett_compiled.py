"""The compiled Everett kernel (``everett_eval``) against the model's vectorised methods."""

import pickle

import numpy as np
import pytest

from hysteresis.preisach import ContinuousPreisachModel
from hysteresis.preisach._everett_kernels import everett_eval
from hysteresis.preisach.everett_table import CompiledEverett
from hysteresis.preisach.gaussian import gaussian_everett


def _points(model, rng, count=400):
    """Random points inside, beyond the support, on and above the diagonal."""
    lo, up = model.lower, model.upper
    span = up - lo
    a = rng.uniform(lo - 0.2 * span, up + 0.2 * span, count)
    b = rng.uniform(lo - 0.2 * span, up + 0.2 * span, count)
    a[:40] = b[:40]  # the diagonal
    b[40:60] = a[40:60] - 1e-9 * span  # just below it
    a[60:70], b[60:70] = up + 1.0, lo - 1.0  # both clipped
    a[70:80] = up  # on the bounds
    b[80:90] = lo
    return a, b


def _compare(model, compiled, a, b, tol):
    e = model.everett(a, b)
    da, db = model.everett_gradient(a, b)
    got = np.array(
        [
            everett_eval(compiled.kind, compiled.params, compiled.table, x, y)
            for x, y in zip(a, b, strict=True)
        ]
    )
    # E lies in [0, 1] and the gradient is bounded by the largest marginal density: both
    # sides do the same float operations up to summation order and erf/erfc ulps
    scale = max(1.0, float(np.max(np.abs(np.r_[da, db]))))
    np.testing.assert_allclose(got[:, 0], e, rtol=0, atol=tol)
    np.testing.assert_allclose(got[:, 1], da, rtol=0, atol=tol * scale)
    np.testing.assert_allclose(got[:, 2], db, rtol=0, atol=tol * scale)
    assert np.all(got[a <= b] == 0.0)


@pytest.mark.parametrize("args", [(2.0, 1.0, 0.2, 8), (2.0, 0.5, 0.0125, 8), (1.0, 1.0, 0.5, 6)])
def test_gaussian_model_is_its_compiled_kernel(args):
    model = ContinuousPreisachModel.gaussian(*args)
    compiled = model.compiled_everett()
    assert compiled.kind == 2 and compiled.table.shape[2] == 9
    a, b = _points(model, np.random.default_rng(1))
    # one function: the model's vectorised methods call the same kernel (bit for bit)
    _compare(model, compiled, a, b, 0.0)


@pytest.mark.parametrize("args", [(2.0, 1.0, 0.2, 48), (2.0, 0.5, 0.0125, 48), (1.0, 1.0, 0.5, 32)])
def test_gaussian_quadrature_kernel_matches_vectorised(args):
    # the reference quadrature (kind 0) compiled and vectorised, inside the triangle
    law = gaussian_everett(*args)
    compiled = law.compiled()
    assert compiled.kind == 0 and compiled.table.shape == (0, 0, 0)
    rng = np.random.default_rng(1)
    a = rng.uniform(-law.bound, law.bound, 300)
    b = a - rng.uniform(0.0, law.bound, 300)
    b = np.maximum(b, -law.bound)
    got = np.array([compiled(x, y) for x, y in zip(a, b, strict=True)])
    da, db = law.gradient(a, b)
    # rounding: ~48 terms of size <= 1, each with a few ulps (1e-16): a bound of 1e-14
    scale = max(1.0, float(np.max(np.abs(np.r_[da, db]))))
    np.testing.assert_allclose(got[:, 0], law.everett(a, b), rtol=0, atol=1e-14)
    np.testing.assert_allclose(got[:, 1], da, rtol=0, atol=1e-14 * scale)
    np.testing.assert_allclose(got[:, 2], db, rtol=0, atol=1e-14 * scale)


def test_compiled_everett_pickles():
    model = ContinuousPreisachModel.gaussian(2.0, 1.0, 0.2)
    compiled = model.compiled_everett()
    back = pickle.loads(pickle.dumps(compiled))
    assert isinstance(back, CompiledEverett) and back.kind == compiled.kind
    np.testing.assert_array_equal(back.params, compiled.params)
    assert back(1.0, -0.5) == compiled(1.0, -0.5)
    again = pickle.loads(pickle.dumps(model)).compiled_everett()
    np.testing.assert_array_equal(again.params, compiled.params)


def test_compiled_everett_validates():
    with pytest.raises(ValueError, match="kind"):
        CompiledEverett(7, np.array([0.0, 1.0]), np.zeros((0, 0, 0)))
    with pytest.raises(ValueError, match="shape"):
        CompiledEverett(1, np.array([0.0, 1.0]), np.zeros((3, 2, 4)))
