"""The Preisach model: a weighted superposition of relays (paper Sec. "Preisach model").

* :mod:`~hysteresis.preisach.base` — the abstract :class:`PreisachModel` (factories
  ``from_relays``, ``from_density``, ``from_everett``, ``from_identification``), its state
  :class:`PreisachState` and the theory (staircase memory, Everett function);
* :mod:`~hysteresis.preisach.discrete` — :class:`DiscretePreisachModel` (relays, exact);
* :mod:`~hysteresis.preisach.continuous` — :class:`ContinuousPreisachModel` (a density), with
  :mod:`~hysteresis.preisach.gaussian` (the width-disorder density);
* :mod:`~hysteresis.preisach.projection` — the non-negative least-squares projection of an
  identified density onto a discrete model (:func:`project_identification`);
* :mod:`~hysteresis.preisach._kernels` — the compiled kernels of both models.
"""

from hysteresis.preisach.base import PreisachModel, PreisachState
from hysteresis.preisach.continuous import ContinuousPreisachModel
from hysteresis.preisach.discrete import DiscretePreisachModel
from hysteresis.preisach.projection import PreisachProjection, project_identification

__all__ = [
    "PreisachModel",
    "DiscretePreisachModel",
    "ContinuousPreisachModel",
    "PreisachState",
    "PreisachProjection",
    "project_identification",
]
