"""Compiled kernels of the play-limit flow (see :mod:`oscillators.engines.play` for the physics).

System (paper eqs. eom_smooth_4, limit_W_0, limit_W_1, salt_matrix_limit)::

    q'' + 2ζ q' + q = cos(φ0 + Ω t) + C f(w),     w = play output of q (width p = 2 hp)

Everything lives in flat arrays so that numba compiles one specialisation; their layouts are
the named index constants below (one definition each;
:func:`oscillators.engines.play.make_parameters` fills ``par`` by these names):

``par`` (float64): ``P_ZETA`` ζ, ``P_OMEGA`` Ω, ``P_C`` C, ``P_HP`` hp = p/2, ``P_SHAPE`` the
shape kind (``SHAPE_IDENTITY``, ``SHAPE_ERF``, ``SHAPE_TABLE``), ``P_SPREAD`` R, ``P_PHI0`` φ0,
``P_H_OUT`` the RK8 step on a wall, ``P_H_IN`` the scan step inside, ``P_AMP_A``/``P_AMP_B``
A, B of the periodic particular solution q_p = A cos φ + B sin φ, ``P_OMEGA_D`` ω_d = √(1 − ζ²),
``P_AMP`` √(A² + B²), ``P_ERF_SCALE`` 1/(√2 R), ``P_ERF_SLOPE`` √(2/π)/R; a table shape
appends from ``P_TABLE`` on: lower knot w_0, step h, knots m, f(w_k) (m values), f'(w_k)
(m values) (a :class:`hysteresis.shape_table.ShapeTable`: the piecewise cubic Hermite
interpolant; in knot interval k with s = (w − w_k)/h,
f = A₀(s) f_k + h B₀(s) f'_k + A₁(s) f_{k+1} + h B₁(s) f'_{k+1}, and beyond the knots the
end value with slope 0).

``st`` (float64) = [``S_T`` t, ``S_Q`` q, ``S_V`` v, ``S_W`` w, ``S_MODE`` mode] with mode 0
inside the play (|q - w| < hp, w frozen), +1 on the right wall moving right (w = q - hp, v > 0),
-1 on the left wall moving left (w = q + hp, v < 0).

``T`` (4, k): tangent vectors as columns, rows (δq, δv, δφ, δw); k = 0 switches the tangent
flow off. ``diag``: [``D_EXITS``, ``D_ENTRIES``, -, -] counted while accumulating.
``flags`` (int64) = [``F_ACCUMULATE``, ``F_QR_MODE``]: qr_mode 0 applies V_out as a plain
matrix (the tangent flow between the Lyapunov loop's re-orthonormalisations); qr_mode 2 omits
V_out (a diagnostic showing that the saltation is needed). The QR itself lives once, in
analysis/dynamics/lyapunov.py.
``ev`` (cap, 5): events [t, q, v, kind, w] (kind +1 leaving the play, -1 entering), ``cnt[0]``
counts all events (also those beyond ``cap``).

Numerical building blocks with one home elsewhere: the Dormand–Prince table and the RK8 step
(:mod:`oscillators.engines._dop853_kernel`; :func:`_rk8_qv` is its (q, v)-only specialisation,
written out stage by stage), the safeguarded Newton root finder
(:mod:`oscillators.engines._roots`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from oscillators.engines import _dop853_kernel as _dop
from oscillators.engines._roots import find_root, secant_start

# Dormand–Prince 8(5,3): the 12 stages of the 8th-order solution, used here with a fixed step
# (coefficients carried in oscillators/engines/_dop853_kernel.py with their citation); short
# names for the written-out step _rk8_qv
_N_STAGES = _dop.N_STAGES
RK_A = _dop.A
RK_B = _dop.B
RK_C = _dop.C

# ``par`` layout (module docstring)
P_ZETA, P_OMEGA, P_C, P_HP, P_SHAPE, P_SPREAD, P_PHI0, P_H_OUT, P_H_IN = range(9)
P_AMP_A, P_AMP_B, P_OMEGA_D, P_AMP, P_ERF_SCALE, P_ERF_SLOPE = range(9, 15)
#: where a table shape starts in ``par`` (also the length of ``par`` without a table)
P_TABLE = 15
#: values of ``par[P_SHAPE]``
SHAPE_IDENTITY, SHAPE_ERF, SHAPE_TABLE = 0.0, 1.0, 2.0
# ``st``, ``diag`` and ``flags`` layouts
S_T, S_Q, S_V, S_W, S_MODE = range(5)
D_EXITS, D_ENTRIES = range(2)
F_ACCUMULATE, F_QR_MODE = range(2)

# Width of the interval on which a possible wall hit inside the play is resolved exactly
# (there the input velocity has at most one zero and the Hermite error bound is ~1e-14).
_RESOLVE = 1e-3


# --------------------------------------------------------------------------------------------
# shape of the generalized play
# --------------------------------------------------------------------------------------------
@njit(cache=True)
def _table_eval(par, w):
    """Kind 2: (f, f') of the cubic Hermite table ``par[15:]`` (layout in the module
    docstring); beyond the last knot on either side that knot's value and slope 0."""
    lower = par[P_TABLE]
    step = par[P_TABLE + 1]
    m = int(par[P_TABLE + 2])
    base = P_TABLE + 3
    x = (w - lower) / step
    if not x > 0.0:  # also NaN: the kernel's divergence checks see q, not w
        return par[base], 0.0
    if x >= m - 1:
        return par[base + m - 1], 0.0
    k = int(x)
    if k > m - 2:
        k = m - 2
    s = x - k
    s2 = s * s
    f0 = par[base + k]
    f1 = par[base + k + 1]
    d0 = par[base + m + k] * step
    d1 = par[base + m + k + 1] * step
    value = (
        (1.0 - 3.0 * s2 + 2.0 * s2 * s) * f0
        + (s - 2.0 * s2 + s2 * s) * d0
        + (3.0 * s2 - 2.0 * s2 * s) * f1
        + (s2 * s - s2) * d1
    )
    slope = (
        (-6.0 * s + 6.0 * s2) * f0
        + (1.0 - 4.0 * s + 3.0 * s2) * d0
        + (6.0 * s - 6.0 * s2) * f1
        + (3.0 * s2 - 2.0 * s) * d1
    ) / step
    return value, slope


@njit(cache=True)
def shape(par, w):
    """f(w): identity (play), erf(w / (√2 R)) (paper eq. prob_mag) or the table (kind 2)."""
    if par[P_SHAPE] == SHAPE_ERF:
        return math.erf(w * par[P_ERF_SCALE])
    if par[P_SHAPE] == SHAPE_TABLE:
        return _table_eval(par, w)[0]
    return w


@njit(cache=True)
def shape_slope(par, w):
    """f'(w)."""
    if par[P_SHAPE] == SHAPE_ERF:
        z = w / par[P_SPREAD]
        return par[P_ERF_SLOPE] * math.exp(-0.5 * z * z)
    if par[P_SHAPE] == SHAPE_TABLE:
        return _table_eval(par, w)[1]
    return 1.0


@njit(cache=True)
def shape_values(par, w):
    """:func:`shape` at every element of the 1-D array ``w``."""
    out = np.empty(w.size)
    for i in range(w.size):
        out[i] = shape(par, w[i])
    return out


# --------------------------------------------------------------------------------------------
# events, QR
# --------------------------------------------------------------------------------------------
@njit(cache=True)
def _record(ev, cnt, t, q, v, kind, w):
    i = cnt[0]
    if i < ev.shape[0]:
        ev[i, 0] = t
        ev[i, 1] = q
        ev[i, 2] = v
        ev[i, 3] = kind
        ev[i, 4] = w
    cnt[0] = i + 1


@njit(cache=True)
def leave_play(T, qr_mode):
    """Saltation at the instant the input hits a wall (paper's V_out: δw := δq).

    The standard saltation ``S = I + (F⁺ − F⁻) nᵀ / (n·F⁻)`` with ``n = ∇(q − w ∓ p/2)`` and
    ``F⁺ − F⁻ = (0, 0, 0, v)``: the force ``C f(w)`` is continuous at the hit and only ``ẇ``
    jumps from 0 to ``v``, so ``δw := δq`` and (δq, δv, δφ) are unchanged. ``V_out`` has rank
    k − 1 (its kernel is the pure-δw direction); the Lyapunov loop learns of it through the
    engine's ``rank_bound()``. ``qr_mode == 2`` omits it (a diagnostic showing it is needed).
    """
    k = T.shape[1]
    if k == 0 or qr_mode == 2:
        return
    for j in range(k):
        T[3, j] = T[0, j]


# --------------------------------------------------------------------------------------------
# inside the play: linear oscillator with constant force C f(w), exact solution
# --------------------------------------------------------------------------------------------
@njit(cache=True)
def _inside_eval(par, phi_s, F, c1, c2, u0d, d2, tau):
    """q, v, a at elapsed time tau of the analytic inside solution."""
    zeta = par[P_ZETA]
    om = par[P_OMEGA]
    wd = par[P_OMEGA_D]
    A = par[P_AMP_A]
    B = par[P_AMP_B]
    ph = phi_s + om * tau
    cp = math.cos(ph)
    sp = math.sin(ph)
    e = math.exp(-zeta * tau)
    cw = math.cos(wd * tau)
    sw = math.sin(wd * tau)
    q = F + A * cp + B * sp + e * (c1 * cw + c2 * sw)
    v = om * (-A * sp + B * cp) + e * (u0d * cw - d2 * sw)
    a = -2.0 * zeta * v - q + cp + F
    return q, v, a


@njit(cache=True)
def _hermite_extrema(ql, vl, qr, vr, h):
    """Max and min over [0, h] of the cubic Hermite interpolant of (q, v) at both ends."""
    c2 = 3.0 * (qr - ql) - h * (2.0 * vl + vr)
    c3 = 2.0 * (ql - qr) + h * (vl + vr)
    hi = max(ql, qr)
    lo = min(ql, qr)
    # H'(s) = h vl + 2 c2 s + 3 c3 s^2, s in (0, 1)
    a = 3.0 * c3
    b = 2.0 * c2
    c = h * vl
    # the zeros of H' as two scalars (no array: the relay kernel's event loop, which calls
    # this through _hit_possible, runs without numba's reference counting and cannot allocate)
    r0 = 0.0
    r1 = 0.0
    nr = 0
    if abs(a) < 1e-300:
        if abs(b) > 0.0:
            r0 = -c / b
            nr = 1
    else:
        disc = b * b - 4.0 * a * c
        if disc >= 0.0:
            sq = math.sqrt(disc)
            qq = -0.5 * (b + math.copysign(sq, b))
            if qq != 0.0:
                r0 = qq / a
                r1 = c / qq
                nr = 2
            else:
                r0 = 0.0
                nr = 1
    for i in range(nr):
        s = r0 if i == 0 else r1
        if 0.0 < s < 1.0:
            val = ql + h * vl * s + c2 * s * s + c3 * s * s * s
            hi = max(hi, val)
            lo = min(lo, val)
    return hi, lo


@njit(cache=True, inline="always")
def _inside_v(tau, args):
    """Root function of the extremum inside: ``(g, g') = sgn·(−v, −a)`` at ``tau``, oriented
    (``sgn`` = the sign of v at the bracket's left end) so that g < 0 there."""
    par, phi_s, F, c1, c2, u0d, d2, sgn = args
    _, v, a = _inside_eval(par, phi_s, F, c1, c2, u0d, d2, tau)
    return -sgn * v, -sgn * a


@njit(cache=True, inline="always")
def _inside_q(tau, args):
    """Root function of a wall hit inside: ``(g, g') = sgn·(q − wall, v)`` at ``tau``, oriented
    (``sgn`` = −1 when q starts above the wall) so that g < 0 at the bracket's left end."""
    par, phi_s, F, c1, c2, u0d, d2, wall, sgn = args
    q, v, _ = _inside_eval(par, phi_s, F, c1, c2, u0d, d2, tau)
    return sgn * (q - wall), sgn * v


@njit(cache=True)
def _velocity_zero(par, phi_s, F, c1, c2, u0d, d2, ta, tb, va, clock):
    """Zero of v on [ta, tb] (sign change assumed; ``va`` = v(ta)) from the midpoint; the
    event clock is ``clock`` (the root finder's scale)."""
    sgn = 1.0 if va > 0.0 else -1.0
    args = (par, phi_s, F, c1, c2, u0d, d2, sgn)
    return find_root(_inside_v, args, ta, tb, 0.5 * (ta + tb), clock)


@njit(cache=True)
def _wall_root(par, phi_s, F, c1, c2, u0d, d2, ta, tb, wall, clock):
    """Root of q(t) = wall on [ta, tb] with q - wall changing sign, from the secant."""
    qa, _, _ = _inside_eval(par, phi_s, F, c1, c2, u0d, d2, ta)
    qb, _, _ = _inside_eval(par, phi_s, F, c1, c2, u0d, d2, tb)
    sgn = -1.0 if qa - wall > 0.0 else 1.0
    args = (par, phi_s, F, c1, c2, u0d, d2, wall, sgn)
    x = secant_start(ta, tb, sgn * (qa - wall), sgn * (qb - wall))
    return find_root(_inside_q, args, ta, tb, x, clock)


@njit(cache=True)
def _resolve(par, phi_s, F, c1, c2, u0d, d2, lo, qlo, vlo, hi, qhi, vhi, up, dn, clock):
    """Exact decision on a short interval [lo, hi] (length <= _RESOLVE) whose left end lies
    inside the play: time of the first wall hit in (lo, hi] and its wall (+1 right, -1 left),
    or (-1.0, 0) if the input stays inside. On such an interval v has at most one zero, so q
    is monotone or has a single extremum, found by Newton on v. ``clock``: the time the
    roots are added to (the root finder's scale)."""
    t_up = -1.0
    t_dn = -1.0
    if qhi >= up:
        t_up = _wall_root(par, phi_s, F, c1, c2, u0d, d2, lo, hi, up, clock)
    elif vlo > 0.0 and vhi < 0.0:
        tm = _velocity_zero(par, phi_s, F, c1, c2, u0d, d2, lo, hi, vlo, clock)
        qm, _, _ = _inside_eval(par, phi_s, F, c1, c2, u0d, d2, tm)
        if qm > up:
            t_up = _wall_root(par, phi_s, F, c1, c2, u0d, d2, lo, tm, up, clock)
    if qhi <= dn:
        t_dn = _wall_root(par, phi_s, F, c1, c2, u0d, d2, lo, hi, dn, clock)
    elif vlo < 0.0 and vhi > 0.0:
        tm = _velocity_zero(par, phi_s, F, c1, c2, u0d, d2, lo, hi, vlo, clock)
        qm, _, _ = _inside_eval(par, phi_s, F, c1, c2, u0d, d2, tm)
        if qm < dn:
            t_dn = _wall_root(par, phi_s, F, c1, c2, u0d, d2, lo, tm, dn, clock)
    if t_up >= 0.0 and (t_dn < 0.0 or t_up <= t_dn):
        return t_up, 1
    if t_dn >= 0.0:
        return t_dn, -1
    return -1.0, 0


@njit(cache=True)
def _hit_possible(ql, vl, qr, vr, h, up, dn, M4):
    """Can q reach a wall on this interval? Cubic Hermite interpolant plus the rigorous error
    bound max|q''''| h^4 / 384."""
    if qr >= up or qr <= dn:
        return True
    hi, lo = _hermite_extrema(ql, vl, qr, vr, h)
    margin = M4 * h * h * h * h / 384.0
    return hi + margin >= up or lo - margin <= dn


@njit(cache=True)
def _inside_tangent(par, T, w, phi_s, tau):
    """Propagate tangent columns over an inside segment of length tau (paper's W0, exact):

    δx(τ) = Φ(τ) δx0 + (I - Φ(τ)) e1 · C f'(w) δw + (x_p'(φ(τ)) - Φ(τ) x_p'(φ_s)) δφ,
    δφ, δw frozen, with Φ the propagator of the damped oscillator and x_p' = ∂x_p/∂φ.
    """
    zeta = par[P_ZETA]
    om = par[P_OMEGA]
    wd = par[P_OMEGA_D]
    A = par[P_AMP_A]
    B = par[P_AMP_B]
    e = math.exp(-zeta * tau)
    cw = math.cos(wd * tau)
    sw = math.sin(wd * tau)
    p11 = e * (cw + zeta / wd * sw)
    p12 = e * sw / wd
    p21 = -e * sw / wd
    p22 = e * (cw - zeta / wd * sw)
    c0 = math.cos(phi_s)
    s0 = math.sin(phi_s)
    c1 = math.cos(phi_s + om * tau)
    s1 = math.sin(phi_s + om * tau)
    dq0 = -A * s0 + B * c0
    dv0 = om * (-A * c0 - B * s0)
    dq1 = -A * s1 + B * c1
    dv1 = om * (-A * c1 - B * s1)
    gq = dq1 - (p11 * dq0 + p12 * dv0)
    gv = dv1 - (p21 * dq0 + p22 * dv0)
    kappa = par[P_C] * shape_slope(par, w)
    for j in range(T.shape[1]):
        dq = T[0, j]
        dv = T[1, j]
        dph = T[2, j]
        dw = T[3, j]
        T[0, j] = p11 * dq + p12 * dv + (1.0 - p11) * kappa * dw + gq * dph
        T[1, j] = p21 * dq + p22 * dv - p21 * kappa * dw + gv * dph


@njit(cache=True)
def _inside(par, st, t_target, T, diag, ev, cnt, flags):
    """Advance inside the play until t_target or the first wall hit (then switch to the wall).

    Plain reading: with F = C f(w) the motion is q(τ) = F + q_p(φ(τ)) + damped free motion.
    Scan [0, τ_end] in steps h_in; on each step decide with the Hermite bound whether q can
    reach a wall; if so bisect (left half first) down to intervals of length 1e-3, where the
    first hit is found exactly (Newton on q - wall, extremum by Newton on v). Nothing is missed
    except tangential touches of depth below ~1e-14.
    """
    zeta = par[P_ZETA]
    om = par[P_OMEGA]
    hp = par[P_HP]
    t0 = st[S_T]
    q0 = st[S_Q]
    v0 = st[S_V]
    w = st[S_W]
    F = par[P_C] * shape(par, w)
    phi_s = par[P_PHI0] + om * t0
    A = par[P_AMP_A]
    B = par[P_AMP_B]
    wd = par[P_OMEGA_D]
    cp = math.cos(phi_s)
    sp = math.sin(phi_s)
    u0 = q0 - F - (A * cp + B * sp)
    u0d = v0 - om * (-A * sp + B * cp)
    c1 = u0
    c2 = (u0d + zeta * u0) / wd
    d2 = (u0 + zeta * u0d) / wd
    # every derivative of the free motion is bounded by its amplitude (|eigenvalue| = 1)
    M4 = math.sqrt(c1 * c1 + c2 * c2) + par[P_AMP] * om * om * om * om
    up = w + hp
    dn = w - hp
    tau_end = t_target - t0
    h_in = par[P_H_IN]
    ta = 0.0
    qa = q0
    va = v0
    hit_t = -1.0
    hit_side = 0
    while ta < tau_end:
        tb = min(ta + h_in, tau_end)
        qb, vb, _ = _inside_eval(par, phi_s, F, c1, c2, u0d, d2, tb)
        lo, qlo, vlo = ta, qa, va
        hi, qhi, vhi = tb, qb, vb
        while True:
            if not _hit_possible(qlo, vlo, qhi, vhi, hi - lo, up, dn, M4):
                cleared = True
            elif hi - lo <= _RESOLVE:
                tr, side = _resolve(
                    par, phi_s, F, c1, c2, u0d, d2, lo, qlo, vlo, hi, qhi, vhi, up, dn, t0 + hi
                )
                if side != 0:
                    _, vr, _ = _inside_eval(par, phi_s, F, c1, c2, u0d, d2, tr)
                    if vr * side > 0.0:
                        hit_t = tr
                        hit_side = side
                        break
                cleared = True  # no hit, or a tangential touch with zero normal velocity
            else:
                mid = 0.5 * (lo + hi)
                qm, vm, _ = _inside_eval(par, phi_s, F, c1, c2, u0d, d2, mid)
                if _hit_possible(qlo, vlo, qm, vm, mid - lo, up, dn, M4):
                    hi, qhi, vhi = mid, qm, vm
                else:
                    lo, qlo, vlo = mid, qm, vm
                cleared = False
            if cleared:
                if hi >= tb:
                    break
                lo, qlo, vlo = hi, qhi, vhi
                hi, qhi, vhi = tb, qb, vb
        if hit_side != 0:
            break
        ta, qa, va = tb, qb, vb
    if hit_side != 0:
        _, v_hit, _ = _inside_eval(par, phi_s, F, c1, c2, u0d, d2, hit_t)
        if T.shape[1] > 0:
            _inside_tangent(par, T, w, phi_s, hit_t)
        st[S_T] = t0 + hit_t if hit_t < tau_end else t_target
        st[S_Q] = w + hit_side * hp  # exactly on the wall
        st[S_V] = v_hit
        st[S_MODE] = float(hit_side)
        accumulate = flags[F_ACCUMULATE] != 0
        if accumulate:
            diag[D_EXITS] += 1.0
        _record(ev, cnt, st[S_T], st[S_Q], st[S_V], 1.0, w)
        leave_play(T, flags[F_QR_MODE])
        return
    qe, ve, _ = _inside_eval(par, phi_s, F, c1, c2, u0d, d2, tau_end)
    if T.shape[1] > 0:
        _inside_tangent(par, T, w, phi_s, tau_end)
    st[S_T] = t_target
    st[S_Q] = qe
    st[S_V] = ve


# --------------------------------------------------------------------------------------------
# on a wall: smooth nonlinear ODE, fixed-step 8th-order Runge–Kutta (with the tangent flow W1)
# --------------------------------------------------------------------------------------------
@njit(cache=True)
def _accel(par, side, t, q, v):
    """q'' on wall ``side`` (w = q − side·p/2): −2ζv − q + cos(φ0 + Ωt) + C f(w)."""
    ph = par[P_PHI0] + par[P_OMEGA] * t
    w = q - side * par[P_HP]
    return -2.0 * par[P_ZETA] * v - q + math.cos(ph) + par[P_C] * shape(par, w)


@njit(cache=True)
def _rhs(par, side, t, y, dy, k):
    """Right-hand side of (q, v) and of the k tangent columns (paper's W1) on wall ``side``."""
    dy[0] = y[1]
    dy[1] = _accel(par, side, t, y[0], y[1])
    if k > 0:
        w = y[0] - side * par[P_HP]
        kappa = par[P_C] * shape_slope(par, w)
        zeta = par[P_ZETA]
        sph = math.sin(par[P_PHI0] + par[P_OMEGA] * t)
        for j in range(k):
            b = 2 + 4 * j
            dq = y[b]
            dv = y[b + 1]
            dph = y[b + 2]
            dw = y[b + 3]
            dy[b] = dv
            dy[b + 1] = -dq - 2.0 * zeta * dv - sph * dph + kappa * dw
            dy[b + 2] = 0.0
            dy[b + 3] = dv


@njit(cache=True)
def _rk8(par, side, t, y, h, out, K, tmp, k):
    """One step of the 8th-order Dormand–Prince scheme from (t, y) over h into ``out``, with
    the k tangent columns: :func:`oscillators.engines._dop853_kernel.rk8_step` specialised to
    the columns' structure (:func:`_rk8_qv` is the same step of (q, v) alone).

    Plain reading: stage i evaluates ``K[i] = rhs(t + c_i h, y + h Σ_j a_ij K[j])`` and the step
    is ``y + h Σ_i b_i K[i]``; the sums run over the table's nonzero coefficients only, and a
    column's δφ (zero rate) and δw (the rate of δq) reuse what they equal instead of summing:
    the same bits as the generic step with half the sums per column (the generic step made the
    Lyapunov run of the erf play 1.4–1.6× slower, measured with ``benchmarks/bench_versions.py``
    conditions).
    """
    for i in range(_N_STAGES):
        s = _dop.NZ_START[i]
        e = _dop.NZ_START[i + 1]
        for r in range(2):
            acc = 0.0
            for jj in range(s, e):
                acc += RK_A[i, _dop.NZ_COL[jj]] * K[_dop.NZ_COL[jj], r]
            tmp[r] = y[r] + h * acc
        for c in range(k):
            b = 2 + 4 * c
            acc_q = 0.0
            acc_v = 0.0
            for jj in range(s, e):
                j = _dop.NZ_COL[jj]
                acc_q += RK_A[i, j] * K[j, b]
                acc_v += RK_A[i, j] * K[j, b + 1]
            tmp[b] = y[b] + h * acc_q
            tmp[b + 1] = y[b + 1] + h * acc_v
            tmp[b + 2] = y[b + 2] + h * 0.0
            tmp[b + 3] = y[b + 3] + h * acc_q
        _rhs(par, side, t + RK_C[i] * h, tmp, K[i], k)
    for r in range(2):
        acc = 0.0
        for i in _dop.NZ_B:
            acc += RK_B[i] * K[i, r]
        out[r] = y[r] + h * acc
    for c in range(k):
        b = 2 + 4 * c
        acc_q = 0.0
        acc_v = 0.0
        for i in _dop.NZ_B:
            acc_q += RK_B[i] * K[i, b]
            acc_v += RK_B[i] * K[i, b + 1]
        out[b] = y[b] + h * acc_q
        out[b + 1] = y[b + 1] + h * acc_v
        out[b + 2] = y[b + 2] + h * 0.0
        out[b + 3] = y[b + 3] + h * acc_q


@njit(cache=True)
def _rk8_qv(par, side, t, q, v, h, a0):
    """:func:`_rk8` without tangent columns, written out stage by stage: ``(q, v)`` after one
    step of length h from (t, q, v), given ``a0 = _accel(par, side, t, q, v)`` (the first stage,
    which does not depend on h: the previous step's end value, or the same for every trial
    length of the reversal search).

    The arithmetic is :func:`_rk8`'s in the same order, with the zero coefficients of the
    Dormand–Prince table left out (adding 0·K changes no bit), so the result is bit-identical
    (``tests/test_oscillators/test_play_kernel_unrolled.py``); scalars instead of the stage
    array make it about twice as fast, and the wall motion is most of a basin map's cost.
    Stage i: v_i = v + h Σ_j a_ij k_j,  k_i = _accel(t + c_i h, q + h Σ_j a_ij v_j, v_i).
    """
    v0 = v
    v1 = v + h * (RK_A[1, 0] * a0)
    a1 = _accel(par, side, t + RK_C[1] * h, q + h * (RK_A[1, 0] * v0), v1)
    v2 = v + h * (RK_A[2, 0] * a0 + RK_A[2, 1] * a1)
    a2 = _accel(par, side, t + RK_C[2] * h, q + h * (RK_A[2, 0] * v0 + RK_A[2, 1] * v1), v2)
    v3 = v + h * (RK_A[3, 0] * a0 + RK_A[3, 2] * a2)
    a3 = _accel(par, side, t + RK_C[3] * h, q + h * (RK_A[3, 0] * v0 + RK_A[3, 2] * v2), v3)
    v4 = v + h * (RK_A[4, 0] * a0 + RK_A[4, 2] * a2 + RK_A[4, 3] * a3)
    a4 = _accel(
        par,
        side,
        t + RK_C[4] * h,
        q + h * (RK_A[4, 0] * v0 + RK_A[4, 2] * v2 + RK_A[4, 3] * v3),
        v4,
    )
    v5 = v + h * (RK_A[5, 0] * a0 + RK_A[5, 3] * a3 + RK_A[5, 4] * a4)
    a5 = _accel(
        par,
        side,
        t + RK_C[5] * h,
        q + h * (RK_A[5, 0] * v0 + RK_A[5, 3] * v3 + RK_A[5, 4] * v4),
        v5,
    )
    v6 = v + h * (RK_A[6, 0] * a0 + RK_A[6, 3] * a3 + RK_A[6, 4] * a4 + RK_A[6, 5] * a5)
    a6 = _accel(
        par,
        side,
        t + RK_C[6] * h,
        q + h * (RK_A[6, 0] * v0 + RK_A[6, 3] * v3 + RK_A[6, 4] * v4 + RK_A[6, 5] * v5),
        v6,
    )
    v7 = v + h * (
        RK_A[7, 0] * a0 + RK_A[7, 3] * a3 + RK_A[7, 4] * a4 + RK_A[7, 5] * a5 + RK_A[7, 6] * a6
    )
    a7 = _accel(
        par,
        side,
        t + RK_C[7] * h,
        q
        + h
        * (RK_A[7, 0] * v0 + RK_A[7, 3] * v3 + RK_A[7, 4] * v4 + RK_A[7, 5] * v5 + RK_A[7, 6] * v6),
        v7,
    )
    v8 = v + h * (
        RK_A[8, 0] * a0
        + RK_A[8, 3] * a3
        + RK_A[8, 4] * a4
        + RK_A[8, 5] * a5
        + RK_A[8, 6] * a6
        + RK_A[8, 7] * a7
    )
    a8 = _accel(
        par,
        side,
        t + RK_C[8] * h,
        q
        + h
        * (
            RK_A[8, 0] * v0
            + RK_A[8, 3] * v3
            + RK_A[8, 4] * v4
            + RK_A[8, 5] * v5
            + RK_A[8, 6] * v6
            + RK_A[8, 7] * v7
        ),
        v8,
    )
    v9 = v + h * (
        RK_A[9, 0] * a0
        + RK_A[9, 3] * a3
        + RK_A[9, 4] * a4
        + RK_A[9, 5] * a5
        + RK_A[9, 6] * a6
        + RK_A[9, 7] * a7
        + RK_A[9, 8] * a8
    )
    a9 = _accel(
        par,
        side,
        t + RK_C[9] * h,
        q
        + h
        * (
            RK_A[9, 0] * v0
            + RK_A[9, 3] * v3
            + RK_A[9, 4] * v4
            + RK_A[9, 5] * v5
            + RK_A[9, 6] * v6
            + RK_A[9, 7] * v7
            + RK_A[9, 8] * v8
        ),
        v9,
    )
    v10 = v + h * (
        RK_A[10, 0] * a0
        + RK_A[10, 3] * a3
        + RK_A[10, 4] * a4
        + RK_A[10, 5] * a5
        + RK_A[10, 6] * a6
        + RK_A[10, 7] * a7
        + RK_A[10, 8] * a8
        + RK_A[10, 9] * a9
    )
    a10 = _accel(
        par,
        side,
        t + RK_C[10] * h,
        q
        + h
        * (
            RK_A[10, 0] * v0
            + RK_A[10, 3] * v3
            + RK_A[10, 4] * v4
            + RK_A[10, 5] * v5
            + RK_A[10, 6] * v6
            + RK_A[10, 7] * v7
            + RK_A[10, 8] * v8
            + RK_A[10, 9] * v9
        ),
        v10,
    )
    v11 = v + h * (
        RK_A[11, 0] * a0
        + RK_A[11, 3] * a3
        + RK_A[11, 4] * a4
        + RK_A[11, 5] * a5
        + RK_A[11, 6] * a6
        + RK_A[11, 7] * a7
        + RK_A[11, 8] * a8
        + RK_A[11, 9] * a9
        + RK_A[11, 10] * a10
    )
    a11 = _accel(
        par,
        side,
        t + RK_C[11] * h,
        q
        + h
        * (
            RK_A[11, 0] * v0
            + RK_A[11, 3] * v3
            + RK_A[11, 4] * v4
            + RK_A[11, 5] * v5
            + RK_A[11, 6] * v6
            + RK_A[11, 7] * v7
            + RK_A[11, 8] * v8
            + RK_A[11, 9] * v9
            + RK_A[11, 10] * v10
        ),
        v11,
    )
    q_end = q + h * (
        RK_B[0] * v0
        + RK_B[5] * v5
        + RK_B[6] * v6
        + RK_B[7] * v7
        + RK_B[8] * v8
        + RK_B[9] * v9
        + RK_B[10] * v10
        + RK_B[11] * v11
    )
    v_end = v + h * (
        RK_B[0] * a0
        + RK_B[5] * a5
        + RK_B[6] * a6
        + RK_B[7] * a7
        + RK_B[8] * a8
        + RK_B[9] * a9
        + RK_B[10] * a10
        + RK_B[11] * a11
    )
    return q_end, v_end


@njit(cache=True, inline="always")
def _wall_v(tau, args):
    """Root function of the reversal on a wall: ``(g, g') = −side·(v, a)`` after the RK8 step
    over ``tau`` from the step start (``args = (par, side, t, q, v, a0)``); g < 0 at τ = 0."""
    par, side, t, q, v, a0 = args
    qt, vt = _rk8_qv(par, side, t, q, v, tau, a0)
    return -side * vt, -side * _accel(par, side, t + tau, qt, vt)


@njit(cache=True, inline="always")
def _wall_a(tau, args):
    """Root function of a velocity dip's minimum: ``(side·a, 0)`` after the RK8 step over
    ``tau`` (no derivative: the root finder bisects)."""
    par, side, t, q, v, a0 = args
    qt, vt = _rk8_qv(par, side, t, q, v, tau, a0)
    return side * _accel(par, side, t + tau, qt, vt), 0.0


@njit(cache=True)
def _outside(par, st, t_target, T, diag, ev, cnt, flags, work):
    """Advance on a wall until t_target or the reversal v = 0 where the input re-enters.

    Plain reading: RK8 steps of length h_out; a step whose end has the velocity reversed
    contains the reversal; it is located by Newton on v(τ) where each iterate re-steps RK8
    from the step start over τ (so the located state has full RK8 accuracy). A velocity dip
    to zero and back inside one step is caught with the cubic Hermite interpolant of v.
    (q, v) are stepped by :func:`_rk8_qv`; with tangent columns the full step :func:`_rk8`
    carries them (its (q, v) are the same bits). The first stage of a step is the previous
    step's end acceleration, computed once.
    """
    side = st[S_MODE]
    hp = par[P_HP]
    k = T.shape[1]
    n = 2 + 4 * k
    # scratch of the step with tangent columns: state, step end, stage argument, stages
    y = work[0, :n]
    y1 = work[1, :n]
    tmp = work[2, :n]
    K = work[3 : 3 + _N_STAGES, :n]
    t = st[S_T]
    q = st[S_Q]
    v = st[S_V]
    if k > 0:
        y[0] = q
        y[1] = v
        for j in range(k):
            for r in range(4):
                y[2 + 4 * j + r] = T[r, j]
    a = _accel(par, side, t, q, v)
    h_out = par[P_H_OUT]
    reversal = False
    while t < t_target:
        last = t_target - t <= h_out
        h = t_target - t if last else h_out
        if k > 0:
            _rk8(par, side, t, y, h, y1, K, tmp, k)
            q1 = y1[0]
            v1 = y1[1]
        else:
            q1, v1 = _rk8_qv(par, side, t, q, v, h, a)
        a1 = 0.0
        if side * v1 <= 0.0:
            reversal = True
            lo = 0.0
            hi = h
        else:
            # a dip of v to zero and back within the step: cubic Hermite of v (a = v')
            a1 = _accel(par, side, t + h, q1, v1)
            vmax, vmin = _hermite_extrema(side * v, side * a, side * v1, side * a1, h)
            if vmin < 0.0:
                # locate the minimum of the true velocity (sign change of a: bisection, no
                # derivative at hand) and test v there
                m = find_root(_wall_a, (par, side, t, q, v, a), 0.0, h, 0.5 * h, t)
                qm, vm = _rk8_qv(par, side, t, q, v, m, a)
                if side * vm < 0.0:
                    reversal = True
                    lo = 0.0
                    hi = m
                    v1 = vm
        if reversal:
            # Newton on v(tau) inside the bracket, each iterate one RK8 step from the step start
            tau = secant_start(lo, hi, -side * v, -side * v1)
            tau = find_root(_wall_v, (par, side, t, q, v, a), lo, hi, tau, t)
            if k > 0:
                _rk8(par, side, t, y, tau, y1, K, tmp, k)
                for r in range(n):
                    y[r] = y1[r]
                q = y[0]
                v = y[1]
            else:
                q, v = _rk8_qv(par, side, t, q, v, tau, a)
            t = t + tau
            break
        if k > 0:
            for r in range(n):
                y[r] = y1[r]
        q = q1
        v = v1
        a = a1
        t = t_target if last else t + h
    st[S_Q] = q
    st[S_W] = q - side * hp
    for j in range(k):
        for r in range(4):
            T[r, j] = y[2 + 4 * j + r]
    if reversal:
        st[S_T] = t
        st[S_V] = 0.0  # the reversal: v = 0 exactly
        st[S_MODE] = 0.0
        accumulate = flags[F_ACCUMULATE] != 0
        if accumulate:
            diag[D_ENTRIES] += 1.0
        _record(ev, cnt, t, q, 0.0, -1.0, st[S_W])
        # V_in = I. A play of zero width is left at once through the opposite wall.
        if hp == 0.0:
            st[S_MODE] = 1.0 if _accel(par, side, t, q, v) > 0.0 else -1.0
            if accumulate:
                diag[D_EXITS] += 1.0
            _record(ev, cnt, t, q, 0.0, 1.0, st[S_W])
            leave_play(T, flags[F_QR_MODE])
    else:
        st[S_T] = t_target
        st[S_V] = v


# --------------------------------------------------------------------------------------------
# drivers
# --------------------------------------------------------------------------------------------
@njit(cache=True)
def advance(par, st, t_target, T, diag, ev, cnt, flags, work):
    """Advance the full state (and tangent columns) to exactly ``t_target``."""
    guard = 0
    while st[S_T] < t_target:
        if st[S_MODE] == 0.0:
            _inside(par, st, t_target, T, diag, ev, cnt, flags)
        else:
            _outside(par, st, t_target, T, diag, ev, cnt, flags, work)
        guard += 1
        if guard > 100_000_000:
            raise RuntimeError("play flow: no progress (too many events)")


def make_work(k: int) -> np.ndarray:
    """Scratch space for :func:`advance` with k tangent columns."""
    return np.zeros((3 + _N_STAGES, 2 + 4 * k))


@njit(cache=True)
def sample_kernel(par, st, times, out, T, diag, ev, cnt, flags, work):
    """Advance through ``times`` (increasing), storing q, v, w at each into ``out`` rows."""
    for i in range(times.shape[0]):
        advance(par, st, times[i], T, diag, ev, cnt, flags, work)
        out[i, 0] = st[S_Q]
        out[i, 1] = st[S_V]
        out[i, 2] = st[S_W]
