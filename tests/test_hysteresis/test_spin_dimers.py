"""Spin dimers: paper Table I / Fig. elem_hys_ex, the N = 4 example, brute-force metastability
from the Hamiltonian, and the equivalence with a relay system."""

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hysteresis import Relay, SpinDimerEnsemble


def hamiltonian(spins, q, fields, J):
    """H = Σ_k [-J σ1σ2 - σ1(q+b1) - σ2(q+b2)], written out independently of the package."""
    s = np.asarray(spins, dtype=float).reshape(-1, 2)
    b = np.asarray(fields, dtype=float).reshape(-1, 2)
    return float(np.sum(-J * s[:, 0] * s[:, 1] - s[:, 0] * (q + b[:, 0]) - s[:, 1] * (q + b[:, 1])))


def relaxed_path(ens, inputs):
    """Spins after relaxing at each input, one call per input (continuing the spins)."""
    spins, states = None, []
    for q in inputs:
        _, spins = ens.simulate([q], spins)
        states.append(spins.copy())
    return states


def test_table_one_hysteretic_dimer():
    """J = 2, b = (2, 1): alpha = 0, beta = -3, width 3 (paper Fig. elem_hys_ex)."""
    ens = SpinDimerEnsemble([[2.0, 1.0]], spin_coupling=2.0)
    th = ens.thresholds()
    assert th.alpha.tolist() == [0.0] and th.beta.tolist() == [-3.0]
    assert th.width.tolist() == [3.0] and th.hysteretic.tolist() == [True]
    q = [-5.0, -1.5, -0.001, 0.0, -1.5, -3.0, -3.001, -1.0]
    m, _ = ens.simulate(q)
    np.testing.assert_array_equal(m, [-1, -1, -1, 1, 1, 1, -1, -1])
    # energies: ↑↑ becomes the ground state at q = -1.5 already, but is not reachable by one flip
    b = [2.0, 1.0]
    assert hamiltonian([1, 1], -1.5, b, 2.0) == pytest.approx(hamiltonian([-1, -1], -1.5, b, 2.0))
    assert hamiltonian([1, -1], 0.0, b, 2.0) == pytest.approx(hamiltonian([-1, -1], 0.0, b, 2.0))
    # ↓↑ always lies above ↑↓ (b1 > b2)
    for qq in np.linspace(-6, 6, 25):
        assert hamiltonian([-1, 1], qq, b, 2.0) > hamiltonian([1, -1], qq, b, 2.0)


def test_table_one_non_hysteretic_dimer():
    """b1 - b2 > 2J: reversible single flips, first spin at J - b1, second at -J - b2."""
    J, b1, b2 = 1.0, 2.0, -1.5
    ens = SpinDimerEnsemble([[b1, b2]], spin_coupling=J)
    th = ens.thresholds()
    assert (th.alpha[0], th.beta[0]) == (J - b1, -J - b2) == (-1.0, 0.5)
    assert not th.hysteretic[0] and not th.paired[0]
    q = np.array([-3.0, -1.0, 0.0, 0.5, 2.0, 0.5, 0.499, -0.999, -1.0, -1.001])
    states = relaxed_path(ens, q)
    expected = [
        (-1, -1),
        (1, -1),
        (1, -1),
        (1, 1),
        (1, 1),
        (1, 1),
        (1, -1),
        (1, -1),
        (1, -1),
        (-1, -1),
    ]
    assert [tuple(s.tolist()) for s in states] == expected
    alpha, beta, weights = ens.relays()
    np.testing.assert_array_equal(alpha, [-1.0, 0.5])
    np.testing.assert_array_equal(beta, [-1.0, 0.5])
    np.testing.assert_array_equal(weights, [0.5, 0.5])


def test_border_case_single_jump():
    ens = SpinDimerEnsemble([[2.0, -2.0]], spin_coupling=2.0)  # b1 - b2 = 2J
    th = ens.thresholds()
    assert th.alpha[0] == th.beta[0] == 0.0 and th.paired[0] and not th.hysteretic[0]
    m, _ = ens.simulate([-1.0, 0.0, -1e-12, 0.0])
    np.testing.assert_array_equal(m, [-1, 1, -1, 1])  # both spins together, at 0 exactly
    assert ens.relays()[2].tolist() == [1.0]


def test_paper_example_four_spins():
    ens = SpinDimerEnsemble([[2.0, 0.0], [-0.5, -2.5]], spin_coupling=2.0)
    th = ens.thresholds()
    np.testing.assert_array_equal(th.alpha, [0.0, 2.5])
    np.testing.assert_array_equal(th.beta, [-2.0, 0.5])
    np.testing.assert_array_equal(th.width, [2.0, 2.0])
    m, _ = ens.simulate([-3.0, 0.0, 2.5, 0.5, 0.49, -2.0, -2.01])
    np.testing.assert_array_equal(m, [-1, 0, 1, 1, 0, 0, -1])


def test_fields_are_ordered_larger_first():
    ens = SpinDimerEnsemble([[1.0, 2.0], [0.0, -1.0]], spin_coupling=2.0)
    np.testing.assert_array_equal(ens.fields, [[2.0, 1.0], [0.0, -1.0]])
    assert ens.n_dimers == 2 and ens.n_spins == 4 and ens.spin_coupling == 2.0


@st.composite
def ensembles(draw):
    n = draw(st.integers(1, 6))
    fields = draw(st.lists(st.tuples(st.floats(-4, 4), st.floats(-4, 4)), min_size=n, max_size=n))
    return SpinDimerEnsemble(fields, spin_coupling=draw(st.floats(0.1, 3.0)))


inputs = st.lists(st.floats(-8, 8), min_size=1, max_size=40)


@settings(max_examples=100, deadline=None)
@given(ensembles(), inputs)
def test_metastable_states_are_local_energy_minima(ens, q):
    """After relaxation no single spin flip lowers H (checked from H directly), and the state
    (↓, ↑) never occurs for b1 >= b2."""
    for qq, spins in zip(q, relaxed_path(ens, q), strict=True):
        e0 = hamiltonian(spins, qq, ens.fields, ens.spin_coupling)
        assert ens.energy(spins, qq) == pytest.approx(e0)
        for i in range(spins.size):
            flipped = spins.copy()
            flipped[i] *= -1
            assert hamiltonian(flipped, qq, ens.fields, ens.spin_coupling) >= e0 - 1e-9
        pairs = spins.reshape(-1, 2)
        assert not np.any((pairs[:, 0] == -1) & (pairs[:, 1] == 1))


@settings(max_examples=100, deadline=None)
@given(ensembles(), inputs)
def test_simulation_equals_relay_superposition(ens, q):
    """Brute-force spin dynamics == Σ weights · Relay(alpha, beta), starting from all down."""
    m, _ = ens.simulate(q)
    alpha, beta, weights = ens.relays()
    assert weights.sum() == pytest.approx(1.0)
    total = np.zeros(len(q))
    for a, b, w in zip(alpha, beta, weights, strict=True):
        relay = Relay(a, b)
        # all spins down relaxed at q[0]: the state reached by rising from -inf to q[0]
        total += w * relay.apply(q, relay.initial_state(q[0]))[0]
    np.testing.assert_allclose(m, total, atol=1e-12)


def test_random_ensemble_follows_the_paper_disorder():
    J, p, R, N = 2.0, 1.5, 0.8, 20_000
    ens = SpinDimerEnsemble.random(N, width=p, spread=R, spin_coupling=J, seed=7)
    th = ens.thresholds()
    np.testing.assert_allclose(th.width, p, atol=1e-12)  # every loop has width p
    assert th.hysteretic.all() and ens.n_spins == N
    # b_{2k-1} - b_{2k} = 2J - p, centres s_k = -(b1 + b2)/2 ~ N(0, R^2)
    np.testing.assert_allclose(ens.fields[:, 0] - ens.fields[:, 1], 2 * J - p, atol=1e-12)
    s = th.centre
    np.testing.assert_allclose(s, -(ens.fields[:, 0] + ens.fields[:, 1]) / 2, atol=1e-12)
    se = R / np.sqrt(N / 2)
    assert abs(s.mean()) < 5 * se and abs(s.std() - R) < 5 * se
    # int seed and Generator give the same realization, different seeds differ
    same = SpinDimerEnsemble.random(N, p, R, J, seed=np.random.default_rng(7))
    np.testing.assert_array_equal(same.fields, ens.fields)
    other = SpinDimerEnsemble.random(N, p, R, J, seed=8)
    assert not np.array_equal(other.fields, ens.fields)


def test_simulate_respects_given_spins_and_returns_final_state():
    ens = SpinDimerEnsemble([[2.0, 1.0]], spin_coupling=2.0)
    m, spins = ens.simulate([-1.0], spins=[1, 1])  # inside the loop, starting up: stays up
    assert m.tolist() == [1.0] and spins.tolist() == [1, 1]
    m, spins = ens.simulate([-1.0], spins=[-1, 1])  # not metastable: relaxes
    assert spins.tolist() in ([1, 1], [-1, -1])
    assert hamiltonian(spins, -1.0, [2, 1], 2.0) <= hamiltonian([-1, 1], -1.0, [2, 1], 2.0)


def test_preisach_delegation_when_available():
    ens = SpinDimerEnsemble([[2.0, 0.0], [-0.5, -2.5], [3.0, -2.0]], spin_coupling=2.0)
    try:
        model = ens.to_preisach()
    except NotImplementedError:
        pytest.skip("PreisachModel.from_relays not implemented yet")
    q = [-4.0, 0.0, 2.5, 0.5, 0.49, -2.0, 1.0, -5.0]
    out, _ = ens.apply(q)
    np.testing.assert_allclose(out, ens.simulate(q)[0], atol=1e-12)
    assert ens.to_preisach() is model
    # contract through the Preisach model: all down at -4; the first flip on rising is the
    # first spin of the non-hysteretic third dimer at J - b1 = -1 (one spin: ΔM = 2/N = 1/3)
    state = ens.initial_state(-4.0)
    assert ens.output(state) == -1.0
    sw = ens.switching(state)
    assert sw.upper == -1.0 and sw.jump_up == pytest.approx(1.0 / 3.0)


@pytest.mark.parametrize(
    "factory,name",
    [
        (lambda: SpinDimerEnsemble([[1.0, 0.0]], spin_coupling=0.0), "coupling"),
        (lambda: SpinDimerEnsemble([[1.0, 0.0]], spin_coupling=-1.0), "coupling"),
        (lambda: SpinDimerEnsemble([[1.0, np.nan]], spin_coupling=1.0), "fields"),
        (lambda: SpinDimerEnsemble([1.0, 0.0], spin_coupling=1.0), "fields"),
        (lambda: SpinDimerEnsemble(np.zeros((2, 3)), spin_coupling=1.0), "fields"),
        (lambda: SpinDimerEnsemble(np.zeros((0, 2)), spin_coupling=1.0), "fields"),
        (lambda: SpinDimerEnsemble.random(5, 1.0, 1.0, 2.0, seed=0), "n_spins"),
        (lambda: SpinDimerEnsemble.random(0, 1.0, 1.0, 2.0, seed=0), "n_spins"),
        (lambda: SpinDimerEnsemble.random(4, 4.0, 1.0, 2.0, seed=0), "width"),
        (lambda: SpinDimerEnsemble.random(4, 0.0, 1.0, 2.0, seed=0), "width"),
        (lambda: SpinDimerEnsemble.random(4, 1.0, 0.0, 2.0, seed=0), "spread"),
        (lambda: SpinDimerEnsemble.random(4, 1.0, 1.0, 0.0, seed=0), "coupling"),
        (lambda: SpinDimerEnsemble.random(4, 1.0, 1.0, 2.0, seed=-3), "seed"),
        (lambda: SpinDimerEnsemble.random(4, 1.0, 1.0, 2.0, seed=None), "seed"),
        (lambda: SpinDimerEnsemble([[1.0, 0.0]], 1.0).simulate([]), "inputs"),
        (lambda: SpinDimerEnsemble([[1.0, 0.0]], 1.0).simulate([np.inf]), "inputs"),
        (lambda: SpinDimerEnsemble([[1.0, 0.0]], 1.0).simulate([0.0], spins=[1, 0]), "spins"),
    ],
)
def test_bad_input(factory, name):
    with pytest.raises(ValueError, match=name):
        factory()


def test_random_requires_a_seed():
    """No silent fall-back to fresh entropy: the seed is a required argument."""
    with pytest.raises(TypeError, match="seed"):
        SpinDimerEnsemble.random(4, 1.0, 1.0, 2.0)


def test_all_four_states_enumerated_energetics_match_table_one():
    """Metastable configurations from H alone (every single flip raises or keeps H) reproduce
    Table I's conditions for a hysteretic dimer."""
    J, b = 2.0, (2.0, 1.0)
    for q in np.linspace(-6, 3, 37):
        meta = set()
        for s in itertools.product((-1, 1), repeat=2):
            e = hamiltonian(s, q, b, J)
            if all(
                hamiltonian([s[0] * (-1 if i == 0 else 1), s[1] * (-1 if i == 1 else 1)], q, b, J)
                >= e
                for i in range(2)
            ):
                meta.add(s)
        assert ((-1, -1) in meta) == (q <= J - b[0])
        assert ((1, 1) in meta) == (q >= -J - b[1])
        assert (-1, 1) not in meta
