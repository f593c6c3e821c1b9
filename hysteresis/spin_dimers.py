"""Ensemble of independent ferromagnetic spin dimers at zero temperature (paper Secs. II.B–D).

Each dimer ``k`` has two Ising spins ``σ1, σ2 ∈ {-1, +1}`` with local fields ``b1 >= b2`` (the
columns of ``fields`` are swapped where needed so that the first spin has the larger field, as the
paper assumes "without loss of generality") and the Hamiltonian

    H_k = -J σ1 σ2 - σ1 (q + b1) - σ2 (q + b2),    J = spin_coupling > 0.

Single-spin-flip dynamics: a spin is stable when it points along its local field
``F_i = J σ_partner + q + b_i``; a spin with ``F_i = 0`` counts as pointing up (ties go up), which
matches the relay convention (+1 once ``u >= alpha``, -1 once ``u < beta``).

Thresholds (paper Table I): with ``α = J - b1`` and ``β = -J - b2``

* ``2J > b1 - b2`` (``α > β``): hysteretic, both spins flip up together at ``q = α`` and down
  together below ``q = β``; loop width ``p = 2J - b1 + b2``. One relay of weight ``2/N``.
* ``2J = b1 - b2`` (``α = β``): one reversible jump of both spins at ``α``; a zero-width relay
  of weight ``2/N``.
* ``2J < b1 - b2`` (``α < β``): no hysteresis; the first spin flips reversibly at ``J - b1`` and
  the second at ``-J - b2``: two zero-width relays of weight ``1/N``.

The state ``(σ1, σ2) = (↓, ↑)`` is never metastable for ``b1 >= b2``. The magnetization is
``M = (1/N) Σ σ_i`` over all ``N = 2 n_dimers`` spins.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from numba import njit

from hysteresis._validation import (
    MAX_MAGNITUDE,
    as_generator,
    as_input_sequence,
    bounded_work,
    finite_array,
    positive_integer,
    positive_scalar,
    readonly_array,
    scalar_in_open_interval,
)
from hysteresis.base import PiecewiseConstantHysteron, Switching
from hysteresis.preisach import PreisachModel, PreisachState
from hysteresis.relay_table import RelayTable

__all__ = ["SpinDimerEnsemble", "DimerThresholds", "MAX_SPINS"]

#: largest ensemble :meth:`SpinDimerEnsemble.random` builds (memory ~ 100 bytes per spin)
MAX_SPINS = 100_000_000


@dataclass(frozen=True)
class DimerThresholds:
    """Per-dimer switching inputs (read-only arrays of length ``n_dimers``).

    Attributes
    ----------
    alpha:
        ``J - b1``: where both spins flip up (hysteretic/border) or where the first spin flips
        (non-hysteretic).
    beta:
        ``-J - b2``: where both spins flip down (hysteretic/border) or where the second spin flips
        (non-hysteretic; then ``beta > alpha``).
    hysteretic:
        ``alpha > beta`` (``2J > b1 - b2``): an elementary loop of width ``alpha - beta``.
    paired:
        ``alpha >= beta``: the two spins always flip together (hysteretic or the border case).
    """

    alpha: np.ndarray
    beta: np.ndarray
    hysteretic: np.ndarray
    paired: np.ndarray

    @property
    def centre(self) -> np.ndarray:
        """s = (α + β)/2."""
        return 0.5 * (self.alpha + self.beta)

    @property
    def width(self) -> np.ndarray:
        """p = α − β = 2J − b1 + b2 (negative for non-hysteretic dimers)."""
        return self.alpha - self.beta


@njit(cache=True)
def _spin_flip_kernel(inputs, fields, coupling, spins):  # pragma: no cover - compiled
    """Zero-temperature single-spin-flip dynamics; ``spins`` (int8, length N) is updated in place.

    Plain-Python reading::

        for k, q in enumerate(inputs):
            for each dimer (i, j = 2d, 2d + 1):
                repeat until no spin flips:
                    for spin i in (2d, 2d+1), partner j:
                        F = q + (b[i] + J * spins[j])
                        if (F >= 0) != (spins[i] == +1): spins[i] = -spins[i]
            M[k] = mean(spins)

    Dimers do not interact, so relaxing them one after the other reaches the same metastable
    state as flipping unstable spins anywhere in any order (ferromagnetic J > 0: the flips of a
    dimer all go the same way).
    """
    n = spins.size
    total = 0
    for i in range(n):
        total += spins[i]
    out = np.empty(inputs.size)
    for k in range(inputs.size):
        q = inputs[k]
        for d in range(n // 2):
            while True:
                flipped = False
                for i in range(2 * d, 2 * d + 2):
                    partner = 2 * d + 1 if i == 2 * d else 2 * d
                    # F = q + (b_i + J σ_partner): forming the offset first makes the sign
                    # test exactly "q >= -(b_i + J σ_partner)", the same float as the
                    # thresholds alpha = J - b1, beta = -J - b2 (IEEE rounding is symmetric).
                    local_field = q + (fields[i] + coupling * spins[partner])
                    wanted = 1 if local_field >= 0.0 else -1
                    if wanted != spins[i]:
                        spins[i] = wanted
                        total += 2 * wanted
                        flipped = True
                if not flipped:
                    break
        out[k] = total / n
    return out


#: marks a required argument that follows an optional one (the deprecated alias made J optional)
_REQUIRED: object = object()


def _spin_coupling_alias(spin_coupling: float | None, coupling: float | None) -> float:
    """Resolve the deprecated ``coupling=`` keyword of the spin interaction J."""
    if coupling is not None:
        if spin_coupling is not None:
            raise TypeError("give spin_coupling (J) only; coupling= is its deprecated alias")
        warnings.warn(
            "SpinDimerEnsemble(spin_coupling=...) is deprecated; use spin_coupling= (J)",
            DeprecationWarning,
            stacklevel=3,
        )
        return coupling
    if spin_coupling is None:
        raise TypeError("missing required argument spin_coupling (J > 0)")
    return spin_coupling


class SpinDimerEnsemble(PiecewiseConstantHysteron[PreisachState]):
    """Independent spin dimers: the magnetization ``M[q]`` as a hysteresis operator.

    Parameters
    ----------
    fields:
        Local fields, shape ``(n_dimers, 2)``: row ``k`` is ``(b_{2k-1}, b_{2k})``. Each row is
        ordered so that ``b1 >= b2`` (columns swapped where needed).
    spin_coupling:
        Ferromagnetic spin-spin coupling J > 0 (``coupling=`` is a deprecated alias: in this
        toolkit ``coupling`` means the oscillator's C).

    Notes
    -----
    ``initial_state``/``apply``/``output``/``switching`` use the equivalent discrete Preisach
    model (:meth:`to_preisach`, built once); the state type is that model's state. The
    brute-force spin dynamics, independent of the relay picture, is :meth:`simulate`.
    """

    def __init__(
        self, fields, spin_coupling: float | None = None, *, coupling: float | None = None
    ) -> None:
        spin_coupling = _spin_coupling_alias(spin_coupling, coupling)
        # bounded so that the thresholds J - b1, -J - b2 and the local fields stay finite
        fields = finite_array(fields, "fields", max_abs=MAX_MAGNITUDE)
        if fields.ndim != 2 or fields.shape[1] != 2 or fields.shape[0] < 1:
            raise ValueError(
                f"fields must have shape (n_dimers, 2) with n_dimers >= 1, got {fields.shape}"
            )
        self._spin_coupling = positive_scalar(spin_coupling, "spin_coupling", MAX_MAGNITUDE)
        self._fields = readonly_array(
            np.sort(fields, axis=1)[:, ::-1], None
        )  # b1 >= b2 in every row
        self._preisach = None
        self._relay_table = None

    @classmethod
    def random(
        cls,
        n_spins: int,
        width: float,
        spread: float,
        spin_coupling: float | None = None,
        seed: int | np.random.Generator | None = _REQUIRED,  # type: ignore[assignment]
        *,
        coupling: float | None = None,
    ) -> SpinDimerEnsemble:
        """The paper's disorder: loop width ``p`` fixed, centres ``s_k ~ N(0, R²)``,
        ``b_{2k-1} = -s_k + J - p/2``, ``b_{2k} = -s_k - J + p/2``.

        ``n_spins`` = N (even, >= 2), ``width`` = p with ``0 < p < 2J``, ``spread`` = R > 0,
        ``spin_coupling`` = J > 0 (``coupling=`` is a deprecated alias), ``seed`` (required) a
        non-negative int or a ``numpy.random.Generator``; ``None`` raises ``ValueError`` (no
        irreproducible default).
        """
        spin_coupling = _spin_coupling_alias(spin_coupling, coupling)
        if seed is _REQUIRED:
            raise TypeError("missing required argument seed (int >= 0 or numpy Generator)")
        n_spins = positive_integer(n_spins, "n_spins", minimum=2)
        if n_spins % 2:
            raise ValueError(f"n_spins must be even (pairs of spins), got {n_spins}")
        bounded_work(n_spins, "n_spins", MAX_SPINS, "spins")
        spin_coupling = positive_scalar(spin_coupling, "spin_coupling", MAX_MAGNITUDE)
        width = scalar_in_open_interval(width, "width", 0.0, 2.0 * spin_coupling)
        spread = positive_scalar(spread, "spread", MAX_MAGNITUDE)
        rng = as_generator(seed)
        centres = rng.normal(0.0, spread, size=n_spins // 2)
        b1 = -centres + spin_coupling - 0.5 * width
        b2 = -centres - spin_coupling + 0.5 * width
        return cls(np.column_stack([b1, b2]), spin_coupling)

    # -- parameters -------------------------------------------------------------------------
    @property
    def fields(self) -> np.ndarray:
        """Local fields, shape ``(n_dimers, 2)``, each row ordered ``b1 >= b2``."""
        return self._fields

    @property
    def spin_coupling(self) -> float:
        """J, the spin-spin coupling."""
        return self._spin_coupling

    @property
    def coupling(self) -> float:
        """Deprecated alias of :attr:`spin_coupling` (``coupling`` means C elsewhere)."""
        warnings.warn(
            "SpinDimerEnsemble.coupling is deprecated; use spin_coupling (J)",
            DeprecationWarning,
            stacklevel=2,
        )
        return self._spin_coupling

    @property
    def n_dimers(self) -> int:
        return self._fields.shape[0]

    @property
    def n_spins(self) -> int:
        """N = 2 n_dimers."""
        return 2 * self._fields.shape[0]

    def __repr__(self) -> str:
        return f"SpinDimerEnsemble(n_dimers={self.n_dimers}, spin_coupling={self._spin_coupling!r})"

    # -- relay picture ----------------------------------------------------------------------
    def thresholds(self) -> DimerThresholds:
        """Per-dimer ``alpha = J - b1``, ``beta = -J - b2`` and the classification."""
        b1, b2 = self._fields[:, 0], self._fields[:, 1]
        alpha = self._spin_coupling - b1
        beta = -self._spin_coupling - b2
        return DimerThresholds(
            alpha=readonly_array(alpha, None),
            beta=readonly_array(beta, None),
            hysteretic=readonly_array(alpha > beta, None),
            paired=readonly_array(alpha >= beta, None),
        )

    def relays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(alpha, beta, weights)`` of the equivalent relay system, ``M = Σ w_j y_j``.

        A paired dimer (hysteretic or border) is one relay of weight ``2/N``; a non-hysteretic
        dimer is two zero-width relays at ``J - b1`` and ``-J - b2`` of weight ``1/N`` each.
        """
        th = self.thresholds()
        n = self.n_spins
        paired = th.paired
        single = ~paired
        alpha = np.concatenate([th.alpha[paired], th.alpha[single], th.beta[single]])
        beta = np.concatenate([th.beta[paired], th.alpha[single], th.beta[single]])
        weights = np.concatenate(
            [np.full(int(paired.sum()), 2.0 / n), np.full(2 * int(single.sum()), 1.0 / n)]
        )
        return alpha, beta, weights

    def to_preisach(self):
        """The discrete Preisach model ``PreisachModel.from_relays(*self.relays())`` (cached)."""
        if self._preisach is None:
            self._preisach = PreisachModel.from_relays(*self.relays())
        return self._preisach

    # -- operator contract (through the Preisach model) ---------------------------------------
    def initial_state(self, u0: float):
        return self.to_preisach().initial_state(u0)

    def apply(self, inputs, state=None):
        return self.to_preisach().apply(inputs, state)

    def output(self, state) -> float:
        return self.to_preisach().output(state)

    def switching(self, state) -> Switching:
        return self.to_preisach().switching(state)

    # -- relay contract (oscillators' relay engine) -------------------------------------------
    def relay_table(self):
        """The relays of :meth:`relays` as a :class:`~hysteresis.relay_table.RelayTable`: a
        paired dimer is one relay of weight ``2/N``, a non-hysteretic one two zero-width relays
        of weight ``1/N`` (the order of :meth:`to_preisach`). Built once, straight from
        :meth:`relays`: the Preisach model's search tables are not needed for it (the iid
        reference drives the table's nested plan and never builds the model)."""
        if self._relay_table is None:
            self._relay_table = RelayTable(*self.relays())
        return self._relay_table

    def relay_outputs(self, state) -> np.ndarray:
        """Outputs of the relays of :meth:`relay_table` in ``state``."""
        return self.to_preisach().relay_outputs(state)

    def state_from_relay_outputs(self, outputs, input: float):
        """The state whose relays (order of :meth:`relay_table`) output ``outputs``."""
        return self.to_preisach().state_from_relay_outputs(outputs, input)

    # -- brute force ------------------------------------------------------------------------
    def energy(self, spins, q: float) -> float:
        """Total energy ``H = Σ_k [-J σ1σ2 - σ1(q+b1) - σ2(q+b2)]`` of a spin configuration."""
        s = self._check_spins(spins).astype(np.float64).reshape(-1, 2)
        b = self._fields
        return float(
            np.sum(
                -self._spin_coupling * s[:, 0] * s[:, 1]
                - s[:, 0] * (q + b[:, 0])
                - s[:, 1] * (q + b[:, 1])
            )
        )

    def _check_spins(self, spins) -> np.ndarray:
        s = np.asarray(spins)
        if s.dtype.kind not in "iuf":
            raise ValueError(
                f"spins must be an array of {self.n_spins} values in {{-1, +1}}, got dtype "
                f"{s.dtype}"
            )
        if s.shape != (self.n_spins,) or not np.all(np.isin(s, (-1, 1))):
            raise ValueError(f"spins must be an array of {self.n_spins} values in {{-1, +1}}")
        return s.astype(np.int8)

    def simulate(self, inputs, spins=None) -> tuple[np.ndarray, np.ndarray]:
        """Brute-force single-spin-flip dynamics of the Hamiltonian, independent of the relays.

        Parameters
        ----------
        inputs:
            Sequence of fields q (1-D, finite, non-empty).
        spins:
            Initial spins, length N, ordered ``(σ1, σ2)`` per dimer with σ1 the spin of the larger
            field ``b1``. ``None``: all down. The start is relaxed at ``inputs[0]`` first.

        Returns
        -------
        (M, spins):
            Magnetization after relaxation at each input, and the final spins (int8, length N).
        """
        u = as_input_sequence(inputs)
        start = (
            np.full(self.n_spins, -1, dtype=np.int8)
            if spins is None
            else self._check_spins(spins).copy()
        )
        flat_fields = np.ascontiguousarray(self._fields.reshape(-1))
        magnetization = _spin_flip_kernel(u, flat_fields, self._spin_coupling, start)
        return magnetization, start
