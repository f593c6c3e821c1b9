"""Congruency of minor loops: a grid-independent measure of non-Preisach behaviour.

Mayergoyz's representation theorem: a rate-independent operator is a Preisach model if and
only if it has the *wiping-out* property (return-point memory) and the *congruency* property —
all minor loops traced between the same two input extrema ``u1 < u2`` are congruent (equal up
to a vertical shift), whatever history brought the operator to them. For a Preisach model the
output change along the loop, ``ΔM(u) = M(u) − M(u1)``, comes from the relays of the triangle
``u1 < β <= α <= u2`` only, which every such history leaves in the same state (all down after
the descent to ``u1`` from at least ``u2``), so ``ΔM`` is the same for every history — exactly,
up to the round-off of the output sum. The random-field Ising model has return-point memory
but its avalanches depend on the neighbours' spins, which the history sets: its loops are not
congruent.

:func:`minor_loop_congruency` prepares the operator by each of several histories (turning
points from negative saturation), then drives it to ``u2`` and back to ``u1`` (so the last
extremum is ``>= u2`` and the last move a descent: the loop's start), and traces the loop
``u1 → u2 → u1`` on ``samples`` inputs each way. The *congruency violation* is::

    max over histories h and loop inputs u of |ΔM_h(u) − ΔM_ref(u)|

with the reference the descending major branch (history: positive saturation). It needs no
identification grid: it is a property of the operator, in units of its output. The
*return gap* ``max_h |M_h(end) − M_h(u1)|`` checks return-point memory (0 for both operator
families). :func:`congruency_scan` takes the loops between every pair of a set of nodes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["default_histories", "minor_loop_congruency", "congruency_scan"]


def _finite(x: Any, name: str) -> float:
    try:
        v = float(x)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a real number, got {x!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {x!r}")
    return v


def default_histories(low: float, high: float, saturation: float, count: int = 8) -> list:
    """``count`` histories (turning points, each from negative saturation ``−saturation``)
    that end above ``high`` or below ``low`` in different states: half rise to a maximum
    ``A ∈ [high, saturation]`` (the first, ``A = saturation``, is the reference: the
    descending major branch follows), half go to positive saturation and back down to a
    minimum ``B ∈ [−saturation, low)``."""
    low, high = _finite(low, "low"), _finite(high, "high")
    saturation = _finite(saturation, "saturation")
    if not low < high:
        raise ValueError(f"low must be < high, got low={low}, high={high}")
    if not saturation > max(abs(low), abs(high)):
        raise ValueError(f"saturation must exceed |low| and |high|, got {saturation}")
    if isinstance(count, bool) or not isinstance(count, int | np.integer) or count < 2:
        raise ValueError(f"count must be an integer >= 2, got {count!r}")
    n_a = (count + 1) // 2
    tops = np.linspace(saturation, high, n_a)
    bottoms = np.linspace(-saturation, low, count - n_a + 1)[:-1]
    out = [np.array([-saturation, a]) for a in tops]
    out += [np.array([-saturation, saturation, b]) for b in bottoms]
    return out


def minor_loop_congruency(
    operator: Any,
    low: float,
    high: float,
    histories: Sequence[Any],
    samples: int = 16,
) -> dict:
    """The congruency violation of the minor loop ``[low, high]`` (module docstring).

    ``operator``: any rate-independent operator with ``initial_state(u)`` and
    ``apply(inputs, state)``; ``histories``: turning-point sequences, each starting from
    negative saturation (the first is the reference); ``samples``: inputs per branch
    (evenly spaced, the endpoints included). Returns ``violation`` (max ``|ΔM_h − ΔM_ref|``),
    ``rms`` (over histories and inputs), ``height`` (the reference loop's ``ΔM(high)``),
    ``return_gap`` (return-point memory) and ``spread_at_low`` (how different the histories'
    states at ``u1`` are: the range of ``M(u1)``).
    """
    low, high = _finite(low, "low"), _finite(high, "high")
    if not low < high:
        raise ValueError(f"low must be < high, got low={low}, high={high}")
    if isinstance(samples, bool) or not isinstance(samples, int | np.integer) or samples < 2:
        raise ValueError(f"samples must be an integer >= 2, got {samples!r}")
    if len(histories) < 2:
        raise ValueError(f"histories must hold at least 2 sequences, got {len(histories)}")
    up = np.linspace(low, high, samples)
    loop = np.concatenate([up[1:], up[::-1][1:]])
    deltas, starts, gaps = [], [], []
    for k, h in enumerate(histories):
        h = np.asarray(h, dtype=float).reshape(-1)
        if h.size == 0 or not np.all(np.isfinite(h)):
            raise ValueError(f"histories[{k}] must be a non-empty finite sequence")
        drive = np.concatenate([h, [high, low], loop])
        m, _ = operator.apply(drive, operator.initial_state(float(drive[0])))
        m = np.asarray(m, dtype=float)
        start = m[h.size + 1]  # at u1, after the descent from u2
        deltas.append(m[h.size + 2 :] - start)
        starts.append(start)
        gaps.append(abs(m[-1] - start))
    d = np.asarray(deltas)
    diff = d[1:] - d[0]
    return {
        "violation": float(np.max(np.abs(diff))),
        "rms": float(np.sqrt(np.mean(diff**2))),
        "height": float(d[0][samples - 2]),
        "return_gap": float(max(gaps)),
        "spread_at_low": float(max(starts) - min(starts)),
    }


def congruency_scan(
    operator: Any,
    nodes: Sequence[float],
    saturation: float,
    count: int = 8,
    samples: int = 16,
) -> dict:
    """:func:`minor_loop_congruency` for the loop between every pair of ``nodes`` (ascending,
    inside ``(−saturation, saturation)``) with :func:`default_histories`; returns the largest
    violation and its loop, the mean violation over loops, the largest return gap, and the
    per-loop ``violation`` and ``height`` arrays (pairs in ``itertools.combinations`` order)."""
    x = np.asarray(nodes, dtype=float).reshape(-1)
    if x.size < 2 or not np.all(np.diff(x) > 0) or not np.all(np.isfinite(x)):
        raise ValueError("nodes must be at least 2 finite, strictly increasing inputs")
    viol, height, pairs, gap = [], [], [], 0.0
    for i in range(x.size):
        for j in range(i + 1, x.size):
            hist = default_histories(x[i], x[j], saturation, count)
            r = minor_loop_congruency(operator, x[i], x[j], hist, samples)
            viol.append(r["violation"])
            height.append(r["height"])
            pairs.append((float(x[i]), float(x[j])))
            gap = max(gap, r["return_gap"])
    v = np.asarray(viol)
    k = int(np.argmax(v))
    return {
        "violation": float(v[k]),
        "worst_loop": list(pairs[k]),
        "mean_violation": float(np.mean(v)),
        "return_gap": gap,
        "violations": v.tolist(),
        "heights": height,
    }
