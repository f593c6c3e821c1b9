"""The 1-bit-per-spin random-field Ising lattice (hysteresis.rfim_bits) against independent truth:
the event-driven RandomFieldIsing on the same fields and edges (M equal at every grid input),
brute-force neighbour counts, scipy's normal quantile and distribution."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import special, stats

from hysteresis import _rfim_bits_kernels as kern
from hysteresis.rfim import RandomFieldIsing
from hysteresis.rfim_bits import (
    BitLattice,
    _cut,
    bit_lattice_loop,
    pack_spins,
    random_fields,
    unpack_spins,
)

#: a loop with minor loops: up, back down part way, up again past it, then all the way down
LOOP = np.concatenate(
    [
        np.linspace(-12.0, 1.0, 40),
        np.linspace(1.0, -1.5, 12),
        np.linspace(-1.5, 2.5, 15),
        np.linspace(2.5, 0.5, 8),
        np.linspace(0.5, 12.0, 30),
        np.linspace(12.0, -0.5, 45),
        np.linspace(-0.5, 0.7, 7),
        np.linspace(0.7, -12.0, 40),
    ]
)


#: the two-thread (prange) scan: compiling it costs ~40 s of a fresh machine's default suite,
#: so its cases run with ``-m slow`` (with the 64³ comparison of both thread settings)
SLOW_PARALLEL = pytest.mark.slow


def brute_up_counts(spins: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    up = (spins > 0).reshape(shape).astype(np.int64)
    total = sum(np.roll(up, s, axis=a) for a in range(len(shape)) for s in (1, -1))
    return total.ravel()


@pytest.mark.parametrize(
    ("shape", "disorder", "coupling", "seed", "threads"),
    [
        ((200,), 0.8, 1.0, 1, 1),  # 1-D, L2 >= 64: bit-sliced counts
        ((40,), 1.2, 0.5, 2, 1),  # 1-D, L2 < 64: per-spin counts
        ((12, 12), 1.5, 1.0, 3, 1),
        ((5, 70), 1.0, 1.0, 4, 1),  # a word spans two rows
        ((8, 8, 8), 2.0, 1.0, 5, 1),
        ((8, 8, 8), 1.2, 1.0, 6, 1),  # below R_c: system-spanning avalanches
        # the same through the parallel scan
        pytest.param((40,), 1.2, 0.5, 2, 2, marks=SLOW_PARALLEL),
        pytest.param((5, 70), 1.0, 1.0, 4, 2, marks=SLOW_PARALLEL),
        pytest.param((8, 8, 8), 1.2, 1.0, 6, 2, marks=SLOW_PARALLEL),
        ((3, 4, 70), 1.6, 1.0, 7, 1),
        ((4, 3, 130), 2.6, 0.5, 8, 1),
    ],
)
def test_magnetization_equals_event_driven_model(shape, disorder, coupling, seed, threads):
    # J = 1 or 0.5: J·n is exact, so both models form the same floats f + J·n
    loop = bit_lattice_loop(shape, disorder, LOOP, coupling, seed, threads)
    lattice = BitLattice(shape, disorder, coupling, seed)
    model = RandomFieldIsing(lattice.fields(), lattice.edges(), coupling)
    ref, final = model.apply(LOOP, model.initial_state(float(LOOP[0])))
    assert np.array_equal(loop.magnetization, ref)
    assert loop.flips.sum() > 0 and np.all(loop.largest <= loop.flips)
    for u in LOOP:
        lattice.relax(float(u))
    assert np.array_equal(lattice.spins(), model.spins(final))
    assert lattice.magnetization == model.output(final)


@SLOW_PARALLEL
def test_serial_and_parallel_scans_agree_on_everything():
    inputs = np.concatenate([np.linspace(-9.0, 9.0, 30), np.linspace(9.0, -9.0, 30)])
    one = bit_lattice_loop((6, 7, 150), 2.2, inputs, 1.0, 11, threads=1)
    two = bit_lattice_loop((6, 7, 150), 2.2, inputs, 1.0, 11, threads=2)
    for name in ("magnetization", "flips", "avalanches", "largest"):
        assert np.array_equal(getattr(one, name), getattr(two, name)), name


def test_every_spin_flips_twice_on_a_saturating_loop():
    far = 8.5 * 2.0 + 6 + 1  # |Φ⁻¹(U)| <= 8.3 for every U of the generator
    loop = bit_lattice_loop((6, 6, 6), 2.0, [-far, far, -far], 1.0, 0)
    assert loop.magnetization.tolist() == [-1.0, 1.0, -1.0]
    assert loop.flips.tolist() == [0, 216, 216]


def test_state_is_stable_after_every_step():
    lattice = BitLattice((5, 6, 80), 1.8, 1.0, 9)
    f = lattice.fields()
    jn = lambda s: 2 * brute_up_counts(s, lattice.shape) - 6  # noqa: E731
    for u in (-3.0, 0.5, 0.2, 2.0, -0.4):
        lattice.relax(u)
        s = lattice.spins()
        h = u + (f + 1.0 * jn(s))
        assert np.all((s > 0) == (h >= 0.0))


@pytest.mark.parametrize("shape", [(300,), (64,), (7, 65), (3, 5, 200), (4, 4, 100), (3, 3, 127)])
def test_bit_sliced_and_per_spin_counts_equal_brute_force(shape):
    rng = np.random.default_rng(0)
    dims = np.array((1,) * (3 - len(shape)) + shape, dtype=np.int64)
    n = math.prod(shape)
    for p_up in (0.5, 0.9, 0.05):
        s = rng.choice([-1, 1], size=n, p=[1 - p_up, p_up])
        words = pack_spins(s)
        per_spin, sliced = np.zeros(n, np.int64), np.zeros(n, np.int64)
        kern.count_up(words, dims, per_spin)
        kern.up_counts_bitsliced(words, dims, sliced)
        truth = brute_up_counts(s, shape)
        assert np.array_equal(per_spin, truth)
        assert np.array_equal(sliced, truth)


def test_pack_round_trip_and_numpy_layout():
    rng = np.random.default_rng(1)
    for n in (1, 63, 64, 65, 1000):
        s = rng.choice(np.array([-1, 1], dtype=np.int8), size=n)
        words = pack_spins(s)
        assert words.dtype == np.uint64 and words.size == (n + 63) // 64
        assert np.array_equal(unpack_spins(words, n), s)
        # spin i is bit i & 63 of word i >> 6
        i = np.arange(n)
        assert np.array_equal((words[i >> 6] >> (i & 63).astype(np.uint64)) & 1, s > 0)


def test_quantile_matches_scipy_to_1e15():
    p = np.concatenate([np.linspace(1e-9, 1 - 1e-9, 20001), np.logspace(-300, -1, 600)])
    p = np.concatenate([p, 1 - p[(p < 1e-3) & (p > 1e-15)]])
    x = np.array([kern.ppnd16(v) for v in p])
    err = np.abs(x - special.ndtri(p)) / np.maximum(1.0, np.abs(special.ndtri(p)))
    assert err.max() < 5e-15


def test_fields_are_standard_normal():
    # KS and moments of 10⁶ draws: the thresholds are many standard errors wide at this size
    n = 10**6
    x = random_fields(0, n, 1.0, seed=12345)
    assert stats.kstest(x, "norm").pvalue > 1e-3
    se = 1 / math.sqrt(n)
    assert abs(x.mean()) < 5 * se
    assert abs(x.var() - 1) < 5 * math.sqrt(2) * se
    assert abs(stats.skew(x)) < 5 * math.sqrt(6) * se
    assert abs(stats.kurtosis(x)) < 5 * math.sqrt(24) * se
    # neighbours along the counter are uncorrelated
    assert abs(np.corrcoef(x[:-1], x[1:])[0, 1]) < 5 * se


def test_fields_reproducible_by_range_and_seed():
    a = random_fields(0, 1000, 2.0, seed=7)
    assert np.array_equal(a, random_fields(0, 1000, 2.0, seed=7))
    assert np.array_equal(a[300:700], random_fields(300, 700, 2.0, seed=7))
    assert np.array_equal(a, 2.0 * random_fields(0, 1000, 1.0, seed=7))
    b = random_fields(0, 1000, 2.0, seed=8)
    assert not np.any(a == b)
    assert abs(np.corrcoef(a, b)[0, 1]) < 5 / math.sqrt(1000)
    assert np.array_equal(BitLattice(10, 2.0, seed=7).fields(), a[:10])


def test_hash_cut_is_conservative_at_the_boundary():
    # rising: m < cut ⟹ U < Φ(x); falling: m > cut ⟹ U > Φ(x), checked at the cut itself
    for x in (-8.0, -3.3, -1e-3, 0.0, 0.4, 2.5, 7.9):
        phi = special.ndtr(x)
        up = _cut(x, True)
        if up > 0:
            assert (up - 1 + 0.5) * 2.0**-52 < phi
        down = _cut(x, False)
        if down < 2**52 - 1:
            assert (down + 1 + 0.5) * 2.0**-52 > phi


def test_zero_disorder_and_zero_coupling():
    # R = 0: every spin flips at u = J·z (all down) — one step; J = 0: independent spins
    loop = bit_lattice_loop((10, 10), 0.0, [3.9, 4.0, -4.0, -4.01], 1.0, 0)
    assert loop.magnetization.tolist() == [-1.0, 1.0, 1.0, -1.0]
    f = random_fields(0, 1000, 1.5, 3)
    m = bit_lattice_loop((10, 100), 1.5, [-0.3], 0.0, 3).magnetization[0]
    assert m == (2 * np.count_nonzero(f >= 0.3) - 1000) / 1000


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda: BitLattice((2, 5), 1.0, seed=0), "shape"),
        (lambda: BitLattice((5, 5, 5, 5), 1.0, seed=0), "shape"),
        (lambda: BitLattice((2000, 2000, 1000), 1.0, seed=0), "shape"),
        (lambda: BitLattice(10, -1.0, seed=0), "disorder"),
        (lambda: BitLattice(10, 1.0, spin_coupling=-0.5, seed=0), "spin_coupling"),
        (lambda: BitLattice(10, 1.0, seed=-1), "seed"),
        (lambda: BitLattice(10, 1.0, seed=2**64), "seed"),
        (lambda: BitLattice(10, 1.0, seed=0, threads=0), "threads"),
        (lambda: BitLattice(10, 1.0, seed=0).relax(math.nan), "u"),
        (lambda: bit_lattice_loop(10, 1.0, [], seed=0), "inputs"),
        (lambda: random_fields(5, 3, seed=0), "start"),
        (lambda: pack_spins([1, 0, -1]), "spins"),
        (lambda: unpack_spins(np.zeros(2, np.uint64), 200), "n_spins"),
    ],
)
def test_bad_input_raises_one_line_error_naming_the_parameter(call, name):
    with pytest.raises(ValueError) as info:
        call()
    message = str(info.value)
    assert name in message and "\n" not in message


def test_a_random_lattice_names_its_seed():
    for call in (
        lambda: BitLattice(10, 1.0),
        lambda: random_fields(0, 5),
        lambda: bit_lattice_loop(10, 1.0, [0.0]),
    ):
        with pytest.raises(TypeError, match="seed"):
            call()


@pytest.mark.slow
def test_large_lattice_loop_matches_event_driven_model():
    # 64³ (262 144 spins) near R_c: a longer loop, both scan paths
    inputs = np.concatenate([np.linspace(-10, 10, 120), np.linspace(10, -10, 120)])
    lattice = BitLattice((64, 64, 64), 2.2, 1.0, 21)
    model = RandomFieldIsing(lattice.fields(), lattice.edges(), 1.0)
    ref, _ = model.apply(inputs, model.initial_state(float(inputs[0])))
    for threads in (1, 2):
        loop = bit_lattice_loop((64, 64, 64), 2.2, inputs, 1.0, 21, threads)
        assert np.array_equal(loop.magnetization, ref)
