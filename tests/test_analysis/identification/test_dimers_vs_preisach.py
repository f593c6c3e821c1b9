"""Brute-force spin-flip dynamics of spin dimers equals the equivalent discrete Preisach model."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

spin_dimers = pytest.importorskip("hysteresis.spin_dimers")
SpinDimerEnsemble = spin_dimers.SpinDimerEnsemble

# quarter-integer grid: thresholds J - b1, -J - b2 and inputs coincide often (ties), and the
# border case 2J = b1 - b2 occurs
grid = st.integers(-12, 12).map(lambda k: k / 4)


@st.composite
def ensembles(draw):
    n_dimers = draw(st.integers(1, 10))
    coupling = draw(st.sampled_from([0.25, 0.5, 1.0, 1.5]))
    fields = np.array([[draw(grid), draw(grid)] for _ in range(n_dimers)])
    return SpinDimerEnsemble(fields, coupling)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(ensembles(), st.lists(grid | st.floats(-4, 4), min_size=1, max_size=40))
def test_spin_flip_dynamics_equals_preisach(ensemble, inputs):
    spins_m, _ = ensemble.simulate(np.array(inputs))
    preisach_m, _ = ensemble.to_preisach().apply(inputs)
    np.testing.assert_allclose(preisach_m, spins_m, atol=1e-12)


def test_disorder_classes_are_covered():
    # one hysteretic (2J > b1 - b2), one border (2J = b1 - b2), one reversible (2J < b1 - b2)
    ensemble = SpinDimerEnsemble([[0.5, 0.0], [1.0, -1.0], [2.0, -1.0]], spin_coupling=1.0)
    alpha, beta, weights = ensemble.relays()
    assert weights.sum() == pytest.approx(1.0)
    model = ensemble.to_preisach()
    assert model.n_relays == 4  # the reversible dimer gives two zero-width relays
    rng = np.random.default_rng(0)
    inputs = np.round(rng.uniform(-3, 3, 500) * 4) / 4
    spins_m, _ = ensemble.simulate(inputs)
    out, _ = model.apply(inputs)
    np.testing.assert_allclose(out, spins_m, atol=1e-12)


def test_paper_ensemble_long_walk():
    ensemble = SpinDimerEnsemble.random(2000, width=2.0, spread=1.0, spin_coupling=2.0, seed=3)
    rng = np.random.default_rng(1)
    walk = np.clip(np.cumsum(rng.normal(0, 0.1, 3000)), -4, 4)
    spins_m, _ = ensemble.simulate(walk)
    out, _ = ensemble.to_preisach().apply(walk)
    np.testing.assert_allclose(out, spins_m, atol=1e-12)
    assert ensemble.to_preisach().equal_widths
