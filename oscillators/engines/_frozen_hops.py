"""Closed-form hops of a composite (plays + relays) while every play is frozen.

A composite of plays (plain or erf-shaped, Prandtl–Ishlinskii) and relays runs on the compiled
continuous engine (:mod:`oscillators.engines._continuous_kernels`). While no wagon is dragged
(the input inside every play's band) each play's output is a constant (``a·w`` or
``a·erf(w/(√2 R))`` with ``w`` frozen), so between two relay switches::

    q'' + 2ζ q' + q = cos φ + F,   F = C·(y_plays + Σ w_i y_i)   constant

exactly the relay kernel's linear system, and a play wall is one more threshold. This module
hops from threshold to threshold with the relay kernel's own closed-form hop
(:func:`oscillators.engines._relay_kernels.hop`: series reversion + Newton for short hops, the
Taylor polynomial, the exact solution with its turning-point scan for long flights), imported,
not copied. What the continuous engine adds is the turning point ``v = 0``: it is an event
there (recorded, the relays' scan and the walls ahead change with the direction), so a hop must
not pass one unnoticed.

A hop in direction ``d`` (``d·v > 0``, or ``v = 0`` just after a reversal) targets the
threshold ahead (``S_BP``: the nearer of the next relay threshold and the next wall) and, on
the other side, the start ``q0`` itself: a motion that turns back crosses ``q0`` again, which
ends the hop early. The hop is accepted as monotone when it ends ahead or at the stop with
``d·v > 0`` after at most the Taylor limit ``h_T = 0.02/ρ`` and the cubic Hermite interpolant
of ``v`` over the hop stays off zero — the test the RK8 engine applies to its steps, far
finer here (hops are ~1e-3 long) — and the fast and Taylor hops prove monotonicity anyway.
Otherwise the exact solution is scanned for the first zero of ``v`` in (0, h] (sub-intervals
split at the zeros of ``q''``, safeguarded Newton on each monotone piece,
:func:`first_turn`): the reversal is the event, with ``v := 0`` exactly.

Tangent columns (rows δq, δv of ``Y``; the memory rows are frozen): with ``s = ∂y/∂u = 0`` on a
frozen branch the variational equation is linear with constant forcing,
``δv' = −2ζ δv − δq − sin φ δφ + C·F0`` (``F0`` the frozen wagons' force, ``F2 = δφ``), so
over a hop of length h::

    [δq, δv] := Φ(h) [δq, δv] + p_φ·δφ + p_F·C·F0,   p_F = A⁻¹(Φ(h) − I)(0, 1)ᵀ
              = (1 − Φ_11 − 2ζ Φ_01, Φ_01)

with ``Φ`` and the phase column ``p_φ`` in closed form (:mod:`oscillators.linear`). The
saltations at relay switches and the wall/reversal updates are the continuous engine's own
(its ``_event``).

Pushed branches (:func:`landing`): while a play is dragged the output ``y(q)`` is smooth, not
constant; without tangent columns the next relay threshold is reached by the degree-6 Taylor
polynomial of ``q`` (derivatives by the chain rule from ``y`` and its first four
``q``-derivatives), solved by Newton — instead of the RK8 landing's two state-only steps, its
Newton correction and the full step (~40 right-hand sides).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from oscillators.engines._play_kernels import _hermite_extrema
from oscillators.engines._relay_kernels import (
    _CONTRACT,
    ORDER,
    P_A,
    P_B,
    P_C,
    P_DSUB,
    P_HT,
    P_OMEGA,
    P_PHI0,
    P_ZETA,
    _eval,
    _root,
    hop,
    make_params,
    taylor_matrix_coefficients,
)
from oscillators.linear import exact_step, hom_matrix, particular_amplitudes, phase_column

__all__ = ["hop_tables", "no_hops", "first_turn", "frozen_hop", "frozen_tangent", "landing"]

#: ``frozen_hop`` codes: the threshold ahead reached, the stop reached, a turning point, and
#: "undecided" (the hop and the scan disagree at a degenerate turning point: the caller takes
#: one RK8 step instead)
CROSSED, STOPPED, TURNED, UNDECIDED = 1, 0, -1, 2
#: a sufficient test that the cubic Hermite interpolant of v stays off zero: its basis
#: functions give ``|H(s) − linear| <= (4/27)·h·(|a0| + |a1|)``
_HERMITE_MARGIN = 4.0 / 27.0
#: ``fpar`` entries after the relay kernel's: the engine's ρ, the largest 1/(√2 R)
F_RHO, F_KAPPA = 13, 14
#: the pushed landing's limit ρ_eff·h <= LANDING_RH: its degree-6 Taylor polynomial then errs
#: by ~(ρ_eff h)^7/7! <= 3e-16 relative, four orders below the RK8 step it replaces (local
#: error ~(ρh)^9 at ρh = 0.05); measured at C = 2, 2000 relays: 96% of the pushed switches
#: lie within 0.01/ρ_eff, the rest fall back to the RK8 landing
LANDING_RH = 0.02


def hop_tables(
    zeta: float, omega: float, coupling: float, phi0: float, rho: float, kappa: float
) -> tuple:
    """(``fpar``, ``fmp``, ``fe``): the relay kernel's parameter vector (then ``F_RHO`` the
    engine's rate ρ and ``F_KAPPA`` the largest ``1/(√2 R)`` of the shaped plays) and hop
    tables for the frozen stretches, and the scratch of its Taylor path; empty ``fpar`` (hops
    off) at the undamped resonance ζ = 0, Ω = 1, which has no bounded particular solution."""
    if zeta == 0.0 and omega == 1.0:
        return no_hops()
    amp_a, amp_b = particular_amplitudes(zeta, omega)
    fpar = make_params(zeta, omega, coupling, phi0, amp_a, amp_b, 0.0)
    fpar = np.concatenate([fpar, [rho, kappa]])
    return fpar, taylor_matrix_coefficients(zeta, omega), np.zeros(ORDER + 1)


def no_hops() -> tuple:
    """:func:`hop_tables` of an engine without hops (no relays)."""
    return np.zeros(0), np.zeros((ORDER + 1, 7)), np.zeros(ORDER + 1)


@njit(cache=True)
def first_turn(par, force, q0, v0, c0, s0, tau0, horizon):
    """First zero of ``v`` in (0, horizon] on the exact solution from (q0, v0) at period time
    tau0 (``(c0, s0)`` the phase's cos/sin there), or −1. The span is cut into the relay
    kernel's sub-intervals and each at the zero of ``q''``, so ``v`` is monotone on every piece
    and a sign change brackets its only zero (a zero at the start, ``v0 = 0``, is not one)."""
    zeta = par[P_ZETA]
    dsub = par[P_DSUB]
    tl = 0.0
    vl = v0
    al = -2.0 * zeta * v0 - q0 + c0 + force
    while tl < horizon:
        tr = tl + dsub
        if tr > horizon or horizon - tr < 0.25 * dsub:
            tr = horizon
        _, vr, ar, _ = _eval(par, force, q0, v0, c0, s0, tau0, tr)
        if al * ar < 0.0:
            ta = _root(par, force, q0, v0, c0, s0, tau0, 2, 0.0, tl, tr, al)
            _, va, _, _ = _eval(par, force, q0, v0, c0, s0, tau0, ta)
            if vl * va < 0.0:
                return _root(par, force, q0, v0, c0, s0, tau0, 1, 0.0, tl, ta, vl)
            if va == 0.0 and ta > 0.0:
                return ta
            tl = ta
            vl = va
        if vl * vr < 0.0:
            return _root(par, force, q0, v0, c0, s0, tau0, 1, 0.0, tl, tr, vl)
        if vr == 0.0:
            return tr
        tl = tr
        vl = vr
        al = ar
    return -1.0


@njit(cache=True, fastmath=_CONTRACT)
def frozen_hop(par, coefs, mp, e, d, q, v, tau, c, s, ahead, mv, tau_stop):
    """One hop in direction ``d`` from (q, v) at period time ``tau`` with the output ``mv``:
    to the threshold ``ahead``, to ``tau_stop``, or to the first turning point, whichever comes
    first (module docstring). Returns ``(code, q, v, tau, c, s)``: ``CROSSED`` (q = ahead
    exactly), ``STOPPED`` (tau = tau_stop), ``TURNED`` (v = 0 exactly) or ``UNDECIDED`` (the
    state unchanged)."""
    zeta = par[P_ZETA]
    omega = par[P_OMEGA]
    force = par[P_C] * mv
    if d > 0:
        up = ahead
        down = q
    else:
        up = q
        down = ahead
    z = 0.0
    direction, q1, v1, tau1, c1, s1, _, _, _, _, _, _, _ = hop(
        par, coefs, mp, e, q, v, tau, c, s, up, down, mv, tau_stop, False, 0,
        z, z, z, z, z, z, z, z, z, z,
    )  # fmt: skip
    h = tau1 - tau
    code = CROSSED if direction != 0 else STOPPED  # (valid when direction is d or 0)
    if (direction == d or direction == 0) and d * v1 > 0.0 and h <= par[P_HT]:
        # short and ending in the direction of motion: monotone unless v dips to zero inside
        a0 = d * (-2.0 * zeta * v - q + c + force)
        a1 = d * (-2.0 * zeta * v1 - q1 + c1 + force)
        lo = min(d * v, d * v1)
        if lo > _HERMITE_MARGIN * h * (abs(a0) + abs(a1)):
            return code, q1, v1, tau1, c1, s1
        if _hermite_extrema(d * v, a0, d * v1, a1, h)[1] > 0.0:
            return code, q1, v1, tau1, c1, s1
    # a long flight or a turn: the exact solution's first zero of v decides
    ph = par[P_PHI0] + omega * tau
    c0 = math.cos(ph)
    s0 = math.sin(ph)
    t = first_turn(par, force, q, v, c0, s0, tau, h)
    if t < 0.0:
        if (direction == d or direction == 0) and d * v1 > 0.0:
            return code, q1, v1, tau1, c1, s1  # monotone after all
        return UNDECIDED, q, v, tau, c, s
    tau_t = tau + t
    ph = par[P_PHI0] + omega * tau_t
    ct = math.cos(ph)
    st = math.sin(ph)
    qt, _ = exact_step(q, v, c0, s0, ct, st, force, t, zeta, omega, par[P_A], par[P_B])
    return TURNED, qt, 0.0, tau_t, ct, st


@njit(cache=True)
def frozen_tangent(par, h, c0, s0, c1, s1, Y, F, k):
    """The tangent columns over a frozen hop of length h from phase (c0, s0) to (c1, s1):
    ``[δq, δv] := Φ(h)[δq, δv] + p_φ·δφ + p_F·C·F0`` (module docstring); the memory rows and
    δφ are unchanged."""
    zeta = par[P_ZETA]
    m00, m01, m10, m11 = hom_matrix(h, zeta)
    pq, pv = phase_column(m00, m01, m10, m11, c0, s0, c1, s1, par[P_OMEGA], par[P_A], par[P_B])
    fq = (1.0 - m11) - 2.0 * zeta * m01
    fv = m01
    coupling = par[P_C]
    for j in range(k):
        dq = Y[0, j]
        dv = Y[1, j]
        f = coupling * F[0, j]
        phi = F[2, j]
        Y[0, j] = m00 * dq + m01 * dv + pq * phi + fq * f
        Y[1, j] = m10 * dq + m11 * dv + pv * phi + fv * f


@njit(cache=True, inline="always")
def landing(zeta, omega, coupling, rho, kappa, cp, sp, q, v, d, theta, hmax, y, y1, y2, y3, y4):
    """Time to the relay threshold ``theta`` ahead on a *pushed* branch (a dragged play: the
    output ``y(q)`` is smooth, not constant) by its Taylor polynomial, or −1.

    ``y, y1..y4`` are the output and its first four derivatives in ``q`` at the start, ``cp``,
    ``sp`` the cosine and sine of the forcing phase there; ``rho``, ``kappa`` are ``fpar``'s
    ``F_RHO``, ``F_KAPPA`` (scalars only: inlined into a loop, an array argument would cost a
    reference count per call). The
    time derivatives of ``q`` follow from ``q'' = −2ζq' − q + cos φ + C·y(q)`` by the chain rule
    (``u = y(q(t))``: ``u' = y1 q'``, ``u'' = y2 q'² + y1 q''``, ...); the degree-6 polynomial
    is solved for ``q(h) = θ`` by Newton from the root of its quadratic. Accepted when
    ``h <= min(hmax, LANDING_RH/ρ_eff)`` with ``ρ_eff = max(ρ, κ|v|)`` (the rate of the
    shaped plays' argument), the Newton step has converged, and ``q`` is provably monotone on
    [0, h] (``Σ n|e_n| h^(n−1) < |v|/2``). Returns ``(h, v(h))``."""
    gap = d * (theta - q)
    av = d * v
    if not (gap > 0.0 and av > 0.0):
        return -1.0, 0.0
    rate = max(rho, kappa * av)
    hlim = min(hmax, LANDING_RH / rate)
    if gap >= hlim * av * 2.0:
        return -1.0, 0.0  # too far for one landing (v would have to double)
    o2 = omega * omega
    a = -2.0 * zeta * v - q + cp + coupling * y
    j = -2.0 * zeta * a - v - omega * sp + coupling * (y1 * v)
    s4 = -2.0 * zeta * j - a - o2 * cp + coupling * (y2 * v * v + y1 * a)
    vv = v * v
    s5 = -2.0 * zeta * s4 - j + o2 * omega * sp
    s5 += coupling * (y3 * vv * v + 3.0 * y2 * v * a + y1 * j)
    s6 = -2.0 * zeta * s5 - s4 + o2 * o2 * cp
    s6 += coupling * (y4 * vv * vv + 6.0 * y3 * vv * a + y2 * (3.0 * a * a + 4.0 * v * j) + y1 * s4)
    e2 = 0.5 * a
    e3 = j / 6.0
    e4 = s4 / 24.0
    e5 = s5 / 120.0
    e6 = s6 / 720.0
    disc = v * v + 4.0 * d * e2 * gap
    if disc <= 0.0:
        return -1.0, 0.0
    h = 2.0 * gap / (av + math.sqrt(disc))
    target = theta - q
    curv = abs(e2) + abs(e3) * h
    converged = False
    for _ in range(6):
        p = h * (v + h * (e2 + h * (e3 + h * (e4 + h * (e5 + h * e6)))))
        dp = v + h * (2.0 * e2 + h * (3.0 * e3 + h * (4.0 * e4 + h * (5.0 * e5 + h * 6.0 * e6))))
        if d * dp <= 0.0:
            return -1.0, 0.0
        dh = (p - target) / dp
        h -= dh
        if dh * dh * curv <= 1e-17 * av:  # the next Newton correction: ~|e2|/v·dh²
            converged = True
            break
    if not (converged and 0.0 < h <= hlim):
        return -1.0, 0.0
    bound = h * (2.0 * abs(e2) + h * (3.0 * abs(e3) + h * (4.0 * abs(e4)
                 + h * (5.0 * abs(e5) + h * 6.0 * abs(e6)))))  # fmt: skip
    if bound >= 0.5 * av:
        return -1.0, 0.0
    v1 = v + h * (2.0 * e2 + h * (3.0 * e3 + h * (4.0 * e4 + h * (5.0 * e5 + h * 6.0 * e6))))
    return h, v1
