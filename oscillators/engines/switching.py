"""The switching engine: the oscillator coupled exactly to interacting spins, compiled.

An operator without a relay table whose ``compiled_switching()`` hands over interacting Ising
spins (:class:`hysteresis.compiled_spins.CompiledSpins`: a random-field Ising lattice) is
integrated here: between events the relay kernel's closed-form hops, the next trigger input
in each direction from the spins' sorted lists (:mod:`oscillators.engines._switching_kernels`:
per list two candidates around the current input kept up to date over one membership byte
per spin; O(G + members passed + z·flips) per event, no trial run), each
avalanche one jump ``C·ΔM`` at its trigger input with the saltation ``δv += C·ΔM/v*·δq``,
``n_events`` counting spin flips. Filippov sliding, the switch budget, grazing, the tangent
flow and the records are the relay kernel engine's
(:class:`~oscillators.engines.relay.RelayKernelEngine`, whose Python side this class reuses).

Methods (``engine_options={"method": ...}``): ``"auto"`` (this engine) or ``"generic"`` (the
relay engine's Python reference path through ``switching()``/``apply()``, the reference the
tests compare with); ``"nested"``/``"heap"`` need a relay table and are refused.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from hysteresis._rfim_kernels import count_up_neighbours
from hysteresis.compiled_spins import CompiledSpins
from hysteresis.seam import check_state
from oscillators.engines import _relay_kernels as rk
from oscillators.engines import _switching_kernels as sk
from oscillators.engines.relay import RelayEngine, RelayKernelEngine, RelayReferenceEngine
from oscillators.results import OscillatorState

__all__ = ["SwitchingKernelEngine"]


class SwitchingKernelEngine(RelayKernelEngine):
    """Compiled event-driven engine for interacting spins (module docstring).

    ``SwitchingKernelEngine(system, state, method="generic")`` returns the reference
    :class:`~oscillators.engines.relay.RelayReferenceEngine` instead.
    """

    name = "switching kernel (interacting spins, sorted lists)"
    kernel_module = "oscillators.engines._switching_kernels"

    def __new__(cls, system: Any, state: OscillatorState, method: str = "auto", **kw: Any):
        if method == "generic":
            return RelayReferenceEngine(system, state, method, **kw)
        if method in ("nested", "heap"):
            name = type(system.operator).__name__
            raise ValueError(f"method {method!r} needs a relay table; {name} has none")
        return super().__new__(cls, system, state, method, **kw)

    def __init__(
        self, system: Any, state: OscillatorState, method: str = "auto", taylor: bool = True
    ) -> None:
        RelayEngine.__init__(self, system, state, method, taylor)
        spec = self._op.compiled_switching()
        if not isinstance(spec, CompiledSpins):
            raise TypeError(
                f"{type(self._op).__name__}.compiled_switching() must return a "
                f"hysteresis.compiled_spins.CompiledSpins, got {type(spec).__name__}"
            )
        self._spec = spec
        self.method = "compiled"
        q0, v0 = float(state.q), float(state.v)
        bits, n_up = spec.spins(self._opstate0)
        u0 = float(self._opstate0.input)
        n = spec.n_spins
        deg = int(spec.max_degree)
        nvals = np.asarray(spec.neighbour_sums, dtype=np.int64)
        if nvals.size > sk.MAX_LISTS:
            raise ValueError(
                f"the spins' graph has {nvals.size} neighbour-sum values; the switching kernel "
                f"takes at most {sk.MAX_LISTS} (a degree below {sk.MAX_LISTS // 2})"
            )
        gidx = np.full(2 * deg + 1, -1, dtype=np.int64)
        gidx[nvals + deg] = np.arange(nvals.size)
        # the list after a neighbour's flip up (row 0) or down (row 1); sums that cannot occur
        # keep their list (never read)
        nxt = np.empty((2, nvals.size), dtype=np.int64)
        for row, dn in enumerate((2, -2)):
            k = np.clip(nvals + dn + deg, 0, 2 * deg)
            nxt[row] = np.where(gidx[k] >= 0, gidx[k], np.arange(nvals.size))
        bits = np.array(bits, dtype=np.uint8)
        nup = np.zeros(n, dtype=np.uint8 if deg < 256 else np.int32)
        count_up_neighbours(bits, spec.lattice, spec.offsets, spec.adjacency, deg, nup)
        # one record per spin in site order: rank, list, up (kernel docstring; 4 bytes on a
        # lattice), and on a lattice its faces
        dtype, shift = sk.record_layout(n, nvals.size)
        recs = np.empty(n, dtype=dtype)
        rank = np.empty(n, dtype=np.int64)
        rank[spec.order] = np.arange(n, dtype=np.int64)
        faces = sk.boundary_flags(spec.lattice, n)
        # the lists in rank order, one byte per entry (two past 127 lists): 2·list + up, padded
        # with 0xFF to whole 8-byte words (the kernels search 8 entries at a time)
        small = 2 * nvals.size <= 254
        words = (n + 7) // 8 + 1
        memb = np.full(8 * words if small else n, 0xFF, dtype=np.uint8 if small else np.uint16)
        # per list and block of 64 positions the number of members (the searches skip empty
        # blocks)
        cnt = np.zeros((nvals.size, words // 8 + 1) if small else (0, 0), dtype=np.uint8)
        sk.records(recs, shift, rank, memb, cnt, bits, nup, gidx, spec.lattice, spec.offsets,
                   deg)  # fmt: skip
        del rank
        mw = memb.view(np.uint64) if small else np.empty(0, dtype=np.uint64)
        del nup
        fs, j = spec.sorted_fields, float(spec.spin_coupling)
        jn = j * nvals  # J·n rounded once, here: the kernels add it (no fused multiply-add)
        # every list's boundary: its entries with t <= u0 (binary search; t grows along a list)
        bound = np.array([np.searchsorted(-(fs + x), u0, side="right") for x in jn.tolist()],
                         dtype=np.int64)  # fmt: skip
        ng = nvals.size
        cand = np.empty(2 * ng, dtype=np.int64)
        ctr = np.empty(2 * ng)
        sk.candidates(memb, mw, cnt, fs, jn, bound, cand, ctr)
        self._plan = (
            recs, shift, memb, mw, cnt, fs, spec.order, jn, nxt, faces, spec.lattice, spec.offsets,
            spec.adjacency, deg, bits, np.empty(max(n, 1), dtype=np.int32), bound,
            np.empty(ng, dtype=np.int64), cand, ctr,
        )  # fmt: skip
        self._n_relays = n  # the switch budget scales with the spins
        self._mp = rk.taylor_matrix_coefficients(float(system.damping_ratio), self._omega)
        self._tn1 = np.zeros(1, dtype=np.int64)
        self._tt1 = np.zeros(1)
        self._nobuf = np.empty((0, 3))
        self._nosw = np.empty((1, 4))
        self._cnt = np.zeros(1, dtype=np.int64)
        self._tf = self._ti = self._bits = self._lay = None  # the relay tables' slots: unused
        st = np.zeros(rk.N_ST)
        st[: rk.S_SIN + 1] = (q0, v0, 0.0, math.cos(self._phi0), math.sin(self._phi0))
        st[sk.S_U] = u0
        st[rk.S_MV] = (2 * n_up - n) / n
        ist = np.zeros(rk.N_IST, dtype=np.int64)
        ist[sk.I_NUP] = n_up
        sk.refresh(st, ctr, ng)
        self._st, self._ist = st, ist
        self._start_on_sliding_set(q0, v0)

    def _run(self, par, _tf, _ti, _bits, _lay, st, ist, *rest):  # noqa: ANN001, ANN202
        """:meth:`RelayKernelEngine._run_targets`'s kernel call, on the spins' plan."""
        return sk.run_spins(par, st, ist, *rest, self._plan)

    def kernel_arrays(self) -> None:
        """``None``: the compiled Benettin loop (:mod:`analysis.dynamics._relay_benettin`) drives
        the relay kernel's tables only; the spins' plan steps through the Python loop."""
        return None

    def _switched_copy(self, direction: int) -> tuple[float, float, float]:
        """(output, next up, next down trigger) after the event at the current trigger in
        ``direction``, on a copy of the plan (O(N): only where a start sits on a trigger)."""
        st, ist = self._st.copy(), self._ist.copy()
        # the operator's read-only arrays (fields, order, graph) are shared, not copied: the
        # kernel cannot write them, and a writable copy would be another numba type, i.e. a
        # second compilation of ``switch`` (~13 s on a fresh machine) next to _slide_switch's
        plan = [
            a.copy() if isinstance(a, np.ndarray) and a.flags.writeable else a for a in self._plan
        ]
        if plan[3].size:
            plan[3] = plan[2].view(np.uint64)  # the membership words: a view of the bytes
        plan = tuple(plan)
        sk.switch(direction, st, ist, plan)
        return float(st[rk.S_MV]), float(st[rk.S_UP]), float(st[rk.S_DN])

    def _slide_switch(self, direction: int) -> None:
        sk.switch(direction, self._st, self._ist, self._plan)

    def relay_outputs(self) -> np.ndarray:
        """No relay table: the spins are in :meth:`state` (``operator.spins(...)``)."""
        raise AttributeError(
            f"{type(self._op).__name__} has no relay_outputs (no relay table): read the spins "
            "from engine.state().operator_state"
        )

    @property
    def n_up(self) -> int:
        """The number of up spins now."""
        return int(self._ist[sk.I_NUP])

    def _now(self) -> tuple[float, float, Any]:
        st = self._st
        q, v = float(st[rk.S_Q]), float(st[rk.S_V])
        # the spins are stable at every input in [next down trigger, next up trigger); right
        # after a falling event q sits on the trigger the input has just left below
        u = q
        if not st[rk.S_DN] <= u < st[rk.S_UP]:
            u = float(np.nextafter(q, -np.inf))
            if not st[rk.S_DN] <= u < st[rk.S_UP]:
                u = float(st[sk.S_U])  # sliding on a trigger: the input of the last event
        bits = self._plan[sk.PL_BITS].copy()
        opstate = self._spec.make_state(bits, self.n_up, u)
        check_state(
            opstate, f"returned by {type(self._op).__name__}.compiled_switching().make_state"
        )
        return q, v, opstate
