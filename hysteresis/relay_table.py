"""A piecewise-constant operator as a table of weighted relays (the relay side of the engine seam).

Every piecewise-constant operator of this package (:class:`~hysteresis.relay.Relay`, the discrete
:class:`~hysteresis.preisach.PreisachModel`, :class:`~hysteresis.spin_dimers.SpinDimerEnsemble`)
hands the oscillator a :class:`RelayTable` through ``relay_table()``: thresholds ``alpha[i] >=
beta[i]`` and weights ``weights[i] >= 0`` with output ``M = Σ_i weights[i]·y_i``, ``y_i = ±1``
(relay convention: ``y_i = +1`` once the input has reached ``u >= alpha[i]``, ``-1`` once it has
fallen to ``u < beta[i]``). Relays are independent, so the table and the outputs ``y_i``
(``relay_outputs(state)``) are all an event-driven integrator needs; the operator turns outputs
back into its own state with ``state_from_relay_outputs(outputs, input)``.

The table also knows its *nested plan* (:meth:`RelayTable.nested_plan`): when the relays can be
ordered so that the upper and the lower thresholds increase together (every equal-width model,
the paper's spin dimers), the reachable configurations at any input are prefixes of that order
and one index ``k`` describes the state — the oscillator then switches in O(1), and
:meth:`NestedPlan.drive` maps an input sequence to outputs in O(log G) per input, however many
relays switch.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from hysteresis._validation import (
    as_input_sequence,
    finite_array,
    finite_scalar,
    nonnegative_integer,
    real_array,
)

__all__ = ["HeapTable", "NestedPlan", "RelayTable"]


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=np.float64)
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class NestedPlan:
    """Relays grouped by identical thresholds, in an order where both thresholds increase.

    With the first ``k`` groups up and the others down, the next up switch is at ``up[k]``
    (``q >= up[k]``), the next down switch below ``down[k-1]`` and the output is ``mval[k]``.

    Attributes
    ----------
    up, down:
        Upper and lower thresholds of the groups, both strictly increasing (length G).
    mval:
        Output with the first ``k`` groups up, ``k = 0..G`` (length G + 1).
    order:
        Relay indices (table order) sorted into the group order.
    starts:
        Start of each group in ``order`` (length G + 1, last entry = number of relays).
    """

    up: np.ndarray
    down: np.ndarray
    mval: np.ndarray
    order: np.ndarray
    starts: np.ndarray

    @property
    def n_groups(self) -> int:
        """Number of groups G."""
        return int(self.up.size)

    def index_at(self, q: float) -> int:
        """Index reached by rising from negative saturation to ``q`` (groups with up <= q): the
        prefix form of :meth:`RelayTable.initial_outputs` (a relay is up iff ``alpha <= q``)."""
        q = finite_scalar(q, "q")
        return int(np.searchsorted(self.up, q, side="right"))

    def drive(self, inputs, k: int) -> tuple[np.ndarray, int]:
        """Outputs for the input sequence ``inputs`` from index ``k``, and the final index.

        The relay rule (up once ``u >= alpha``, down once ``u < beta``) on prefix states: at an
        input ``v`` the groups with ``up <= v`` must be up, ``a = #{up <= v}``, and those with
        ``down > v`` must be down, ``b = #{down <= v}``; ``a <= b`` because ``down <= up``
        group by group, so the new index is ``min(max(k, a), b)``:

        * rising, ``v >= up[k]``: ``k = a`` (``searchsorted(up, v, 'right')``);
        * falling, ``k > 0`` and ``v < down[k-1]``: ``k = b`` (``searchsorted(down, v,
          'right')``);
        * otherwise ``k`` is unchanged (no relay switches),

        and the output is ``mval[k]``: O(log G) per input however many relays switch (the
        general Preisach kernel is O(1 + relays switched)). The outputs are the values of
        :attr:`mval`, not a running sum, so no round-off accumulates along the sequence.

        Parameters
        ----------
        inputs:
            The input sequence (1-D, finite, non-empty).
        k:
            Start index, an integer in ``[0, n_groups]`` (first ``k`` groups up); rising from
            negative saturation to ``u0`` is ``index_at(u0)``.

        Returns
        -------
        (outputs, k_final):
            ``mval`` after each input (float64, length of ``inputs``) and the final index.
        """
        u = as_input_sequence(inputs, "inputs")
        k = nonnegative_integer(k, "k")
        if k > self.n_groups:
            raise ValueError(
                f"k must be an integer in [0, {self.n_groups}] (the number of groups up), got {k}"
            )
        outputs, k_final = _drive_nested(u, self.up, self.down, self.mval, k)
        return outputs, int(k_final)

    def index_of(self, outputs: np.ndarray) -> int | None:
        """Index ``k`` of a relay configuration (table order), or ``None`` if it is not a
        prefix configuration (first ``k`` groups up, the rest down)."""
        y = np.asarray(outputs)[self.order] > 0
        n_up = int(np.count_nonzero(y))
        if n_up and not np.all(y[:n_up]):
            return None  # the up relays are not the first ones in group order
        k = int(np.searchsorted(self.starts, n_up))  # starts[k] = relays in the first k groups
        if k >= self.starts.size or self.starts[k] != n_up:
            return None  # a group is split
        return k

    def outputs(self, k: int, n_relays: int) -> np.ndarray:
        """Relay outputs (table order) with the first ``k`` groups up."""
        y = np.full(n_relays, -1.0)
        y[self.order[: self.starts[k]]] = 1.0
        return y


@njit(cache=True, inline="always")
def _first_above(values, v, lo, hi):  # pragma: no cover - compiled
    """First index in ``[lo, hi]`` whose value exceeds ``v`` (``values`` ascending; ``hi`` is
    returned when none in ``[lo, hi)`` does): a binary search."""
    while lo < hi:
        mid = (lo + hi) >> 1
        if values[mid] <= v:
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit(cache=True)
def _drive_nested(inputs, up, down, mval, k):  # pragma: no cover - compiled
    """The loop of :meth:`NestedPlan.drive`; returns ``(outputs, k_final)``.

    Plain-Python reading::

        for t, v in enumerate(inputs):
            if k < G and v >= up[k]:            # rising: groups k.. with up <= v switch up
                k = searchsorted(up, v, "right")     # searched in (k, G]
            elif k > 0 and v < down[k - 1]:     # falling: groups ..k-1 with down > v go down
                k = searchsorted(down, v, "right")   # searched in [0, k)
            outputs[t] = mval[k]
    """
    g = up.size
    outputs = np.empty(inputs.size)
    for t in range(inputs.size):
        v = inputs[t]
        if k < g and v >= up[k]:
            k = _first_above(up, v, k + 1, g)  # up[k] <= v is known
        elif k > 0 and v < down[k - 1]:
            k = _first_above(down, v, 0, k - 1)  # down[k-1] > v is known
        outputs[t] = mval[k]
    return outputs, k


class RelayTable:
    """Weighted relays ``M = Σ weights[i]·y_i`` with thresholds ``alpha[i] >= beta[i]``.

    Parameters
    ----------
    alpha, beta:
        Upper and lower thresholds (1-D, finite, same length N >= 1, ``alpha >= beta``; equal
        values are zero-width relays, reversible switches).
    weights:
        ``>= 0``, finite, length N (no normalisation is imposed: ``M`` ranges over
        ``[-Σw, Σw]``).

    The arrays are read-only copies. Instances are immutable.
    """

    __slots__ = ("_alpha", "_beta", "_weights", "_plan", "_plan_done", "_positive", "_heap")

    def __init__(self, alpha, beta, weights) -> None:
        alpha = finite_array(alpha, "alpha", ndim=1)
        beta = finite_array(beta, "beta", ndim=1)
        weights = finite_array(weights, "weights", ndim=1)
        if alpha.shape != beta.shape or alpha.shape != weights.shape:
            raise ValueError(
                "alpha, beta and weights must have the same length, got "
                f"{alpha.size}, {beta.size} and {weights.size}"
            )
        bad = np.flatnonzero(alpha < beta)
        if bad.size:
            i = int(bad[0])
            raise ValueError(
                f"alpha must be >= beta for every relay, relay {i} has alpha={alpha[i]} < "
                f"beta={beta[i]}"
            )
        if np.any(weights < 0.0):
            raise ValueError("weights must be >= 0")
        object.__setattr__(self, "_alpha", _readonly(alpha))
        object.__setattr__(self, "_beta", _readonly(beta))
        object.__setattr__(self, "_weights", _readonly(weights))
        object.__setattr__(self, "_plan", None)
        object.__setattr__(self, "_plan_done", False)
        object.__setattr__(self, "_positive", None)
        object.__setattr__(self, "_heap", None)

    def __setattr__(self, name, value):
        raise AttributeError("RelayTable is immutable")

    def __reduce__(self) -> tuple:
        """Pickled as its thresholds and weights (the cached plans are rebuilt on demand)."""
        return (RelayTable, (self._alpha, self._beta, self._weights))

    # -- parameters -----------------------------------------------------------------------------
    @property
    def alpha(self) -> np.ndarray:
        """Upper thresholds α_i (read-only)."""
        return self._alpha

    @property
    def beta(self) -> np.ndarray:
        """Lower thresholds β_i (read-only)."""
        return self._beta

    @property
    def weights(self) -> np.ndarray:
        """Weights w_i >= 0 (read-only)."""
        return self._weights

    @property
    def n_relays(self) -> int:
        """Number of relays N."""
        return int(self._alpha.size)

    def __len__(self) -> int:
        return self.n_relays

    def __repr__(self) -> str:
        return f"RelayTable(n_relays={self.n_relays})"

    # -- outputs ---------------------------------------------------------------------------------
    def check_outputs(self, outputs, input: float) -> np.ndarray:
        """Validated relay outputs (float ±1, length N) consistent with the current ``input``.

        Relays with ``alpha <= input`` must be up and relays with ``beta > input`` down (any
        other configuration cannot be reached with the input at ``input``).
        """
        input = finite_scalar(input, "input")
        y = real_array(outputs, "outputs")
        if y.shape != self._alpha.shape:
            raise ValueError(f"outputs must have length {self.n_relays}, got shape {y.shape}")
        if not np.all((y == 1.0) | (y == -1.0)):
            raise ValueError("outputs must be +1 or -1")
        wrong = np.flatnonzero(
            ((self._alpha <= input) & (y < 0)) | ((self._beta > input) & (y > 0))
        )
        if wrong.size:
            i = int(wrong[0])
            raise ValueError(
                f"outputs are not reachable at input={input}: relay {i} (alpha={self._alpha[i]}, "
                f"beta={self._beta[i]}) has output {y[i]:+.0f}"
            )
        return y

    def output(self, outputs) -> float:
        """``M = Σ weights·y``, correctly rounded (``math.fsum``)."""
        return math.fsum(np.asarray(outputs, dtype=np.float64) * self._weights)

    def initial_outputs(self, u0: float) -> np.ndarray:
        """Outputs after rising from negative saturation to ``u0``: up iff ``alpha <= u0``."""
        u0 = finite_scalar(u0, "u0")
        return np.where(self._alpha <= u0, 1.0, -1.0)

    # -- the O(1) plan ---------------------------------------------------------------------------
    def nested_plan(self) -> NestedPlan | None:
        """The O(1)-per-switch plan, or ``None`` if the thresholds do not nest.

        Eligible when, after grouping relays with identical ``(alpha, beta)``, both the upper
        and the lower thresholds increase strictly along the order (true for equal widths). With
        all weights equal, ``mval[k] = (2c_k − n)/n · Σw`` from the exact integer count c_k of
        up relays (n relays): no summation drift, each value within a few roundings of the
        exact one (``Σw`` is summed once, then one subtraction, division and product; e.g.
        dimers ``M_k = 4k/N − 1``); cumulative sums of the group weights otherwise.
        """
        if self._plan_done:
            return self._plan
        plan = self._build_plan()
        object.__setattr__(self, "_plan", plan)
        object.__setattr__(self, "_plan_done", True)
        return plan

    def _build_plan(self) -> NestedPlan | None:
        alpha, beta, w = self._alpha, self._beta, self._weights
        order = np.lexsort((beta, alpha))
        a = alpha[order]
        b = beta[order]
        ws = w[order]
        new_group = np.ones(a.size, dtype=bool)
        new_group[1:] = (a[1:] != a[:-1]) | (b[1:] != b[:-1])
        starts = np.flatnonzero(new_group)
        up = a[starts]
        down = b[starts]
        if up.size > 1 and (np.any(np.diff(up) <= 0.0) or np.any(np.diff(down) <= 0.0)):
            return None
        total = float(np.sum(ws))
        if np.all(ws == ws[0]):
            counts = np.concatenate([[0], np.cumsum(np.diff(np.append(starts, a.size)))])
            mval = (2.0 * counts - a.size) / a.size * total
        else:
            cum = np.concatenate([[0.0], np.cumsum(np.add.reduceat(ws, starts))])
            mval = 2.0 * cum - total
        all_starts = np.append(starts, a.size).astype(np.int64)
        order = order.astype(np.int64)
        for arr in (up, down, mval, order, all_starts):
            arr.setflags(write=False)
        return NestedPlan(up=up, down=down, mval=mval, order=order, starts=all_starts)

    # -- the plans of the oscillator's relay kernels (built once, cached: the table is immutable)
    def positive_part(self) -> tuple[np.ndarray, RelayTable]:
        """(indices, table) of the relays of positive weight (``self`` if every weight is
        positive): relays of zero weight never change ``M`` and the kernels leave them out."""
        if self._positive is None:
            active = np.flatnonzero(self._weights > 0.0)
            if active.size == 0:
                raise ValueError("the relay table has no relay of positive weight")
            active.setflags(write=False)
            work = self
            if active.size < self.n_relays:
                work = RelayTable(self._alpha[active], self._beta[active], self._weights[active])
            object.__setattr__(self, "_positive", (active, work))
        return self._positive

    def heap_plan(self) -> HeapTable:
        """The bitset-heap plan (any relays, O(log₆₄ N) per switch) of a table whose weights
        are all positive (see :meth:`positive_part`)."""
        if self._heap is None:
            object.__setattr__(self, "_heap", HeapTable(self._alpha, self._beta, self._weights))
        return self._heap


# -- the heap plan: two hierarchical 64-ary bitsets over the presorted thresholds -----------------
def _bitset_layout(n: int) -> list[int]:
    """Word counts per level of a 64-ary hierarchical bitset over n >= 1 items (top: 1 word)."""
    sizes = [max(1, -(-n // 64))]
    while sizes[-1] > 1:
        sizes.append(-(-sizes[-1] // 64))
    return sizes


def _bitset_words(flags: np.ndarray) -> np.ndarray:
    """All levels of the hierarchical bitset of boolean ``flags`` (layout of _bitset_layout)."""
    levels = []
    level = flags
    for size in _bitset_layout(flags.size):
        padded = np.zeros(64 * size, dtype=bool)
        padded[: level.size] = level
        words = np.packbits(padded, bitorder="little").view("<u8").astype(np.uint64)
        levels.append(words)
        level = words != 0
    return np.concatenate(levels)


class HeapTable:
    """The bitset-heap form (kind 1) of relays of positive weight.

    ``rank_a`` / ``rank_b`` map the alpha ranks (ascending) and beta ranks (descending) to the
    indices of the given arrays. ``unit > 0`` when every weight is an integer multiple of
    ``unit`` (then ``M`` is kept as integer units).
    """

    def __init__(self, alpha: np.ndarray, beta: np.ndarray, weights: np.ndarray) -> None:
        if not np.all(weights > 0.0):
            raise ValueError("the heap table takes relays of positive weight only")
        n = int(alpha.size)
        order_a = np.lexsort((-beta, alpha))  # ties in alpha: any order, kept deterministic
        order_b = np.lexsort((alpha, -beta))
        inv_b = np.empty(n, dtype=np.int64)
        inv_b[order_b] = np.arange(n)
        inv_a = np.empty(n, dtype=np.int64)
        inv_a[order_a] = np.arange(n)
        unit = float(weights.min())
        units = np.rint(weights / unit)
        if not (np.all(units * unit == weights) and units.max() * n < 2**52):
            unit = 0.0
            units = np.zeros(n)
        units = units.astype(np.int64)
        self.n = n
        self.rank_a = order_a
        self.rank_b = order_b
        self.unit = unit
        self.total_units = int(units.sum())
        self.w_a = weights[order_a]
        self.units_a = units[order_a]
        self.tf = np.concatenate(
            [alpha[order_a], beta[order_b], weights[order_a], weights[order_b]]
        ).astype(np.float64)
        self.ti = np.concatenate(
            [inv_b[order_a], inv_a[order_b], units[order_a], units[order_b]]
        ).astype(np.int64)
        sizes = _bitset_layout(n)
        offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        self.n_words = int(offsets[-1])
        levels = len(sizes)
        self.lay = np.concatenate([[levels, n], offsets[:-1], offsets[:-1] + self.n_words]).astype(
            np.int64
        )

    def bits_from_outputs(self, outputs: np.ndarray) -> np.ndarray:
        """The two bitsets for relay outputs ``outputs`` (±1, order of the given arrays)."""
        down = np.asarray(outputs)[self.rank_a] < 0
        up = np.asarray(outputs)[self.rank_b] > 0
        return np.concatenate([_bitset_words(down), _bitset_words(up)])

    def outputs_from_bits(self, bits: np.ndarray) -> np.ndarray:
        """Relay outputs (±1, order of the given arrays) from the bitsets."""
        leaf = bits[: -(-self.n // 64)]
        flags = np.unpackbits(leaf.view(np.uint8), bitorder="little")[: self.n].astype(bool)
        y = np.empty(self.n)
        y[self.rank_a] = np.where(flags, -1.0, 1.0)
        return y

    def state_arrays(self, outputs: np.ndarray) -> tuple[np.ndarray, int, float, float]:
        """(bits, units up, M, compensation) for relay outputs ``outputs``."""
        bits = self.bits_from_outputs(outputs)
        y = np.asarray(outputs)[self.rank_a]
        units_up = int(self.units_a[y > 0].sum())
        m = math.fsum(self.w_a * y)
        return bits, units_up, m, 0.0
