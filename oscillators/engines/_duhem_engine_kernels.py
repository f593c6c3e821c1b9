"""Compiled kernels of the Duhem engine (see :mod:`oscillators.engines.compiled_duhem`).

System (paper eq. eom_2) with a Duhem operator of internal variable ``z``::

    q' = v,   v' = −2ζ v − q + cos(φ0 + Ω t) + C·y(q, z),   z' = g_d(q, z)·v,   d = sign v

``g_d`` the model's slope while the input moves in direction ``d`` and ``y`` its output
(Bouc–Wen ``MODEL_BOUC_WEN``: ``y = z``; Jiles–Atherton ``MODEL_JILES_ATHERTON``: ``z`` the
irreversible magnetisation, ``y = M(H, M_irr)``). The right-hand sides are those of
:mod:`hysteresis._duhem_kernels` (their one home); this module integrates them.

Layouts (named constants below): ``par`` (float64) ``P_ZETA`` ζ, ``P_OMEGA`` Ω, ``P_C`` C,
``P_PHI0`` φ0, ``P_H`` the RK8 step, ``P_PERIOD`` T, ``P_BOUND`` the divergence bound,
``P_T0`` the start time, then scratch (``P_TRIG_H``: the stages' forcing phases by angle
addition for steps of the usual length); ``mp`` the model's parameters in the kernel's order
(Bouc–Wen ``A, β, γ, n``; Jiles–Atherton ``M_s, a, k, c, α``); ``ist`` (int64) ``I_DIR`` d,
``I_PERIOD`` period index, ``I_EVENTS`` reversals since the start, ``I_SAMPLE`` next sample,
``I_NEV`` events in ``ev``, ``I_RECORD``, ``I_K`` tangent columns (0: off), ``I_MODEL``,
``I_STUCK`` events at zero distance in a row, ``I_BAD`` the model was evaluated where it is
ill-posed, ``I_KINKS`` kinks landed on, ``I_SIDE`` the side of the kink the current step is
on; ``st`` (float64) ``S_TAU`` time in the period,
``S_Q``, ``S_V``, ``S_Z``, ``S_HNEXT`` the next graded step behind a kink (0: none).

Tangent flow: ``Y`` (4, k), rows δq, δv, δφ (zero without the phase), δz::

    δq' = δv
    δv' = −2ζ δv − δq − sin φ δφ + C (∂y/∂q δq + ∂y/∂z δz)
    δz' = g_d δv + v (∂g/∂q δq + ∂g/∂z δz)

Events. A **reversal** ``v = 0`` switches ``d``; the vector field is continuous there (``z' =
g_d·v`` is 0 on both sides), so the saltation matrix ``I + (f₊ − f₋)nᵀ/(nᵀf₋)`` is the
identity and the tangent passes unchanged (only the coefficient ``g_d`` of ``δv`` in ``δz'``
changes). A **kink** of ``g`` (Bouc–Wen: ``z = 0``, where ``|z|ⁿ`` is not smooth) is landed on
so that no RK8 step straddles it; ``g`` is continuous there, so again no saltation. A step
whose end has ``d·v <= 0`` (or whose cubic Hermite interpolant of ``v`` dips through zero)
contains the reversal; one whose ``z`` changed sign, the kink; both are located by the
safeguarded Newton root finder (:func:`oscillators.engines._roots.find_root`) on the step's own
RK8 map, then ``v := 0`` or ``z := 0`` exactly. The step's end derivative (computed for the
velocity-dip test) is the next step's first stage.

A non-integer exponent ``n`` leaves ``|z|ⁿ`` singular at the kink even on one side (``z`` is
``~(t − t*)^(n+1)`` near it), so an RK8 step that starts or ends there errs by ``~h^(n+1)``
(measured: 8e-9 over 40 time units at n = 1.5, h = 0.05). The steps are therefore graded
geometrically on both sides: approaching, each step is half the predicted distance ``−z/z'``
down to ``h·GRADE_FIRST``, which crosses the kink and locates it; behind it the steps grow
from ``h·GRADE_FIRST`` by doubling. A step as long as its distance from the singularity errs
by ``~h_j^(n+1)`` times the RK8 error constant and a binomial coefficient ~1e-3 (negligible), so
the grading leaves the steps at the singularity itself, ``~(h·GRADE_FIRST)^(n+1)``
(about 12 extra steps per kink). Integer ``n`` is smooth on each
side: no grading.

Jiles–Atherton. The kink is the switch of ``δ_M`` (the sign of ``G = d·(M_an − M_irr)``, smooth,
the event function); at ``G = 0`` exactly (the demagnetised state, or a reversal on the
anhysteretic curve) the side is ``δ_M = 1``: with ``M_irr`` frozen ``dG/dH·d = M_an'/D > 0``.
Each side's ``δ_M`` is imposed on the stages. Deep in saturation ``G' = M_an'·v`` is small and
``G`` is known only to its rounding (a few ``ε·M_s``), so the kink is located to that band
(``_ja_gap_noise``: ``|G|`` below it counts as the root; the kink moves by band/``|G'|``, and a
stage past it errs by ``g ~ G/k`` inside the band: nothing). The relaxation of ``M_irr`` toward
``M_an`` has the rate ``λ = |v·∂g/∂M_irr|`` (about ``|v|/k``), which neither ``ρ`` nor
``max_slope`` sees: the steps keep ``h·λ <= RELAX_STEP = 1`` (a fixed step with ``h·λ ~ 6``
erred by 5e-4; at 1 and below the error is 5e-11, measured). Where the pole ``w = 1 − αχ = 0``
is reachable (:func:`hysteresis._duhem_kernels.jiles_atherton_slope_bound` is None: ``I_POLE``)
the steps on the side ``δ_M = 1`` are half the predicted time to it (``w ~ (t* − t)^{1/2}``), so
they close in geometrically; when that time (or a retried step that met the pole) is below
``POLE_STOP·h`` the run stops there with ``ILL_POSED`` (the field located to ~1e-12·|v|).

Status codes of :func:`run`: ``DONE``, ``EVENTS_FULL`` (``ev`` full: drained and called again),
``DIVERGED``, ``STUCK``, ``ILL_POSED`` (the model's slope is undefined at a state reached:
Jiles–Atherton with ``1 − α·χ <= 0``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from hysteresis._duhem_kernels import (
    bouc_wen_slope,
    jiles_atherton_margins,
    jiles_atherton_rhs,
)
from oscillators.engines import _continuous_layout as _layout
from oscillators.engines import _dop853_kernel as _dop
from oscillators.engines._play_kernels import _hermite_extrema
from oscillators.engines._relay_landings import add_time
from oscillators.engines._roots import find_root, secant_start

_N_STAGES = _dop.N_STAGES

P_ZETA, P_OMEGA, P_C, P_PHI0, P_H, P_PERIOD, P_BOUND, P_T0 = range(8)
#: scratch after the parameters (not parameters): the step ``h`` of the table (0: none), then
#: ``cos(Ω c_i h)`` and ``sin(Ω c_i h)`` of the RK8 nodes (``_stages``)
P_TRIG_H = 8
P_COS = 9
P_SIN = P_COS + _N_STAGES
N_PAR = P_SIN + _N_STAGES
I_DIR, I_PERIOD, I_EVENTS, I_SAMPLE, I_NEV, I_RECORD, I_K, I_MODEL = range(8)
I_STUCK, I_BAD, I_KINKS, I_SIDE, I_LANDED, I_POLE = range(8, 14)
N_IST = 14
S_TAU, S_Q, S_V, S_Z, S_HNEXT = range(5)
# the clock slots are the continuous engine's, so its clock arithmetic (add_time) serves both
if (P_PERIOD, I_PERIOD, S_TAU) != (_layout.P_PERIOD, _layout.I_PERIOD, _layout.S_TAU):
    raise ImportError("the Duhem kernels' clock slots must match _continuous_layout")
N_ST = 5

MODEL_BOUC_WEN = 0
MODEL_JILES_ATHERTON = 1

#: the ``kind`` of a recorded reversal (as the generic engine's)
EVENT_REVERSAL = -1

DONE = 0
EVENTS_FULL = 2
DIVERGED = 3
STUCK = 4
ILL_POSED = 6

#: the least graded step at a kink of a non-integer exponent, relative to the step (module
#: docstring): the ungraded steps at the kink err by ~h^(n+1) (8e-9 over 40 time units at
#: n = 1.5), the graded ones by (h·GRADE_FIRST)^(n+1), (2^-6)^2.5 = 3e-5 of that; 6 halvings
#: on each side (measured 1e-12 over 40 time units)
GRADE_FIRST = 2.0**-6
#: the least subnormal number: a stage state on the step's side of the kink (see _slope)
_TINY = 5e-324
#: Jiles–Atherton's scratch slots after the 5 parameters of ``mp`` (not parameters): the last
#: solve's ``M``, ``q``, ``z``, ``∂M/∂q``, ``∂M/∂z`` (the next solve starts from the linear
#: prediction ``M + ∂M/∂q·Δq + ∂M/∂z·Δz``) and ``∂g/∂z`` (the relaxation rate at a step start)
M_LAST, M_Q, M_Z, M_MQ, M_MZ, M_GZ = range(5, 11)
N_JA_MP = 11
#: Jiles–Atherton: the RK8 step times the relaxation rate ``λ = |v·∂g/∂M_irr|`` (about
#: ``|v|/k``) stays below this (module docstring)
RELAX_STEP = 1.0
#: Jiles–Atherton's pole: the predicted time to it (or a step that fails on it) below
#: ``POLE_STOP·h`` ends the run with ``ILL_POSED`` there (module docstring)
POLE_STOP = 1e-10
_EPS = 2.220446049250313e-16
#: events at zero distance in a row before STUCK
_MAX_STUCK = 50


# --------------------------------------------------------------------------------------------
# the model
# --------------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _ja(ist, mp, q, z, d, on):
    """Jiles–Atherton from one solve warm-started at the linear prediction from the last one
    (the scratch slots ``mp[M_LAST:]``, updated): ``(M, ∂M/∂q,
    ∂M/∂z, g, ∂g/∂q, ∂g/∂z)`` with ``δ_M = on``; an ill-posed point sets ``I_BAD`` (and
    gives ``g = 0``)."""
    guess = mp[M_LAST] + mp[M_MQ] * (q - mp[M_Q]) + mp[M_MZ] * (z - mp[M_Z])
    m, m_h, m_i, g, gh, gi, ok = jiles_atherton_rhs(
        q, z, d, on, mp[0], mp[1], mp[2], mp[3], mp[4], guess
    )
    mp[M_LAST] = m
    mp[M_Q] = q
    mp[M_Z] = z
    mp[M_MQ] = m_h
    mp[M_MZ] = m_i
    if not ok:
        ist[I_BAD] = 1
        mp[M_GZ] = math.inf
        return m, m_h, m_i, 0.0, 0.0, 0.0
    mp[M_GZ] = gi
    return m, m_h, m_i, g, gh, gi


@njit(cache=True, inline="always")
def _model(ist, mp, q, z, d):
    """``(y, ∂y/∂q, ∂y/∂z, g, ∂g/∂q, ∂g/∂z)``: the output and the slope in direction ``d`` on
    the side ``ist[I_SIDE]`` of the kink that the step is on (no step straddles a kink; its
    stage states may lie a little beyond it, and there each side's own smooth formula holds,
    not the other side's, whose ``∂g/∂z`` differs by a finite jump: one such stage errs the
    tangent by ``~h·b·v·jump``, measured 1e-4).

    Bouc–Wen (kink ``z = 0``): a stage beyond it is evaluated at the least subnormal number of
    the step's side (``|z|ⁿ`` is 0 there to rounding). Jiles–Atherton (kink where ``δ_M``
    switches, ``M_an = M_irr``): the side's ``δ_M`` is imposed (0: ``g = 0``; 1: the ``δ_M =
    1`` formula, smooth through the kink)."""
    side = ist[I_SIDE]
    if ist[I_MODEL] == MODEL_BOUC_WEN:
        zs = side * _TINY if side * z <= 0.0 else z
        g, gz = bouc_wen_slope(zs, d, mp[0], mp[1], mp[2], mp[3])
        return z, 0.0, 1.0, g, 0.0, gz
    return _ja(ist, mp, q, z, d, 1.0 if side > 0 else 0.0)


@njit(cache=True, inline="always")
def _slope(ist, mp, q, z, d):
    """``(g, ∂g/∂q, ∂g/∂z)`` of :func:`_model`."""
    r = _model(ist, mp, q, z, d)
    return r[3], r[4], r[5]


@njit(cache=True, inline="always")
def _regime(ist, mp, q, z, d):
    """The function whose sign tells the side of the kink, with ``(∂/∂q, ∂/∂z)``: Bouc–Wen
    ``z``; Jiles–Atherton the switch function ``G = d·(M_an − M_irr)`` (positive where ``δ_M =
    1`` for ``d``; smooth, and defined past the pole too)."""
    if ist[I_MODEL] == MODEL_BOUC_WEN:
        return z, 0.0, 1.0
    r = jiles_atherton_margins(q, z, d, mp[0], mp[1], mp[2], mp[3], mp[4], mp[M_LAST])
    return r[1], r[2], r[3]


@njit(cache=True, inline="always")
def _ja_gap_noise(mp):
    """The rounding of Jiles–Atherton's gap ``G = d·(M_s·L(x) − M_irr)``: ``M`` from the solve
    to a few ``ε·M_s/D`` (moving ``x`` by ``α/a`` times that, ``L`` by a third of it), ``L``
    to a few ε, the difference to ε·M_s: bounded by ``16ε·M_s·(1 + α·M_s/a)`` (D >= 1/3 for
    the benchmark's and most parameters; a wider band only moves the kink by band/|G'|)."""
    return 16.0 * _EPS * mp[0] * (1.0 + mp[4] * mp[0] / mp[1])


@njit(cache=True, inline="always")
def _crossed(ist, mp, q, z, d, side):
    """Whether ``(q, z)`` lies beyond the kink seen from ``side`` (Bouc–Wen: ``side·z <= 0``;
    Jiles–Atherton from ``δ_M = 0``: ``G > 0``)."""
    if ist[I_MODEL] == MODEL_BOUC_WEN:
        return side * z <= 0.0
    return _regime(ist, mp, q, z, d)[0] > 0.0


@njit(cache=True)
def _pole_distance(mp, q, v, z, zdot, d):
    """Jiles–Atherton on the side ``δ_M = 1``: the time to the pole ``w = 1 − αχ = 0``
    predicted from ``w`` and ``ẇ = w_q·v + w_z·ż`` at the state (``inf`` if ``w`` does not
    fall). Near the pole ``g ~ 1/w`` and ``w ~ (t* − t)^{1/2}`` (the branch ``H(M_irr)``
    folds there), so ``t* − t = w/(2|ẇ|)`` to leading order."""
    w, w_q, w_z = jiles_atherton_margins(q, z, d, mp[0], mp[1], mp[2], mp[3], mp[4], mp[M_LAST])[4:]
    wdot = w_q * v + w_z * zdot
    if not wdot < 0.0:
        return math.inf
    return max(w, 0.0) / (-2.0 * wdot)


@njit(cache=True, inline="always")
def _output(ist, mp, q, z):
    """``(y, ∂y/∂q, ∂y/∂z)``: the operator's output."""
    if ist[I_MODEL] == MODEL_BOUC_WEN:
        return z, 0.0, 1.0
    r = _ja(ist, mp, q, z, 1.0, 0.0)
    return r[0], r[1], r[2]


@njit(cache=True)
def output_now(ist, st, mp):
    """The operator output at the current state."""
    return _output(ist, mp, st[S_Q], st[S_Z])[0]


@njit(cache=True)
def side_now(ist, st, mp, d):
    """The side of the kink the current state is on (``I_SIDE``), or at the kink the side it
    moves into (after a kink landed on: the other side; Bouc–Wen at ``z = 0``: ``z' = A·v``,
    the side ``d``; Jiles–Atherton at ``G = 0``: ``δ_M = 1``, since with ``M_irr`` frozen
    ``dG/dH·d = M_an'/D > 0``: the gap opens at once whichever way the input moves); sets
    ``I_BAD`` where the model is ill-posed on that side."""
    r = _regime(ist, mp, st[S_Q], st[S_Z], d)[0]
    if ist[I_LANDED]:
        side = -ist[I_SIDE]
    elif r == 0.0:
        side = d if ist[I_MODEL] == MODEL_BOUC_WEN else 1
    else:
        side = 1 if r > 0.0 else -1
    ist[I_LANDED] = 0
    ist[I_SIDE] = side
    _slope(ist, mp, st[S_Q], st[S_Z], d)
    return side


# --------------------------------------------------------------------------------------------
# the RK8 step
# --------------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _rhs(par, ist, mp, Y, t, y, dy, k):
    """Right-hand side of (q, v, z) and of k tangent columns (δq, δv, δz) at time t."""
    ph = par[P_PHI0] + par[P_OMEGA] * t
    _rhs_at(par, ist, mp, Y, math.cos(ph), math.sin(ph) if k > 0 else 0.0, y, dy, k)


@njit(cache=True, inline="always")
def _rhs_at(par, ist, mp, Y, cph, sph, y, dy, k):
    """:func:`_rhs` at the forcing phase whose cosine and sine are ``cph``, ``sph``."""
    zeta = par[P_ZETA]
    c = par[P_C]
    q = y[0]
    v = y[1]
    z = y[2]
    out, yq, yz, g, gq, gz = _model(ist, mp, q, z, ist[I_DIR])
    dy[0] = v
    dy[1] = -2.0 * zeta * v - q + cph + c * out
    dy[2] = g * v
    if k > 0:
        cq = c * yq - 1.0
        cz = c * yz
        vq = v * gq
        vz = v * gz
        for j in range(k):
            dq = y[3 + 3 * j]
            dv = y[4 + 3 * j]
            dz = y[5 + 3 * j]
            dy[3 + 3 * j] = dv
            dy[4 + 3 * j] = -2.0 * zeta * dv + cq * dq + cz * dz - sph * Y[2, j]
            dy[5 + 3 * j] = g * dv + vq * dq + vz * dz


@njit(cache=True)
def _rk8(par, ist, mp, Y, t, y, h, out, K, tmp, k):
    """One 8th-order Dormand–Prince step from (t, y) over h into ``out`` (3 + 3k entries)."""
    _stages(par, ist, mp, Y, t, y, h, out, K, tmp, k, 0)


@njit(cache=True)
def _stages(par, ist, mp, Y, t, y, h, out, K, tmp, k, first):
    """The RK8 step (:func:`oscillators.engines._dop853_kernel.rk8_step`, written around its
    stage and end sums: the right-hand side takes arrays) with stages ``first``.. evaluated
    (``first = 1``: ``K[0] = f(t, y)`` is there, the previous step's end derivative)."""
    n = 3 + 3 * k
    if par[P_TRIG_H] != h:  # a step of another length (an event's): the phase of each stage
        if first == 0:
            _rhs(par, ist, mp, Y, t, y, K[0], k)
        for i in range(1, _N_STAGES):
            ti = _dop.rk8_stage(i, t, y, h, K, tmp, n)
            _rhs(par, ist, mp, Y, ti, tmp, K[i], k)
        _dop.rk8_end(y, h, K, out, n)
        return
    # the step of the table: the stages' forcing by angle addition from the step start's
    # (cos(φ + Ωc_i h) = cos φ·cos(Ωc_i h) − sin φ·sin(Ωc_i h): two trigonometric calls per
    # step instead of twelve; a few ulps, as the direct call's argument carries)
    ph = par[P_PHI0] + par[P_OMEGA] * t
    c0 = math.cos(ph)
    s0 = math.sin(ph)
    if first == 0:
        _rhs_at(par, ist, mp, Y, c0, s0, y, K[0], k)
    for i in range(1, _N_STAGES):
        _dop.rk8_stage(i, t, y, h, K, tmp, n)
        ci = par[P_COS + i]
        si = par[P_SIN + i]
        _rhs_at(par, ist, mp, Y, c0 * ci - s0 * si, s0 * ci + c0 * si, tmp, K[i], k)
    _dop.rk8_end(y, h, K, out, n)


@njit(cache=True)
def set_trig_table(par, h):
    """Fill the table of :func:`_stages` for steps of length ``h``."""
    for i in range(_N_STAGES):
        arg = par[P_OMEGA] * (_dop.C[i] * h)
        par[P_COS + i] = math.cos(arg)
        par[P_SIN + i] = math.sin(arg)
    par[P_TRIG_H] = h


# --------------------------------------------------------------------------------------------
# events
# --------------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _event_fn(tau, args):
    """Root function after the state-only RK8 step over ``tau`` from (t, y): ``which`` 0 the
    reversal ``(−d·v, −d·a)``, 1 the kink ``(−s·z, −s·z')`` (``s`` the sign of ``z`` at the
    step start); both negative at τ = 0."""
    par, ist, mp, Y, t, y, z, dz, K, tmp, which, s = args
    _rk8(par, ist, mp, Y, t, y, tau, z, K, tmp, 0)
    _rhs(par, ist, mp, Y, t + tau, z, dz, 0)
    d = ist[I_DIR]
    if which == 0:
        return -d * z[1], -d * dz[1]
    r, rq, rz = _regime(ist, mp, z[0], z[2], d)
    if ist[I_MODEL] == MODEL_JILES_ATHERTON and abs(r) <= _ja_gap_noise(mp):
        # Jiles–Atherton's gap within its rounding of zero: the kink, as closely as G tells it
        # (Newton would bounce in that noise until the bracket closed: 13 RK8 steps a kink)
        return 0.0, -s * (rq * z[1] + rz * dz[2])
    return -s * r, -s * (rq * z[1] + rz * dz[2])


@njit(cache=True, inline="always")
def _dip_fn(tau, args):
    """Root function of a velocity dip's minimum: ``(d·a, 0)`` (bisection)."""
    par, ist, mp, Y, t, y, z, dz, K, tmp, which, s = args
    _rk8(par, ist, mp, Y, t, y, tau, z, K, tmp, 0)
    _rhs(par, ist, mp, Y, t + tau, z, dz, 0)
    return ist[I_DIR] * dz[1], 0.0


@njit(cache=True)
def _args(par, ist, mp, Y, t, y, which, s, work):
    """Arguments of the root functions: the step start (t, y[:3]) copied into ``work``."""
    y3 = work[3, :3]
    y3[0] = y[0]
    y3[1] = y[1]
    y3[2] = y[2]
    K = work[4 : 4 + _N_STAGES, :3]
    return (par, ist, mp, Y, t, y3, work[0, :3], work[1, :3], K, work[2, :3], which, s)


@njit(cache=True)
def _locate(par, ist, mp, Y, t, y, hi, which, s, work):
    """Event time in (0, hi] of the step from (t, y): which 0 the reversal, 1 the kink."""
    args = _args(par, ist, mp, Y, t, y, which, s, work)
    d = ist[I_DIR]
    g_lo = -d * y[1] if which == 0 else -s * _regime(ist, mp, y[0], y[2], d)[0]
    g_hi = _event_fn(hi, args)[0]
    tau = secant_start(0.0, hi, g_lo, g_hi)
    return find_root(_event_fn, args, 0.0, hi, tau, t)


@njit(cache=True)
def _state_at(par, ist, mp, Y, t, y, tau, work):
    """The state-only RK8 step over ``tau`` from (t, y) (into ``work[0, :3]``)."""
    args = _args(par, ist, mp, Y, t, y, 0, 0.0, work)
    z = args[6]
    _rk8(par, ist, mp, Y, t, args[5], tau, z, args[8], args[9], 0)
    return z


@njit(cache=True)
def _load(st, Y, y, k):
    y[0] = st[S_Q]
    y[1] = st[S_V]
    y[2] = st[S_Z]
    for j in range(k):
        y[3 + 3 * j] = Y[0, j]
        y[4 + 3 * j] = Y[1, j]
        y[5 + 3 * j] = Y[3, j]


@njit(cache=True)
def _store(st, Y, y, k):
    st[S_Q] = y[0]
    st[S_V] = y[1]
    st[S_Z] = y[2]
    for j in range(k):
        Y[0, j] = y[3 + 3 * j]
        Y[1, j] = y[4 + 3 * j]
        Y[3, j] = y[5 + 3 * j]


@njit(cache=True)
def _record_event(par, ist, st, mp, ev):
    """Count the reversal and, when recording, write (t, q, v, kind, M, 0)."""
    ist[I_EVENTS] += 1
    if ist[I_RECORD]:
        i = ist[I_NEV]
        ev[i, 0] = par[P_T0] + ist[I_PERIOD] * par[P_PERIOD] + st[S_TAU]
        ev[i, 1] = st[S_Q]
        ev[i, 2] = st[S_V]
        ev[i, 3] = EVENT_REVERSAL
        ev[i, 4] = output_now(ist, st, mp)
        ev[i, 5] = 0.0
        ist[I_NEV] = i + 1


@njit(cache=True)
def _to_target(par, ist, mp, st, nt, taut, Y, ev, work):
    """Integrate to (period nt, time taut), handling every event on the way."""
    k = ist[I_K]
    n = 3 + 3 * k
    y = work[0, :n]
    y1 = work[1, :n]
    dy = work[2, :n]
    tmp = work[3, :n]
    K = work[4 : 4 + _N_STAGES, :n]
    loc = work[4 + _N_STAGES :, :]
    h_step = par[P_H]
    bound = par[P_BOUND]
    kinked = ist[I_MODEL] == MODEL_BOUC_WEN
    # a non-integer exponent makes |z|ⁿ singular at the kink (z ~ t^(n+1) behind it): the
    # steps on both sides are graded geometrically down to h·GRADE_FIRST (module docstring)
    graded = kinked and mp[3] != math.floor(mp[3])
    pole_stop = POLE_STOP * h_step
    cap = math.inf  # Jiles–Atherton: a step that met the pole is retried shorter (below)
    gz_end = gz_new = 0.0
    first = 0  # 1: K[0] holds f(t, y), the previous step's end derivative
    _load(st, Y, y, k)
    while True:
        rem = (nt - ist[I_PERIOD]) * par[P_PERIOD] + (taut - st[S_TAU])
        if rem <= 0.0:
            break
        if ist[I_RECORD] and ist[I_NEV] >= ev.shape[0]:
            _store(st, Y, y, k)
            return EVENTS_FULL
        h_max = h_step if st[S_HNEXT] == 0.0 else min(h_step, st[S_HNEXT])
        if graded and y[2] != 0.0:
            # approaching the kink: steps of half the predicted distance (z/z' to first
            # order), down to the least graded step, which then crosses it and locates it
            zdot = _slope(ist, mp, y[0], y[2], ist[I_DIR])[0] * y[1]
            if y[2] * zdot < 0.0:
                ahead = -y[2] / zdot
                if ahead < 2.0 * h_max:
                    h_max = max(0.5 * ahead, h_step * GRADE_FIRST)
        if not kinked:
            # Jiles–Atherton: RK8 steps resolve the relaxation of M_irr (h·λ <= RELAX_STEP);
            # with δ_M = 1 where the pole may be reached, half the predicted time to it, so
            # that they close in on it geometrically: there the run ends (module docstring)
            if first:  # K[0] = f(t, y) and gz_end = ∂g/∂z at y: the previous step's end
                zdot = K[0, 2]
                gz = gz_end
            else:
                zdot = _slope(ist, mp, y[0], y[2], ist[I_DIR])[0] * y[1]
                gz = mp[M_GZ]
            rate = abs(y[1] * gz)  # 0 on the side δ_M = 0 (the step is cut at the switch)
            if rate * h_max > RELAX_STEP:
                h_max = max(RELAX_STEP / rate, pole_stop)
            if ist[I_POLE] and ist[I_SIDE] > 0:
                ahead = _pole_distance(mp, y[0], y[1], y[2], zdot, ist[I_DIR])
                if ahead <= pole_stop:
                    ist[I_BAD] = 1
                    _store(st, Y, y, k)
                    return ILL_POSED
                h_max = min(h_max, 0.5 * ahead)
        h_max = min(h_max, cap)
        last = rem <= h_max
        h = rem if last else h_max
        t = st[S_TAU]
        d = ist[I_DIR]
        _stages(par, ist, mp, Y, t, y, h, y1, K, tmp, k, first)
        first = 0
        if not ist[I_BAD] and d * y1[1] > 0.0:
            # the end derivative: the velocity-dip test's and the next step's first stage
            _rhs(par, ist, mp, Y, t + h, y1, dy, k)
            gz_new = mp[M_GZ] if not kinked else 0.0
        if ist[I_BAD]:
            # a stage (or the end) past Jiles–Atherton's pole, which the prediction missed:
            # retry a quarter as long (K[0] = f(t, y) stays), down to the stop
            if h <= pole_stop:
                _store(st, Y, y, k)
                return ILL_POSED
            ist[I_BAD] = 0
            cap = 0.25 * h
            first = 1
            continue
        cap *= 2.0
        if not (abs(y1[0]) <= bound and abs(y1[1]) <= bound and abs(y1[2]) <= bound):
            st[S_Q] = y1[0]
            st[S_V] = y1[1]
            return DIVERGED
        kind = 0
        tau = h
        if d * y1[1] <= 0.0:
            kind = -1
        else:
            # a dip of v to zero and back within the step: cubic Hermite of d·v (a = v')
            vmax, vmin = _hermite_extrema(d * y[1], d * K[0, 1], d * y1[1], d * dy[1], h)
            if vmin < 0.0:
                args = _args(par, ist, mp, Y, t, y, 0, 0.0, loc)
                mid = find_root(_dip_fn, args, 0.0, h, 0.5 * h, t)
                if d * _state_at(par, ist, mp, Y, t, y, mid, loc)[1] <= 0.0:
                    kind = -1
                    tau = mid
        if kind == -1:
            tau = _locate(par, ist, mp, Y, t, y, tau, 0, 0.0, loc)
        side = ist[I_SIDE]
        if kinked or side < 0:
            # a kink before the step's end (or the reversal)? Bouc–Wen: z changed sign (z is
            # monotone up to the reversal: z' = g·v, g(0) = A > 0). Jiles–Atherton: δ_M
            # switched on (it switches off only at a reversal: M_irr relaxes toward M_an)
            end = y1 if kind == 0 else _state_at(par, ist, mp, Y, t, y, tau, loc)
            if _crossed(ist, mp, end[0], end[2], d, side):
                tau = _locate(par, ist, mp, Y, t, y, tau, 1, float(side), loc)
                kind = 1
        if kind == 0:
            for r in range(n):
                y[r] = y1[r]
                K[0, r] = dy[r]
            first = 1
            gz_end = gz_new
            if st[S_HNEXT] != 0.0 and h == st[S_HNEXT]:
                st[S_HNEXT] = 2.0 * h if 2.0 * h < h_step else 0.0
            if last:
                ist[I_PERIOD] = nt
                st[S_TAU] = taut
            else:
                add_time(par, ist, st, h)
            continue
        _stages(par, ist, mp, Y, t, y, tau, y1, K, tmp, k, 1)
        for r in range(n):
            y[r] = y1[r]
        add_time(par, ist, st, tau)
        if kind > 0:
            if kinked:
                y[2] = 0.0  # z := 0 exactly (the kink)
            ist[I_KINKS] += 1
            ist[I_LANDED] = 1  # the side flips (side_now)
            if graded:
                st[S_HNEXT] = h_step * GRADE_FIRST
            _store(st, Y, y, k)
            side_now(ist, st, mp, d)
        else:
            y[1] = 0.0  # v := 0 exactly; the tangent passes unchanged (module docstring)
            ist[I_DIR] = -d
            _store(st, Y, y, k)
            side_now(ist, st, mp, -d)
            _record_event(par, ist, st, mp, ev)
        ist[I_STUCK] = ist[I_STUCK] + 1 if tau == 0.0 else 0
        if ist[I_STUCK] > _MAX_STUCK:
            return STUCK
    _store(st, Y, y, k)
    return DONE


@njit(cache=True)
def run(par, ist, st, mp, nts, tauts, out, Y, ev, work):
    """Advance through the targets ``(nts[i], tauts[i])`` from sample ``ist[I_SAMPLE]`` on,
    writing ``(q, v, M)`` into ``out[i]``; returns a status code (module docstring)."""
    i = ist[I_SAMPLE]
    while i < nts.size:
        status = _to_target(par, ist, mp, st, nts[i], tauts[i], Y, ev, work)
        if status != DONE:
            return status
        out[i, 0] = st[S_Q]
        out[i, 1] = st[S_V]
        out[i, 2] = output_now(ist, st, mp)
        i += 1
        ist[I_SAMPLE] = i
    return DONE


def make_work(k: int) -> np.ndarray:
    """Scratch space of :func:`run` with k tangent columns (the last rows: event location)."""
    return np.zeros((2 * (4 + _N_STAGES), 3 + 3 * k))
