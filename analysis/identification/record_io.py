"""Reading an input/output record (a delimited text file) for the record fitters.

Format: one sample per line, fields separated by commas, semicolons, tabs or white space (the
separator of the first data line decides); blank lines and lines starting with ``#`` are
skipped. The first line is a header when any of its fields is not a number; the input and
output columns are then found by name (default ``input`` and ``output``, case-insensitive).
Without a header, columns are named by 1-based position (``"1"``, ``"2"``; default the first
two). Every value must be a finite number: a bad file is refused with one line naming the file,
the line and the column.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["DEFAULT_COLUMNS", "InputOutputRecord", "read_record"]

#: the header names of the input and output columns looked for by default
DEFAULT_COLUMNS = ("input", "output")


@dataclass(frozen=True)
class InputOutputRecord:
    """A record read from a file: inputs ``u``, outputs ``y`` and the names of their columns."""

    u: np.ndarray
    y: np.ndarray
    columns: tuple[str, str]
    path: str


def _split(line: str, sep: str | None) -> list[str]:
    return [f.strip() for f in (line.split(sep) if sep else line.split())]


def _number(text: str) -> float | None:
    try:
        return float(text)
    except ValueError:
        return None


def read_record(
    path: str | Path,
    columns: tuple[str, str] | None = None,
    min_samples: int = 2,
) -> InputOutputRecord:
    """Read the input and output columns of a delimited text file (module docstring).

    Parameters
    ----------
    path:
        The file.
    columns:
        ``(input, output)`` header names, or 1-based positions as text for a file without a
        header (default :data:`DEFAULT_COLUMNS`, or the first two columns without a header).
    min_samples:
        Least number of samples (rows).

    Raises
    ------
    ValueError
        One line naming the file (and the line and column): unreadable, no such column,
        a non-numeric or non-finite value, a short row, fewer than ``min_samples`` rows.
    """
    path = Path(path)
    if columns is not None and (
        isinstance(columns, str)
        or len(columns) != 2
        or not all(isinstance(c, str) and c for c in columns)
    ):
        raise TypeError(f"columns must be two names (input, output), got {columns!r}")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        why = getattr(exc, "strerror", None) or str(exc)
        raise ValueError(f"{path}: cannot be read ({why})") from None
    lines = [
        (k, ln.strip())
        for k, ln in enumerate(text.splitlines(), start=1)
        if ln.strip() and not ln.lstrip().startswith("#")
    ]
    if not lines:
        raise ValueError(f"{path}: no data (an empty file, or only comments)")
    first = lines[0][1]
    sep = next((s for s in (",", ";", "\t") if s in first), None)
    head = _split(first, sep)
    has_header = any(_number(f) is None for f in head)
    if has_header:
        names = [h.strip("\"'") for h in head]
        wanted = DEFAULT_COLUMNS if columns is None else columns
        lower = [n.lower() for n in names]
        index = []
        for w in wanted:
            if w.lower() not in lower:
                raise ValueError(
                    f"{path}: no column {w!r} (its columns: {', '.join(names)}); name the input "
                    "and output columns"
                )
            index.append(lower.index(w.lower()))
        body = lines[1:]
        used = (names[index[0]], names[index[1]])
    else:
        wanted = ("1", "2") if columns is None else columns
        index = []
        for w in wanted:
            if not re.fullmatch(r"[1-9][0-9]*", w) or int(w) > len(head):
                raise ValueError(
                    f"{path}: has no header, so columns are positions 1 to {len(head)}; got {w!r}"
                )
            index.append(int(w) - 1)
        body = lines
        used = (wanted[0], wanted[1])
    need = max(index) + 1
    u = np.empty(len(body))
    y = np.empty(len(body))
    for row, (lineno, line) in enumerate(body):
        fields = _split(line, sep)
        if len(fields) < need:
            raise ValueError(f"{path} line {lineno}: {len(fields)} fields, the columns need {need}")
        for arr, col, name in ((u, index[0], used[0]), (y, index[1], used[1])):
            value = _number(fields[col])
            if value is None:
                raise ValueError(
                    f"{path} line {lineno}, column {name!r}: {fields[col]!r} is not a number"
                )
            if not math.isfinite(value):
                raise ValueError(
                    f"{path} line {lineno}, column {name!r}: {fields[col]!r} is not finite"
                )
            arr[row] = value
    if u.size < min_samples:
        raise ValueError(f"{path}: {u.size} samples; a fit needs at least {min_samples}")
    return InputOutputRecord(u, y, used, str(path))


def write_record(
    path: str | Path, u: Any, y: Any, columns: tuple[str, str] = DEFAULT_COLUMNS
) -> Path:
    """Write ``u`` and ``y`` as a CSV file with the header ``columns`` (what
    :func:`read_record` reads back exactly: ``repr`` of every float)."""
    u = np.asarray(u, dtype=float).ravel()
    y = np.asarray(y, dtype=float).ravel()
    if u.shape != y.shape:
        raise ValueError(f"u and y must have one length, got {u.size} and {y.size}")
    path = Path(path)
    rows = "".join(f"{a!r},{b!r}\n" for a, b in zip(u.tolist(), y.tolist(), strict=True))
    path.write_text(f"{columns[0]},{columns[1]}\n" + rows, encoding="utf-8")
    return path
