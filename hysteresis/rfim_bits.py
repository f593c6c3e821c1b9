"""The random-field Ising lattice in one bit per spin, for loops of 10⁹ spins.

The model is :class:`~hysteresis.rfim.RandomFieldIsing` on a periodic hypercubic lattice (1 to 3
dimensions, site ``(x0, x1, x2)`` is spin ``(x0·L1 + x1)·L2 + x2``): spins ``s_i = ±1``, local
field ``h_i = u + f_i + J·Σ_{j ~ i} s_j``, a down spin flips up once ``h_i >= 0``, an up spin
flips down once ``h_i < 0``, every avalanche relaxed completely. What differs is the storage:

* the spins are packed bits (``uint64`` words, spin ``i`` = bit ``i & 63`` of word ``i >> 6``,
  ``1`` up): ``N/8`` bytes, 125 MB for 1000³ spins;
* the random fields are not stored: ``f_i = disorder · Φ⁻¹(U_i)`` is recomputed whenever needed
  from a stateless counter-based generator (a keyed SplitMix64 hash of ``i``, 52 bits, mapped
  to ``U_i = (m + 1/2)·2⁻⁵²``, Wichura's AS241 quantile; :mod:`hysteresis._rfim_bits_kernels`).
  :func:`random_fields` returns them for any range of sites, so that a small lattice can be
  rebuilt as a :class:`~hysteresis.rfim.RandomFieldIsing` with the same fields.

The input follows a grid ``u_0, u_1, …``: at each ``u_k`` the spins relaxed at ``u_{k−1}`` are
relaxed at ``u_k`` (a scan finds the spins the step made unstable, each starts an avalanche
relaxed depth first with an explicit stack, neighbours by periodic index arithmetic). With
``J >= 0`` relaxation is abelian and the state at ``u_k`` does not depend on how the input got
there, so the magnetization at every grid input is *exactly* the event-driven model's there
(the tests compare with :class:`~hysteresis.rfim.RandomFieldIsing` bit for bit); the avalanches
triggered between two grid inputs are merged: a step reports its flips, the avalanches its
scan started (their roots are the spins unstable right after the step) and the largest of those.

A scan hashes every spin of a word that has a spin able to flip (rising: a down spin), and
evaluates Φ⁻¹ only for the few whose hash lies beyond a conservative cut: a down spin with ``k``
up neighbours (``n = 2k − z``) can flip only if ``Φ⁻¹(U_i) >= (−u − J·n)/disorder``, a bound on
``U_i`` and so on the hash. With ``threads > 1`` the scan runs in parallel (numba ``prange``)
over chunks of 2¹⁸ spins, collecting the unstable spins, which are then flipped serially in
index order: the same spins, flips and avalanches as ``threads = 1``.

Memory: ``N/8`` bytes of spins, a candidate buffer of about 0.06 bytes per spin with
``threads > 1``, and the avalanche stack (4 bytes per spin on it, grown on demand).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Integral
from typing import Any

import numba
import numpy as np

from hysteresis import _rfim_bits_kernels as kern
from hysteresis._validation import (
    MAX_MAGNITUDE,
    ParameterTypeError,
    as_input_sequence,
    finite_scalar,
    lattice_shape,
    nonnegative_scalar,
)

__all__ = [
    "BitLattice",
    "BitLoop",
    "bit_lattice_loop",
    "pack_spins",
    "random_fields",
    "unpack_spins",
]

#: largest lattice (the avalanche stack holds int32 site indices)
MAX_BIT_SPINS = 2**31 - 1
#: spins per chunk of the parallel scan (in words of 64) and candidates a chunk may collect
_CHUNK_WORDS = 4096
_CHUNK_CAP = 4096
_MASK64 = (1 << 64) - 1
_GAMMA = 0x9E3779B97F4A7C15
_TWO52 = 2**52


def _splitmix(x: int) -> int:
    """SplitMix64's output function of ``x`` (Python ints, exact)."""
    z = x & _MASK64
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & _MASK64
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & _MASK64
    return z ^ (z >> 31)


#: no default seed: every random lattice names its seed (as RandomFieldIsing.lattice does)
_REQUIRED: Any = object()


def _seed(seed: Any) -> int:
    if seed is _REQUIRED:
        raise TypeError("missing required argument seed (an int in [0, 2**64))")
    if isinstance(seed, bool) or not isinstance(seed, Integral):
        raise ParameterTypeError(f"seed must be an int in [0, 2**64), got {seed!r}")
    if not 0 <= int(seed) < 2**64:
        raise ValueError(f"seed must be an int in [0, 2**64), got {seed}")
    return int(seed)


def _keys(seed: int) -> tuple[np.uint64, np.uint64]:
    """The generator's two keys: the first two SplitMix64 outputs of the state ``seed``."""
    k0 = _splitmix(seed + _GAMMA)
    k1 = _splitmix(seed + 2 * _GAMMA)
    return np.uint64(k0), np.uint64(k1)


def random_fields(
    start: int, stop: int, disorder: float = 1.0, seed: int = _REQUIRED
) -> np.ndarray:
    """The random fields ``f_i = disorder·Φ⁻¹(U_i)`` of sites ``start <= i < stop`` (float64),
    bit for bit the values the lattice uses; ``disorder = 1``: standard normal numbers. They are
    a function of ``(i, seed)`` alone: any range can be regenerated in any order."""
    for name, value in (("start", start), ("stop", stop)):
        if isinstance(value, bool) or not isinstance(value, Integral):
            raise ParameterTypeError(f"{name} must be an int in [0, 2**62], got {value!r}")
    if not 0 <= start <= stop <= 2**62:
        raise ValueError(f"start and stop must satisfy 0 <= start <= stop <= 2**62, got "
                         f"start={start}, stop={stop}")  # fmt: skip
    disorder = nonnegative_scalar(disorder, "disorder", MAX_MAGNITUDE)
    k0, k1 = _keys(_seed(seed))
    out = np.empty(int(stop) - int(start))
    kern.hash_fields(int(start), int(stop), k0, k1, disorder, out)
    return out


def pack_spins(spins: Any) -> np.ndarray:
    """Spins ``±1`` (site order) as ``uint64`` words: spin ``i`` is bit ``i & 63`` of word
    ``i >> 6`` (``1`` up; the words' bytes on a little-endian machine are numpy's
    ``packbits(..., bitorder="little")``, the layout of
    :class:`~hysteresis.rfim.RandomFieldIsingState`)."""
    s = np.asarray(spins)
    if s.ndim != 1 or s.dtype.kind not in "iuf" or not np.all(np.isin(s, (-1, 1))):
        raise ValueError("spins must be a 1-D array of values in {-1, +1}")
    n_words = (s.size + 63) // 64
    packed = np.zeros(8 * n_words, dtype=np.uint8)
    packed[: (s.size + 7) // 8] = np.packbits(s > 0, bitorder="little")
    return packed.view("<u8").astype(np.uint64)


def unpack_spins(words: Any, n_spins: int) -> np.ndarray:
    """The first ``n_spins`` spins of ``uint64`` ``words`` as int8 ``±1`` (inverse of
    :func:`pack_spins`)."""
    w = np.asarray(words)
    if w.dtype != np.uint64 or w.ndim != 1:
        raise ValueError(f"words must be a 1-D uint64 array, got {w.dtype} of shape {w.shape}")
    if isinstance(n_spins, bool) or not isinstance(n_spins, Integral):
        raise ParameterTypeError(f"n_spins must be an int in [0, 64·len(words)], got {n_spins!r}")
    if not 0 <= n_spins <= 64 * w.size:
        raise ValueError(f"n_spins must be an int in [0, {64 * w.size}], got {n_spins}")
    up = np.unpackbits(w.astype("<u8").view(np.uint8), count=int(n_spins), bitorder="little")
    return (2 * up.astype(np.int8) - 1).astype(np.int8)


def _shape(shape: Any) -> tuple[int, ...]:
    dims = lattice_shape(shape)
    if math.prod(dims) > MAX_BIT_SPINS:
        raise ValueError(f"shape must hold at most {MAX_BIT_SPINS} spins (2**31 - 1), got "
                         f"{math.prod(dims)} for {dims}")  # fmt: skip
    return dims


def _threads(threads: Any) -> int:
    top = numba.config.NUMBA_NUM_THREADS
    if isinstance(threads, bool) or not isinstance(threads, Integral) or not 1 <= threads <= top:
        raise ValueError(f"threads must be an int in [1, {top}] (numba's threads), got {threads!r}")
    return int(threads)


def _phi(x: float) -> tuple[float, float]:
    """``(Φ(x), 1 − Φ(x))``, each with a small relative error (erfc, no cancellation)."""
    return 0.5 * math.erfc(-x / math.sqrt(2.0)), 0.5 * math.erfc(x / math.sqrt(2.0))


def _cut(x: float, rising: bool) -> int:
    """The cut on the 52-bit hash ``m``: rising, ``m < cut`` implies ``U < Φ(x)``; falling,
    ``m > cut`` implies ``U > Φ(x)`` (``U = (m + 1/2)·2⁻⁵²``; worked out in the tests)."""
    if not math.isfinite(x):
        return 0 if x < 0 else _TWO52  # (a falling cut of 0 lets m = 0 through: still safe)
    p, q = _phi(x)
    if x <= 0.0:
        return math.floor(p * _TWO52)
    return _TWO52 - (math.ceil(q * _TWO52) if rising else math.floor(q * _TWO52))


@dataclass(frozen=True)
class BitLoop:
    """A loop of :func:`bit_lattice_loop`: at every grid input, ``magnetization``
    ``M = (2 n_up − N)/N``, ``flips`` (spins flipped by the step to it), ``avalanches`` (those
    the step's scan started, merged per step) and ``largest`` (the largest of them)."""

    inputs: np.ndarray
    magnetization: np.ndarray
    flips: np.ndarray
    avalanches: np.ndarray
    largest: np.ndarray


class BitLattice:
    """A periodic random-field Ising lattice of 1 bit per spin (module docstring), all spins down
    at ``u = −∞``; :meth:`relax` moves the input.

    Parameters
    ----------
    shape:
        1 to 3 side lengths ``>= 3``, at most ``2**31 − 1`` spins.
    disorder:
        R, the standard deviation of the random fields (``>= 0``).
    spin_coupling:
        J ``>= 0``, the ferromagnetic coupling.
    seed:
        The generator's seed, an int in ``[0, 2**64)``.
    threads:
        Threads of the scan (``1``: serial; the result does not depend on it).
    """

    def __init__(
        self,
        shape: Any,
        disorder: float,
        spin_coupling: float = 1.0,
        seed: int = _REQUIRED,
        threads: int = 1,
    ) -> None:
        self._shape = _shape(shape)
        self._disorder = nonnegative_scalar(disorder, "disorder", MAX_MAGNITUDE)
        self._j = nonnegative_scalar(spin_coupling, "spin_coupling", MAX_MAGNITUDE)
        self._seed = _seed(seed)
        self._threads = _threads(threads)
        self._k0, self._k1 = _keys(self._seed)
        self._dims = np.array((1,) * (3 - len(self._shape)) + self._shape, dtype=np.int64)
        self._n = math.prod(self._shape)
        z = 2 * len(self._shape)
        self._z = z
        self._jn = self._j * np.arange(-z, z + 1, 2, dtype=np.float64)  # J·n for k = 0 … z
        self._words = np.zeros((self._n + 63) // 64, dtype=np.uint64)
        self._stack = np.empty(1 << 16, dtype=np.int32)
        self._u = -math.inf
        self._n_up = 0
        self._buf: np.ndarray | None = None

    @property
    def n_spins(self) -> int:
        """N, the number of spins."""
        return self._n

    @property
    def shape(self) -> tuple[int, ...]:
        """The side lengths."""
        return self._shape

    @property
    def input(self) -> float:
        """The input the spins are relaxed at (``−inf`` before the first :meth:`relax`)."""
        return self._u

    @property
    def n_up(self) -> int:
        """The number of up spins."""
        return self._n_up

    @property
    def magnetization(self) -> float:
        """``M = (2 n_up − N)/N``."""
        return (2 * self._n_up - self._n) / self._n

    @property
    def words(self) -> np.ndarray:
        """The spins as ``uint64`` words (a read-only view; :func:`unpack_spins`)."""
        view = self._words.view()
        view.setflags(write=False)
        return view

    @property
    def nbytes(self) -> int:
        """Bytes held: the spins, the avalanche stack and the parallel scan's buffer."""
        buf = 0 if self._buf is None else self._buf.nbytes
        return int(self._words.nbytes + self._stack.nbytes + buf)

    def fields(self, start: int = 0, stop: int | None = None) -> np.ndarray:
        """The random fields of sites ``[start, stop)`` (:func:`random_fields`)."""
        stop = self._n if stop is None else stop
        return random_fields(start, stop, self._disorder, self._seed)

    def spins(self) -> np.ndarray:
        """The spins as int8 ``±1`` in site order (N bytes: for small lattices)."""
        return unpack_spins(self._words, self._n)

    def edges(self) -> np.ndarray:
        """The undirected neighbour pairs, ``(E, 2)`` int64 (those of
        :meth:`RandomFieldIsing.lattice <hysteresis.rfim.RandomFieldIsing.lattice>`)."""
        sites = np.arange(self._n).reshape(self._shape)
        return np.concatenate(
            [
                np.column_stack([sites.ravel(), np.roll(sites, -1, axis=a).ravel()])
                for a in range(len(self._shape))
            ]
        )

    def _cuts(self, u: float, rising: bool) -> np.ndarray:
        """Per ``k`` (up neighbours) the hash cut beyond which a spin may flip at ``u``: the
        threshold ``x = (−u − J·n)/R`` of ``Φ⁻¹(U)`` moved outwards by a margin far above the
        rounding of the float test, of ``Φ⁻¹`` (relative 1e-16) and of ``erfc``."""
        r = self._disorder
        if r == 0.0:
            return np.full(self._z + 1, 0 if rising else _TWO52, dtype=np.int64)
        out = np.empty(self._z + 1, dtype=np.int64)
        scale = (abs(u) + self._j * self._z) / r
        for k, jn in enumerate(self._jn):
            x = (-u - jn) / r
            margin = 1e-6 * (1.0 + abs(x)) + 1e-12 * scale
            out[k] = _cut(x - margin if rising else x + margin, rising)
        return out

    def relax(self, u: float) -> tuple[int, int, int]:
        """Relax the spins at input ``u`` from the state at :attr:`input` (every avalanche the
        move triggers); returns ``(flips, avalanches, largest)`` of the step."""
        u = finite_scalar(u, "u", MAX_MAGNITUDE)
        stats = np.zeros(3, dtype=np.int64)
        if u == self._u:
            return 0, 0, 0
        rising = u > self._u
        p = (self._dims, rising, u, self._cuts(u, rising), self._jn, self._k0, self._k1,
             self._disorder, 1.0 / self._dims)  # fmt: skip
        n_words = self._words.size
        if self._threads == 1:
            self._stack = kern.relax_serial(self._words, self._n, 0, n_words, p, self._stack,
                                            stats)  # fmt: skip
        else:
            chunks = (n_words + _CHUNK_WORDS - 1) // _CHUNK_WORDS
            if self._buf is None:
                self._buf = np.empty((chunks, _CHUNK_CAP), dtype=np.int32)
            counts = np.empty(chunks, dtype=np.int64)
            resume = np.empty(chunks, dtype=np.int64)
            before = numba.get_num_threads()
            numba.set_num_threads(self._threads)
            try:
                kern.collect(self._words, self._n, _CHUNK_WORDS, p, self._buf, counts, resume)
            finally:
                numba.set_num_threads(before)
            self._stack = kern.apply_candidates(self._words, self._n, _CHUNK_WORDS, p, self._buf,
                                                counts, resume, self._stack, stats)  # fmt: skip
        self._u = u
        self._n_up += int(stats[0]) if rising else -int(stats[0])
        return int(stats[0]), int(stats[1]), int(stats[2])


def bit_lattice_loop(
    shape: Any,
    disorder: float,
    inputs: Any,
    spin_coupling: float = 1.0,
    seed: int = _REQUIRED,
    threads: int = 1,
) -> BitLoop:
    """``M`` of a periodic 1-bit-per-spin random-field Ising lattice (:class:`BitLattice`, all
    spins down at ``−∞``) relaxed at each of ``inputs`` in turn (any sequence: each step from
    the state at the previous input). ``M`` at every input equals the event-driven
    :class:`~hysteresis.rfim.RandomFieldIsing`'s there, bit for bit (abelian relaxation); the
    avalanches between two inputs are merged (:class:`BitLoop`)."""
    u = as_input_sequence(inputs)
    lattice = BitLattice(shape, disorder, spin_coupling, seed, threads)
    m = np.empty(u.size)
    stats = np.zeros((u.size, 3), dtype=np.int64)
    for k, x in enumerate(u):
        stats[k] = lattice.relax(float(x))
        m[k] = lattice.magnetization
    return BitLoop(u, m, stats[:, 0].copy(), stats[:, 1].copy(), stats[:, 2].copy())
