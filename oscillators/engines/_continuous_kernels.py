"""Compiled kernels of the continuous engine (see :mod:`oscillators.engines.compiled_continuous`).

System (paper eq. eom_2)::

    q'' + 2ζ q' + q = cos(φ0 + Ω t) + C·y,   y = M[q](t)

for a Prandtl–Ishlinskii operator (``OP_PI``; its plays may carry the erf shape, so that a sum
of plays, Prandtl–Ishlinskii operators and erf plays is one ``OP_PI``) or a continuous Preisach
model (``OP_PREISACH``).
While ``q`` moves one way the output is a smooth function of ``q`` (a *branch*); the branch
ends at a reversal ``v = 0`` or at its breakpoint ``q = bp``.

Everything lives in flat arrays so that numba compiles one specialisation; their layouts are
the named index constants below (one definition each; the Python side builds ``par`` with
:func:`make_parameters`):

``par`` (float64): ``P_ZETA`` ζ, ``P_OMEGA`` Ω, ``P_C`` C, ``P_PHI0`` φ0, ``P_H`` the RK8 step,
``P_PERIOD`` T = 2π/Ω, ``P_BOUND`` the divergence bound, ``P_T0`` the start time.

``ist`` (int64): ``I_DIR`` direction d (+1/-1), ``I_PERIOD`` period index n, ``I_PARTNER``
partner p (Preisach), ``I_EVENTS`` events since start, ``I_FREE`` free memory count (Preisach),
``I_SAMPLE`` next sample index, ``I_NEV`` events in ``ev``, ``I_RECORD`` record events,
``I_K`` k (tangent columns, 0: off), ``I_OP`` operator (``OP_PI``, ``OP_PREISACH``),
``I_EVERETT`` Everett kind, ``I_STUCK`` events at zero distance in a row, ``I_PUSHED`` the
branch began with a push (Preisach), ``I_OUTSIDE`` the current step lies beyond the support of
a tabulated Everett function (slope 0).

``st`` (float64): ``S_TAU`` τ (time in the period), ``S_Q`` q, ``S_V`` v, ``S_BP`` bp,
``S_U0`` u0 (branch start), ``S_Y0`` y0 (PI: output at u0; Preisach: the base
−1 + 2·prefix[p]), ``S_SLOPE`` slope (PI), ``S_M`` m (Preisach).

Prandtl–Ishlinskii (``hw`` half-widths, ``wt`` weights, ``pos`` wagon positions, ``slv`` 1 for
a wagon dragged on this branch, ``free`` 1 for a memory direction still free since the last
start/set of the tangent flow). On a branch in direction ``d`` the dragged wagons follow
``w_i = q − d r_i``, the others are frozen; in plain Python::

    y(q) = y0 + slope·(q − u0),   slope = Σ_dragged a_i
    (+ Σ_dragged erf plays a_i·erf((q − d r_i)/(√2 R_i)), their slopes added to s)
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

Integration: fixed-step 8th-order Dormand–Prince (the one RK8 step,
:func:`oscillators.engines._dop853_kernel.rk8_step`), the tangent columns with the same
stages. A step whose end has ``d·v <= 0`` contains the reversal, one whose end has
``d·(q − bp) >= 0`` the breakpoint; a dip of ``v`` to zero and back inside a step is caught
with the cubic Hermite interpolant of ``v`` (as in the play kernel). The event time is located
by the safeguarded Newton root finder (:func:`oscillators.engines._roots.find_root`) on the
step's own RK8 map from the step start (each iterate one RK8 step over ``τ``), so the event
state has full RK8 accuracy; then ``q := bp`` or ``v := 0`` exactly.

Composites with relays (PI branch + ``rel``): while no wagon is dragged the system is the
relay kernel's linear one with constant forcing, and :func:`_frozen_stretch` hops in closed
form from event to event (:mod:`oscillators.engines._frozen_hops`: the relay kernel's ``hop``,
the play walls as thresholds, every turning point an event, the tangent columns by ``Φ(h)``);
on a pushed branch without tangent columns one relay threshold after the other is landed on
by the branch's degree-6 Taylor polynomial in a lean loop
(:func:`oscillators.engines._relay_landings.pushed_stretch`), the RK8 landing
:func:`_relay_hop` being the fallback (hops beyond ``0.02/ρ_eff``, and always with the tangent on).

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
from oscillators.engines import _frozen_hops as _fh
from oscillators.engines import _relay_landings as _rl
from oscillators.engines._continuous_layout import (
    EVENT_SWITCH,
    I_DIR,
    I_EVENTS,
    I_EVERETT,
    I_FREE,
    I_K,
    I_NEV,
    I_OP,
    I_OUTSIDE,
    I_PARTNER,
    I_PERIOD,
    I_PUSHED,
    I_RECORD,
    I_RPTR,
    I_SAMPLE,
    I_STUCK,
    P_BOUND,
    P_C,
    P_H,
    P_OMEGA,
    P_PERIOD,
    P_PHI0,
    P_T0,
    P_ZETA,
    S_BP,
    S_CBP,
    S_M,
    S_Q,
    S_RBP,
    S_RCOMP,
    S_RELAY,
    S_SLOPE,
    S_TAU,
    S_U0,
    S_V,
    S_Y0,
)
from oscillators.engines._play_kernels import _hermite_extrema
from oscillators.engines._relay_kernels import hop_coefficients
from oscillators.engines._relay_landings import (
    add_time,
    merge_breakpoints,
    nearest_breakpoint,
    relay_switch,
)
from oscillators.engines._roots import find_root, secant_start

_N_STAGES = _dop.N_STAGES

OP_PI = 0
OP_PREISACH = 1
#: ``CompiledEverett.kind`` of a tabulated (C¹ bicubic Hermite) Everett function
KIND_TABLE = 1


DONE = 0
GROW = 1
EVENTS_FULL = 2
DIVERGED = 3
STUCK = 4
GRAZING = 5
#: internal (:func:`_frozen_stretch`): a degenerate turning point the closed-form hop leaves
#: to one RK8 step
_UNDECIDED = 6

_EPS = 2.220446049250313e-16
#: d/dz erf(z) = (2/√π) exp(−z²)
_TWO_OVER_SQRT_PI = 2.0 / math.sqrt(math.pi)
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
@njit(cache=True, inline="always")
def _operator(ist, st, ep, et, q):
    """(y, s, g) at input q: output, ∂y/∂u + dragged weights, partner's derivative."""
    if ist[I_OP] == OP_PI:
        y = st[S_Y0] + st[S_SLOPE] * (q - st[S_U0])
        s = st[S_SLOPE]
        # the dragged erf-shaped plays (pi_branch lists them in ep: weight, d·r, R)
        for j in range(int(ep[0])):
            a = ep[1 + 3 * j]
            z = (q - ep[2 + 3 * j]) * ep[3 + 3 * j]
            y += a * math.erf(z)
            s += a * ep[3 + 3 * j] * _TWO_OVER_SQRT_PI * math.exp(-z * z)
        return y + (st[S_RELAY] + st[S_RCOMP]), s, 0.0
    m = st[S_M]
    u = q
    outside = ist[I_OUTSIDE] != 0
    if ist[I_EVERETT] == KIND_TABLE:
        # the step's side of the support bounds decides the slope (module docstring); E
        # itself is clipped there anyway
        u = min(max(q, ep[0]), ep[1])
    if ist[I_DIR] > 0:
        e, ea, eb = everett_eval(ist[I_EVERETT], ep, et, u, m)
        return (
            st[S_Y0] + 2.0 * e + (st[S_RELAY] + st[S_RCOMP]),
            0.0 if outside else 2.0 * ea,
            2.0 * eb,
        )
    e, ea, eb = everett_eval(ist[I_EVERETT], ep, et, m, u)
    return (
        st[S_Y0] - 2.0 * e + (st[S_RELAY] + st[S_RCOMP]),
        0.0 if outside else -2.0 * eb,
        -2.0 * ea,
    )


@njit(cache=True, inline="always")
def _rhs(par, ist, st, F, ep, et, t, y, dy, k):
    """Right-hand side of (q, v) and of k tangent columns (δq, δv) at time t (in the period)."""
    zeta = par[P_ZETA]
    c = par[P_C]
    q = y[0]
    v = y[1]
    ph = par[P_PHI0] + par[P_OMEGA] * t
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
    """The RK8 step (:func:`oscillators.engines._dop853_kernel.rk8_step`, written around its
    stage and end sums) with stages ``first``.. evaluated (``first = 1``: ``K[0] = f(t, y)`` is
    already there)."""
    n = 2 + 2 * k
    if first == 0:
        _rhs(par, ist, st, F, ep, et, t, y, K[0], k)
    for i in range(1, _N_STAGES):
        ti = _dop.rk8_stage(i, t, y, h, K, tmp, n)
        _rhs(par, ist, st, F, ep, et, ti, tmp, K[i], k)
    _dop.rk8_end(y, h, K, out, n)


# --------------------------------------------------------------------------------------------
# branches
# --------------------------------------------------------------------------------------------
@njit(cache=True)
def pi_branch(ist, st, hw, wt, pos, slv, Y, F, ep, et):
    """Branch of a Prandtl–Ishlinskii operator in direction d from q: dragged wagons (on the
    wall they push, within 8 ulps as ``hysteresis.play._touches_wall``), slope, output, the
    next wall ahead of a frozen wagon, the frozen force of each tangent column; dragged rows of
    ``Y`` := δq. Shaped plays (``et[0, 0, i] = 1/(√2 R_i) > 0``: output ``erf(w_i/(√2 R_i))``,
    a sum of plays and erf plays): a frozen one adds its constant output and ``a f'(w) δw`` to
    the frozen force; the dragged ones are listed in ``ep`` (count, then weight, ``d·r`` and
    ``1/(√2 R)`` each) for :func:`_operator`, which evaluates them at q."""
    d = ist[I_DIR]
    u = st[S_Q]
    slope = 0.0
    y0 = 0.0
    bp = d * np.inf
    n_shaped = 0
    for i in range(hw.size):
        r = hw[i]
        w = pos[i]
        scale = et[0, 0, i]
        tol = 8.0 * _EPS * max(abs(w), abs(u), r, 1.0)
        if d * (u - w) >= r - tol:
            slv[i] = 1
            if scale == 0.0:
                slope += wt[i]
                y0 += wt[i] * w
            else:
                ep[1 + 3 * n_shaped] = wt[i]
                ep[2 + 3 * n_shaped] = d * r
                ep[3 + 3 * n_shaped] = scale
                n_shaped += 1
        else:
            slv[i] = 0
            ahead = w + d * r
            if (d > 0 and ahead < bp) or (d < 0 and ahead > bp):
                bp = ahead
            y0 += wt[i] * (w if scale == 0.0 else math.erf(w * scale))
    ep[0] = n_shaped
    st[S_BP] = bp
    st[S_U0] = u
    st[S_Y0] = y0
    st[S_SLOPE] = slope
    k = ist[I_K]
    for j in range(k):
        f = 0.0
        for i in range(hw.size):
            if slv[i]:
                Y[3 + i, j] = Y[0, j]
            else:
                scale = et[0, 0, i]
                if scale == 0.0:
                    f += wt[i] * Y[3 + i, j]
                else:
                    z = pos[i] * scale
                    f += wt[i] * scale * _TWO_OVER_SQRT_PI * math.exp(-z * z) * Y[3 + i, j]
        F[0, j] = f
        F[1, j] = 0.0
        F[2, j] = Y[2, j]


@njit(cache=True)
def pi_sync(ist, st, hw, pos, slv):
    """Dragged wagons to the current input, ``w_i = q − d r_i``."""
    d = ist[I_DIR]
    for i in range(hw.size):
        if slv[i]:
            pos[i] = st[S_Q] - d * hw[i]


@njit(cache=True)
def preisach_term(ist, ep, et, stack, prefix, dlo, dhi, i):
    """Fix the Everett term of stack entry i >= 2 (prefix sum and its two derivatives)."""
    if i % 2 == 0:
        e, ea, eb = everett_eval(ist[I_EVERETT], ep, et, stack[i], stack[i - 1])
        prefix[i] = prefix[i - 1] + e
        dhi[i] = 2.0 * ea
        dlo[i] = 2.0 * eb
    else:
        e, ea, eb = everett_eval(ist[I_EVERETT], ep, et, stack[i - 1], stack[i])
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
    p = ist[I_PARTNER]
    ist[I_DIR] = 1 if p % 2 == 1 else -1
    st[S_BP] = stack[p - 1]
    st[S_Y0] = -1.0 + 2.0 * prefix[p]
    st[S_SLOPE] = 0.0
    st[S_M] = stack[p]
    k = ist[I_K]
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
    return _operator(ist, st, ep, et, st[S_Q])[0]


# --------------------------------------------------------------------------------------------
# events
# --------------------------------------------------------------------------------------------
@njit(cache=True)
def _event(
    par, ist, st, kind, hw, wt, pos, slv, free, stack, prefix, dlo, dhi, ep, et, Y, F, ev, rel,
    rord,
):  # fmt: skip
    """Apply a breakpoint (kind +1: a wall, a wipe-out, relays switching, or several at one
    input) or a reversal (kind −1) at the current (q, v); False at a grazing relay switch."""
    k = ist[I_K]
    q = st[S_Q]
    jump = 0.0
    if kind > 0 and rel.shape[0] > 0 and st[S_BP] == st[S_RBP]:
        ok, jump = relay_switch(par, ist, st, rel, rord, Y)
        if not ok:
            return False
        kind = EVENT_SWITCH
        if st[S_BP] != st[S_CBP]:  # the continuous branch goes on
            nearest_breakpoint(ist, st, rel, rord)
            _record_event(par, ist, st, kind, ep, et, ev, jump)
            return True
    if kind < 0:
        ist[I_RPTR] = -1  # a new direction: the relays' scan starts afresh
    if ist[I_OP] == OP_PI:
        pi_sync(ist, st, hw, pos, slv)
        for i in range(hw.size):  # the operator's own update (apply): clamp to the finger
            lo = q - hw[i]
            hi = q + hw[i]
            if pos[i] < lo:
                pos[i] = lo
            elif pos[i] > hi:
                pos[i] = hi
        if kind < 0:
            ist[I_DIR] = -ist[I_DIR]
        n = hw.size
        old = np.empty(n, dtype=np.int8)
        for i in range(n):
            old[i] = slv[i]
        pi_branch(ist, st, hw, wt, pos, slv, Y, F, ep, et)
        for i in range(n):
            if slv[i] and not old[i]:
                free[i] = 0  # V_out: δw := δq (done in pi_branch)
    else:
        if kind > 0:
            ist[I_PARTNER] -= 2  # wipe-out of stack[p-1], stack[p]
            ist[I_PUSHED] = 0
            if ist[I_FREE] > ist[I_PARTNER] - 1:
                ist[I_FREE] = ist[I_PARTNER] - 1
        else:
            p = ist[I_PARTNER] + 1
            stack[p] = q
            ist[I_PARTNER] = p
            preisach_term(ist, ep, et, stack, prefix, dlo, dhi, p)
            for j in range(k):
                Y[p + 1, j] = Y[0, j]  # a pushed extremum: δm := δq
            ist[I_PUSHED] = 1
        st[S_U0] = q  # the branch start (u0)
        preisach_branch(ist, st, stack, prefix, dlo, dhi, Y, F)
    merge_breakpoints(ist, st, rel, rord)
    _record_event(par, ist, st, kind, ep, et, ev, jump)
    return True


@njit(cache=True)
def _record_event(par, ist, st, kind, ep, et, ev, jump):
    """Count the event and, when recording, write (t, q, v, kind, M after it, Δy)."""
    q = st[S_Q]
    ist[I_EVENTS] += 1
    if ist[I_RECORD]:
        i = ist[I_NEV]
        n, tau = ist[I_PERIOD], st[S_TAU]
        ev[i, 0] = par[P_T0] + n * par[P_PERIOD] + tau
        ev[i, 1] = q
        ev[i, 2] = st[S_V]
        ev[i, 3] = kind
        ev[i, 4] = output_now(ist, st, ep, et)
        ev[i, 5] = jump
        ist[I_NEV] = i + 1


@njit(cache=True, inline="always")
def _event_fn(tau, args):
    """Root function of an event after the state-only RK8 step over ``tau`` from (t, y):
    ``which`` 0 the reversal ``(−d·v, −d·a)``, 1 the breakpoint ``(d·(q − bp), d·v)``; both
    are negative at τ = 0."""
    par, ist, st, F, ep, et, t, y, z, dz, K, tmp, which = args
    d = ist[I_DIR]
    _rk8(par, ist, st, F, ep, et, t, y, tau, z, K, tmp, 0)
    if which == 0:
        _rhs(par, ist, st, F, ep, et, t + tau, z, dz, 0)
        return -d * z[1], -d * dz[1]
    return d * (z[0] - st[S_BP]), d * z[1]


@njit(cache=True, inline="always")
def _dip_fn(tau, args):
    """Root function of a velocity dip's minimum: ``(d·a, 0)`` after the state-only RK8 step
    over ``tau`` (no derivative: the root finder bisects)."""
    par, ist, st, F, ep, et, t, y, z, dz, K, tmp, which = args
    _rk8(par, ist, st, F, ep, et, t, y, tau, z, K, tmp, 0)
    _rhs(par, ist, st, F, ep, et, t + tau, z, dz, 0)
    return ist[I_DIR] * dz[1], 0.0


@njit(cache=True)
def _locate_args(par, ist, st, F, ep, et, t, y, which, work):
    """The arguments of :func:`_event_fn`/:func:`_dip_fn`: the step start (t, y[:2]) copied
    into ``work`` with the state-only scratch."""
    y2 = work[3, :2]
    y2[0] = y[0]
    y2[1] = y[1]
    K = work[4 : 4 + _N_STAGES, :2]
    return (par, ist, st, F, ep, et, t, y2, work[0, :2], work[1, :2], K, work[2, :2], which)


@njit(cache=True)
def _locate(par, ist, st, F, ep, et, t, y, hi, which, work):
    """Event time in (0, hi] of the step from (t, y): which 0 the reversal (root of −d·v),
    1 the breakpoint (root of d·(q − bp)); safeguarded Newton from the secant, each iterate
    one RK8 step over τ from the step start (state only)."""
    args = _locate_args(par, ist, st, F, ep, et, t, y, which, work)
    d = ist[I_DIR]
    g_lo = -d * y[1] if which == 0 else d * (y[0] - st[S_BP])  # at τ = 0: the step start
    g_hi = _event_fn(hi, args)[0]
    tau = secant_start(0.0, hi, g_lo, g_hi)
    return find_root(_event_fn, args, 0.0, hi, tau, t)


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
    d = ist[I_DIR]
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
def _relay_hop(par, ist, st, F, ep, et, t, y, h, dy, work):
    """Time of a relay switch ahead within the coming step, found by landing on it, or −1
    (then the step runs as usual and locates whatever event comes first).

    In plain Python: predict ``τ0`` from ``q + vτ + aτ²/2 = θ`` (θ the threshold, the nearest
    breakpoint), take a state-only RK8 step to ``τ0`` and a Newton correction
    ``τ1 = τ0 − (q(τ0) − θ)/v(τ0)``, again from ``τ1`` to ``τ2``, and check that ``q(τ1)`` lies on
    θ to round-off (``64 ε max(1, |θ|)``: a second Newton step then moves τ by round-off
    only) and that no reversal came first (``d·v > 0`` at both ends and at the minimum of the
    cubic Hermite interpolant of ``v``). Two state-only RK8 steps per switch instead of a full
    step, its root search (~6 RK8 steps) and the step to it."""
    d = ist[I_DIR]
    theta = st[S_BP]
    q0 = y[0]
    v0 = y[1]
    if d * v0 <= 0.0:
        return -1.0
    _rhs(par, ist, st, F, ep, et, t, y, dy, 0)
    a0 = dy[1]
    dist = d * (theta - q0)
    s = d * v0
    al = d * a0
    disc = s * s + 2.0 * al * dist
    if disc < 0.0:
        return -1.0
    tau = 2.0 * dist / (s + math.sqrt(disc))
    if not 0.0 <= tau < h:
        return -1.0
    z = work[0, :2]
    tmp = work[2, :2]
    K = work[4 : 4 + _N_STAGES, :2]
    y2 = work[3, :2]
    y2[0] = q0
    y2[1] = v0
    for _ in range(2):
        if tau > 0.0:
            _rk8(par, ist, st, F, ep, et, t, y2, tau, z, K, tmp, 0)
        else:
            z[0] = q0
            z[1] = v0
        if d * z[1] <= 0.0:
            return -1.0
        g = d * (z[0] - theta)
        tau -= g / (d * z[1])
        if not 0.0 <= tau < h:
            return -1.0
    # the check: the last correction was at round-off size, and v stayed positive
    if abs(g) > 64.0 * _EPS * max(1.0, abs(theta)):
        return -1.0
    if tau > 0.0:
        # z is the state at the previous iterate, a round-off distance from tau
        _rhs(par, ist, st, F, ep, et, t + tau, z, work[1, :2], 0)
        vmax, vmin = _hermite_extrema(s, al, d * z[1], d * work[1, 1], tau)
        if vmin <= 0.0:
            return -1.0
    return tau


@njit(cache=True)
def _load(st, Y, y, k):
    y[0] = st[S_Q]
    y[1] = st[S_V]
    for j in range(k):
        y[2 + 2 * j] = Y[0, j]
        y[3 + 2 * j] = Y[1, j]


@njit(cache=True)
def _store(st, Y, y, k):
    st[S_Q] = y[0]
    st[S_V] = y[1]
    for j in range(k):
        Y[0, j] = y[2 + 2 * j]
        Y[1, j] = y[3 + 2 * j]


@njit(cache=True)
def _sync(ist, st, hw, pos, slv, Y):
    """Dragged wagons and their rows follow q (PI)."""
    if ist[I_OP] == OP_PI:
        pi_sync(ist, st, hw, pos, slv)
        for i in range(hw.size):
            if slv[i]:
                for j in range(ist[I_K]):
                    Y[3 + i, j] = Y[0, j]


@njit(cache=True)
def _frozen(slv):
    """No wagon dragged: every play's output is constant (PI with relays)."""
    for i in range(slv.size):
        if slv[i]:
            return False
    return True


@njit(cache=True)
def _frozen_stretch(
    par, ist, st, nt, taut, hw, wt, pos, slv, free, stack, prefix, dlo, dhi, ep, et, Y, F, ev,
    rel, rord, fpar, fmp, fe,
):  # fmt: skip
    """While every play is frozen (a composite with relays): closed-form hops from event to
    event (:mod:`oscillators.engines._frozen_hops`), each event applied by :func:`_event` as
    on the RK8 path, until the target (period nt, time taut) or a branch that drags a wagon
    (a wall hit). Works on ``st``/``Y``; returns a status code (``DONE`` for both ends, or
    ``_UNDECIDED``: take one RK8 step)."""
    k = ist[I_K]
    period = par[P_PERIOD]
    bound = par[P_BOUND]
    coefs = hop_coefficients(fmp)
    tau = st[S_TAU]
    ph = par[P_PHI0] + par[P_OMEGA] * tau
    c = math.cos(ph)
    s = math.sin(ph)
    while True:
        n = ist[I_PERIOD]
        if n > nt or (n == nt and tau >= taut) or not _frozen(slv):
            return DONE
        if ist[I_RECORD] and ist[I_NEV] >= ev.shape[0]:
            return EVENTS_FULL
        d = ist[I_DIR]
        q = st[S_Q]
        if d * (st[S_BP] - q) <= 0.0:
            code = _fh.CROSSED  # a threshold at zero distance (the RK8 path: τ = 0)
            ist[I_STUCK] += 1
            if ist[I_STUCK] > _MAX_STUCK:
                return STUCK
        else:
            tau_stop = taut if n == nt else period
            mv = st[S_Y0] + (st[S_RELAY] + st[S_RCOMP])  # _operator's output, slope 0
            code, q1, v1, tau1, c1, s1 = _fh.frozen_hop(
                fpar, coefs, fmp, fe, d, q, st[S_V], tau, c, s, st[S_BP], mv, tau_stop
            )
            if code == _fh.UNDECIDED:
                return _UNDECIDED
            if not (abs(q1) <= bound and abs(v1) <= bound):
                st[S_Q] = q1
                st[S_V] = v1
                return DIVERGED
            if k > 0:
                _fh.frozen_tangent(fpar, tau1 - tau, c, s, c1, s1, Y, F, k)
            st[S_Q] = q1
            st[S_V] = v1
            tau = tau1
            c = c1
            s = s1
            ist[I_STUCK] = 0
            if code == _fh.STOPPED and tau_stop == period and not n == nt:
                # the period's end (the relay kernel's clock): the phase restarts exactly
                ist[I_PERIOD] = n + 1
                tau = 0.0
                c = math.cos(par[P_PHI0])
                s = math.sin(par[P_PHI0])
            elif tau >= period:  # rounding past the period's end
                ist[I_PERIOD] = n + 1
                tau -= period
            st[S_TAU] = tau
            if code == _fh.STOPPED:
                continue
        if code == _fh.CROSSED and st[S_BP] == st[S_RBP] and st[S_BP] != st[S_CBP]:
            # relays switch, the branch goes on: _event's relay-only path, inline
            jump = _rl.relay_jump(ist, st, rel, rord)
            if k > 0 and jump != 0.0:
                if st[S_V] == 0.0:
                    return GRAZING  # a turning point: infinite saltation
                f = par[P_C] * jump / st[S_V]
                for j in range(k):
                    Y[1, j] += f * Y[0, j]
            nearest_breakpoint(ist, st, rel, rord)
            out = output_now(ist, st, ep, et) if ist[I_RECORD] else 0.0
            _rl.record_switch(par, ist, st, ev, out, jump)
            continue
        # an event: q = bp or v = 0 exactly (frozen_hop), applied as on the RK8 path
        if not _event(
            par, ist, st, code, hw, wt, pos, slv, free, stack, prefix, dlo, dhi, ep, et, Y, F,
            ev, rel, rord,
        ):  # fmt: skip
            return GRAZING


@njit(cache=True)
def _to_target(
    par, ist, st, nt, taut, hw, wt, pos, slv, free, stack, prefix, dlo, dhi, ep, et, Y, F, ev, work,
    rel, rord, fpar, fmp, fe,
):  # fmt: skip
    """Integrate to (period nt, time taut), handling every event on the way."""
    k = ist[I_K]
    n = 2 + 2 * k
    y = work[0, :n]
    y1 = work[1, :n]
    dy = work[2, :n]
    tmp = work[3, :n]
    K = work[4 : 4 + _N_STAGES, :n]
    loc = work[4 + _N_STAGES :, :]
    h_step = par[P_H]
    bound = par[P_BOUND]
    # closed-form hops while the plays are frozen (a composite with relays; module docstring)
    hops = ist[I_OP] == OP_PI and rel.shape[0] > 0 and fpar.size > 0
    rk8_once = False  # a degenerate turning point left to one RK8 step
    _load(st, Y, y, k)
    while True:
        rem = (nt - ist[I_PERIOD]) * par[P_PERIOD] + (taut - st[S_TAU])
        if rem <= 0.0:
            break
        if ist[I_OP] == OP_PREISACH and ist[I_PARTNER] + 3 >= stack.size:
            _store(st, Y, y, k)
            return GROW
        if ist[I_RECORD] and ist[I_NEV] >= ev.shape[0]:
            _store(st, Y, y, k)
            return EVENTS_FULL
        if hops and not rk8_once and _frozen(slv):
            _store(st, Y, y, k)
            status = _frozen_stretch(
                par, ist, st, nt, taut, hw, wt, pos, slv, free, stack, prefix, dlo, dhi, ep, et,
                Y, F, ev, rel, rord, fpar, fmp, fe,
            )  # fmt: skip
            if status == _UNDECIDED:
                rk8_once = True
            elif status != DONE:
                return status
            _load(st, Y, y, k)
            continue
        rk8_once = False
        last = rem <= h_step
        h = rem if last else h_step
        t = st[S_TAU]
        d = ist[I_DIR]
        if ist[I_OP] == OP_PI and rel.shape[0] > 0 and st[S_BP] == st[S_RBP]:
            # the next event is most likely a relay switch a short hop ahead (dense relays):
            # land on it directly instead of stepping past it and locating it (module docstring)
            tau = -1.0
            if k == 0 and hops:
                # without the tangent: threshold after threshold by the branch's Taylor
                # polynomial, in one lean loop (_relay_landings.pushed_stretch)
                code, tau = _rl.pushed_stretch(
                    par, ist, st, y, hw, pos, slv, rel, rord, ep, ev, fpar, nt, taut
                )
                if code == _rl.LEAN_STOP:
                    continue
                # this switch is left to the RK8 landing or the general event: from here
                rem = (nt - ist[I_PERIOD]) * par[P_PERIOD] + (taut - st[S_TAU])
                last = rem <= h_step
                h = rem if last else h_step
                t = st[S_TAU]
            if tau < 0.0:
                tau = _relay_hop(par, ist, st, F, ep, et, t, y, h, dy, loc)
                if tau > 0.0:
                    _rk8(par, ist, st, F, ep, et, t, y, tau, y1, K, tmp, k)
                    for r in range(n):
                        y[r] = y1[r]
            if tau > 0.0:
                add_time(par, ist, st, tau)
                y[0] = st[S_BP]  # q := the threshold exactly
                _store(st, Y, y, k)
                _sync(ist, st, hw, pos, slv, Y)
                if not _event(
                    par, ist, st, 1, hw, wt, pos, slv, free, stack, prefix, dlo, dhi, ep, et, Y,
                    F, ev, rel, rord,
                ):  # fmt: skip
                    _store(st, Y, y, k)
                    return GRAZING
                ist[I_STUCK] = 0
                _load(st, Y, y, k)
                continue
        land = np.inf
        if ist[I_OP] == OP_PREISACH and ist[I_EVERETT] == KIND_TABLE:
            # a C¹ table: end the step exactly on the next grid line of the moving input. At
            # the support bounds the slope jumps: the step takes it on the side it moves into
            # (its start nudged forward), in every stage (stage states may overshoot its end)
            ahead = y[0] + d * 1e-12 * max(1.0, abs(y[0]))
            ist[I_OUTSIDE] = 0 if ep[0] <= ahead <= ep[1] else 1
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
            st[S_Q] = y1[0]
            st[S_V] = y1[1]
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
                # locate the minimum of the true velocity (sign change of d·a: bisection, no
                # derivative at hand) and test v there
                args = _locate_args(par, ist, st, F, ep, et, t, y, 0, loc)
                mid = find_root(_dip_fn, args, 0.0, h, 0.5 * h, t)
                z = loc[0, :2]
                _rk8(par, ist, st, F, ep, et, t, y[:2], mid, z, loc[4:16, :2], loc[2, :2], 0)
                if d * z[1] <= 0.0:
                    kind = -1
                    tau = mid
        if kind == -1:
            tau = _locate(par, ist, st, F, ep, et, t, y, tau, 0, loc)
            # the breakpoint may come first on the way to the reversal
            z = loc[0, :2]
            _rk8(par, ist, st, F, ep, et, t, y[:2], tau, z, loc[4:16, :2], loc[2, :2], 0)
            if d * (z[0] - st[S_BP]) >= 0.0:
                kind = 1
                tau = _locate(par, ist, st, F, ep, et, t, y, tau, 1, loc)
        elif d * (y1[0] - st[S_BP]) >= 0.0:
            kind = 1
            tau = _locate(par, ist, st, F, ep, et, t, y, h, 1, loc)
        if kind == 0:
            for r in range(n):
                y[r] = y1[r]
            if land != np.inf:
                y[0] = land  # on the grid line (Newton-located to rounding)
            if last:
                ist[I_PERIOD] = nt
                st[S_TAU] = taut
            else:
                add_time(par, ist, st, h)
            continue
        _rk8(par, ist, st, F, ep, et, t, y, tau, y1, K, tmp, k)
        for r in range(n):
            y[r] = y1[r]
        add_time(par, ist, st, tau)
        if kind > 0:
            y[0] = st[S_BP]  # q := bp exactly
        else:
            y[1] = 0.0  # v := 0 exactly
        _store(st, Y, y, k)
        _sync(ist, st, hw, pos, slv, Y)
        if not _event(
            par, ist, st, kind, hw, wt, pos, slv, free, stack, prefix, dlo, dhi, ep, et, Y, F, ev,
            rel, rord,
        ):  # fmt: skip
            _store(st, Y, y, k)
            return GRAZING
        ist[I_STUCK] = ist[I_STUCK] + 1 if tau == 0.0 else 0
        if ist[I_STUCK] > _MAX_STUCK:
            return STUCK
        _load(st, Y, y, k)
    _store(st, Y, y, k)
    _sync(ist, st, hw, pos, slv, Y)
    return DONE


@njit(cache=True)
def run(
    par, ist, st, nts, tauts, out, hw, wt, pos, slv, free, stack, prefix, dlo, dhi, ep, et, Y, F,
    ev, work, rel, rord, fpar, fmp, fe,
):  # fmt: skip
    """Advance through the targets ``(nts[i], tauts[i])`` from sample ``ist[I_SAMPLE]`` on, writing
    ``(q, v, M)`` into ``out[i]``; returns a status code (module docstring)."""
    i = ist[I_SAMPLE]
    while i < nts.size:
        status = _to_target(
            par, ist, st, nts[i], tauts[i], hw, wt, pos, slv, free, stack, prefix, dlo, dhi,
            ep, et, Y, F, ev, work, rel, rord, fpar, fmp, fe,
        )  # fmt: skip
        if status != DONE:
            return status
        out[i, 0] = st[S_Q]
        out[i, 1] = st[S_V]
        out[i, 2] = output_now(ist, st, ep, et)
        i += 1
        ist[I_SAMPLE] = i
    return DONE


def make_work(k: int) -> np.ndarray:
    """Scratch space of :func:`run` with k tangent columns (the last rows: event location)."""
    return np.zeros((2 * (4 + _N_STAGES), max(2 + 2 * k, 2)))
