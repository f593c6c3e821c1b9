"""Deprecated alias of :mod:`hysteresis.preisach.projection` (kept for one release).

``import hysteresis.fitting`` emits a :class:`DeprecationWarning`; import from
``hysteresis.preisach.projection`` (or ``hysteresis.preisach``) instead. This is a package, not a
module file, so that git sees the old ``hysteresis/fitting.py`` as renamed to the new path.
"""

import warnings

from hysteresis.preisach.projection import (
    PreisachProjection,
    _everett_adjoint,  # noqa: F401 - imported by name in older code
    _everett_apply,  # noqa: F401
    project_identification,
)

__all__ = ["PreisachProjection", "project_identification"]

warnings.warn(
    "hysteresis.fitting is deprecated and will be removed in the next release; import "
    "project_identification and PreisachProjection from hysteresis.preisach.projection",
    DeprecationWarning,
    stacklevel=2,
)
