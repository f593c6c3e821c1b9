"""Result containers shared by every integrator of the forced oscillator.

They are plain frozen dataclasses of numpy arrays so that analyses never depend on which
integrator (event-driven relay kernel, play-limit flow, generic Python loop) produced them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["OscillatorState", "Trajectory", "PoincareSection"]


@dataclass(frozen=True)
class OscillatorState:
    """Full state of the coupled system: oscillator (q, v, φ) plus the operator's state."""

    q: float
    v: float
    phi: float
    operator_state: Any
    t: float = 0.0


@dataclass(frozen=True)
class Trajectory:
    """Samples on a time grid plus the exact list of output switches.

    ``switches`` is a structured array with fields ``time``, ``q``, ``v``, ``jump`` (ΔM) —
    the relay switches, also those of a composite's relays on a continuous engine (its events
    of kind 2); empty for continuous operators, whose wall hits/reversals are in ``events``
    (fields ``time``, ``q``, ``v``, ``kind``: +1 leaving the play onto a wall or a wipe-out,
    -1 a reversal or entering the play, +2 relays of a composite switched).
    ``w`` is the play position for play-type operators, else ``None``. ``slides`` (relay
    engines) lists the Filippov sliding motions entered and left (fields ``time``, ``q``,
    ``v``, ``kind`` +1 slide-in / -1 slide-out, ``M``); while sliding the samples are
    ``q = θ``, ``v = 0`` and ``M = M_eq = (θ − cos φ)/C``.
    """

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    phi: np.ndarray
    M: np.ndarray
    switches: np.ndarray
    final: OscillatorState
    w: np.ndarray | None = None
    events: np.ndarray | None = None
    slides: np.ndarray | None = None


@dataclass(frozen=True)
class PoincareSection:
    """Stroboscopic section at φ = 0 mod 2π: one point per forcing period."""

    q: np.ndarray
    v: np.ndarray
    M: np.ndarray
    final: OscillatorState
    w: np.ndarray | None = None
    n_switches: int = 0
