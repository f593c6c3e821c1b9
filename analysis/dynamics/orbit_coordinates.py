"""State coordinates of the stroboscopic map: an :class:`OscillatorState` as a vector and back.

Newton on ``F(x) = P^k(x) − x`` (:mod:`analysis.dynamics.periodic_orbits`) needs the state at
the section ``φ = φ0`` as a point of R^d whose components are exactly the rows of the engine's
tangent space without the phase, ``("q", "v", *memory)``, so that the Jacobian the engine
propagates (``ForcedOscillator.jacobian(k·T, state, include_phase=False)``) is the derivative
of the map in these coordinates. Three families, told apart by the operator's contract and the
engine's memory labels (never by class):

* **piecewise constant** (relays, discrete Preisach, dimers): ``x = (q, v)``; the discrete
  relay configuration is carried by a template state (the engine applies the new ``q`` to it,
  which switches nothing while ``q`` stays between the thresholds); interacting spins (a
  random-field Ising lattice, ``compiled_switching()``) likewise, their configuration the
  packed spins (``configuration``: ``(("spins", bytes),)``);
* **one wagon** (memory label ``"w"``: play, generalized play): ``x = (q, v, w)``, the state
  rebuilt by ``operator.state(position=w, input=q)``;
* **several wagons** (labels ``"w0" .. "w{K-1}"``: Prandtl–Ishlinskii): ``x = (q, v, w_0..)``,
  rebuilt by ``operator.state(positions, input=q)``;
* **a composite of plays and relays** (its ``compiled_flow()`` hands over ``positions`` and
  ``make_state``: a sum of plays, erf plays, Prandtl–Ishlinskii operators and relays): ``x = (q,
  v, w_0..)`` with the wagons of every play part (labels ``"k:w"``, ``"k:w{j}"``), the relays'
  configuration carried by the template state as for relay-type operators;
* **a Duhem operator on the compiled Duhem engine** (its ``compiled_flow()`` of kind
  ``"duhem"``: Bouc–Wen, Jiles–Atherton; tangent row ``"z"``): ``x = (q, v, z)`` with ``z``
  the current internal variable, rebuilt by the description's ``make_state(z, q, direction)``
  (the generic engine's branch memory ``"z-"``/``"z+"`` changes its label at every reversal
  and has no such form);
* **a staircase** (labels ``"M1", "m1", "M2", ...``: a continuous Preisach model, any density):
  ``x = (q, v, e_1 .. e_n)`` with ``e_1 .. e_n`` the remembered extrema of the staircase at the
  section (all but its last entry, which is the running input ``q``), rebuilt by the model's
  public ``state_from_extrema((e_1, .., e_n, q))``. The staircase's length is the orbit's own
  structure: it is fixed by the state the coordinates are made from, and a vector whose
  staircase would wipe out entries (not alternating, not nested, or ``q`` beyond the last
  extremum of its kind) raises ``ValueError``, as does a state with another number of extrema.

* **any other continuous operator that sets its memory** (the contract's ``with_memory`` and
  ``memory_restart``, :class:`hysteresis.base.ContinuousHysteron`: Duhem and Bouc–Wen
  operators, sums of them with plays, static maps and relays): ``x = (q, v, *memory)`` with the
  memory its branch in the section's direction reports (a Duhem operator's ``z``), rebuilt by
  ``with_memory``. The engine's rows are the memory of the branch it is on, which for a
  Duhem operator is ``z0`` at the branch start, not the state's ``z``; the Jacobian is mapped
  by ``memory_restart`` at both ends (:meth:`StateCoordinates.chart_jacobian`). Cascades and
  numeric inverses take this chart too (:mod:`hysteresis.composite_memory`); the inverse of
  an operator whose branch memory does not determine its input (a Duhem operator) is refused.

A wagon position that a Newton step places beyond its wall (``|q − w| > p/2``) is put back on
the wall (the state space is the closed strip). Operators whose memory has none of these forms
are refused with a ``ValueError`` naming the operator.
"""

from __future__ import annotations

import math
import re
from dataclasses import replace
from typing import Any

import numpy as np

from oscillators import OscillatorState

__all__ = ["StateCoordinates", "section_direction"]

#: how long after the orbit's last event the replay stops to read the branch that began there
RESTART_DELAY = 1e-9
_WAGON = re.compile(r"^w\d+$")
_EXTREMUM = re.compile(r"^[Mm]\d+$")


class StateCoordinates:
    """Vector coordinates ``("q", "v", *memory)`` of the states of one system at one phase.

    Parameters
    ----------
    system:
        A :class:`~oscillators.system.ForcedOscillator`.
    state:
        A state of that system; its phase is the section's phase and its operator state the
        template of a piecewise-constant operator's relay configuration.
    engine_options:
        Passed to the engine that reads the tangent-space labels.
    """

    def __init__(
        self, system: Any, state: OscillatorState, engine_options: dict | None = None
    ) -> None:
        if not isinstance(state, OscillatorState):
            raise TypeError(f"state must be an OscillatorState, got {type(state).__name__}")
        self.system = system
        self.phi = float(state.phi)
        #: staircase: the number of leading extrema the orbit never reaches (frozen), set by
        #: the orbit finder (:mod:`analysis.dynamics.staircase_orbits`)
        self.prefix = 0
        op = system.operator
        eng = system.engine(state, **(engine_options or {}))
        eng.start_tangent(False)
        self.labels: tuple[str, ...] = tuple(eng.tangent_space)
        memory = self.labels[2:]
        spins = None
        if op.piecewise_constant and not op.has_relay_table:
            spins = op.compiled_switching()
            if spins is None:
                raise ValueError(
                    f"periodic orbits of {type(op).__name__} are not computed: its memory "
                    "(interacting units, no relay table, no compiled_switching() spins) has no "
                    "configuration to compare between the orbit's start and end"
                )
        spec = None if op.piecewise_constant else op.compiled_flow()
        if spins is not None:
            self.kind = "spins"
            self._spins = spins
        elif op.piecewise_constant:
            self.kind = "relay"
        elif spec is not None and spec.kind == "duhem" and memory == (spec.label(0),):
            self.kind = "duhem"
            self._spec = spec
        elif (
            spec is not None and spec.kind != "duhem" and getattr(spec, "make_state", None)
        ):  # a Duhem operator on the generic engine (rows "z±") takes the memory chart below
            self.kind = "composite"
            self._spec = spec
        elif memory == ("w",) and hasattr(op, "state"):
            self.kind = "wagon"
        elif memory and all(_WAGON.match(m) for m in memory) and hasattr(op, "state"):
            self.kind = "wagons"
        elif all(_EXTREMUM.match(m) for m in memory) and hasattr(op, "state_from_extrema"):
            self.kind = "staircase"
            n = np.asarray(state.operator_state.extrema).size
            if n != len(memory) + 1:
                raise ValueError(
                    f"the staircase of the state has {n} extrema, the engine's memory rows "
                    f"{memory} {len(memory) + 1} (the state is at a reversal: v = 0)"
                )
        else:
            self.kind = "memory"
            self._set_memory_chart(op, state, memory)
        wagons = self.kind in ("wagon", "wagons")
        self.half_widths = self._half_widths(op) if wagons else np.zeros(0)
        if self.kind == "composite":
            self.half_widths = np.asarray(spec.half_widths, dtype=np.float64)

    def _set_memory_chart(self, op: Any, state: OscillatorState, memory: tuple) -> None:
        """The operator's own chart (``with_memory``/``memory_restart``), probed once on the
        state: refused in one sentence where the operator cannot set its memory."""
        op_state = state.operator_state
        if op_state is None:
            op_state = op.initial_state(float(state.q))
        self.direction = section_direction(self.system, state, op_state)
        try:
            flow = op.branch_flow(op_state, self.direction)
            if tuple(flow.labels) != memory:
                raise ValueError(f"its branch reports the memory {flow.labels}")
            op.with_memory(op_state, flow.memory, float(state.q), self.direction)
        except ValueError as exc:
            raise ValueError(
                f"the memory of {op!r} (tangent rows {memory}) cannot be set from a vector of "
                f"fixed size: {exc}"
            ) from None

    def restart_rows(self, op_state: Any, direction: int, u: float) -> np.ndarray:
        """``T``: the coordinates' perturbations from the engine's tangent rows on the branch
        of ``op_state`` in ``direction`` at input ``u`` (``δm = d_du·δq + d_dm @ δm_branch``,
        the operator's ``memory_restart``; ``(δq, δv)`` pass). The identity for memory that
        is the state's own (frozen or slaved); a Duhem operator's ``z0`` is not."""
        values, d_du, d_dm = self.system.operator.memory_restart(op_state, direction, u)
        n = self.dimension - 2
        t = np.eye(self.dimension)
        t[2:, 0] = np.asarray(d_du, dtype=np.float64).reshape(n)
        t[2:, 2:] = np.asarray(d_dm, dtype=np.float64).reshape(n, n)
        return t

    def chart_jacobian(
        self, start: OscillatorState, shot: Any, engine_options: dict | None = None, system=None
    ) -> np.ndarray:
        """``D P^k`` in these coordinates from the engine's ``J`` (``shot``: its ``states``
        after each period, ``events`` and ``jacobian``; ``system``: the one it was integrated
        with, default :attr:`system`): ``T_end · J · T_start⁻¹``.

        The engine's rows are the memory of the branch it is on: at the start the branch of
        the start state, at the end the branch that began at the last event (a reversal). The
        operator's ``memory_restart`` turns each into the memory the state reports there
        (:meth:`restart_rows`). The state after the last event comes from a replay of the
        period that holds it, stopped ``RESTART_DELAY`` after the event (the branch memory of
        a later start on the same branch differs by the motion in that time: ``O(δ²)`` after
        a reversal, ``O(δ)`` after a breakpoint, where frozen and slaved memory do not move)."""
        states, events, jacobian = shot.states, shot.events, shot.jacobian
        if self.kind != "memory":
            return jacobian
        system = self.system if system is None else system
        period = system.period
        t_start = self.restart_rows(start.operator_state, self.direction, float(start.q))
        end = states[-1]
        times = np.asarray(events["time"], dtype=np.float64) if events.size else np.zeros(0)
        if times.size == 0:
            t_end = self.restart_rows(start.operator_state, self.direction, float(end.q))
        else:
            t_ev = float(times[-1])
            whole = min(int((t_ev - start.t) // period), len(states) - 1)
            base = start if whole <= 0 else states[whole - 1]
            eng = system.engine(base, **(engine_options or {}))
            eng.advance(np.array([t_ev - base.t + RESTART_DELAY]), None, True)
            met = np.asarray(eng.records().get("events", np.zeros(0, [("time", "f8")]))["time"])
            if met.size == 0 or abs(met[-1] - t_ev) > 1e-6 * period:
                raise ValueError(
                    f"the replay of the orbit's last period did not meet its last event at t = "
                    f"{t_ev:.9g}: the tangent rows at its end cannot be matched to a branch"
                )
            after = eng.state()
            d = section_direction(system, after, after.operator_state)
            t_end = self.restart_rows(after.operator_state, d, float(end.q))
        return t_end @ jacobian @ np.linalg.inv(t_start)

    @property
    def dimension(self) -> int:
        """Number of coordinates ``len(labels)``."""
        return len(self.labels)

    @staticmethod
    def _half_widths(op: Any) -> np.ndarray:
        if hasattr(op, "widths"):
            return 0.5 * np.asarray(op.widths, dtype=np.float64).ravel()
        return np.array([float(op.half_width)])

    def vector(self, state: OscillatorState) -> np.ndarray:
        """``(q, v, *memory)`` of ``state``."""
        head = [float(state.q), float(state.v)]
        if self.kind in ("relay", "spins"):
            return np.array(head)
        op_state = state.operator_state
        if self.kind == "duhem":
            return np.array([*head, float(self._spec.memory(op_state))])
        if self.kind == "wagon":
            return np.array([*head, float(op_state.position)])
        if self.kind == "composite":
            return np.concatenate([head, np.asarray(self._spec.positions(op_state), float)])
        if self.kind == "memory":
            flow = self.system.operator.branch_flow(op_state, self.direction)
            return np.concatenate([head, np.asarray(flow.memory, dtype=np.float64)])
        if self.kind == "staircase":
            extrema = np.asarray(op_state.extrema, dtype=np.float64)
            if extrema.size != self.dimension - 1:
                raise ValueError(
                    f"the staircase has {extrema.size} extrema, the coordinates "
                    f"{self.dimension - 1} (an extremum was wiped out or added: the orbit's "
                    "structure changed)"
                )
            return np.concatenate([head, extrema[:-1]])
        return np.concatenate([head, np.asarray(op_state.positions, dtype=np.float64)])

    def state(self, x: np.ndarray, template: OscillatorState) -> OscillatorState:
        """The state with coordinates ``x`` at the section's phase (``template``: the relay
        configuration of piecewise-constant operators, and the time ``t``)."""
        x = np.asarray(x, dtype=np.float64)
        if x.shape != (self.dimension,) or not np.all(np.isfinite(x)):
            raise ValueError(
                f"coordinates must be {self.dimension} finite numbers {self.labels}, got {x}"
            )
        q, v = float(x[0]), float(x[1])
        op = self.system.operator
        if self.kind in ("relay", "spins"):
            op_state = template.operator_state
        elif self.kind == "duhem":
            # the direction is informative only (hysteresis.duhem): the sign of v
            direction = 1 if v > 0.0 else (-1 if v < 0.0 else 0)
            op_state = self._spec.make_state(float(x[2]), q, direction)
        elif self.kind == "composite":
            w = np.clip(x[2:], q - self.half_widths, q + self.half_widths)
            spec = self._spec
            if spec.relay_alpha is None:
                op_state = spec.make_state(w, q)
            else:  # the relays as the template has them (switching nothing at q)
                op_state = spec.make_state(w, q, spec.relay_outputs(template.operator_state))
        elif self.kind == "staircase":
            op_state = self._staircase(x)
        elif self.kind == "memory":
            op_state = op.with_memory(template.operator_state, x[2:], q, self.direction)
        else:
            w = np.clip(x[2:], q - self.half_widths, q + self.half_widths)
            if self.kind == "wagon":
                op_state = op.state(position=float(w[0]), input=q)
            else:
                op_state = op.state(w, input=q)
        return replace(template, q=q, v=v, phi=self.phi, operator_state=op_state)

    def _staircase(self, x: np.ndarray) -> Any:
        """The continuous Preisach state with extrema ``(x[2:], q)`` (no entry wiped out)."""
        extrema = np.append(x[2:], x[0])
        op_state = self.system.operator.state_from_extrema(extrema)
        got = np.asarray(op_state.extrema, dtype=np.float64)
        if got.shape != extrema.shape or not np.array_equal(got, extrema):
            raise ValueError(
                f"coordinates {self.labels[2:]} = {x[2:]} with q = {x[0]} are not a staircase "
                "of the model (alternating nested extrema, q between the last two): "
                f"{extrema.size - got.size} entries would be wiped out"
            )
        return op_state

    def configuration(self, state: OscillatorState) -> tuple:
        """The discrete memory of ``state`` as part of an orbit's event sequence: ``(("relays",
        outputs),)`` for relay-type operators and composites with relays (their ±1 in table
        order), ``(("spins", packed bits),)`` for interacting spins, ``()`` otherwise. Two
        orbits of one period without switches (a relay held up or down all along) differ only
        here: the configuration changing between two branch points is a grazing, like an event
        sequence changing."""
        if self.kind == "spins":
            return (("spins", self._spins.spins(state.operator_state)[0].tobytes()),)
        if self.kind == "relay":
            outputs = self.system.operator.relay_outputs(state.operator_state)
        elif self.kind == "composite" and self._spec.relay_alpha is not None:
            outputs = self._spec.relay_outputs(state.operator_state)
        else:
            return ()
        return (("relays", tuple(int(y) for y in np.asarray(outputs))),)

    def same_memory(self, a: OscillatorState, b: OscillatorState) -> bool:
        """Whether the discrete relay configurations of ``a`` and ``b`` agree (always true for
        continuous memory, which is part of the coordinates)."""
        if self.kind == "composite" and self._spec.relay_alpha is not None:
            outputs = self._spec.relay_outputs
            return bool(np.array_equal(outputs(a.operator_state), outputs(b.operator_state)))
        if self.kind == "spins":
            bits = self._spins.spins
            return bool(np.array_equal(bits(a.operator_state)[0], bits(b.operator_state)[0]))
        if self.kind != "relay":
            return True
        op = self.system.operator
        return bool(
            np.array_equal(op.relay_outputs(a.operator_state), op.relay_outputs(b.operator_state))
        )

    def scale(self, x: np.ndarray) -> float:
        """``max(1, |x|_∞)``: the size a residual is measured against."""
        return max(1.0, float(np.max(np.abs(x))))

    def __repr__(self) -> str:
        return f"StateCoordinates({self.labels}, kind={self.kind!r}, phi={self.phi:.6g})"


def section_direction(system: Any, state: OscillatorState, op_state: Any) -> int:
    """The direction of the input's motion at ``state``, the branch an engine started there
    follows: the sign of ``v``, at rest the sign of the acceleration (the engines' rule)."""
    if state.v != 0.0:
        return 1 if state.v > 0.0 else -1
    acc = (
        -float(state.q)
        + math.cos(float(state.phi))
        + system.coupling * float(system.operator.output(op_state))
    )
    return 1 if acc >= 0.0 else -1
