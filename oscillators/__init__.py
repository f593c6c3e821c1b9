"""Forced oscillators coupled to hysteresis operators: q'' + 2ζq' + q = cos(Ωt) + C·M[q](t)."""

from hysteresis._distribution import check_import_name as _check_import_name
from hysteresis._version import __version__

_check_import_name("oscillators")

from oscillators.engines import (  # noqa: E402
    DivergenceError,
    Engine,
    GrazingError,
    SlidingError,
    StepBudgetError,
    SwitchBudgetError,
    select_engine,
)
from oscillators.linear import forced_response, homogeneous_propagator, propagate, segment_jacobian
from oscillators.parameters import (
    DEFAULT_DAMPING_RATIO,
    DEFAULT_FREQUENCY,
    DEFAULT_Q0,
    DEFAULT_V0,
    FREQUENCY_RANGE,
    MAX_COUPLING,
    MAX_DAMPING_RATIO,
    MAX_PERIODS,
    MAX_SAMPLES,
)
from oscillators.results import OscillatorState, PoincareSection, Trajectory
from oscillators.system import ForcedOscillator

__all__ = [
    "__version__",
    "DEFAULT_DAMPING_RATIO",
    "DEFAULT_FREQUENCY",
    "DEFAULT_Q0",
    "DEFAULT_V0",
    "FREQUENCY_RANGE",
    "MAX_COUPLING",
    "MAX_DAMPING_RATIO",
    "MAX_PERIODS",
    "MAX_SAMPLES",
    "DivergenceError",
    "Engine",
    "GrazingError",
    "SlidingError",
    "StepBudgetError",
    "SwitchBudgetError",
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
