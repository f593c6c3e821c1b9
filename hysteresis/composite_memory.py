"""The memory of cascades and inverses as coordinates (``with_memory`` / ``memory_restart``).

The periodic-orbit coordinates (:class:`analysis.dynamics.orbit_coordinates.StateCoordinates`,
kind ``"memory"``) write a state as ``(q, v, *m)`` with ``m`` the memory its branch reports
(:attr:`BranchFlow.memory <hysteresis.flow.BranchFlow>`) and rebuild it through the contract's
:meth:`~hysteresis.base.ContinuousHysteron.with_memory`; the engine's tangent rows are mapped to
those coordinates by :meth:`~hysteresis.base.ContinuousHysteron.memory_restart`. This module
does both for the two composites whose memory is not that of their parts side by side.

Cascade ``y = outer[inner[u]]`` (:class:`hysteresis.cascade.Cascade`)
---------------------------------------------------------------------
Its branch memory is the inner's (``"in:"``) and the outer's *frozen* variables (``"out:"``);
the outer's variables dragged by the inner output ``x`` are driven, no coordinates.

* ``with_memory``: the inner from its values at ``input``; the outer at the new inner output
  ``x`` with its frozen variables from the values and its dragged ones moved with ``x``
  (``m_s(x) = m_s(x_t) + x − x_t`` from the template's branch: a dragged wagon stays on its
  wall), through the parts' own ``with_memory``.
* ``memory_restart`` at input ``u`` (inner output ``x = x(u; m_in)``): the inner's own restart
  ``δm_in' = a·δu + A δm_in``; the outer's restart at ``x``, ``δm_out' = b·δx + B δm_out``,
  with the outer's dragged rows ``δm_s = δx`` and ``δx = ∂x/∂u δu + ∂x/∂m_in δm_in`` (chain
  rule). For parts whose memory is their state's own (plays, Prandtl–Ishlinskii, static maps)
  the result is the identity.

A piecewise-constant part keeps the relay outputs of the template (it switches nothing while
its input stays between its thresholds).

Inverse ``y ↦ u`` (:class:`hysteresis.inverse.InverseOperator`)
-------------------------------------------------------------
Its branch memory is the forward branch's *frozen* variables; the forward's slaved ones (a
wagon dragged by ``u``, the width-0 play of an invertible Prandtl–Ishlinskii operator) are
driven by the inverse's output.

* ``with_memory(values, y)``: the forward input ``u`` is the root of
  ``G(u) = forward output of the state with the frozen memory ``values`` and the slaved memory
  at u`` (``G(u) = y``, Brent's method as in the inverse's ``apply``). ``G`` increases strictly
  when the forward branch memory and the input are independent (plays, Prandtl–Ishlinskii,
  sums with static maps). For a Duhem operator the branch memory ``z0`` is the output at the
  branch start, so ``G`` is constant: the memory does not determine the forward input and the
  chart is refused in one sentence (it would need the forward input as a coordinate).
* ``memory_restart`` at ``y``: the forward's restart at ``u(y)``, its slaved columns
  ``δm_s = δu`` and ``δu = ∂u/∂y δy + ∂u/∂m δm`` (implicit function theorem, as in the
  inverse's partials).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from hysteresis._validation import MAX_MAGNITUDE, finite_scalar
from hysteresis.base import Hysteron
from hysteresis.flow import BranchFlow

__all__ = [
    "cascade_with_memory",
    "cascade_memory_restart",
    "inverse_with_memory",
    "inverse_memory_restart",
]

#: Brent's tolerances for the forward input of an inverse (those of hysteresis.inverse)
_RTOL = 4.0 * float(np.finfo(np.float64).eps)


def _part_with_memory(op: Hysteron, state: Any, values: np.ndarray, u: float, d: int) -> Any:
    """A part's state at ``u`` with the memory ``values``; a relay-type part keeps its outputs."""
    if not op.piecewise_constant:
        return op.with_memory(state, values, u, d)
    if not op.has_relay_table:
        raise ValueError(
            f"{type(op).__name__} cannot set its memory from a vector (interacting units, no "
            "relay table)"
        )
    return op.state_from_relay_outputs(op.relay_outputs(state), u)


def _part_restart(op: Hysteron, state: Any, d: int, u: float) -> tuple:
    """A part's ``memory_restart``; none for a piecewise-constant part (no memory rows)."""
    if op.piecewise_constant:
        return np.zeros(0), np.zeros(0), np.zeros((0, 0))
    values, d_du, d_dm = op.memory_restart(state, d, u)
    values = np.asarray(values, dtype=np.float64).reshape(-1)
    n = values.size
    d_du = np.asarray(d_du, dtype=np.float64).reshape(n)
    return values, d_du, np.asarray(d_dm, dtype=np.float64).reshape(n, n)


# -- cascades ---------------------------------------------------------------------------------
def cascade_with_memory(
    inner: Hysteron,
    outer: Hysteron,
    state: Any,
    flows: tuple[BranchFlow, BranchFlow, int],
    values: Any,
    input: float,
    x_at: Any,
) -> tuple[Any, Any]:
    """The parts' states ``(inner, outer)`` of the cascade state at ``input`` whose branch
    reports ``values`` (module docstring); ``flows`` are the template's part flows ``(I, O,
    dx)``, ``x_at(inner_state, u)`` the inner output as the cascade computes it."""
    I, O, dx = flows
    d = I.direction
    u = finite_scalar(input, "input", MAX_MAGNITUDE)
    values = np.asarray(values, dtype=np.float64).reshape(-1)
    frozen = ~np.asarray(O.slaved, dtype=bool)
    n_in, n_out = I.n_memory, int(frozen.sum())
    if values.size != n_in + n_out:
        raise ValueError(
            f"values must hold {n_in + n_out} memory values ({n_in} inner, {n_out} outer "
            f"frozen), got {values.size}"
        )
    inner_state = _part_with_memory(inner, state.inner, values[:n_in], u, d)
    x = float(x_at(inner_state, float(inner_state.input)))
    full = np.array(O.memory_at(x), dtype=np.float64).reshape(O.n_memory)
    full[frozen] = values[n_in:]
    return inner_state, _part_with_memory(outer, state.outer, full, x, dx)


def cascade_memory_restart(
    inner: Hysteron, outer: Hysteron, state: Any, flows: tuple, u: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(values, d_du, d_dm)`` of the cascade branch restarted at ``u`` (module docstring)."""
    I, O, dx = flows
    d = I.direction
    u = float(u)
    slaved = np.asarray(O.slaved, dtype=bool)
    frozen = ~slaved
    n_in, n_out = I.n_memory, int(frozen.sum())
    n = n_in + n_out
    vi, ai, Ai = _part_restart(inner, state.inner, d, u)
    x = float(I.output(u))
    vo, bo, Bo = _part_restart(outer, state.outer, dx, x)
    # δx = ∂x/∂u δu + ∂x/∂m_in δm_in (the inner's slaved rows are δu already)
    gu, gm = I.partials(u)
    gm = np.asarray(gm, dtype=np.float64).reshape(n_in)
    values, d_du, d_dm = np.zeros(n), np.zeros(n), np.zeros((n, n))
    values[:n_in], d_du[:n_in], d_dm[:n_in, :n_in] = vi, ai, Ai
    if n_out:
        # the outer's rows over the cascade's: its dragged columns follow δx
        along = (bo + Bo[:, slaved].sum(axis=1))[frozen]
        values[n_in:] = vo[frozen]
        d_du[n_in:] = along * float(gu)
        d_dm[n_in:, :n_in] = along[:, None] * gm[None, :]
        d_dm[n_in:, n_in:] = Bo[np.ix_(frozen, frozen)]
    return values, d_du, d_dm


# -- inverses ---------------------------------------------------------------------------------
def inverse_with_memory(
    operator: Hysteron, forward: Any, flow: BranchFlow, values: Any, y: float, solve: Any
) -> Any:
    """The forward state whose output is ``y`` and whose branch ``flow`` (the template's, in
    the section's direction) reports the frozen memory ``values`` (module docstring);
    ``solve(G, u0, G(u0), y)`` is the inverse's root finder."""
    d = flow.direction
    frozen = ~np.asarray(flow.slaved, dtype=bool)
    values = np.asarray(values, dtype=np.float64).reshape(-1)
    if values.size != int(frozen.sum()):
        raise ValueError(
            f"values must hold the {int(frozen.sum())} frozen memory values of the forward "
            f"branch {tuple(np.asarray(flow.labels)[frozen])}, got {values.size}"
        )

    def at(u: float) -> Any:
        full = np.array(flow.memory_at(u), dtype=np.float64).reshape(flow.n_memory)
        full[frozen] = values
        return operator.with_memory(forward, full, u, d)

    def G(u: float) -> float:
        return float(operator.output(at(float(u))))

    u0 = float(flow.input)
    h = 1e-6 * max(1.0, abs(u0))
    if not G(u0 + h) > G(u0 - h):
        raise ValueError(
            f"the branch memory {tuple(flow.labels)} of {operator!r} does not determine its "
            f"input: with that memory held its output does not increase with the input near "
            f"{u0!r} (memory that is the output at the branch start, a Duhem operator's z0)"
        )
    g0 = G(u0)
    u = u0 if g0 == y else solve(G, u0, g0, float(y))
    return at(u)


def inverse_memory_restart(
    operator: Hysteron, forward: Any, flow: BranchFlow, u: float, gradient: Any
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(values, d_dy, d_dm)`` of the inverse branch restarted where the forward input is
    ``u`` (module docstring); ``gradient(u) -> (∂u/∂y, ∂u/∂m_frozen)``."""
    slaved = np.asarray(flow.slaved, dtype=bool)
    frozen = ~slaved
    fv, fa, fA = _part_restart(operator, forward, flow.direction, float(u))
    du_dy, du_dm = gradient(float(u))
    if not math.isfinite(du_dy):
        raise ValueError(
            f"the forward branch of {operator!r} is flat at input {u!r}: the inverse's memory "
            "moves infinitely with its input there"
        )
    along = (fa + fA[:, slaved].sum(axis=1))[frozen]
    d_dm = fA[np.ix_(frozen, frozen)] + along[:, None] * np.asarray(du_dm, float)[None, :]
    return fv[frozen], along * du_dy, d_dm
