"""The periodic windows of a parameter sweep below the onset of a period-adding cascade.

A *period-adding cascade* (paper fig:bif_0: one spin dimer, C stepped down from above 9) is a
sequence of periodic windows whose periods change by a constant small step from one window to
the next while the parameter moves away from the cascade's onset, and grow without bound toward
the onset. Here, coming from large C, the system sits on the period-1 orbit without switching;
the onset is where it first leaves it (a grazing, C = 1/(2ζ) + β = 9), and below it the windows
of period ..., 31, 29, 27, ... follow (steps of −2).

:func:`period_adding` measures this on a sweep given as couplings in sweep order and the period
detected at each (``0``: no period up to the detector's limit, i.e. longer, or aperiodic):

- the onset: midway between the last value still on the period-1 orbit (counted from the start
  of the sweep) and the next one, ``nan`` if the sweep starts off it or never leaves it;
- the windows below the onset in sweep order: runs of successive values with one period, with
  their widths (the number of values); *wide* windows hold at least ``min_width`` values and a
  period > 1, *narrow* ones fewer (a window one grid value wide may be a grid accident);
- the steps: the differences between the periods of successive wide windows;
- whether the periods near the onset are long (some period of the first ``near`` values below
  it is unresolved or at least ``long_period``).

Whether that is a period-adding cascade (enough wide windows, steps all small and of one
sign, long periods at the onset) is a decision of the caller
(:func:`analysis.paper.verdicts.is_period_adding`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["PeriodAdding", "period_adding"]


@dataclass(frozen=True)
class PeriodAdding:
    """What :func:`period_adding` measured on one sweep.

    Attributes
    ----------
    onset:
        Midpoint between the last value on the period-1 orbit and the first one off it (``nan``
        without such a pair); known to ± half the grid step.
    no_switch_end:
        The last value of the sweep with period 1 (``nan`` if none).
    grid_step:
        ``|c[1] − c[0]|`` (``inf`` for fewer than two values).
    below:
        ``(coupling, period)`` from the first value off the period-1 orbit on, in sweep order.
    windows:
        ``(period, width)`` of the runs of one period in ``below``, in sweep order.
    wide, narrow:
        Periods (> 1) of the windows at least ``min_width`` values wide, and of the others.
    steps:
        ``wide[k+1] − wide[k]``.
    long_near_onset:
        A period of the first ``near`` values of ``below`` is unresolved (0) or
        ``>= long_period``.
    """

    onset: float
    no_switch_end: float
    grid_step: float
    below: tuple[tuple[float, int], ...]
    windows: tuple[tuple[int, int], ...]
    wide: tuple[int, ...]
    narrow: tuple[int, ...]
    steps: tuple[int, ...]
    long_near_onset: bool


def period_adding(
    couplings: Any,
    periods: Any,
    *,
    min_width: int = 2,
    near: int = 5,
    long_period: int = 20,
) -> PeriodAdding:
    """The onset and the periodic windows of a sweep (see the module docstring).

    ``couplings`` in sweep order and ``periods[i]`` the period (in forcing periods) detected at
    ``couplings[i]``, 0 where none was resolved.
    """
    cs = np.asarray(couplings, dtype=float)
    per = np.asarray(periods, dtype=int)
    if cs.shape != per.shape or cs.ndim != 1:
        raise ValueError(
            f"couplings and periods must be 1-D of one length, got {cs.shape} and {per.shape}"
        )
    off = per != 1
    first = int(np.argmax(off)) if np.any(off) else cs.size
    onset = 0.5 * (cs[first - 1] + cs[first]) if 0 < first < cs.size else float("nan")
    on_orbit = np.nonzero(per == 1)[0]
    below = tuple((float(c), int(p)) for c, p in zip(cs[first:], per[first:], strict=True))
    runs: list[list[int]] = []  # [period, number of successive values]
    for _, p in below:
        if runs and runs[-1][0] == p:
            runs[-1][1] += 1
        else:
            runs.append([p, 1])
    wide = tuple(p for p, width in runs if p > 1 and width >= min_width)
    return PeriodAdding(
        onset=float(onset),
        no_switch_end=float(cs[on_orbit[-1]]) if on_orbit.size else float("nan"),
        grid_step=float(abs(cs[1] - cs[0])) if cs.size > 1 else float("inf"),
        below=below,
        windows=tuple((p, width) for p, width in runs),
        wide=wide,
        narrow=tuple(p for p, width in runs if p > 1 and width < min_width),
        steps=tuple(int(d) for d in np.diff(wide)) if len(wide) > 1 else (),
        long_near_onset=any(p == 0 or p >= long_period for _, p in below[:near]),
    )
