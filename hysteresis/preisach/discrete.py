"""The discrete Preisach model: finitely many weighted relays (see :mod:`hysteresis.preisach.base`).

Its relays are a :class:`~hysteresis.relay_table.RelayTable` (the same table the oscillator's relay
engine runs on); the model adds the sorted orders, sparse tables and bucket grids of the compiled
kernels (:mod:`hysteresis.preisach._kernels`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from hysteresis._validation import (
    MAX_MAGNITUDE,
    as_input_sequence,
    finite_array,
    finite_scalar,
    readonly_array,
    real_array,
)
from hysteresis.base import PiecewiseConstantHysteron, Switching
from hysteresis.preisach import _kernels as _k
from hysteresis.preisach.base import PreisachModel, PreisachState, _fingerprint, _stack
from hysteresis.preisach.projection import project_identification
from hysteresis.relay_table import RelayTable

__all__ = ["DiscretePreisachModel"]

_WEIGHT_TOLERANCE = 1e-9


class DiscretePreisachModel(
    PreisachModel, PiecewiseConstantHysteron[PreisachState], kind="discrete"
):
    """Finite set of relays with weights: ``M = Σ_i w_i y_{α_i β_i}[u]``.

    Attributes: ``alpha``, ``beta``, ``weights`` (read-only, in the given order), ``n_relays``,
    ``equal_widths``, and for fast paths the relays sorted by centre (``order_by_centre``,
    ``sorted_centres``, ``sorted_weights``).
    """

    def __init__(self, alpha, beta, weights=None) -> None:
        # magnitudes bounded: the centres (α+β)/2, widths α−β and the bucket grid below must
        # stay finite (thresholds near ±1e308 made the compiled kernel index out of bounds)
        alpha = finite_array(alpha, "alpha", ndim=1, max_abs=MAX_MAGNITUDE)
        beta = finite_array(beta, "beta", ndim=1, max_abs=MAX_MAGNITUDE)
        if alpha.shape != beta.shape:
            raise ValueError(
                f"alpha and beta must have the same length, got {alpha.size} and {beta.size}"
            )
        bad = np.flatnonzero(alpha < beta)
        if bad.size:
            i = int(bad[0])
            raise ValueError(
                f"alpha must be >= beta for every relay (alpha >= beta), relay {i} has "
                f"alpha={alpha[i]} < beta={beta[i]}"
            )
        n = alpha.size
        if weights is None:
            weights = np.full(n, 1.0 / n)
        else:
            weights = finite_array(weights, "weights", ndim=1)
            if weights.shape != alpha.shape:
                raise ValueError(
                    f"weights must have the same length as alpha ({n}), got {weights.size}"
                )
            if np.any(weights < 0):
                raise ValueError("weights must be >= 0")
            total = float(weights.sum())
            if abs(total - 1.0) > _WEIGHT_TOLERANCE:
                raise ValueError(f"weights must sum to 1 (within 1e-9), got sum {total!r}")
        # the relays themselves: one read-only table, shared with the oscillator's relay engine
        self._relays = RelayTable(alpha, beta, weights)
        self._fingerprint = _fingerprint(b"discrete", alpha, beta, weights)

        order_a = np.argsort(alpha, kind="stable")
        order_b = np.argsort(beta, kind="stable")
        self._order_a = order_a
        self._order_b = order_b
        self._alpha_by_a = np.ascontiguousarray(alpha[order_a])
        self._beta_by_a = np.ascontiguousarray(beta[order_a])
        self._w_by_a = np.ascontiguousarray(weights[order_a])
        self._alpha_by_b = np.ascontiguousarray(alpha[order_b])
        self._beta_by_b = np.ascontiguousarray(beta[order_b])
        self._w_by_b = np.ascontiguousarray(weights[order_b])
        # search keys of the range queries: a relay of zero weight never changes the output, so
        # it is hidden from them (beta = -inf never exceeds a minimum, alpha = +inf never lies
        # below a maximum); it still counts for the staircase positions
        self._beta_key_a = np.where(self._w_by_a > 0, self._beta_by_a, -np.inf)
        self._alpha_key_b = np.where(self._w_by_b > 0, self._alpha_by_b, np.inf)
        self._table_a = _k.sparse_table(self._beta_key_a, True)  # range-argmax
        self._table_b = _k.sparse_table(self._alpha_key_b, False)  # range-argmin
        self._cum_w_a = np.concatenate([[0.0], np.cumsum(self._w_by_a)])
        # uniform bucket grids over the thresholds: O(1) expected "count <= u" per input step;
        # 8 buckets per relay keep the in-bucket search (unpredictable branches) to about one
        # comparison where the thresholds are densest, for 32 bytes per relay (int32 starts)
        grid = []
        starts = []
        for values in (self._alpha_by_a, self._beta_by_b):
            lo, hi = float(values[0]), float(values[-1])
            nb = max(1, 8 * n)
            inv_h = nb / (hi - lo) if hi > lo else 0.0
            grid += [lo, inv_h]
            starts.append(_k.bucket_starts(values, lo, inv_h, nb))
        self._grid = np.array(grid)
        self._starts_a, self._starts_b = starts

        width = alpha - beta
        scale = max(1.0, float(np.max(np.abs(alpha))), float(np.max(np.abs(beta))))
        self._equal_widths = bool(np.ptp(width) <= 1e-12 * scale)
        centre = 0.5 * (alpha + beta)
        order_c = np.argsort(centre, kind="stable")
        self._order_c = readonly_array(order_c, np.int64)
        self._sorted_centres = readonly_array(centre[order_c])
        self._sorted_weights = readonly_array(weights[order_c])

    # -- parameters -------------------------------------------------------------------------
    @property
    def alpha(self) -> np.ndarray:
        """Up-switching thresholds α_i (read-only; the relay table's)."""
        return self._relays.alpha

    @property
    def beta(self) -> np.ndarray:
        """Down-switching thresholds β_i (read-only; the relay table's)."""
        return self._relays.beta

    @property
    def weights(self) -> np.ndarray:
        """Weights w_i >= 0, Σ w_i = 1 (read-only; the relay table's)."""
        return self._relays.weights

    @property
    def n_relays(self) -> int:
        return self._relays.n_relays

    @property
    def centre(self) -> np.ndarray:
        """Loop centres s_i = (α_i + β_i)/2."""
        return 0.5 * (self.alpha + self.beta)

    @property
    def half_width(self) -> np.ndarray:
        """Half-widths r_i = (α_i − β_i)/2."""
        return 0.5 * (self.alpha - self.beta)

    @property
    def equal_widths(self) -> bool:
        """All widths α_i − β_i equal within 1e-12·scale: then the model is a play followed by
        the weighted empirical distribution of the centres."""
        return self._equal_widths

    @property
    def order_by_centre(self) -> np.ndarray:
        """Relay indices sorted by centre (stable)."""
        return self._order_c

    @property
    def sorted_centres(self) -> np.ndarray:
        """Centres in increasing order (``centre[order_by_centre]``)."""
        return self._sorted_centres

    @property
    def sorted_weights(self) -> np.ndarray:
        """Weights in the order of ``sorted_centres``."""
        return self._sorted_weights

    @classmethod
    def _from_identification(cls, result: Any, use_measured_only: bool) -> DiscretePreisachModel:
        """:meth:`PreisachModel.from_identification` (the projection builds this class)."""
        return project_identification(result, use_measured_only=use_measured_only).model()

    def __repr__(self) -> str:
        return f"DiscretePreisachModel(n_relays={self.n_relays}, equal_widths={self._equal_widths})"

    def _saturation_input(self) -> float:
        return float(self.alpha.max())

    # -- states -----------------------------------------------------------------------------
    def _make_state(self, stack, cnt_a, cnt_b, top, output) -> PreisachState:
        return PreisachState(
            extrema=readonly_array(stack[2 : top + 1]),
            output=float(output),
            counts_alpha=readonly_array(cnt_a[2 : top + 1], np.int64),
            counts_beta=readonly_array(cnt_b[2 : top + 1], np.int64),
            model_fingerprint=self._fingerprint,
        )

    def initial_state(self, u0: float) -> PreisachState:
        """Rise from negative saturation to ``u0``: relays with ``α <= u0`` are up."""
        u0 = finite_scalar(u0, "u0", MAX_MAGNITUDE)
        pa = int(np.searchsorted(self._alpha_by_a, u0, side="right"))
        pb = int(np.searchsorted(self._beta_by_b, u0, side="right"))
        output = -1.0 + 2.0 * float(self._cum_w_a[pa])
        return PreisachState(
            extrema=readonly_array([u0]),
            output=output,
            counts_alpha=readonly_array([pa], np.int64),
            counts_beta=readonly_array([pb], np.int64),
            model_fingerprint=self._fingerprint,
        )

    def _unpack(self, state: PreisachState, extra: int = 0):
        self._check_state(state)
        if state.counts_alpha is None or state.counts_beta is None:
            raise ValueError("state must be a state of a discrete PreisachModel")
        n = self.n_relays
        depth = state.extrema.size
        if np.shape(state.counts_alpha) != (depth,) or np.shape(state.counts_beta) != (depth,):
            raise ValueError("state is inconsistent: counts and extrema differ in length")
        if state.model_fingerprint is None:
            self._check_foreign_state(state)
        size = state.extrema.size + 2
        cap = size + extra
        vals = np.empty(cap)
        cnt_a = np.empty(cap, dtype=np.int64)
        cnt_b = np.empty(cap, dtype=np.int64)
        vals[:size] = _stack(state)
        cnt_a[:2] = (n, 0)
        cnt_b[:2] = (n, 0)
        cnt_a[2:size] = state.counts_alpha
        cnt_b[2:size] = state.counts_beta
        if cnt_a[size - 1] > n or cnt_b[size - 1] > n:
            raise ValueError("state does not belong to this PreisachModel (relay counts)")
        return vals, cnt_a, cnt_b, size - 1

    def _check_foreign_state(self, state: PreisachState) -> None:
        """Full check of a state without fingerprint (built by hand), once: a reduced
        staircase, relay counts that match this model's thresholds, and the output."""
        e = np.asarray(state.extrema, dtype=np.float64)
        if not np.all(np.isfinite(e)) or float(np.max(np.abs(e))) > MAX_MAGNITUDE:
            raise ValueError("state.extrema must be finite with magnitude <= 1e300")
        if np.any(np.diff(e[0::2]) >= 0) or np.any(np.diff(e[1::2]) <= 0):
            raise ValueError(
                "state.extrema is not a staircase (maxima must decrease, minima increase)"
            )
        if e.size > 1 and np.any(e[1::2] >= e[0::2][: e[1::2].size]):
            raise ValueError("state.extrema is not a staircase (minimum above its maximum)")
        ca = np.searchsorted(self._alpha_by_a, e, side="right")
        cb = np.searchsorted(self._beta_by_b, e, side="right")
        if not (np.array_equal(ca, state.counts_alpha) and np.array_equal(cb, state.counts_beta)):
            raise ValueError(
                "state does not belong to this PreisachModel (its relay counts do not match "
                "this model's thresholds)"
            )
        if self.n_relays * e.size <= 10_000_000:
            up = self.relay_states(state)
            expected = float(np.sum(np.where(up, self.weights, -self.weights)))
            if abs(expected - float(state.output)) > 1e-9:
                raise ValueError(
                    f"state.output {state.output!r} does not match this model in that staircase "
                    f"({expected!r}): the state belongs to another model"
                )

    def apply(self, inputs, state: PreisachState | None = None) -> tuple[np.ndarray, PreisachState]:
        """Outputs for ``inputs`` (1-D, finite, non-empty) from ``state`` (default:
        ``initial_state(inputs[0])``) and the final state. Nothing is mutated."""
        u = as_input_sequence(inputs)
        if state is None:
            state = self.initial_state(float(u[0]))
        self._check_state(state)
        # the stack grows by at most one entry per input and pruning bounds it (module doc)
        capacity = min(state.extrema.size + u.size, 2 * self.n_relays + 8) + 4
        vals, cnt_a, cnt_b, top = self._unpack(state, extra=capacity - state.extrema.size)
        outputs, vals, cnt_a, cnt_b, top, output = _k.discrete_apply(
            u,
            self._alpha_by_a,
            self._beta_key_a,
            self._w_by_a,
            self._table_a,
            self._alpha_key_b,
            self._beta_by_b,
            self._w_by_b,
            self._table_b,
            self._starts_a,
            self._starts_b,
            self._grid,
            vals,
            cnt_a,
            cnt_b,
            top,
            float(state.output),
            _k.lane_mode(),
        )
        if top < 0:  # pragma: no cover - would be a bug in the capacity bound
            raise RuntimeError("Preisach staircase exceeded its capacity bound")
        return outputs, self._make_state(vals, cnt_a, cnt_b, top, output)

    def switching(self, state: PreisachState) -> Switching:
        """Next switching inputs: the output jumps by ``jump_up`` as soon as the input reaches
        ``upper`` (the smallest α among the relays that a rising input switches, respecting the
        staircase) and by ``jump_down`` as soon as it falls below ``lower`` (the largest β among
        the relays a falling input switches). Relays of zero weight are ignored. Cost: one O(1)
        range query per staircase step above (below) the input until one holds a switching
        relay, O(log N) to locate it, O(1 + k) for the k relays sharing that threshold."""
        vals, cnt_a, cnt_b, top = self._unpack(state)
        lower, upper, jump_down, jump_up = _k.discrete_switching(
            self._alpha_by_a,
            self._beta_key_a,
            self._w_by_a,
            self._table_a,
            self._alpha_key_b,
            self._beta_by_b,
            self._w_by_b,
            self._table_b,
            vals,
            cnt_a,
            cnt_b,
            top,
            _k.lane_mode(),
        )
        return Switching(
            lower=float(lower),
            upper=float(upper),
            jump_down=float(jump_down),
            jump_up=float(jump_up),
        )

    def relay_states(self, state: PreisachState) -> np.ndarray:
        """Boolean array (original relay order): which relays are up in ``state``.

        Computed from the staircase alone (O(N · depth), for checks): a relay is up iff its last
        event is an up event, a maximum ``M >= α`` coming after every minimum ``m < β``.
        """
        self._check_state(state)
        last_up = np.full(self.n_relays, -1)
        last_down = np.zeros(self.n_relays, dtype=int)  # the -inf minimum at position 0
        for i, e in enumerate(state.extrema, start=1):
            if i % 2:  # maxima at odd positions (1-based after the sentinel)
                last_up = np.where(e >= self.alpha, i, last_up)
            else:
                last_down = np.where(e < self.beta, i, last_down)
        return last_up > last_down

    def everett(self, a, b) -> np.ndarray:
        """Discrete Everett function ``E(a, b) = Σ_i w_i [α_i <= a and β_i > b]`` for
        ``a >= b`` (O(N) per point; for checks)."""
        a = np.asarray(a, dtype=np.float64)
        b = np.asarray(b, dtype=np.float64)
        aa, bb = np.broadcast_arrays(a, b)
        out = np.empty(aa.shape)
        for idx in np.ndindex(aa.shape):
            if aa[idx] < bb[idx]:
                out[idx] = 0.0
            else:
                mask = (self.alpha <= aa[idx]) & (self.beta > bb[idx])
                out[idx] = float(self.weights[mask].sum())
        return out

    # -- relay contract (oscillators' relay engine) -------------------------------------------
    def relay_table(self) -> RelayTable:
        """The model's relays as a :class:`~hysteresis.relay_table.RelayTable` (same relay
        order; the table the model holds, not a copy)."""
        return self._relays

    def relay_outputs(self, state: PreisachState) -> np.ndarray:
        """Relay outputs ``±1`` (table order) in ``state``; O(N log depth).

        With the staircase ``M_1, m_1, M_2, ...`` a relay is up iff ``alpha <= M_{j+1}`` where
        ``j`` is the number of minima below its ``beta`` (its last down event is at ``m_j``, the
        maxima after it decrease, so only ``M_{j+1}`` can have switched it up since).
        """
        self._check_state(state)
        if state.counts_alpha is None:
            raise ValueError("state must be a state of a discrete PreisachModel")
        maxima = state.maxima
        j = np.searchsorted(state.minima, self.beta, side="left")
        safe = np.minimum(j, maxima.size - 1)
        up = (j < maxima.size) & (self.alpha <= maxima[safe])
        return np.where(up, 1.0, -1.0)

    def state_from_relay_outputs(self, outputs, input: float) -> PreisachState:
        """The state whose relays output ``outputs`` (table order) with the input at ``input``.

        Relays of zero weight never change the output and are not used (their outputs in the
        result follow from the rebuilt staircase). The up relays (positive weight) define the
        threshold function ``g(β) = max{α_i : i up, β_i >= β}``; its steps give the staircase
        ``M_1 = g(-∞), m_1, M_2, ...`` (minima at the β where ``g`` drops), which is driven into
        the model, followed by ``input``. ``ValueError`` if the configuration cannot be reached
        (a down relay with ``α <= g(β)``, an up relay with ``β > input``, a down relay with
        ``α <= input``).
        """
        input = finite_scalar(input, "input")
        y = real_array(outputs, "outputs")
        if y.shape != self.alpha.shape:
            raise ValueError(f"outputs must have length {self.n_relays}, got shape {y.shape}")
        if not np.all((y == 1.0) | (y == -1.0)):
            raise ValueError("outputs must be +1 or -1")
        active = self.weights > 0.0
        table = self.relay_table()
        table.check_outputs(np.where(active, y, table.initial_outputs(input)), input)
        up = active & (y > 0)
        down = active & (y < 0)
        c = self.beta[up]
        order = np.argsort(c, kind="stable")
        c = c[order]
        a = self.alpha[up][order]
        if c.size:
            smax = np.maximum.accumulate(a[::-1])[::-1]
            # g on (c_{l-1}, c_l] is the suffix maximum at the first relay with β = c_l (tie
            # groups of equal β); it drops after group l when the next group's value is
            # smaller (and to -inf after the last group)
            first = np.flatnonzero(np.concatenate([[True], c[1:] > c[:-1]]))
            gval = smax[first]
            ends = np.flatnonzero(np.append(gval[1:], -np.inf) < gval)
            minima = c[first[ends]]
            maxima = np.concatenate([[gval[0]], gval[ends[:-1] + 1]])
            gb = np.searchsorted(c, self.beta[down], side="left")
            g = np.where(gb < c.size, smax[np.minimum(gb, c.size - 1)], -np.inf)
            bad = np.flatnonzero(self.alpha[down] <= g)
            if bad.size:
                i = int(np.flatnonzero(down)[bad[0]])
                raise ValueError(
                    f"outputs are not a reachable relay configuration: relay {i} "
                    f"(alpha={self.alpha[i]}, beta={self.beta[i]}) is down although an up "
                    "relay has a larger alpha and a larger beta"
                )
            history = np.empty(2 * minima.size + 1)
            history[0:-1:2] = maxima
            history[1:-1:2] = minima
            history[-1] = input
            return self.apply(history, self.initial_state(float(history[0])))[1]
        return self.initial_state(input)
