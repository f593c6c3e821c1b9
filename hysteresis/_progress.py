"""Progress bars (tqdm) that stay visible when the terminal reports zero columns.

A pseudo-terminal without a size (``script``, ``docker run -t``, some CI runners) reports 0
columns and 0 rows; tqdm then draws nothing at all (a bar below the last row is hidden). The bars
here fall back to a fixed width and height there.
"""

from __future__ import annotations

import os
import sys
from typing import Any

#: width and height used when the terminal reports none
FALLBACK_COLUMNS = 100
FALLBACK_ROWS = 24


def _terminal_columns() -> int:
    try:
        return os.get_terminal_size(sys.stderr.fileno()).columns
    except (AttributeError, OSError, ValueError):
        return 0


def progress_bar(iterable: Any = None, **kwargs: Any) -> Any:
    """``tqdm.auto.tqdm(iterable, **kwargs)``, resizing with the terminal where it has a size,
    at :data:`FALLBACK_COLUMNS` columns and :data:`FALLBACK_ROWS` rows where it reports
    none."""
    from tqdm.auto import tqdm

    if "ncols" not in kwargs:
        if _terminal_columns() > 0:
            kwargs.setdefault("dynamic_ncols", True)
        else:
            kwargs["ncols"] = FALLBACK_COLUMNS
            kwargs["dynamic_ncols"] = False
            kwargs.setdefault("nrows", FALLBACK_ROWS)
    return tqdm(iterable, **kwargs)
