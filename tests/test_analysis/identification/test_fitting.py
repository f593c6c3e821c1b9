"""From identified densities to models, and identification from arbitrary input/output records.

Truths are the toolkit's own operators with known parameters; checks are against held-out input
sequences (not used in any fit), noise levels, and exact algebra (cumulative sums, relays).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import nnls

from analysis.identification import (
    ReversalCurves,
    identify_from_curves,
    measure_reversal_curves,
    regular_grid,
)
from analysis.identification.fitting import (
    fit_prandtl_ishlinskii,
    fit_preisach_record,
    relay_outputs,
)
from hysteresis import DiscretePreisachModel, PrandtlIshlinskii, PreisachModel
from hysteresis.preisach.projection import (
    _block_pivoting_nnls,
    _everett_adjoint,
    _everett_apply,
    project_identification,
)

NOISE = 0.01


def _random_relays(n: int, seed: int) -> DiscretePreisachModel:
    rng = np.random.default_rng(seed)
    s = rng.normal(0.0, 0.6, n)
    r = np.abs(rng.normal(0.8, 0.3, n))
    return PreisachModel.from_relays(np.clip(s + r, -2.9, 2.9), np.clip(s - r, -2.9, 2.9))


def _node_walk(nodes: np.ndarray, n: int, rng) -> np.ndarray:
    """Held-out input: a random walk of turning points on the lattice nodes (not FORCs)."""
    idx = np.empty(n, dtype=int)
    k = nodes.size // 2
    for t, d in enumerate(rng.integers(-8, 9, n)):
        k = min(max(k + d, 0), nodes.size - 1)  # clipped at the ends, not an unbounded walk
        idx[t] = k
    return nodes[idx]


def test_everett_operator_and_its_adjoint_by_brute_force():
    rng = np.random.default_rng(0)
    m = rng.normal(size=(4, 5))
    e = _everett_apply(m)
    for k in range(5):
        for l in range(6):  # noqa: E741 - the node index of the formula
            assert e[k, l] == pytest.approx(m[:k, l:].sum(), abs=1e-12)
    r = rng.normal(size=(5, 6))
    # <C m, r> = <m, C* r>
    assert np.sum(e * r) == pytest.approx(np.sum(m * _everett_adjoint(r)), rel=1e-12)


@pytest.mark.parametrize("step", [0.2, 0.075])
def test_from_identification_round_trip_reproduces_held_out_inputs(step):
    """Identify a known relay model from noisy Pike FORCs, project, rebuild, drive it with
    held-out input sequences (step 0.075 exercises the large-problem solver, > 2500 cells).

    For inputs on the lattice nodes every relay of a cell switches like the cell's corner
    relay, so the truth is a lattice model with non-negative masses: its Everett function lies
    in the convex cone the projection maps onto. Projection onto a closed convex set is
    non-expansive, hence over the fitted nodes the projected Everett function is at least as
    close to the truth as the noisy one (a theorem for the exact NNLS optimum, which both
    solvers reach: KKT to 1e-9). On held-out walks the projected model must beat the noisy
    identification it came from (its raw, partly negative cell masses as relays)."""
    truth = _random_relays(3000, seed=1)
    rng = np.random.default_rng(2)
    nodes = regular_grid(step, 3.0)
    clean = measure_reversal_curves(truth, nodes, nodes, convention="pike", saturation=3.0)
    noisy = ReversalCurves(
        clean.reversal_field,
        clean.fields,
        tuple(m + rng.normal(0.0, NOISE, m.size) for m in clean.moments),
        "pike",
    )
    ident = identify_from_curves(noisy, grid="native")
    exact = identify_from_curves(clean, grid="native")
    assert ident.measured is None and exact.measured is None  # every node fitted
    assert ident.cell_mass.min() < -NOISE / 2  # the raw masses are not a valid model
    proj = project_identification(ident)
    model = PreisachModel.from_identification(ident)
    assert isinstance(model, DiscretePreisachModel)
    assert np.all(model.weights >= 0) and model.weights.sum() == pytest.approx(1.0, abs=1e-12)
    assert np.all(model.alpha >= model.beta)
    np.testing.assert_array_equal(model.alpha, proj.alpha)
    # saturation half-swing of the truth is 1 (all relays inside the lattice)
    assert proj.scale == pytest.approx(1.0, abs=3 * NOISE)
    # Everett noise sigma/sqrt(2) per node; a least-squares fit leaves less
    assert proj.residual_rms < NOISE / np.sqrt(2)
    # non-expansiveness over the fitted nodes (all nodes with beta < alpha)
    a, b = np.meshgrid(ident.alpha, ident.beta, indexing="ij")
    fitted = b < a
    err_proj = (_everett_apply(proj.masses) - exact.everett)[fitted]
    err_noisy = (ident.everett - exact.everett)[fitted]
    assert np.sqrt(np.mean(err_proj**2)) <= np.sqrt(np.mean(err_noisy**2))
    # held-out walks: the lattice relays (cell corners), driven relay by relay
    physical = ident.alpha[1:, None] > ident.beta[None, :-1]
    corner_a = np.broadcast_to(ident.alpha[1:, None], physical.shape)[physical]
    corner_b = np.minimum(np.broadcast_to(ident.beta[None, 1:], physical.shape)[physical], corner_a)
    raw_masses = ident.cell_mass[physical]
    lattice_truth = exact.cell_mass[physical]
    errors, raw_errors = [], []
    for _ in range(5):
        u = _node_walk(nodes, 400, rng)
        y_true, _ = truth.apply(u)
        y_model, _ = model.apply(u)
        relays = relay_outputs(u, corner_a, corner_b)
        # the truth is the lattice model with the exact cell masses (to round-off)
        np.testing.assert_allclose(relays @ lattice_truth, y_true, rtol=0, atol=1e-12)
        errors.append(np.sqrt(np.mean((proj.scale * y_model - y_true) ** 2)))
        raw_errors.append(np.sqrt(np.mean((relays @ raw_masses - y_true) ** 2)))
    assert np.mean(errors) < np.mean(raw_errors)
    # the model is a normal operator: state round trip and continuation
    u = _node_walk(nodes, 50, rng)
    y1, st = model.apply(u[:20])
    y2, _ = model.apply(u[20:], st)
    np.testing.assert_array_equal(np.concatenate([y1, y2]), model.apply(u)[0])


def test_large_problem_solver_reaches_the_lawson_hanson_optimum():
    """Block principal pivoting (matrix-free, used above 2500 cells) against scipy's
    Lawson–Hanson NNLS on the explicit matrix: the same optimum, to the KKT tolerance."""
    rng = np.random.default_rng(5)
    shape = (30, 30)
    cells = np.tril(np.ones(shape, dtype=bool))
    truth = np.where(rng.random(shape) < 0.3, rng.random(shape), 0.0) * cells
    target = _everett_apply(truth)[:-1, :-1] + rng.normal(0.0, 0.05, (30, 30))
    rows = np.ones(target.shape, dtype=bool)

    def forward(x):
        m = np.zeros(shape)
        m[cells] = x
        return _everett_apply(m)[:-1, :-1][rows]

    def adjoint(r):
        full = np.zeros((31, 31))
        full[:-1, :-1][rows] = r
        return _everett_adjoint(full)[cells]

    n = int(cells.sum())
    mat = np.column_stack([forward(np.eye(n)[c]) for c in range(n)])
    np.testing.assert_allclose(mat.T @ target.ravel(), adjoint(target.ravel()), atol=1e-12)
    reference, _ = nnls(mat, target.ravel(), maxiter=50 * n)
    x = _block_pivoting_nnls(forward, adjoint, target.ravel(), n, None)
    assert np.count_nonzero(reference) < n  # the bound is active somewhere
    np.testing.assert_allclose(x, reference, rtol=0, atol=1e-8 * reference.max())


def test_project_identification_rejects_bad_input():
    class Bad:
        alpha = np.array([0.0, 1.0])
        beta = np.array([0.0, 1.0])
        everett = np.zeros((3, 2))

    with pytest.raises(ValueError, match="everett must have shape"):
        project_identification(Bad())
    Bad.everett = np.zeros((2, 2))
    with pytest.raises(ValueError, match="no positive mass"):
        project_identification(Bad())


# ----------------------------------------------------------------------------------------------
# arbitrary (u, y) records
# ----------------------------------------------------------------------------------------------
def test_relay_outputs_match_the_relay_operator():
    from hysteresis.relay import Relay

    rng = np.random.default_rng(3)
    u = np.cumsum(rng.normal(0, 0.4, 300))
    a = np.array([0.5, 1.0, -0.2, 0.0])
    b = np.array([-0.5, 0.3, -0.2, -1.5])
    got = relay_outputs(u, a, b)
    for k in range(a.size):
        relay = Relay(a[k], b[k])
        ref, _ = relay.apply(u, relay.initial_state(u[0]))
        np.testing.assert_array_equal(got[:, k], ref)


def test_fit_preisach_record_validates_on_held_out_part():
    truth = _random_relays(2000, seed=4)
    rng = np.random.default_rng(5)
    nodes = np.linspace(-3.0, 3.0, 25)
    u = _node_walk(nodes, 3000, rng)
    u[0] = -3.0  # start from negative saturation, as the fit assumes
    y = 0.2 + 2.0 * truth.apply(u)[0] + rng.normal(0.0, NOISE, u.size)
    fit = fit_preisach_record(u, y, nodes, train_fraction=0.7)
    assert fit.n_train == 2100 and fit.n_validation == 900
    assert fit.scale == pytest.approx(2.0, abs=0.02) and fit.offset == pytest.approx(0.2, abs=0.02)
    # noise-limited on data it never saw; on the training part the residual is the noise minus
    # what the few active relays absorb: ≈ NOISE, sampling spread ≈ NOISE/sqrt(2·2100) ≈ 1.5 %
    assert fit.validation_rms < 1.2 * NOISE
    assert fit.train_rms < 1.05 * NOISE
    u2 = _node_walk(nodes, 500, rng)
    u2[0] = -3.0
    held_out = 0.2 + 2.0 * truth.apply(u2)[0]
    assert np.sqrt(np.mean((fit.predict(u2) - held_out) ** 2)) < NOISE


def test_fit_prandtl_ishlinskii_recovers_weights_and_compensates():
    rng = np.random.default_rng(6)
    true = PrandtlIshlinskii([0.0, 0.4, 0.8, 1.2, 1.6], [0.5, 0.3, 0.2, 0.15, 0.1])
    t = np.arange(4000)
    u = 2.0 * np.sin(2 * np.pi * t / 400) * (1 + 0.5 * np.sin(2 * np.pi * t / 1700))
    y = 0.3 + true.apply(u)[0] + rng.normal(0.0, NOISE, u.size)
    fit = fit_prandtl_ishlinskii(u, y, [0.4, 0.8, 1.2, 1.6])
    np.testing.assert_allclose(fit.model.weights, true.weights, atol=5 * NOISE)
    assert fit.offset == pytest.approx(0.3, abs=5 * NOISE)
    assert fit.validation_rms < 1.1 * NOISE
    # compensation: drive the true actuator through the fitted model's exact inverse
    inverse = fit.model.inverse()
    y_ref = 1.5 * np.sin(2 * np.pi * np.arange(800) / 200)
    v = y_ref - fit.offset
    u_cmd, _ = inverse.apply(v)  # default states of operator and inverse are consistent
    achieved = 0.3 + true.apply(u_cmd)[0]
    err = np.sqrt(np.mean((achieved - y_ref)[200:] ** 2))  # after the first period
    naive = 0.3 + true.apply(y_ref / (true.weights.sum()))[0]
    err_naive = np.sqrt(np.mean((naive - y_ref)[200:] ** 2))
    assert err < 5 * NOISE and err < err_naive / 10


def test_record_fit_argument_checks():
    u = np.linspace(0, 1, 10)
    with pytest.raises(ValueError, match="same length"):
        fit_prandtl_ishlinskii(u, u[:-1], [0.1])
    with pytest.raises(ValueError, match="train_fraction"):
        fit_prandtl_ishlinskii(u, u, [0.1], train_fraction=0.0)
    with pytest.raises(ValueError, match="widths"):
        fit_prandtl_ishlinskii(u, u, [-0.1])
    with pytest.raises(ValueError, match="finite"):
        fit_preisach_record(np.r_[u[:-1], np.nan], u, [0.0, 1.0])
    with pytest.raises(ValueError, match="nodes"):
        fit_preisach_record(u, u, [1.0, 0.0])


# ----------------------------------------------------------------------------------------------
# the sparse second-difference solve of square (native-grid) problems
# ----------------------------------------------------------------------------------------------
def test_fine_grid_recovers_a_discrete_model_exactly_from_its_own_forcs():
    """A model whose relays sit on the nodes of a 160-node grid (12 720 cells: beyond the
    dense limit, so the sparse path) is recovered exactly from its own FORCs on that grid:
    Mayergoyz's second differences are its weights, to round-off, and no NNLS step is taken."""
    rng = np.random.default_rng(11)
    grid = np.linspace(-4.0, 4.0, 160)
    i, j = np.triu_indices(grid.size, k=1)  # node pairs alpha = grid[j] > beta = grid[i]
    i, j = i[i > 0], j[i > 0]  # beta = grid[0] never switches down on the grid: left out
    pick = rng.choice(i.size, 400, replace=False)
    w = rng.random(400)
    truth = PreisachModel.from_relays(grid[j[pick]], grid[i[pick]], w / w.sum())
    curves = measure_reversal_curves(truth, grid)
    ident = identify_from_curves(curves, output_range=(-1.0, 1.0), extend=True)
    proj = project_identification(ident)
    assert int(np.isfinite(ident.cell_mass).sum()) > 2500
    expected = np.zeros(proj.masses.shape)  # cell (k, l): alpha in (grid[k], grid[k + 1]]
    np.add.at(expected, (j[pick] - 1, i[pick] - 1), w / w.sum())
    np.testing.assert_allclose(proj.masses, expected, rtol=0, atol=1e-14)
    assert proj.scale == pytest.approx(1.0, abs=1e-13) and proj.residual_rms < 1e-15
    model = proj.model()
    u = _node_walk(grid, 400, rng)
    np.testing.assert_allclose(model.apply(u)[0], truth.apply(u)[0], rtol=0, atol=1e-13)


def test_sparse_solve_reaches_the_lawson_hanson_optimum_on_noisy_lattice_forcs(monkeypatch):
    """Noisy FORCs (negative exact cell masses, an active bound) of a 40-node grid: the sparse
    active-set solve (forced by lowering the dense limit) and scipy's Lawson–Hanson NNLS on the
    explicit matrix (the default below 2500 cells) find the same optimum (strictly convex: the
    square Everett map is invertible), to the KKT tolerance."""
    import hysteresis.preisach.projection as proj_mod

    grid = np.linspace(-3.0, 3.0, 40)
    curves = measure_reversal_curves(_random_relays(300, seed=8), grid)
    rng = np.random.default_rng(9)
    noisy = ReversalCurves(
        curves.reversal_field,
        curves.fields,
        tuple(m + rng.normal(0.0, 0.01, m.size) for m in curves.moments),
    )
    ident = identify_from_curves(noisy, output_range=(-1.0, 1.0), extend=True)
    reference = project_identification(ident)  # dense Lawson–Hanson
    calls = []
    real = proj_mod._second_difference_nnls
    monkeypatch.setattr(proj_mod, "_DENSE_LIMIT", 0)
    monkeypatch.setattr(proj_mod, "_second_difference_nnls", lambda *a: calls.append(1) or real(*a))
    sparse = project_identification(ident)
    assert calls == [1]
    assert np.count_nonzero(reference.masses) < np.isfinite(ident.cell_mass).sum() / 2
    assert np.nanmin(ident.cell_mass) < -0.01  # the bound is active
    np.testing.assert_allclose(sparse.masses, reference.masses, rtol=0, atol=1e-9)
    assert sparse.residual_rms == pytest.approx(reference.residual_rms, rel=1e-9)


def test_square_problem_with_unmeasured_nodes_uses_the_matrix_free_solver(monkeypatch):
    """A hole in the measured nodes makes the system non-square: no second-difference
    inverse, the block principal pivoting path instead (same optimum as Lawson–Hanson)."""
    import hysteresis.preisach.projection as proj_mod

    grid = np.linspace(-3.0, 3.0, 20)
    ident = identify_from_curves(
        measure_reversal_curves(_random_relays(100, seed=2), grid),
        output_range=(-1.0, 1.0),
        extend=True,
    )

    class Holed:
        alpha, beta, everett = ident.alpha, ident.beta, ident.everett
        measured = np.ones(ident.everett.shape, dtype=bool)

    Holed.measured[10, 3] = False
    reference = project_identification(Holed())
    monkeypatch.setattr(proj_mod, "_DENSE_LIMIT", 0)
    monkeypatch.setattr(proj_mod, "_second_difference_nnls", None)  # must not be called
    other = project_identification(Holed())
    np.testing.assert_allclose(other.masses, reference.masses, rtol=0, atol=1e-8)
