"""A Duhem operator's memory as coordinates: ``with_memory`` and ``memory_restart`` of
:class:`hysteresis.duhem.Duhem` (the contract methods of :class:`hysteresis.base.
ContinuousHysteron` that periodic orbits and continuation use).

The branch memory of a Duhem operator is ``z0``, the internal variable at the branch start; a
state's own memory is its current ``z`` (the ``z0`` of the branch that starts at it). Along a
branch ``z = Z(u; z0)``, so the memory of the branch restarted at ``u`` is ``Z(u; z0)`` with
gradient ``∂Z/∂u = g_d(u, Z)`` and ``∂Z/∂z0 = Φ(u)`` (the variational solution the branch flow
already carries: the ``d_dm`` of its driven variable).

These two methods live here, attached to the class, while ``hysteresis/duhem.py`` is being
changed on another work branch; they belong in the class body and move there at the merge.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from hysteresis._validation import check_state_type, direction_sign
from hysteresis.duhem import Duhem, DuhemState

__all__: list[str] = []


def _with_memory(
    self: Duhem, state: DuhemState, values: Any, input: float, direction: int
) -> DuhemState:
    """The state ``(z0, input)``: the branch that starts there reports ``z0`` (``values``, one
    number; put back into the output range where a Newton step left it, Bouc–Wen's
    ``[−z_max, z_max]``)."""
    check_state_type(state, DuhemState, self)
    d = direction_sign(direction)
    z = np.asarray(values, dtype=np.float64).reshape(-1)
    if z.size != 1:
        raise ValueError(f"values must hold the one memory value z0, got {z.size} values")
    lo, hi = self.output_range
    return self.state(float(np.clip(z[0], lo, hi)), input, d)


def _memory_restart(self: Duhem, state: DuhemState, direction: int, u: float) -> tuple:
    """``([Z(u)], [g_d(u, Z)], [[Φ(u)]])`` on the branch of ``state`` in ``direction`` (module
    docstring)."""
    d = direction_sign(direction)
    flow = self.branch_flow(state, d)
    values, _, d_dm = flow.driven(float(u))  # the current z and Φ = ∂Z/∂z0
    z = float(np.asarray(values).reshape(-1)[0])
    phi = float(np.asarray(d_dm).reshape(-1)[0])
    return np.array([z]), np.array([self.slope(float(u), z, d)]), np.array([[phi]])


Duhem.with_memory = _with_memory  # type: ignore[method-assign]
Duhem.memory_restart = _memory_restart  # type: ignore[method-assign]
