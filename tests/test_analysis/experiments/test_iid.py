"""The iid-input reference: M_T against brute-force spins, VAR[M] against the CLT."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from analysis.experiments.execution import spawn_seeds
from analysis.experiments.iid import iid_inputs, iid_magnetization, iid_task, iid_variance_scaling
from hysteresis.spin_dimers import SpinDimerEnsemble


def test_iid_task_matches_brute_force_spin_flips():
    res = iid_task(spins=200, n_steps=3000, seed=11, input_seed=12)
    ensemble = SpinDimerEnsemble.random(200, 2.0, 1.0, 2.0, 11)
    m, _ = ensemble.simulate(iid_inputs(3000, 2.0, 12))  # all spins down, relaxed at u_0
    assert res["magnetization"] == pytest.approx(float(np.mean(m)), abs=1e-12)


def _old_path_bound(ensemble: SpinDimerEnsemble, steps: int) -> float:
    """Bound on |M_T(nested drive) − M_T(ensemble.apply)| (tests/test_hysteresis/
    test_nested_drive.py): the general kernel's running sum drifts by at most
    ``|1 − W| + (2n + 3)(t + 1)·u·W`` after t inputs, the plan's outputs are within
    ``(n + 3)·u·W`` (equal weights), and each mean of ``steps`` values with |M| <= 1 adds
    ``(steps + 1)·u``."""
    w = ensemble.relay_table().weights
    n, total, u = w.size, math.fsum(w), np.finfo(float).eps / 2
    drift = abs(1.0 - total) + ((2 * n + 3) * (steps + 1) + n + 3) * u * total
    return drift + 2 * (steps + 1) * u


@pytest.mark.parametrize(
    "spins, seed, transient", [(2, 0, 0), (200, 3, 0), (2000, 4, 100), (6000, 5, 7)]
)
def test_iid_task_matches_the_general_preisach_path(spins, seed, transient):
    # the nested drive against the general kernel it replaced (ensemble.apply from
    # initial_state(u_0): all spins down, relaxed at u_0)
    n_steps = 3000
    res = iid_task(
        spins=spins, n_steps=n_steps, seed=seed, input_seed=seed + 1, transient_steps=transient
    )
    ensemble = SpinDimerEnsemble.random(spins, 2.0, 1.0, 2.0, seed)
    u = iid_inputs(n_steps + transient, 2.0, seed + 1)
    old, _ = ensemble.apply(u, ensemble.initial_state(float(u[0])))
    diff = abs(res["magnetization"] - float(np.mean(old[transient:])))
    assert diff <= _old_path_bound(ensemble, u.size)


def test_iid_task_falls_back_without_a_nested_plan(monkeypatch):
    from hysteresis.relay_table import RelayTable

    class NotNested(RelayTable):
        __slots__ = ()

        def nested_plan(self):
            return None

    nested = iid_task(spins=400, n_steps=2000, seed=8, input_seed=9, transient_steps=10)
    # the ensemble's relay table without a nested plan
    monkeypatch.setattr(SpinDimerEnsemble, "relay_table", lambda self: NotNested(*self.relays()))
    fallback = iid_task(spins=400, n_steps=2000, seed=8, input_seed=9, transient_steps=10)
    ensemble = SpinDimerEnsemble.random(400, 2.0, 1.0, 2.0, 8)
    u = iid_inputs(2010, 2.0, 9)
    old, _ = ensemble.apply(u, ensemble.initial_state(float(u[0])))
    assert fallback["magnetization"] == float(np.mean(old[10:]))  # the general path, as is
    diff = abs(nested["magnetization"] - fallback["magnetization"])
    assert diff <= _old_path_bound(ensemble, u.size)


def _relay_time_average(centres: np.ndarray, u: np.ndarray, half_width: float) -> np.ndarray:
    """Time-averaged output of relays α = s + r, β = s − r driven by u, started at −1 and
    relaxed at u_0 — written directly from the relay rule, independent of the package."""
    y = np.where(u[0] >= centres + half_width, 1.0, -1.0)
    total = np.zeros_like(centres)
    for x in u:
        y = np.where(x >= centres + half_width, 1.0, np.where(x < centres - half_width, -1.0, y))
        total += y
    return total / u.size


def test_variance_matches_central_limit_prediction():
    # M_T = (2/N) Σ_k g(s_k) with g the time-averaged relay output: VAR[M] = (2/N) Var_s[g(s)],
    # s ~ N(0, R² = 1), loop width p = 2 (half width 1). Var_s[g] by quadrature on a fine grid.
    n_spins, n_steps, k = 400, 400, 400
    u = iid_inputs(n_steps, 2.0, 99)
    s_grid = np.linspace(-7.0, 7.0, 4001)
    g = _relay_time_average(s_grid, u, 1.0)
    w = stats.norm.pdf(s_grid)
    w /= w.sum()
    var_g = np.sum(w * g**2) - np.sum(w * g) ** 2
    predicted = 2.0 / n_spins * var_g
    m = np.array(
        [
            iid_task(spins=n_spins, n_steps=n_steps, seed=s, input_seed=99)["magnetization"]
            for s in spawn_seeds(3, k)
        ]
    )
    measured = np.var(m)
    # relative standard error of a sample variance of K values ≈ sqrt(2/(K−1)) = 0.07
    assert measured == pytest.approx(predicted, rel=4 * np.sqrt(2.0 / (k - 1)))
    # the ensemble mean is the quadrature mean of g
    assert np.mean(m) == pytest.approx(np.sum(w * g), abs=4 * np.sqrt(predicted / k))


def test_variance_scales_as_inverse_spin_number():
    res = iid_variance_scaling([100, 300, 1000, 3000], n_steps=500, realizations=300, seed=5)
    assert abs(res.fit.exponent + 1.0) < 0.1
    assert res.fit.stderr < 0.05
    assert np.all(np.diff(res.variance) < 0)


def test_iid_magnetization_reproducible_and_input_modes():
    a = iid_magnetization(100, 200, 5, seed=1)
    b = iid_magnetization(100, 200, 5, seed=1)
    assert a.tolist() == b.tolist()
    assert not np.array_equal(a, iid_magnetization(100, 200, 5, seed=2))
    c = iid_magnetization(100, 200, 5, seed=1, common_input=False)
    assert c[0] == a[0] and not np.array_equal(a[1:], c[1:])  # first input shared, others new
    with pytest.raises(ValueError):
        iid_magnetization(100, 200, 0, seed=1)
    with pytest.raises(ValueError):
        iid_inputs(10, 0.0, 1)


def test_store_of_another_code_version_is_reused_only_when_allowed(tmp_path, monkeypatch):
    # the iid ensemble honours allow_version_mismatch like every other run_tasks caller (hyst
    # paper --allow-version-mismatch passes it through): refused by default, reused when told
    import analysis.experiments.store as store_module
    from analysis.experiments.iid import iid_magnetization
    from analysis.experiments.store import StoreError

    store = tmp_path / "s.sqlite"
    with monkeypatch.context() as m:  # written (and sealed) by another code version
        m.setattr(store_module, "code_version", lambda: "hysteresis-toolkit 0.0.1 (git 0000000)")
        first = iid_magnetization(20, 200, 3, seed=1, store=store)
    with pytest.raises(StoreError, match="allow_version_mismatch|other code versions"):
        iid_magnetization(20, 200, 3, seed=1, store=store)
    with pytest.warns(UserWarning, match="other code versions"):
        again = iid_magnetization(20, 200, 3, seed=1, store=store, allow_version_mismatch=True)
    assert np.array_equal(first, again)


def test_variance_scaling_runs_every_size_at_once_with_the_per_size_tasks(tmp_path):
    # iid_variance_scaling sends the tasks of every N through one run_tasks call (one worker
    # pool); they must be exactly the tasks of one iid_magnetization call per N: the same
    # magnetizations bit for bit, and the same store keys (a per-N rerun finds every task)
    from analysis.experiments.iid import _seed_for
    from analysis.experiments.store import ResultStore

    store = tmp_path / "iid.sqlite"
    sizes, steps, k = [20, 60, 200], 150, 4
    res = iid_variance_scaling(sizes, n_steps=steps, realizations=k, seed=3, store=store)
    with ResultStore(store) as s:
        stored = set(s.keys("iid"))
    assert len(stored) == len(sizes) * k
    for n, mags in zip(sizes, res.magnetizations, strict=True):
        alone = iid_magnetization(n, steps, k, _seed_for(3, n))  # no store: computed afresh
        assert mags.tolist() == alone.tolist()
        served = iid_magnetization(n, steps, k, _seed_for(3, n), store=store)
        assert served.tolist() == alone.tolist()
    with ResultStore(store) as s:
        assert set(s.keys("iid")) == stored  # nothing new was computed for the per-N calls
    # a pool of two workers gives the same values as the serial run
    pooled = iid_variance_scaling(sizes, n_steps=steps, realizations=k, seed=3, workers=2)
    assert [m.tolist() for m in pooled.magnetizations] == [m.tolist() for m in res.magnetizations]
