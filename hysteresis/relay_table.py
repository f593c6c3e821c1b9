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
and one index ``k`` describes the state — the oscillator then switches in O(1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hysteresis._validation import finite_array, finite_scalar

__all__ = ["NestedPlan", "RelayTable"]


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
        """Index reached by rising from negative saturation to ``q`` (groups with up <= q)."""
        return int(np.searchsorted(self.up, q, side="right"))

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

    __slots__ = ("_alpha", "_beta", "_weights", "_plan", "_plan_done")

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

    def __setattr__(self, name, value):
        raise AttributeError("RelayTable is immutable")

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
        y = np.asarray(outputs, dtype=np.float64)
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
        and the lower thresholds increase strictly along the order (true for equal widths). The
        outputs ``mval`` are exact integer counts times the weight when all weights are equal
        (no summation drift, e.g. dimers ``M_k = 4k/N - 1``), cumulative sums otherwise.
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
