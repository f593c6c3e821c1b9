"""Reversal-curve data, the two FORC conventions, and the measurement protocol.

Conventions
-----------
**Mayergoyz (used internally).** A reversal curve starts in *negative* saturation, rises
monotonically to the reversal input ``α`` and then falls monotonically to ``β <= α``; ``f_αβ`` is
the output on the way down, ``f_α = f_αα``. The Everett function is

    E(α, β) = (f_α − f_αβ) / 2,

and for a Preisach operator ``M = ∬ μ(α, β) y_αβ`` it counts the relays that switched up on the
way to ``α`` and back down on the way to ``β``::

    E(α, β) = Σ_k w_k [α_k <= α] [β_k > β]           (relay conventions of docs/architecture.md)

so that ``μ(α, β) = −∂²E/∂α∂β``. ``E(α, β) = 0`` for ``β >= α`` (nothing can have switched back),
which is the exact constant extension of the measured region used by the identification
(:mod:`analysis.identification.density`).

**Pike (FORC literature).** A curve starts in *positive* saturation, falls to the reversal field
``H_r`` and rises through fields ``H >= H_r``, moment ``M(H_r, H)``; the FORC distribution is
``ρ(H_r, H) = −½ ∂²M/∂H_r∂H``. For a Preisach operator the same relay count gives

    E(α = H, β = H_r) = (M(H_r, H) − M(H_r, H_r)) / 2,   ρ(H_r, H) = μ(α = H, β = H_r),

i.e. Pike's (H, H_r) are Mayergoyz's (α, β) and the FORC coordinates ``H_c = (H − H_r)/2``,
``H_u = (H + H_r)/2`` are the rotated ``r``, ``s``. Both conventions therefore identify the *same*
cell masses for a Preisach operator (:func:`pike_to_preisach`, :func:`preisach_to_pike` convert the
coordinates; :meth:`ReversalCurves.mirrored` maps the data of one experiment onto the other
experiment on the mirror-image operator ``u → −u, y → −y``).

**Rotated coordinates.** ``s = (α+β)/2`` (centre), ``r = (α−β)/2`` (half-width). The Jacobian is
``dα dβ = 2 dr ds``, so a density per unit ``r``-``s`` area is ``μ_rs = 2 μ_αβ`` (the paper's
``μ(s) δ(r − p/2)`` is a density in ``r``-``s``). FORC software usually plots ``ρ(H_c, H_u)`` with
the value of ``ρ(H_r, H)``, i.e. *without* that factor 2.

**Remanence FORCs** (``kind="remanence"``; Zhao et al. 2017, "Magnetic domain state diagnosis
using hysteresis reversal curves"). Every point of a Pike curve is measured back at zero field
after the field ``H`` was reached: ``M_rem(H_r, H)`` is the moment at zero field after positive
saturation → ``H_r`` → ``H`` → 0. For a Preisach operator a relay ``(α, β)`` is up at zero
field iff ``β <= 0`` and (``β <= H_r`` or ``α <= max(H, 0)``), so that

    ρ_rem(H_r, H) = −½ ∂²M_rem/∂H_r∂H = μ(α = H, β = H_r) · [H_r <= 0 <= H],

the in-field density restricted to the relays that are bistable at zero field
(``|H_u| <= H_c``, the remanence carriers; Egli's remanent FORC diagram); it vanishes where
``H_r > 0`` or ``H < 0`` and carries no reversible ridge. The curves are processed exactly like
in-field curves; :attr:`ReversalCurves.kind` says which they are.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from analysis.identification._checks import finite_number, positive_number
from hysteresis._progress import progress_bar
from hysteresis._validation import real_array

__all__ = [
    "ReversalCurves",
    "measure_reversal_curves",
    "preisach_to_pike",
    "pike_to_preisach",
    "regular_grid",
    "protocol_lattice",
]

CONVENTIONS = ("mayergoyz", "pike")
#: what the moments of a set of curves are: measured in the field (the usual FORC) or back at
#: zero field after every field point (remanence FORC, module docstring)
KINDS = ("in-field", "remanence")
#: how results and diagrams name the curves of each kind
KIND_NAMES = {"in-field": "FORC", "remanence": "remanence FORC"}
#: largest number of nodes along one side of the protocol lattice of measured data
#: (:func:`protocol_lattice`; the lattice is square: memory and time grow with the square of the
#: node count). A bound of its own: ``hysteresis._validation.MAX_GRID_NODES`` (2001) limits the
#: grid an *operator* is driven through (:func:`~analysis.identification.identify_preisach`,
#: nodes²/2 operator steps).
MAX_PROTOCOL_NODES = 3000


# ----------------------------------------------------------------------------------------------
# coordinates
# ----------------------------------------------------------------------------------------------
def preisach_to_pike(alpha: Any, beta: Any) -> tuple[np.ndarray, np.ndarray]:
    """Preisach thresholds (α, β) → Pike FORC coordinates (reversal field H_r, field H).

    ``H_r = β``, ``H = α``; the densities agree pointwise, ``ρ(H_r, H) = μ_αβ(α, β)``.
    """
    return real_array(beta, "beta"), real_array(alpha, "alpha")


def pike_to_preisach(reversal_field: Any, field_: Any) -> tuple[np.ndarray, np.ndarray]:
    """Pike FORC coordinates (H_r, H) → Preisach thresholds (α, β) = (H, H_r)."""
    return real_array(field_, "field_"), real_array(reversal_field, "reversal_field")


# ----------------------------------------------------------------------------------------------
# reversal-curve data
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class ReversalCurves:
    """A set of first-order reversal curves.

    Attributes
    ----------
    reversal_field:
        Reversal input of each curve (``α`` for Mayergoyz, ``H_r`` for Pike), shape (n_curves,).
    fields:
        Input values along each curve; the first value is the reversal input itself. Mayergoyz
        curves fall (strictly decreasing), Pike curves rise (strictly increasing).
    moments:
        Output at those inputs (same lengths as ``fields``).
    convention:
        ``"mayergoyz"`` (from negative saturation up to α, down to β) or ``"pike"`` (from
        positive saturation down to H_r, up to H).
    kind:
        ``"in-field"`` (moments measured at the fields) or ``"remanence"`` (each moment
        measured back at zero field after its field; module docstring).
    """

    reversal_field: np.ndarray
    fields: tuple[np.ndarray, ...]
    moments: tuple[np.ndarray, ...]
    convention: str = "mayergoyz"
    kind: str = "in-field"

    def __post_init__(self) -> None:
        if self.convention not in CONVENTIONS:
            raise ValueError(f"convention must be one of {CONVENTIONS}, got {self.convention!r}")
        if self.kind not in KINDS:
            raise ValueError(f"kind must be one of {KINDS}, got {self.kind!r}")
        rev = np.array(self.reversal_field, dtype=float).reshape(-1)
        if len(self.fields) != rev.size or len(self.moments) != rev.size:
            raise ValueError("reversal_field, fields and moments must have one entry per curve")
        if rev.size == 0:
            raise ValueError("at least one reversal curve is needed")
        fields = []
        moments = []
        sign = -1.0 if self.convention == "mayergoyz" else 1.0
        for c, (h, m) in enumerate(zip(self.fields, self.moments, strict=True)):
            h = np.array(h, dtype=float).reshape(-1)
            m = np.array(m, dtype=float).reshape(-1)
            if h.size == 0 or h.size != m.size:
                raise ValueError(f"curve {c}: fields and moments must be non-empty, equal length")
            if not (np.all(np.isfinite(h)) and np.all(np.isfinite(m))):
                raise ValueError(f"curve {c}: fields and moments must be finite (no NaN/inf)")
            if not np.all(sign * np.diff(h) > 0):
                direction = "decrease" if sign < 0 else "increase"
                raise ValueError(
                    f"curve {c}: fields must strictly {direction} along a {self.convention} curve"
                )
            if not math.isclose(h[0], rev[c], rel_tol=1e-9, abs_tol=1e-12):
                raise ValueError(
                    f"curve {c}: the first field ({h[0]}) must equal the reversal field ({rev[c]})"
                )
            h.setflags(write=False)
            m.setflags(write=False)
            fields.append(h)
            moments.append(m)
        if not np.all(np.isfinite(rev)):
            raise ValueError("reversal_field must be finite")
        if np.unique(rev).size != rev.size:
            raise ValueError("reversal fields must be distinct (one curve per reversal field)")
        rev.setflags(write=False)
        object.__setattr__(self, "reversal_field", rev)
        object.__setattr__(self, "fields", tuple(fields))
        object.__setattr__(self, "moments", tuple(moments))

    @property
    def n_curves(self) -> int:
        return int(self.reversal_field.size)

    @property
    def n_points(self) -> int:
        return int(sum(h.size for h in self.fields))

    def mirrored(self) -> ReversalCurves:
        """The same data read as the other experiment on the mirror-image operator.

        ``u → −u``, ``y → −y`` maps a Pike curve (from positive saturation down to ``H_r``, up)
        onto a Mayergoyz curve (from negative saturation up to ``α = −H_r``, down) and back. For an
        operator that is symmetric under the mirror (the erf play, a symmetric Preisach model) the
        mirrored Pike data are the Mayergoyz data of the operator itself.
        """
        other = "pike" if self.convention == "mayergoyz" else "mayergoyz"
        return ReversalCurves(
            -self.reversal_field,
            tuple(-h for h in self.fields),
            tuple(-m for m in self.moments),
            other,
            self.kind,
        )

    def as_rows(self) -> np.ndarray:
        """All points as rows ``(reversal_field, field, moment)``, curve after curve."""
        rows = [
            np.column_stack([np.full(h.size, r), h, m])
            for r, h, m in zip(self.reversal_field, self.fields, self.moments, strict=True)
        ]
        return np.vstack(rows)


def regular_grid(step: float, saturation: float, centre: float = 0.0) -> np.ndarray:
    """Nodes ``centre + k·step`` for ``k = −K … K``, ``K = ⌈saturation/step⌉``.

    The grid covers at least ``[centre − saturation, centre + saturation]``.
    """
    step = positive_number(step, "step")
    saturation = positive_number(saturation, "saturation")
    centre = finite_number(centre, "centre")
    k_max = int(math.ceil(saturation / step - 1e-9))
    return centre + step * np.arange(-k_max, k_max + 1, dtype=float)


def measure_reversal_curves(
    operator: Any,
    reversal_fields: Any,
    fields: Any | None = None,
    convention: str = "mayergoyz",
    saturation: float | None = None,
    progress: bool = False,
) -> ReversalCurves:
    """Drive ``operator`` through first-order reversal curves (one ``apply`` per curve).

    Parameters
    ----------
    operator:
        Any operator with ``initial_state(u0)`` and ``apply(inputs, state)``.
    reversal_fields:
        Reversal inputs (``α`` for Mayergoyz, ``H_r`` for Pike).
    fields:
        Input values at which the curves are sampled (default: the reversal fields themselves).
        Each curve visits the values beyond its reversal field in monotone order, starting with
        the reversal field.
    convention:
        ``"mayergoyz"``: ``initial_state(α)`` (rise from negative saturation), then fall.
        ``"pike"``: ``initial_state(saturation)``, fall to ``H_r``, then rise.
    saturation:
        Positive saturation input for Pike curves (required for ``"pike"``).
    """
    if convention not in CONVENTIONS:
        raise ValueError(f"convention must be one of {CONVENTIONS}, got {convention!r}")
    rev = np.unique(np.asarray(reversal_fields, dtype=float))
    if rev.size == 0 or not np.all(np.isfinite(rev)):
        raise ValueError("reversal_fields must be a non-empty sequence of finite numbers")
    pts = rev if fields is None else np.unique(np.asarray(fields, dtype=float))
    if not np.all(np.isfinite(pts)):
        raise ValueError("fields must be finite")
    if convention == "pike":
        if saturation is None:
            raise ValueError("saturation is required for Pike curves (positive saturation input)")
        saturation = finite_number(saturation, "saturation")
        if saturation < rev.max() or saturation < pts.max():
            raise ValueError("saturation must be >= every reversal field and field (Pike curves)")
    out_fields, out_moments = [], []
    iterator = _progress(rev, progress, "reversal curves")
    for a in iterator:
        if convention == "mayergoyz":
            inputs = np.concatenate([[a], pts[pts < a][::-1]])
            state = operator.initial_state(float(a))
            y, _ = operator.apply(inputs, state)
        else:
            inputs = np.concatenate([[a], pts[pts > a]])
            state = operator.initial_state(float(saturation))
            y, _ = operator.apply(inputs, state)  # first input: monotone fall to H_r
        out_fields.append(inputs)
        out_moments.append(np.asarray(y, dtype=float))
    return ReversalCurves(rev, tuple(out_fields), tuple(out_moments), convention)


def rising_form(curves: ReversalCurves) -> tuple[np.ndarray, list, list]:
    """Curves as rising branches ``(R_c, h, E_c(h))`` with ``h >= R_c``: Pike curves as they
    are, Mayergoyz curves mirrored (``R = −α``, ``h = −β``); ``E`` is the Everett function in
    both cases."""
    if curves.convention == "pike":
        rev = np.asarray(curves.reversal_field)
        fields = list(curves.fields)
        ev = [0.5 * (m - m[0]) for m in curves.moments]
    else:
        rev = -np.asarray(curves.reversal_field)
        fields = [-h for h in curves.fields]
        ev = [0.5 * (m[0] - m) for m in curves.moments]
    return rev, fields, ev


def protocol_lattice(curves: ReversalCurves, step: float | None = None) -> np.ndarray:
    """Regular nodes of the measurement protocol for ``curves``.

    The step is ``step`` or the median increment of the field along the curves; the lattice
    is anchored at the reversal fields (circular mean of their offsets modulo the step, so that
    a regular protocol with slightly drifting measured fields lands on its nominal nodes) and
    spans from the lowest reversal field to the highest field (Pike; mirrored for Mayergoyz).
    """
    rev, fields, _ = rising_form(curves)
    if step is None:
        inc = np.concatenate([np.diff(h) for h in fields])
        if inc.size == 0:
            raise ValueError("every curve has one point: pass the lattice step explicitly")
        step = float(np.median(inc))
    step = positive_number(step, "step")
    phase = np.angle(np.mean(np.exp(2j * np.pi * rev / step)))
    offset = step * phase / (2 * np.pi)
    lo = float(rev.min())
    hi = float(max(h[-1] for h in fields))
    k_lo = int(np.floor((lo - offset) / step + 0.5))
    k_hi = int(np.floor((hi - offset) / step + 0.5))
    if k_hi - k_lo < 1:
        raise ValueError(f"step {step} is larger than the field range of the data")
    if k_hi - k_lo >= MAX_PROTOCOL_NODES:
        # the lattice is square: memory and time grow with the square of the node count
        raise ValueError(
            f"step {step} gives {k_hi - k_lo + 1} nodes (> {MAX_PROTOCOL_NODES}); choose a "
            "larger step"
        )
    return offset + step * np.arange(k_lo, k_hi + 1, dtype=float)


def _progress(seq: Sequence, enabled: bool, desc: str):
    return progress_bar(seq, desc=desc) if enabled else seq
