"""One JSON encoding for every record the toolkit writes (``--json`` output, reports).

Strict JSON has no infinities or NaN; Python's ``json`` would write the invalid tokens
``Infinity``/``NaN``, and ``null`` would be ambiguous. Non-finite floats are therefore written
as the strings ``"inf"``, ``"-inf"`` and ``"nan"`` (``float(x)`` reads them back); numpy scalars
and arrays become Python numbers and lists, paths become strings.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["jsonable", "to_json"]


def jsonable(x: Any) -> Any:
    """``x`` with every value converted to what :func:`json.dumps` writes as strict JSON."""
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return [jsonable(v) for v in x.tolist()]
    if isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, float):
        if math.isnan(x):
            return "nan"
        if math.isinf(x):
            return "inf" if x > 0 else "-inf"
        return x
    if isinstance(x, Path):
        return str(x)
    return x


def to_json(record: Any, indent: int | None = None) -> str:
    """Strict JSON text of ``record`` (see the module docstring for the encoding)."""
    return json.dumps(jsonable(record), indent=indent, allow_nan=False)
