"""Analyses of systems with hysteresis: Lyapunov spectra, dimensions, bifurcations, ensembles,
Preisach-plane identification, figures and the ``hyst`` command line.

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
    "lyapunov_spectrum": "analysis.lyapunov",
    "TangentStepper": "analysis.lyapunov",
    "LyapunovResult": "analysis.lyapunov",
    "kaplan_yorke_dimension": "analysis.dimensions",
    "box_counting_dimension": "analysis.dimensions",
    "BoxCountingResult": "analysis.dimensions",
    "self_averaging_parameter": "analysis.statistics",
    "identify_preisach": "analysis.identification",
    "bifurcation_diagram": "analysis.bifurcation",
    "magnetization_variance": "analysis.statistics",
    "run_ensemble": "analysis.ensemble",
    "ensemble_task": "analysis.ensemble",
    "iid_magnetization": "analysis.iid",
    "ResultStore": "analysis.store",
    "run_tasks": "analysis.execution",
}

__all__ = sorted([*_LAZY, "__version__"])


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'analysis' has no attribute {name!r}")
    return getattr(importlib.import_module(module), name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
