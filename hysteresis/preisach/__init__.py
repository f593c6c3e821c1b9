"""The Preisach model (see :mod:`hysteresis.preisach.continuous` for the theory)."""

from hysteresis.preisach.continuous import (
    ContinuousPreisachModel,
    DiscretePreisachModel,
    PreisachModel,
    PreisachState,
)
from hysteresis.preisach.projection import PreisachProjection, project_identification

__all__ = [
    "PreisachModel",
    "DiscretePreisachModel",
    "ContinuousPreisachModel",
    "PreisachState",
    "PreisachProjection",
    "project_identification",
]
