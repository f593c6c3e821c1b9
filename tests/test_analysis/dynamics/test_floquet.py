"""The one home of Floquet multipliers (:mod:`analysis.dynamics.floquet`) against matrices whose
eigenvalues are constructed: ``J = V diag(μ) V⁻¹``, a block-triangular ``[[A, B], [0, I]]``
(frozen memory) and a rank-deficient block (a reset direction); and the basins' unrefined cycle
through it."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg

from analysis.dynamics.attractors import periodic_attractor, section_run, start_state
from analysis.dynamics.floquet import (
    active_multipliers,
    floquet_exponents,
    floquet_multipliers,
    frozen_coordinates,
    is_stable,
    max_abs_multiplier,
    multiplier_roundoff,
    stability,
)
from analysis.experiments.models import build_operator
from oscillators import ForcedOscillator

#: eigenvalues of a well-conditioned 4 × 4 matrix built from them are recovered to a few ulp
#: times the condition number of V (below 10 here): 1e-12 is far above round-off
ROUNDOFF = 1e-12


def _with_eigenvalues(mu: np.ndarray, seed: int = 0) -> np.ndarray:
    """A real matrix with eigenvalues ``mu`` (complex ones in conjugate pairs, in order)."""
    rng = np.random.default_rng(seed)
    d = mu.size
    block = np.zeros((d, d))
    i = 0
    while i < d:
        if mu[i].imag == 0.0:
            block[i, i] = mu[i].real
            i += 1
        else:  # the real 2 × 2 block of a conjugate pair a ± ib
            a, b = mu[i].real, abs(mu[i].imag)
            block[i : i + 2, i : i + 2] = [[a, -b], [b, a]]
            i += 2
    v = np.eye(d) + 0.3 * rng.uniform(-1, 1, size=(d, d))
    return v @ block @ np.linalg.inv(v)


def test_plain_eigenvalues_by_decreasing_modulus():
    mu = np.array([0.3 + 0.4j, 0.3 - 0.4j, -1.7, 0.05])
    jac = _with_eigenvalues(mu)
    got, vec, tags = floquet_multipliers(jac)
    assert got.dtype == complex and tags == ("",) * 4
    want = mu[np.argsort(-np.abs(mu), kind="stable")]
    assert np.abs(got).tolist() == sorted(np.abs(got).tolist(), reverse=True)
    assert np.max(np.abs(np.sort_complex(got) - np.sort_complex(want))) < ROUNDOFF
    # J v = μ v for every column
    assert np.max(np.abs(jac @ vec - vec * got)) < ROUNDOFF


def test_frozen_directions_are_exactly_one_with_the_family_tangent():
    a = _with_eigenvalues(np.array([0.6, -0.2]), seed=1)
    b = np.array([[0.3, -0.1], [0.2, 0.5]])
    jac = np.block([[a, b], [np.zeros((2, 2)), np.eye(2)]])
    frozen = frozen_coordinates(jac)
    assert frozen.tolist() == [False, False, True, True]
    labels = ("q", "v", "w0", "w1")
    mu, vec, tags = floquet_multipliers(jac, frozen, 0, labels)
    assert tags == ("frozen: w0", "frozen: w1", "", "")
    assert mu[0] == 1.0 and mu[1] == 1.0  # exactly, not a round-off eigenvalue of J
    assert np.max(np.abs(np.sort(mu[2:].real) - [-0.2, 0.6])) < ROUNDOFF
    # the family's tangents (−(A − I)⁻¹ B e_f, e_f) are fixed by J
    for j in (0, 1):
        assert np.max(np.abs(jac @ vec[:, j] - vec[:, j])) < ROUNDOFF
    # the reduced eigenvectors do not move the frozen coordinates
    assert np.all(vec[2:, 2:] == 0.0)
    assert active_multipliers(mu, tags).tolist() == mu[2:].tolist()
    assert max_abs_multiplier(mu, tags) == pytest.approx(0.6, abs=ROUNDOFF)
    assert is_stable(mu, tags) and not is_stable(mu)  # frozen 1s judge nothing
    with pytest.raises(ValueError, match="labels"):
        floquet_multipliers(jac, frozen)


def test_structural_zero_is_exact_and_a_genuine_multiplier_is_kept():
    # a rank-1 block: one multiplier 0.8, one structurally 0 (computed as round-off)
    u, w = np.array([1.0, 0.5]), np.array([0.6, 0.4])
    jac = np.outer(u, w)  # eigenvalues w·u = 0.8 and 0
    mu, _, tags = floquet_multipliers(jac, None, 1)
    assert mu[1] == 0.0 and tags == ("", "reset")
    assert mu[0] == pytest.approx(0.8, abs=ROUNDOFF)
    # claimed structural zero that is not one (|μ| = 0.5 >> RESET_ROUNDOFF): kept, unlabelled
    mu, _, tags = floquet_multipliers(np.diag([0.9, 0.5]), None, 1)
    assert mu.tolist() == [0.9, 0.5] and tags == ("", "")


def test_exponents_stability_and_the_empty_cases():
    mu = np.array([0.5 + 0.5j, 0.5 - 0.5j, 0.0])
    exps = floquet_exponents(mu, 4.0)
    assert exps[0] == exps[1] == pytest.approx(math.log(math.sqrt(0.5)) / 4.0, rel=1e-15)
    assert exps[2] == -math.inf
    assert is_stable(mu) and not is_stable(np.array([1.0 + 0j]))
    assert not is_stable(np.array([-1.000001]))
    assert max_abs_multiplier(np.array([1.0]), ("frozen: w",)) == 1.0  # all frozen: 1
    assert max_abs_multiplier(np.array([-2.0, 0.5])) == 2.0


def test_an_unrefined_cycle_gets_the_jacobians_multipliers():
    # periodic_attractor's fallback: on the chaotic erf-play attractor (C = 2.9) no period-3
    # orbit is next to the state, Newton fails, and the multipliers are those of the Jacobian
    # of P^3 at the state itself: complex, by decreasing modulus, their product det J (an
    # invariant of the eigenvalue problem; round-off ~1e-15·|J|^d), exponents log|μ|/(3T)
    system = ForcedOscillator(build_operator("erf-play"), 2.9)
    run = section_run(
        system, start_state(system, -1.0, 0.0), 100, 40, max_period=20, keep_state=True
    )
    assert run.period == 0  # chaotic
    # whether Newton fails from a given chaotic state depends on the trajectory's last bits
    # (unstable period-3 orbits are dense there): take the first of the next section points
    # from which it fails
    engine = system.engine(run.final)
    for k in range(1, 41):
        state = engine.state()
        got = periodic_attractor(system, state, 3)
        if not got["refined"]:
            break
        engine.advance(k * system.period)
    assert got["refined"] is False, "Newton converged from 40 successive chaotic states"
    mu = got["multipliers"]
    jac, _ = system.jacobian(3 * system.period, state, include_phase=False)
    assert mu.dtype == complex
    assert np.all(np.diff(np.abs(mu)) <= 0.0)
    assert abs(np.prod(mu) - np.linalg.det(jac)) <= 1e-12 * max(1.0, np.max(np.abs(jac))) ** 3
    assert np.array_equal(got["exponents"], np.log(np.abs(mu)) / (3 * system.period))
    assert got["stable"] == bool(np.all(np.abs(mu) < 1.0))


def test_neutral_band_from_the_eigenvalue_condition():
    # J = V diag(μ) V⁻¹: the band of μ_i is κ_i·n·ε·|J|₂ with κ_i = |x_i||y_i|/|y_i^H x_i|
    # (1 for a normal matrix); a multiplier within it of the unit circle is neutral
    mu = np.array([1.0 - 1e-15, 0.5, 0.2])
    jac = _with_eigenvalues(mu)
    got, _, _ = floquet_multipliers(jac)
    band = multiplier_roundoff(jac, got, None, 10)
    w, vl, vr = scipy.linalg.eig(jac, left=True)
    kappa = (
        np.linalg.norm(vl, axis=0)
        * np.linalg.norm(vr, axis=0)
        / np.abs(np.sum(vl.conj() * vr, axis=0))
    )
    order = np.argsort(-np.abs(w), kind="stable")
    want = kappa[order] * 10 * np.finfo(float).eps * np.linalg.norm(jac, 2)
    assert np.allclose(band, want, rtol=1e-6)
    assert stability(got, (), band) == "neutral" and not is_stable(got, (), band)
    assert stability(got, ()) == "stable" and is_stable(got)  # no band: as before
    assert stability(np.array([1.5, 1.0]), (), np.array([1e-12, 1e-12])) == "unstable"
    assert stability(np.array([0.5, 1.0 + 1e-13]), (), np.array([1e-12, 1e-12])) == "neutral"
    assert stability(np.array([1.0 + 0j]), ("frozen: w",)) == "stable"  # frozen judge nothing
