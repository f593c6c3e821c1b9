"""Branches of periodic orbits: their points, events, the problem ``F(x, λ) = P_λ^k(x) − x``
with its predictor–corrector, and the location of events on a branch.

The algorithms are described in :mod:`analysis.dynamics.continuation`, which drives them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from analysis.dynamics.floquet import (
    active_multipliers,
    floquet_multipliers,
    frozen_coordinates,
    max_abs_multiplier,
)
from analysis.dynamics.newton import Border, Linearization, NewtonError, newton
from analysis.dynamics.orbit_coordinates import StateCoordinates
from analysis.dynamics.periodic_orbits import OrbitNotFoundError, event_sequence, orbit_shooter
from analysis.dynamics.staircase_orbits import StaircaseChangedError
from oscillators import DivergenceError, ForcedOscillator, GrazingError, OscillatorState

__all__ = [
    "BranchPoint",
    "BranchProblem",
    "ContinuationEvent",
    "FAILURES",
    "PARAMETERS",
    "locate_grazing",
    "natural_point",
    "same_sequence",
    "smooth_events",
    "system_factory",
]

#: continuation parameters and their aliases -> the ForcedOscillator argument
PARAMETERS = {
    "coupling": "coupling",
    "C": "coupling",
    "damping_ratio": "damping_ratio",
    "zeta": "damping_ratio",
    "frequency": "frequency",
    "omega": "frequency",
}


def system_factory(system: ForcedOscillator, parameter: str = "coupling") -> Callable:
    """``value -> ForcedOscillator`` with ``parameter`` (``coupling``/``C``,
    ``damping_ratio``/``zeta``, ``frequency``/``omega``) set and everything else from
    ``system``."""
    if parameter not in PARAMETERS:
        raise ValueError(f"parameter must be one of {sorted(PARAMETERS)}, got {parameter!r}")
    name = PARAMETERS[parameter]
    base = {
        "coupling": system.coupling,
        "damping_ratio": system.damping_ratio,
        "frequency": system.frequency,
    }

    def make(value: float) -> ForcedOscillator:
        return ForcedOscillator(system.operator, **{**base, name: float(value)})

    return make


#: failures the engines raise for a state where no orbit with this sequence exists
FAILURES = (OrbitNotFoundError, GrazingError, DivergenceError, ValueError, np.linalg.LinAlgError)
#: the corrector's constraint row holds when ``|c·(z − z_pred)| <= 1e-12·(1 + |z|_∞)``: round-off
#: of a dot product of a few unit-size terms (the step is linear in it, so Newton satisfies it
#: exactly up to round-off after one step)
BORDER_TOLERANCE = 1e-12


@dataclass(frozen=True)
class BranchPoint:
    """One point of a branch: the parameter, the orbit's period, its multipliers (with labels:
    ``"frozen: <label>"`` for frozen memory, exactly 1 and left out of the bifurcation tests and
    of ``max_abs_multiplier``; see :mod:`analysis.dynamics.periodic_orbits`)."""

    parameter: float
    period: int
    multipliers: np.ndarray
    point: np.ndarray
    sequence: tuple = field(repr=False)
    state: OscillatorState = field(repr=False)
    monodromy: np.ndarray = field(repr=False)
    multiplier_labels: tuple[str, ...] = field(repr=False, default=())

    @property
    def max_abs_multiplier(self) -> float:
        """``max |μ|`` over the non-frozen multipliers."""
        return max_abs_multiplier(self.multipliers, self.multiplier_labels)

    @property
    def active_multipliers(self) -> np.ndarray:
        """The multipliers not labelled frozen (those the bifurcation tests use)."""
        return active_multipliers(self.multipliers, self.multiplier_labels)

    def to_dict(self) -> dict[str, Any]:
        return {
            "parameter": float(self.parameter),
            "period": int(self.period),
            "max_abs_multiplier": self.max_abs_multiplier,
            "multipliers": [[float(m.real), float(m.imag)] for m in self.multipliers],
            "n_events": len(self.sequence),
            "frozen": [t[8:] for t in self.multiplier_labels if t.startswith("frozen: ")],
        }


@dataclass(frozen=True)
class ContinuationEvent:
    """A bifurcation on the branch: ``kind`` in :data:`KINDS`, the located ``parameter`` and
    the bracket it was located in; ``point`` the orbit there (smooth events) or the last orbit
    of the old sequence (grazing); ``multipliers`` there; ``index`` the number of branch points
    before it: ``Continuation.points[index]`` is the first point after a smooth event; after a
    grazing it is ``point`` (the old sequence's last orbit, within the bracket) when the
    bisection moved past the previous branch point, else the first point of the new piece."""

    kind: str
    parameter: float
    bracket: tuple[float, float]
    period: int
    multipliers: np.ndarray
    point: BranchPoint | None = field(repr=False, default=None)
    index: int = -1

    def to_dict(self) -> dict[str, Any]:
        return {
            "kind": self.kind,
            "parameter": float(self.parameter),
            "bracket": [float(b) for b in self.bracket],
            "period": int(self.period),
            "multipliers": [[float(m.real), float(m.imag)] for m in self.multipliers],
        }


def same_sequence(a: tuple, b: tuple) -> bool:
    """Equal up to a cyclic shift (an event crossing the section moves from end to start)."""
    if len(a) != len(b):
        return False
    if not a:
        return True
    return any(a[i:] + a[:i] == b for i in range(len(a)))


class BranchProblem:
    """``F(x, λ)`` and its derivatives for one operator, one period and one section."""

    def __init__(
        self, factory: Callable, coords: StateCoordinates, k: int, tol: float, iters: int, eo
    ):
        self.factory = factory
        self.coords = coords
        self.k = k
        self.tol = tol
        self.iters = iters
        self.eo = eo
        self._systems: dict[float, Any] = {}

    def system(self, lam: float) -> Any:
        s = self._systems.get(lam)
        if s is None:
            if len(self._systems) > 64:
                self._systems.clear()
            s = self._systems[lam] = self.factory(lam)
        return s

    def residual(self, x: np.ndarray, lam: float, template: OscillatorState):
        run = orbit_shooter(self.system(lam), self.coords, self.k, self.eo)
        shot = run(self.coords.state(x, template))
        return self.coords.vector(shot.states[-1]) - x, shot

    def d_lambda(self, x: np.ndarray, lam: float, template: OscillatorState) -> np.ndarray:
        """``∂F/∂λ`` by central differences, step ``h = 1e-6·max(1, |λ|)`` (truncation
        ``h²/6·|F_λλλ|``). Where the staircase changes on one side (the orbit within ``h`` of a
        grazing of its frozen prefix: ``F`` of these coordinates is not defined beyond it) the
        one-sided difference on the other side, truncation ``h/2·|F_λλ|``, a relative error
        ~1e-6: it only sets the predictor's direction and a column of the corrector's
        Jacobian, whose converged point does not depend on it (the residual test decides).
        Raises :class:`StaircaseChangedError` if the staircase changes on both sides."""
        h = 1e-6 * max(1.0, abs(lam))
        side = {}
        for sign in (1.0, -1.0):
            try:
                side[sign] = self.residual(x, lam + sign * h, template)[0]
            except StaircaseChangedError:
                continue
        if len(side) == 2:
            return (side[1.0] - side[-1.0]) / (2.0 * h)
        if not side:
            raise StaircaseChangedError(
                f"the orbit's staircase changes on both sides of λ = {lam!r} (step {h:.3g})"
            )
        centre = self.residual(x, lam, template)[0]
        sign, other = next(iter(side.items()))
        return sign * (other - centre) / h

    def point(self, x: np.ndarray, lam: float, template: OscillatorState) -> BranchPoint:
        system = self.system(lam)
        state = self.coords.state(x, template)
        shot = orbit_shooter(system, self.coords, self.k, self.eo)(state, True)
        mu, _, tags = floquet_multipliers(
            shot.jacobian,
            frozen_coordinates(shot.jacobian),
            self.coords.dimension - shot.rank,
            self.coords.labels,
        )
        return BranchPoint(
            parameter=float(lam),
            period=self.k,
            multipliers=mu,
            point=np.array(x, dtype=float),
            sequence=self.sequence(shot.events) + self.coords.configuration(state),
            state=state,
            monodromy=shot.jacobian,
            multiplier_labels=tags,
        )

    def sequence(self, events: np.ndarray) -> tuple:
        """The event sequence that delimits a smooth piece of the branch:
        :func:`~analysis.dynamics.periodic_orbits.event_sequence`, for a continuous Preisach
        staircase its reversals only. A wipe-out (kind +1) can appear or vanish only where a
        swing's reversal meets the remembered extremum, at ``v = 0`` — on every such orbit's
        own border it does so at round-off level from one point to the next — and the two
        sides differ by an Everett mass ``O(δ²)`` (``δ`` the distance to the border): the
        closed-loop map stays smooth. Its structural changes (a frozen extremum wiped, another
        number of own extrema) raise :class:`StaircaseChangedError` instead."""
        seq = event_sequence(events)
        if self.coords.kind == "staircase":
            return tuple(e for e in seq if e[0] == -1)
        return seq

    def correct(
        self,
        z_pred: np.ndarray,
        c: np.ndarray,
        template: OscillatorState,
        arclength: bool,
    ) -> tuple[np.ndarray, OscillatorState] | None:
        """Newton on ``[F(x, λ); c·(z − z_pred)] = 0`` from ``z_pred`` (the undamped, bordered
        loop of :func:`~analysis.dynamics.newton.newton`); None if it fails, or if the
        converged orbit's relay configuration does not close or it covers a shorter orbit.
        Frozen memory (identity rows of ``D P^k``) is held: the step solves for the other
        coordinates and λ."""
        d = self.coords.dimension

        def evaluate(z: np.ndarray, previous: Linearization | None) -> Linearization:
            x, lam = z[:d], float(z[d])
            tmpl = template if previous is None else previous.data[0].states[-1]
            r, shot = self.residual(x, lam, tmpl)

            def jacobian() -> np.ndarray:
                jac = np.zeros((d, d + 1))
                jac[:, :d] = shot.jacobian - np.eye(d)
                if arclength:
                    jac[:, d] = self.d_lambda(x, lam, tmpl)
                return jac

            free = np.nonzero(~frozen_coordinates(shot.jacobian))[0]
            return Linearization(r, jacobian, free, (shot, tmpl))

        try:
            got = newton(
                evaluate,
                z_pred,
                tolerance=self.tol,
                max_iterations=self.iters,
                scale=lambda z: self.coords.scale(z[:d]),
                border=Border(c, z_pred, BORDER_TOLERANCE),
            )
        except (NewtonError, *FAILURES):
            return None
        shot, tmpl = got.evaluation.data
        x = got.z[:d]
        if self.coords.same_memory(self.coords.state(x, tmpl), shot.states[-1]) and not (
            self._covers(x, shot)
        ):
            return got.z, shot.states[-1]
        return None

    def _covers(self, x: np.ndarray, shot: Any) -> bool:
        """Whether the orbit closes after a proper divisor of k periods (a multiple cover of a
        shorter orbit, which is not on this branch)."""
        bound = 1e3 * self.tol * self.coords.scale(x)
        for m in range(1, self.k):
            if self.k % m == 0:
                try:
                    y = self.coords.vector(shot.states[m - 1])
                except ValueError:  # another staircase length there: not the same point
                    continue
                if float(np.max(np.abs(y - x))) <= bound:
                    return True
        return False

    def tangent(self, bp: BranchPoint, previous: np.ndarray | None, direction: float):
        """Unit null vector of ``[J − I, ∂F/∂λ]`` at ``bp``, oriented like ``previous`` (else
        with ``sign(dλ) = direction``)."""
        d = self.coords.dimension
        a = np.zeros((d, d + 1))
        a[:, :d] = bp.monodromy - np.eye(d)
        a[:, d] = self.d_lambda(bp.point, bp.parameter, bp.state)
        # frozen memory is held: the null vector of the other rows and columns
        keep = np.nonzero(~frozen_coordinates(bp.monodromy))[0]
        cols = np.append(keep, d)
        _, _, vt = np.linalg.svd(a[np.ix_(keep, cols)])
        t = np.zeros(d + 1)
        t[cols] = vt[-1]
        if previous is not None and previous.shape == (d + 1,):
            ref = previous
        else:
            ref = np.append(np.zeros(d), direction)
        if float(t @ ref) < 0.0:
            t = -t
        return t / np.linalg.norm(t)


def _tests(mu: np.ndarray) -> dict[str, float]:
    """Test functions of fold, period doubling and torus from the multipliers."""
    prod_pairs = 1.0 + 0.0j
    for i in range(mu.size):
        for j in range(i + 1, mu.size):
            prod_pairs *= mu[i] * mu[j] - 1.0
    return {
        "fold": float(np.real(np.prod(mu - 1.0))),
        "period-doubling": float(np.real(np.prod(mu + 1.0))),
        "torus": float(np.real(prod_pairs)),
    }


def _is_torus(mu: np.ndarray) -> bool:
    return bool(np.any((np.abs(mu.imag) > 1e-8) & (np.abs(np.abs(mu) - 1.0) < 1e-4)))


def natural_point(prob: BranchProblem, a: BranchPoint, lam: float) -> BranchPoint | None:
    """The orbit of ``a``'s period at parameter ``lam`` by Newton from ``a`` (None if none)."""
    d = prob.coords.dimension
    z_pred = np.append(a.point, lam)
    got = prob.correct(z_pred, np.append(np.zeros(d), 1.0), a.state, False)
    if got is None:
        return None
    try:
        return prob.point(got[0][:d], lam, got[1])
    except FAILURES:
        return None


def locate_grazing(
    prob: BranchProblem, a: BranchPoint, trial: float, tol: float
) -> tuple[ContinuationEvent | None, BranchPoint]:
    """Bisection on the parameter between ``a`` (old sequence) and ``trial`` (not) for the end
    of ``a``'s event sequence; ``(None, orbit at trial)`` if the sequence holds at ``trial``
    (``(None, a)`` when ``a`` reaches it in one step).

    A failure at ``mid`` may be Newton's, not the orbit's: the corrector starts from the last
    orbit of the old sequence, and its first iterate's motion can overshoot a border (wipe a
    frozen extremum) that the orbit at ``mid`` does not reach. So the failure at the final
    ``hi`` is verified from the converged orbit at ``lo`` (a step of at most ``tol``); if the
    orbit of the old sequence exists there, the bisection goes on toward the next failure
    further out."""
    last = a
    b = natural_point(prob, a, trial)
    if b is not None and same_sequence(a.sequence, b.sequence):
        return None, a
    lo, failed = a.parameter, [trial]  # failing parameters, the nearest last
    while True:
        while abs(failed[-1] - lo) > tol:
            mid = 0.5 * (lo + failed[-1])
            m = natural_point(prob, last, mid)
            if m is not None and same_sequence(a.sequence, m.sequence):
                lo, last = mid, m
            else:
                failed.append(mid)
        if len(failed) == 1:  # every midpoint held: trial failed from a, verify it from last
            if last is a:
                break
            m = natural_point(prob, last, failed[-1])
            if m is None or not same_sequence(a.sequence, m.sequence):
                break
            return None, m  # the sequence holds at trial: no grazing up to there
        m = natural_point(prob, last, failed[-1])
        if m is None or not same_sequence(a.sequence, m.sequence):
            break
        lo, last = failed.pop(), m
    hi = failed[-1]
    event = ContinuationEvent(
        kind="grazing",
        parameter=0.5 * (lo + hi),
        bracket=(min(lo, hi), max(lo, hi)),
        period=a.period,
        multipliers=last.multipliers,
        point=last,
    )
    return event, last


def smooth_events(
    prob: BranchProblem,
    a: BranchPoint,
    b: BranchPoint,
    tangent_a: np.ndarray | None,
    tangent_b: np.ndarray | None,
    direction: float,
    tol: float,
) -> list[ContinuationEvent]:
    """Sign changes of the test functions between ``a`` and ``b``, located on the branch arc
    between them (:func:`_locate`; ``bracket`` the λ of its last two ends). With
    pseudo-arclength the fold's test function is the parameter component of the tangent (it
    changes sign where the branch turns back), which also catches a fold whose multiplier
    touches +1 without crossing it."""
    arclength = tangent_a is not None
    d = prob.coords.dimension

    def tests(bp: BranchPoint, tangent: np.ndarray | None) -> tuple[dict[str, float], Any]:
        t = _tests(bp.active_multipliers)
        if arclength:
            if tangent is None:
                tangent = prob.tangent(bp, tangent_a, direction)
            t["fold"] = float(tangent[d])
        return t, tangent

    (ta, _), (tb, _) = tests(a, tangent_a), tests(b, tangent_b)
    out = []
    for kind in ("fold", "period-doubling", "torus"):
        if not ta[kind] * tb[kind] < 0.0:
            continue
        ends = (a, ta[kind], tangent_a), (b, tb[kind], tangent_b)
        at, lo, hi = _locate(prob, kind, *ends, tests, tol)
        if kind == "torus" and not _is_torus(at.active_multipliers):
            continue
        out.append(
            ContinuationEvent(
                kind=kind,
                parameter=at.parameter,
                bracket=(min(lo.parameter, hi.parameter), max(lo.parameter, hi.parameter)),
                period=a.period,
                multipliers=at.multipliers,
                point=at,
            )
        )
    return out


#: most corrector solves when locating one smooth event (the Illinois iteration converges
#: superlinearly: about ten suffice from a continuation step)
LOCATE_ITERATIONS = 60


def _locate(prob, kind, end_lo, end_hi, tests, tol: float):
    """The zero of the test function ``kind`` on the branch arc between two points where it
    has opposite signs (each end ``(point, value, tangent)``, ``lo`` the first along the arc):
    ``(at, lo, hi)``, the last point computed and the bracket's final ends.

    Each trial point is ``p(θ)`` on the cubic Hermite curve through the bracket's ends with
    their tangents (pseudo-arclength; the chord for natural continuation, whose points have no
    tangent), corrected on the hyperplane through it normal to ``p′(θ)`` (λ fixed for natural
    continuation); ``θ`` by the Illinois variant of regula falsi (the value of an end kept
    twice is halved: no creeping of one end, which cost a hundred solves per fold). The curve
    follows the arc through a fold, where a hyperplane fixed normal to the first point's
    tangent cuts both sheets: a corrected point farther than a quarter of the chord from its
    prediction is on another sheet (or branch) and refused; the bracket is bisected instead,
    and the location stops if that is refused too. It ends when the bracket is within ``tol``
    in λ and (a fold, where λ is extremal: its error is the curvature times the square of the
    chord) its chord within ``sqrt(tol)·max(1, |x|_∞)``, or when a corrector fails."""
    d = prob.coords.dimension
    (lo, g_lo, t_lo), (hi, g_hi, t_hi) = end_lo, end_hi
    arclength = t_lo is not None
    at = hi
    kept = 0  # -1: lo replaced by the last step (hi kept), +1: hi replaced
    bisect = False
    for _ in range(LOCATE_ITERATIONS):
        z_lo = np.append(lo.point, lo.parameter)
        z_hi = np.append(hi.point, hi.parameter)
        chord = z_hi - z_lo
        length = float(np.linalg.norm(chord))
        scale = max(1.0, float(np.max(np.abs(z_hi[:d]))))
        if abs(hi.parameter - lo.parameter) <= tol and (
            kind != "fold" or float(np.max(np.abs(chord))) <= np.sqrt(tol) * scale
        ):
            break
        theta = 0.5 if bisect else g_lo / (g_lo - g_hi)
        if not 1e-3 < theta < 1.0 - 1e-3:
            theta = 0.5
        if arclength:
            z_pred, c = _hermite(z_lo, z_hi, length * t_lo, length * t_hi, theta)
        else:
            z_pred, c = z_lo + theta * chord, np.append(np.zeros(d), 1.0)
        got = prob.correct(z_pred, c, lo.state, arclength)
        if got is None:
            break
        z = got[0]
        if float(np.linalg.norm(z - z_pred)) > 0.25 * length:
            if bisect:
                break  # not even the bisection stays on this arc: stop here
            bisect = True
            continue
        bisect = False
        try:
            at_s = prob.point(z[:d], float(z[d]), got[1])
            values, tangent = tests(at_s, None)
        except StaircaseChangedError:  # no tangent there (both sides change): stop here
            break
        at, g = at_s, values[kind]
        if g * g_lo > 0.0:
            lo, g_lo, t_lo = at, g, tangent
            if kept == -1:
                g_hi *= 0.5
            kept = -1
        else:
            hi, g_hi, t_hi = at, g, tangent
            if kept == 1:
                g_lo *= 0.5
            kept = 1
    return at, lo, hi


def _hermite(z0, z1, m0, m1, theta: float) -> tuple[np.ndarray, np.ndarray]:
    """The cubic Hermite curve with ends ``z0, z1`` and end derivatives ``m0, m1`` at
    ``theta`` in [0, 1]: the point and its unit tangent."""
    t, t2, t3 = theta, theta**2, theta**3
    p = (2 * t3 - 3 * t2 + 1) * z0 + (t3 - 2 * t2 + t) * m0 + (-2 * t3 + 3 * t2) * z1
    p = p + (t3 - t2) * m1
    dp = (6 * t2 - 6 * t) * z0 + (3 * t2 - 4 * t + 1) * m0 + (-6 * t2 + 6 * t) * z1
    dp = dp + (3 * t2 - 2 * t) * m1
    return p, dp / np.linalg.norm(dp)
