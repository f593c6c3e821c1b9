"""The Preisach model: a weighted superposition of relays (paper Sec. "Preisach model").

Output ``M[u] = Σ_i w_i y_{α_i β_i}[u]`` (discrete, weights summing to 1) or
``M[u] = ∬_{α >= β} μ(α, β) y_{αβ}[u] dα dβ`` (continuous, ``∬ μ = 1``), so ``M ∈ [-1, 1]``.
Relay convention: +1 once ``u >= α``, -1 once ``u < β``, ``α >= β`` (zero width allowed).

Memory (Mayergoyz): the alternating sequence of dominant input extrema left after wiping-out,
``M_1 > M_2 > ...`` (maxima) and ``m_1 < m_2 < ...`` (minima), interleaved
``M_1, m_1, M_2, m_2, ...``; its last entry is the current input. A new input that reaches a
previous maximum (``u >= M_k``) or falls to a previous minimum (``u <= m_k``) wipes out all
extrema after it. :class:`PreisachState` holds this staircase and the output.

Everett function (docs/architecture.md): ``E(α, β) = (f_α − f_αβ)/2`` — half the output drop
when the input rises from negative saturation to ``α`` and then falls to ``β``; equivalently the
mass of the triangle ``{β < β' <= α' <= α}`` of the Preisach plane, and ``μ = −∂²E/∂α∂β``.
With the staircase ``M_1, m_1, ..., `` (``m_0 = −∞``)::

    M = −1 + 2 Σ_k [E(M_k, m_{k−1}) − E(M_k, m_k)]

(the last bracket has only its first term if the last entry is a maximum). In rotated
coordinates ``s = (α+β)/2``, ``r = (α−β)/2`` the density is ``μ_rs(r, s) = 2 μ(s+r, s−r)``.

Discrete model (:meth:`PreisachModel.from_relays`): exact. Per input step: one "count of
thresholds <= u" lookup (uniform bucket grid: O(1) expected, O(log N) worst case), amortised O(1)
staircase updates, and a 3-sided range query costing O(1 + k) range-extremum visits for the k
relays that switch (each visit does bounded work; see :mod:`hysteresis._preisach_kernels`).
Nothing loops over all relays. The staircase is pruned to at most ``2 N + 6`` entries.
Continuous model (:meth:`PreisachModel.from_density`, :meth:`PreisachModel.from_everett`):
amortised O(1) Everett evaluations per step through cached prefix sums along the staircase.
"""

from __future__ import annotations

import functools
import hashlib
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hysteresis._validation import (
    MAX_MAGNITUDE,
    ParameterTypeError,
    as_input_sequence,
    bounded_work,
    check_state_type,
    direction_sign,
    finite_array,
    finite_scalar,
    positive_integer,
    positive_scalar,
)
from hysteresis.base import (
    Branch,
    ContinuousHysteron,
    Hysteron,
    Linearization,
    PiecewiseConstantHysteron,
    Switching,
)
from hysteresis.flow import BranchFlow
from hysteresis.preisach import _kernels as _k
from hysteresis.relay_table import RelayTable

__all__ = [
    "PreisachModel",
    "DiscretePreisachModel",
    "ContinuousPreisachModel",
    "PreisachState",
]

_WEIGHT_TOLERANCE = 1e-9
#: largest ``resolution`` of :meth:`PreisachModel.from_density` (memory ~ 16·resolution²/2)
_MAX_RESOLUTION = 4096


def _fingerprint(*parts: Any) -> int:
    """64-bit digest of a model's defining data; states carry it to find their owner."""
    h = hashlib.blake2b(digest_size=8)
    for part in parts:
        h.update(part if isinstance(part, bytes) else np.ascontiguousarray(part).tobytes())
    return int.from_bytes(h.digest(), "little")


def _readonly(a: Any, dtype=np.float64) -> np.ndarray:
    arr = np.array(a, dtype=dtype)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class PreisachState:
    """Memory of a Preisach model: the staircase of dominant alternating extrema.

    Attributes
    ----------
    extrema:
        Read-only array ``[M_1, m_1, M_2, m_2, ...]`` of the dominant alternating extrema left by
        wiping-out; it starts with a maximum (reached by rising from negative saturation) and
        its last entry is the current input. Maxima strictly decrease, minima strictly increase.
    output:
        The model output ``M`` in this state.
    counts_alpha, counts_beta:
        Discrete model only (internal bookkeeping): number of relays with ``alpha <= e`` and
        ``beta <= e`` for every extremum ``e``.
    prefix:
        Continuous model only (internal): cached Everett prefix sums along the staircase.
    model_fingerprint:
        Fingerprint of the model that made the state (internal): ``apply`` refuses a state of
        another model in O(1). A state built by hand (``None``) is checked in full instead.
    """

    extrema: np.ndarray
    output: float
    counts_alpha: np.ndarray | None = field(default=None, repr=False)
    counts_beta: np.ndarray | None = field(default=None, repr=False)
    prefix: np.ndarray | None = field(default=None, repr=False)
    model_fingerprint: int | None = field(default=None, repr=False)

    @property
    def input(self) -> float:
        """Current input (the last staircase entry)."""
        return float(self.extrema[-1])

    @property
    def maxima(self) -> np.ndarray:
        """Dominant maxima ``M_1 > M_2 > ...`` (the last one may be the current input)."""
        return self.extrema[0::2]

    @property
    def minima(self) -> np.ndarray:
        """Dominant minima ``m_1 < m_2 < ...`` (the last one may be the current input)."""
        return self.extrema[1::2]

    @property
    def rising(self) -> bool:
        """True if the last entry (the current input) is a maximum, i.e. the input last rose."""
        return self.extrema.size % 2 == 1

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, PreisachState):
            return NotImplemented
        return self.output == other.output and np.array_equal(self.extrema, other.extrema)

    __hash__ = None  # type: ignore[assignment]


def _stack(state: PreisachState) -> np.ndarray:
    """Staircase with the two sentinels ``[+inf, -inf, M_1, m_1, ...]`` (a new array)."""
    return np.concatenate([[np.inf, -np.inf], state.extrema])


class PreisachModel(Hysteron):
    """Preisach model. Build it with :meth:`from_relays` (discrete), :meth:`from_density` or
    :meth:`from_everett` (continuous); these return a :class:`DiscretePreisachModel`
    (piecewise constant) or a :class:`ContinuousPreisachModel`.
    """

    # -- constructors ---------------------------------------------------------------------
    @classmethod
    def from_relays(cls, alpha, beta, weights=None) -> DiscretePreisachModel:
        """Discrete model ``M = Σ_i w_i y_{α_i β_i}``.

        ``alpha``, ``beta``: 1-D arrays of equal length N >= 1 with ``alpha >= beta`` and
        magnitudes <= 1e300 (so that centres and widths are finite);
        ``weights``: ``>= 0`` summing to 1 (within 1e-9), default ``1/N`` each. Weights are not
        renormalised: a wrong sum raises ``ValueError``.
        """
        return DiscretePreisachModel(alpha, beta, weights)

    @classmethod
    def from_density(
        cls,
        density: Callable[[np.ndarray, np.ndarray], np.ndarray],
        lower: float,
        upper: float,
        resolution: int = 512,
        mass_tolerance: float = 1e-3,
    ) -> ContinuousPreisachModel:
        """Continuous model with density ``μ(α, β) >= 0`` on ``lower <= β <= α <= upper``.

        ``density`` is a vectorised callable ``(alpha, beta) -> μ``; its mass on the triangle
        must be 1 within ``mass_tolerance`` (otherwise ``ValueError``; the remaining quadrature
        defect is divided out so that saturation is exactly ±1). The Everett function
        is tabulated on a ``resolution × resolution`` grid (Gauss–Legendre cell masses) and
        interpolated bilinearly (error O(h²), ``h = (upper − lower)/resolution``); branch slopes
        use a 1-D Gauss–Legendre quadrature of ``μ`` along the moving edge.
        """
        return ContinuousPreisachModel._from_density(
            density, lower, upper, resolution, mass_tolerance
        )

    @classmethod
    def from_everett(
        cls,
        everett: Callable[[np.ndarray, np.ndarray], np.ndarray],
        lower: float,
        upper: float,
        everett_gradient: Callable | None = None,
    ) -> ContinuousPreisachModel:
        """Continuous model from its Everett function ``E(α, β)`` on ``lower <= β <= α <= upper``.

        ``E(α, β) = (f_α − f_αβ)/2`` (vectorised callable); ``E(α, α) = 0`` and
        ``E(upper, lower) = 1`` (total mass) are checked. ``everett_gradient(a, b)`` may return
        ``(∂E/∂α, ∂E/∂β)``; otherwise central differences are used.
        """
        return ContinuousPreisachModel._from_everett(everett, lower, upper, everett_gradient)

    @classmethod
    def from_identification(
        cls, result: Any, *, use_measured_only: bool = True
    ) -> DiscretePreisachModel:
        """Valid discrete model from an identified (noisy, partly negative) density.

        Non-negative least squares on the cell masses so that the model's Everett function —
        hence its reversal curves — fits the identified one on the measured nodes; one relay
        per cell at its upper corner; weights normalised to sum 1 (the measured output is
        ``offset + K · M[u]`` with ``K`` the fitted total mass). See
        :func:`hysteresis.fitting.project_identification`, which also returns ``K`` and the
        residual.
        """
        from hysteresis.preisach.projection import project_identification

        return project_identification(result, use_measured_only=use_measured_only).model()

    # -- shared -----------------------------------------------------------------------------
    def output(self, state: PreisachState) -> float:
        self._check_state(state)
        return float(state.output)

    def _check_state(self, state: Any) -> None:
        """Type and owner of a state (O(1)); states without a fingerprint are checked in
        full by the subclasses' ``_unpack``."""
        check_state_type(state, PreisachState, self)
        owner = state.model_fingerprint
        if owner is not None and owner != self._fingerprint:
            raise ValueError(
                f"state belongs to another Preisach model (fingerprint {owner:#x}, this model "
                f"{self._fingerprint:#x}); start from this model's initial_state()"
            )
        ext = state.extrema
        if not isinstance(ext, np.ndarray) or ext.ndim != 1 or ext.size == 0:
            raise ValueError("state.extrema must be a non-empty 1-D array")

    def state_from_extrema(self, extrema, saturation: str = "negative") -> PreisachState:
        """State after the input history ``extrema`` (a sequence of turning points).

        ``saturation='negative'``: the history starts by rising from negative saturation to
        ``extrema[0]``; ``'positive'``: it starts by falling from positive saturation.
        Non-alternating or dominated entries are allowed: wiping-out removes them.
        """
        e = as_input_sequence(extrema, "extrema")
        if saturation == "negative":
            return self.apply(e, self.initial_state(float(e[0])))[1]
        if saturation == "positive":
            top = self._saturation_input()
            top = max(top, float(e.max()))
            return self.apply(e, self.initial_state(top))[1]
        raise ValueError(f"saturation must be 'negative' or 'positive', got {saturation!r}")

    def _saturation_input(self) -> float:  # pragma: no cover - overridden
        raise NotImplementedError


# ============================================================================================
# discrete
# ============================================================================================


class DiscretePreisachModel(PreisachModel, PiecewiseConstantHysteron):
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
        self._alpha = _readonly(alpha)
        self._beta = _readonly(beta)
        self._weights = _readonly(weights)
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
        self._table_a = _k.sparse_table_argmax(self._beta_key_a)
        self._table_b = _k.sparse_table_argmin(self._alpha_key_b)
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
        self._order_c = _readonly(order_c, np.int64)
        self._sorted_centres = _readonly(centre[order_c])
        self._sorted_weights = _readonly(weights[order_c])

    # -- parameters -------------------------------------------------------------------------
    @property
    def alpha(self) -> np.ndarray:
        """Up-switching thresholds α_i (read-only)."""
        return self._alpha

    @property
    def beta(self) -> np.ndarray:
        """Down-switching thresholds β_i (read-only)."""
        return self._beta

    @property
    def weights(self) -> np.ndarray:
        """Weights w_i >= 0, Σ w_i = 1 (read-only)."""
        return self._weights

    @property
    def n_relays(self) -> int:
        return int(self._alpha.size)

    @property
    def centre(self) -> np.ndarray:
        """Loop centres s_i = (α_i + β_i)/2."""
        return 0.5 * (self._alpha + self._beta)

    @property
    def half_width(self) -> np.ndarray:
        """Half-widths r_i = (α_i − β_i)/2."""
        return 0.5 * (self._alpha - self._beta)

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

    def __repr__(self) -> str:
        return f"DiscretePreisachModel(n_relays={self.n_relays}, equal_widths={self._equal_widths})"

    def _saturation_input(self) -> float:
        return float(self._alpha.max())

    # -- states -----------------------------------------------------------------------------
    def _make_state(self, stack, cnt_a, cnt_b, top, output) -> PreisachState:
        return PreisachState(
            extrema=_readonly(stack[2 : top + 1]),
            output=float(output),
            counts_alpha=_readonly(cnt_a[2 : top + 1], np.int64),
            counts_beta=_readonly(cnt_b[2 : top + 1], np.int64),
            model_fingerprint=self._fingerprint,
        )

    def initial_state(self, u0: float) -> PreisachState:
        """Rise from negative saturation to ``u0``: relays with ``α <= u0`` are up."""
        u0 = finite_scalar(u0, "u0", MAX_MAGNITUDE)
        pa = int(np.searchsorted(self._alpha_by_a, u0, side="right"))
        pb = int(np.searchsorted(self._beta_by_b, u0, side="right"))
        output = -1.0 + 2.0 * float(self._cum_w_a[pa])
        return PreisachState(
            extrema=_readonly([u0]),
            output=output,
            counts_alpha=_readonly([pa], np.int64),
            counts_beta=_readonly([pb], np.int64),
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
            expected = float(np.sum(np.where(up, self._weights, -self._weights)))
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
                last_up = np.where(e >= self._alpha, i, last_up)
            else:
                last_down = np.where(e < self._beta, i, last_down)
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
                mask = (self._alpha <= aa[idx]) & (self._beta > bb[idx])
                out[idx] = float(self._weights[mask].sum())
        return out

    # -- relay contract (oscillators' relay engine) -------------------------------------------
    def relay_table(self) -> RelayTable:
        """The model as a :class:`~hysteresis.relay_table.RelayTable` (same relay order; cached)."""
        table = self.__dict__.get("_relay_table")
        if table is None:
            table = RelayTable(self._alpha, self._beta, self._weights)
            self.__dict__["_relay_table"] = table
        return table

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
        j = np.searchsorted(state.minima, self._beta, side="left")
        safe = np.minimum(j, maxima.size - 1)
        up = (j < maxima.size) & (self._alpha <= maxima[safe])
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
        y = np.asarray(outputs, dtype=np.float64)
        if y.shape != self._alpha.shape:
            raise ValueError(f"outputs must have length {self.n_relays}, got shape {y.shape}")
        if not np.all((y == 1.0) | (y == -1.0)):
            raise ValueError("outputs must be +1 or -1")
        active = self._weights > 0.0
        table = self.relay_table()
        table.check_outputs(np.where(active, y, table.initial_outputs(input)), input)
        up = active & (y > 0)
        down = active & (y < 0)
        c = self._beta[up]
        order = np.argsort(c, kind="stable")
        c = c[order]
        a = self._alpha[up][order]
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
            gb = np.searchsorted(c, self._beta[down], side="left")
            g = np.where(gb < c.size, smax[np.minimum(gb, c.size - 1)], -np.inf)
            bad = np.flatnonzero(self._alpha[down] <= g)
            if bad.size:
                i = int(np.flatnonzero(down)[bad[0]])
                raise ValueError(
                    f"outputs are not a reachable relay configuration: relay {i} "
                    f"(alpha={self._alpha[i]}, beta={self._beta[i]}) is down although an up "
                    "relay has a larger alpha and a larger beta"
                )
            history = np.empty(2 * minima.size + 1)
            history[0:-1:2] = maxima
            history[1:-1:2] = minima
            history[-1] = input
            return self.apply(history, self.initial_state(float(history[0])))[1]
        return self.initial_state(input)


# ============================================================================================
# continuous
# ============================================================================================


@functools.lru_cache(maxsize=8)
def _gauss(n: int) -> tuple[np.ndarray, np.ndarray]:
    # cached: leggauss solves an eigenvalue problem, and everett_gradient needs the nodes on
    # every call (the oscillator's continuous engine calls it once per integrator stage)
    x, w = np.polynomial.legendre.leggauss(n)
    return _readonly(0.5 * (x + 1.0)), _readonly(0.5 * w)  # on [0, 1]


class ContinuousPreisachModel(PreisachModel, ContinuousHysteron):
    """Preisach model with a density on the triangle ``lower <= β <= α <= upper``.

    Memory variables for :meth:`linearize`: the staircase extrema (see there). Branch slopes are
    ``2 ∂E/∂α(u, m_last)`` on a rising input and ``−2 ∂E/∂β(M_last, u)`` on a falling one.
    """

    def __init__(self, lower: float, upper: float) -> None:
        self._lower = finite_scalar(lower, "lower", MAX_MAGNITUDE)
        self._upper = finite_scalar(upper, "upper", MAX_MAGNITUDE)
        if not self._upper > self._lower:
            raise ValueError(f"upper must be > lower, got lower={lower}, upper={upper}")
        self._everett_fn: Callable = None  # type: ignore[assignment]
        self._gradient_fn: Callable | None = None
        self._density_fn: Callable | None = None

    @property
    def lower(self) -> float:
        return self._lower

    @property
    def upper(self) -> float:
        return self._upper

    def _saturation_input(self) -> float:
        return self._upper

    def __repr__(self) -> str:
        return f"ContinuousPreisachModel(lower={self._lower}, upper={self._upper})"

    # -- construction ------------------------------------------------------------------------
    @classmethod
    def _from_density(cls, density, lower, upper, resolution, mass_tolerance):
        if not callable(density):
            raise ParameterTypeError("density must be a vectorised callable density(alpha, beta)")
        model = cls(lower, upper)
        n = positive_integer(resolution, "resolution", minimum=2)
        # the quadrature holds 16 resolution²/2 density values: bound the memory up front
        bounded_work(n, "resolution", _MAX_RESOLUTION, "grid cells per side")
        mass_tolerance = positive_scalar(mass_tolerance, "mass_tolerance")
        lo, up = model._lower, model._upper
        h = (up - lo) / n
        nodes = lo + h * np.arange(n + 1)
        g, gw = _gauss(4)
        # square cells (alpha-cell i > beta-cell j): tensor Gauss
        ii, jj = np.tril_indices(n, -1)
        qa = nodes[ii][:, None, None] + h * g[None, :, None]
        qb = nodes[jj][:, None, None] + h * g[None, None, :]
        mu = np.asarray(density(*np.broadcast_arrays(qa, qb)), dtype=np.float64)
        if mu.shape != qa.shape[:1] + (g.size, g.size):
            mu = np.broadcast_to(mu, (ii.size, g.size, g.size))
        if not np.all(np.isfinite(mu)) or np.any(mu < 0):
            raise ValueError("density must be finite and >= 0 on lower <= beta <= alpha <= upper")
        sq = h * h * np.einsum("kij,i,j->k", mu, gw, gw)
        # diagonal cells: triangle beta <= alpha, collapsed coordinates
        # alpha = x + h*xi, beta = x + h*xi*eta, Jacobian h^2 xi
        d = np.arange(n)
        ta = nodes[d][:, None, None] + h * g[None, :, None] + 0.0 * g[None, None, :]
        tb = nodes[d][:, None, None] + h * g[None, :, None] * g[None, None, :]
        mu_t = np.asarray(density(ta, tb), dtype=np.float64)
        mu_t = np.broadcast_to(mu_t, ta.shape)
        if not np.all(np.isfinite(mu_t)) or np.any(mu_t < 0):
            raise ValueError("density must be finite and >= 0 on lower <= beta <= alpha <= upper")
        tri = h * h * np.einsum("kij,i,j,i->k", mu_t, gw, gw, g)
        cell = np.zeros((n, n))
        cell[ii, jj] = sq
        cell[d, d] = tri
        total = float(cell.sum())
        if abs(total - 1.0) > mass_tolerance:
            raise ValueError(
                f"density must have mass 1 on the triangle lower <= beta <= alpha <= upper "
                f"(within mass_tolerance={mass_tolerance}), got {total!r}"
            )
        # within the tolerance the small mass defect is quadrature error: divide it out so that
        # saturation is exactly M = ±1
        cell /= total
        model._mass_scale = 1.0 / total
        # E(x_i, x_j) = sum of cells with alpha-cell < i and beta-cell >= j
        table = np.zeros((n + 1, n + 1))
        suffix = np.cumsum(cell[:, ::-1], axis=1)[:, ::-1]  # sum over beta-cells >= j
        table[1:, :n] = np.cumsum(suffix, axis=0)
        model._table = table
        model._h = h
        model._n = n
        model._density_fn = density
        model._everett_fn = model._everett_from_table
        model._gradient_fn = model._gradient_from_density
        model._set_fingerprint()
        return model

    @classmethod
    def _from_everett(cls, everett, lower, upper, everett_gradient):
        if not callable(everett):
            raise ParameterTypeError("everett must be a vectorised callable everett(alpha, beta)")
        if everett_gradient is not None and not callable(everett_gradient):
            raise ParameterTypeError("everett_gradient must be callable or None")
        model = cls(lower, upper)
        lo, up = model._lower, model._upper
        try:
            total_arr = np.asarray(everett(np.array([up]), np.array([lo])))
        except Exception as exc:
            raise ValueError(
                f"everett must accept numpy arrays (a, b); it raised {type(exc).__name__}: {exc}"
            ) from exc
        if total_arr.dtype.kind not in "iuf" or total_arr.shape != (1,):
            raise ValueError(
                "everett must return one real value per (a, b) pair, got "
                f"dtype {total_arr.dtype} shape {total_arr.shape}"
            )
        total = float(total_arr[0])
        if abs(total - 1.0) > 1e-6:
            raise ValueError(
                f"everett must satisfy E(upper, lower) = 1 (total mass), got {total!r}"
            )
        x = np.linspace(lo, up, 11)
        if np.max(np.abs(np.asarray(everett(x, x), dtype=np.float64))) > 1e-9:
            raise ValueError("everett must vanish on the diagonal, E(a, a) = 0")
        model._everett_fn = lambda a, b: np.asarray(everett(a, b), dtype=np.float64)
        model._gradient_fn = everett_gradient
        model._check_everett_probe()
        model._set_fingerprint()
        return model

    def _check_everett_probe(self, nodes: int = 65) -> None:
        """Everett function on a probe grid: finite, one value per pair, and every cell mass
        ``E(a', b) − E(a, b) − E(a', b') + E(a, b') >= 0`` (non-negative density)."""
        x = np.linspace(self._lower, self._upper, nodes)
        a, b = np.meshgrid(x, x, indexing="ij")
        lower = a > b
        values = self._everett_fn(a[lower], b[lower])
        if values.shape != (int(lower.sum()),):
            raise ValueError(
                f"everett must return one value per (a, b) pair, got shape {values.shape}"
            )
        if not np.all(np.isfinite(values)):
            i = int(np.argmax(~np.isfinite(values)))
            raise ValueError(
                f"everett must be finite on lower <= b <= a <= upper, got {values[i]} at "
                f"(a, b) = ({a[lower][i]!r}, {b[lower][i]!r})"
            )
        table = np.zeros((nodes, nodes))
        table[lower] = values
        # cell (a_i, a_{i+1}] x (b_j, b_{j+1}] for j <= i; E = 0 for b >= a
        mass = table[1:, :-1] - table[:-1, :-1] - table[1:, 1:] + table[:-1, 1:]
        cells = np.tril(np.ones_like(mass, dtype=bool))
        tol = 1e-9 * max(1.0, float(np.max(np.abs(values))))
        if np.any(mass[cells] < -tol):
            i, j = np.argwhere(cells & (mass < -tol))[0]
            raise ValueError(
                "everett must be the Everett function of a non-negative density, but the cell "
                f"alpha in ({x[i]:.6g}, {x[i + 1]:.6g}], beta in ({x[j]:.6g}, {x[j + 1]:.6g}] "
                f"has negative mass {mass[i, j]:.3g}"
            )

    def _set_fingerprint(self) -> None:
        x = np.linspace(self._lower, self._upper, 9)
        a, b = np.meshgrid(x, x, indexing="ij")
        self._fingerprint = _fingerprint(
            b"continuous", np.array([self._lower, self._upper]), self.everett(a, b)
        )

    # -- Everett function ----------------------------------------------------------------------
    def _clip(self, a, b):
        a = np.clip(np.asarray(a, dtype=np.float64), self._lower, self._upper)
        b = np.clip(np.asarray(b, dtype=np.float64), self._lower, self._upper)
        return np.broadcast_arrays(a, b)

    def everett(self, a, b) -> np.ndarray:
        """``E(a, b)``: mass of ``{b < β <= α <= a}``; 0 for ``b >= a``. Arguments outside
        ``[lower, upper]`` act as the nearest bound (the density vanishes outside)."""
        a, b = self._clip(a, b)
        out = np.zeros(a.shape)
        mask = a > b
        if np.any(mask):
            out[mask] = self._everett_fn(a[mask], b[mask])
        return out

    def _everett_from_table(self, a, b):
        fa = (a - self._lower) / self._h
        fb = (b - self._lower) / self._h
        i = np.clip(np.floor(fa).astype(np.int64), 0, self._n - 1)
        j = np.clip(np.floor(fb).astype(np.int64), 0, self._n - 1)
        ta = fa - i
        tb = fb - j
        t = self._table
        e = (
            t[i, j] * (1 - ta) * (1 - tb)
            + t[i + 1, j] * ta * (1 - tb)
            + t[i, j + 1] * (1 - ta) * tb
            + t[i + 1, j + 1] * ta * tb
        )
        return np.maximum(e, 0.0)

    def _gradient_from_density(self, a, b):
        # dE/da = ∫_b^a μ(a, β) dβ ; dE/db = -∫_b^a μ(α, b) dα (Gauss–Legendre, 64 points)
        g, gw = _gauss(64)
        span = (a - b)[..., None]
        pts = b[..., None] + span * g
        mu = self._density_fn
        da = np.sum(np.asarray(mu(np.broadcast_to(a[..., None], pts.shape), pts)) * gw, -1)
        db = -np.sum(np.asarray(mu(pts, np.broadcast_to(b[..., None], pts.shape))) * gw, -1)
        scale = self._mass_scale * span[..., 0]
        return da * scale, db * scale

    def everett_gradient(self, a, b) -> tuple[np.ndarray, np.ndarray]:
        """``(∂E/∂α, ∂E/∂β)`` at ``(a, b)``; zero outside the triangle's interior."""
        a0 = np.asarray(a, dtype=np.float64)
        b0 = np.asarray(b, dtype=np.float64)
        a, b = self._clip(a0, b0)
        da = np.zeros(a.shape)
        db = np.zeros(a.shape)
        inside = a > b
        if np.any(inside):
            if self._gradient_fn is not None:
                ga, gb = self._gradient_fn(a[inside], b[inside])
            else:
                step = 1e-6 * (self._upper - self._lower)
                ai, bi = a[inside], b[inside]
                ga = (self._everett_fn(ai + step, bi) - self._everett_fn(ai - step, bi)) / (
                    2 * step
                )
                gb = (self._everett_fn(ai, bi + step) - self._everett_fn(ai, bi - step)) / (
                    2 * step
                )
            da[inside] = ga
            db[inside] = gb
        a_b, b_b = np.broadcast_arrays(a0, b0)
        # beyond the support the Everett function no longer depends on that argument
        da = np.where((a_b < self._lower) | (a_b > self._upper), 0.0, da)
        db = np.where((b_b < self._lower) | (b_b > self._upper), 0.0, db)
        return da, db

    def density(self, alpha, beta) -> np.ndarray:
        """Preisach density ``μ(α, β) = −∂²E/∂α∂β`` (the given callable for
        :meth:`from_density`, central differences of ``E`` for :meth:`from_everett`)."""
        alpha, beta = np.broadcast_arrays(
            np.asarray(alpha, dtype=np.float64), np.asarray(beta, dtype=np.float64)
        )
        if self._density_fn is not None:
            return self._mass_scale * np.asarray(self._density_fn(alpha, beta), dtype=np.float64)
        h = 1e-4 * (self._upper - self._lower)
        e = self._everett_fn
        return -(
            e(alpha + h, beta + h)
            - e(alpha + h, beta - h)
            - e(alpha - h, beta + h)
            + e(alpha - h, beta - h)
        ) / (4 * h * h)

    def density_rs(self, r, s) -> np.ndarray:
        """Density in rotated coordinates ``s = (α+β)/2``, ``r = (α−β)/2``:
        ``μ_rs(r, s) = 2 μ(s + r, s − r)`` (Jacobian of the map (r, s) -> (α, β) is 2)."""
        r = np.asarray(r, dtype=np.float64)
        s = np.asarray(s, dtype=np.float64)
        return 2.0 * self.density(s + r, s - r)

    # -- states ------------------------------------------------------------------------------
    def _terms(self, stack: np.ndarray) -> np.ndarray:
        """Everett term of every stack entry (0 for the sentinels)."""
        terms = np.zeros(stack.size)
        if stack.size > 2:
            idx = np.arange(2, stack.size)
            is_max = idx % 2 == 0
            a = np.where(is_max, stack[idx], stack[idx - 1])
            b = np.where(is_max, stack[idx - 1], stack[idx])
            terms[2:] = np.where(is_max, 1.0, -1.0) * self.everett(a, b)
        return terms

    def initial_state(self, u0: float) -> PreisachState:
        """Rise from negative saturation to ``u0``: ``M = −1 + 2 E(u0, lower)``."""
        u0 = finite_scalar(u0, "u0", MAX_MAGNITUDE)
        stack = np.array([np.inf, -np.inf, u0])
        prefix = np.cumsum(self._terms(stack))
        return PreisachState(
            extrema=_readonly([u0]),
            output=float(-1.0 + 2.0 * prefix[-1]),
            prefix=_readonly(prefix),
            model_fingerprint=self._fingerprint,
        )

    def _unpack(self, state: PreisachState):
        self._check_state(state)
        if state.prefix is None:
            raise ValueError("state must be a state of a continuous PreisachModel")
        prefix = np.asarray(state.prefix, dtype=np.float64)
        if prefix.shape != (state.extrema.size + 2,):
            raise ValueError("state is inconsistent: prefix and extrema differ in length")
        if state.model_fingerprint is None:
            # a state built by hand: its prefix sums must be this model's (O(depth), once)
            e = np.asarray(state.extrema, dtype=np.float64)
            if not np.all(np.isfinite(e)) or float(np.max(np.abs(e))) > MAX_MAGNITUDE:
                raise ValueError("state.extrema must be finite with magnitude <= 1e300")
            expected = np.cumsum(self._terms(_stack(state)))
            if not np.allclose(prefix, expected, rtol=0.0, atol=1e-9):
                raise ValueError("state does not belong to this PreisachModel (prefix sums)")
        return _stack(state), prefix

    def apply(self, inputs, state: PreisachState | None = None) -> tuple[np.ndarray, PreisachState]:
        u = as_input_sequence(inputs)
        if state is None:
            state = self.initial_state(float(u[0]))
        stack, prefix = self._unpack(state)
        top = stack.size - 1
        vals = np.empty(stack.size + u.size + 2)  # at most one new entry per input
        vals[: stack.size] = stack
        refs = np.empty(vals.size, dtype=np.int64)
        refs[: stack.size] = -1 - np.arange(stack.size)
        a, b, sign, base, vals, refs, top = _k.continuous_staircase(u, vals, refs, top)
        terms = sign * self.everett(a, b)
        sums = _k.continuous_accumulate(terms, base, prefix)
        refs = refs[: top + 1]
        final_prefix = np.where(
            refs >= 0, sums[np.maximum(refs, 0)], prefix[np.maximum(-1 - refs, 0)]
        )
        final_prefix[:2] = 0.0
        outputs = -1.0 + 2.0 * sums
        new_state = PreisachState(
            extrema=_readonly(vals[2 : top + 1]),
            output=float(outputs[-1]),
            prefix=_readonly(final_prefix),
            model_fingerprint=self._fingerprint,
        )
        return outputs, new_state

    # -- branch and linearization ----------------------------------------------------------------
    def branch(self, state: PreisachState, direction: int) -> Branch:
        """Branch for a rising (+1) or falling (−1) input.

        Rising: ``slope = 2 ∂E/∂α(u, m)`` with ``m`` the last minimum (``m = u`` right after a
        reversal, where the slope vanishes for a bounded density); breakpoint: the previous
        maximum, where wiping-out changes the branch (``+inf`` if none). Falling: mirror image,
        ``slope = −2 ∂E/∂β(M, u)``, breakpoint the previous minimum.
        """
        direction = direction_sign(direction)
        stack, _ = self._unpack(state)
        top = stack.size - 1
        u = stack[top]
        is_max = top % 2 == 0
        if direction > 0:
            m = stack[top - 1] if is_max else u
            bp = stack[top - 2] if is_max else stack[top - 1]
            da, _ = self.everett_gradient(u, m)
            slope = 2.0 * float(da)
        else:
            big = u if is_max else stack[top - 1]
            bp = stack[top - 1] if is_max else stack[top - 2]
            _, db = self.everett_gradient(big, u)
            slope = -2.0 * float(db)
        return Branch(value=float(state.output), slope=slope, breakpoint=float(bp))

    def linearize(self, state: PreisachState, direction: int) -> Linearization:
        """Derivatives of ``M = −1 + 2 Σ_k ±E(pair_k)`` on the branch in ``direction``.

        Memory variables: the completed extrema. Continuing in the direction of the last
        monotone segment they are ``extrema[:-1]`` (the last entry is the input itself); on a
        reversal the current input becomes a turning point, so they are all of ``extrema``.
        All memory variables are frozen (``slaved`` all False, nothing reset); wiping-out at
        :meth:`branch`'s breakpoint removes memory variables.
        """
        direction = direction_sign(direction)
        stack, _ = self._unpack(state)
        u = stack[-1]
        is_max = (stack.size - 1) % 2 == 0
        reversing = (direction > 0) != is_max
        if reversing:
            stack = np.append(stack, u)
        n = stack.size
        grad = np.zeros(n)
        for i in range(2, n):
            if i % 2 == 0:  # +E(e_i, e_{i-1})
                da, db = self.everett_gradient(stack[i], stack[i - 1])
                grad[i] += 2.0 * float(da)
                grad[i - 1] += 2.0 * float(db)
            else:  # -E(e_{i-1}, e_i)
                da, db = self.everett_gradient(stack[i - 1], stack[i])
                grad[i - 1] -= 2.0 * float(da)
                grad[i] -= 2.0 * float(db)
        memory = grad[2 : n - 1]
        return Linearization(
            d_output_d_input=float(grad[n - 1]),
            d_output_d_memory=memory.copy(),
            slaved=np.zeros(memory.size, dtype=bool),
            reset_on_leave=np.zeros(0, dtype=np.int64),
        )

    # -- branch flow for the oscillator's continuous engine ------------------------------------
    @staticmethod
    def extremum_label(index: int) -> str:
        """Memory label of ``extrema[index]``: ``"M1", "m1", "M2", "m2", ...``."""
        return f"M{index // 2 + 1}" if index % 2 == 0 else f"m{index // 2 + 1}"

    def branch_flow(self, state: PreisachState, direction: int) -> BranchFlow:
        """The branch in ``direction`` as a :class:`~hysteresis.flow.BranchFlow`.

        Memory: the remembered extrema (labels :meth:`extremum_label`), all frozen. Continuing
        the last monotone segment they are ``extrema[:-1]``; reversing, the current input
        becomes a new extremum (flagged ``pushed``, ``δm := δu``) and the memory is all of
        ``extrema``. With ``m`` the last memory variable (partner of the moving input) and
        ``c`` the Everett prefix sum up to it, the output is
        ``y(u) = −1 + 2c + 2E(u, m)`` rising and ``y(u) = −1 + 2c − 2E(m, u)`` falling, so
        ``∂y/∂u = 2∂E/∂α(u, m)`` / ``−2∂E/∂β(m, u)``; ``∂y/∂m_j`` is constant for every
        extremum but ``m``, which adds ``2∂E/∂β(u, m)`` / ``−2∂E/∂α(m, u)``
        (:meth:`everett_gradient`). Breakpoint: the previous extremum of the moving input's
        kind; reaching it wipes it out together with ``m`` (``breakpoint_removes``). A reversal
        pushes the reversal input (``reversal_pushes``).
        """
        direction = direction_sign(direction)
        stack, prefix = self._unpack(state)
        top = stack.size - 1
        rising_state = top % 2 == 0
        reversing = (direction > 0) != rising_state
        partner = top if reversing else top - 1  # stack index of the memory variable m
        n_mem = partner - 1  # stack indices 2 .. partner
        memory = stack[2 : partner + 1].copy()
        labels = tuple(self.extremum_label(k) for k in range(n_mem))
        pushed = np.zeros(n_mem, dtype=bool)
        if reversing:
            pushed[-1] = True
        # constant gradient of the Everett terms that do not involve the moving input
        grad0 = np.zeros(stack.size)
        if partner >= 2:
            idx = np.arange(2, partner + 1)
            even = idx % 2 == 0
            a = np.where(even, stack[idx], stack[idx - 1])
            b = np.where(even, stack[idx - 1], stack[idx])
            da, db = self.everett_gradient(a, b)
            sign = np.where(even, 2.0, -2.0)
            np.add.at(grad0, np.where(even, idx, idx - 1), sign * da)
            np.add.at(grad0, np.where(even, idx - 1, idx), sign * db)
        grad0 = grad0[2 : partner + 1]
        m = float(stack[partner])
        base = -1.0 + 2.0 * float(prefix[partner])
        k_last = n_mem - 1
        everett, gradient = self._scalar_everett(), self._scalar_gradient()
        if direction > 0:

            def output(u):
                return base + 2.0 * everett(u, m)

            def partials(u):
                ea, eb = gradient(u, m)
                u = np.asarray(u, dtype=np.float64)
                d_m = np.broadcast_to(grad0, u.shape + grad0.shape).copy()
                if k_last >= 0:
                    d_m[..., k_last] += 2.0 * eb
                return 2.0 * ea, d_m

        else:

            def output(u):
                return base - 2.0 * everett(m, u)

            def partials(u):
                ea, eb = gradient(m, u)
                u = np.asarray(u, dtype=np.float64)
                d_m = np.broadcast_to(grad0, u.shape + grad0.shape).copy()
                if k_last >= 0:
                    d_m[..., k_last] -= 2.0 * ea
                return -2.0 * eb, d_m

        bp_index = partner - 1
        breakpoint = float(stack[bp_index])
        removes = tuple(labels[i - 2] for i in (bp_index, partner) if i >= 2)
        return BranchFlow(
            direction=direction,
            input=float(stack[top]),
            labels=labels,
            memory=memory,
            slaved=np.zeros(n_mem, dtype=bool),
            output=output,
            partials=partials,
            breakpoint=breakpoint,
            breakpoint_removes=removes if np.isfinite(breakpoint) else (),
            reversal_pushes=True,
            pushed=pushed,
        )

    def _scalar_everett(self) -> Callable:
        """``everett`` with a fast path for scalar arguments (same arithmetic as the tabulated
        bilinear interpolation, so the result is identical; the engine calls it per stage)."""
        vector = self.everett
        fast = getattr(self, "_fast_scalar", None)
        if fast is not None:
            everett_scalar = fast[0]

            def everett_fast(a, b):
                if isinstance(a, float) and isinstance(b, float):
                    return everett_scalar(a, b)
                return vector(a, b)[()]

            return everett_fast
        if getattr(self, "_table", None) is None:

            def everett_any(a, b):
                return vector(a, b)[()]

            return everett_any
        rows = self.__dict__.get("_table_rows")
        if rows is None:
            rows = self._table.tolist()
            self._table_rows = rows
        lo, up, h, n = self._lower, self._upper, self._h, self._n

        def everett(a, b):
            if not (isinstance(a, float) and isinstance(b, float)):
                return vector(a, b)[()]
            a = min(max(a, lo), up)
            b = min(max(b, lo), up)
            if not a > b:
                return 0.0
            fa = (a - lo) / h
            fb = (b - lo) / h
            i = min(max(math.floor(fa), 0), n - 1)
            j = min(max(math.floor(fb), 0), n - 1)
            ta = fa - i
            tb = fb - j
            r0, r1 = rows[i], rows[i + 1]
            e = (
                r0[j] * (1 - ta) * (1 - tb)
                + r1[j] * ta * (1 - tb)
                + r0[j + 1] * (1 - ta) * tb
                + r1[j + 1] * ta * tb
            )
            return max(e, 0.0)

        return everett

    def _scalar_gradient(self) -> Callable:
        """``everett_gradient`` with a fast path for scalar arguments of a density model."""
        vector = self.everett_gradient

        def gradient_any(a, b):
            da, db = vector(a, b)
            return da[()], db[()]

        fast = getattr(self, "_fast_scalar", None)
        if fast is not None:
            gradient_scalar = fast[1]

            def gradient_fast(a, b):
                if isinstance(a, float) and isinstance(b, float):
                    return gradient_scalar(a, b)
                return gradient_any(a, b)

            return gradient_fast
        if self._density_fn is None or self._gradient_fn != self._gradient_from_density:
            return gradient_any
        nodes, weights = _gauss(64)
        mu = self._density_fn
        lo, up, scale = self._lower, self._upper, self._mass_scale

        def gradient(a0, b0):
            if not (isinstance(a0, float) and isinstance(b0, float)):
                return gradient_any(a0, b0)
            a = min(max(a0, lo), up)
            b = min(max(b0, lo), up)
            if not a > b:
                return 0.0, 0.0
            span = a - b
            pts = b + span * nodes
            da = 0.0
            db = 0.0
            if lo <= a0 <= up:
                da = float(np.dot(np.asarray(mu(np.full(pts.shape, a), pts)), weights))
            if lo <= b0 <= up:
                db = -float(np.dot(np.asarray(mu(pts, np.full(pts.shape, b))), weights))
            return da * scale * span, db * scale * span

        return gradient

    @classmethod
    def gaussian(
        cls,
        width: float = 2.0,
        spread: float = 1.0,
        width_spread: float = 0.1,
        nodes: int = 48,
    ) -> ContinuousPreisachModel:
        """Density ``N(s; 0, R²)·N(r; p/2, σ_r²)`` in rotated coordinates (paper eq. pdens_sr
        with the ridge ``δ(r − p/2)`` widened to a normal law of the half-width ``r``).

        ``width`` = p > 0, ``spread`` = R > 0, ``width_spread`` = σ_r > 0. The width law is
        cut at ``r >= 0`` and the model renormalised to mass 1 (a change only if σ_r is not
        small against p/2). The Everett function is smooth and computed by ``nodes``-point
        Gauss–Legendre quadrature of the one remaining integral,

            E(a, b) = ∫_0^{(a−b)/2} N(r; p/2, σ_r²) [Φ((a − r)/R) − Φ((b + r)/R)] dr

        (``Φ`` the standard normal CDF), restricted to ``|r − p/2| <= 8σ_r``; its gradient
        ``∂E/∂a = ∫ N(r) φ((a − r)/R)/R dr``, ``∂E/∂b = −∫ N(r) φ((b + r)/R)/R dr`` likewise
        (the integrand vanishes at the moving limit). As σ_r → 0 the model tends to the
        generalized play ``GeneralizedPlay.erf(p, R)`` (paper: the thermodynamic limit).
        Support ``[−L, L]`` with ``L = p/2 + 8σ_r + 9R``.
        """
        from scipy.special import ndtr

        width = positive_scalar(width, "width")
        spread = positive_scalar(spread, "spread")
        width_spread = positive_scalar(width_spread, "width_spread")
        n = positive_integer(nodes, "nodes", minimum=4)
        half = 0.5 * width
        r_lo = max(0.0, half - 8.0 * width_spread)
        r_hi = half + 8.0 * width_spread
        bound = r_hi + 9.0 * spread
        g, gw = _gauss(n)
        norm_r = 1.0 / (width_spread * math.sqrt(2.0 * math.pi))
        norm_s = 1.0 / (spread * math.sqrt(2.0 * math.pi))

        def _nodes(a, b):
            a, b = np.broadcast_arrays(
                np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
            )
            top = np.clip(0.5 * (a - b), r_lo, r_hi)
            span = (top - r_lo)[..., None]
            r = r_lo + span * g
            wr = span * gw * norm_r * np.exp(-0.5 * ((r - half) / width_spread) ** 2)
            return a[..., None], b[..., None], r, wr

        def raw(a, b):
            a, b, r, wr = _nodes(a, b)
            return np.sum(wr * (ndtr((a - r) / spread) - ndtr((b + r) / spread)), axis=-1)

        total = float(raw(bound, -bound))

        def everett(a, b):
            return raw(a, b) / total

        def gradient(a, b):
            a, b, r, wr = _nodes(a, b)
            da = np.sum(wr * np.exp(-0.5 * ((a - r) / spread) ** 2), axis=-1) * norm_s
            db = -np.sum(wr * np.exp(-0.5 * ((b + r) / spread) ** 2), axis=-1) * norm_s
            return da / total, db / total

        def weights_at(a, b):
            top = min(max(0.5 * (a - b), r_lo), r_hi)
            span = top - r_lo
            r = r_lo + span * g
            return r, span * gw * norm_r * np.exp(-0.5 * ((r - half) / width_spread) ** 2)

        # scalar fast paths with the semantics of everett()/everett_gradient() (arguments
        # clipped to the support, zero off the triangle): the oscillator engine evaluates them
        # once per integrator stage
        def everett_scalar(a, b):
            a = min(max(a, -bound), bound)
            b = min(max(b, -bound), bound)
            if not a > b:
                return 0.0
            r, wr = weights_at(a, b)
            return float(np.dot(wr, ndtr((a - r) / spread) - ndtr((b + r) / spread))) / total

        def gradient_scalar(a0, b0):
            a = min(max(a0, -bound), bound)
            b = min(max(b0, -bound), bound)
            if not a > b:
                return 0.0, 0.0
            r, wr = weights_at(a, b)
            da = db = 0.0
            if -bound <= a0 <= bound:
                da = float(np.dot(wr, np.exp(-0.5 * ((a - r) / spread) ** 2))) * norm_s / total
            if -bound <= b0 <= bound:
                db = -float(np.dot(wr, np.exp(-0.5 * ((b + r) / spread) ** 2))) * norm_s / total
            return da, db

        model = cls._from_everett(everett, -bound, bound, gradient)
        model._gaussian = (width, spread, width_spread)
        model._fast_scalar = (everett_scalar, gradient_scalar)
        return model
