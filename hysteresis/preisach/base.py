"""The Preisach model: a weighted superposition of relays (paper Sec. "Preisach model").

This module holds what both models share: the abstract :class:`PreisachModel` with its factories,
the state :class:`PreisachState` and small helpers. The discrete model lives in
:mod:`hysteresis.preisach.discrete`, the continuous one in :mod:`hysteresis.preisach.continuous`.

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
relays that switch (each visit does bounded work; see :mod:`hysteresis.preisach._kernels`).
Nothing loops over all relays. The staircase is pruned to at most ``2 N + 6`` entries.
Continuous model (:meth:`PreisachModel.from_density`, :meth:`PreisachModel.from_everett`):
amortised O(1) Everett evaluations per step through cached prefix sums along the staircase.
"""

from __future__ import annotations

import functools
import hashlib
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from hysteresis._validation import (
    as_input_sequence,
    check_state_type,
    frozen_state_reduce,
    readonly_array,
)
from hysteresis.base import Hysteron

__all__ = ["PreisachModel", "PreisachState"]


def _fingerprint(*parts: Any) -> int:
    """64-bit digest of a model's defining data; states carry it to find their owner."""
    h = hashlib.blake2b(digest_size=8)
    for part in parts:
        h.update(part if isinstance(part, bytes) else np.ascontiguousarray(part).tobytes())
    return int.from_bytes(h.digest(), "little")


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

    def __reduce__(self) -> tuple:
        return frozen_state_reduce(self)


def _stack(state: PreisachState) -> np.ndarray:
    """Staircase with the two sentinels ``[+inf, -inf, M_1, m_1, ...]`` (a new array)."""
    return np.concatenate([[np.inf, -np.inf], state.extrema])


@functools.lru_cache(maxsize=8)
def _gauss(n: int) -> tuple[np.ndarray, np.ndarray]:
    # cached: leggauss solves an eigenvalue problem, and everett_gradient needs the nodes on
    # every call (the oscillator's continuous engine calls it once per integrator stage)
    x, w = np.polynomial.legendre.leggauss(n)
    return readonly_array(0.5 * (x + 1.0)), readonly_array(0.5 * w)  # on [0, 1]


class PreisachModel(Hysteron[PreisachState]):
    """Preisach model. Build it with :meth:`from_relays` (discrete), :meth:`from_density` or
    :meth:`from_everett` (continuous); these return a :class:`DiscretePreisachModel`
    (piecewise constant) or a :class:`ContinuousPreisachModel`.

    The concrete models register under a kind (``class DiscretePreisachModel(PreisachModel,
    ..., kind="discrete")``), so the factories here build them without this module importing
    theirs (which import this one).
    """

    #: concrete model classes by kind ("discrete", "continuous"), filled by __init_subclass__
    _kinds: ClassVar[dict[str, type[PreisachModel]]] = {}

    def __init_subclass__(cls, kind: str | None = None, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if kind is not None:
            PreisachModel._kinds[kind] = cls

    # -- constructors ---------------------------------------------------------------------
    @classmethod
    def from_relays(cls, alpha, beta, weights=None) -> PreisachModel:
        """Discrete model ``M = Σ_i w_i y_{α_i β_i}``.

        ``alpha``, ``beta``: 1-D arrays of equal length N >= 1 with ``alpha >= beta`` and
        magnitudes <= 1e300 (so that centres and widths are finite);
        ``weights``: ``>= 0`` summing to 1 (within 1e-9), default ``1/N`` each. Weights are not
        renormalised: a wrong sum raises ``ValueError``.
        """
        return PreisachModel._kinds["discrete"](alpha, beta, weights)

    @classmethod
    def from_density(
        cls,
        density: Callable[[np.ndarray, np.ndarray], np.ndarray],
        lower: float,
        upper: float,
        resolution: int = 512,
        mass_tolerance: float = 1e-3,
    ) -> PreisachModel:
        """Continuous model with density ``μ(α, β) >= 0`` on ``lower <= β <= α <= upper``.

        ``density`` is a vectorised callable ``(alpha, beta) -> μ``; its mass on the triangle
        must be 1 within ``mass_tolerance`` (otherwise ``ValueError``; the remaining quadrature
        defect is divided out so that saturation is exactly ±1). The Everett function is
        tabulated on a ``resolution × resolution`` grid (nodal ``E``, ``∂E/∂α``, ``∂E/∂β`` by
        Gauss–Legendre quadrature, ``∂²E/∂α∂β = −μ``) and interpolated by C¹ bicubic Hermite
        polynomials: ``everett`` and ``everett_gradient`` are one function (the gradient is the
        derivative of ``E``), with error ``O(h⁴)`` off the diagonal cells and ``O(h³)`` in them
        (``h = (upper − lower)/resolution``; the bounds in
        :mod:`hysteresis.preisach.everett_table`), ``E → 0`` exactly as ``β → α``. The same
        table is the model's :meth:`compiled_everett`. Memory ``32 (resolution + 1)²`` bytes.
        """
        return PreisachModel._kinds["continuous"]._from_density(
            density, lower, upper, resolution, mass_tolerance
        )

    @classmethod
    def from_everett(
        cls,
        everett: Callable[[np.ndarray, np.ndarray], np.ndarray],
        lower: float,
        upper: float,
        everett_gradient: Callable | None = None,
    ) -> PreisachModel:
        """Continuous model from its Everett function ``E(α, β)`` on ``lower <= β <= α <= upper``.

        ``E(α, β) = (f_α − f_αβ)/2`` (vectorised callable); ``E(α, α) = 0`` and
        ``E(upper, lower) = 1`` (total mass) are checked. ``everett_gradient(a, b)`` may return
        ``(∂E/∂α, ∂E/∂β)``; otherwise central differences are used.

        The model pickles when its callables do (module-level functions, not lambdas); the
        same holds for the ``density`` of :meth:`from_density`.
        """
        kind = PreisachModel._kinds["continuous"]
        return kind._from_everett(everett, lower, upper, everett_gradient)

    @classmethod
    def from_identification(cls, result: Any, *, use_measured_only: bool = True) -> PreisachModel:
        """Valid discrete model from an identified (noisy, partly negative) density.

        Non-negative least squares on the cell masses so that the model's Everett function —
        hence its reversal curves — fits the identified one on the measured nodes; one relay
        per cell at its upper corner; weights normalised to sum 1 (the measured output is
        ``offset + K · M[u]`` with ``K`` the fitted total mass). See
        :func:`hysteresis.preisach.projection.project_identification`, which also returns ``K``
        and the residual.
        """
        kind = PreisachModel._kinds["discrete"]
        return kind._from_identification(result, use_measured_only=use_measured_only)

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
