"""Branch switching at a period doubling: the period-2k orbit born where a multiplier of a
period-k branch passes through −1 (:func:`period_doubled_orbit`).

Near a period doubling at ``λ_0`` the period-2k orbit lies ``O(sqrt(|λ − λ_0|))`` from the
period-k orbit along the eigenvector ``e`` of ``μ = −1`` (the normal form
``y → −(1 + a·δλ)·y + c·y³``: the doubled orbit at ``y² ≈ −a·δλ/c``), on one side of ``λ_0``
(``sign(−a·δλ/c) > 0``), which the located event does not tell. So Newton for period 2k starts
on both sides, at ``λ_0 ± offset``, from the period-k point plus ``± A·e``; the cubic
coefficient is unknown too, so ``A`` runs up a ladder (``amplitude``, ×10, ×100): a start
much closer to the period-k orbit than to the doubled one converges back to the period-k
orbit covered twice, which is recognised (its two halves coincide) and skipped.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from analysis.dynamics.branch import FAILURES, ContinuationEvent, system_factory
from analysis.dynamics.floquet import floquet_multipliers
from analysis.dynamics.orbit_coordinates import StateCoordinates
from analysis.dynamics.periodic_orbits import (
    OrbitNotFoundError,
    PeriodicOrbit,
    refine_periodic_orbit,
)
from hysteresis._validation import positive_scalar
from oscillators import ForcedOscillator

__all__ = ["AMPLITUDE_LADDER", "period_doubled_orbit"]

#: the perturbation amplitudes tried, in units of ``amplitude``: the doubled orbit's distance
#: ``sqrt(|a·δλ/c|)`` from the period-k orbit is not known before it is found (a Gaussian
#: Preisach period doubling at C = 3.8055: 0.01 at δλ = 1e-5, where a start 1e-3 away converges
#: back to the period-5 orbit)
AMPLITUDE_LADDER = (1.0, 10.0, 100.0)


def period_doubled_orbit(
    system: ForcedOscillator | Callable[[float], Any],
    event: ContinuationEvent,
    *,
    parameter: str = "coupling",
    offset: float | None = None,
    amplitude: float = 1e-3,
    tolerance: float = 1e-10,
    max_iterations: int = 30,
    engine_options: dict | None = None,
) -> tuple[float, PeriodicOrbit]:
    """Branch switching at a period doubling: the period-2k orbit near ``event``.

    Starts Newton (period 2k) at ``event.parameter ± offset`` (default ``1e3·|bracket|`` and at
    least ``1e-6·max(1, |λ|)``) from the orbit point plus ``± A`` times the eigenvector of the
    multiplier closest to −1 (normalised to ``|e|_∞ = 1``), ``A`` in ``amplitude`` times
    :data:`AMPLITUDE_LADDER` (the smallest first, on both sides), and returns
    ``(parameter, orbit)`` for the first start that converges to an orbit of minimal period 2k
    (the two halves' section points distinct beyond ``1e3·tolerance·max(1, |x|_∞)``, compared
    where both are defined: a staircase's points have another length along a Preisach orbit)
    whose nearest section point lies within ``10·A`` of the start's.

    Raises :class:`~analysis.dynamics.periodic_orbits.OrbitNotFoundError` saying what every
    start converged to if none does.
    """
    if event.kind != "period-doubling" or event.point is None:
        raise ValueError(f"event must be a located period-doubling event, got {event.kind!r}")
    factory = system_factory(system, parameter) if isinstance(system, ForcedOscillator) else system
    bp = event.point
    lam0 = bp.parameter
    if offset is None:
        offset = max(1e3 * abs(event.bracket[1] - event.bracket[0]), 1e-6 * max(1.0, abs(lam0)))
    offset = positive_scalar(offset, "offset")
    amplitude = positive_scalar(amplitude, "amplitude")
    mu, vec, _ = floquet_multipliers(bp.monodromy)
    e = np.real(vec[:, int(np.argmin(np.abs(mu + 1.0)))])
    e = e / np.max(np.abs(e))
    k, k2 = bp.period, 2 * bp.period
    covered = failed = far = 0
    for amp in (amplitude * f for f in AMPLITUDE_LADDER):
        for lam in (lam0 + offset, lam0 - offset):
            sys_l = factory(lam)
            coords = StateCoordinates(sys_l, bp.state, engine_options)
            for sign in (1.0, -1.0):
                try:
                    # a staircase perturbed along e may not be one (its extrema must stay
                    # nested): that start is skipped
                    guess = coords.state(bp.point + sign * amp * e, bp.state)
                    orb = refine_periodic_orbit(
                        sys_l,
                        guess,
                        k2,
                        tolerance=tolerance,
                        max_iterations=max_iterations,
                        engine_options=engine_options,
                    )
                except FAILURES:
                    failed += 1
                    continue
                # NaN marks a memory coordinate a section point does not have: compare the
                # coordinates both halves have ((q, v) always)
                half = np.abs(orb.points[:k] - orb.points[k:])
                if float(np.nanmax(half)) <= 1e3 * tolerance * max(
                    1.0, float(np.nanmax(np.abs(orb.points)))
                ):
                    covered += 1
                    continue
                near = np.min(np.max(np.abs(orb.points[:, :2] - bp.point[:2]), axis=1))
                if near > 10.0 * amp:
                    far += 1
                    continue
                return lam, orb
    raise OrbitNotFoundError(
        f"no period-{k2} orbit next to the period doubling at {lam0:.10g}: of the Newton starts "
        f"at ±{offset:g} with amplitudes {amplitude:g}..{amplitude * AMPLITUDE_LADDER[-1]:g}, "
        f"{covered} converged back to the period-{k} orbit (covered twice), {far} to a period-"
        f"{k2} orbit elsewhere, {failed} failed (a period doubling of a nonsmooth map, or the "
        "doubled orbit farther than the largest amplitude)"
    )
