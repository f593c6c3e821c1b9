"""The one Newton loop (:mod:`analysis.dynamics.newton`) on problems with closed-form roots:
quadratic convergence, damping where the full step diverges (arctan), a bordered system (the
unit circle cut by a line: natural and pseudo-arclength rows), held unknowns, the named
tolerances and the failures."""

from __future__ import annotations

import math

import numpy as np
import pytest

from analysis.dynamics.newton import Border, Linearization, NewtonError, newton


def _scalar(f, df):
    """``evaluate`` of a scalar equation f(z) = 0 as a 1-vector problem."""

    def evaluate(z, previous):
        return Linearization(np.array([f(z[0])]), lambda: np.array([[df(z[0])]]))

    return evaluate


SQRT2 = _scalar(lambda x: x * x - 2.0, lambda x: 2.0 * x)


def test_quadratic_convergence_to_the_root():
    got = newton(SQRT2, [1.0], tolerance=1e-15, max_iterations=10)
    assert got.z[0] == pytest.approx(math.sqrt(2.0), rel=2e-16)
    r = got.residuals
    # e_{n+1} = e_n² / (2 x_n): the residual (= 2√2·e to first order) squares each step
    for a, b in zip(r[1:-1], r[2:], strict=False):
        if a > 1e-7:
            assert b <= a * a  # b ≈ a²/(4√2)
    assert got.iterations == len(r) - 1 <= 6
    assert r[-1] <= 1e-15 * math.sqrt(2.0)


def test_damping_where_the_full_step_diverges():
    # Newton on arctan from |x0| > 1.3917 overshoots ever further (the full step diverges);
    # halving the step until |F| decreases converges to the root 0. Absolute residuals here:
    # relative to max(1, |x|) a runaway iterate of 1e18 would pass any tolerance
    atan = _scalar(math.atan, lambda x: 1.0 / (1.0 + x * x))
    with pytest.raises(NewtonError) as exc, np.errstate(over="ignore"):
        newton(atan, [3.0], tolerance=1e-12, max_iterations=20, scale=lambda z: 1.0)
    assert exc.value.residuals[-1] > 1.5  # arctan of the runaway iterate, toward π/2
    got = newton(atan, [3.0], tolerance=1e-12, max_iterations=30, max_halvings=10)
    assert abs(got.z[0]) <= 1e-12
    assert all(b < a for a, b in zip(got.residuals, got.residuals[1:], strict=False))


def _circle(z, previous):
    """F(x, λ) = x² + λ² − 1 (one residual, two unknowns)."""
    x, lam = z
    return Linearization(np.array([x * x + lam * lam - 1.0]), lambda: np.array([[2 * x, 2 * lam]]))


def test_bordered_system_natural_and_pseudo_arclength():
    # natural: λ fixed at 0.3 by the row e_λ: x = √(1 − 0.09)
    z_pred = np.array([0.9, 0.3])
    got = newton(
        _circle,
        z_pred,
        tolerance=1e-14,
        max_iterations=20,
        border=Border(np.array([0.0, 1.0]), z_pred),
    )
    assert got.z[1] == 0.3
    assert got.z[0] == pytest.approx(math.sqrt(0.91), rel=1e-14)
    # pseudo-arclength: the row along the tangent τ = (−sin θ, cos θ) at θ = 0.4, from the
    # predictor z(θ) + 0.1·τ: the corrector lands where the line τ·(z − z_pred) = 0 meets
    # the circle, τ·z = sin(φ − θ) = 0.1, at angle φ = θ + asin(0.1) (closed form)
    theta, ds = 0.4, 0.1
    tau = np.array([-math.sin(theta), math.cos(theta)])
    z_pred = np.array([math.cos(theta), math.sin(theta)]) + ds * tau
    got = newton(_circle, z_pred, tolerance=1e-14, max_iterations=20, border=Border(tau, z_pred))
    phi = theta + math.asin(ds)
    assert np.max(np.abs(got.z - [math.cos(phi), math.sin(phi)])) < 1e-14
    assert abs(float(tau @ (got.z - z_pred))) <= 1e-12 * (1.0 + np.max(np.abs(got.z)))


def test_held_unknowns_keep_their_value():
    # F = (x0² − 2·x1, x1 − 1) but x1 held (left out of free): only x0 moves, to √(2·x1)
    def evaluate(z, previous):
        x0, x1 = z
        return Linearization(
            np.array([x0 * x0 - 2.0 * x1, 0.0]),
            lambda: np.array([[2 * x0, -2.0], [0.0, 0.0]]),  # singular in the held row
            free=np.array([0]),
        )

    got = newton(evaluate, [1.0, 1.5], tolerance=1e-14, max_iterations=20)
    assert got.z[1] == 1.5
    assert got.z[0] == pytest.approx(math.sqrt(3.0), rel=1e-14)


def test_the_step_tolerance_and_the_callers_criterion():
    root = math.sqrt(2.0)
    # from the root: 0 steps by the residual; a finite step tolerance asks for one (a zero step)
    assert newton(SQRT2, [root], tolerance=1e-15, max_iterations=5).iterations == 0
    assert (
        newton(SQRT2, [root], tolerance=1e-15, max_iterations=5, step_tolerance=1e-8).iterations
        == 1
    )
    # a loose residual tolerance stops early; the step tolerance then demands the steps until
    # the last one is below 1e-12 (quadratic convergence: one step more than the residual's
    # 1e-12 at most)
    loose = newton(SQRT2, [1.0], tolerance=1e-3, max_iterations=20)
    both = newton(SQRT2, [1.0], tolerance=1e-3, max_iterations=20, step_tolerance=1e-12)
    assert both.iterations > loose.iterations
    assert abs(both.z[0] - root) < 1e-15
    # the caller's condition: the positive root only; from −1 Newton goes to −√2 and stays
    with pytest.raises(NewtonError, match="iterations"):
        newton(SQRT2, [-1.0], tolerance=1e-14, max_iterations=10, converged=lambda z, ev: z[0] > 0)


def test_failures_are_named():
    no_root = _scalar(lambda x: x * x + 1.0, lambda x: 2.0 * x)
    with pytest.raises(NewtonError) as exc:
        newton(no_root, [0.0], tolerance=1e-12, max_iterations=5)
    assert exc.value.reason == "singular" and exc.value.residuals == (1.0,)

    def fragile(z, previous):  # every trial point fails: the damped step stalls
        if previous is not None:
            raise ValueError("outside the domain")
        return Linearization(np.array([z[0] - 1.0]), lambda: np.array([[1.0]]))

    with pytest.raises(NewtonError) as exc:
        newton(
            fragile,
            [0.0],
            tolerance=1e-12,
            max_iterations=5,
            max_halvings=3,
            trial_failures=(ValueError,),
        )
    assert exc.value.reason == "stalled"
    with pytest.raises(ValueError, match="outside"):  # undamped: the caller's failure propagates
        newton(fragile, [0.0], tolerance=1e-12, max_iterations=5)
    with pytest.raises(ValueError, match="tolerance"):
        newton(SQRT2, [1.0], tolerance=0.0, max_iterations=5)
    with pytest.raises(ValueError, match="unknowns"):
        newton(_circle, [1.0, 0.0], tolerance=1e-12, max_iterations=5)  # no border row
