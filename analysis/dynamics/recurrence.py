"""Basins by recurrences on a cell grid of the Poincaré section (Datseris & Wagemakers 2022,
"Effortless estimation of basins of attraction", the recurrence mapper of Attractors.jl).

Each start is followed on the stroboscopic section (one point per forcing period) and every
point is mapped to a cell of a grid over the section. A finite state machine reads the cells'
labels and stops the start as soon as its fate is known, instead of integrating every start
for a fixed budget:

* a start that visits cells of a known attractor ``mx_chk_att`` times in a row belongs to it;
* a start that visits basin cells of one attractor ``mx_chk_hit_bas + 1`` times in a row (cells
  that an earlier start passed on its way to that attractor) belongs to it;
* a start that revisits cells it has itself visited ``mx_chk_fnd_att`` times in a row has found
  a new attractor: it goes on ``mx_chk_loc_att`` steps, and every cell it visits then is
  recorded as that attractor's;
* a start outside the cell box (``box``) for ``mx_chk_lost`` steps in a row is lost,
  one that diverges (the engine's divergence test) divergent, and one still searching after
  ``max_steps`` periods undecided — unless an attractor was found after it in the same chunk:
  then it runs once more at the chunk's end, with the cells known now (a departure from
  Attractors.jl, which leaves it unlabelled: the first starts of a chunk would otherwise pay
  for finding a chaotic attractor, which at cells of 0.05 takes about the budget; its
  ``steps`` add up both runs).

Plain reading of :func:`recurrence_chunk` (one task: a list of starts sharing one cell grid)::

    cells = {}                                 # cell -> 2a (attractor a) or 2a + 1 (its basin)
    for every start: visited = set(); state = search; count = 0
        for step in 1..max_steps:  x = next section point; c = cell(x)
            found:      record c for the new attractor a; count += 1;
                        count == mx_chk_loc_att -> label a
            cell c of attractor b (2b):  b twice in a row (mx_chk_att)          -> label b
            basin cell of b (2b + 1):    more than mx_chk_hit_bas in a row       -> label b
            c in visited:  count += 1; count == mx_chk_fnd_att -> found (a new attractor)
            empty c:       visited.add(c); count = 0
            outside box:   mx_chk_lost in a row                                 -> lost
        label a: every visited cell still empty becomes a basin cell of a (path_basins)

A change of state (search, attractor hit, basin hit) restarts the count at 1, as in
Attractors.jl; leaving or entering the box does not (an attractor may reach beyond it).

**Which coordinates the cells have.** Two section points with the same (q, v) but different
memory are different states with different futures, so the cells include the memory the section
point carries: for play-type operators the cells are over ``(q, v, w)`` (w the play's wagon
position; ``M = f(w)`` adds nothing), otherwise over ``(q, v, M)`` (the engine's sample columns;
an operator whose memory is more than M — relays, Preisach — has states the cells conflate,
which coarse cells do anyway). For the erf play at the section the wagon is mostly inside the
band (w free, not ``q ∓ p/2``), so w is a genuine third coordinate.

**Basin cells.** Attractors.jl labels the cell of each classified start (its grid of starts is
the cell grid). Here the starts of a (q0, v0) grid lie on a sheet of the (q, v, w) cell space
(``w0 = q0 − p/2``) that later orbits rarely cross, so ``path_basins`` (default) labels every
cell a start visited on its way to attractor a as a basin cell of a — the trajectory is a
witness that the cell leads to a (for cells small against the basins' structure). Requiring
``mx_chk_hit_bas + 1`` basin cells of the same attractor in a row guards against a single cell
straddling a boundary.

**A new attractor that meets a known one.** Attractors.jl raises when a start that is locating
a new attractor enters a known attractor's cell (two attractors in one cell, or an attractor
declared before its transient ended). Here the new cells join the known attractor and the start
gets its label: a chaotic attractor whose cells were not all recorded the first time is found
again this way. Each such merge is counted (``merges``).

The chunks of one map do not share cells (each is one task, so tasks stay independent and
resumable); :func:`merge_attractors` joins the chunks' attractors that share a cell.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from analysis.dynamics.attractors import start_state
from hysteresis._validation import finite_scalar, nonnegative_integer, positive_integer
from oscillators import DivergenceError

__all__ = [
    "DIVERGED",
    "LOST",
    "NO_STATE",
    "UNDECIDED",
    "RecurrenceSettings",
    "cell_columns",
    "merge_attractors",
    "recurrence_chunk",
    "representative_state",
]

#: outcome codes of a start (a label >= 0 is the chunk's attractor index)
DIVERGED, NO_STATE, UNDECIDED, LOST = -1, -2, -3, -4

_SEARCH, _ATT_HIT, _BAS_HIT, _LOST, _FOUND = range(5)
_EMPTY, _VISITED, _OUT = -1, -2, -3


@dataclass(frozen=True)
class RecurrenceSettings:
    """The recurrence mapper's knobs (module docstring), with Attractors.jl's defaults where it
    has them (its newer names in brackets).

    Attributes
    ----------
    cell_size:
        Edge of the cubic cells over the section coordinates (absolute, in the units of q, v
        and w). Cells must be small against the distance between attractors and the basins'
        structure, and large enough that a chaotic attractor is covered in a few hundred
        periods: 0.05 for the erf play (attractors of extent ~3). Coexisting attractors
        closer than a cell are merged: at C = 1, ζ = 0.1 the sum ``0.7*erf-play +
        0.3*preisach`` (100 relays) has a period-1 and a period-2 orbit 0.003–0.009 apart,
        which need cells of 0.002 (tests/test_analysis/dynamics/test_basins_recurrence_c1.py).
    mx_chk_fnd_att:
        Recurrences in a row on the start's own cells that declare a new attractor (100;
        ``consecutive_recurrences``).
    mx_chk_loc_att:
        Steps a new attractor is followed, recording its cells (1000;
        ``attractor_locate_steps``).
    mx_chk_att:
        Known attractor's cells in a row that label a start (2;
        ``consecutive_attractor_steps``).
    mx_chk_hit_bas:
        Basin cells of one attractor in a row, beyond which a start gets its label (10;
        ``consecutive_basin_steps``).
    mx_chk_lost:
        Steps in a row outside ``box`` after which a start is lost (20;
        ``consecutive_lost_steps``).
    box:
        ``((q_lo, q_hi), (v_lo, v_hi), (m_lo, m_hi))`` bounds of the cell grid, or ``None``
        (default: unbounded, cells kept in a dictionary; a start then ends only by a label, the
        divergence test or ``max_steps``, which :func:`~analysis.dynamics.basins.basins` sets
        to its ``max_periods − transient``: Attractors.jl's ``maximum_iterations``).
    path_basins:
        Label the cells a start visited as basin cells of its attractor (default ``True``;
        ``False``: no basin cells, only attractor hits and recurrences label starts).
    batch:
        Periods integrated per engine call while searching (a start stops at most
        ``batch − 1`` periods late; larger batches save call overhead).
    chunk:
        Starts per task (one cell grid per task): larger chunks reuse more basin cells (C =
        2.92, 100 × 100 starts: 16.2 periods per start with chunks of 2500, 13.4 with 10 000)
        but give fewer tasks to spread over workers and to resume from.
    """

    cell_size: float = 0.05
    mx_chk_fnd_att: int = 100
    mx_chk_loc_att: int = 1000
    mx_chk_att: int = 2
    mx_chk_hit_bas: int = 10
    mx_chk_lost: int = 20
    box: tuple[tuple[float, float], ...] | None = None
    path_basins: bool = True
    batch: int = 4
    chunk: int = 10_000

    def __post_init__(self) -> None:
        size = finite_scalar(self.cell_size, "cell_size")
        if not size > 0:
            raise ValueError(f"cell_size must be > 0, got {self.cell_size}")
        for name in ("mx_chk_fnd_att", "mx_chk_loc_att", "mx_chk_att", "batch", "chunk"):
            positive_integer(getattr(self, name), name)
        for name in ("mx_chk_hit_bas", "mx_chk_lost"):
            nonnegative_integer(getattr(self, name), name)
        if not isinstance(self.path_basins, bool):
            raise TypeError(f"path_basins must be a bool, got {self.path_basins!r}")
        if self.box is not None:
            box = np.asarray(self.box, dtype=float)
            bad = box.shape != (3, 2) or not np.all(np.isfinite(box))
            if bad or np.any(box[:, 0] >= box[:, 1]):
                raise ValueError(
                    f"box must be three (low, high) pairs with low < high, got {self.box!r}"
                )

    def task(self) -> dict:
        """The knobs a task needs (JSON-ready)."""
        return {
            "cell_size": float(self.cell_size),
            "mx_chk_fnd_att": self.mx_chk_fnd_att,
            "mx_chk_loc_att": self.mx_chk_loc_att,
            "mx_chk_att": self.mx_chk_att,
            "mx_chk_hit_bas": self.mx_chk_hit_bas,
            "mx_chk_lost": self.mx_chk_lost,
            "box": None if self.box is None else [list(map(float, b)) for b in self.box],
            "path_basins": self.path_basins,
            "batch": self.batch,
        }


def cell_columns(columns: Sequence[str]) -> tuple[int, ...]:
    """Indices of the section columns the cells are over: ``(q, v, w)`` when the engine samples
    the play's wagon ``w``, else ``(q, v, M)`` (module docstring)."""
    cols = tuple(columns)
    return (0, 1, cols.index("w")) if "w" in cols else (0, 1, 2)


def recurrence_chunk(
    *,
    system: Any,
    starts: Sequence[Sequence[float]],
    transient: int,
    max_steps: int,
    cell_size: float,
    mx_chk_fnd_att: int,
    mx_chk_loc_att: int,
    mx_chk_att: int,
    mx_chk_hit_bas: int,
    mx_chk_lost: int,
    box: Sequence[Sequence[float]] | None,
    path_basins: bool,
    batch: int,
    system_key: str = "",
) -> dict:
    """One task: the recurrence mapper over ``starts`` (rows ``(q0, v0, w0)``, w0 nan: default
    memory) with one cell grid (module docstring). ``system_key`` only names the system in the
    task's key.

    Returns ``outcome`` (per start: the chunk's attractor index, or :data:`DIVERGED`,
    :data:`NO_STATE`, :data:`UNDECIDED`, :data:`LOST`), ``steps`` (periods integrated after the
    transient), ``stop`` (0 new attractor, 1 attractor hit, 2 basin hit, 3 other), and per
    attractor of the chunk: ``cells`` (its recorded cells, concatenated, integer triples),
    ``cell_counts``, ``found_by`` (the start that found it) and ``found_steps`` (the periods
    after which that start's state is on it: rerun it to get the state), plus ``merges``.
    """
    pts = np.asarray(starts, dtype=float).reshape(-1, 3)
    inv = 1.0 / cell_size
    lo_box = hi_box = None
    if box is not None:
        lo_box = [float(b[0]) for b in box]
        hi_box = [float(b[1]) for b in box]
    cells: dict[tuple[int, int, int], int] = {}
    att_cells: list[list[tuple[int, int, int]]] = []
    found_by: list[int] = []
    found_steps: list[int] = []
    n = pts.shape[0]
    outcome = np.full(n, UNDECIDED, dtype=np.int32)
    steps = np.zeros(n, dtype=np.int32)
    stop = np.full(n, 3, dtype=np.int8)
    merges = 0
    T = system.period
    # a start still searching at max_steps is run once more at the end of the chunk if an
    # attractor was found after it: the first starts of a chunk otherwise pay for finding the
    # attractors (a chaotic one needs ~mx_chk_fnd_att recurrences on fine cells)
    order, known_at_end, pos = list(range(n)), np.zeros(n, dtype=np.int64), 0
    while pos < len(order):
        i = order[pos]
        pos += 1
        retry = pos > n
        if retry and len(att_cells) == known_at_end[i]:
            continue  # nothing found since: it stays undecided
        q0, v0, w0 = pts[i]
        try:
            state = start_state(system, q0, v0, None if math.isnan(w0) else w0)
        except ValueError:
            outcome[i] = NO_STATE
            continue
        eng = system.engine(state)
        cols = cell_columns(eng.sample_columns)
        out = np.empty((max(batch, mx_chk_loc_att), len(eng.sample_columns)))
        done = 0  # periods integrated
        try:
            if transient:
                times = np.array([transient * T])
                eng.advance(times, out[:1])
                system.check_finite(eng, out[:1, :2], times)
        except DivergenceError:
            outcome[i] = DIVERGED
            continue
        visited: set[tuple[int, int, int]] = set()
        fsm, count, lost, prev = _SEARCH, 0, 0, _EMPTY
        new = -1  # index of the attractor this start is locating
        label = None
        buf_pos, buf_len = 0, 0
        while label is None:
            if done >= max_steps:
                # a start that has declared a new attractor keeps it (locating only records)
                label, kind = (new, 0) if fsm == _FOUND else (UNDECIDED, 3)
                break
            if buf_pos == buf_len:
                # the locate phase runs a known number of steps: one call for them
                m = mx_chk_loc_att - count if fsm == _FOUND else batch
                m = min(m, max_steps - done)
                times = (transient + done + 1 + np.arange(m)) * T
                try:
                    eng.advance(times, out[:m])
                    system.check_finite(eng, out[:m, :2], times)
                except DivergenceError:
                    label, kind = DIVERGED, 3
                    break
                buf_pos, buf_len = 0, m
            row = out[buf_pos]
            buf_pos += 1
            done += 1
            x = (row[cols[0]], row[cols[1]], row[cols[2]])
            if lo_box is not None and not all(lo_box[j] <= x[j] <= hi_box[j] for j in range(3)):
                key = None
                lab = _OUT
            else:
                key = (math.floor(x[0] * inv), math.floor(x[1] * inv), math.floor(x[2] * inv))
                lab = cells.get(key, _EMPTY)
                if lab == _EMPTY and key in visited:
                    lab = _VISITED
            if fsm == _FOUND:
                if key is not None and lab != 2 * new:
                    if lab >= 0 and lab % 2 == 0:
                        # a known attractor's cell: the new one is that attractor
                        old = lab // 2
                        for c in att_cells[new]:
                            cells[c] = lab
                        att_cells[old].extend(att_cells[new])
                        att_cells[new] = []
                        merges += 1
                        new = old
                    else:
                        cells[key] = 2 * new
                        att_cells[new].append(key)
                count += 1
                if count >= mx_chk_loc_att:
                    if found_by[new] < 0:
                        found_by[new], found_steps[new] = i, transient + done
                    label, kind = new, 0
                continue
            nxt = (
                _SEARCH
                if lab in (_EMPTY, _VISITED)
                else _LOST
                if lab == _OUT
                else _ATT_HIT
                if lab % 2 == 0
                else _BAS_HIT
            )
            if nxt != fsm:
                if _LOST in (fsm, nxt):
                    lost = 1
                else:
                    count = 1
            fsm = nxt
            if fsm == _ATT_HIT:
                if lab == prev:
                    count += 1
                if count >= mx_chk_att:
                    label, kind = lab // 2, 1
            elif fsm == _SEARCH:
                if lab == _EMPTY:
                    visited.add(key)
                    count = 0
                else:
                    count += 1
                if count >= mx_chk_fnd_att:
                    new = len(att_cells)
                    att_cells.append([key])
                    cells[key] = 2 * new
                    found_by.append(-1)
                    found_steps.append(0)
                    fsm, count = _FOUND, 0
            elif fsm == _BAS_HIT:
                count = count + 1 if lab == prev else 0
                if count > mx_chk_hit_bas:
                    label, kind = lab // 2, 2
            else:  # outside the box
                lost += 1
                if lost > mx_chk_lost:
                    label, kind = LOST, 3
            prev = lab
        if new >= 0 and found_by[new] < 0:
            # stopped (max_steps) while locating: the state now is on the attractor
            found_by[new], found_steps[new] = i, transient + done
        outcome[i], stop[i] = label, kind
        steps[i] = steps[i] + done if retry else done
        if label == UNDECIDED and not retry:
            known_at_end[i] = len(att_cells)
            order.append(i)
        if label >= 0 and path_basins:
            basin = 2 * label + 1
            for c in visited:
                if c not in cells:
                    cells[c] = basin
    # attractors merged into an older one are empty: drop them, renumber the outcomes
    keep = [a for a, c in enumerate(att_cells) if c]
    renumber = np.full(len(att_cells) + 1, -1, dtype=np.int32)
    renumber[keep] = np.arange(len(keep), dtype=np.int32)
    known = outcome >= 0
    outcome[known] = renumber[outcome[known]]
    att_cells = [att_cells[a] for a in keep]
    found_by = [found_by[a] for a in keep]
    found_steps = [found_steps[a] for a in keep]
    counts = np.array([len(c) for c in att_cells], dtype=np.int64)
    flat = [c for group in att_cells for c in group]
    return {
        "outcome": outcome,
        "steps": steps,
        "stop": stop,
        "cells": np.array(flat, dtype=np.int64).reshape(-1, 3),
        "cell_counts": counts,
        "found_by": np.array(found_by, dtype=np.int64),
        "found_steps": np.array(found_steps, dtype=np.int64),
        "merges": merges,
    }


def merge_attractors(results: Sequence[dict]) -> tuple[list[np.ndarray], list[list[tuple]]]:
    """Join the chunks' attractors that share a cell (union-find over the cell keys).

    Returns, per chunk, the global attractor index of each of its attractors, and per global
    attractor its members ``(chunk, local index)`` in chunk order."""
    parent: list[int] = []
    owner: dict[tuple[int, int, int], int] = {}
    index: list[np.ndarray] = []

    def find(a: int) -> int:
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for r in results:
        counts = np.asarray(r["cell_counts"], dtype=np.int64)
        cells = np.asarray(r["cells"], dtype=np.int64).reshape(-1, 3)
        ids = np.arange(len(parent), len(parent) + counts.size)
        parent.extend(int(a) for a in ids)
        offsets = np.concatenate([[0], np.cumsum(counts)])
        for a, lo, hi in zip(ids, offsets[:-1], offsets[1:], strict=True):
            for c in map(tuple, cells[lo:hi].tolist()):
                b = owner.setdefault(c, int(a))
                ra, rb = find(int(a)), find(b)
                if ra != rb:
                    parent[max(ra, rb)] = min(ra, rb)
        index.append(ids)
    roots = sorted({find(a) for a in range(len(parent))})
    number = {r: g for g, r in enumerate(roots)}
    members: list[list[tuple]] = [[] for _ in roots]
    out = []
    for k, ids in enumerate(index):
        g = np.array([number[find(int(a))] for a in ids], dtype=np.int64)
        for local, gi in enumerate(g):
            members[gi].append((k, local))
        out.append(g)
    return out, members


def representative_state(system: Any, start: Sequence[float], periods: int) -> Any:
    """The state ``periods`` forcing periods after ``start`` ``(q0, v0, w0)`` (sampled every
    period, as the mapper did): on the attractor that start located."""
    q0, v0, w0 = (float(x) for x in start)
    eng = system.engine(start_state(system, q0, v0, None if math.isnan(w0) else w0))
    times = np.arange(1, periods + 1, dtype=float) * system.period
    out = np.empty((times.size, len(eng.sample_columns)))
    eng.advance(times, out)
    system.check_finite(eng, out[:, :2], times)
    return eng.state()
