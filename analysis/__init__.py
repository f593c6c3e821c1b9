"""Analyses of systems with hysteresis: Lyapunov spectra, dimensions, bifurcations, ensembles,
Preisach-plane identification, figures and the ``hyst`` command line.

Grouped by purpose: :mod:`analysis.dynamics` (one system: Lyapunov spectra, dimensions,
bifurcations, statistics), :mod:`analysis.experiments` (the paper's parameters, the model
registry, ensembles, task execution and the results store), :mod:`analysis.identification`,
:mod:`analysis.paper` (``hyst paper``) and :mod:`analysis.cli` (``hyst``).

Public names are imported lazily so that a command line subcommand only loads what it uses.
(The import-name check below imports :mod:`hysteresis`, which every analysis needs anyway.)
"""

from __future__ import annotations

import importlib
from typing import Any

from hysteresis._distribution import check_import_name as _check_import_name
from hysteresis._version import __version__ as __version__

# "analysis" is also the import name of an unrelated PyPI distribution: refuse to run mixed
_check_import_name("analysis")

_LAZY = {
    "lyapunov_spectrum": "analysis.dynamics.lyapunov",
    "TangentStepper": "analysis.dynamics.lyapunov",
    "LyapunovResult": "analysis.dynamics.lyapunov",
    "kaplan_yorke_dimension": "analysis.dynamics.dimensions",
    "box_counting_dimension": "analysis.dynamics.dimensions",
    "BoxCountingResult": "analysis.dynamics.dimensions",
    "self_averaging_parameter": "analysis.dynamics.statistics",
    "identify_preisach": "analysis.identification",
    "bifurcation_diagram": "analysis.dynamics.bifurcation",
    "magnetization_variance": "analysis.dynamics.statistics",
    "run_ensemble": "analysis.experiments.ensemble",
    "ensemble_task": "analysis.experiments.ensemble",
    "iid_magnetization": "analysis.experiments.iid",
    "ResultStore": "analysis.experiments.store",
    "run_tasks": "analysis.experiments.execution",
}

__all__ = sorted([*_LAZY, "__version__"])


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'analysis' has no attribute {name!r}")
    return getattr(importlib.import_module(module), name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
