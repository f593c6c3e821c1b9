"""Forced oscillators coupled to hysteresis operators: q'' + 2ζq' + q = cos(Ωt) + C·M[q](t)."""

from oscillators.engine import DivergenceError, Engine, GrazingError, select_engine
from oscillators.linear import forced_response, homogeneous_propagator, propagate, segment_jacobian
from oscillators.results import OscillatorState, PoincareSection, Trajectory
from oscillators.system import ForcedOscillator

__all__ = [
    "DivergenceError",
    "Engine",
    "GrazingError",
    "select_engine",
    "ForcedOscillator",
    "OscillatorState",
    "PoincareSection",
    "Trajectory",
    "forced_response",
    "homogeneous_propagator",
    "propagate",
    "segment_jacobian",
]
