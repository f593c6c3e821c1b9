"""Compile (and cache) the numba kernels that the default test suite needs late in its run, in
a process of its own beside pytest (started by ``tests/conftest.py`` on a fresh checkout).

Why: without a numba cache (a fresh clone, CI) about 300 s of the suite's ~750 s are first-use
compilations, one after another in the pytest process, while the machine's second core idles.
This process compiles the kernels of the suite's later modules (Duhem engine, spins engine,
bit-sliced lattice, the compiled Benettin loop, ...) while pytest runs its first ones; pytest
then loads them from numba's cache. It runs the library's public calls on small models, so it
compiles exactly the specialisations the engines use; it checks nothing (the tests do).

The order is the order in which the suite first needs each kernel, leaving out the two that
pytest compiles itself in its first minute (the play and the continuous engine): each kernel is
cached before pytest gets there. A kernel pytest reaches first is compiled by both processes
(no harm: the saves of the two processes are serialized, ``tests/numba_cache_lock.py``).
"""

from __future__ import annotations

import os
import sys
import warnings
from collections.abc import Callable

import numpy as np
from numba_cache_lock import LOCK_ENV, lock_cache_saves

from analysis.dynamics.dimensions import box_counting_dimension
from analysis.dynamics.lyapunov import lyapunov_spectra, lyapunov_spectrum
from analysis.identification import identify_from_curves
from analysis.identification.datasets import forc_sample
from analysis.identification.forc_io import read_forc_file
from hysteresis import (
    BoucWen,
    JilesAtherton,
    PreisachModel,
    RandomFieldIsing,
    SpinDimerEnsemble,
)
from hysteresis import _rfim_bits_kernels as bits_kernels
from hysteresis.preisach import _kernels as preisach_kernels
from hysteresis.rfim_bits import BitLattice, bit_lattice_loop, pack_spins
from oscillators import ForcedOscillator


def _relay_and_benettin() -> None:
    """The relay kernel's two tables and the compiled Benettin loop around them, alone and as
    lanes (systems side by side)."""
    dimers = ForcedOscillator(SpinDimerEnsemble.random(40, 2.0, 1.0, 2.0, seed=3), 3.2)
    lyapunov_spectrum(dimers, 20 * dimers.period, 0.0)  # nested table
    pair = [
        ForcedOscillator(SpinDimerEnsemble.random(40, 2.0, 1.0, 2.0, seed=s), 3.2) for s in (4, 5)
    ]
    lyapunov_spectra(pair, 20 * dimers.period, 0.0)
    rng = np.random.default_rng(0)
    c, h = rng.normal(0.0, 1.0, 50), rng.uniform(0.5, 1.5, 50)
    heap = ForcedOscillator(PreisachModel.from_relays(c + h, c - h), 4.0)
    lyapunov_spectrum(heap, 20 * heap.period, 0.0)  # heap table


def _operators_and_identification() -> None:
    """Compiled apply of Bouc-Wen, Jiles-Atherton, the RFIM and a discrete Preisach model
    (both lane modes), VARIFORC regression, box counting."""
    u = 3.0 * np.sin(np.linspace(0.0, 6 * np.pi, 200))
    for op in (BoucWen(1.0, 0.5, 0.3, 1.0), JilesAtherton(ms=1.0, a=0.5, k=0.4, c=0.0, alpha=0.3)):
        op.apply(u, op.initial_state(u[0]))
    data = read_forc_file(forc_sample("micromag-synthetic"), drift_correction="multiplicative")
    identify_from_curves(data.curves, smoothing="variforc", extend=False, uncertainty=True)
    lattice = RandomFieldIsing.lattice((4, 4, 4), 2.0, seed=1)
    lattice.apply(u, lattice.initial_state(float(u[0])))
    box_counting_dimension(np.random.default_rng(1).random((5000, 2)))
    rng = np.random.default_rng(3)
    alpha = rng.normal(size=300) + 0.5
    m = PreisachModel.from_relays(alpha, alpha - rng.random(300), rng.dirichlet(np.ones(300)))
    simd = preisach_kernels.USE_SIMD
    try:
        for flag in (simd, False):  # the scalar fallback compiles its own specialisation
            preisach_kernels.USE_SIMD = flag
            _, state = m.apply(u)
            m.switching(state)
    finally:
        preisach_kernels.USE_SIMD = simd


def _duhem_engine() -> None:
    system = ForcedOscillator(BoucWen(1.0, 0.5, 0.3, 1.0), 1.0)
    system.trajectory(10.0)
    lyapunov_spectrum(system, 5 * system.period, 0.0)


def _spins(model: RandomFieldIsing) -> None:
    system = ForcedOscillator(model, 2.9)
    system.trajectory(10.0)
    lyapunov_spectrum(system, 3 * system.period, 0.0)
    system.engine()._switched_copy(1)  # the event kernel outside a run (slides, a start on a
    # trigger; tests/test_oscillators/test_switching_structure.py calls it directly)


def _lattice_spins() -> None:
    _spins(RandomFieldIsing.lattice((4, 4, 4), 3.5, seed=3))  # 4-byte records


def _bit_lattice() -> None:
    loop = np.concatenate([np.linspace(-9.0, 9.0, 20), np.linspace(9.0, -9.0, 20)])
    bit_lattice_loop((200,), 0.8, loop, 1.0, 1, 1)
    BitLattice((5, 6, 80), 1.8, 1.0, 9).relax(0.5)
    words = pack_spins(np.ones(300, dtype=np.int64))
    dims = np.array((1, 1, 300), dtype=np.int64)
    bits_kernels.count_up(words, dims, np.zeros(300, np.int64))
    bits_kernels.up_counts_bitsliced(words, dims, np.zeros(300, np.int64))


def _graph_spins() -> None:
    rng = np.random.default_rng(7)
    pairs = np.unique(np.sort(rng.integers(0, 120, (300, 2)), axis=1), axis=0)
    # degrees 0-9: more than 16 neighbour-sum lists, i.e. the 8-byte records
    _spins(RandomFieldIsing(rng.normal(0, 2.5, 120), pairs[pairs[:, 0] != pairs[:, 1]], 0.7))


#: in the order the suite first needs them (tests/test_analysis/cli ... tests/test_oscillators)
STEPS: tuple[Callable[[], None], ...] = (
    _relay_and_benettin,
    _operators_and_identification,
    _duhem_engine,
    _lattice_spins,
    _bit_lattice,
    _graph_spins,
)


def main() -> int:
    lock = os.environ.get(LOCK_ENV)
    if lock:
        lock_cache_saves(lock)
    os.nice(5)  # where the machine has no idle core, the tests come first
    warnings.simplefilter("ignore")
    for step in STEPS:
        try:
            step()
        except Exception as exc:  # a failure here is the tests' to report, not this process's
            print(f"kernel warm-up: {step.__name__} failed: {exc!r}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
