"""Interacting Ising spins as an operator hands them to the oscillator's compiled engine.

A :class:`~hysteresis.base.SwitchingHysteron` whose units are Ising spins ``s_i = ±1`` with
random fields ``f_i`` and a ferromagnetic coupling ``J >= 0`` on a graph — local field
``h_i = u + (f_i + J·n_i)``, ``n_i = Σ_{j ~ i} s_j``, a down spin flips up once ``h_i >= 0`` and
an up spin down once ``h_i < 0``, every avalanche relaxed at its trigger input, output
``M = (2 n_up − N)/N`` — hands this description over from
:meth:`~hysteresis.base.SwitchingHysteron.compiled_switching` (the generalisation of a relay
table to interacting units). The engine (:mod:`oscillators.engines.switching`) builds its
compiled plan from it: every spin has one threshold ``t_i(n) = −(f_i + J·n)`` per value ``n``
of its neighbour sum, and ``order`` (fields descending) sorts the thresholds of every ``n`` at
once (Kuntz, Perković and Sethna's sorted lists).

Nothing here is mutable or copied per state: the arrays are the operator's own (read-only),
and the two callables convert between the operator's state and packed spins.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["CompiledSpins"]


@dataclass(frozen=True, eq=False)
class CompiledSpins:
    """Interacting Ising spins for the compiled switching engine (module docstring).

    Attributes
    ----------
    fields:
        ``f_i`` in site order (float64, read-only).
    spin_coupling:
        ``J >= 0``.
    lattice:
        int64 ``[ndim, L0, L1, L2, s0, s1, s2]``: a periodic hypercubic lattice of ``ndim``
        (1–3) side lengths ``L`` and strides ``s`` (neighbours by index arithmetic), or
        ``ndim = 0``: the graph is ``offsets``/``adjacency``.
    offsets, adjacency:
        Compressed rows of the graph (int64 ``N + 1``, int32), empty for a lattice.
    max_degree:
        The largest number of neighbours of a spin.
    neighbour_sums:
        int64, ascending: every value a neighbour sum ``n_i`` can take (``−z, …, z`` step 2 on
        a lattice of coordination ``z``).
    order:
        int32: the spins by fields descending (ties in site order), so that along it every
        threshold ``−(f_i + J·n)`` is non-decreasing for each ``n``.
    sorted_fields:
        ``fields[order]`` (float64).
    spins:
        ``spins(state) -> (bits, n_up)``: the state's spins packed 8 to a byte (``uint8``, spin
        ``i`` is bit ``i % 8`` of byte ``i // 8``, 1 = up) and the number of up spins; the
        spins are relaxed at ``state.input``.
    make_state:
        ``make_state(bits, n_up, input) -> state``: the operator's state with those spins,
        relaxed (stable) at ``input``; the engine hands it a fresh array it does not keep.
    """

    fields: np.ndarray
    spin_coupling: float
    lattice: np.ndarray
    offsets: np.ndarray
    adjacency: np.ndarray
    max_degree: int
    neighbour_sums: np.ndarray
    order: np.ndarray
    sorted_fields: np.ndarray
    spins: Callable[[Any], tuple[np.ndarray, int]]
    make_state: Callable[[np.ndarray, int, float], Any]

    @property
    def n_spins(self) -> int:
        """N, the number of spins."""
        return int(self.fields.size)
