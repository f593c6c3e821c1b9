"""Duhem operators: hysteresis given by a differential equation in the input.

A rate-independent Duhem operator (Visintin, *Differential Models of Hysteresis*, 1994, ch. V)
has one internal variable ``z`` that obeys

    dz/du = g₊(u, z)   while the input rises,      dz/du = g₋(u, z)   while it falls,

and outputs ``y = z`` (or ``y = h(u, z)``, a given output map). Only the *path* of the input
enters (``dz = g_d(u, z) du``), so the output does not depend on the speed of the input: it is a
hysteresis operator. Bouc–Wen (:class:`hysteresis.bouc_wen.BoucWen`) is the best-known member.

State
-----
:class:`DuhemState` ``(z, input, direction)``: ``(u, z)`` is the whole memory (the ODE is of
first order); ``direction`` (+1 the input last rose, −1 it last fell, 0 no motion yet) is
informative only — a reversal is simply the switch from one ODE to the other, which needs no
memory of the past direction, so outputs never depend on it.

Integration
-----------
On every monotone piece of the input the ODE is integrated in ``u`` with
``scipy.integrate.solve_ivp`` (DOP853, ``rtol = atol = 1e-12``); values between steps come from
its 7th-order dense output. Inputs ``z`` where ``g`` is not smooth (``kinks``: ``z = 0`` for
Bouc–Wen's ``|z|ⁿ``) stop the integration by an event and restart it there, so no step straddles
them. Error: about ``1e-12`` per unit of ``z`` per step, a few ``1e-12`` at most on branches
of unit length (measured against Bouc–Wen's closed-form branches, tests/test_hysteresis/
test_duhem.py). ``apply`` from a returned state continues exactly (the state is the whole
memory), and sampling a path more finely changes the outputs at common inputs by no more than
that error (rate independence).

Branch flow (what the oscillator's generic continuous engine integrates)
----------------------------------------------------------------------
On the branch followed in direction ``d`` from the state ``(u0, z0)`` the memory variable is
``z0``, the value at the branch start, frozen on the branch; its label alternates with the
direction: ``"z+"`` on a falling branch (where the last rise ended), ``"z-"`` on a rising one.
The output is ``Z(u; z0)``, the solution of ``dz/du = g_d`` through ``(u0, z0)``, with

    ∂Z/∂u = g_d(u, Z)   (z0 fixed),      Φ(u) = ∂Z/∂z0 = exp ∫_{u0}^{u} ∂g_d/∂z (s, Z(s)) ds,

``Φ`` from the variational equation ``dΦ/du = ∂g_d/∂z·Φ``, ``Φ(u0) = 1``, integrated alongside.
The branch's solution is integrated once (lazily extended on both sides as the engine asks for
inputs; the integrator's stages may look slightly behind ``u0``) and cached in the flow.

The current ``z`` is the *driven* variable of the branch (:mod:`hysteresis.flow`, "Driven
memory"), labelled as the next branch's memory (``"z+"`` on a rising branch): at a reversal at
``u*`` it becomes the new branch's ``z0``. Its gradient is the one of the new branch's
coordinate, the value *at the nominal reversal input* of the reversed branch through the
reversal point: a reversal moved to ``u* + δu`` reaches ``Z + g_d δu``, and the reversed branch
through it passes ``u*`` at ``Z + (g_d − g_{−d}) δu``. Hence
``d_du = g_d(u, Z) − g_{−d}(u, Z)``, ``d_dm = Φ(u)``, and the engine's reconciliation gives
``δz0_new = (g_d − g_{−d})·δq + Φ·δz0_old`` (the ``(q, v)`` perturbations pass unchanged: the
output is continuous). There are no breakpoints: reversals are the only events.

``initial_state(u0)`` ("rising from negative saturation", the contract): a general Duhem
operator has no canonical saturation, so it is the rising curve through ``origin`` (default
``(0, 0)``) evaluated at ``u0``; a subclass that knows its saturation overrides it (Bouc–Wen:
``z = z_max``).
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from hysteresis import _duhem_kernels as _kernels
from hysteresis._validation import (
    MAX_MAGNITUDE,
    as_input_sequence,
    check_state_type,
    direction_sign,
    finite_scalar,
    frozen_state_reduce,
)
from hysteresis.base import ContinuousHysteron
from hysteresis.flow import BranchFlow, CompiledFlow

__all__ = ["Duhem", "DuhemDomainError", "DuhemState", "RTOL", "ATOL"]

#: tolerances of every branch integration (DOP853)
RTOL = 1e-12
ATOL = 1e-12
#: least extension of a cached branch solution (input units): few solve_ivp calls per branch
_MIN_SPAN = 1.0


@dataclass(frozen=True)
class DuhemState:
    """State of a Duhem operator: the internal variable ``z`` at ``input``, and the direction of
    the last input motion (+1, −1; 0 none yet), which is informative only."""

    z: float
    input: float
    direction: int = 0

    def __reduce__(self) -> tuple:
        return frozen_state_reduce(self)


class DuhemDomainError(ValueError):
    """The branch ODE of a Duhem operator is ill-posed at the state reached (an operator's
    ``slope`` raises it, e.g. Jiles–Atherton's pole). A branch solution integrates up to where
    it occurs and raises it only for inputs at or beyond that point."""


def _z_label(i: int) -> str:
    """The compiled engine's tangent row of the current internal variable."""
    return "z"


def _memory(state: DuhemState) -> float:
    """The internal variable of a state (the compiled description's ``memory``)."""
    return state.z


def _label(direction: int) -> str:
    """Memory label of a branch in ``direction``: where the opposite motion ended."""
    return "z-" if direction > 0 else "z+"


class _BranchSolution:
    """``Z(u)`` and ``Φ(u) = ∂Z/∂z0`` of one branch through ``(u0, z0)``, integrated lazily on
    both sides of ``u0`` and kept as DOP853 dense-output pieces."""

    def __init__(self, op: Duhem, direction: int, u0: float, z0: float) -> None:
        self._op = op
        self._d = direction
        self._u0 = u0
        self._z0 = z0
        # per side (+1 right of u0, −1 left): piece ends |u − u0| (sorted), interpolants, and
        # the end point (u, z, Φ) reached so far
        self._ends: dict[int, list[float]] = {1: [], -1: []}
        self._pieces: dict[int, list[Any]] = {1: [], -1: []}
        self._tip: dict[int, tuple[float, float, float]] = {1: (u0, z0, 1.0), -1: (u0, z0, 1.0)}
        # per side: the domain error met at the end of the integrated stretch (None: none)
        self._limit: dict[int, DuhemDomainError | None] = {1: None, -1: None}
        self._error: DuhemDomainError | None = None

    def _rhs(self, u: float, y: np.ndarray) -> np.ndarray:
        try:
            g = self._op.slope(u, y[0], self._d)
            gz = self._op.slope_partials(u, y[0], self._d)[1]
        except DuhemDomainError as error:
            # NaN makes the integrator reject the step and shrink it: it closes in on the
            # point of ill-posedness, where its step collapses (status -1, handled below)
            self._error = error
            return np.array([math.nan, math.nan])
        return np.array([g, gz * y[1]])

    def extend_to(self, u: float) -> None:
        """Integrate until ``u`` is covered (plus a margin, so that an integrator's steps that
        creep forward need few extensions)."""
        side = 1 if u >= self._u0 else -1
        reach = abs(self._tip[side][0] - self._u0)
        if abs(u - self._u0) <= reach and (self._pieces[side] or u == self._u0):
            return
        if self._limit[side] is not None:
            raise self._limit[side]
        target = self._u0 + side * max(abs(u - self._u0) * 1.5, reach + _MIN_SPAN)
        self._integrate(side, target)

    def _integrate(self, side: int, target: float) -> None:
        # scipy.integrate costs ~0.4 s at import: loaded where used (fast `import hysteresis`,
        # as in oscillators.engines.continuous)
        from scipy.integrate import solve_ivp

        kinks = self._op.kinks
        u_a, z_a, phi_a = self._tip[side]
        try:
            self._op.slope(u_a, z_a, self._d)
        except DuhemDomainError as error:
            self._limit[side] = error
            raise
        for _ in range(4 * len(kinks) + 8):  # each kink is crossed at most a few times
            events = []
            for c in kinks:

                def event(u, y, c=c):
                    return y[0] - c

                event.terminal = True
                if z_a == c:  # leaving the kink: only the crossing back counts
                    g = self._op.slope(u_a, z_a, self._d)
                    event.direction = -np.sign(g * side) if g != 0.0 else 0.0
                    if g == 0.0:
                        continue
                events.append(event)
            sol = solve_ivp(
                self._rhs,
                (u_a, target),
                np.array([z_a, phi_a]),
                method="DOP853",
                dense_output=True,
                events=events or None,
                rtol=RTOL,
                atol=ATOL,
            )
            if sol.status < 0:
                # the step collapsed: at a point of ill-posedness (NaN from the slope) or
                # approaching one (a slope growing without bound); the operator names it
                if self._error is None:
                    u_t, z_t = float(sol.t[-1]), float(sol.y[0, -1])
                    self._error = self._op.domain_error(u_t, z_t, self._d, sol.message)
                self._stop_at_domain_error(side, sol)
                return
            if not np.all(np.isfinite(sol.y[:, -1])):
                raise ValueError(
                    f"{type(self._op).__name__}: the branch ODE could not be integrated from "
                    f"u = {u_a!r}, z = {z_a!r} (direction {self._d:+d}): {sol.message}"
                )
            ode = sol.sol
            for k, interp in enumerate(ode.interpolants):
                lo, hi = ode.ts[k], ode.ts[k + 1]
                self._ends[side].append(abs(max(lo, hi, key=lambda t: side * t) - self._u0))
                self._pieces[side].append(interp)
            u_a = float(sol.t[-1])
            z_a, phi_a = float(sol.y[0, -1]), float(sol.y[1, -1])
            if sol.status == 1:  # a kink: z exactly there, integration restarted
                hit = [ev for ev in sol.y_events if len(ev)]
                z_a = float(min(kinks, key=lambda c: abs(c - hit[0][0][0])))
            self._tip[side] = (u_a, z_a, phi_a)
            if sol.status == 0:
                return
        raise ValueError(
            f"{type(self._op).__name__}: the branch crosses its kinks {kinks} too often near "
            f"u = {u_a!r} (direction {self._d:+d})"
        )

    def _stop_at_domain_error(self, side: int, sol: Any) -> None:
        """Keep the steps accepted before the domain error; raise it for the inputs beyond
        them (only if they are asked for: the extension past the requested input is a margin)."""
        if sol.t.size > 1:
            ode = sol.sol
            for k, interp in enumerate(ode.interpolants):
                lo, hi = ode.ts[k], ode.ts[k + 1]
                self._ends[side].append(abs(max(lo, hi, key=lambda t: side * t) - self._u0))
                self._pieces[side].append(interp)
            self._tip[side] = (float(sol.t[-1]), float(sol.y[0, -1]), float(sol.y[1, -1]))
        self._limit[side] = self._error
        self._error = None

    def __call__(self, u: float) -> tuple[float, float]:
        """``(Z(u), Φ(u))`` for a scalar ``u``."""
        if u == self._u0:
            return self._z0, 1.0
        self.extend_to(u)
        side = 1 if u > self._u0 else -1
        if self._limit[side] is not None and abs(u - self._u0) > abs(self._tip[side][0] - self._u0):
            raise self._limit[side]
        ends = self._ends[side]
        k = min(bisect.bisect_left(ends, abs(u - self._u0)), len(ends) - 1)
        y = self._pieces[side][k](u)
        return float(y[0]), float(y[1])


class Duhem(ContinuousHysteron[DuhemState]):
    """The rate-independent Duhem operator ``dz/du = g₊(u, z)`` (input rising), ``g₋(u, z)``
    (falling), output ``z`` or ``output(u, z)`` (see the module docstring).

    Parameters
    ----------
    rising, falling:
        ``g₊(u, z)`` and ``g₋(u, z)`` (scalar in, scalar out).
    rising_partials, falling_partials:
        ``(u, z) -> (∂g/∂u, ∂g/∂z)``; ``∂g/∂z`` drives the variational equation of the tangent
        (``∂g/∂u`` is part of the description, not needed by the integration).
    output, output_partials:
        The output map ``h(u, z)`` and ``(u, z) -> (∂h/∂u, ∂h/∂z)``, given together (default:
        ``y = z``).
    origin:
        ``(u, z)`` on the curve that :meth:`initial_state` follows (default ``(0, 0)``).
    kinks:
        Values of ``z`` where ``g`` is not smooth (the integration restarts there).
    """

    def __init__(
        self,
        rising: Callable[[float, float], float],
        falling: Callable[[float, float], float],
        *,
        rising_partials: Callable[[float, float], tuple[float, float]],
        falling_partials: Callable[[float, float], tuple[float, float]],
        output: Callable[[float, float], float] | None = None,
        output_partials: Callable[[float, float], tuple[float, float]] | None = None,
        origin: tuple[float, float] = (0.0, 0.0),
        kinks: tuple[float, ...] = (),
    ) -> None:
        for name, fn in (
            ("rising", rising),
            ("falling", falling),
            ("rising_partials", rising_partials),
            ("falling_partials", falling_partials),
        ):
            if not callable(fn):
                raise TypeError(f"{name} must be a callable of (u, z), got {type(fn).__name__}")
        if (output is None) != (output_partials is None):
            raise TypeError("output and output_partials must be given together (or neither)")
        if output is not None and not (callable(output) and callable(output_partials)):
            raise TypeError("output and output_partials must be callables of (u, z)")
        self._g = {1: rising, -1: falling}
        self._dg = {1: rising_partials, -1: falling_partials}
        self._h = output
        self._dh = output_partials
        self._set_common(origin, kinks)
        for d in (1, -1):  # one probe: a wrong signature fails here, not deep in an engine
            self.slope(self._origin[0], self._origin[1], d)
            self.slope_partials(self._origin[0], self._origin[1], d)

    def _set_common(self, origin: Any, kinks: Any) -> None:
        if not (isinstance(origin, tuple | list) and len(origin) == 2):
            raise ValueError(f"origin must be a pair (u, z), got {origin!r}")
        self._origin = (
            finite_scalar(origin[0], "origin[0]", MAX_MAGNITUDE),
            finite_scalar(origin[1], "origin[1]", MAX_MAGNITUDE),
        )
        self._kinks = tuple(finite_scalar(c, "kinks") for c in kinks)

    # -- the ODE ---------------------------------------------------------------------------
    @property
    def kinks(self) -> tuple[float, ...]:
        """Values of ``z`` where the slope functions are not smooth."""
        return self._kinks

    def slope(self, u: float, z: float, direction: int) -> float:
        """``g_d(u, z) = dz/du`` while the input moves in ``direction``."""
        value = float(self._g[direction](u, z))
        if not math.isfinite(value):
            raise ValueError(
                f"{'rising' if direction > 0 else 'falling'}(u, z) returned {value} at "
                f"u = {u!r}, z = {z!r}; it must be finite"
            )
        return value

    def slope_partials(self, u: float, z: float, direction: int) -> tuple[float, float]:
        """``(∂g_d/∂u, ∂g_d/∂z)`` at ``(u, z)``."""
        du, dz = self._dg[direction](u, z)
        return float(du), float(dz)

    def map_output(self, u: float, z: float) -> float:
        """The output ``h(u, z)`` (``z`` without an output map)."""
        return float(z) if self._h is None else float(self._h(u, z))

    def map_output_partials(self, u: float, z: float) -> tuple[float, float]:
        """``(∂h/∂u, ∂h/∂z)`` (``(0, 1)`` without an output map)."""
        if self._dh is None:
            return 0.0, 1.0
        du, dz = self._dh(u, z)
        return float(du), float(dz)

    @property
    def output_range(self) -> tuple[float, float]:
        """Unknown for a general Duhem operator: ``(−inf, inf)``."""
        return (-math.inf, math.inf)

    # -- states ----------------------------------------------------------------------------
    def state(self, z: float, input: float, direction: int = 0) -> DuhemState:
        """The state with internal variable ``z`` at ``input`` (``direction``: +1, −1, or 0 for
        no motion yet; informative only)."""
        z = finite_scalar(z, "z", MAX_MAGNITUDE)
        u = finite_scalar(input, "input", MAX_MAGNITUDE)
        if direction not in (-1, 0, 1) or isinstance(direction, bool):
            raise ValueError(f"direction must be +1, -1 or 0, got {direction!r}")
        return DuhemState(z, u, int(direction))

    def _check_state(self, state: Any) -> DuhemState:
        check_state_type(state, DuhemState, self)
        return state

    def initial_state(self, u0: float) -> DuhemState:
        """The rising curve through ``origin`` evaluated at ``u0`` (module docstring)."""
        u0 = finite_scalar(u0, "u0", MAX_MAGNITUDE)
        u_s, z_s = self._origin
        z, _ = _BranchSolution(self, 1, u_s, z_s)(u0)
        return DuhemState(z, u0, 1)

    def output(self, state: DuhemState) -> float:
        """``h(u, z)`` of the state (``z`` without an output map)."""
        state = self._check_state(state)
        return self.map_output(state.input, state.z)

    # -- the compiled path ----------------------------------------------------------------------
    def compiled_model(self) -> tuple[str, dict[str, float]] | None:
        """The compiled right-hand side this operator's slope and output equal, as ``(model,
        parameters)`` with ``model`` one of :mod:`hysteresis._duhem_kernels`' models
        (``"bouc_wen"``: ``A, beta, gamma, n``; ``"jiles_atherton"``: ``ms, a, k, c,
        alpha``), or ``None`` (the default: a general Duhem operator of user functions runs on
        the generic engine). A subclass that changes ``slope`` or the output returns ``None``."""
        return None

    def compiled_flow(self) -> CompiledFlow | None:
        """The ``"duhem"`` description of :meth:`compiled_model` for the oscillator's compiled
        Duhem engine (``(q, v, z)`` integrated in time, :class:`hysteresis.flow.CompiledFlow`),
        or ``None``."""
        described = self.compiled_model()
        if described is None:
            return None
        model, parameters = described
        return CompiledFlow(
            kind="duhem",
            label=_z_label,
            model=model,
            parameters=parameters,
            memory=_memory,
            make_state=self.state,
        )

    def apply(self, inputs: Any, state: DuhemState | None = None) -> tuple[np.ndarray, DuhemState]:
        """Integrate the ODE along every monotone piece of ``inputs`` (the input moves
        monotonically between consecutive samples); a returned state continues exactly."""
        u = as_input_sequence(inputs)
        state = self.initial_state(float(u[0])) if state is None else self._check_state(state)
        z_all = np.empty(u.size)
        u_a, z_a, direction = state.input, state.z, state.direction
        i = 0
        while i < u.size:
            step = u[i] - u_a
            if step == 0.0:
                z_all[i] = z_a
                i += 1
                continue
            d = 1 if step > 0 else -1
            j = i  # the run of samples moving monotonically in direction d from u_a
            prev = u_a
            while j < u.size and (u[j] - prev) * d >= 0.0:
                prev = u[j]
                j += 1
            branch = _BranchSolution(self, d, u_a, z_a)
            branch.extend_to(u[j - 1])
            for k in range(i, j):
                z_all[k] = branch(float(u[k]))[0]
            u_a, z_a, direction = float(u[j - 1]), float(z_all[j - 1]), d
            i = j
        return self._outputs(u, z_all), DuhemState(z_a, u_a, direction)

    def _compiled_apply(
        self,
        inputs: Any,
        state: DuhemState | None,
        model: int,
        params: np.ndarray,
        z_scale: float,
        u_scale: float,
    ) -> tuple[np.ndarray, DuhemState]:
        """``apply`` by the compiled kernel of a built-in model (``model``, ``params`` of
        :func:`hysteresis._duhem_kernels.integrate_record`; ``z_scale``, ``u_scale`` the scales
        of ``z`` and of the input)."""
        u = as_input_sequence(inputs)
        state = self.initial_state(float(u[0])) if state is None else self._check_state(state)
        z = np.empty(u.size)
        status, u_end, z_end, done = _kernels.integrate_record(
            model, params, z_scale, u_scale, u, state.input, state.z, z
        )
        steps = np.diff(np.concatenate(([state.input], u[: done + 1])))
        moved = np.flatnonzero(steps)
        direction = state.direction if moved.size == 0 else (1 if steps[moved[-1]] > 0 else -1)
        if status == _kernels.STATUS_ILL_POSED:
            raise self.domain_error(u_end, z_end, direction)
        if status != _kernels.STATUS_OK:
            raise ValueError(
                f"{self!r}: the integration step collapsed at u = {u_end!r}, z = {z_end!r}"
            )
        return self._outputs(u, z), DuhemState(float(z_end), float(u_end), direction)

    def domain_error(
        self, u: float, z: float, direction: int, reason: str = "its step collapsed"
    ) -> DuhemDomainError:
        """The error for a branch that cannot be continued past ``(u, z)`` (a subclass with a
        known ill-posedness names its parameters). Part of the contract a compiled engine uses:
        it raises this where its kernel reports the model ill-posed, so both engines raise the
        operator's own error."""
        return DuhemDomainError(
            f"{type(self).__name__}: the branch ODE could not be integrated past u = {u!r}, "
            f"z = {z!r} (direction {direction:+d}): {reason}"
        )

    def _outputs(self, inputs: np.ndarray, z: np.ndarray) -> np.ndarray:
        """The outputs ``h(u_i, z_i)`` of a record (``z`` itself without an output map)."""
        if self._h is None:
            return z
        return np.array([self.map_output(a, b) for a, b in zip(inputs, z, strict=True)])

    # -- the branch flow -------------------------------------------------------------------
    def branch_flow(self, state: DuhemState, direction: int) -> BranchFlow:
        """Memory ``z0`` (label ``"z-"`` rising, ``"z+"`` falling), output ``h(u, Z(u; z0))``,
        the current ``Z`` driven with the reversed branch's label (module docstring)."""
        direction = direction_sign(direction)
        state = self._check_state(state)
        u0, z0 = state.input, state.z
        sol = _BranchSolution(self, direction, u0, z0)
        op = self

        def output(u):
            if np.ndim(u) == 0:
                u = float(u)
                return op.map_output(u, sol(u)[0])
            return np.array([output(x) for x in np.asarray(u, dtype=np.float64).ravel()]).reshape(
                np.shape(u)
            )

        def partials(u):
            if np.ndim(u) == 0:
                u = float(u)
                z, phi = sol(u)
                h_u, h_z = op.map_output_partials(u, z)
                g = op.slope(u, z, direction)
                return h_u + h_z * g, np.array([h_z * phi])
            rows = [partials(x) for x in np.asarray(u, dtype=np.float64).ravel()]
            d_u = np.array([r[0] for r in rows]).reshape(np.shape(u))
            return d_u, np.array([r[1] for r in rows]).reshape(np.shape(u) + (1,))

        def driven(u):
            u = float(u)
            z, phi = sol(u)
            jump = op.slope(u, z, direction) - op.slope(u, z, -direction)
            return np.array([z]), np.array([jump]), np.array([[phi]])

        return BranchFlow(
            direction=direction,
            input=u0,
            labels=(_label(direction),),
            memory=np.array([z0]),
            slaved=np.zeros(1, dtype=bool),
            output=output,
            partials=partials,
            breakpoint=direction * math.inf,
            driven_labels=(_label(-direction),),
            driven=driven,
        )

    # -- memory as coordinates (periodic orbits, continuation) ---------------------------------
    def with_memory(
        self, state: DuhemState, values: Any, input: float, direction: int
    ) -> DuhemState:
        """The state ``(z0, input)`` (contract, :meth:`ContinuousHysteron.with_memory`): the
        branch that starts there reports ``z0`` (``values``, one number; put back into the
        output range where a Newton step left it, Bouc–Wen's ``[−z_max, z_max]``).

        The branch memory of a Duhem operator is ``z0``, the internal variable at the branch
        start; a state's own memory is its current ``z`` (the ``z0`` of the branch that starts
        at it)."""
        check_state_type(state, DuhemState, self)
        d = direction_sign(direction)
        z = np.asarray(values, dtype=np.float64).reshape(-1)
        if z.size != 1:
            raise ValueError(f"values must hold the one memory value z0, got {z.size} values")
        lo, hi = self.output_range
        return self.state(float(np.clip(z[0], lo, hi)), input, d)

    def memory_restart(self, state: DuhemState, direction: int, u: float) -> tuple:
        """``([Z(u)], [g_d(u, Z)], [[Φ(u)]])`` on the branch of ``state`` in ``direction``
        (contract, :meth:`ContinuousHysteron.memory_restart`): along a branch
        ``z = Z(u; z0)``, so the memory of the branch restarted at ``u`` is ``Z(u; z0)`` with
        gradient ``∂Z/∂u = g_d(u, Z)`` and ``∂Z/∂z0 = Φ(u)`` (the variational solution the
        branch flow carries: the ``d_dm`` of its driven variable)."""
        d = direction_sign(direction)
        flow = self.branch_flow(state, d)
        values, _, d_dm = flow.driven(float(u))
        z = float(np.asarray(values).reshape(-1)[0])
        phi = float(np.asarray(d_dm).reshape(-1)[0])
        return np.array([z]), np.array([self.slope(float(u), z, d)]), np.array([[phi]])

    def __repr__(self) -> str:
        return f"Duhem({self._g[1]!r}, {self._g[-1]!r})"
