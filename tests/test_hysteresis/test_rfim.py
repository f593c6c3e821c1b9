"""The random-field Ising model (hysteresis.rfim) against independent truth: brute-force
relaxation written here from the Hamiltonian (every unstable spin flipped until none is left),
the spin dimers, the plain-Python reference of the kernels, and the model's own laws
(return-point memory, no-passing, avalanche sizes adding up to N, the 3-D disorder-induced
transition)."""

from __future__ import annotations

import math
import pickle
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

from hysteresis import SpinDimerEnsemble
from hysteresis._rfim_kernels import reference_sweep
from hysteresis.rfim import RandomFieldIsing, RandomFieldIsingState


# -- the brute force, from the Hamiltonian only ---------------------------------------------------
def neighbour_sums(edges, spins):
    """n_i = Σ_{j ~ i} s_j (integers)."""
    n = np.zeros(spins.size, dtype=np.int64)
    np.add.at(n, edges[:, 0], spins[edges[:, 1]])
    np.add.at(n, edges[:, 1], spins[edges[:, 0]])
    return n


def relax(spins, u, fields, edges, J):
    """Flip every spin that points against h_i = u + (f_i + J n_i) (h = 0 counts as up) until
    none does. From a state stable at an earlier input all unstable spins want the same way, so
    flipping them together is a valid order (the final state does not depend on the order)."""
    s = spins.copy()
    while True:
        h = u + (fields + J * neighbour_sums(edges, s))
        bad = (h >= 0.0) != (s > 0)
        if not bad.any():
            return s
        s[bad] = -s[bad]


def brute_history(model, inputs, spins=None):
    """M after relaxing at each input, from all spins down relaxed at inputs[0] (or ``spins``)."""
    e, f, J = model.edges(), np.asarray(model.fields), model.spin_coupling
    s = -np.ones(model.n_spins, dtype=np.int64) if spins is None else np.array(spins, np.int64)
    out = []
    for u in inputs:
        s = relax(s, float(u), f, e, J)
        out.append((2 * int(np.sum(s > 0)) - s.size) / s.size)
    return np.array(out), s


def brute_thresholds(model, spins):
    """(greatest threshold −(f + J n) of an up spin, least of a down spin)."""
    t = -(np.asarray(model.fields) + model.spin_coupling * neighbour_sums(model.edges(), spins))
    down, up = spins < 0, spins > 0
    return (t[up].max() if up.any() else -math.inf, t[down].min() if down.any() else math.inf)


def wandering_inputs(rng, n, scale=3.0):
    """A non-monotone input sequence (a random walk with reversals of every size)."""
    return np.cumsum(rng.normal(0.0, scale / 4, size=n)) % (2 * scale) - scale


def random_graph(n, n_edges, rng):
    pairs = {tuple(sorted(p)) for p in rng.integers(0, n, size=(n_edges, 2)) if p[0] != p[1]}
    return np.array(sorted(pairs), dtype=np.int64)


MODELS = {
    "chain": lambda: RandomFieldIsing.lattice(40, 1.0, seed=3),
    "square": lambda: RandomFieldIsing.lattice((7, 9), 1.4, seed=4),
    "cubic": lambda: RandomFieldIsing.lattice((5, 4, 6), 2.0, seed=5),
    "cubic_low_disorder": lambda: RandomFieldIsing.lattice((6, 6, 6), 1.2, 1.0, seed=6),
    "graph": lambda: RandomFieldIsing(
        np.random.default_rng(7).normal(0, 1.5, 80),
        random_graph(80, 160, np.random.default_rng(8)),
        0.7,
    ),
}


# -- relaxation -----------------------------------------------------------------------------------
@pytest.mark.parametrize("name", MODELS)
def test_outputs_and_spins_equal_the_brute_force_relaxation(name):
    model = MODELS[name]()
    u = wandering_inputs(np.random.default_rng(11), 300, scale=4.0)
    y, state = model.apply(u)
    y_ref, s_ref = brute_history(model, u)
    np.testing.assert_array_equal(y, y_ref)
    np.testing.assert_array_equal(model.spins(state), s_ref)
    # one input at a time continues the same history
    s = model.initial_state(float(u[0]))
    for k in range(1, 60):
        yk, s = model.apply([u[k]], s)
        assert yk[0] == y[k]


@pytest.mark.parametrize("name", MODELS)
def test_the_kernel_equals_the_plain_python_reference(name):
    """Outputs, spins and every avalanche (trigger input, size) of the compiled sweep equal
    the heap-based plain-Python reference path."""
    model = MODELS[name]()
    nb = [[] for _ in range(model.n_spins)]
    for i, j in model.edges():
        nb[i].append(j)
        nb[j].append(i)
    u = wandering_inputs(np.random.default_rng(12), 200, scale=4.0)
    start = model.apply([-3.0, 1.0, -0.5])[1]
    triggers, sizes, final = model.avalanches(u, start)
    y, _ = model.apply(u, start)
    y_ref, s_ref, events = reference_sweep(
        model.spins(start), start.input, u, np.asarray(model.fields), nb, model.spin_coupling
    )
    np.testing.assert_array_equal(y, y_ref)
    np.testing.assert_array_equal(model.spins(final), s_ref)
    np.testing.assert_array_equal(triggers, [e[0] for e in events])
    np.testing.assert_array_equal(sizes, [e[1] for e in events])


def test_initial_state_is_all_down_relaxed_at_u0():
    model = MODELS["cubic_low_disorder"]()
    for u0 in (-20.0, -2.0, -0.3, 0.0, 5.0):
        state = model.initial_state(u0)
        _, s_ref = brute_history(model, [u0])
        np.testing.assert_array_equal(model.spins(state), s_ref)
        assert state.input == u0 and model.output(state) == np.mean(s_ref)
    assert model.output(model.initial_state(-20.0)) == -1.0
    # an input above the lowest trigger starts an avalanche
    low = model.initial_state(-20.0)
    upper = model.switching(low).upper
    assert model.output(model.apply([upper], low)[1]) > -1.0
    assert model.output(model.apply([math.nextafter(upper, -math.inf)], low)[1]) == -1.0


def test_pairs_graph_is_the_spin_dimer_ensemble():
    """Edges (2k, 2k+1) with the dimers' fields (b1, b2) and J: the same thresholds α = J − b1,
    β = −J − b2, so the same outputs as the dimers' brute-force spin flips (exactly) and as their
    Preisach picture, and the same next switching inputs."""
    ens = SpinDimerEnsemble.random(400, width=1.2, spread=1.0, spin_coupling=1.5, seed=21)
    # non-hysteretic dimers too (b1 − b2 > 2J: two reversible single flips)
    mixed = np.vstack([ens.fields, [[3.0, -2.5], [0.4, -2.6], [1.0, 1.0]]])
    ens = SpinDimerEnsemble(mixed, spin_coupling=1.5)
    pairs = np.arange(ens.n_spins).reshape(-1, 2)
    model = RandomFieldIsing(ens.fields.reshape(-1), pairs, 1.5)
    u = wandering_inputs(np.random.default_rng(22), 500, scale=5.0)
    y, state = model.apply(u)
    y_spins, spins = ens.simulate(u)
    np.testing.assert_array_equal(y, y_spins)
    np.testing.assert_array_equal(model.spins(state), spins)
    y_relays, pstate = ens.apply(u)
    np.testing.assert_allclose(y, y_relays, rtol=0, atol=1e-14)
    for k in (50, 51, 300, 499):
        s_model = model.apply(u[: k + 1])[1]
        s_ens = ens.apply(u[: k + 1])[1]
        a, b = model.switching(s_model), ens.switching(s_ens)
        assert (a.lower, a.upper) == (b.lower, b.upper)
        assert a.jump_up == pytest.approx(b.jump_up, abs=1e-14)
        assert a.jump_down == pytest.approx(b.jump_down, abs=1e-14)


# -- laws of the model ----------------------------------------------------------------------------
def test_return_point_memory():
    """After a sub-loop inside [a, b] the spins return exactly to the state they had at the
    turning point b (Sethna et al. 1993): every spin, not only M."""
    model = MODELS["cubic_low_disorder"]()
    rng = np.random.default_rng(31)
    state = model.apply([-6.0, 2.0, -1.5])[1]  # some history
    for a, b in ((-1.5, 0.8), (-1.0, 0.3)):
        at_b = model.apply([b], model.apply([a], state)[1])[1]
        inner = rng.uniform(a, b, size=50)
        back = model.apply([*inner, b], at_b)[1]
        np.testing.assert_array_equal(model.spins(back), model.spins(at_b))
        # falling turning point: a reached from b, a sub-loop inside, back to a
        at_a = model.apply([a], at_b)[1]
        back = model.apply([*rng.uniform(a, b, size=50), a], at_a)[1]
        np.testing.assert_array_equal(model.spins(back), model.spins(at_a))


def test_no_passing():
    """Two states ordered spin by spin stay ordered under the same input history."""
    model = MODELS["cubic"]()
    lower = model.initial_state(0.2)  # from below
    upper = model.apply([20.0, 0.2])[1]  # from above
    s_low, s_up = model.spins(lower), model.spins(upper)
    assert np.all(s_low <= s_up) and np.any(s_low < s_up)
    for u in wandering_inputs(np.random.default_rng(32), 150, scale=4.0):
        lower, upper = model.apply([u], lower)[1], model.apply([u], upper)[1]
        assert np.all(model.spins(lower) <= model.spins(upper))


@pytest.mark.parametrize("name", MODELS)
def test_avalanche_sizes_add_up_to_n_over_a_full_sweep(name):
    model = MODELS[name]()
    bottom = model.initial_state(-1e3)
    sizes, top = model.avalanche_sizes([1e3], bottom)
    assert sizes.sum() == model.n_spins and np.all(sizes > 0)
    assert model.output(top) == 1.0
    down, _ = model.avalanche_sizes([-1e3], top)
    assert down.sum() == model.n_spins
    # relaxed at its trigger: the avalanches do not depend on how finely the sweep is sampled
    fine, _ = model.avalanche_sizes(np.linspace(-1e3, 1e3, 20001)[1:], bottom)
    np.testing.assert_array_equal(fine, sizes)


def largest_avalanche(model, seed_input=-1e3):
    """The spins of the largest avalanche of a rising sweep from saturation (they flip between
    the state just below its trigger and the state at it)."""
    bottom = model.initial_state(seed_input)
    triggers, sizes, _ = model.avalanches([-seed_input], bottom)
    k = int(np.argmax(sizes))
    before = model.apply([math.nextafter(triggers[k], -math.inf)], bottom)[1]
    after = model.apply([triggers[k]], before)[1]
    flipped = model.spins(before) != model.spins(after)
    assert flipped.sum() == sizes[k]
    return flipped.reshape(model.shape)


def spans(cluster):
    """The cluster touches every plane perpendicular to some axis."""
    return any(
        np.all(cluster.any(axis=tuple(b for b in range(cluster.ndim) if b != a)))
        for a in range(cluster.ndim)
    )


def test_three_dimensional_transition_spanning_avalanche_only_below_critical_disorder():
    """R_c ≈ 2.16 (Perković, Dahmen, Sethna 1999): at R = 1.6 one avalanche flips most of a
    24³ lattice and spans it; at R = 3.5 no avalanche spans and the largest is a small fraction
    (measured: 98% and 1.0% of the spins; at this size R = 2.6 still spans, the correlation
    length exceeds L near R_c)."""
    below = largest_avalanche(RandomFieldIsing.lattice((24, 24, 24), 1.6, seed=41))
    assert spans(below) and below.mean() > 0.5
    above = largest_avalanche(RandomFieldIsing.lattice((24, 24, 24), 3.5, seed=42))
    assert not spans(above) and above.mean() < 0.05


# -- the switching contract -----------------------------------------------------------------------
@pytest.mark.parametrize("name", MODELS)
def test_switching_against_brute_force_thresholds_and_apply(name):
    model = MODELS[name]()
    u = wandering_inputs(np.random.default_rng(51), 40, scale=4.0)
    state = model.initial_state(float(u[0]))
    for x in u[1:]:
        state = model.apply([x], state)[1]
        sw = model.switching(state)
        assert (sw.lower, sw.upper) == brute_thresholds(model, model.spins(state))
        assert sw.lower <= state.input < sw.upper
        m = model.output(state)
        if math.isfinite(sw.upper):
            assert model.output(model.apply([sw.upper], state)[1]) - m == sw.jump_up > 0
            below = math.nextafter(sw.upper, -math.inf)
            assert model.output(model.apply([below], state)[1]) == m
        if math.isfinite(sw.lower):
            below = math.nextafter(sw.lower, -math.inf)
            assert model.output(model.apply([below], state)[1]) - m == sw.jump_down < 0
            assert model.output(model.apply([sw.lower], state)[1]) == m


# -- states, validation, memory -------------------------------------------------------------------
def test_states_are_immutable_compact_and_owned():
    model = RandomFieldIsing.lattice((10, 10, 10), 2.0, seed=61)
    state = model.initial_state(0.1)
    assert isinstance(state, RandomFieldIsingState) and state.nbytes == 125  # 1 bit per spin
    with pytest.raises(ValueError):
        state.bits[0] = 1
    y, after = model.apply([0.5, -0.2], state)
    assert model.output(state) == model.apply([0.1], model.initial_state(0.1))[0][0]
    # fields 8 + sorted fields 8 + order 4 + workspace 5.1 bytes per spin (issue: <= 40)
    assert model.nbytes <= 25.2 * model.n_spins + 200
    other = RandomFieldIsing.lattice((10, 10, 10), 2.0, seed=62)
    with pytest.raises(ValueError, match="another random-field Ising model"):
        other.apply([0.0], state)
    with pytest.raises(TypeError, match="state must be a RandomFieldIsingState"):
        model.output(0.3)
    copy = pickle.loads(pickle.dumps(model))
    np.testing.assert_array_equal(copy.apply([0.5, -0.2], state)[0], y)
    rebuilt = model.state(model.spins(after), -0.2)
    assert model.output(rebuilt) == model.output(after)
    with pytest.raises(ValueError, match="stable at input"):
        model.state(-model.spins(after), -0.2)


def test_the_cached_workspace_follows_any_state_and_any_thread():
    """The workspace (spins, up-neighbour counts) is rebuilt whenever a call starts from another
    state than the last one returned, and a lock keeps threads apart: calls interleaved over
    states and threads give the serial answers."""
    model = MODELS["cubic"]()
    rng = np.random.default_rng(71)
    starts = [model.apply([x])[1] for x in (-2.0, -0.5, 0.0, 0.7)]
    runs = [(starts[k % 4], wandering_inputs(rng, 80)) for k in range(16)]
    serial = [model.apply(u, s)[0] for s, u in runs]
    for (s, u), y in zip(runs, serial, strict=True):  # interleaved with switching on others
        model.switching(starts[0])
        np.testing.assert_array_equal(model.apply(u, s)[0], y)
    with ThreadPoolExecutor(4) as pool:
        threaded = list(pool.map(lambda r: model.apply(r[1], r[0])[0], runs))
    for a, b in zip(threaded, serial, strict=True):
        np.testing.assert_array_equal(a, b)


def test_pairs_graph_memory_and_lattice_edges():
    model = RandomFieldIsing.lattice((3, 4, 5), 1.0, seed=1)
    e = model.edges()
    assert e.shape == (3 * 60, 2)
    deg = np.bincount(e.ravel(), minlength=60)
    assert np.all(deg == 6) and len({tuple(sorted(p)) for p in e.tolist()}) == 180
    # the same lattice as a general graph gives the same history
    graph = RandomFieldIsing(model.fields, e, 1.0)
    u = wandering_inputs(np.random.default_rng(2), 100)
    np.testing.assert_array_equal(graph.apply(u)[0], model.apply(u)[0])
    np.testing.assert_array_equal(np.sort(graph.edges(), axis=0), np.sort(np.sort(e, 1), axis=0))


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: RandomFieldIsing([0.0, 1.0], [[0, 2]], 1.0), r"spin indices in \[0, 1\]"),
        (lambda: RandomFieldIsing([0.0, 1.0], [[1, 1]], 1.0), "self-loop"),
        (lambda: RandomFieldIsing([0.0, 1.0], [[0, 1], [1, 0]], 1.0), "each undirected pair once"),
        (lambda: RandomFieldIsing([0.0, 1.0], [[0.0, 1.0]], 1.0), "integer spin indices"),
        (lambda: RandomFieldIsing([0.0, 1.0], [0, 1], 1.0), r"shape \(E, 2\)"),
        (lambda: RandomFieldIsing([0.0, np.nan], [[0, 1]], 1.0), "fields must be finite"),
        (lambda: RandomFieldIsing([0.0, 1.0], [[0, 1]], -0.5), "ferromagnetic"),
        (lambda: RandomFieldIsing.lattice((4, 2), 1.0, seed=0), "integers >= 3"),
        (lambda: RandomFieldIsing.lattice((3, 3, 3, 3), 1.0, seed=0), "1 to 3 integers"),
        (lambda: RandomFieldIsing.lattice((4, 4), -1.0, seed=0), "disorder must be >= 0"),
        (lambda: RandomFieldIsing.lattice((4, 4), 1.0, seed=None), "seed is required"),
        (lambda: RandomFieldIsing.lattice((4, 4), 1.0), "missing required argument seed"),
        (lambda: RandomFieldIsing.lattice((5000, 5000, 5000), 1.0, seed=0), "limit"),
    ],
)
def test_bad_input_is_refused_in_one_sentence(call, message):
    with pytest.raises((ValueError, TypeError), match=message):
        call()


def test_independent_spins_and_zero_coupling():
    """No edges or J = 0: every spin is a zero-width relay at −f_i."""
    f = np.array([0.5, -1.0, 2.0, 0.0])
    for model in (RandomFieldIsing(f, np.zeros((0, 2), int), 1.0),
                  RandomFieldIsing(f, [[0, 1], [2, 3]], 0.0)):  # fmt: skip
        y, _ = model.apply([-3.0, -0.5, 0.0, 1.0, -1.5, 3.0])
        np.testing.assert_array_equal(y, [-1.0, 0.0, 0.5, 1.0, -0.5, 1.0])  # thresholds −f_i


@pytest.mark.parametrize(
    "model",
    [
        RandomFieldIsing.lattice((16, 16, 16), 2.16, seed=81),  # near R_c: large avalanches
        RandomFieldIsing.lattice((64, 64), 0.9, seed=82),
        RandomFieldIsing(
            np.random.default_rng(83).normal(0, 3.0, 2000),
            random_graph(2000, 12000, np.random.default_rng(84)),  # degrees up to ~25
            1.0,
        ),
    ],
    ids=["cubic_critical", "square_large", "dense_graph"],
)
def test_long_histories_equal_the_brute_force(model):
    """1500 reversals of every size near the 3-D critical disorder, on a large square lattice
    and on a graph with degrees up to ~25 (more lists than a lattice has)."""
    u = wandering_inputs(np.random.default_rng(85), 1500, scale=6.0)
    y, state = model.apply(u)
    y_ref, s_ref = brute_history(model, u)
    np.testing.assert_array_equal(y, y_ref)
    np.testing.assert_array_equal(model.spins(state), s_ref)
