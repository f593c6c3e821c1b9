"""Compiled kernels of the continuous engine (see :mod:`oscillators.engines.compiled_continuous`).

System (paper eq. eom_2)::

    q'' + 2ζ q' + q = cos(φ0 + Ω t) + C·y,   y = M[q](t)

for a Prandtl–Ishlinskii operator (``OP_PI``) or a continuous Preisach model (``OP_PREISACH``).
While ``q`` moves one way the output is a smooth function of ``q`` (a *branch*); the branch
ends at a reversal ``v = 0`` or at its breakpoint ``q = bp``.

Everything lives in flat arrays so that numba compiles one specialisation:

``par`` (float64)::

    0 ζ   1 Ω   2 C   3 φ0   4 h (RK8 step)   5 T = 2π/Ω   6 divergence bound   7 t0

``ist`` (int64)::

    0 direction d (+1/-1)   1 period index n   2 partner p (Preisach)   3 events since start
    4 free memory count (Preisach)   5 next sample index   6 events in ``ev``   7 record
    8 k (tangent columns, 0: off)   9 operator (OP_PI, OP_PREISACH)   10 Everett kind
    11 events at zero distance in a row   12 the branch began with a push (Preisach)
    13 the current step lies beyond the support of a tabulated Everett function (slope 0)

``st`` (float64)::

    0 τ (time in the period)   1 q   2 v   3 bp   4 u0 (branch start)
    5 y0 (PI: output at u0; Preisach: the base −1 + 2·prefix[p])   6 slope (PI)   7 m (Preisach)

Prandtl–Ishlinskii (``hw`` half-widths, ``wt`` weights, ``pos`` wagon positions, ``slv`` 1 for
a wagon dragged on this branch, ``free`` 1 for a memory direction still free since the last
start/set of the tangent flow). On a branch in direction ``d`` the dragged wagons follow
``w_i = q − d r_i``, the others are frozen; in plain Python::

    y(q) = y0 + slope·(q − u0),   slope = Σ_dragged a_i
    bp = nearest  w_i + d r_i  over the frozen wagons        (the next wall reached)

Continuous Preisach (``stack`` = ``[+inf, −inf, M1, m1, ...]`` up to the partner index ``p``,
the remembered extrema; ``prefix[i]`` the Everett prefix sums; ``dlo[i]``/``dhi[i]`` the
derivatives of ``2·term_i`` with respect to ``stack[i−1]``/``stack[i]``, term_i = ``E(stack[i],
stack[i−1])`` for even ``i`` (a maximum), ``−E(stack[i−1], stack[i])`` for odd ``i``). The moving
input ``q`` rises when ``p`` is odd (its partner is a minimum ``m``) and falls when ``p`` is
even::

    rising:  y(q) = −1 + 2 prefix[p] + 2 E(q, m)        falling: y(q) = −1 + 2 prefix[p] − 2 E(m, q)
    bp = stack[p − 1]   (reaching it wipes out stack[p − 1] and stack[p]:  p −= 2)
    reversal at u*: push  stack[p + 1] = u*,  p += 1,  one Everett evaluation for its term

with ``E`` = :func:`hysteresis.preisach._everett_kernels.everett_eval` (one call per
right-hand side; it returns the gradient as well). Only a tabulated C¹ Everett function
(``KIND_TABLE``) needs its grid lines landed on (below); the separable Gaussian table (kind 2,
bi-quintic) is C² across its lines, so a step across one errs by ``O(h⁴ J₃)`` with ``J₃`` the
jump of the interpolant's third derivative (``~h_cell³‖F⁽⁶⁾‖``, i.e. ~1e-4 of it), and it is
integrated as the analytic quadrature (kind 0) is.

Tangent flow: ``Y`` (3 + capacity, k): rows δq, δv, δφ (zero without the phase), then one row
per memory variable (wagon ``i``: row ``3 + i``; stack index ``i``: row ``i + 1``). On a branch
the memory rows are constant except dragged wagons (``δw = δq``); with ``F[0, j]`` the frozen
memory's force ``Σ ∂y/∂m_i δm_ij``, ``F[1, j]`` the partner's row (Preisach), ``F[2, j] = δφ_j``::

    δq' = δv,   δv' = −2ζ δv − δq − sin φ δφ + C (s(q) δq + F0 + g(q) F1)

with ``s = ∂y/∂u`` + the dragged weights and ``g`` the partner's moving-term derivative. Events
(saltations; the output is continuous so (δq, δv, δφ) pass unchanged): a wagon that becomes
dragged and a pushed extremum get ``δm := δq``; wiped-out rows are dropped.

Integration: fixed-step 8th-order Dormand–Prince (coefficients in
:mod:`oscillators.engines._dop853_kernel`), the tangent columns with the same stages. A step
whose end has ``d·v <= 0`` contains the reversal, one whose end has ``d·(q − bp) >= 0`` the
breakpoint; a dip of ``v`` to zero and back inside a step is caught with the cubic Hermite
interpolant of ``v`` (as in the play kernel). The event time is located by safeguarded Newton
on the step's own RK8 map from the step start (each iterate one RK8 step over ``τ``), so the
event state has full RK8 accuracy; then ``q := bp`` or ``v := 0`` exactly.

Status codes of :func:`run`: ``DONE``; ``GROW`` (a Preisach push may need more room: the Python
side enlarges ``stack``/``Y`` and calls again); ``EVENTS_FULL`` (``ev`` full: drained and called
again); ``DIVERGED`` (``q``/``v`` non-finite or above the bound; ``st`` holds the bad values);
``STUCK`` (events at zero distance without progress).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from hysteresis.preisach._everett_kernels import everett_eval
from oscillators.engines import _dop853_kernel as _dop
from oscillators.engines._play_kernels import _hermite_extrema

_N_STAGES = _dop.N_STAGES
RK_A = np.ascontiguousarray(_dop.A, dtype=np.float64)
RK_B = np.ascontiguousarray(_dop.B, dtype=np.float64)
RK_C = np.ascontiguousarray(_dop.C, dtype=np.float64)

OP_PI = 0
OP_PREISACH = 1
#: ``CompiledEverett.kind`` of a tabulated (C¹ bicubic Hermite) Everett function
KIND_TABLE = 1

DONE = 0
GROW = 1
EVENTS_FULL = 2
DIVERGED = 3
STUCK = 4

_EPS = 2.220446049250313e-16
#: a grid line of a tabulated Everett function closer than this (in cells) ahead counts as
#: passed: a step that crosses an interior (C¹) line at a distance τ from its start errs by
#: O(h·J·τ²) with J the jump of the second derivative there (negligible for 1e-3 cell); the
#: support bounds (slope jumps) are landed on to rounding
_LINE_SKIP = 1e-3
#: events at zero distance in a row before STUCK
_MAX_STUCK = 50


# --------------------------------------------------------------------------------------------
# the operator on the current branch
# --------------------------------------------------------------------------------------------
@njit(cache=True)
def _operator(ist, st, ep, et, q):
    """(y, s, g) at input q: output, ∂y/∂u + dragged weights, partner's derivative."""
    if ist[9] == OP_PI:
        return st[5] + st[6] * (q - st[4]), st[6], 0.0
    m = st[7]
    u = q
    outside = ist[13] != 0
    if ist[10] == KIND_TABLE:
        # the step's side of the support bounds decides the slope (module docstring); E
        # itself is clipped there anyway
        u = min(max(q, ep[0]), ep[1])
    if ist[0] > 0:
        e, ea, eb = everett_eval(ist[10], ep, et, u, m)
        return st[5] + 2.0 * e, 0.0 if outside else 2.0 * ea, 2.0 * eb
    e, ea, eb = everett_eval(ist[10], ep, et, m, u)
    return st[5] - 2.0 * e, 0.0 if outside else -2.0 * eb, -2.0 * ea


@njit(cache=True)
def _rhs(par, ist, st, F, ep, et, t, y, dy, k):
    """Right-hand side of (q, v) and of k tangent columns (δq, δv) at time t (in the period)."""
    zeta = par[0]
    c = par[2]
    q = y[0]
    v = y[1]
    ph = par[3] + par[1] * t
    out, s, g = _operator(ist, st, ep, et, q)
    dy[0] = v
    dy[1] = -2.0 * zeta * v - q + math.cos(ph) + c * out
    if k > 0:
        sph = math.sin(ph)
        cs = c * s - 1.0
        cg = c * g
        for j in range(k):
            dq = y[2 + 2 * j]
            dv = y[3 + 2 * j]
            dy[2 + 2 * j] = dv
            dy[3 + 2 * j] = -2.0 * zeta * dv + cs * dq + c * F[0, j] + cg * F[1, j] - sph * F[2, j]


@njit(cache=True)
def _rk8(par, ist, st, F, ep, et, t, y, h, out, K, tmp, k):
    """One 8th-order Dormand–Prince step from (t, y) over h into ``out`` (2 + 2k entries)."""
    _stages(par, ist, st, F, ep, et, t, y, h, out, K, tmp, k, 0)


@njit(cache=True)
def _stages(par, ist, st, F, ep, et, t, y, h, out, K, tmp, k, first):
    """The RK8 step with stages ``first``.. evaluated (``first = 1``: ``K[0] = f(t, y)`` is
    already there)."""
    n = 2 + 2 * k
    for i in range(first, _N_STAGES):
        for r in range(n):
            acc = 0.0
            for j in range(i):
                acc += RK_A[i, j] * K[j, r]
            tmp[r] = y[r] + h * acc
        _rhs(par, ist, st, F, ep, et, t + RK_C[i] * h, tmp, K[i], k)
    for r in range(n):
        acc = 0.0
        for i in range(_N_STAGES):
            acc += RK_B[i] * K[i, r]
        out[r] = y[r] + h * acc


# --------------------------------------------------------------------------------------------
# branches
# --------------------------------------------------------------------------------------------
@njit(cache=True)
def pi_branch(ist, st, hw, wt, pos, slv, Y, F):
    """Branch of a Prandtl–Ishlinskii operator in direction d from q: dragged wagons (on the
    wall they push, within 8 ulps as ``hysteresis.play._touches_wall``), slope, output, the
    next wall ahead of a frozen wagon, the frozen force of each tangent column; dragged rows of
    ``Y`` := δq."""
    d = ist[0]
    u = st[1]
    slope = 0.0
    y0 = 0.0
    bp = d * np.inf
    for i in range(hw.size):
        r = hw[i]
        w = pos[i]
        tol = 8.0 * _EPS * max(abs(w), abs(u), r, 1.0)
        if d * (u - w) >= r - tol:
            slv[i] = 1
            slope += wt[i]
        else:
            slv[i] = 0
            ahead = w + d * r
            if (d > 0 and ahead < bp) or (d < 0 and ahead > bp):
                bp = ahead
        y0 += wt[i] * w
    st[3] = bp
    st[4] = u
    st[5] = y0
    st[6] = slope
    k = ist[8]
    for j in range(k):
        f = 0.0
        for i in range(hw.size):
            if slv[i]:
                Y[3 + i, j] = Y[0, j]
            else:
                f += wt[i] * Y[3 + i, j]
        F[0, j] = f
        F[1, j] = 0.0
        F[2, j] = Y[2, j]


@njit(cache=True)
def pi_sync(ist, st, hw, pos, slv):
    """Dragged wagons to the current input, ``w_i = q − d r_i``."""
    d = ist[0]
    for i in range(hw.size):
        if slv[i]:
            pos[i] = st[1] - d * hw[i]


@njit(cache=True)
def preisach_term(ist, ep, et, stack, prefix, dlo, dhi, i):
    """Fix the Everett term of stack entry i >= 2 (prefix sum and its two derivatives)."""
    if i % 2 == 0:
        e, ea, eb = everett_eval(ist[10], ep, et, stack[i], stack[i - 1])
        prefix[i] = prefix[i - 1] + e
        dhi[i] = 2.0 * ea
        dlo[i] = 2.0 * eb
    else:
        e, ea, eb = everett_eval(ist[10], ep, et, stack[i - 1], stack[i])
        prefix[i] = prefix[i - 1] - e
        dlo[i] = -2.0 * ea
        dhi[i] = -2.0 * eb


@njit(cache=True)
def preisach_init(ist, ep, et, stack, prefix, dlo, dhi, p):
    """Prefix sums and derivatives of the entries 2..p (sentinels: 0)."""
    prefix[0] = 0.0
    prefix[1] = 0.0
    dlo[0] = dlo[1] = dhi[0] = dhi[1] = 0.0
    for i in range(2, p + 1):
        preisach_term(ist, ep, et, stack, prefix, dlo, dhi, i)


@njit(cache=True)
def preisach_branch(ist, st, stack, prefix, dlo, dhi, Y, F):
    """Branch of a continuous Preisach model from q with partner p (direction from p's
    parity): partner value, breakpoint, base, the frozen force of each tangent column."""
    p = ist[2]
    ist[0] = 1 if p % 2 == 1 else -1
    st[3] = stack[p - 1]
    st[5] = -1.0 + 2.0 * prefix[p]
    st[6] = 0.0
    st[7] = stack[p]
    k = ist[8]
    for j in range(k):
        f = 0.0
        for i in range(2, p + 1):
            g0 = dhi[i]
            if i + 1 <= p:
                g0 += dlo[i + 1]
            f += g0 * Y[i + 1, j]
        F[0, j] = f
        F[1, j] = Y[p + 1, j] if p >= 2 else 0.0
        F[2, j] = Y[2, j]


@njit(cache=True)
def output_now(ist, st, ep, et):
    """The operator output at the current q."""
    return _operator(ist, st, ep, et, st[1])[0]


# --------------------------------------------------------------------------------------------
# events
# --------------------------------------------------------------------------------------------
@njit(cache=True)
def _event(par, ist, st, kind, hw, wt, pos, slv, free, stack, prefix, dlo, dhi, ep, et, Y, F, ev):
    """Apply a breakpoint (kind +1) or reversal (kind −1) at the current (q, v)."""
    k = ist[8]
    q = st[1]
    if ist[9] == OP_PI:
        pi_sync(ist, st, hw, pos, slv)
        for i in range(hw.size):  # the operator's own update (apply): clamp to the finger
            lo = q - hw[i]
            hi = q + hw[i]
            if pos[i] < lo:
                pos[i] = lo
            elif pos[i] > hi:
                pos[i] = hi
        if kind < 0:
            ist[0] = -ist[0]
        n = hw.size
        old = np.empty(n, dtype=np.int8)
        for i in range(n):
            old[i] = slv[i]
        pi_branch(ist, st, hw, wt, pos, slv, Y, F)
        for i in range(n):
            if slv[i] and not old[i]:
                free[i] = 0  # V_out: δw := δq (done in pi_branch)
    else:
        if kind > 0:
            ist[2] -= 2  # wipe-out of stack[p-1], stack[p]
            ist[12] = 0
            if ist[4] > ist[2] - 1:
                ist[4] = ist[2] - 1
        else:
            p = ist[2] + 1
            stack[p] = q
            ist[2] = p
            preisach_term(ist, ep, et, stack, prefix, dlo, dhi, p)
            for j in range(k):
                Y[p + 1, j] = Y[0, j]  # a pushed extremum: δm := δq
            ist[12] = 1
        st[4] = q  # the branch start (u0)
        preisach_branch(ist, st, stack, prefix, dlo, dhi, Y, F)
    ist[3] += 1
    if ist[7]:
        i = ist[6]
        n, tau = ist[1], st[0]
        ev[i, 0] = par[7] + n * par[5] + tau
        ev[i, 1] = q
        ev[i, 2] = st[2]
        ev[i, 3] = kind
        ev[i, 4] = output_now(ist, st, ep, et)
        ist[6] = i + 1


@njit(cache=True)
def _locate(par, ist, st, F, ep, et, t, y, lo, hi, which, work):
    """Event time in (lo, hi] of the step from (t, y): which 0 the reversal (root of −d·v),
    1 the breakpoint (root of d·(q − bp)); safeguarded Newton, each iterate one RK8 step over τ
    from the step start (state only)."""
    d = ist[0]
    bp = st[3]
    z = work[0, :2]
    dz = work[1, :2]
    tmp = work[2, :2]
    K = work[4 : 4 + _N_STAGES, :2]
    y2 = work[3, :2]
    y2[0] = y[0]
    y2[1] = y[1]
    g_lo = -d * y[1] if which == 0 else d * (y[0] - bp)
    _rk8(par, ist, st, F, ep, et, t, y2, hi, z, K, tmp, 0)
    g_hi = -d * z[1] if which == 0 else d * (z[0] - bp)
    den = g_hi - g_lo
    tau = lo + (hi - lo) * (-g_lo) / den if den > 0.0 else 0.5 * (lo + hi)
    if not (lo < tau <= hi):
        tau = 0.5 * (lo + hi)
    for _ in range(80):
        _rk8(par, ist, st, F, ep, et, t, y2, tau, z, K, tmp, 0)
        if which == 0:
            _rhs(par, ist, st, F, ep, et, t + tau, z, dz, 0)
            g = -d * z[1]
            dg = -d * dz[1]
        else:
            g = d * (z[0] - bp)
            dg = d * z[1]
        if g < 0.0:
            lo = tau
        else:
            hi = tau
        tn = tau - g / dg if dg != 0.0 else 0.5 * (lo + hi)
        if not (lo <= tn <= hi):
            tn = 0.5 * (lo + hi)
        if abs(tn - tau) <= 4.0 * _EPS * max(hi, 1e-300) or hi - lo <= 4.0 * _EPS * hi:
            return tn
        tau = tn
    return tau


@njit(cache=True)
def _to_grid_line(ep, et, d, q, v, a):
    """(predicted time, position) of the next line ``lower + i·h_cell`` of a tabulated
    Everett function ahead of the moving input: there its second derivatives jump (and at the
    support bounds its first), so an RK8 step across a line loses order — a step that stages
    at a distance τ from a slope jump J errs by O(h·J·τ). Time from ``q + v τ + a τ²/2``
    (``inf`` if not reached); lines within ``_LINE_SKIP·h_cell`` ahead count as passed (a
    bound landed on to rounding is always passed)."""
    lower = ep[0]
    upper = ep[1]
    cell = (upper - lower) / (et.shape[0] - 1)
    x = (q - lower) / cell
    n = et.shape[0] - 1
    if d > 0:
        i = max(math.floor(x + _LINE_SKIP) + 1.0, 0.0)  # from below the support: its bound
        if i > n:
            return np.inf, np.inf
    else:
        i = min(math.ceil(x - _LINE_SKIP) - 1.0, float(n))
        if i < 0.0:
            return np.inf, np.inf
    line = lower + i * cell
    dist = d * (line - q)
    s = d * v
    al = d * a
    disc = s * s + 2.0 * al * dist
    if disc < 0.0:
        return np.inf, line
    den = s + math.sqrt(disc)
    if den <= 0.0:
        return np.inf, line
    return 2.0 * dist / den, line


@njit(cache=True)
def _land(par, ist, st, F, ep, et, t, y, tau, line, work):
    """Time at which the step from (t, y) reaches ``q = line``: Newton on the state-only RK8
    map from the guess ``tau`` (converges to rounding in 2–3 iterations from the predictor);
    −1 if it does not (the input turns back first)."""
    d = ist[0]
    z = work[0, :2]
    tmp = work[2, :2]
    K = work[4 : 4 + _N_STAGES, :2]
    y2 = work[3, :2]
    y2[0] = y[0]
    y2[1] = y[1]
    tol = 4.0 * _EPS * max(1.0, abs(line))
    for _ in range(8):
        _rk8(par, ist, st, F, ep, et, t, y2, tau, z, K, tmp, 0)
        g = d * (z[0] - line)
        dg = d * z[1]
        if dg <= 0.0:
            return -1.0
        step = g / dg
        tau -= step
        if not tau > 0.0:
            return -1.0
        if abs(g) <= tol or abs(step) <= 4.0 * _EPS * tau:
            return tau
    return -1.0


@njit(cache=True)
def _add_time(par, ist, st, h):
    st[0] += h
    if st[0] >= par[5]:
        st[0] -= par[5]
        ist[1] += 1
        if st[0] >= par[5] or st[0] < 0.0:  # rounding
            extra = math.floor(st[0] / par[5])
            ist[1] += int(extra)
            st[0] -= extra * par[5]
            if st[0] < 0.0:
                st[0] = 0.0


@njit(cache=True)
def _load(st, Y, y, k):
    y[0] = st[1]
    y[1] = st[2]
    for j in range(k):
        y[2 + 2 * j] = Y[0, j]
        y[3 + 2 * j] = Y[1, j]


@njit(cache=True)
def _store(st, Y, y, k):
    st[1] = y[0]
    st[2] = y[1]
    for j in range(k):
        Y[0, j] = y[2 + 2 * j]
        Y[1, j] = y[3 + 2 * j]


@njit(cache=True)
def _sync(ist, st, hw, pos, slv, Y):
    """Dragged wagons and their rows follow q (PI)."""
    if ist[9] == OP_PI:
        pi_sync(ist, st, hw, pos, slv)
        for i in range(hw.size):
            if slv[i]:
                for j in range(ist[8]):
                    Y[3 + i, j] = Y[0, j]


@njit(cache=True)
def _to_target(
    par, ist, st, nt, taut, hw, wt, pos, slv, free, stack, prefix, dlo, dhi, ep, et, Y, F, ev, work
):
    """Integrate to (period nt, time taut), handling every event on the way."""
    k = ist[8]
    n = 2 + 2 * k
    y = work[0, :n]
    y1 = work[1, :n]
    dy = work[2, :n]
    tmp = work[3, :n]
    K = work[4 : 4 + _N_STAGES, :n]
    loc = work[4 + _N_STAGES :, :]
    h_step = par[4]
    bound = par[6]
    _load(st, Y, y, k)
    while True:
        rem = (nt - ist[1]) * par[5] + (taut - st[0])
        if rem <= 0.0:
            break
        if ist[9] == OP_PREISACH and ist[2] + 3 >= stack.size:
            _store(st, Y, y, k)
            return GROW
        if ist[7] and ist[6] >= ev.shape[0]:
            _store(st, Y, y, k)
            return EVENTS_FULL
        last = rem <= h_step
        h = rem if last else h_step
        t = st[0]
        d = ist[0]
        land = np.inf
        if ist[9] == OP_PREISACH and ist[10] == KIND_TABLE:
            # a C¹ table: end the step exactly on the next grid line of the moving input. At
            # the support bounds the slope jumps: the step takes it on the side it moves into
            # (its start nudged forward), in every stage (stage states may overshoot its end)
            ahead = y[0] + d * 1e-12 * max(1.0, abs(y[0]))
            ist[13] = 0 if ep[0] <= ahead <= ep[1] else 1
            _rhs(par, ist, st, F, ep, et, t, y, K[0], k)
            tp, line = _to_grid_line(ep, et, d, y[0], y[1], K[0, 1])
            if tp < h:
                if line == ep[0] or line == ep[1]:
                    # a support bound (the slope jumps): land on it exactly
                    tl = _land(par, ist, st, F, ep, et, t, y, tp, line, loc)
                    if 0.0 < tl < h:
                        h = tl
                        last = False
                        land = line
                else:
                    # an interior line (E is C¹ there): ending the step near it suffices
                    h = tp
                    last = False
            _stages(par, ist, st, F, ep, et, t, y, h, y1, K, tmp, k, 1)
        else:
            _rk8(par, ist, st, F, ep, et, t, y, h, y1, K, tmp, k)
        if not (abs(y1[0]) <= bound and abs(y1[1]) <= bound):
            st[1] = y1[0]
            st[2] = y1[1]
            return DIVERGED
        kind = 0
        tau = h
        if d * y1[1] <= 0.0:
            kind = -1
        else:
            # a dip of v to zero and back within the step: cubic Hermite of d·v (a = v')
            _rhs(par, ist, st, F, ep, et, t + h, y1, dy, 0)
            vmax, vmin = _hermite_extrema(d * y[1], d * K[0, 1], d * y1[1], d * dy[1], h)
            if vmin < 0.0:
                # locate the minimum of the true velocity (sign of d·a) and test v there
                lo_s = 0.0
                hi_s = h
                z = loc[0, :2]
                dz = loc[1, :2]
                for _ in range(60):
                    mid = 0.5 * (lo_s + hi_s)
                    _rk8(par, ist, st, F, ep, et, t, y[:2], mid, z, loc[4:16, :2], loc[2, :2], 0)
                    _rhs(par, ist, st, F, ep, et, t + mid, z, dz, 0)
                    if d * dz[1] < 0.0:
                        lo_s = mid
                    else:
                        hi_s = mid
                mid = 0.5 * (lo_s + hi_s)
                _rk8(par, ist, st, F, ep, et, t, y[:2], mid, z, loc[4:16, :2], loc[2, :2], 0)
                if d * z[1] <= 0.0:
                    kind = -1
                    tau = mid
        if kind == -1:
            tau = _locate(par, ist, st, F, ep, et, t, y, 0.0, tau, 0, loc)
            # the breakpoint may come first on the way to the reversal
            z = loc[0, :2]
            _rk8(par, ist, st, F, ep, et, t, y[:2], tau, z, loc[4:16, :2], loc[2, :2], 0)
            if d * (z[0] - st[3]) >= 0.0:
                kind = 1
                tau = _locate(par, ist, st, F, ep, et, t, y, 0.0, tau, 1, loc)
        elif d * (y1[0] - st[3]) >= 0.0:
            kind = 1
            tau = _locate(par, ist, st, F, ep, et, t, y, 0.0, h, 1, loc)
        if kind == 0:
            for r in range(n):
                y[r] = y1[r]
            if land != np.inf:
                y[0] = land  # on the grid line (Newton-located to rounding)
            if last:
                ist[1] = nt
                st[0] = taut
            else:
                _add_time(par, ist, st, h)
            continue
        _rk8(par, ist, st, F, ep, et, t, y, tau, y1, K, tmp, k)
        for r in range(n):
            y[r] = y1[r]
        _add_time(par, ist, st, tau)
        if kind > 0:
            y[0] = st[3]  # q := bp exactly
        else:
            y[1] = 0.0  # v := 0 exactly
        _store(st, Y, y, k)
        _sync(ist, st, hw, pos, slv, Y)
        _event(
            par, ist, st, kind, hw, wt, pos, slv, free, stack, prefix, dlo, dhi, ep, et, Y, F, ev
        )
        ist[11] = ist[11] + 1 if tau == 0.0 else 0
        if ist[11] > _MAX_STUCK:
            return STUCK
        _load(st, Y, y, k)
    _store(st, Y, y, k)
    _sync(ist, st, hw, pos, slv, Y)
    return DONE


@njit(cache=True)
def run(
    par, ist, st, nts, tauts, out, hw, wt, pos, slv, free, stack, prefix, dlo, dhi, ep, et, Y, F,
    ev, work,
):  # fmt: skip
    """Advance through the targets ``(nts[i], tauts[i])`` from sample ``ist[5]`` on, writing
    ``(q, v, M)`` into ``out[i]``; returns a status code (module docstring)."""
    i = ist[5]
    while i < nts.size:
        status = _to_target(
            par, ist, st, nts[i], tauts[i], hw, wt, pos, slv, free, stack, prefix, dlo, dhi,
            ep, et, Y, F, ev, work,
        )  # fmt: skip
        if status != DONE:
            return status
        out[i, 0] = st[1]
        out[i, 1] = st[2]
        out[i, 2] = output_now(ist, st, ep, et)
        i += 1
        ist[5] = i
    return DONE


def make_work(k: int) -> np.ndarray:
    """Scratch space of :func:`run` with k tangent columns (the last rows: event location)."""
    return np.zeros((2 * (4 + _N_STAGES), max(2 + 2 * k, 2)))
