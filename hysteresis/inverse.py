"""The numeric inverse of a continuous operator with strictly increasing branches.

For a fixed direction of input motion a continuous operator follows a smooth branch
``y = Y(u)`` up to a breakpoint (:meth:`~hysteresis.base.ContinuousHysteron.branch_flow`). If
every branch strictly increases, the output history determines the input history, and the map
``y(t) ↦ u(t)`` is again a rate-independent operator: :class:`InverseOperator`. Its state
(:class:`InverseState`) is the forward operator's state together with the forward output ``y``
it stands at (the inverse's own input).

Branch inversion (:meth:`InverseOperator.apply`): to move the output to a target ``y_k`` the
forward input moves in the direction ``d = sign(y_k − y_{k−1})``. On the branch
``branch_flow(state, d)``: if ``y_k`` lies beyond the output at the branch's breakpoint, the
forward operator is driven to the breakpoint (``apply``) and the next branch taken; otherwise
``Y(u) = y_k`` is solved on the bracket between the branch start and the breakpoint (or a
bracket found by doubling steps) by Brent's method (``scipy.optimize.brentq``), and the forward
operator driven to the root. Stopping criterion (``brentq`` with ``xtol = 4ε·max(|a|, |b|)``,
``rtol = 4ε``, ``ε`` the float64 epsilon, ``[a, b]`` the bracket): the root's bracket is at most
``8ε·max(|a|, |b|)`` wide, i.e. ``u`` to a few units in the last place of the bracket's scale,
so ``|Y(u) − y_k| <= 8ε·slope·max(|a|, |b|)`` plus the forward operator's own rounding: far
below ``1e-10`` of the output scale unless the slope is ~1e5 output scales per input scale
(measured: at most 2e-15 of the output scale on the tests' sequences). A target equal to the
breakpoint's output moves the input exactly to the breakpoint (a wiped-out extremum is wiped
out, a wall is reached).

What has an inverse (checked at construction, one-line ``ValueError`` otherwise): a
continuous operator (a piecewise-constant one jumps: outputs between its levels are never
taken) whose :attr:`~hysteresis.base.Hysteron.min_slope` is not ``<= 0`` (a flat branch — a
play between its walls — makes the inverse jump). With ``min_slope`` ``None`` (unknown) every
branch piece the inverse follows is checked: its outputs at the piece's ends and at eight
points in between (``2^-8 ... 2^-1`` of the way) must strictly increase in the direction of
motion, else ``ValueError``; a piece whose output change is below ``1e-8`` of the output scale
is not sampled (rounding could not tell a slow start from a flat one). A branch that jumps
(``breakpoint_jump``: a sum with relays) raises once a target lies at or beyond the jump.

Targets must lie in the forward operator's open output range: a saturating operator reaches
its saturation values only on a half-line of inputs, so they have no single preimage. The
inverse's own :attr:`~InverseOperator.output_range` is the forward operator's reachable input
range: ``±inf`` on a side where the forward output is unbounded; on a saturating side the input
at which the forward major loop reaches the saturation value in floating point (the ascending
branch from negative saturation for the upper end, the descending branch from positive
saturation for the lower end), found by bisection: ``[lower, upper]`` of a continuous Preisach
model, ``±(p/2 + 5.9·√2·R)`` for ``GeneralizedPlay.erf(p, R)`` (erf reaches ±1 at 5.9).

Coupled to the oscillator (:meth:`InverseOperator.branch_flow`, for the generic continuous
engine): the inverse's branch is ``u(y)`` with its partials by the implicit function theorem.
The forward memory that follows the input (a dragged wagon, ``δm = δu``) follows the inverse's
*output*, so it is *driven* memory of the inverse (:mod:`hysteresis.flow`), as is the extremum
a forward Preisach model pushes at a reversal (``pushed_gradient``). Each output evaluation is
a root solve (a few to ~15 forward branch evaluations): the generic engine ran an oscillator
driving the inverse of a four-play Prandtl–Ishlinskii operator 3.4× slower than one driving
its closed-form inverse (10 periods). Outside the forward output range the inverse is
undefined: an oscillator whose ``q`` leaves it stops with the ``ValueError`` of a target out of
range. Where the forward slope vanishes the inverse's is infinite: at every reversal of a
continuous Preisach model (``u − u* ∝ √(y − y*)``), where the variation of the oscillator's
flow diverges (``∫ dt/|t − t*|``), so tangent quantities (Lyapunov spectra, Floquet
multipliers) of an oscillator driving the inverse of a Preisach model are undefined (the
partials are ``inf`` there); its trajectories integrate, ``u(y)`` being continuous. Operators
with ``min_slope > 0`` (a Prandtl–Ishlinskii operator with a linear term) have a bounded
inverse slope everywhere.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from hysteresis._validation import (
    MAX_MAGNITUDE,
    ParameterTypeError,
    as_input_sequence,
    check_state_type,
    direction_sign,
    finite_scalar,
)
from hysteresis.base import ContinuousHysteron, Hysteron
from hysteresis.composite_memory import inverse_memory_restart, inverse_with_memory
from hysteresis.flow import BranchFlow
from hysteresis.seam import checked_branch_flow

__all__ = ["InverseOperator", "InverseState"]

_EPS = float(np.finfo(np.float64).eps)
#: Brent's tolerances: the root's bracket at the stop is <= 8ε·max(|a|, |b|) wide
_RTOL = 4.0 * _EPS
#: fractions of a branch piece where the outputs are sampled (min_slope unknown)
_SAMPLES = 2.0 ** -np.arange(8, 0, -1)
#: a piece whose output change is below this fraction of the output scale is not sampled
_RESOLVABLE = 1e-8
#: branch pieces of zero length in a row before the inversion gives up (no progress)
_MAX_STALLS = 8


@dataclass(frozen=True)
class InverseState:
    """State of an :class:`InverseOperator`.

    Attributes
    ----------
    forward:
        The forward operator's state (its input is the inverse's output ``u``).
    input:
        The inverse's input: the forward operator's output ``y`` it stands at.
    """

    forward: Any
    input: float


class InverseOperator(ContinuousHysteron[InverseState]):
    """The inverse ``y ↦ u`` of a continuous operator ``u ↦ y`` with strictly increasing
    branches, by branch inversion (see the module docstring).

    Parameters
    ----------
    operator:
        A :class:`~hysteresis.base.ContinuousHysteron` whose branches strictly increase
        (:attr:`~hysteresis.base.Hysteron.min_slope` > 0 or ``None``).

    ``operator.apply(inverse.apply(y)[0])[0]`` reproduces ``y`` to the stated accuracy, and the
    initial states agree: ``initial_state(y0)`` is the forward ``initial_state(u0)`` at the
    ``u0`` whose output on the ascending branch from negative saturation is ``y0``.
    """

    def __init__(self, operator: ContinuousHysteron) -> None:
        if not isinstance(operator, Hysteron):
            raise ParameterTypeError(
                f"operator must be a hysteresis operator (Hysteron), got {type(operator).__name__}"
            )
        if operator.piecewise_constant or not isinstance(operator, ContinuousHysteron):
            raise ValueError(
                f"operator {operator!r} has no inverse: its output jumps at switching inputs and "
                "is constant between them, so outputs between its levels have no input"
            )
        slope = operator.min_slope
        if slope is not None:
            slope = finite_scalar(slope, f"{type(operator).__name__}.min_slope")
            if slope <= 0.0:
                what = "flat over an interval of inputs" if slope == 0.0 else "decreasing"
                raise ValueError(
                    f"operator {operator!r} has no inverse: some branch is {what} (min_slope = "
                    f"{slope:g}), so the input that produced an output is not unique and the "
                    "inverse would jump"
                )
        self._operator = operator
        self._checked = slope is None
        lo, hi = (float(v) for v in operator.output_range)
        self._targets = (lo, hi)
        finite = [abs(v) for v in (lo, hi) if math.isfinite(v)]
        # the output scale that "relative" refers to (checks and the sampling threshold)
        self._scale = max(0.5 * (hi - lo), 1.0) if len(finite) == 2 else 1.0
        self._centre = self._interior_input()
        self._range = self._reachable_inputs()

    # -- properties ----------------------------------------------------------------------------
    @property
    def operator(self) -> ContinuousHysteron:
        """The forward operator."""
        return self._operator

    @property
    def output_range(self) -> tuple[float, float]:
        """The forward operator's reachable input range (see the module docstring)."""
        return self._range

    @property
    def input_range(self) -> tuple[float, float]:
        """The forward operator's output range: targets must lie strictly inside."""
        return self._targets

    @property
    def max_slope(self) -> float | None:
        """``1/min_slope`` of the forward operator when that is known (> 0), else ``None``."""
        slope = self._operator.min_slope
        return None if slope is None else 1.0 / float(slope)

    @property
    def min_slope(self) -> float | None:
        """``1/max_slope`` of the forward operator when that is known (a lower bound: the
        forward bound may cover states no input history reaches), else ``None``."""
        slope = self._operator.max_slope
        return None if slope is None or not slope > 0.0 else 1.0 / float(slope)

    def __repr__(self) -> str:
        return f"InverseOperator({self._operator!r})"

    # -- the forward operator's major loop -------------------------------------------------------
    def _ascending(self, u: float) -> float:
        """Output at ``u`` after rising from negative saturation (the contract's initial
        branch)."""
        op = self._operator
        return float(op.output(op.initial_state(u)))

    def _interior_input(self) -> float:
        """An input whose ascending output lies strictly inside the output range (0, ±1, ±2,
        ±4, ...)."""
        lo, hi = self._targets
        u = 0.0
        while abs(u) <= MAX_MAGNITUDE:
            for x in (u, -u):
                if lo < self._ascending(x) < hi:
                    return x
            u = 1.0 if u == 0.0 else 2.0 * u
        raise ValueError(
            f"operator {self._operator!r} has no inverse: its ascending branch stays saturated "
            f"at {self._ascending(0.0)!r} for every input"
        )

    def _edge(self, branch, level: float, d: int) -> float:
        """The input where ``branch`` (increasing) reaches the saturation ``level`` when moving
        in direction ``d`` from the interior input, to a few ulps (bisection); ``d·inf`` if it
        does not within ``|u| <= MAX_MAGNITUDE``."""
        inside = self._centre
        step = 1.0
        while True:
            out = inside + d * step
            if abs(out) > MAX_MAGNITUDE:
                return d * math.inf
            if (branch(out) - level) * d >= 0.0:
                break
            inside, step = out, 2.0 * step
        while abs(out - inside) > _RTOL * max(abs(out), abs(inside)):
            mid = 0.5 * (inside + out)
            if mid in (inside, out):
                break
            if (branch(mid) - level) * d >= 0.0:
                out = mid
            else:
                inside = mid
        return out

    def _reachable_inputs(self) -> tuple[float, float]:
        lo, hi = self._targets
        upper = self._edge(self._ascending, hi, 1) if math.isfinite(hi) else math.inf
        if not math.isfinite(lo):
            return (-math.inf, upper)
        if math.isfinite(upper):
            # the descending branch from positive saturation reaches the lower end last
            top = self._operator.initial_state(upper)

            def descending(u: float) -> float:
                return float(self._operator.apply(np.array([u]), top)[0][0])

            return (self._edge(descending, lo, -1), upper)
        return (self._edge(self._ascending, lo, -1), upper)

    # -- states --------------------------------------------------------------------------------
    def _check_target(self, y: float, name: str) -> None:
        lo, hi = self._targets
        if not lo < y < hi:
            raise ValueError(
                f"{name}: the target {y!r} lies outside the forward operator's open output "
                f"range ({lo}, {hi}), where the inverse is defined"
            )

    def initial_state(self, y0: float) -> InverseState:
        """The forward ``initial_state(u0)`` at the ``u0`` whose output on the ascending branch
        from negative saturation is ``y0`` (Brent's method, as in :meth:`apply`)."""
        y0 = finite_scalar(y0, "y0", MAX_MAGNITUDE)
        self._check_target(y0, "y0")
        u0 = self._solve(self._ascending, self._centre, self._ascending(self._centre), y0)
        return InverseState(self._operator.initial_state(u0), y0)

    def _check_state(self, state: Any) -> None:
        check_state_type(state, InverseState, self)
        y = finite_scalar(state.input, "state.input", MAX_MAGNITUDE)
        self._check_target(y, "state.input")
        out = float(self._operator.output(state.forward))
        if abs(out - y) > 1e-9 * max(abs(y), self._scale):
            raise ValueError(
                f"state: the forward state's output {out!r} differs from state.input {y!r}; the "
                "state belongs to another operator"
            )

    def output(self, state: InverseState) -> float:
        """The inverse's output: the forward state's input."""
        check_state_type(state, InverseState, self)
        return float(state.forward.input)

    # -- branch inversion -------------------------------------------------------------------------
    def apply(
        self, inputs: Any, state: InverseState | None = None
    ) -> tuple[np.ndarray, InverseState]:
        """Inputs ``u_k`` of the forward operator that produce the outputs ``inputs`` (``y_k``)
        from ``state`` (default ``initial_state(inputs[0])``), and the final state."""
        y = as_input_sequence(inputs)
        for value in (float(np.min(y)), float(np.max(y))):
            self._check_target(value, "inputs")
        if state is None:
            state = self.initial_state(float(y[0]))
        else:
            self._check_state(state)
        forward, last = state.forward, float(state.input)
        out = np.empty(y.size)
        for k, target in enumerate(y.tolist()):
            if target != last:
                forward = self._follow(forward, target, 1 if target > last else -1)
                last = target
            out[k] = float(forward.input)
        return out, InverseState(forward, last)

    def _follow(self, forward: Any, target: float, d: int) -> Any:
        """The forward state after moving its output in direction ``d`` to ``target``, piece
        by piece along its branches."""
        op = self._operator
        stalls = 0
        while True:
            flow = checked_branch_flow(op, forward, d)
            u0 = flow.input
            y0 = float(flow.output(u0))
            if (target - y0) * d <= 0.0:  # reached (within rounding of the last solve)
                return forward
            bp = float(flow.breakpoint)
            if math.isfinite(bp):
                y_bp = float(flow.output(bp))
                if (target - y_bp) * d >= 0.0:
                    if flow.breakpoint_jump != 0.0:
                        raise ValueError(
                            f"operator {op!r} has no inverse: its output jumps by "
                            f"{flow.breakpoint_jump!r} at input {bp!r}, so the outputs in "
                            "between have no input"
                        )
                    self._check_piece(flow, u0, bp, y0, y_bp)
                    stalls = stalls + 1 if bp == u0 else 0
                    if stalls > _MAX_STALLS:
                        raise RuntimeError(
                            f"{type(op).__name__}.branch_flow reports the breakpoint {bp!r} at "
                            "its own input again after apply() moved there (no progress)"
                        )
                    forward = op.apply(np.array([bp]), forward)[1]
                    continue
            u = self._solve(flow.output, u0, y0, target, bp)
            self._check_piece(flow, u0, u, y0, target)
            return op.apply(np.array([u]), forward)[1]

    def _solve(self, branch, u0: float, y0: float, target: float, end: float = math.nan) -> float:
        """Root of ``branch(u) = target`` beyond ``u0`` (``branch`` increasing, ``branch(u0) =
        y0``): bracketed by ``end`` if finite (``branch(end)`` at or beyond the target), else
        by doubling steps from ``u0``; then Brent's method (module docstring)."""
        if target == y0:
            return u0
        d = 1 if target > y0 else -1

        def residual(u: float) -> float:
            return float(branch(u)) - target

        near = u0
        if math.isfinite(end):
            far = end
        else:
            step = 1e-3 * max(abs(u0), 1.0)
            r_near = y0 - target
            while True:
                far = near + d * step
                if abs(far) > MAX_MAGNITUDE:
                    raise ValueError(
                        f"operator {self._operator!r}: the target {target!r} lies beyond the "
                        f"branch followed from input {u0!r}, which saturates below it"
                    )
                r_far = residual(far)
                if r_far * d >= 0.0:
                    break
                if (r_far - r_near) * d < 0.0:
                    raise ValueError(
                        f"operator {self._operator!r} has no inverse: a branch decreases, from "
                        f"input {near!r} to {far!r} its output goes {r_near + target!r} -> "
                        f"{r_far + target!r}"
                    )
                near, r_near, step = far, r_far, 2.0 * step
        # scipy.optimize costs ~0.25 s at import: loaded where used (fast `hyst` start)
        from scipy.optimize import brentq

        a, b = (near, far) if near < far else (far, near)
        if residual(a) == 0.0:
            return a
        if residual(b) == 0.0:
            return b
        return float(brentq(residual, a, b, xtol=_RTOL * max(abs(a), abs(b)), rtol=_RTOL))

    def _check_piece(self, flow: BranchFlow, ua: float, ub: float, ya: float, yb: float) -> None:
        """With ``min_slope`` unknown: the outputs at the ends of the piece ``[ua, ub]`` and at
        :data:`_SAMPLES` of the way must strictly increase in the flow's direction."""
        if not self._checked or ub == ua:
            return
        d = flow.direction
        us, ys = np.array([ua, ub]), np.array([ya, yb])
        if (yb - ya) * d > _RESOLVABLE * max(abs(ya), abs(yb), self._scale):
            inner = ua + (ub - ua) * _SAMPLES
            us = np.concatenate([[ua], inner, [ub]])
            ys = np.concatenate([[ya], np.asarray(flow.output(inner), dtype=np.float64), [yb]])
        steps = np.diff(ys) * d
        if np.all(steps > 0.0):
            return
        k = int(np.argmax(steps <= 0.0))
        shape = "is flat" if steps[k] == 0.0 else "decreases"
        raise ValueError(
            f"operator {self._operator!r} has no inverse: its branch in direction {d:+d} "
            f"{shape} from input {us[k]!r} to {us[k + 1]!r} (output {ys[k]!r} -> "
            f"{ys[k + 1]!r}), so the inverse would jump"
        )

    # -- branch flow ------------------------------------------------------------------------------
    def branch_flow(self, state: InverseState, direction: int) -> BranchFlow:
        """The inverse's branch in ``direction`` (+1: ``y`` rising, which moves the forward
        input up as well), derived from the forward branch ``y = G(u, m)`` of
        ``operator.branch_flow(state.forward, direction)``.

        Output: ``u(y)``, the root of the forward branch (as :meth:`apply` finds it; before
        the branch start the start input, for integrator stages that look back). Memory: the
        forward branch's *frozen* variables, frozen here too. With the forward slope
        ``S = ∂G/∂u + Σ_slaved ∂G/∂m`` at ``u(y)`` the implicit function theorem gives
        ``∂u/∂y = 1/S`` and ``∂u/∂m_j = −(∂G/∂m_j)/S`` (``inf`` where ``S = 0``: the inverse of
        a continuous Preisach model at a reversal). The forward's *slaved* variables (a
        dragged wagon, ``δm = δu``) follow the inverse's output, not its input: they are
        *driven* (:mod:`hysteresis.flow`), ``m_s(y) = m_s0 + u(y) − u0`` with the gradient of
        ``u``. Breakpoint: the forward branch's breakpoint output ``G(bp)``; there the forward
        breakpoint's variables (wiped-out extrema, and wagons whose wall is reached, which
        become driven) leave the memory. A reversal pushes what the forward pushes (the
        reversal input ``u*`` of a Preisach model), with ``δu* = (δy − Σ ∂G/∂m_j δm_j)/S`` on
        the forward branch that arrived there (``pushed_gradient``).
        """
        d = direction_sign(direction)
        self._check_state(state)
        op = self._operator
        forward = state.forward
        flow = checked_branch_flow(op, forward, d)
        y0 = float(state.input)
        keep = np.flatnonzero(~flow.slaved)
        moved = np.flatnonzero(flow.slaved)
        labels = tuple(flow.labels[i] for i in keep)
        y_bp = _breakpoint_output(flow, y0)
        solve = self._branch_solver(flow, y0, y_bp)

        def gradient(u: float) -> tuple[float, np.ndarray]:
            return _inverse_gradient(flow, u, keep, moved)

        def output(y):
            y = np.asarray(y, dtype=np.float64)
            return np.vectorize(solve, otypes=[np.float64])(y)[()]

        def partials(y):
            y = np.asarray(y, dtype=np.float64)
            d_y = np.empty(y.shape)
            d_m = np.empty(y.shape + (keep.size,))
            for k in np.ndindex(y.shape):
                d_y[k], d_m[k] = gradient(solve(float(y[k])))
            return d_y[()], d_m

        extra: dict[str, Any] = {}
        if moved.size or flow.driven_labels:
            driven_labels = tuple(flow.labels[i] for i in moved) + flow.driven_labels
            extra.update(
                driven_labels=driven_labels, driven=_driven(flow, solve, gradient, keep, moved)
            )
        pushed = np.asarray(flow.pushed, dtype=bool)[keep]
        if np.any(pushed):
            arrived = checked_branch_flow(op, forward, -d)
            extra["pushed_gradient"] = _pushed_gradient(flow, arrived, keep, moved)
        gone = set(flow.breakpoint_resets) | set(flow.breakpoint_removes)
        return BranchFlow(
            direction=d,
            input=y0,
            labels=labels,
            memory=np.asarray(flow.memory, dtype=np.float64)[keep],
            slaved=np.zeros(keep.size, dtype=bool),
            output=output,
            partials=partials,
            breakpoint=y_bp,
            breakpoint_removes=tuple(label for label in labels if label in gone),
            reversal_pushes=flow.reversal_pushes,
            pushed=pushed,
            constant_partials=flow.constant_partials,
            **extra,
        )

    # -- the memory as coordinates (periodic orbits; hysteresis.composite_memory) ---------------
    def with_memory(
        self, state: InverseState, values: Any, input: float, direction: int
    ) -> InverseState:
        """The state at ``input`` (a forward output ``y``) whose branch reports the forward
        frozen memory ``values``: the forward input solves ``G(u) = y`` with that memory held
        (:func:`hysteresis.composite_memory.inverse_with_memory`); refused where the forward
        branch memory does not determine the forward input (a Duhem operator's ``z0``)."""
        d = direction_sign(direction)
        self._check_state(state)
        y = finite_scalar(input, "input", MAX_MAGNITUDE)
        self._check_target(y, "input")
        flow = checked_branch_flow(self._operator, state.forward, d)
        forward = inverse_with_memory(self._operator, state.forward, flow, values, y, self._solve)
        return InverseState(forward, y)

    def memory_restart(self, state: InverseState, direction: int, u: float) -> tuple:
        """The forward's restart at ``u(y)`` (``u`` here is the inverse's input ``y``), its
        slaved columns following ``δu = ∂u/∂y δy + ∂u/∂m δm``
        (:func:`hysteresis.composite_memory.inverse_memory_restart`)."""
        d = direction_sign(direction)
        self._check_state(state)
        flow = checked_branch_flow(self._operator, state.forward, d)
        keep = np.flatnonzero(~flow.slaved)
        moved = np.flatnonzero(flow.slaved)
        y0 = float(state.input)
        x = self._branch_solver(flow, y0, _breakpoint_output(flow, y0))(float(u))

        def gradient(at: float) -> tuple[float, np.ndarray]:
            return _inverse_gradient(flow, at, keep, moved)

        return inverse_memory_restart(self._operator, state.forward, flow, x, gradient)

    def _branch_solver(self, flow: BranchFlow, y0: float, y_bp: float):
        """``y -> u(y)`` on ``flow`` from ``(flow.input, y0)`` (one value remembered: the
        engine asks for the output and the partials at the same ``y``)."""
        d, u0, bp = flow.direction, float(flow.input), float(flow.breakpoint)
        y_start = float(flow.output(u0))  # y0 up to the rounding of the last solve
        last = [y0, u0]

        def solve(y: float) -> float:
            if y == last[0]:
                return last[1]
            self._check_target(y, "y")
            if (y - y_start) * d <= 0.0:
                u = u0
            elif (y - y_bp) * d <= 0.0:
                u = self._solve(flow.output, u0, y_start, y, bp)
            else:  # past the breakpoint (an integrator stage): the branch's formula continued
                u = self._solve(flow.output, bp, y_bp, y)
            last[:] = [y, u]
            return u

        return solve


def _breakpoint_output(flow: BranchFlow, y0: float) -> float:
    """The forward output at the breakpoint of ``flow`` (``±inf`` without one), not behind
    ``y0`` (the forward output at the branch start differs from ``y0`` by rounding)."""
    d, bp = flow.direction, float(flow.breakpoint)
    if not math.isfinite(bp):
        return d * math.inf
    y_bp = float(flow.output(bp))
    return y0 if (y_bp - y0) * d < 0.0 else y_bp


def _inverse_gradient(
    flow: BranchFlow, u: float, keep: np.ndarray, moved: np.ndarray
) -> tuple[float, np.ndarray]:
    """``(∂u/∂y, ∂u/∂m_keep)`` on the forward ``flow`` at ``u`` (implicit function theorem:
    ``1/S`` and ``−(∂G/∂m)/S``, ``S`` the forward slope; ``inf``/``∓inf`` where ``S = 0``)."""
    g_u, g_m = flow.partials(u)
    g_m = np.asarray(g_m, dtype=np.float64)
    slope = float(g_u) + float(np.sum(g_m[moved]))
    if not slope > 0.0:
        with np.errstate(divide="ignore", invalid="ignore"):
            return math.inf, np.where(g_m[keep] == 0.0, 0.0, -np.sign(g_m[keep]) * np.inf)
    return 1.0 / slope, -g_m[keep] / slope


def _driven(flow: BranchFlow, solve, gradient, keep: np.ndarray, moved: np.ndarray):
    """``driven`` of the inverse branch: the forward's slaved variables, ``m_s0 + u(y) − u0``
    with the gradient of ``u`` (``δm_s = δu = ∂u/∂y δy + ∂u/∂m δm``), then the forward's own
    driven variables, ``δm_d = c·δu + D_keep δm`` with ``c = d_du + Σ_slaved D`` (their
    forward gradient ``(d_du, D)``, the slaved columns moving with ``u``)."""
    u0 = float(flow.input)
    start = np.asarray(flow.memory, dtype=np.float64)[moved]
    n_s, n_d, n = moved.size, len(flow.driven_labels), flow.n_memory

    def driven(y):
        u = solve(float(y))
        d_y, d_m = gradient(u)
        values = np.empty(n_s + n_d)
        rows_y = np.full(n_s + n_d, d_y)
        rows_m = np.tile(d_m, (n_s + n_d, 1))
        values[:n_s] = start + (u - u0)
        if n_d:
            v, d_du, d_dm = flow.driven(u)
            d_dm = np.asarray(d_dm, dtype=np.float64).reshape(n_d, n)
            along = np.asarray(d_du, dtype=np.float64).reshape(n_d) + d_dm[:, moved].sum(axis=1)
            values[n_s:] = np.asarray(v, dtype=np.float64).reshape(n_d)
            rows_y[n_s:] = along * d_y
            rows_m[n_s:] = along[:, None] * d_m[None, :] + d_dm[:, keep]
        return values, rows_y, rows_m

    return driven


def _pushed_gradient(flow: BranchFlow, arrived: BranchFlow, keep: np.ndarray, moved: np.ndarray):
    """``pushed_gradient`` of an inverse branch that starts with a reversal at ``u*``.

    The forward pushes ``m_p`` with ``δm_p = p_du·δu* + P δm`` (its ``pushed_gradient``;
    ``δm_p = δu*`` without one), and ``u*`` moves with ``δu* = (δy − Σ ∂G/∂m_j δm_j)/S`` on
    the forward branch ``arrived`` that reached it (its frozen variables are among the
    inverse's labels). Columns: the inverse's labels (``flow``'s frozen ones), zero on the
    pushed ones."""
    labels = [flow.labels[i] for i in keep]
    position = {label: i for i, label in enumerate(labels)}
    u_star = float(flow.input)
    frozen = np.flatnonzero(~arrived.slaved)
    a_y, a_m = _inverse_gradient(arrived, u_star, frozen, np.flatnonzero(arrived.slaved))
    a_row = np.zeros(len(labels))
    for j, value in zip(frozen, a_m, strict=True):
        a_row[position[arrived.labels[j]]] = value
    n_p = int(np.count_nonzero(flow.pushed))
    if flow.pushed_gradient is None:
        along, p_keep = np.ones(n_p), np.zeros((n_p, len(labels)))
    else:
        p_du, p_dm = flow.pushed_gradient(u_star)
        p_dm = np.asarray(p_dm, dtype=np.float64).reshape(n_p, flow.n_memory)
        along = np.asarray(p_du, dtype=np.float64).reshape(n_p) + p_dm[:, moved].sum(axis=1)
        p_keep = p_dm[:, keep]
    d_y = along * a_y
    d_m = along[:, None] * a_row[None, :] + p_keep

    def pushed_gradient(y):
        return d_y.copy(), d_m.copy()

    return pushed_gradient
