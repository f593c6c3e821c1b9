"""Continuation of periodic orbits in a parameter, with smooth and nonsmooth bifurcations.

A branch is a curve ``z(s) = (x(s), λ(s))`` of solutions of ``F(x, λ) = P_λ^k(x) − x = 0``
(``P_λ`` the stroboscopic map at parameter value λ, ``x`` the coordinates of
:class:`~analysis.dynamics.orbit_coordinates.StateCoordinates`). From a point ``z_a`` with
unit tangent ``τ_a`` a step of length ``ds`` is a predictor and a Newton corrector on::

    F(x, λ) = 0,   c·(z − z_a − ds·τ_a) = 0

* **pseudo-arclength** (default for continuous memory): ``c = τ_a``, the tangent being the
  null vector of ``[J − I, ∂F/∂λ]`` (``∂F/∂λ`` by central differences of ``P^k`` in λ, step
  ``1e-6·max(1, |λ|)``), oriented like the previous one: folds are passed;
* **natural** (default for relay-type operators): ``c = e_λ`` (λ fixed at ``λ_a + ds``), the
  predictor extrapolating the last secant.

The corrector stops when ``|F|_∞ <= tolerance·max(1, |x|_∞)`` (and the constraint holds to
round-off); a step whose corrector fails is halved down to ``min_step``.

Events
------
Between two consecutive points with the same period and event sequence the Floquet multipliers
``μ_i`` give test functions whose sign changes bracket a bifurcation:

* ``fold``: ``Π (μ_i − 1)`` (a multiplier through +1);
* ``period-doubling``: ``Π (μ_i + 1)`` (through −1);
* ``torus``: ``Π_{i<j} (μ_i μ_j − 1)`` with a complex pair on the unit circle at the located
  point (a real pair with ``μ_i μ_j = 1`` is a neutral saddle, not reported);

located by the secant method (safeguarded by bisection) on the step length from the bracket's
first point, to ``locate_tolerance`` in the parameter.

Nonsmooth events end a branch in these systems: the event (switching) sequence along the orbit
changes — a relay threshold or a play wall is grazed by a turning point, a border collision.
When two consecutive points differ in their sequence (up to a cyclic shift: an event crossing
the section), or the corrector fails for every step, the parameter where the old sequence stops
holding is located by bisection in the parameter (natural corrector, from the last point of the
old sequence) to ``locate_tolerance`` and reported as ``grazing`` (a corrector failure at the
bracket's end is verified from the converged orbit at its other end, a step of at most
``locate_tolerance``: a failure of Newton's first iterate rather than of the orbit is passed).
The continuation then goes on from the first point of the new sequence. When no orbit in the
old coordinates follows, the next piece is found past the event along the branch (after a fold
the failing step's grazing is sought ahead, the sign of the tangent's λ component): first by
Newton for the old period from the last orbit (it finds unstable pieces too; accepted when it
continues the last orbit's ``(q, v)`` within
:data:`~analysis.dynamics.branch_loops.CONTINUITY`), then — only for a stable
orbit heading toward ``stop`` — by re-detecting the orbit (and period) the motion settles on
with :func:`~analysis.dynamics.periodic_orbits.find_periodic_orbit`. Past a fold or from an
unstable orbit a transient would find another attractor, a jump to another branch: the
continuation stops instead, ``stop_reason`` saying why.

A closed branch (an isola, or a loop between folds) stops on its first return
(:mod:`~analysis.dynamics.branch_loops`): where it passes its start, or a piece's first point
after a grazing, again in the same direction at the same orbit (Newton at that parameter from
the branch), or where it comes round to an event already found (the same kind, period,
dimension and orbit, at the parameter to ``10·locate_tolerance``), which is not reported a
second time; ``stop_reason`` says which.

Frozen memory (a wagon strictly inside its play along the whole orbit; see
:mod:`analysis.dynamics.periodic_orbits`) is held at its value along the branch: the corrector
and the tangent solve for the other coordinates and λ, and the bifurcation tests use the
multipliers that are not frozen. Continuous Preisach orbits are continued with the closed-loop
map of :mod:`analysis.dynamics.staircase_orbits` (its frozen extrema held); an orbit that grows
onto a frozen extremum changes its staircase
(:class:`~analysis.dynamics.staircase_orbits.StaircaseChangedError`), which ends the piece like
a grazing wherever it is met: a trial point or a corrector iterate fails (the step is halved;
at the smallest step the grazing is located by bisection from the last point), the tangent's
``∂F/∂λ`` becomes one-sided (:meth:`~analysis.dynamics.branch.BranchProblem.d_lambda`), the
location of an event stops at the last point that keeps the staircase. The new piece is the
orbit re-detected past the event (its transient's remnants settled anew). A staircase piece's
sequence is its reversals (:meth:`~analysis.dynamics.branch.BranchProblem.sequence`): the
orbit's own wipe-out at its reversal is the border itself, recorded or not at round-off.

Branch switching at a period doubling: :func:`period_doubled_orbit` (from
:mod:`~analysis.dynamics.branch_switching`) starts the period-2k orbit from the located point
plus a perturbation along the eigenvector of ``μ = −1``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from analysis.dynamics.branch import (
    FAILURES,
    PARAMETERS,
    BranchPoint,
    BranchProblem,
    ContinuationEvent,
    locate_grazing,
    same_sequence,
    smooth_events,
    system_factory,
)
from analysis.dynamics.branch_loops import Mark, loop_closed, returned_to, within
from analysis.dynamics.branch_switching import period_doubled_orbit
from analysis.dynamics.orbit_coordinates import StateCoordinates
from analysis.dynamics.periodic_orbits import (
    PeriodicOrbit,
    find_periodic_orbit,
    refine_periodic_orbit,
)
from analysis.dynamics.staircase_orbits import StaircaseChangedError
from hysteresis._validation import finite_scalar, positive_integer, positive_scalar
from oscillators import ForcedOscillator
from oscillators.engines import (
    DivergenceError,
    GrazingError,
    SlidingError,
    StepBudgetError,
    SwitchBudgetError,
)

__all__ = [
    "PARAMETERS",
    "BranchPoint",
    "Continuation",
    "ContinuationEvent",
    "continue_orbit",
    "period_doubled_orbit",
    "system_factory",
]

#: continuation methods (``auto``: natural for relay-type operators, pseudo-arclength otherwise)
METHODS = ("auto", "natural", "pseudo-arclength")
#: event kinds
KINDS = ("fold", "period-doubling", "torus", "grazing")
#: what ends a branch part-way with its points so far (the integration or the orbit's
#: structure failed), as opposed to a bug, which propagates
NUMERICAL_FAILURES = (
    DivergenceError,
    GrazingError,
    StepBudgetError,
    SwitchBudgetError,
    SlidingError,
    StaircaseChangedError,
    np.linalg.LinAlgError,
)
#: most accepted branch points of one call
MAX_POINTS = 100_000
#: largest distance of a pseudo-arclength corrector's result from its prediction, in units of
#: the predictor step ``h``. On a branch of curvature ``κ`` the corrector moves ``≈ κh²/2`` (the
#: chord's angle to the tangent ``≈ κh/2``): this allows steps up to the radius of curvature.
#: A corrector that lands farther (on the Gaussian Preisach loop's outer sheet, 1.5–3 step
#: lengths away, past the fold it should have turned at) found another branch: the step is
#: halved. Steps that stay on the branch measured 0.26 at most
REACH = 0.5


@dataclass(frozen=True)
class Continuation:
    """A continued branch (possibly several smooth pieces joined at grazing events)."""

    parameter: str
    method: str
    points: tuple[BranchPoint, ...]
    events: tuple[ContinuationEvent, ...]
    stop_reason: str

    def to_dict(self) -> dict[str, Any]:
        return {
            "parameter": self.parameter,
            "method": self.method,
            "branch": [p.to_dict() for p in self.points],
            "events": [e.to_dict() for e in self.events],
            "stop_reason": self.stop_reason,
        }


#: largest relative residual ``|P^k(x) − x|`` of the orbit handed to :func:`continue_orbit`
#: at ``start``: far above a refined orbit's (1e-10) and the integrators' error, far below what
#: a parameter change of 1e-4 leaves (an orbit found at another value)
START_RESIDUAL = 1e-6


def continue_orbit(
    system: ForcedOscillator | Callable[[float], Any],
    orbit: PeriodicOrbit,
    start: float,
    stop: float,
    *,
    parameter: str = "coupling",
    method: str = "auto",
    step: float | None = None,
    min_step: float | None = None,
    max_points: int = 2000,
    tolerance: float = 1e-10,
    max_iterations: int = 12,
    locate_tolerance: float = 1e-8,
    transient: int = 200,
    max_period: int = 64,
    engine_options: dict | None = None,
    symmetric: bool = False,
) -> Continuation:
    """Continue ``orbit`` (a periodic orbit of the system at ``parameter = start``) to ``stop``.

    Parameters
    ----------
    system:
        The :class:`~oscillators.system.ForcedOscillator` at ``start`` (the parameter is varied
        by :func:`system_factory`), or a factory ``value -> ForcedOscillator``.
    orbit:
        A :class:`~analysis.dynamics.periodic_orbits.PeriodicOrbit` at ``start``.
    start, stop:
        The parameter range, in continuation order (``stop < start`` continues downward).
    parameter:
        ``coupling`` (default), ``damping_ratio`` or ``frequency`` (labels and the factory).
    method:
        ``pseudo-arclength`` (passes folds), ``natural`` or ``auto`` (default): natural for
        relay-type operators, whose orbits are piecewise linear between switches, so that their
        branches end at grazings (switching-sequence changes) far more often than at folds, and
        whose short branches of long periods (the N = 2 period-adding cascade) the arclength
        predictor overshoots; pseudo-arclength for continuous memory (plays), where folds
        bound the periodic windows.
    step:
        Largest step in arclength (pseudo-arclength) or in the parameter (natural); default
        ``|stop − start|/50``. ``min_step`` (default ``step/2^12``) is the smallest.
    max_points:
        Most branch points (1 .. 100 000).
    tolerance, max_iterations:
        The corrector's convergence criterion ``|F|_∞ <= tolerance·max(1, |x|_∞)`` and its
        iteration limit.
    locate_tolerance:
        Width in the parameter to which events are located (bisection / secant).
    transient, max_period:
        For re-detecting the orbit (period) after a grazing, from the last state.
    symmetric:
        The system is invariant under ``x → −x`` with a half-period shift (an odd operator —
        plays, symmetric relays, symmetric Preisach densities — under ``cos`` forcing): every
        orbit has a partner, ``−x(t + T/2)``. A branch that reaches an event of the partner of
        an event found before (the same kind, parameter and multipliers) has closed its loop
        up to the symmetry and stops there, ``stop_reason`` saying so.

    Notes
    -----
    A numerical failure part-way (:data:`NUMERICAL_FAILURES`: the integration diverged, a
    switch grazed with the tangent flow on, the staircase changed, ...) ends the branch there:
    the points and events computed so far are returned, ``stop_reason`` naming the failure.
    A start or stop the system refuses, or an orbit that is not periodic at ``start`` (found
    at another parameter value), raises ``ValueError`` before anything is computed.
    """
    start = finite_scalar(start, "start")
    stop = finite_scalar(stop, "stop")
    if start == stop:
        raise ValueError(f"start and stop must differ, got {start}")
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    if not isinstance(orbit, PeriodicOrbit):
        raise TypeError(f"orbit must be a PeriodicOrbit, got {type(orbit).__name__}")
    if isinstance(system, ForcedOscillator):
        factory = system_factory(system, parameter)
    elif callable(system):
        if parameter not in PARAMETERS:
            raise ValueError(f"parameter must be one of {sorted(PARAMETERS)}, got {parameter!r}")
        factory = system
    else:
        raise TypeError("system must be a ForcedOscillator or a callable value -> system")
    for name, value in (("start", start), ("stop", stop)):
        # a value the system refuses (a frequency of 0, a coupling beyond its bound) is bad
        # input now, not a branch that creeps toward it for hours
        try:
            factory(value)
        except ValueError as exc:
            raise ValueError(f"{name}: {parameter} = {value:g}: {exc}") from None
    span = abs(stop - start)
    step = span / 50.0 if step is None else positive_scalar(step, "step")
    min_step = step / 4096.0 if min_step is None else positive_scalar(min_step, "min_step")
    if min_step > step:
        raise ValueError(f"min_step must be <= step ({step}), got {min_step}")
    max_points = positive_integer(max_points, "max_points")
    if max_points > MAX_POINTS:
        raise ValueError(f"max_points must be <= {MAX_POINTS}, got {max_points}")
    tolerance = positive_scalar(tolerance, "tolerance")
    max_iterations = positive_integer(max_iterations, "max_iterations")
    locate_tolerance = positive_scalar(locate_tolerance, "locate_tolerance")
    direction = math.copysign(1.0, stop - start)
    if method == "auto":
        method = "natural" if factory(start).operator.piecewise_constant else "pseudo-arclength"
    arclength = method == "pseudo-arclength"

    sys0 = factory(start)
    coords = _orbit_coordinates(sys0, orbit, engine_options)
    prob = BranchProblem(factory, coords, orbit.period, tolerance, max_iterations, engine_options)
    x0 = coords.vector(orbit.start)
    drift = float(np.max(np.abs(prob.residual(x0, start, orbit.start)[0])))
    if drift > START_RESIDUAL * max(1.0, float(np.max(np.abs(x0)))):
        # an orbit found at another parameter value would be relabelled silently
        raise ValueError(
            f"orbit is not a periodic orbit of the system at start = {start:g} "
            f"(|P^k(x) − x| = {drift:.2g}): pass the {parameter} it was found at as start"
        )
    first = prob.point(x0, start, orbit.start)
    points = [first]
    events: list[ContinuationEvent] = []
    ds = step
    reason = "reached stop"
    try:
        tangent = prob.tangent(first, None, direction) if arclength else None
    except StaircaseChangedError:
        tangent, reason = None, _no_tangent(parameter, first)
    d = coords.dimension
    # the points a closed branch comes back to (pseudo-arclength: natural continuation moves
    # monotonically in λ and cannot come back)
    marks = [Mark(first, math.copysign(1.0, tangent[d]))] if tangent is not None else []
    try:  # a failure part-way returns the branch computed so far, with the reason
        while tangent is not None or not arclength:
            a = points[-1]
            if len(points) >= max_points:
                reason = "max_points"
                break
            if direction * (stop - a.parameter) <= locate_tolerance:
                break
            z_a = np.append(a.point, a.parameter)
            new = None
            while ds >= min_step:
                if arclength:
                    # the step in the parameter is about ds (ten times ds along the branch near a
                    # fold, where the tangent is nearly orthogonal to the parameter axis)
                    z_pred = z_a + ds / max(abs(tangent[d]), 0.1) * tangent
                    c = tangent
                else:
                    lam = a.parameter + direction * ds
                    slope = _secant(points)
                    z_pred = np.append(a.point + slope * (lam - a.parameter), lam)
                    c = np.append(np.zeros(d), 1.0)
                if direction * (z_pred[d] - stop) > 0.0:  # land on stop exactly
                    lam = stop
                    z_pred = np.append(a.point + _secant(points) * (lam - a.parameter), lam)
                    got = prob.correct(z_pred, np.append(np.zeros(d), 1.0), a.state, False)
                else:
                    got = prob.correct(z_pred, c, a.state, arclength)
                # a corrected point farther than 10 steps in the parameter, beyond stop, or (arc
                # length) farther from its prediction than REACH times the predictor step jumped
                # to another branch: a failed step
                if got is not None and (
                    abs(got[0][d] - a.parameter) <= 10.0 * ds + locate_tolerance
                    and direction * (got[0][d] - stop) <= locate_tolerance
                    and (not arclength or _near(got[0], z_pred, z_a))
                ):
                    z, image = got
                    new = prob.point(z[:d], float(z[d]), image)
                    break
                ds *= 0.5
            if new is None or not same_sequence(a.sequence, new.sequence):
                # the old sequence ends between a and new (or the next failing step: along the
                # branch, which runs away from stop after a fold)
                ahead = math.copysign(1.0, tangent[d]) if arclength else direction
                trial = new.parameter if new is not None else a.parameter + ahead * 2 * min_step
                event, last = locate_grazing(prob, a, trial, locate_tolerance)
                if event is None and new is None:
                    reason = "corrector failed (no grazing found)"
                    break
                if event is None and ds >= 2.0 * min_step:
                    # the old orbit holds at new's parameter (it grazes there within round-off,
                    # or the corrector jumped to a coexisting orbit): on along it, shorter
                    ds *= 0.5
                    continue
                if event is not None:
                    events.append(replace(event, index=len(points)))
                    if last is not a:
                        points.append(last)
                resumed, redetected = new, new is None
                if resumed is None:
                    # a transient finds attractors only: it may stand in for the branch where the
                    # branch heads toward stop from a stable orbit; past a fold, or from an
                    # unstable orbit, only Newton can follow it (else it would jump)
                    settle = ahead == direction and last.max_abs_multiplier < 1.0
                    resumed = _redetect(
                        prob, event, ahead, settle, stop, step, transient, max_period, tolerance
                    )
                    if resumed is None:
                        reason = (
                            "no periodic orbit after the grazing"
                            if settle
                            else "no orbit continues the branch past the grazing (Newton from the "
                            "last orbit failed; it runs "
                            + ("against stop after a fold" if ahead != direction else "unstable")
                            + ", where a transient would find another attractor)"
                        )
                        break
                    prob = resumed[0]
                    resumed = resumed[1]
                    d = prob.coords.dimension  # a re-detected staircase may have another length
                closed = loop_closed(prob, [event], events[:-1], locate_tolerance, symmetric)
                if closed:
                    if closed[1]:  # the grazing found again: reported once
                        events.pop()
                    reason = closed[0].format(parameter)
                    break
                points.append(resumed)
                # the new piece continues the old one's orientation (after a fold: backwards); a
                # re-detected orbit (another problem) starts toward stop
                if arclength:
                    try:
                        tangent = prob.tangent(resumed, None if redetected else tangent, ahead)
                    except StaircaseChangedError:
                        reason = _no_tangent(parameter, resumed)
                        break
                    marks.append(Mark(resumed, math.copysign(1.0, tangent[d])))
                ds = step
                continue
            try:
                new_tangent = prob.tangent(new, tangent, direction) if arclength else None
            except StaircaseChangedError:
                reason = _no_tangent(parameter, new)
                break
            found = smooth_events(prob, a, new, tangent, new_tangent, direction, locate_tolerance)
            closed = loop_closed(prob, found, events, locate_tolerance, symmetric)
            repeats = closed[1] if closed else []
            events.extend(
                replace(e, index=len(points)) for e in found if not any(e is r for r in repeats)
            )
            back = None if closed or not arclength else returned_to(prob, marks, a, new)
            if back is not None:  # the branch passed a point of its own again
                points.append(back)
                reason = (
                    f"the branch came back to its orbit at {parameter} = {back.parameter:.10g} "
                    "(a closed loop)"
                )
                break
            points.append(new)
            if closed:  # the branch came round to a fold (or other event) already found
                reason = closed[0].format(parameter)
                break
            tangent = new_tangent
            ds = min(step, ds * 1.5)
            if direction * (new.parameter - start) < -span:
                reason = "turned back past start"
                break
    except NUMERICAL_FAILURES as exc:
        where = points[-1].parameter
        reason = f"failed after {parameter} = {where:.10g}: {type(exc).__name__}: {exc}"
    return Continuation(
        parameter=PARAMETERS[parameter],
        method=method,
        points=tuple(points),
        events=tuple(events),
        stop_reason=reason,
    )


def _near(z: np.ndarray, z_pred: np.ndarray, z_a: np.ndarray) -> bool:
    """The corrected point ``z`` is within :data:`REACH` times the predictor step
    ``|z_pred − z_a|`` of its prediction ``z_pred`` (Euclidean norm in ``(x, λ)``)."""
    return float(np.linalg.norm(z - z_pred)) <= REACH * float(np.linalg.norm(z_pred - z_a))


def _no_tangent(parameter: str, bp: BranchPoint) -> str:
    return (
        f"the orbit's staircase changes on both sides of {parameter} = {bp.parameter:.10g} "
        "(no tangent: a frozen extremum within 1e-6·max(1, |λ|), the λ-difference step, on "
        "either side)"
    )


def _orbit_coordinates(system: Any, orbit: PeriodicOrbit, engine_options: dict | None):
    """The coordinates of ``orbit.start``; a staircase's frozen prefix is the orbit's frozen
    extrema (the leading entries: the orbit's own extrema follow them)."""
    coords = StateCoordinates(system, orbit.start, engine_options)
    if coords.kind == "staircase":
        coords.prefix = len(orbit.frozen)
    return coords


def _secant(points: list[BranchPoint]) -> np.ndarray:
    """dx/dλ from the last two points of the same period and coordinates (zero if none: a
    re-detected staircase may have another length)."""
    if len(points) < 2 or points[-1].period != points[-2].period:
        return np.zeros_like(points[-1].point)
    a, b = points[-2], points[-1]
    if a.point.shape != b.point.shape:
        return np.zeros_like(b.point)
    dl = b.parameter - a.parameter
    if dl == 0.0 or not same_sequence(a.sequence, b.sequence):
        return np.zeros_like(b.point)
    return (b.point - a.point) / dl


def _redetect(prob, event, side, settle, stop, step, transient, max_period, tolerance):
    """After a grazing with no orbit in the old coordinates: the branch's next piece past the
    event on ``side`` (the sign of the branch's λ direction there).

    First Newton for the old period from the last orbit's state
    (:func:`~analysis.dynamics.periodic_orbits.refine_periodic_orbit`, which finds unstable
    orbits as well) at 10, 100 and 1000 bracket widths past the event, accepted when one of its
    section points continues the last orbit's ``(q, v)`` within
    :data:`~analysis.dynamics.branch_loops.CONTINUITY` ``·max(1, |x|_∞)`` (a branch is
    continuous through a border collision).
    Then, only if ``settle`` (a stable orbit heading toward ``stop``), the orbit the motion
    settles on (:func:`~analysis.dynamics.periodic_orbits.find_periodic_orbit`: an attractor,
    maybe of another period, as in the period-adding cascade) at ``10·bracket``, ``step``,
    ``2·step``, ... beyond the event (not beyond ``stop``; at most 8 tries)."""
    if event is None:
        return None
    edge = event.bracket[1] if side > 0 else event.bracket[0]
    width = event.bracket[1] - event.bracket[0]
    last = event.point
    for offset in (10.0 * width, 100.0 * width, 1000.0 * width):
        lam = edge + side * offset
        if settle and _beyond(lam, stop, side):
            break
        system = prob.system(lam)
        try:
            orbit = refine_periodic_orbit(
                system,
                last.state,
                last.period,
                tolerance=tolerance,
                max_iterations=prob.iters,
                engine_options=prob.eo,
            )
        except FAILURES:
            continue
        if any(within(p - last.point[:2], last.point) for p in orbit.points[:, :2]):
            return _resume(prob, system, orbit, lam)
    if not settle:
        return None
    offsets = [10.0 * width] + [step * 2**i for i in range(7)]
    for offset in offsets:
        lam = edge + side * offset
        if _beyond(lam, stop, side):
            lam = stop
        system = prob.system(lam)
        try:
            orbit = find_periodic_orbit(
                system,
                last.state,
                transient=transient,
                max_period=max_period,
                tolerance=tolerance,
                engine_options=prob.eo,
            )
        except FAILURES:
            if lam == stop:
                return None
            continue
        return _resume(prob, system, orbit, lam)
    return None


def _beyond(lam: float, stop: float, side: float) -> bool:
    """``lam`` lies beyond ``stop`` seen along ``side``."""
    return side * (lam - stop) > 0.0


def _resume(prob, system, orbit, lam):
    """The new piece's problem and first point from an orbit found at ``lam``."""
    coords = _orbit_coordinates(system, orbit, prob.eo)
    new = BranchProblem(prob.factory, coords, orbit.period, prob.tol, prob.iters, prob.eo)
    return new, new.point(coords.vector(orbit.start), lam, orbit.start)
