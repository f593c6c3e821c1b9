"""The first use of a compiled engine says that numba compiles its kernels now.

The kernels are compiled with ``cache=True``: the first process that uses an engine compiles
them (up to a minute for the relay and play kernels) and writes the cache next to the kernel
module (``__pycache__``), in ``NUMBA_CACHE_DIR``, or in numba's per-user cache directory; later
processes load it in a fraction of a second. Without a word that first minute looks like a
hang, so the first engine of a process whose kernel module has no cache yet warns once
(:class:`CompilationNotice`, a ``UserWarning``; ``hyst`` prints its own line instead).
"""

from __future__ import annotations

import os
import sys
import warnings
from pathlib import Path

__all__ = ["CompilationNotice", "first_use_notice"]


class CompilationNotice(UserWarning):
    """The kernels of an engine are being compiled (first use on this machine)."""


#: kernel modules already checked in this process
_checked: set[str] = set()


def _cache_places() -> list[Path]:
    places = []
    for env in ("NUMBA_CACHE_DIR", "XDG_CACHE_HOME"):
        value = os.environ.get(env)
        if value:
            places.append(Path(value) / ("numba" if env == "XDG_CACHE_HOME" else ""))
    places.append(Path.home() / ".cache" / "numba")
    return places


def has_cache(module_name: str) -> bool:
    """True if numba's cache index of some kernel of ``module_name`` exists (next to the
    module, or in a cache directory)."""
    module = sys.modules.get(module_name)
    if module is None or not getattr(module, "__file__", None):
        return True  # nothing to say about a module that is not loaded
    source = Path(module.__file__)
    pattern = f"{source.stem}.*.nbi"
    if any((source.parent / "__pycache__").glob(pattern)):
        return True
    return any(place.is_dir() and any(place.rglob(pattern)) for place in _cache_places())


def first_use_notice(module_name: str | None, engine_name: str) -> None:
    """Warn once per process if the kernels of ``module_name`` have no cache yet."""
    if module_name is None or module_name in _checked:
        return
    _checked.add(module_name)
    if not has_cache(module_name):
        warnings.warn(
            f"first use of the {engine_name} on this machine: numba compiles its kernels now "
            "(once, up to a minute; cached for later runs)",
            CompilationNotice,
            stacklevel=4,
        )
