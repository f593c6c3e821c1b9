"""Analytic propagator of q'' + 2ζq' + q = cos φ + F against independent integrations."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import expm

from oscillators.linear import (
    forced_response,
    homogeneous_propagator,
    propagate,
    segment_jacobian,
)


def reference(q, v, phi, h, force, zeta, omega):
    def rhs(t, x):
        return [x[1], -2 * zeta * x[1] - x[0] + math.cos(phi + omega * t) + force]

    sol = solve_ivp(rhs, (0.0, h), [q, v], method="DOP853", rtol=1e-13, atol=1e-13)
    return sol.y[0, -1], sol.y[1, -1]


CASES = [
    # q, v, phi, h, F, zeta, omega
    (-1.0, 0.1, 0.0, 7.3, 4.0, 0.05, 1.0),
    (0.3, -2.0, 1.1, 0.37, -2.9, 0.05, 1.0),
    (2.0, 0.0, 2.5, 12.0, 0.0, 0.2, 1.7),
    (0.5, 1.5, 0.3, 3.0, 1.0, 1.0, 0.6),  # critical damping
    (-0.5, 0.7, 4.0, 2.5, 0.5, 2.5, 2.0),  # overdamped
    (1.0, -1.0, 0.0, 9.0, 0.3, 0.0, 0.5),  # undamped, off resonance
    (1.0, 0.2, 0.7, 1e-3, 2.0, 0.05, 1.0),  # a short hop
]


@pytest.mark.parametrize("q, v, phi, h, force, zeta, omega", CASES)
def test_propagate_matches_solve_ivp(q, v, phi, h, force, zeta, omega):
    q1, v1, phi1 = propagate(q, v, phi, h, force, zeta, omega)
    qr, vr = reference(q, v, phi, h, force, zeta, omega)
    scale = max(1.0, abs(qr), abs(vr))
    assert abs(q1 - qr) <= 1e-12 * scale
    assert abs(v1 - vr) <= 1e-12 * scale
    assert phi1 == phi + omega * h


def test_particular_solution_is_periodic_response():
    zeta, omega = 0.05, 1.3
    a, b = forced_response(zeta, omega)
    # start exactly on the periodic orbit: stays on it
    q0 = a * 1.0 + b * 0.0 + 0.7
    v0 = omega * b
    q1, v1, _ = propagate(q0, v0, 0.0, 2 * math.pi / omega, 0.7, zeta, omega)
    assert abs(q1 - q0) < 1e-13 and abs(v1 - v0) < 1e-13
    # amplitude 1/sqrt((1-Ω²)² + (2ζΩ)²)
    assert math.isclose(math.hypot(a, b), 1 / math.hypot(1 - omega**2, 2 * zeta * omega))


@pytest.mark.parametrize("zeta", [0.0, 0.05, 0.9, 1.0, 1.7])
def test_homogeneous_propagator_is_matrix_exponential(zeta):
    for h in (1e-4, 0.3, 5.0):
        got = homogeneous_propagator(h, zeta)
        want = expm(h * np.array([[0.0, 1.0], [-1.0, -2.0 * zeta]]))
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-14)
        assert abs(np.linalg.det(got) - math.exp(-2 * zeta * h)) < 1e-14  # Liouville


def test_segment_jacobian_matches_finite_differences():
    q, v, phi, h, force, zeta, omega = 0.4, -0.8, 1.2, 2.7, 1.5, 0.05, 1.0
    jac = segment_jacobian(phi, h, zeta, omega)
    eps = 1e-6
    base = np.array([q, v, phi])
    fd = np.empty((3, 3))
    for j in range(3):
        dp = base.copy()
        dm = base.copy()
        dp[j] += eps
        dm[j] -= eps
        fp = np.array(propagate(dp[0], dp[1], dp[2], h, force, zeta, omega))
        fm = np.array(propagate(dm[0], dm[1], dm[2], h, force, zeta, omega))
        fd[:, j] = (fp - fm) / (2 * eps)
    np.testing.assert_allclose(jac, fd, atol=1e-8)


def test_validation():
    with pytest.raises(ValueError, match="damping_ratio"):
        propagate(0, 0, 0, 1, damping_ratio=-1)
    with pytest.raises(ValueError, match="frequency"):
        propagate(0, 0, 0, 1, frequency=0)
    with pytest.raises(ValueError, match="resonance"):
        propagate(0, 0, 0, 1, damping_ratio=0.0, frequency=1.0)
