"""Forced oscillators coupled to hysteresis operators: q'' + 2ζq' + q = cos(Ωt) + C·M[q](t)."""

from oscillators.linear import forced_response, homogeneous_propagator, propagate, segment_jacobian
from oscillators.results import OscillatorState, PoincareSection, TangentResult, Trajectory
from oscillators.system import ForcedOscillator

__all__ = [
    "ForcedOscillator",
    "OscillatorState",
    "PoincareSection",
    "TangentResult",
    "Trajectory",
    "forced_response",
    "homogeneous_propagator",
    "propagate",
    "segment_jacobian",
]
