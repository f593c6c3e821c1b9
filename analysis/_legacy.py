"""The module paths of ``analysis`` before it was grouped by purpose, kept for one release.

``import analysis.lyapunov`` (and the other paths in :data:`MOVED`) still works: a finder at the
front of :data:`sys.meta_path` answers only for these names and only when the package has no
real module of that name (so it also wins over an editable install's finder that still maps the
old file of another checkout), imports the new module, warns with a :class:`DeprecationWarning`
naming the new path, and registers the very same module object under the old name.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import importlib.util
import sys
import warnings
from types import ModuleType

__all__ = ["MOVED", "install"]

#: old module path -> new module path
MOVED = {
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
}


class _LegacyPaths(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finder and loader of the old paths: the new module under the old name, with a warning."""

    def find_spec(
        self, fullname: str, path: object = None, target: ModuleType | None = None
    ) -> importlib.machinery.ModuleSpec | None:
        if fullname not in MOVED:
            return None
        if importlib.machinery.PathFinder.find_spec(fullname, path) is not None:
            return None  # a real module of the old name in this package: it wins
        return importlib.util.spec_from_loader(fullname, self)

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType:
        new = MOVED[spec.name]
        # stacklevel 2: the import statement (the warnings module skips importlib's frames)
        warnings.warn(
            f"{spec.name} is deprecated and will be removed in the next release; "
            f"import {new} instead",
            DeprecationWarning,
            stacklevel=2,
        )
        return importlib.import_module(new)

    def exec_module(self, module: ModuleType) -> None:
        """Nothing to run: the new module is already executed."""


def install() -> None:
    """Put the finder at the front of :data:`sys.meta_path` (once)."""
    if not any(isinstance(f, _LegacyPaths) for f in sys.meta_path):
        sys.meta_path.insert(0, _LegacyPaths())
