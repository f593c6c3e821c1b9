"""The module paths before the grouping by purpose (``analysis.lyapunov``, ``hysteresis.fitting``,
...) were never released and are gone: importing one fails, and ``import analysis`` installs no
import hook (a finder on :data:`sys.meta_path` would change every later import of the process)."""

from __future__ import annotations

import importlib
import importlib.machinery
import subprocess
import sys

import pytest

_OLD = {
    "analysis.lyapunov": "analysis.dynamics.lyapunov",
    "analysis.dimensions": "analysis.dynamics.dimensions",
    "analysis.bifurcation": "analysis.dynamics.bifurcation",
    "analysis.statistics": "analysis.dynamics.statistics",
    "analysis.models": "analysis.experiments.models",
    "analysis.ensemble": "analysis.experiments.ensemble",
    "analysis.iid": "analysis.experiments.iid",
    "analysis.execution": "analysis.experiments.execution",
    "analysis.store": "analysis.experiments.store",
    "analysis.forc_io": "analysis.identification.forc_io",
    "analysis.fitting": "analysis.identification.fitting",
    "analysis.preisach_plots": "analysis.identification.plots",
    "hysteresis.fitting": "hysteresis.preisach.projection",
}


@pytest.mark.parametrize("old", sorted(_OLD))
def test_old_path_has_no_module_and_new_one_imports(old: str) -> None:
    """Asked of this checkout's package directory, not of :func:`importlib.import_module`: an
    editable install of another checkout appends a finder that still maps the old file there."""
    importlib.import_module(_OLD[old])
    parent, _, name = old.rpartition(".")
    path = importlib.import_module(parent).__path__
    assert importlib.machinery.PathFinder.find_spec(old, path) is None, f"{old} still exists"


def test_import_analysis_installs_no_finder() -> None:
    code = (
        "import sys; before = list(sys.meta_path); import analysis, hysteresis; "
        "print(sys.meta_path == before)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    assert out.strip() == "True"
