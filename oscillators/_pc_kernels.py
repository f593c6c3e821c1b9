"""Numba kernels of the event-driven integrator for piecewise-constant operators.

The system is ``q'' + 2ζq' + q = cos φ + C·M``, ``φ' = Ω``, with ``M`` constant between switches.
Time is kept as (period index ``n``, time ``τ`` since the start of the period, ``0 <= τ < T``,
``T = 2π/Ω``) so that the forcing phase ``φ = φ_0 + Ωτ`` never loses digits on long runs.

Equal-width discrete Preisach models (all relays of one width, e.g. the paper's spin dimers) are
handled in O(1) per switch: the relays are grouped by equal thresholds and sorted by centre; the
state is one index ``k`` = number of up groups; the next up threshold is ``up[k]`` (switch when
``q >= up[k]``), the next down threshold ``down[k-1]`` (switch when ``q < down[k-1]``).

Plain-Python reading of one hop (``_advance``)::

    F = C*M[k]; derivatives d_n of q at the current point from the equation of motion
    if the next threshold in the direction of v is predicted within h_T (linear estimate) :
        Newton on the Taylor polynomial  sum d_n h^n/n! = threshold  -> h
        if |sum_{n>=2} d_n h^(n-1)/(n-1)!| < |v|/2 (q provably monotone on [0, h]):
            advance by Taylor (phase by a rotation), switch (or stop first)
    otherwise (long flight, turning point):
        scan [0, H] in sub-intervals with the exact propagator; inside each sub-interval split at
        the zero of q'' and at the zero of v, so q is monotone between checkpoints; the first
        checkpoint at or past a threshold brackets the crossing, found by safeguarded Newton
        on the exact solution.
    at a switch: q := threshold exactly, k += ±1, tangent vectors get the saltation
        δv += C·ΔM/v* · δq  (paper eq. salt_matrix)

Grazing: crossings are decided on the computed extrema. A maximum that reaches ``up`` (``>=``)
switches (the relay convention ``u >= α``); a minimum that only touches ``down`` (``== down``)
does not (the relay needs ``u < β``). A crossing that happens and undoes itself inside one
sub-interval is found because every interior extremum is a checkpoint. A degenerate double zero of
q'' inside one sub-interval (length 0.1/max(1, Ω)) is not resolved; it needs |v| and |q''| both
tiny at once.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from oscillators.linear import exact_step, hom_matrix, phase_column

#: Taylor order of the short-hop expansion (error term h^9/9! ≈ 1e-21 at h = 0.02).
ORDER = 8
_IFAC = np.array([1.0 / math.factorial(n) for n in range(ORDER + 2)])

# parameter vector layout
P_ZETA, P_OMEGA, P_C, P_PHI0, P_A, P_B, P_T, P_HT, P_DSUB, P_TBASE = range(10)
N_PAR = 10
# float state layout: q, v, tau, cos(phi), sin(phi)
S_Q, S_V, S_TAU, S_COS, S_SIN = range(5)
# int state layout: k (index), n (period), number of switches so far
I_K, I_N, I_NSW = range(3)


def make_params(
    zeta: float,
    omega: float,
    coupling: float,
    phi0: float,
    amp_a: float,
    amp_b: float,
    t_base: float,
    taylor: bool = True,
) -> np.ndarray:
    """Pack the parameter vector used by the kernels."""
    par = np.zeros(N_PAR)
    par[P_ZETA] = zeta
    par[P_OMEGA] = omega
    par[P_C] = coupling
    par[P_PHI0] = phi0
    par[P_A] = amp_a
    par[P_B] = amp_b
    par[P_T] = 2.0 * math.pi / omega
    par[P_HT] = (0.02 / max(1.0, omega)) if taylor else 0.0
    par[P_DSUB] = 0.1 / max(1.0, omega)
    par[P_TBASE] = t_base
    return par


def taylor_matrix_coefficients(zeta: float) -> np.ndarray:
    """Rows n = 0..ORDER: entries of A^n/n! with A = [[0, 1], [-1, -2ζ]] (flattened 2×2)."""
    a = np.array([[0.0, 1.0], [-1.0, -2.0 * zeta]])
    out = np.empty((ORDER + 1, 4))
    p = np.eye(2)
    for n in range(ORDER + 1):
        out[n] = (p / math.factorial(n)).ravel()
        p = p @ a
    return out


@njit(cache=True)
def _taylor_coeffs(q, v, c, s, force, zeta, omega, e):
    """e[n] = q^(n)(0)/n! from the equation of motion (forcing derivatives by rotation)."""
    e[0] = q
    e[1] = v
    dm2 = q
    dm1 = v
    w = 1.0
    for n in range(ORDER - 1):
        m = n & 3
        if m == 0:
            f = w * c
        elif m == 1:
            f = -w * s
        elif m == 2:
            f = -w * c
        else:
            f = w * s
        d = -2.0 * zeta * dm1 - dm2 + f
        if n == 0:
            d += force
        e[n + 2] = d * _IFAC[n + 2]
        dm2 = dm1
        dm1 = d
        w *= omega


@njit(cache=True)
def _poly2(e, h):
    """Value and derivative of sum e[n] h^n."""
    p = e[ORDER]
    dp = ORDER * e[ORDER]
    for n in range(ORDER - 1, 0, -1):
        p = p * h + e[n]
        dp = dp * h + n * e[n]
    p = p * h + e[0]
    return p, dp


@njit(cache=True)
def _slope_bound(e, h):
    """Bound of |v(s) - v(0)| on [0, h]: sum_{n>=2} n |e_n| h^(n-1)."""
    b = 0.0
    hp = h
    for n in range(2, ORDER + 1):
        b += n * abs(e[n]) * hp
        hp *= h
    return b


@njit(cache=True)
def _excursion_bound(e, h):
    """Bound of |q(s) - q(0)| on [0, h]: sum_{n>=1} |e_n| h^n."""
    b = 0.0
    hp = h
    for n in range(1, ORDER + 1):
        b += abs(e[n]) * hp
        hp *= h
    return b


@njit(cache=True)
def _rotation(x):
    """cos x, sin x by their Taylor series (|x| <= 0.02: error below 1e-20)."""
    x2 = x * x
    cx = 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0)))
    sx = x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0))))
    return cx, sx


@njit(cache=True)
def _eval(par, force, q0, v0, c0, s0, tau0, h):
    """Exact q, v, q'', q''' at time h after (q0, v0) at period time tau0."""
    zeta = par[P_ZETA]
    omega = par[P_OMEGA]
    ph = par[P_PHI0] + omega * (tau0 + h)
    c1 = math.cos(ph)
    s1 = math.sin(ph)
    q, v = exact_step(q0, v0, c0, s0, c1, s1, force, h, zeta, omega, par[P_A], par[P_B])
    a = -2.0 * zeta * v - q + c1 + force
    j = -2.0 * zeta * a - v - omega * s1
    return q, v, a, j


@njit(cache=True)
def _root(par, force, q0, v0, c0, s0, tau0, kind, target, lo, hi, flo):
    """Zero of f on [lo, hi] (sign change), f = q - target (kind 0), v (kind 1), q'' (kind 2).

    Safeguarded Newton: bisection whenever the Newton step leaves the bracket.
    """
    t = 0.5 * (lo + hi)
    neg_lo = flo < 0.0
    for _ in range(200):
        q, v, a, j = _eval(par, force, q0, v0, c0, s0, tau0, t)
        if kind == 0:
            f = q - target
            df = v
        elif kind == 1:
            f = v
            df = a
        else:
            f = a
            df = j
        if f == 0.0:
            return t
        if (f < 0.0) == neg_lo:
            lo = t
        else:
            hi = t
        tn = t - f / df if df != 0.0 else 0.5 * (lo + hi)
        if not (lo < tn < hi):
            tn = 0.5 * (lo + hi)
        if abs(tn - t) <= 2e-16 * max(1.0, abs(t)) or hi - lo <= 4e-16 * max(1.0, hi):
            return tn
        t = tn
    return t


@njit(cache=True)
def _check_point(par, force, q0, v0, c0, s0, tau0, tp, qp, tn, qn, up, down):
    """Crossing on the monotone stretch [tp, tn]? Returns (time, +1/-1) or (-1, 0)."""
    if qn >= up:
        return _root(par, force, q0, v0, c0, s0, tau0, 0, up, tp, tn, qp - up), 1
    if qn < down:
        return _root(par, force, q0, v0, c0, s0, tau0, 0, down, tp, tn, qp - down), -1
    return -1.0, 0


@njit(cache=True)
def _check_piece(par, force, q0, v0, c0, s0, tau0, t1, q1, v1, t2, q2, v2, up, down):
    """[t1, t2] with monotone v: checkpoints at the zero of v (extremum of q) and at t2."""
    if v1 * v2 < 0.0:
        tv = _root(par, force, q0, v0, c0, s0, tau0, 1, 0.0, t1, t2, v1)
        qv, _, _, _ = _eval(par, force, q0, v0, c0, s0, tau0, tv)
        hc, d = _check_point(par, force, q0, v0, c0, s0, tau0, t1, q1, tv, qv, up, down)
        if d != 0:
            return hc, d
        return _check_point(par, force, q0, v0, c0, s0, tau0, tv, qv, t2, q2, up, down)
    return _check_point(par, force, q0, v0, c0, s0, tau0, t1, q1, t2, q2, up, down)


@njit(cache=True)
def scan_crossing(par, force, q0, v0, c0, s0, tau0, horizon, up, down):
    """First time in (0, horizon] with q >= up or q < down on the exact segment solution.

    Returns (time, direction) with direction +1 (up), -1 (down) or 0 (none; time = horizon).
    (c0, s0) must be cos/sin of the phase at tau0.
    """
    zeta = par[P_ZETA]
    dsub = par[P_DSUB]
    tl = 0.0
    ql = q0
    vl = v0
    al = -2.0 * zeta * v0 - q0 + c0 + force
    while tl < horizon:
        tr = tl + dsub
        if tr > horizon or horizon - tr < 0.25 * dsub:
            tr = horizon
        qr, vr, ar, _ = _eval(par, force, q0, v0, c0, s0, tau0, tr)
        if al * ar < 0.0:
            ta = _root(par, force, q0, v0, c0, s0, tau0, 2, 0.0, tl, tr, al)
            qa, va, _, _ = _eval(par, force, q0, v0, c0, s0, tau0, ta)
            hc, d = _check_piece(par, force, q0, v0, c0, s0, tau0, tl, ql, vl, ta, qa, va, up, down)
            if d != 0:
                return hc, d
            hc, d = _check_piece(par, force, q0, v0, c0, s0, tau0, ta, qa, va, tr, qr, vr, up, down)
        else:
            hc, d = _check_piece(par, force, q0, v0, c0, s0, tau0, tl, ql, vl, tr, qr, vr, up, down)
        if d != 0:
            return hc, d
        tl = tr
        ql = qr
        vl = vr
        al = ar
    return horizon, 0


@njit(cache=True)
def _tangent_update(y, ntan, m00, m01, m10, m11, pq, pv):
    for j in range(ntan):
        dq = y[0, j]
        dv = y[1, j]
        dphi = y[2, j]
        y[0, j] = m00 * dq + m01 * dv + pq * dphi
        y[1, j] = m10 * dq + m11 * dv + pv * dphi


@njit(cache=True)
def advance(
    par, up_thr, down_thr, mval, st, ist, tau_stop, tan_on, y, ntan, e, mp, rec_on, sw, sw_count
):
    """Advance the equal-width kernel state (st, ist) to period time ``tau_stop``.

    Switch records go to ``sw`` (rows: time, q, v, ΔM) while ``rec_on``; returns 1 if that buffer
    filled up (state left right after the last recorded switch, call again to continue), else 0.
    Tangent vectors (columns of ``y``, rows δq, δv, δφ) are propagated while ``tan_on``.
    """
    zeta = par[P_ZETA]
    omega = par[P_OMEGA]
    coupling = par[P_C]
    phi0 = par[P_PHI0]
    amp_a = par[P_A]
    amp_b = par[P_B]
    period = par[P_T]
    h_taylor = par[P_HT]
    n_groups = up_thr.shape[0]
    cap = sw.shape[0]
    q = st[S_Q]
    v = st[S_V]
    tau = st[S_TAU]
    c = st[S_COS]
    s = st[S_SIN]
    k = ist[I_K]
    nsw = ist[I_NSW]
    status = 0
    while True:
        horizon = tau_stop - tau
        if horizon <= 0.0:
            break
        force = coupling * mval[k]
        up = up_thr[k] if k < n_groups else np.inf
        down = down_thr[k - 1] if k > 0 else -np.inf
        mode = 0  # 1 Taylor hop to a switch, 2 Taylor hop to the stop, 0 exact flight
        h = 0.0
        theta = 0.0
        tdir = 0
        if h_taylor > 0.0:
            _taylor_coeffs(q, v, c, s, force, zeta, omega, e)
            av = abs(v)
            if v > 0.0:
                tdir = 1
                theta = up
                gap = up - q
            elif v < 0.0:
                tdir = -1
                theta = down
                gap = q - down
            else:
                gap = np.inf
            disc = v * v + 4.0 * tdir * e[2] * gap
            if gap < h_taylor * av and disc > 0.0:
                # start from the root of the quadratic Taylor polynomial (stable form), then
                # Newton; stop once the next Newton error (~ |q''|/(2|v|) dh^2) is below 1e-17
                h = 2.0 * gap / (av + math.sqrt(disc))
                curv = abs(e[2]) + abs(e[3]) * h
                converged = False
                for _ in range(8):
                    p, dp = _poly2(e, h)
                    dh = (p - theta) / dp
                    h -= dh
                    if dh * dh * curv <= 1e-17 * av:
                        converged = True
                        break
                if converged and 0.0 < h <= h_taylor and _slope_bound(e, h) < 0.5 * av:
                    mode = 1 if h <= horizon else 2
            if mode == 0 and horizon <= h_taylor:
                b = _excursion_bound(e, horizon)
                if q + b < up and q - b >= down:
                    mode = 2
        direction = 0
        if mode != 0:
            hh = h if mode == 1 else horizon
            p, dp = _poly2(e, hh)
            cx, sx = _rotation(omega * hh)
            c1 = c * cx - s * sx
            s1 = s * cx + c * sx
            if tan_on:
                m00 = mp[ORDER, 0]
                m01 = mp[ORDER, 1]
                m10 = mp[ORDER, 2]
                m11 = mp[ORDER, 3]
                for n in range(ORDER - 1, -1, -1):
                    m00 = m00 * hh + mp[n, 0]
                    m01 = m01 * hh + mp[n, 1]
                    m10 = m10 * hh + mp[n, 2]
                    m11 = m11 * hh + mp[n, 3]
                pq = 0.0
                pv = 0.0
                if ntan == 3:
                    pq, pv = phase_column(m00, m01, m10, m11, c, s, c1, s1, omega, amp_a, amp_b)
                _tangent_update(y, ntan, m00, m01, m10, m11, pq, pv)
            c = c1
            s = s1
            v = dp
            if mode == 2:
                q = p
                tau = tau_stop
                break
            q = theta
            tau += hh
            direction = tdir
        else:
            ph = phi0 + omega * tau
            c = math.cos(ph)
            s = math.sin(ph)
            hc, direction = scan_crossing(par, force, q, v, c, s, tau, horizon, up, down)
            hh = hc if direction != 0 else horizon
            ph1 = phi0 + omega * (tau + hh)
            c1 = math.cos(ph1)
            s1 = math.sin(ph1)
            q1, v1 = exact_step(q, v, c, s, c1, s1, force, hh, zeta, omega, amp_a, amp_b)
            if tan_on:
                m00, m01, m10, m11 = hom_matrix(hh, zeta)
                pq = 0.0
                pv = 0.0
                if ntan == 3:
                    pq, pv = phase_column(m00, m01, m10, m11, c, s, c1, s1, omega, amp_a, amp_b)
                _tangent_update(y, ntan, m00, m01, m10, m11, pq, pv)
            c = c1
            s = s1
            v = v1
            if direction == 0:
                q = q1
                tau = tau_stop
                break
            q = up if direction > 0 else down
            tau += hh
        # the switch: every relay of the group flips at once
        k_old = k
        k += direction
        jump = mval[k] - mval[k_old]
        if tan_on:
            # saltation X = [[1,0,0],[C ΔM / v*, 1, 0],[0,0,1]]
            sal = coupling * jump / v if v != 0.0 else np.inf
            for j in range(ntan):
                y[1, j] += sal * y[0, j]
        nsw += 1
        if rec_on:
            i = sw_count[0]
            sw[i, 0] = par[P_TBASE] + ist[I_N] * period + tau
            sw[i, 1] = q
            sw[i, 2] = v
            sw[i, 3] = jump
            sw_count[0] = i + 1
            if i + 1 >= cap:
                status = 1
                break
    st[S_Q] = q
    st[S_V] = v
    st[S_TAU] = tau
    st[S_COS] = c
    st[S_SIN] = s
    ist[I_K] = k
    ist[I_NSW] = nsw
    return status


@njit(cache=True)
def _wrap(par, st, ist):
    st[S_TAU] = 0.0
    st[S_COS] = math.cos(par[P_PHI0])
    st[S_SIN] = math.sin(par[P_PHI0])
    ist[I_N] += 1


@njit(cache=True)
def run_targets(
    par,
    up_thr,
    down_thr,
    mval,
    st,
    ist,
    tgt_n,
    tgt_tau,
    i_start,
    out,
    rec_on,
    sw,
    sw_count,
):
    """Advance through the targets (period index, period time); row i of ``out`` = (q, v, M).

    Returns (status, next target index); status 1 means the switch buffer is full.
    """
    e = np.empty(ORDER + 1)
    y = np.zeros((3, 3))
    mp = np.zeros((ORDER + 1, 4))
    period = par[P_T]
    for i in range(i_start, tgt_n.shape[0]):
        while ist[I_N] < tgt_n[i]:
            status = advance(
                par,
                up_thr,
                down_thr,
                mval,
                st,
                ist,
                period,
                False,
                y,
                0,
                e,
                mp,
                rec_on,
                sw,
                sw_count,
            )
            if status != 0:
                return status, i
            _wrap(par, st, ist)
        status = advance(
            par,
            up_thr,
            down_thr,
            mval,
            st,
            ist,
            tgt_tau[i],
            False,
            y,
            0,
            e,
            mp,
            rec_on,
            sw,
            sw_count,
        )
        if status != 0:
            return status, i
        out[i, 0] = st[S_Q]
        out[i, 1] = st[S_V]
        out[i, 2] = mval[ist[I_K]]
    return 0, tgt_n.shape[0]


@njit(cache=True)
def _gram_schmidt(y, ntan, lsum):
    """Modified Gram-Schmidt on the first ntan columns; adds log of the R diagonal to lsum."""
    for j in range(ntan):
        for i in range(j):
            d = y[0, i] * y[0, j] + y[1, i] * y[1, j] + y[2, i] * y[2, j]
            y[0, j] -= d * y[0, i]
            y[1, j] -= d * y[1, i]
            y[2, j] -= d * y[2, i]
        nrm = math.sqrt(y[0, j] ** 2 + y[1, j] ** 2 + y[2, j] ** 2)
        lsum[j] += math.log(nrm) if nrm > 0.0 else -np.inf
        if nrm > 0.0:
            y[0, j] /= nrm
            y[1, j] /= nrm
            y[2, j] /= nrm


@njit(cache=True)
def run_tangent(
    par,
    up_thr,
    down_thr,
    mval,
    st,
    ist,
    tgt_n,
    tgt_tau,
    tgt_elapsed,
    hist_flag,
    i_start,
    y,
    ntan,
    mp,
    lsum,
    hist,
    hist_count,
    do_qr,
):
    """Tangent flow through the targets; at each target QR (if do_qr) and optional history row.

    ``hist`` rows receive lsum/elapsed at targets with ``hist_flag``. Returns next target index.
    """
    e = np.empty(ORDER + 1)
    sw = np.zeros((1, 4))
    swc = np.zeros(1, dtype=np.int64)
    period = par[P_T]
    for i in range(i_start, tgt_n.shape[0]):
        while ist[I_N] < tgt_n[i]:
            advance(
                par, up_thr, down_thr, mval, st, ist, period, True, y, ntan, e, mp, False, sw, swc
            )
            _wrap(par, st, ist)
        advance(
            par, up_thr, down_thr, mval, st, ist, tgt_tau[i], True, y, ntan, e, mp, False, sw, swc
        )
        if do_qr:
            _gram_schmidt(y, ntan, lsum)
        if hist_flag[i]:
            r = hist_count[0]
            for j in range(ntan):
                hist[r, j] = lsum[j] / tgt_elapsed[i]
            hist_count[0] = r + 1
    return tgt_n.shape[0]
