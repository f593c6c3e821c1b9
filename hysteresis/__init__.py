"""Rate-independent hysteresis operators with immutable state and linearization."""

from hysteresis._distribution import check_import_name as _check_import_name
from hysteresis._version import __version__

# fail early, naming the culprit, if an unrelated distribution also installs "hysteresis"
_check_import_name("hysteresis")

from hysteresis import duhem_memory as _duhem_memory  # noqa: F401  (Duhem.with_memory)
from hysteresis.algebra import (
    BranchSum,
    RelaySum,
    SumState,
    SwitchingSum,
    WeightedSum,
    weighted_sum,
)
from hysteresis.base import (
    Branch,
    ContinuousHysteron,
    Hysteron,
    HysteronState,
    Linearization,
    PiecewiseConstantHysteron,
    Switching,
    SwitchingHysteron,
)
from hysteresis.bouc_wen import BoucWen
from hysteresis.cascade import Cascade, CascadeState
from hysteresis.duhem import Duhem, DuhemState
from hysteresis.flow import BranchFlow
from hysteresis.inverse import InverseOperator, InverseState
from hysteresis.jiles_atherton import JilesAtherton
from hysteresis.play import GeneralizedPlay, PlayOperator, PlayState
from hysteresis.prandtl_ishlinskii import PIState, PrandtlIshlinskii
from hysteresis.preisach import (
    ContinuousPreisachModel,
    DiscretePreisachModel,
    PreisachModel,
    PreisachState,
)
from hysteresis.relay import Relay, RelayState
from hysteresis.relay_table import NestedPlan, RelayTable
from hysteresis.rfim import RandomFieldIsing, RandomFieldIsingState
from hysteresis.spin_dimers import DimerThresholds, SpinDimerEnsemble
from hysteresis.static_map import StaticMap, StaticMapState

__all__ = [
    "BoucWen",
    "Duhem",
    "DuhemState",
    "RandomFieldIsing",
    "RandomFieldIsingState",
    "SwitchingHysteron",
    "SwitchingSum",
    "Cascade",
    "CascadeState",
    "InverseOperator",
    "JilesAtherton",
    "InverseState",
    "StaticMap",
    "StaticMapState",
    "BranchSum",
    "RelaySum",
    "SumState",
    "WeightedSum",
    "weighted_sum",
    "BranchFlow",
    "__version__",
    "Branch",
    "HysteronState",
    "ContinuousHysteron",
    "ContinuousPreisachModel",
    "DimerThresholds",
    "DiscretePreisachModel",
    "GeneralizedPlay",
    "Hysteron",
    "Linearization",
    "PIState",
    "PiecewiseConstantHysteron",
    "PlayOperator",
    "PlayState",
    "NestedPlan",
    "PrandtlIshlinskii",
    "PreisachModel",
    "PreisachState",
    "Relay",
    "RelayState",
    "RelayTable",
    "SpinDimerEnsemble",
    "Switching",
]
