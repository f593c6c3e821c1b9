"""The relays of a composite on the compiled continuous engine (plays + relays).

The relays' output is constant between their thresholds: the branch's breakpoint ``S_BP`` is
the nearer of the continuous branch's own (``S_CBP``, a wall) and the relays' next threshold
(``S_RBP``, :func:`relay_seek`); reaching ``S_RBP`` switches the relays there
(:func:`relay_switch`: the output jumps by ``Δy``, a running Neumaier-compensated sum). Layouts:
:mod:`oscillators.engines._continuous_layout`; the events and the integration:
:mod:`oscillators.engines._continuous_kernels`.

Pushed stretches (:func:`pushed_stretch`): while a play is dragged (the output ``y(q)`` smooth)
and no tangent column is carried, a dense ensemble puts the next relay threshold a short hop
ahead, and the engine lands on one threshold after the other by the branch's Taylor polynomial
(:func:`oscillators.engines._frozen_hops.landing`). This loop does only what such a switch
changes, in one compiled function (no array crosses a call, so numba's reference counting —
an atomic increment and decrement per array argument — stays out of the loop)::

    c, s = cos φ, sin φ at the start                      (then carried by rotation)
    while the target is ahead and S_BP is a relay threshold (not also a wall):
        y, y', .., y'''' of the branch at q               (branch_taylor: one erf, one exp)
        h, v1 = landing(c, s, q, v, θ = S_BP)             (degree-6 Taylor + Newton) or stop
        q, v, τ := θ, v1, τ + h;  (c, s) := rotation by Ωh (exact cos/sin after a period wrap)
        switch the relays at θ; S_RBP := the next threshold (scan pointer); count the event

The phase rotation by the relay kernel's ``_rotation`` (``|Ωh| <= 0.02``: series error below
1e-20) replaces a cos and a sin per switch; its rounding random-walks by ~1 ulp per switch and
restarts exactly at each stretch and period.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from oscillators.engines._continuous_layout import (
    EVENT_SWITCH,
    I_DIR,
    I_EVENTS,
    I_K,
    I_NEV,
    I_PERIOD,
    I_RECORD,
    I_RPTR,
    I_STUCK,
    P_C,
    P_H,
    P_OMEGA,
    P_PERIOD,
    P_PHI0,
    P_T0,
    P_ZETA,
    R_ALPHA,
    R_BETA,
    R_OUT,
    R_WEIGHT,
    S_BP,
    S_CBP,
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
from oscillators.engines._frozen_hops import F_KAPPA, F_RHO, landing
from oscillators.engines._relay_kernels import _rotation

__all__ = [
    "LEAN_FAILED",
    "LEAN_LANDED",
    "LEAN_STOP",
    "add_time",
    "branch_taylor",
    "erf_play_terms",
    "merge_breakpoints",
    "nearest_breakpoint",
    "pushed_stretch",
    "relay_output",
    "relay_jump",
    "relay_seek",
    "relay_switch",
    "record_switch",
]

#: :func:`pushed_stretch` outcomes: stopped (the caller's loop decides what comes next), the
#: Taylor landing declined (the caller's RK8 landing takes this switch), landed on a relay
#: threshold that is also a wall (the caller applies the general event)
LEAN_STOP, LEAN_FAILED, LEAN_LANDED = 0, 1, 2
#: d/dz erf(z) = (2/√π) exp(−z²)
_TWO_OVER_SQRT_PI = 2.0 / math.sqrt(math.pi)


# --------------------------------------------------------------------------------------------
# the relays of a composite (play + relays): constant output between their thresholds
# --------------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def relay_seek(ist, st, rel, rord):
    """The relays' next threshold ahead of q (``S_RBP``; ``±inf`` if none) and the scan
    pointer ``I_RPTR`` at it. Rising: the least α of the down relays (every relay with
    α <= q is up); falling: the greatest β of the up relays (every relay with β > q is down).
    In plain Python, rising::

        order = argsort(alpha);  i = first index with alpha[order[i]] >= q
        while i < n and out[order[i]] == +1:  i += 1      # skip the relays already up
        bp = alpha[order[i]] if i < n else inf

    The scan starts where the last one stopped while the direction is unchanged (the input
    only moved on), so a branch costs O(N) in all, a binary search per reversal. (``rord`` is
    read by element: a row view would cost a reference count per call.)"""
    n = rel.shape[0]
    if n == 0:
        st[S_RBP] = ist[I_DIR] * np.inf
        return
    d = ist[I_DIR]
    q = st[S_Q]
    i = ist[I_RPTR]
    if d > 0:
        if i < 0:  # a new direction: binary search
            lo, hi = 0, n
            while lo < hi:
                mid = (lo + hi) // 2
                if rel[rord[0, mid], R_ALPHA] < q:
                    lo = mid + 1
                else:
                    hi = mid
            i = lo
        while i < n and rel[rord[0, i], R_OUT] > 0.0:
            i += 1
        ist[I_RPTR] = i
        st[S_RBP] = rel[rord[0, i], R_ALPHA] if i < n else np.inf
    else:
        if i < 0:
            lo, hi = 0, n
            while lo < hi:
                mid = (lo + hi) // 2
                if rel[rord[1, mid], R_BETA] <= q:
                    lo = mid + 1
                else:
                    hi = mid
            i = n - 1 - (lo - 1)  # counted from the top: the greatest β <= q first
        while i < n and rel[rord[1, n - 1 - i], R_OUT] < 0.0:
            i += 1
        ist[I_RPTR] = i
        st[S_RBP] = rel[rord[1, n - 1 - i], R_BETA] if i < n else -np.inf


@njit(cache=True)
def merge_breakpoints(ist, st, rel, rord):
    """After the continuous branch set ``S_BP``: keep it as ``S_CBP``, seek the relays' next
    threshold and make ``S_BP`` the nearer of the two."""
    st[S_CBP] = st[S_BP]
    nearest_breakpoint(ist, st, rel, rord)


@njit(cache=True, inline="always")
def nearest_breakpoint(ist, st, rel, rord):
    """``S_BP`` := the nearer of the continuous branch's ``S_CBP`` and the relays' next
    threshold (sought afresh from the scan pointer)."""
    relay_seek(ist, st, rel, rord)
    if ist[I_DIR] > 0:
        st[S_BP] = min(st[S_CBP], st[S_RBP])
    else:
        st[S_BP] = max(st[S_CBP], st[S_RBP])


@njit(cache=True)
def relay_output(rel):
    """``Σ w_i y_i`` of the relays (in table order)."""
    total = 0.0
    for i in range(rel.shape[0]):
        total += rel[i, R_WEIGHT] * rel[i, R_OUT]
    return total


@njit(cache=True, inline="always")
def relay_jump(ist, st, rel, rord):
    """Switch every relay at the threshold reached (``q = S_RBP``): rising, the down relays
    with α = q go up; falling, the up relays with β = q go down (the relay rule ``u < β``
    holds just past it); the scan pointer moves past them and the output ``S_RELAY`` (with
    its compensation ``S_RCOMP``) takes the jump ``Δy = Σ 2 w_i·(±1)``, returned."""
    n = rel.shape[0]
    d = ist[I_DIR]
    q = st[S_RBP]
    i = ist[I_RPTR]
    jump = 0.0
    if d > 0:
        while i < n and rel[rord[0, i], R_ALPHA] == q:
            j = rord[0, i]
            if rel[j, R_OUT] < 0.0:
                rel[j, R_OUT] = 1.0
                jump += 2.0 * rel[j, R_WEIGHT]
            i += 1
    else:
        while i < n and rel[rord[1, n - 1 - i], R_BETA] == q:
            j = rord[1, n - 1 - i]
            if rel[j, R_OUT] > 0.0:
                rel[j, R_OUT] = -1.0
                jump -= 2.0 * rel[j, R_WEIGHT]
            i += 1
    ist[I_RPTR] = i
    # the relays' output as a compensated running sum (Neumaier): O(1) per switch, and the
    # error stays at a few ulps of the largest term instead of growing with the switches
    total = st[S_RELAY] + jump
    if abs(st[S_RELAY]) >= abs(jump):
        st[S_RCOMP] += (st[S_RELAY] - total) + jump
    else:
        st[S_RCOMP] += (jump - total) + st[S_RELAY]
    st[S_RELAY] = total
    return jump


@njit(cache=True)
def relay_switch(par, ist, st, rel, rord, Y):
    """:func:`relay_jump`, and each tangent column gets the saltation ``δv += C·Δy/v*·δq``
    (paper eq. ``salt_matrix``). Returns (False, Δy) at a turning point with the tangent flow
    on (infinite saltation: the caller raises), else (True, Δy)."""
    jump = relay_jump(ist, st, rel, rord)
    k = ist[I_K]
    if k > 0 and jump != 0.0:
        v = st[S_V]
        if v == 0.0:
            return False, jump
        f = par[P_C] * jump / v
        for j in range(k):
            Y[1, j] += f * Y[0, j]
    return True, jump


@njit(cache=True, inline="always")
def add_time(par, ist, st, h):
    """``τ += h`` with the period count carried (``0 <= τ < T``)."""
    st[S_TAU] += h
    if st[S_TAU] >= par[P_PERIOD]:
        st[S_TAU] -= par[P_PERIOD]
        ist[I_PERIOD] += 1
        if st[S_TAU] >= par[P_PERIOD] or st[S_TAU] < 0.0:  # rounding
            extra = math.floor(st[S_TAU] / par[P_PERIOD])
            ist[I_PERIOD] += int(extra)
            st[S_TAU] -= extra * par[P_PERIOD]
            if st[S_TAU] < 0.0:
                st[S_TAU] = 0.0


@njit(cache=True, inline="always")
def record_switch(par, ist, st, ev, out, jump):
    """Count a relay switch and, when recording, write (t, q, v, kind, M after it, Δy) as the
    engine's ``_record_event`` does (``out`` the output after the switch)."""
    ist[I_EVENTS] += 1
    if ist[I_RECORD]:
        i = ist[I_NEV]
        ev[i, 0] = par[P_T0] + ist[I_PERIOD] * par[P_PERIOD] + st[S_TAU]
        ev[i, 1] = st[S_Q]
        ev[i, 2] = st[S_V]
        ev[i, 3] = EVENT_SWITCH
        ev[i, 4] = out
        ev[i, 5] = jump
        ist[I_NEV] = i + 1


@njit(cache=True, inline="always")
def erf_play_terms(a, kap, z):
    """One dragged erf play's ``a·erf(z)``, ``z = κ(q − d r)``, and its first four derivatives
    in ``q``, ``a·κⁿ·erf⁽ⁿ⁾(z)`` with ``erf⁽¹⁾ = (2/√π)e^{−z²}``, ``erf⁽²⁾ = −2z·erf⁽¹⁾``,
    ``erf⁽³⁾ = (4z² − 2)·erf⁽¹⁾``, ``erf⁽⁴⁾ = (12z − 8z³)·erf⁽¹⁾``."""
    g = a * kap * _TWO_OVER_SQRT_PI * math.exp(-z * z)
    g2 = g * kap
    g3 = g2 * kap
    return (
        a * math.erf(z),
        g,
        -(2.0 * z * g2),
        (4.0 * z * z - 2.0) * g3,
        (12.0 * z - 8.0 * z * z * z) * g3 * kap,
    )


@njit(cache=True)
def branch_taylor(st, ep, q):
    """The PI branch's output (relays included) and its first four derivatives in ``q``: the
    dragged plain plays contribute the slope, each dragged erf play :func:`erf_play_terms`."""
    y = st[S_Y0] + st[S_SLOPE] * (q - st[S_U0])
    y1 = st[S_SLOPE]
    y2 = 0.0
    y3 = 0.0
    y4 = 0.0
    for j in range(int(ep[0])):
        kap = ep[3 + 3 * j]
        t0, t1, t2, t3, t4 = erf_play_terms(ep[1 + 3 * j], kap, (q - ep[2 + 3 * j]) * kap)
        y += t0
        y1 += t1
        y2 += t2
        y3 += t3
        y4 += t4
    return y + (st[S_RELAY] + st[S_RCOMP]), y1, y2, y3, y4


@njit(cache=True)
def pushed_stretch(par, ist, st, y, hw, pos, slv, rel, rord, ep, ev, fpar, nt, taut):
    """Land on relay thresholds one after the other on a pushed branch without tangent columns
    (module docstring), from ``(y[0], y[1])`` at ``S_TAU`` towards the target (period ``nt``,
    time ``taut``), each landing limited to the engine's RK8 step as the caller's. Returns
    ``(code, h)``: ``LEAN_STOP`` (the target reached, ``ev`` full, or the breakpoint ahead not
    a relay threshold), ``LEAN_FAILED`` (the Taylor landing declined: ``h = -1``), or
    ``LEAN_LANDED`` (``h`` > 0 to a relay threshold that is also a wall: ``y[1]`` holds v
    there, the time is not yet advanced). ``y``, ``st`` (q, v) and the dragged wagons are
    current on return.

    The loop body calls nothing that takes an array (numba counts references to every array
    argument of a call, two atomic operations each, ~40% of the time of a switch): the
    branch's Taylor data (:func:`branch_taylor`), the clock (:func:`add_time`), the switch
    (:func:`relay_jump`) and the next threshold (:func:`relay_seek`, :func:`nearest_breakpoint`)
    are written out here, direction-generic (``d = ±1``: the relays at θ with ``d·y_i < 0``
    flip to ``y_i = d``; the scan skips those with ``d·y_i > 0``)."""
    period = par[P_PERIOD]
    h_step = par[P_H]
    omega = par[P_OMEGA]
    zeta = par[P_ZETA]
    coupling = par[P_C]
    rho = fpar[F_RHO]
    kappa = fpar[F_KAPPA]
    d = ist[I_DIR]
    fd = float(d)
    record = ist[I_RECORD] != 0
    n_rel = rel.shape[0]
    row = 0 if d > 0 else 1  # rord[0]: α ascending; rord[1]: β ascending, read from the top
    col = R_ALPHA if d > 0 else R_BETA
    n_shaped = int(ep[0])
    base = st[S_Y0]
    slope = st[S_SLOPE]
    u0 = st[S_U0]
    cbp = st[S_CBP]
    q = y[0]
    v = y[1]
    tau = st[S_TAU]
    n = ist[I_PERIOD]
    ph = par[P_PHI0] + omega * tau
    c = math.cos(ph)
    s = math.sin(ph)
    code = LEAN_STOP
    h_land = -1.0
    while True:
        rem = (nt - n) * period + (taut - tau)
        theta = st[S_BP]
        if rem <= 0.0 or theta != st[S_RBP]:
            break
        if record and ist[I_NEV] >= ev.shape[0]:
            break
        h = rem if rem <= h_step else h_step
        # the branch's output and its q-derivatives at q (branch_taylor)
        yb = base + slope * (q - u0)
        y1 = slope
        y2 = 0.0
        y3 = 0.0
        y4 = 0.0
        for j in range(n_shaped):
            kap = ep[3 + 3 * j]
            t0, t1, t2, t3, t4 = erf_play_terms(ep[1 + 3 * j], kap, (q - ep[2 + 3 * j]) * kap)
            yb += t0
            y1 += t1
            y2 += t2
            y3 += t3
            y4 += t4
        yb = yb + (st[S_RELAY] + st[S_RCOMP])
        hl, v1 = landing(zeta, omega, coupling, rho, kappa, c, s, q, v, d, theta, h, yb, y1, y2,
                         y3, y4)  # fmt: skip
        if not hl > 0.0:
            code = LEAN_FAILED
            break
        v = v1
        if theta == cbp:
            code = LEAN_LANDED  # a wall too: the general event
            h_land = hl
            break
        q = theta  # q := the threshold exactly
        # the clock (add_time); the phase rotated, afresh in a new period
        tau += hl
        if tau >= period:
            tau -= period
            n += 1
            if tau >= period or tau < 0.0:  # rounding
                extra = math.floor(tau / period)
                n += int(extra)
                tau -= extra * period
                if tau < 0.0:
                    tau = 0.0
            ph = par[P_PHI0] + omega * tau
            c = math.cos(ph)
            s = math.sin(ph)
        else:
            cx, sx = _rotation(omega * hl)
            c, s = c * cx - s * sx, s * cx + c * sx
        st[S_TAU] = tau
        ist[I_PERIOD] = n
        st[S_Q] = q
        st[S_V] = v
        # the relays at θ switch (relay_jump)
        i = ist[I_RPTR]
        jump = 0.0
        while i < n_rel:
            r = rord[row, i] if d > 0 else rord[row, n_rel - 1 - i]
            if rel[r, col] != theta:
                break
            if fd * rel[r, R_OUT] < 0.0:
                rel[r, R_OUT] = fd
                jump += 2.0 * fd * rel[r, R_WEIGHT]
            i += 1
        total = st[S_RELAY] + jump  # Neumaier, as relay_jump
        if abs(st[S_RELAY]) >= abs(jump):
            st[S_RCOMP] += (st[S_RELAY] - total) + jump
        else:
            st[S_RCOMP] += (jump - total) + st[S_RELAY]
        st[S_RELAY] = total
        # the next threshold ahead (relay_seek, nearest_breakpoint)
        rbp = fd * np.inf
        while i < n_rel:
            r = rord[row, i] if d > 0 else rord[row, n_rel - 1 - i]
            if not fd * rel[r, R_OUT] > 0.0:
                rbp = rel[r, col]
                break
            i += 1
        ist[I_RPTR] = i
        st[S_RBP] = rbp
        st[S_BP] = min(cbp, rbp) if d > 0 else max(cbp, rbp)
        if record:
            record_switch(par, ist, st, ev, branch_taylor(st, ep, q)[0], jump)
        else:
            ist[I_EVENTS] += 1
        ist[I_STUCK] = 0
    y[0] = q
    y[1] = v
    st[S_Q] = q
    st[S_V] = v
    for i in range(hw.size):  # the dragged wagons follow q (pi_sync)
        if slv[i]:
            pos[i] = q - d * hw[i]
    return code, h_land
