"""StaticMap (hysteresis.static_map) against closed forms.

* ``apply`` is ``f`` itself; the branch flow has no memory, output ``f``, partials ``(f', ())``
  and no breakpoint;
* the numeric derivative (Richardson-extrapolated central differences) against exact
  derivatives, within the error bound stated in the module docstring;
* bad input: a derivative that disagrees with ``f``, an ``f`` that is not finite, a wrong
  ``output_range`` or ``max_slope`` — each one line naming the parameter.
"""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest

from hysteresis.base import ContinuousHysteron
from hysteresis.static_map import STEP, StaticMap, StaticMapState

EPS = np.finfo(np.float64).eps


def cubic(u):
    return 0.1 * np.asarray(u) ** 3 - u


def cubic_derivative(u):
    return 0.3 * np.asarray(u) ** 2 - 1.0


def pole_at_200(u):
    """Finite on the probe grid (|u| <= 100), infinite at u = 200."""
    return 1.0 / (200.0 - np.asarray(u, dtype=np.float64))


def test_apply_is_f_and_the_state_is_the_input():
    op = StaticMap(np.tanh)
    assert isinstance(op, ContinuousHysteron) and not op.piecewise_constant
    u = np.array([-2.0, 0.3, 5.0, -0.7])
    y, state = op.apply(u)
    np.testing.assert_array_equal(y, np.tanh(u))
    assert state == StaticMapState(-0.7)
    assert op.output(state) == np.tanh(-0.7)
    assert op.initial_state(1.5) == StaticMapState(1.5)
    # memoryless: continuing from any state gives the same outputs
    y2, _ = op.apply(u, StaticMapState(40.0))
    np.testing.assert_array_equal(y2, y)


@pytest.mark.parametrize(
    ("f", "exact", "fifth"),
    [
        (np.sin, np.cos, 1.0),  # |f^(5)| = |cos| <= 1
        (np.tanh, lambda u: 1.0 / np.cosh(u) ** 2, 16.0),  # |tanh^(5)| <= 16
        (cubic, cubic_derivative, 0.0),
    ],
)
def test_numeric_derivative_within_its_stated_error(f, exact, fifth):
    """Richardson on D(h), D(h/2): truncation f^(5) h⁴/480, rounding about 3ε·|f|/h."""
    op = StaticMap(f)
    u = np.linspace(-5.0, 5.0, 201) + 0.0123
    h = STEP * np.maximum(1.0, np.abs(u))
    scale = np.max(np.abs(f(np.linspace(-5.1, 5.1, 1001))))
    bound = fifth * h**4 / 480.0 + 3.0 * EPS * scale / h
    err = np.abs(op.derivative(u) - exact(u))
    assert np.all(err <= 2.0 * bound), float(np.max(err / bound))
    # and the stated order of magnitude: ε^{4/5} ~ 3e-13 on unit scale
    assert float(np.max(err[np.abs(u) <= 1.0])) < 1e-11


def test_given_derivative_is_used_and_checked():
    op = StaticMap(cubic, cubic_derivative)
    u = np.array([-3.0, 0.5, 2.0])
    np.testing.assert_array_equal(op.derivative(u), cubic_derivative(u))
    with pytest.raises(ValueError, match="^derivative disagrees with f: at u = "):
        StaticMap(cubic, lambda u: 1.001 * cubic_derivative(u))
    with pytest.raises(ValueError, match="^derivative disagrees"):
        StaticMap(np.sin, np.sin)


def test_branch_flow_has_no_memory_and_its_partials_are_differences_of_apply():
    op = StaticMap(cubic, cubic_derivative)
    state = op.initial_state(1.3)
    for d in (1, -1):
        flow = op.branch_flow(state, d)
        assert flow.labels == () and flow.n_memory == 0
        assert flow.breakpoint == d * math.inf
        u = np.array([1.3, 1.3 + 0.4 * d, 1.3 + 2.0 * d])
        np.testing.assert_array_equal(flow.output(u), cubic(u))
        d_u, d_m = flow.partials(u)
        assert d_m.shape == (3, 0)
        h = 1e-5
        fd = (op.apply(u + h)[0] - op.apply(u - h)[0]) / (2 * h)
        # central difference error 0.1·h²·|f'''|/6·6 = 0.1 h² plus rounding ε|f|/h
        np.testing.assert_allclose(d_u, fd, rtol=0, atol=0.2 * h**2 + 10 * EPS * 10 / h)
        assert float(flow.slope(1.3)) == cubic_derivative(1.3)


def test_monotonicity_from_the_probe_grid():
    assert StaticMap(np.tanh).monotonicity == 1
    assert StaticMap(np.negative).monotonicity == -1
    assert StaticMap(np.sin).monotonicity == 0
    assert StaticMap(cubic).monotonicity == 0
    assert StaticMap(np.zeros_like).monotonicity == 1  # constant: non-decreasing


def test_output_range_and_max_slope_are_checked_on_the_probe_grid():
    op = StaticMap(np.tanh, output_range=(-1.0, 1.0), max_slope=1.0)
    assert op.output_range == (-1.0, 1.0) and op.max_slope == 1.0
    assert StaticMap(np.tanh).output_range == (-math.inf, math.inf)
    assert StaticMap(np.tanh).max_slope is None
    with pytest.raises(ValueError, match=r"^output_range \(-0.5, 0.5\) does not contain f\("):
        StaticMap(np.tanh, output_range=(-0.5, 0.5))
    with pytest.raises(ValueError, match="^output_range must have low <= high"):
        StaticMap(np.tanh, output_range=(1.0, -1.0))
    with pytest.raises(ValueError, match="^max_slope 0.5 is below the slope"):
        StaticMap(np.tanh, max_slope=0.5)


def test_non_finite_f_is_refused_at_construction_and_in_apply():
    with pytest.raises(ValueError, match="^f must be finite, got nan at u = "):
        StaticMap(np.log)
    op = StaticMap(pole_at_200)
    with pytest.raises(ValueError, match="^f must be finite, got inf at u = 200.0"):
        op.apply([0.0, 200.0])
    with pytest.raises(TypeError, match="^f must be a callable"):
        StaticMap(3.0)
    with pytest.raises(TypeError, match="^derivative must be a callable"):
        StaticMap(np.tanh, 1.0)
    with pytest.raises(ValueError, match="^f must return one value per input"):
        StaticMap(np.sum)
    with pytest.raises(TypeError, match="^state must be a StaticMapState"):
        StaticMap(np.tanh).apply([0.0], state=1.0)


def test_pickles_where_f_does():
    op = StaticMap(np.tanh, name="tanh", output_range=(-1.0, 1.0))
    copy = pickle.loads(pickle.dumps(op))
    u = np.linspace(-3, 3, 11)
    np.testing.assert_array_equal(copy.apply(u)[0], op.apply(u)[0])
    np.testing.assert_array_equal(copy.derivative(u), op.derivative(u))
    assert copy.output_range == (-1.0, 1.0) and repr(copy) == "StaticMap(tanh)"
    op2 = StaticMap(cubic, cubic_derivative)
    np.testing.assert_array_equal(pickle.loads(pickle.dumps(op2)).apply(u)[0], cubic(u))
