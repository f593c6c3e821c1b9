"""The safeguarded Newton root finder of the compiled oscillator kernels (its one home).

Every event the play and continuous kernels locate is a sign change of a smooth function of
time inside a bracket the caller has already found: the wall hit ``q = wall`` and the extremum
``v = 0`` of the analytic motion inside the play, the reversal ``v = 0`` and the breakpoint
``q = bp`` on an RK8 step's own map, and the minimum of a velocity dip (``a = 0``, where no
derivative is at hand). One function locates them all; the caller passes the function of time
as a compiled function ``fn(x, args) -> (g, g')`` and its extra arguments as a tuple.

Plain reading::

    # on entry g(lo) < 0 <= g(hi) and lo <= x <= hi
    for _ in range(ROOT_MAX_ITER):
        g, dg = fn(x)
        if g == 0: return x
        if g < 0: lo = x  else: hi = x          # the bracket keeps the sign change
        xn = x - g / dg  (the midpoint if dg == 0 or xn leaves [lo, hi])
        if |xn - x| <= tol or hi - lo <= tol: return xn
        x = xn
    return x          # tol = ROOT_RTOL * max(1, scale)

A derivative of 0 turns every step into a bisection (the velocity-dip search passes ``g' = 0``).
:func:`find_root` and the kernels' root functions are inlined into their callers
(``inline="always"``), for the reasons given at :func:`oscillators.engines._dop853_kernel.rk8_step`.

Not here: the continuous kernel's ``_land`` (a step ending on a grid line of a tabulated Everett
function) is Newton without a bracket from a predicted time, which must report failure (the
input turns back first) rather than bisect; bracketing it would cost one more RK8 step per line.
"""

from __future__ import annotations

import numpy as np
from numba import njit

_EPS = float(np.finfo(np.float64).eps)

#: Convergence tolerance relative to ``max(1, scale)``, ``scale`` being the size of the clock
#: the root is added to (the event time ``t + τ``). Digits of ``τ`` below an ulp of that clock
#: are lost in the sum, and at convergence Newton's steps move by the rounding noise of ``g``
#: divided by ``g'``, a few ulps; 4ε stops there instead of bouncing in the noise until the
#: bracket closes. An event located to 4ε of the clock moves the event state by
#: ``|q'|·4ε·max(1, t)``, below the RK8 step's own error (~1e-13 per unit time).
ROOT_RTOL = 4.0 * _EPS

#: Iteration limit. A bracket no wider than ``max(1, scale)`` (every caller's bracket is at
#: most one integration step, ≤ 0.2) shrinks to ``ROOT_RTOL·max(1, scale)`` after
#: log2(1/ROOT_RTOL) = 50 bisections; the limit allows that many again for Newton steps that
#: are accepted but shrink the bracket less (in practice Newton converges in 3–6 iterations).
#: Reaching the limit returns the last iterate, which lies in the bracket.
ROOT_MAX_ITER = 100


@njit(cache=True)
def secant_start(lo, hi, g_lo, g_hi):
    """Start of :func:`find_root`: the secant through (lo, g_lo), (hi, g_hi) when it lies in
    (lo, hi] (``g_lo < 0 <= g_hi``), else the midpoint."""
    den = g_hi - g_lo
    x = lo + (hi - lo) * (-g_lo) / den if den > 0.0 else 0.5 * (lo + hi)
    if not (lo < x <= hi):
        x = 0.5 * (lo + hi)
    return x


@njit(cache=True, inline="always")
def find_root(fn, args, lo, hi, x, scale):
    """Root of ``g`` in [lo, hi] by safeguarded Newton (module docstring), from ``x``.

    ``fn(x, args)`` returns ``(g(x), g'(x))`` with ``g(lo) < 0 <= g(hi)`` (callers orient
    ``g``: a sign flip is exact, so it changes no bit of the iterates); ``scale`` is the size of
    the clock the root is added to (the tolerance is ``ROOT_RTOL·max(1, scale)``).
    """
    tol = ROOT_RTOL * max(1.0, scale)
    for _ in range(ROOT_MAX_ITER):
        g, dg = fn(x, args)
        if g == 0.0:
            return x
        if g < 0.0:
            lo = x
        else:
            hi = x
        xn = x - g / dg if dg != 0.0 else 0.5 * (lo + hi)
        if not (lo <= xn <= hi):
            xn = 0.5 * (lo + hi)
        if abs(xn - x) <= tol or hi - lo <= tol:
            return xn
        x = xn
    return x
