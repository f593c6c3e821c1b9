"""Memory bound of an identification: estimate the peak before allocating, refuse above a bound.

Where memory scales: every identification tabulates the Everett function on an
``n_α × n_β`` lattice (protocol lattice of measured data, native grid of reversal fields × union
of fields, or the operator's regular grid), with a handful of same-sized temporaries (the
interpolation across reversal fields, the masks, the cell masses). The smoothing dominates:

* protocol lattice (:func:`~analysis.identification.smoothing.grid_quadratic_density`): for every
  evaluated node (up to half the lattice) 15 moment correlations, the 6×6 normal matrix, its
  eigen-decomposition and right-hand side, about 1 kB per node;
* native grid (:func:`~analysis.identification.smoothing.local_quadratic_density`): the k-d tree's
  neighbour lists hold every sample of every window, ∝ the window's area in nodes.
* native table fitted by the lattice regression (VARIFORC, ``"auto"``, uncertainty:
  :func:`~analysis.identification.variforc.weighted_quadratic_density`, FFT normal equations):
  a few lattice-sized arrays per moment, independent of the window.

The estimate (:func:`estimate_identification_bytes`), in bytes, with ``N = n_α·n_β`` and ``P``
the number of measured points::

    peak ≈ 16·P + 40·N                                 (no smoothing)
         + 520·N                                       (protocol lattice, smoothed)
         + 44·N·(2·SF_r + 1)·(2·SF_s + 1)              (native grid, smoothed)
         + 360·N                                       (native table, lattice regression)

Calibrated against ``tracemalloc`` peaks (``tests/test_analysis/identification/test_memory.py``):
protocol lattice n = 101/201/401 measured 45/40/38 B·N unsmoothed and 440/484/508 B·N smoothed
(SF 3); native grid of the erf play n = 221/369/551 unsmoothed 29/26/25 B·N, n = 111/185 smoothed
960 B·N (SF 2) and 2930–2980 B·N (SF 4); the lattice regression on the erf play's native table
n = 101/201: 386/314 B·N (VARIFORC), 287/269 (``"auto"``), 281/249 (SF 3 with uncertainty);
a per-window term summed over scattered windows would overestimate these 8 to 60 times. The
estimate
is an upper bound: it lies between the measured peak and 1.75 times it (margin +0 % … +75 %;
+65 % on the unsmoothed native grid, where the curves are half the lattice) on those cases.

The bound (:func:`default_max_memory`) is :data:`MAX_MEMORY_FRACTION` of the physical memory
(``os.sysconf``), or :data:`FALLBACK_MAX_MEMORY` where that is unavailable; ``max_memory=``
(bytes) of the identification functions and of
:func:`~analysis.identification.forc_io.read_forc_file` and ``hyst identify --max-memory GB``
override it. Reading a file is bounded too
(:func:`estimate_read_bytes`, checked on the file's size before it is opened).
"""

from __future__ import annotations

import math
import os
from typing import Any

__all__ = [
    "MAX_MEMORY_FRACTION",
    "FALLBACK_MAX_MEMORY",
    "MemoryBoundError",
    "default_max_memory",
    "estimate_identification_bytes",
    "check_memory",
    "estimate_read_bytes",
]

#: fraction of the physical memory an identification may take by default
MAX_MEMORY_FRACTION = 0.5
#: default bound (bytes) where the physical memory cannot be read: 4 GiB
FALLBACK_MAX_MEMORY = 4 * 2**30

#: calibrated bytes per lattice node (see the module docstring)
_BYTES_PER_POINT = 16
_BYTES_PER_NODE = 40
_BYTES_PER_NODE_PROTOCOL_SMOOTHING = 520
_BYTES_PER_NODE_WINDOW_NATIVE = 44
_BYTES_PER_NODE_LATTICE_NATIVE = 360
#: calibrated bytes per byte of a FORC file while it is read (its lines, fields and curves)
_BYTES_PER_FILE_BYTE = 16


class MemoryBoundError(ValueError):
    """An identification whose estimated peak memory exceeds the bound (refused up front)."""


def default_max_memory() -> int:
    """The default bound in bytes: :data:`MAX_MEMORY_FRACTION` of the physical memory, or
    :data:`FALLBACK_MAX_MEMORY` where ``os.sysconf`` cannot tell."""
    try:
        total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        return FALLBACK_MAX_MEMORY
    if total <= 0:
        return FALLBACK_MAX_MEMORY
    return int(MAX_MEMORY_FRACTION * total)


def estimate_identification_bytes(
    n_points: int,
    n_alpha: int,
    n_beta: int | None = None,
    *,
    smoothing: tuple[float, float] | None = None,
    grid: str = "protocol",
) -> int:
    """Estimated peak bytes of an identification (formula and margin: module docstring).

    ``n_points``: measured points of all curves; ``n_alpha × n_beta``: the lattice (square when
    ``n_beta`` is omitted); ``smoothing``: ``(SF_r, SF_s)`` or ``None``; ``grid``:
    ``"protocol"`` (FFT normal equations), ``"native"`` (scattered local regression) or
    ``"lattice"`` (the native table fitted by the lattice regression).
    """
    nodes = float(n_alpha) * float(n_alpha if n_beta is None else n_beta)
    total = _BYTES_PER_POINT * float(n_points) + _BYTES_PER_NODE * nodes
    if smoothing is not None:
        if grid == "protocol":
            total += _BYTES_PER_NODE_PROTOCOL_SMOOTHING * nodes
        elif grid == "lattice":
            total += _BYTES_PER_NODE_LATTICE_NATIVE * nodes
        else:
            area = (2.0 * smoothing[0] + 1.0) * (2.0 * smoothing[1] + 1.0)
            total += _BYTES_PER_NODE_WINDOW_NATIVE * nodes * area
    return int(math.ceil(total)) if math.isfinite(total) else 2**63


def estimate_read_bytes(file_size: int) -> int:
    """Estimated peak bytes of reading a FORC file of ``file_size`` bytes: ``16·size`` (the
    readers hold its lines and parsed numbers; ``tracemalloc`` peaks of 8.7, 13.1 and 13.4 bytes
    per file byte on the test files: margin +20 % … +85 %)."""
    return int(_BYTES_PER_FILE_BYTE * max(int(file_size), 0))


def _gb(n: float) -> str:
    return f"{n / 1e9:.3g} GB"


def check_memory(estimate: int, max_memory: Any = None, what: str = "identification") -> int:
    """Refuse (:class:`MemoryBoundError`, one line naming the estimate, the bound and what to
    change) an ``estimate`` in bytes above ``max_memory`` (bytes; default
    :func:`default_max_memory`); returns the bound."""
    bound = default_max_memory() if max_memory is None else float(max_memory)
    if not (bound > 0):
        raise ValueError(f"max_memory must be > 0 bytes, got {max_memory!r}")
    if estimate > bound:
        raise MemoryBoundError(
            f"the {what} needs an estimated {_gb(estimate)} of memory, more than the bound "
            f"{_gb(bound)}: refused before allocating; choose a coarser step (--step, "
            "--grid-step), fewer curves, or raise the bound (--max-memory GB)"
        )
    return int(bound)
