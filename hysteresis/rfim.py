"""The zero-temperature random-field Ising model (RFIM): interacting spins with avalanches.

Ising spins ``s_i = ±1`` on a graph (any graph, or a periodic hypercubic lattice in 1–3
dimensions), random fields ``f_i``, ferromagnetic coupling ``J >= 0`` between neighbours and
the input ``u`` as the uniform external field:

    H = −J Σ_{<ij>} s_i s_j − Σ_i (u + f_i) s_i,    h_i = u + f_i + J·Σ_{j ~ i} s_j.

Zero temperature, single-spin-flip dynamics (Sethna, Dahmen, Karra, Kuntz, Roberts and
Shore 1993): a down spin flips up once ``h_i >= 0``, an up spin flips down once ``h_i < 0``
(the relay convention, as :class:`~hysteresis.spin_dimers.SpinDimerEnsemble`). A flip raises
(lowers) its neighbours' local fields and may make them flip too: an *avalanche*, relaxed
completely at the input that triggered it before the input moves on. With ``J >= 0`` the state
an avalanche ends in does not depend on the order of the flips, so the output ``M = (1/N) Σ s_i``
is a rate-independent hysteresis operator with return-point memory and no-passing; it is not a
Preisach model (its minor loops are not congruent), and below a critical disorder
(``R_c ≈ 2.16`` for Gaussian fields on the cubic lattice, ``J = 1``) one avalanche spans the
system and ``M`` jumps macroscopically.

A pairs graph (edges ``(2k, 2k+1)``) with the dimers' fields ``b1, b2`` and ``J`` is the
spin-dimer ensemble: the dimers' thresholds ``α = J − b1``, ``β = −J − b2`` are the thresholds
``−(f_i + J·n)`` of this model with ``n = ∓1``.

The operator is piecewise constant, but its jumps are avalanches, not independent relays: it is
a :class:`~hysteresis.base.SwitchingHysteron` (no relay table), coupled to the oscillator
through :meth:`RandomFieldIsing.compiled_switching` by the compiled switching engine
(:mod:`oscillators.engines.switching`), or through :meth:`RandomFieldIsing.switching` by the
relay engine's exact Python reference path (``method="generic"``).
The algorithm (sorted lists of thresholds, O(flips) per monotone sweep) is described in
:mod:`hysteresis._rfim_kernels`.

Memory: the operator holds the fields twice (in site order and sorted, 16 bytes per spin),
their sorted order (4 bytes) and, for a general graph, its compressed adjacency (8 bytes per
spin and 8 per edge); a lattice's neighbours are computed. A state holds the spins as packed
bits (1/8 byte per spin), the input and the number of up spins. What a sweep needs besides is
cached in the operator, not copied per state: a *workspace* (the spins of the last state it
saw, their up-neighbour counts and a queue of flipped spins, 5.1 bytes per spin), rebuilt in
O(N) only when a call starts from another state than the one the last call returned; a lock
keeps it to one thread at a time. In all about 25 bytes per spin.
"""

from __future__ import annotations

import hashlib
import math
import threading
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hysteresis import _rfim_kernels as kern
from hysteresis._validation import (
    MAX_MAGNITUDE,
    ParameterTypeError,
    as_generator,
    as_input_sequence,
    bounded_work,
    check_state_type,
    finite_array,
    finite_scalar,
    frozen_state_reduce,
    lattice_shape,
    nonnegative_scalar,
    readonly_array,
)
from hysteresis.base import Switching, SwitchingHysteron
from hysteresis.compiled_spins import CompiledSpins
from hysteresis.spin_dimers import MAX_SPINS

__all__ = ["RandomFieldIsing", "RandomFieldIsingState"]

#: marks the required ``seed`` of :meth:`RandomFieldIsing.lattice` (no irreproducible default)
_REQUIRED: Any = object()
#: first capacity of the avalanche record of one call (grown by 4× when full)
_EVENTS0 = 1024


@dataclass(frozen=True, eq=False)
class RandomFieldIsingState:
    """Spins of a random-field Ising model relaxed at ``input`` (immutable).

    Attributes
    ----------
    bits:
        Read-only ``uint8`` array of ``ceil(N/8)`` bytes: spin ``i`` is bit ``i % 8`` of byte
        ``i // 8`` (``1`` up, ``0`` down; :meth:`RandomFieldIsing.spins` unpacks them).
    input:
        The input the spins are relaxed at.
    n_up:
        Number of up spins (``M = (2 n_up − N)/N``).
    fingerprint:
        Digest of the model that made the state (internal): a state of another model is refused.
    """

    bits: np.ndarray
    input: float
    n_up: int
    fingerprint: int = field(repr=False)

    __reduce__ = frozen_state_reduce

    @property
    def nbytes(self) -> int:
        """Bytes of the spins (1/8 per spin)."""
        return int(self.bits.nbytes)


class _Workspace:
    """The operator's mutable copy of one state (see the module docstring): the spins, their
    up-neighbour counts and the queue of flipped spins; ``state`` is the state it equals
    (``None``: none, e.g. after an interrupted call)."""

    def __init__(self, model: RandomFieldIsing) -> None:
        n = model.n_spins
        self.bits = np.zeros((n + 7) // 8, dtype=np.uint8)
        self.nup = np.zeros(n, dtype=np.uint8 if model.max_degree < 256 else np.int32)
        self.queue = np.empty(n, dtype=np.int32)
        self.state: RandomFieldIsingState | None = None


def _ferromagnetic(coupling: Any) -> float:
    j = finite_scalar(coupling, "spin_coupling", MAX_MAGNITUDE)
    if j < 0.0:
        raise ValueError(
            f"spin_coupling must be >= 0 (ferromagnetic J), got {j}: with J < 0 the state an "
            "avalanche ends in depends on the order of the flips and return-point memory fails, "
            "so the zero-temperature dynamics is no hysteresis operator"
        )
    return j


def _check_edges(edges: Any, n: int) -> np.ndarray:
    """``edges`` as an ``(E, 2)`` int64 array of distinct undirected pairs of spins."""
    if isinstance(edges, str | bytes) or edges is None:
        raise ParameterTypeError(f"edges must be an (E, 2) array of spin indices, got {edges!r}")
    arr = np.asarray(edges)
    if arr.size == 0:
        return np.zeros((0, 2), dtype=np.int64)
    if arr.dtype.kind not in "iu":
        raise ParameterTypeError(
            f"edges must be integer spin indices (an (E, 2) int array), got dtype {arr.dtype}"
        )
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise ValueError(f"edges must have shape (E, 2) (pairs of spins), got {arr.shape}")
    arr = arr.astype(np.int64)
    if arr.min() < 0 or arr.max() >= n:
        bad = arr[(arr < 0) | (arr >= n)][0]
        raise ValueError(f"edges must hold spin indices in [0, {n - 1}] (n_spins = {n}), got {bad}")
    loops = np.flatnonzero(arr[:, 0] == arr[:, 1])
    if loops.size:
        i = int(arr[loops[0], 0])
        raise ValueError(f"edges must join two different spins, got the self-loop ({i}, {i})")
    pairs = np.sort(arr, axis=1)
    keys = pairs[:, 0] * n + pairs[:, 1]
    uniq, counts = np.unique(keys, return_counts=True)
    if uniq.size != keys.size:
        i, j = divmod(int(uniq[np.argmax(counts > 1)]), n)
        raise ValueError(f"edges must list each undirected pair once, got ({i}, {j}) twice")
    return arr


class RandomFieldIsing(SwitchingHysteron[RandomFieldIsingState]):
    """The zero-temperature random-field Ising model as a hysteresis operator (module docstring):
    output ``M = (1/N) Σ s_i``; a periodic hypercubic lattice is :meth:`lattice`.

    Parameters
    ----------
    fields:
        Random fields ``f_i``, 1-D, finite, ``|f_i| <= 1e300``; ``N = len(fields)`` spins.
    edges:
        ``(E, 2)`` integer array of undirected neighbour pairs (each pair once, no self-loops,
        indices in ``[0, N)``); ``E = 0`` gives independent spins.
    spin_coupling:
        The ferromagnetic coupling ``J >= 0`` (``coupling`` means the oscillator's C in this
        toolkit, as for :class:`~hysteresis.spin_dimers.SpinDimerEnsemble`).
    """

    def __init__(self, fields: Any, edges: Any, spin_coupling: float) -> None:
        f = finite_array(fields, "fields", ndim=1, max_abs=MAX_MAGNITUDE)
        n = bounded_work(f.size, "fields", MAX_SPINS, "spins")
        j = _ferromagnetic(spin_coupling)
        e = _check_edges(edges, n)
        ends = np.concatenate([e[:, 0], e[:, 1]])
        others = np.concatenate([e[:, 1], e[:, 0]])
        by_spin = np.argsort(ends, kind="stable")
        offsets = np.zeros(n + 1, dtype=np.int64)
        np.cumsum(np.bincount(ends, minlength=n), out=offsets[1:])
        adj = others[by_spin].astype(np.int32)
        degrees = np.diff(offsets)
        values = {v for d in np.unique(degrees).tolist() for v in range(-d, d + 1, 2)}
        self._setup(f, j, np.zeros(7, dtype=np.int64), offsets, adj, sorted(values), None)

    @classmethod
    def lattice(
        cls,
        shape: Any,
        disorder: float,
        spin_coupling: float = 1.0,
        seed: int | np.random.Generator = _REQUIRED,
    ) -> RandomFieldIsing:
        """A periodic hypercubic lattice of side lengths ``shape`` (1 to 3 integers ``>= 3``;
        site ``(x0, x1, x2)`` is spin ``(x0·L1 + x1)·L2 + x2``), each site coupled to its
        ``2d`` nearest neighbours, fields ``f_i ~ N(0, disorder²)`` drawn in site order from
        ``seed`` (required: a non-negative int or a ``numpy.random.Generator``)."""
        dims = lattice_shape(shape)
        n = bounded_work(math.prod(dims), "shape", MAX_SPINS, "spins")
        disorder = nonnegative_scalar(disorder, "disorder", MAX_MAGNITUDE)
        j = _ferromagnetic(spin_coupling)
        if seed is _REQUIRED:
            raise TypeError("missing required argument seed (int >= 0 or numpy Generator)")
        f = as_generator(seed).normal(0.0, disorder, size=n)
        lat = np.zeros(7, dtype=np.int64)
        lat[0] = len(dims)
        strides = np.cumprod((1, *dims[::-1]))[: len(dims)][::-1]
        lat[1 : 1 + len(dims)] = dims
        lat[4 : 4 + len(dims)] = strides
        z = 2 * len(dims)
        model = cls.__new__(cls)
        empty = np.zeros(0, dtype=np.int64)
        model._setup(f, j, lat, empty, empty.astype(np.int32), range(-z, z + 1, 2), dims)
        return model

    def _setup(self, f, j, lat, offsets, adj, values, shape) -> None:
        self._fields = readonly_array(f)
        self._coupling = j
        self._lat = readonly_array(lat, np.int64)
        self._offsets = readonly_array(offsets, np.int64)
        self._adj = readonly_array(adj, np.int32)
        self._nvals = readonly_array(list(values), np.int64)
        self._shape = shape
        # fields descending: along this order every threshold −(f_i + J·n) grows
        self._order = readonly_array(np.argsort(-self._fields, kind="stable"), np.int32)
        self._fsorted = readonly_array(self._fields[self._order])
        self._max_degree = (
            2 * int(lat[0]) if lat[0] > 0 else int(np.max(np.diff(offsets), initial=0))
        )
        h = hashlib.blake2b(digest_size=8)
        for part in (self._fields, self._lat, self._offsets, self._adj, np.array([j])):
            h.update(np.ascontiguousarray(part).tobytes())
        self._fingerprint = int.from_bytes(h.digest(), "little")
        self._workspace: _Workspace | None = None
        self._lock = threading.Lock()

    _transient_attributes = ("_workspace", "_lock")

    def __setstate__(self, state: Any) -> None:
        super().__setstate__(state)
        self._workspace = None
        self._lock = threading.Lock()

    # -- parameters -------------------------------------------------------------------------
    @property
    def n_spins(self) -> int:
        """N, the number of spins."""
        return int(self._fields.size)

    @property
    def n_units(self) -> int:
        """The spins (the oscillator's switch budget scales with them)."""
        return self.n_spins

    @property
    def fields(self) -> np.ndarray:
        """The random fields ``f_i`` (read-only)."""
        return self._fields

    @property
    def spin_coupling(self) -> float:
        """J, the ferromagnetic coupling of neighbouring spins."""
        return self._coupling

    @property
    def shape(self) -> tuple[int, ...] | None:
        """The lattice's side lengths, ``None`` for a general graph."""
        return self._shape

    @property
    def max_degree(self) -> int:
        """The largest number of neighbours of a spin (``2d`` on a lattice)."""
        return self._max_degree

    @property
    def nbytes(self) -> int:
        """Bytes the operator holds: fields, sorted fields and order, a graph's adjacency and
        the cached workspace (counted whether built yet or not)."""
        arrays = (self._fields, self._fsorted, self._order, self._offsets, self._adj, self._lat,
                  self._nvals)  # fmt: skip
        n = self.n_spins
        workspace = (n + 7) // 8 + n * (1 if self._max_degree < 256 else 4) + 4 * n
        return int(sum(a.nbytes for a in arrays)) + workspace

    def __repr__(self) -> str:
        where = f"lattice {self._shape}" if self._shape else f"graph of {self.n_spins} spins"
        return f"RandomFieldIsing({where}, spin_coupling={self._coupling!r})"

    def edges(self) -> np.ndarray:
        """The undirected neighbour pairs as an ``(E, 2)`` int64 array (a lattice's built on
        demand: ``(i, i + stride)`` along every axis, periodic)."""
        if self._shape is None:
            src = np.repeat(np.arange(self.n_spins), np.diff(self._offsets))
            pairs = np.column_stack([src, self._adj.astype(np.int64)])
            return pairs[pairs[:, 0] < pairs[:, 1]]
        sites = np.arange(self.n_spins).reshape(self._shape)
        return np.concatenate(
            [
                np.column_stack([sites.ravel(), np.roll(sites, -1, axis=a).ravel()])
                for a in range(len(self._shape))
            ]
        )

    # -- states -----------------------------------------------------------------------------
    def _check_state(self, state: Any) -> RandomFieldIsingState:
        check_state_type(state, RandomFieldIsingState, self)
        if state.fingerprint != self._fingerprint:
            raise ValueError(
                "state belongs to another random-field Ising model; start from this model's "
                "initial_state() or state()"
            )
        return state

    def spins(self, state: RandomFieldIsingState) -> np.ndarray:
        """The spins of ``state`` as an int8 array of ±1 (site order)."""
        state = self._check_state(state)
        up = np.unpackbits(state.bits, count=self.n_spins, bitorder="little")
        return (2 * up.astype(np.int8) - 1).astype(np.int8)

    def state(self, spins: Any, input: float) -> RandomFieldIsingState:
        """The state with ``spins`` (±1, site order) at ``input``; they must be stable there
        (every spin along its local field ``h_i``, ``h_i = 0`` counting as up)."""
        s = np.asarray(spins)
        if (
            s.dtype.kind not in "iuf"
            or s.shape != (self.n_spins,)
            or not np.all(np.isin(s, (-1, 1)))
        ):
            raise ValueError(f"spins must be an array of {self.n_spins} values in {{-1, +1}}")
        u = finite_scalar(input, "input", MAX_MAGNITUDE)
        bits = np.packbits(s > 0, bitorder="little")
        bad = kern.stable(bits, u, *self._topology())
        if bad >= 0:
            raise ValueError(
                f"spins must be stable at input {u!r}: spin {bad} points against its local field"
            )
        bits.setflags(write=False)
        return RandomFieldIsingState(bits, u, int(np.count_nonzero(s > 0)), self._fingerprint)

    def _topology(self) -> tuple:
        return (self._fields, self._coupling, self._lat, self._offsets, self._adj,
                self._max_degree)  # fmt: skip

    def _workspace_at(self, state: RandomFieldIsingState | None) -> _Workspace:
        """The workspace holding ``state`` (``None``: all spins down at −∞); rebuilt in O(N)
        unless it holds that very state object already. Call with the lock held."""
        ws = self._workspace
        if ws is None:
            ws = self._workspace = _Workspace(self)
        if state is None or ws.state is not state:
            ws.state = None
            if state is None:
                ws.bits[:] = 0
                ws.nup[:] = 0
            else:
                ws.bits[:] = state.bits
                kern.count_up_neighbours(
                    ws.bits, self._lat, self._offsets, self._adj, self._max_degree, ws.nup
                )
        return ws

    def _sweep(self, ws: _Workspace, inputs: np.ndarray, u: float, n_up: int, record: bool):
        """Follow ``inputs`` from the workspace's spins relaxed at ``u`` (modified in place):
        the outputs, ``(u, n_up)`` at the end, the flips of the last input and, with
        ``record``, the avalanches (trigger inputs, sizes)."""
        out = np.empty(inputs.size)
        cap = _EVENTS0 if record else 0
        ev_t, ev_s = np.empty(cap), np.empty(cap, dtype=np.int64)
        triggers, sizes = [], []
        k = 0
        while True:
            status, k, u, n_up, n_ev, flips = kern.sweep(
                ws.bits, ws.nup, n_up, u, inputs, k, self._fields, self._fsorted, self._order,
                self._coupling, self._nvals, self._lat, self._offsets, self._adj,
                self._max_degree, ws.queue, out, ev_t, ev_s, record,
            )  # fmt: skip
            if record:
                triggers.append(ev_t[:n_ev].copy())
                sizes.append(ev_s[:n_ev].copy())
            if status == kern.DONE:
                break
            cap *= 4
            ev_t, ev_s = np.empty(cap), np.empty(cap, dtype=np.int64)
        events = None
        if record:
            events = (np.concatenate(triggers), np.concatenate(sizes))
        return out, u, n_up, flips, events

    def _run(self, inputs: np.ndarray, state: RandomFieldIsingState | None, record: bool):
        """Outputs, final state and (with ``record``) avalanches of ``inputs`` from ``state``
        (``None``: all down at −∞); the workspace then holds the final state."""
        with self._lock:
            ws = self._workspace_at(state)
            u, n_up = (-math.inf, 0) if state is None else (state.input, state.n_up)
            ws.state = None  # modified from here on
            out, x, n_up, _, events = self._sweep(ws, inputs, u, n_up, record)
            bits = ws.bits.copy()
            bits.setflags(write=False)
            final = RandomFieldIsingState(bits, float(x), int(n_up), self._fingerprint)
            ws.state = final
        return out, final, events

    # -- the operator contract --------------------------------------------------------------
    def initial_state(self, u0: float) -> RandomFieldIsingState:
        """All spins down, relaxed at ``u0`` (the input rising from −∞: every avalanche with a
        trigger ``<= u0`` has happened)."""
        u0 = finite_scalar(u0, "u0", MAX_MAGNITUDE)
        return self._run(np.array([u0]), None, False)[1]

    def output(self, state: RandomFieldIsingState) -> float:
        """``M = (1/N) Σ s_i = (2 n_up − N)/N``."""
        state = self._check_state(state)
        n = self.n_spins
        return (2 * state.n_up - n) / n

    def apply(
        self, inputs: Any, state: RandomFieldIsingState | None = None
    ) -> tuple[np.ndarray, RandomFieldIsingState]:
        """``M`` after each input, every avalanche relaxed at the input that triggers it (the
        new state's spins are copied once per call: ``N/8`` bytes)."""
        u = as_input_sequence(inputs)
        if state is None:
            state = self.initial_state(float(u[0]))
        out, final, _ = self._run(u, self._check_state(state), False)
        return out, final

    def avalanches(
        self, inputs: Any, state: RandomFieldIsingState | None = None
    ) -> tuple[np.ndarray, np.ndarray, RandomFieldIsingState]:
        """Every avalanche triggered while following ``inputs`` from ``state`` (``None``:
        ``initial_state(inputs[0])``), in order: its trigger input (rising: the threshold;
        falling: the largest float below it), its size (spins flipped, ``> 0``; spins whose
        triggers coincide exactly count as one avalanche) and the final state."""
        u = as_input_sequence(inputs)
        if state is None:
            state = self.initial_state(float(u[0]))
        _, final, (triggers, sizes) = self._run(u, self._check_state(state), True)
        return triggers, sizes, final

    def avalanche_sizes(
        self, inputs: Any, state: RandomFieldIsingState | None = None
    ) -> tuple[np.ndarray, RandomFieldIsingState]:
        """The sizes of the avalanches of :meth:`avalanches` (int64) and the final state."""
        _, sizes, final = self.avalanches(inputs, state)
        return sizes, final

    def compiled_switching(self) -> CompiledSpins:
        """The lattice or graph as interacting spins for the oscillator's compiled switching
        engine (:class:`~hysteresis.compiled_spins.CompiledSpins`; the operator's own arrays,
        no copy)."""
        return CompiledSpins(
            fields=self._fields,
            spin_coupling=self._coupling,
            lattice=self._lat,
            offsets=self._offsets,
            adjacency=self._adj,
            max_degree=self._max_degree,
            neighbour_sums=self._nvals,
            order=self._order,
            sorted_fields=self._fsorted,
            spins=self._packed_spins,
            make_state=self._state_from_bits,
        )

    def _packed_spins(self, state: RandomFieldIsingState) -> tuple[np.ndarray, int]:
        state = self._check_state(state)
        return state.bits, state.n_up

    def _state_from_bits(self, bits: np.ndarray, n_up: int, input: float) -> RandomFieldIsingState:
        """The state with packed ``bits`` (taken over, made read-only) relaxed at ``input``."""
        bits.setflags(write=False)
        return RandomFieldIsingState(bits, float(input), int(n_up), self._fingerprint)

    def switching(self, state: RandomFieldIsingState) -> Switching:
        """The next switching inputs: ``upper`` the least threshold ``−(f_i + J·n_i)`` of a
        down spin, ``lower`` the greatest of an up spin; each jump is the ΔM of the whole
        avalanche there (relaxed in the workspace at ``upper`` and at the largest float below
        ``lower``, then undone: O(avalanche), no copy of the spins)."""
        state = self._check_state(state)
        u, n_up = state.input, state.n_up
        m = self.output(state)
        with self._lock:
            ws = self._workspace_at(state)
            bounds = []
            jumps = []
            for rising in (True, False):
                t = float(kern.next_trigger(
                    ws.bits, ws.nup, u, rising, self._fsorted, self._order, self._coupling,
                    self._nvals, self._lat, self._offsets,
                ))  # fmt: skip
                bounds.append(t)
                target = t if rising else math.nextafter(t, -math.inf)
                if not math.isfinite(target):
                    jumps.append(0.0)
                    continue
                ws.state = None  # modified until undone
                out, _, _, flips, _ = self._sweep(ws, np.array([target]), u, n_up, False)
                kern.undo(ws.bits, ws.nup, ws.queue, flips, rising, self._lat, self._offsets,
                          self._adj, self._max_degree)  # fmt: skip
                ws.state = state
                jumps.append(float(out[0]) - m)
        return Switching(lower=bounds[1], upper=bounds[0], jump_down=jumps[1], jump_up=jumps[0])
