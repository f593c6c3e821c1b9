"""The engine seam: one interface between the forced oscillator and every integrator.

:class:`~oscillators.system.ForcedOscillator` knows an operator only through its contract
(:mod:`hysteresis.base`). It asks the operator once what it can hand over and picks the engine
from the answer (:func:`select_engine`), never by ``isinstance`` on operator classes:

* ``operator.piecewise_constant`` and ``operator.relay_table()`` -> :class:`RelayEngine`
  (exact event-driven integration: closed-form propagation between switches, saltation
  ``C·ΔM/v*`` at each switch; an O(1) kernel when the thresholds nest, an O(log N) heap kernel
  for arbitrary relays);
* ``operator.compiled_play()`` not ``None`` -> the compiled play-limit engine (plain play and
  ``GeneralizedPlay.erf``: the paper's thermodynamic limit, a fast path);
* any other continuous operator -> the generic continuous engine over
  ``operator.branch_flow(state, direction)`` (play with any shape, Prandtl–Ishlinskii,
  continuous Preisach).

Everything above an engine — trajectories, Poincaré sections, the stroboscopic map, flow-map
Jacobians (:mod:`oscillators.system`) and the one Benettin/QR loop of
:mod:`analysis.lyapunov` — is written once against :class:`Engine`.

Engine contract
---------------
An engine is a mutable integrator of one trajectory of the coupled system started from an
:class:`~oscillators.results.OscillatorState` (time ``t0``, phase ``φ0``). Time is measured as
*elapsed time since the start*; engines keep it internally as (period index, time in period) or
in any other exact way, so the forcing phase ``φ0 + Ω·elapsed`` never loses digits.

Motion
    ``advance(times, out=None, record=False)`` moves through the sorted elapsed times (each
    ``>=`` the current one); row ``i`` of ``out`` receives ``(q, v, M)`` at ``times[i]`` and
    the extra sampled columns named by :attr:`Engine.sample_columns` after the first three.
    With ``record`` every event (relay switch; wall hit or reversal; ...) is kept for
    :meth:`Engine.records`. ``state()`` is the full :class:`OscillatorState` now.
    ``output_integral()`` is ``∫ M dt`` since the start where the engine can give it exactly
    (relay engines; time averages such as the paper's ``M_T`` come from it in the same pass as
    the tangent flow), else ``NotImplementedError``.
Tangent flow
    ``start_tangent(include_phase)`` switches the variational flow on with the identity as
    deviation vectors. :attr:`Engine.tangent_space` names the rows of the deviation matrix:
    ``("q", "v"[, "phi"], *memory)`` where ``memory`` are the operator's memory directions
    (none for relays; ``"w"`` for the play; the wagon positions of a Prandtl–Ishlinskii
    operator; the remembered extrema of a continuous Preisach staircase, a number that changes
    along the orbit). ``deviations()`` returns the current matrix (rows as in ``tangent_space``
    now, one column per tracked vector), ``set_deviations(y)`` replaces it (same shape), and
    ``rank_bound()`` is an upper bound of the rank of the tangent map since the last
    ``start_tangent``/``set_deviations`` that is known *structurally* (from events, not from
    round-off): a play wall hit resets ``δw := δq`` and removes the ``w`` direction, a wiped-out
    extremum removes its direction. The QR loop records exactly ``-inf`` for the directions
    beyond that bound (the paper's ``λ = -∞``) instead of the log of a round-off remainder.

Engines raise :class:`DivergenceError` when the state becomes non-finite or runs away, and
:class:`GrazingError` (piecewise-constant operators) when a switch happens at a turning point
while the tangent flow is on.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from typing import Any

import numpy as np

from oscillators.results import OscillatorState

__all__ = [
    "DivergenceError",
    "Engine",
    "GrazingError",
    "select_engine",
    "split_times",
    "wrap_phase",
]


class DivergenceError(RuntimeError):
    """The coupled system left every bounded region (non-finite or runaway state).

    Raised instead of returning numbers computed from a diverged orbit. ``time`` is the
    (absolute) time at which it was detected, ``cause`` a short explanation.
    """

    def __init__(self, message: str, time: float | None = None) -> None:
        super().__init__(message)
        self.time = time


class GrazingError(ValueError):
    """A switch at a turning point (``v* = 0``) while the tangent flow is propagated.

    The grazing rule makes a maximum that reaches an upper threshold switch; the saltation
    ``C·ΔM/v*`` of that switch is infinite, so the flow map is not differentiable on this orbit
    and Lyapunov exponents / Jacobians are undefined. A ``ValueError`` subclass so that callers
    reporting bad input also report this.
    """


def wrap_phase(phi: float) -> float:
    """``phi`` mod 2π in [0, 2π)."""
    two_pi = 2.0 * math.pi
    wrapped = math.fmod(phi, two_pi)
    if wrapped < 0.0:
        wrapped += two_pi
    # fmod of a tiny negative number plus 2π rounds to exactly 2π
    return 0.0 if wrapped >= two_pi else wrapped


def split_times(times: np.ndarray, period: float) -> tuple[np.ndarray, np.ndarray]:
    """Elapsed times as (period index, time within the period in [0, T))."""
    times = np.asarray(times, dtype=np.float64)
    n = np.floor(times / period).astype(np.int64)
    tau = times - n * period
    fix = tau >= period
    n[fix] += 1
    tau[fix] = 0.0
    tau[tau < 0.0] = 0.0
    return n, tau


class Engine(ABC):
    """Integrator of one trajectory of a :class:`~oscillators.system.ForcedOscillator`.

    Subclasses implement the motion and tangent-flow primitives below; see the module docstring
    for the contract. Engines are created by :meth:`ForcedOscillator.engine`.
    """

    #: Short name reported in results (``"relay kernel"``, ``"play kernel"``, ...).
    name: str = "engine"

    def __init__(self, system: Any, state: OscillatorState) -> None:
        self.system = system
        self.start = state

    # -- motion --------------------------------------------------------------------------------
    @property
    def sample_columns(self) -> tuple[str, ...]:
        """Names of the columns :meth:`advance` writes: ``("q", "v", "M", ...)``."""
        return ("q", "v", "M")

    @property
    @abstractmethod
    def elapsed(self) -> float:
        """Time since the start state."""

    @abstractmethod
    def advance(
        self, times: np.ndarray | float, out: np.ndarray | None = None, record: bool = False
    ) -> None:
        """Move through the sorted elapsed ``times``; fill ``out`` rows (see module docstring)."""

    @abstractmethod
    def state(self) -> OscillatorState:
        """The full state now (operator state included)."""

    @abstractmethod
    def records(self) -> dict[str, np.ndarray]:
        """Events recorded while ``record`` was on, as structured arrays by kind.

        Piecewise-constant engines give ``{"switches": time, q, v, jump}``; the play engines
        ``{"events": time, q, v, kind, w}`` (kind +1 the input leaves the play onto a wall,
        -1 it enters the play).
        """

    def output_integral(self) -> float:
        """``∫ M dt`` over the elapsed time (for exact time averages of the output).

        Engines that cannot give it exactly raise ``NotImplementedError`` (the relay engine
        accumulates it per hop; continuous engines would need a quadrature of ``M``).
        """
        raise NotImplementedError(
            f"the {self.name} engine does not accumulate the time integral of the output M"
        )

    @property
    @abstractmethod
    def n_events(self) -> int:
        """Number of events (switches, wall hits, reversals) since the start."""

    # -- tangent flow --------------------------------------------------------------------------
    @abstractmethod
    def start_tangent(self, include_phase: bool = False) -> None:
        """Switch the variational flow on; deviations := identity on :attr:`tangent_space`."""

    @property
    @abstractmethod
    def tangent_space(self) -> tuple[str, ...]:
        """Names of the rows of :meth:`deviations` now."""

    @abstractmethod
    def deviations(self) -> np.ndarray:
        """Current deviation vectors as columns (a copy)."""

    @abstractmethod
    def set_deviations(self, y: np.ndarray) -> None:
        """Replace the deviation vectors (same shape as :meth:`deviations`)."""

    @abstractmethod
    def rank_bound(self) -> int:
        """Structural bound of the tangent map's rank since the last start/set (see module)."""


def select_engine(operator: Any) -> type[Engine]:
    """The engine class for ``operator``, chosen from what its contract hands over."""
    if getattr(operator, "piecewise_constant", False):
        from oscillators.piecewise_constant import RelayEngine

        return RelayEngine
    compiled = getattr(operator, "compiled_play", None)
    if compiled is not None and compiled() is not None:
        from oscillators.play_flow import PlayEngine

        return PlayEngine
    if callable(getattr(operator, "branch_flow", None)):
        try:
            from oscillators.continuous import ContinuousEngine
        except ImportError:  # pragma: no cover - the generic engine is part of the package
            ContinuousEngine = None
        if ContinuousEngine is not None:
            return ContinuousEngine
    raise TypeError(
        f"operator {type(operator).__name__} cannot be coupled to the oscillator: a "
        "piecewise-constant operator must provide relay_table(), a continuous one "
        "branch_flow(state, direction) (see hysteresis.base)"
    )
