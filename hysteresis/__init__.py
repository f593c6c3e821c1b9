"""Rate-independent hysteresis operators with immutable state and linearization."""

from hysteresis.base import (
    Branch,
    ContinuousHysteron,
    Hysteron,
    Linearization,
    PiecewiseConstantHysteron,
    Switching,
)

__all__ = [
    "Branch",
    "ContinuousHysteron",
    "Hysteron",
    "Linearization",
    "PiecewiseConstantHysteron",
    "Switching",
]
