"""Version and import-name ownership of the ``hysteresis-toolkit`` distribution.

The toolkit installs three top-level import names, ``hysteresis``, ``oscillators`` and
``analysis``. Unrelated PyPI distributions use some of the same names (``hysteresis`` 2.0.5,
``analysis`` 0.1.7); installed into one environment, one overwrites the other's files and both
break in confusing ways. Each package therefore checks at import that no *other* installed
distribution claims its import name and fails with an ``ImportError`` naming the conflicting
distribution. (Run from a source tree without installation, nothing is checked.)
"""

from __future__ import annotations

import functools
import re
from importlib import metadata

__all__ = ["DISTRIBUTION", "IMPORT_NAMES", "check_import_name", "conflicting_distributions"]

#: the name of this distribution on PyPI
DISTRIBUTION = "hysteresis-toolkit"
#: the top-level import names it installs
IMPORT_NAMES = ("hysteresis", "oscillators", "analysis")


def _normalize(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


@functools.lru_cache(maxsize=1)
def _claims() -> dict[str, tuple[str, ...]]:
    """Import name -> other distributions (``"name version"``) that claim it.

    A distribution claims a name if it is called that name or lists it in ``top_level.txt``.
    Only metadata headers and ``top_level.txt`` are read (no RECORD), which keeps the check
    to a few milliseconds.
    """
    found: dict[str, list[str]] = {name: [] for name in IMPORT_NAMES}
    own = _normalize(DISTRIBUTION)

    def label(dist: metadata.Distribution) -> str | None:
        try:
            name = dist.metadata["Name"] or "?"
        except Exception:  # a broken metadata directory must not break our import
            return None
        return None if _normalize(name) == own else f"{name} {dist.version}"

    for imp in IMPORT_NAMES:  # a distribution named like the import name (cheap lookup)
        try:
            text = label(metadata.distribution(imp))
        except metadata.PackageNotFoundError:
            continue
        if text:
            found[imp].append(text)
    for dist in metadata.distributions():  # top_level.txt of every distribution (one read each)
        try:
            top_level = set((dist.read_text("top_level.txt") or "").split())
        except Exception:
            continue
        for imp in IMPORT_NAMES:
            if imp in top_level:
                text = label(dist)
                if text:
                    found[imp].append(text)
    return {k: tuple(sorted(set(v))) for k, v in found.items()}


def conflicting_distributions(import_name: str) -> tuple[str, ...]:
    """Other installed distributions that claim ``import_name`` (``"name version"`` each)."""
    return _claims().get(import_name, ())


def check_import_name(import_name: str) -> None:
    """Raise ``ImportError`` if another installed distribution claims ``import_name``."""
    others = conflicting_distributions(import_name)
    if others:
        raise ImportError(
            f"the import name {import_name!r} is also installed by the unrelated distribution "
            f"{', '.join(others)}; it overwrites or shadows {DISTRIBUTION}'s package of that "
            f"name. Uninstall it (pip uninstall {others[0].split()[0]}) or install "
            f"{DISTRIBUTION} into its own virtual environment."
        )
