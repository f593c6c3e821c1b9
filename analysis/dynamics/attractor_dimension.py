"""The attractor's Kaplan–Yorke dimension where neutral memory directions spoil the full-space one.

The tangent space of a continuous operator holds its memory directions
(``("q", "v", *memory)``, :mod:`oscillators.engines.continuous`). A memory direction that lives
across QR intervals (a remembered extremum of a continuous Preisach staircase, a
Prandtl–Ishlinskii wagon strictly inside its play) is frozen, ``δm' = 0``: it carries its
perturbation unchanged, an exponent 0 while it lives. Such *neutral* directions outrank the
contraction of the ``(q, v)`` motion, and when one is wiped out the loop marks the last slot
``-inf`` — the contraction's. The full-space ``D_KY`` then counts neutral directions as
dimensions: the Gaussian width-disorder Preisach model at C = 4 gives λ = (0.077, −0.004, −inf, …)
or (0.077, −inf, …), D_KY = 2.0 or 1.0 per run, while the box-counting dimension of its section
is 1.34–1.44 (``docs/width_disorder``). The exponents of the motion without long-lived memory
(:func:`~analysis.dynamics.memory.memory_frozen_exponents`) give D_KY = 1.38–1.42 there, the
attractor's dimension. :func:`attractor_dimension` reports that value where neutral memory
exists and the full-space value everywhere else, with both named.

**When neutral memory exists** (:func:`has_neutral_memory`) is measured, structurally and
exactly, on the same start: a memory direction was carried unchanged through a whole projection
interval of the memory-frozen run (``zeroed_mean > 0``, read off the survival probe of
:class:`~analysis.dynamics.memory.MemoryProjectionStepper`: a probe column exactly 1 on every
memory row at the interval's start, still exactly 1 only on a row the engine never wrote). Such
a direction is frozen, ``δm' = 0``, its exponent 0 through the interval: neutral by
construction, not by a threshold. The full spectrum is computed first; the second run happens
only if its tangent space has memory rows (at the start or at the end of the run).

Why not the full spectrum's exponents: they are attached to no coordinate, and neutral memory
does not always leave a finite memory exponent or a zero. In the Preisach runs above every
memory slot ends ``-inf`` (so "memory exponents finite rather than -inf" sees nothing) while the
slot next to ``λ_max`` holds a mixture (−0.004 … −0.09 at C = 4; zero within its block error or
not, depending on the run length and on how many vectors were tracked: a start without extrema
tracks two), or the contraction is gone altogether (``(0.077, −inf, …)``). A zero within errors
would also flag the edge of chaos (``λ_max ≈ 0``, the attractor's own), and a comparison of the
full spectrum with the memory-frozen one within their errors misses the distortion at short runs
(at t = 1500 with the phase followed: ``−0.11 ± 0.05`` against ``−0.19``). A play's ``w`` is
reset at every wall hit (``δw := δq``) and dragged (slaved) between: in the erf play at C = 2.9
and 4 no ``w`` is carried unchanged through a whole forcing period (``zeroed_mean = 0`` over
2000 periods), so the paper's systems keep the full-space value (relays and dimers have no memory
rows and skip the second run). Where a wagon does rest inside its play for a period, the
memory-frozen value is reported; it then differs from the full-space one only by the dropped
rests.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from analysis.dynamics.dimensions import kaplan_yorke_dimension
from analysis.dynamics.lyapunov import LyapunovResult, TangentStepper, lyapunov_spectrum
from analysis.dynamics.memory import (
    MemoryFrozenResult,
    kaplan_yorke_block_error,
    memory_frozen_exponents,
)
from hysteresis._validation import positive_integer, time_window
from oscillators import DEFAULT_Q0, DEFAULT_V0

__all__ = ["AttractorDimension", "attractor_dimension", "has_neutral_memory"]

#: the ways :attr:`AttractorDimension.kaplan_yorke` is obtained (the last: memory rows, but the
#: window is shorter than one projection interval, so neutral memory cannot be tested)
MEMORY_FROZEN, FULL_SPACE, UNTESTED = "memory-frozen", "full space", "full space, untested"

_EXPLANATION = {
    MEMORY_FROZEN: "D_KY of the memory-frozen exponents: the full tangent space holds neutral "
    "memory directions (frozen extrema or wagons, exponent 0 while they live), which distort "
    "the full-space D_KY (they outrank the contraction, and a wiped-out one takes its slot)",
    FULL_SPACE: "D_KY of the full spectrum: no neutral memory direction",
    UNTESTED: "D_KY of the full spectrum: the window is shorter than one projection interval, "
    "too short to test for neutral memory directions",
}


@dataclass(frozen=True)
class AttractorDimension:
    """Outcome of :func:`attractor_dimension`.

    Attributes
    ----------
    kaplan_yorke:
        The attractor's ``D_KY``: of the memory-frozen exponents if :attr:`neutral_memory`,
        else of the full spectrum (then equal to ``spectrum.kaplan_yorke``).
    kaplan_yorke_error:
        Its finite-time error (jackknife over ``blocks`` batches,
        :func:`~analysis.dynamics.memory.kaplan_yorke_block_error`; nan if the run is too short).
    kaplan_yorke_full_space:
        ``D_KY`` of the full spectrum in ``(q, v[, phi], memory)`` (``spectrum.kaplan_yorke``).
    source:
        ``"memory-frozen"`` or ``"full space"``: which spectrum :attr:`kaplan_yorke` is from
        (``"full space, untested"``: memory rows, but a window shorter than one projection
        interval).
    neutral_memory:
        Whether the full spectrum holds neutral memory directions (:func:`has_neutral_memory`).
    spectrum:
        The full :class:`~analysis.dynamics.lyapunov.LyapunovResult`.
    frozen:
        The :class:`~analysis.dynamics.memory.MemoryFrozenResult` of the same start (None if the
        tangent space never had memory rows: relays, dimers). ``blocks`` batches give both
        runs' finite-time errors.
    """

    kaplan_yorke: float
    kaplan_yorke_error: float
    kaplan_yorke_full_space: float
    source: str
    neutral_memory: bool
    spectrum: LyapunovResult
    frozen: MemoryFrozenResult | None

    @property
    def exponents(self) -> np.ndarray:
        """The exponents :attr:`kaplan_yorke` is computed from (with the phase's 0 if the
        spectrum follows the phase)."""
        if self.source != MEMORY_FROZEN:
            return np.asarray(self.spectrum.exponents)
        return _with_phase(self.frozen.exponents, self.spectrum)

    @property
    def explanation(self) -> str:
        """One line: which D_KY is reported and why."""
        return _EXPLANATION[self.source]

    def to_record(self) -> dict[str, Any]:
        """The dimension's JSON keys (``kaplan_yorke`` and its error, the full-space value,
        ``kaplan_yorke_source`` and ``_note``, the memory-frozen exponents or None)."""
        return {
            "kaplan_yorke": self.kaplan_yorke,
            "kaplan_yorke_error": self.kaplan_yorke_error,
            "kaplan_yorke_full_space": self.kaplan_yorke_full_space,
            "kaplan_yorke_source": self.source,
            "kaplan_yorke_note": self.explanation,
            "memory_frozen_exponents": (
                None if self.frozen is None else list(self.frozen.exponents)
            ),
        }

    def __repr__(self) -> str:
        return (
            f"AttractorDimension(kaplan_yorke={self.kaplan_yorke:.4f} +- "
            f"{self.kaplan_yorke_error:.2g} ({self.source}), kaplan_yorke_full_space="
            f"{self.kaplan_yorke_full_space:.4f}, exponents=["
            + ", ".join(f"{x:.5g}" for x in self.exponents)
            + "])"
        )


def _base(tangent_space: tuple[str, ...]) -> int:
    """Number of non-memory directions: q, v and the phase if followed."""
    return 3 if "phi" in tangent_space else 2


def _with_phase(exponents: np.ndarray, spectrum: LyapunovResult) -> np.ndarray:
    lam = np.asarray(exponents, dtype=float)
    if "phi" in spectrum.tangent_space:
        lam = -np.sort(-np.append(lam, 0.0))
    return lam


def _memory_rows(system: Any, spectrum: LyapunovResult) -> bool:
    """Whether the tangent space holds memory rows at the start or at the end of the run (a
    continuous Preisach start without extrema has none at first)."""
    base = _base(spectrum.tangent_space)
    if len(spectrum.tangent_space) > base:
        return True
    engine = system.engine(spectrum.final)
    if not hasattr(engine, "start_tangent"):
        return False
    engine.start_tangent(base == 3)
    return len(engine.tangent_space) > base


def has_neutral_memory(frozen: MemoryFrozenResult) -> bool:
    """Whether memory directions were carried unchanged through whole projection intervals of
    the memory-frozen run ``frozen`` (module docstring): neutral memory exists."""
    if not isinstance(frozen, MemoryFrozenResult):
        raise TypeError(f"frozen must be a MemoryFrozenResult, got {type(frozen).__name__}")
    return bool(frozen.zeroed_mean > 0.0)


def attractor_dimension(
    system: Any,
    t_end: float,
    transient: float = 0.0,
    q0: float = DEFAULT_Q0,
    v0: float = DEFAULT_V0,
    operator_state: Any = None,
    include_phase: bool = False,
    progress: bool = False,
    *,
    spectrum: LyapunovResult | None = None,
    projection_periods: int = 1,
    blocks: int = 10,
    observer: Callable[[TangentStepper], None] | None = None,
) -> AttractorDimension:
    """The attractor's ``D_KY`` and the full-space one, from the same initial condition.

    Runs :func:`~analysis.dynamics.lyapunov.lyapunov_spectrum` over ``[transient, t_end]``
    (one QR step per forcing period, the running estimates of every step kept for the
    block errors; ``observer`` rides on it, e.g. to record the Poincaré section) unless its
    result is given as ``spectrum`` (then ``t_end``, ``transient`` and the phase must be its
    own, and ``observer`` is refused). If the tangent space has memory rows (at the start or the
    end), also :func:`~analysis.dynamics.memory.memory_frozen_exponents` from the same start
    (``projection_periods``); if :func:`has_neutral_memory` it reports ``D_KY`` of the two
    memory-frozen exponents (with the phase's 0 if the phase is followed), else the full-space
    value.
    """
    t_end, transient = time_window(t_end, transient)
    blocks = positive_integer(blocks, "blocks", minimum=2)
    projection_periods = positive_integer(projection_periods, "projection_periods")
    if spectrum is None:
        n_qr = max(1, int(math.ceil((t_end - transient) / float(system.period) - 1e-9)))
        spectrum = lyapunov_spectrum(
            system,
            t_end,
            transient,
            q0,
            v0,
            operator_state,
            include_phase=include_phase,
            progress=progress,
            history_points=max(n_qr, blocks),
            observer=observer,
        )
    else:
        if observer is not None:
            raise ValueError("observer needs the run: give either spectrum or observer")
        if spectrum.t_end != t_end or spectrum.transient != transient:
            raise ValueError(
                f"spectrum averages over [{spectrum.transient:g}, {spectrum.t_end:g}], not "
                f"[transient, t_end] = [{transient:g}, {t_end:g}]"
            )
        if ("phi" in spectrum.tangent_space) != bool(include_phase):
            raise ValueError("include_phase must match the spectrum's tangent space")
    full = float(spectrum.kaplan_yorke)
    frozen = None
    enough = len(spectrum.history_t) >= blocks
    ky_error = kaplan_yorke_block_error(spectrum, blocks) if enough else math.nan
    if _memory_rows(system, spectrum):
        interval = projection_periods * float(system.period)
        if (t_end - transient) / interval + 1e-9 < 1.0:
            return AttractorDimension(full, ky_error, full, UNTESTED, False, spectrum, None)
        frozen = memory_frozen_exponents(
            system,
            t_end,
            transient,
            q0,
            v0,
            operator_state,
            projection_periods=projection_periods,
            blocks=blocks,
        )
    if frozen is None or not has_neutral_memory(frozen):
        return AttractorDimension(full, ky_error, full, FULL_SPACE, False, spectrum, frozen)
    ky = kaplan_yorke_dimension(_with_phase(frozen.exponents, spectrum))
    return AttractorDimension(
        ky, frozen.kaplan_yorke_error, full, MEMORY_FROZEN, True, spectrum, frozen
    )
