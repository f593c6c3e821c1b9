"""Numba kernels of the Bouc–Wen and Jiles–Atherton Duhem operators: the one home of their
right-hand sides (:mod:`hysteresis.bouc_wen`, :mod:`hysteresis.jiles_atherton` and the compiled
oscillator engine call these functions) and of their fast ``apply`` (:func:`integrate_record`).

Slopes (scalar float arguments; ``direction`` is ``+1.0`` rising, ``-1.0`` falling)
---------------------------------------------------------------------------------
* :func:`bouc_wen_slope` ``(z, d, A, β, γ, n) -> (g, ∂g/∂z)`` with
  ``g = A − |z|ⁿ(β·d·sign z + γ)``, ``∂g/∂z = −n|z|ⁿ⁻¹(β·d + γ·sign z)`` (one-sided at the kink
  ``z = 0``: ``sign z := d``, the side the branch moves into).
* :func:`jiles_atherton_magnetization` ``(H, M_irr, ms, a, c, α) -> (M, ∂M/∂H, ∂M/∂M_irr)``: the
  root of ``F(M) = M − (1−c)M_irr − c·M_an(H + αM)``, ``M_an(x) = ms·L(x/a)``. ``F' = 1 − αc·M_an'
  >= 1 − αc·ms/(3a) > 0`` (``max L' = 1/3``), and ``F(±ms)`` has the sign of ``±1`` when
  ``|M_irr| < ms`` (``|L| < 1``): one root, in ``[−ms, ms]``. Partials by the implicit function
  theorem: ``∂M/∂H = c·M_an'/D``, ``∂M/∂M_irr = (1−c)/D``, ``D = 1 − αc·M_an'``.
* :func:`jiles_atherton_slope` ``(H, M_irr, d, ms, a, k, c, α) -> (g, ∂g/∂H, ∂g/∂M_irr, ok)``:
  ``g = dM_irr/dH = χ_irr/(1 − αχ)`` with ``χ_irr = δ_M(M_an − M_irr)/(k·d)``,
  ``χ = (1−c)χ_irr + c·M_an'`` (all at ``H_e = H + αM``); ``ok`` is False where ``1 − αχ <= 0``
  (the model is ill-posed there; the caller raises). Partials: with ``H_e,p = ∂H_e/∂p``
  (``1/D`` for ``p = H``, ``α(1−c)/D`` for ``p = M_irr``), ``∂χ_irr/∂p = δ_M(M_an'·H_e,p −
  [p = M_irr])/(k·d)``, ``∂χ/∂p = (1−c)∂χ_irr/∂p + c·M_an''·H_e,p`` and
  ``∂g/∂p = (∂χ_irr/∂p + α·g·∂χ/∂p)/(1 − αχ)``.
* :func:`jiles_atherton_rhs` ``(H, M_irr, d, δ_M, ms, a, k, c, α, guess) -> (M, ∂M/∂H,
  ∂M/∂M_irr, g, ∂g/∂H, ∂g/∂M_irr, ok)``: both of the above from ONE solve of the output map,
  warm-started at ``guess`` (the engine passes the previous ``M``), ``δ_M`` imposed (0 or 1) or
  natural (:data:`DELTA_M_NATURAL`); the two functions above are this one, cold-started.
* :func:`jiles_atherton_margins` ``(H, M_irr, d, ms, a, k, c, α, guess) -> (M, G, G_H, G_M,
  w, w_H, w_M)``: the switch function ``G = d·(M_an − M_irr)`` (``δ_M = 1`` iff ``G > 0``) and
  the pole margin ``w = 1 − αχ`` of the ``δ_M = 1`` formula, with partials (the engine's kink
  and pole). Along a branch with ``δ_M = 1`` the gap obeys ``dG/dH_e = M_an'(H_e) − G/k`` (a
  linear ODE in ``H_e``, which is monotone while ``w > 0``), so ``G <= max(G_0, k·ms/(3a))``:
  :func:`jiles_atherton_slope_bound` turns that into ``χ <= χ_s = (1−c)·max(ms/(3a), |G_0|/k)
  + c·ms/(3a)`` and ``dM/dH = χ/(1 − αχ) <= χ_s/(1 − αχ_s)`` (``None`` if ``αχ_s >= 1``; every
  branch after a reversal starts at ``G <= 0``).

The output map is solved by Chebyshev's method on ``F`` from the guess (``m ← m − Δ − βΔ²``,
``Δ = F(m)/F'(m)``, ``β = F''(m)/(2F'(m))``; ``F'' = −(α/a)·s·L''``, ``s = αc·ms/a``),
safeguarded by the bracket ``[−ms, ms]`` (bisection where a step leaves it). Stopping rule
(explicit): with ``r`` the root and ``e = m − r``, ``|e| <= |F(m)|/D_min <= |Δ|/D_min`` (``F'``
lies in ``[D_min, 1]``, ``D_min = 1 − s/3``), ``|e − Δ| <= B₂e²/(2D_min)`` and ``Δ = e − βe² +
γe³`` with ``|γ| <= B₃/(6D_min)``, so the step errs by ``|β(e − Δ)(e + Δ) − γe³| <= K₃·|Δ|³``,
``K₃ = (B₂²(1 + 1/D_min)/4 + B₃/6)/D_min⁴``, ``B₂ = s(α/a)·max|L''|``, ``B₃ = s(α/a)²·
max|L'''|`` (``max|L''| < 0.106``, ``max|L'''| = 2/15``). The solve stops, accepting that step,
once ``K₃|Δ|³ <= ε·ms`` (or the bracket is a few ulps wide): the truncation error is then below
an ulp of ``ms`` and ``M`` carries only the rounding of ``F``, a few ``ε·ms/D``. ``L, L', L''``
at the accepted root are Taylor's from the last evaluation where the step is short, ``|δ| <=
2e-5`` (``δ = (α/a)·(m_new − m)``; to 3rd, 3rd and 2nd order, with ``L'''`` and ``L''''`` from
:func:`_langevin4`): the remainders ``L''''δ⁴/24``, ``L⁽⁵⁾δ⁴/24`` and ``L⁽⁵⁾δ³/6`` (``|L⁽⁵⁾|
<= 16/63``) are below 3.4e-16, as small as the rounding of the closed form of ``L''`` near
``|x| = 1`` (measured: within 70ε·max|L''| of a direct evaluation); a longer one evaluates
``L`` there. From a warm start within ``min((ε·ms/K₃)^{1/3}, 2e-5·a/α)`` of the root
(``1e-4·ms`` for ``ms = 1, a = 0.5, c = 0.2, α = 0.1``) that is ONE evaluation of ``L``.

The Langevin function ``L(x) = coth x − 1/x`` and its first two derivatives come from their
Taylor series ``L(x) = Σ_{j>=1} 2^{2j}B_{2j}x^{2j−1}/(2j)!`` (Bernoulli numbers; radius π) for
``|x| < 1`` — 20 terms: the remainder is below ``π^{−40}`` relative — and from the closed forms
(``coth|x| = (1+e)/(1−e)``, ``1/sinh²x = 4e/(1−e)²``, ``e = exp(−2|x|)``: no overflow) above,
where the cancellation of ``coth x`` against ``1/x`` costs at most ``3ε/x² <= 3ε`` (``15ε/x⁴`` in
``L''``).
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
from numba import njit

__all__ = [
    "DELTA_M_NATURAL",
    "bouc_wen_slope",
    "jiles_atherton_margins",
    "jiles_atherton_magnetization",
    "jiles_atherton_rhs",
    "jiles_atherton_slope",
    "jiles_atherton_slope_bound",
    "langevin",
]


def _langevin_coefficients(terms: int) -> np.ndarray:
    """``c_j = 2^{2j}B_{2j}/(2j)!``, ``j = 1..terms`` (exact Bernoulli numbers,
    Akiyama–Tanigawa)."""
    size = 2 * terms + 1
    bernoulli, row = [], [Fraction(0)] * (size + 1)
    for m in range(size + 1):
        row[m] = Fraction(1, m + 1)
        for j in range(m, 0, -1):
            row[j - 1] = j * (row[j - 1] - row[j])
        bernoulli.append(row[0])  # B_m (B_1 = +1/2, unused)
    return np.array(
        [
            float(2 ** (2 * j) * bernoulli[2 * j] / math.factorial(2 * j))
            for j in range(1, terms + 1)
        ]
    )


#: Taylor coefficients of L(x)/x in powers of x² (1/3, −1/45, 2/945, ...)
_LANGEVIN_SERIES = _langevin_coefficients(20)


@njit(cache=True)
def langevin(x: float) -> tuple[float, float, float]:
    """``(L(x), L'(x), L''(x))`` of the Langevin function ``L(x) = coth x − 1/x`` (module
    docstring: series for ``|x| < 1``, overflow-free closed forms above)."""
    if abs(x) < 1.0:
        y = x * x
        c = _LANGEVIN_SERIES
        nt = c.size
        p = c[nt - 1]
        p1 = c[nt - 1] * (2 * nt - 1)
        p2 = c[nt - 1] * (2 * nt - 1) * (2 * nt - 2)
        for j in range(nt - 2, -1, -1):
            p = p * y + c[j]
            p1 = p1 * y + c[j] * (2 * j + 1)
            if j >= 1:
                p2 = p2 * y + c[j] * (2 * j + 1) * (2 * j)
        return x * p, p1, x * p2
    s = 1.0 if x > 0.0 else -1.0
    e = math.exp(-2.0 * abs(x))
    coth = s * (1.0 + e) / (1.0 - e)
    inv_sinh2 = 4.0 * e / ((1.0 - e) * (1.0 - e))
    inv_x = 1.0 / x
    return coth - inv_x, inv_x * inv_x - inv_sinh2, 2.0 * coth * inv_sinh2 - 2.0 * inv_x**3


@njit(cache=True)
def bouc_wen_slope(
    z: float, direction: float, A: float, beta: float, gamma: float, n: float
) -> tuple[float, float]:
    """``(g, ∂g/∂z)`` of Bouc–Wen, ``g = dz/du = A − |z|ⁿ(β·d·sign z + γ)`` (module docstring)."""
    s = 1.0 if z > 0.0 else (-1.0 if z < 0.0 else 0.0)
    az = abs(z)
    g = A - az**n * (beta * direction * s + gamma)
    side = s if s != 0.0 else direction  # one-sided at the kink: the side the branch enters
    dg = -n * az ** (n - 1.0) * (beta * direction + gamma * side)
    return g, dg


#: bounds of ``|L''|``, ``|L'''|`` (the maxima: 0.10596 at ``|x| = 1.372``, ``2/15`` at 0):
#: the constant of the solve's stopping rule (module docstring)
_L2_MAX = 0.106
_L3_MAX = 2.0 / 15.0 + 1e-15
#: the longest last step ``|δx|`` across which the solve carries ``L, L', L''`` by Taylor: the
#: remainders, at most ``(16/63)·δx³/6 = 3.4e-16`` in ``L''`` and less in ``L'`` and ``L``,
#: stay at the rounding of ``L`` (module docstring)
_TAYLOR_STEP = 2e-5
_THIRD, _SIXTH = 1.0 / 3.0, 1.0 / 6.0
#: ``delta_m`` of :func:`jiles_atherton_rhs`: δ_M from the sign of the gap
DELTA_M_NATURAL = -1.0


def _derivative_series(order: int) -> np.ndarray:
    """Coefficients of ``L^(order)`` in powers of ``x²`` (times ``x`` for even ``order``):
    ``d^order/dx^order Σ_j c_j x^(2j+1)``, the terms with ``2j + 1 >= order``."""
    out = []
    for j, cj in enumerate(_LANGEVIN_SERIES):
        p = 2 * j + 1
        if p < order:
            continue
        out.append(cj * math.prod(range(p - order + 1, p + 1)))
    return np.array(out)


#: the series of ``L, L', L'', L''', L''''`` (``L = x·S0(x²)``, ``L' = S1(x²)``, ``L'' =
#: x·S2(x²)``, ``L''' = S3(x²)``, ``L'''' = x·S4(x²)``)
_S0, _S1, _S2, _S3, _S4 = (_derivative_series(n) for n in range(5))


@njit(cache=True, inline="always")
def _horner(c, y):
    p = c[c.size - 1]
    for j in range(c.size - 2, -1, -1):
        p = p * y + c[j]
    return p


@njit(cache=True)
def _langevin4(x):
    """``(L, L', L'', L''', L'''')`` at ``x``: the series below ``|x| = 1`` (each derivative's
    own from the 20 terms of ``L``: the first omitted term is below 2e-16 in ``L'''`` and 7e-15
    in ``L''''``), the closed forms above (``C = coth x``, ``S = 1/sinh²x = 4e/(1−e)²``, ``e =
    exp(−2|x|)``: ``L''' = −2S² − 4C²S + 6/x⁴``, ``L'''' = 16CS² + 8C³S − 24/x⁵``, whose
    cancellation costs up to ~300ε at ``|x| = 1``). ``L'''`` and ``L''''`` only carry ``L, L',
    L''`` across the solve's last step (``|δx| <= 2e-5``), where these errors are immaterial."""
    if abs(x) < 1.0:
        y = x * x
        return (
            x * _horner(_S0, y),
            _horner(_S1, y),
            x * _horner(_S2, y),
            _horner(_S3, y),
            x * _horner(_S4, y),
        )
    e = math.exp(-2.0 * abs(x))
    w = 1.0 / ((1.0 - e) * x)  # one division for 1/(1 − e) and 1/x
    r = x * w
    coth = (1.0 + e) * r if x > 0.0 else -(1.0 + e) * r
    sh = 4.0 * e * r * r  # 1/sinh²x
    ix = (1.0 - e) * w
    ix2 = ix * ix
    return (
        coth - ix,
        ix2 - sh,
        2.0 * coth * sh - 2.0 * ix2 * ix,
        -2.0 * sh * sh - 4.0 * coth * coth * sh + 6.0 * ix2 * ix2,
        (16.0 * sh + 8.0 * coth * coth) * coth * sh - 24.0 * ix2 * ix2 * ix,
    )


@njit(cache=True)
def _solve(h, m_irr, ms, a, c, alpha, guess):
    """``(M, D, x, L(x), L'(x), L''(x))``: the output map's root from ``guess`` (a cold start,
    one fixed-point step from ``M_irr``, where ``guess`` is NaN or outside ``[−ms, ms]``),
    ``D = F'(M) = 1 − αc·M_an'(H_e)``, ``x = H_e/a`` (module docstring: the stopping rule; the
    last step is Chebyshev's, and ``L, L', L''`` at the root are Taylor's from the last
    evaluation, so that a warm start costs one evaluation of ``L`` as a rule)."""
    base = (1.0 - c) * m_irr
    if c == 0.0 or alpha == 0.0:
        x = (h + alpha * base) / a if c == 0.0 else h / a
        lv, l1, l2 = langevin(x)
        return base + c * ms * lv, 1.0 - alpha * c * ms / a * l1, x, lv, l1, l2
    inv_a = 1.0 / a
    r = alpha * inv_a  # dx/dM
    s = c * ms * r  # F' = 1 − s·L'(x), in [D_min, 1], D_min = 1 − s/3
    d_min = 1.0 - s * _THIRD
    b2 = s * r * _L2_MAX  # max|F''|
    b3 = s * r * r * _L3_MAX  # max|F'''|
    # Chebyshev's step from m errs by <= K₃·|Δ|³ (module docstring); the test K₃|Δ|³ <= ε·ms
    # multiplied out by D_min⁵ (no division)
    k3 = b2 * b2 * (1.0 + d_min) * 0.25 + b3 * d_min * _SIXTH
    tol = 2.220446049250313e-16 * ms * (d_min * d_min) * (d_min * d_min) * d_min
    if -ms <= guess <= ms:
        m = guess
    else:
        m = base + c * ms * langevin((h + alpha * m_irr) / a)[0]
    lo, hi = -ms, ms
    for _ in range(100):
        x = (h + alpha * m) * inv_a
        lv, l1, l2, l3, l4 = _langevin4(x)
        f = m - base - c * ms * lv
        fp = 1.0 - s * l1
        if f == 0.0:
            return m, fp, x, lv, l1, l2
        if f > 0.0:
            hi = m
        else:
            lo = m
        inv_fp = 1.0 / fp
        step = f * inv_fp
        m_new = m - step + 0.5 * s * r * l2 * inv_fp * step * step  # Chebyshev: F'' = −s·r·L''
        size = abs(step)
        if k3 * size * size * size <= tol and lo <= m_new <= hi:
            # within ε·ms of the root: L and its derivatives there by Taylor from x (the
            # remainders L''''δ⁴/24, L⁽⁵⁾δ⁴/24, L⁽⁵⁾δ³/6 with |δ| <= r·|Δ|: module docstring)
            x1 = (h + alpha * m_new) * inv_a
            dx = x1 - x
            if abs(dx) <= _TAYLOR_STEP:
                lv += dx * (l1 + 0.5 * dx * (l2 + dx * _THIRD * l3))
                l1 += dx * (l2 + 0.5 * dx * (l3 + dx * _THIRD * l4))
                l2 += dx * (l3 + 0.5 * dx * l4)
            else:
                lv, l1, l2 = langevin(x1)
            return m_new, 1.0 - s * l1, x1, lv, l1, l2
        m = m_new
        if not lo < m < hi:  # the step left the bracket: bisect
            m = 0.5 * (lo + hi)
        if hi - lo <= 8.9e-16 * ms:
            break
    x = (h + alpha * m) / a
    lv, l1, l2 = langevin(x)
    return m, 1.0 - s * l1, x, lv, l1, l2


@njit(cache=True)
def jiles_atherton_rhs(
    h: float,
    m_irr: float,
    direction: float,
    delta_m: float,
    ms: float,
    a: float,
    k: float,
    c: float,
    alpha: float,
    guess: float,
) -> tuple[float, float, float, float, float, float, bool]:
    """``(M, ∂M/∂H, ∂M/∂M_irr, g, ∂g/∂H, ∂g/∂M_irr, ok)`` from one solve of the output map
    from ``guess`` (the previous ``M``: a warm start; NaN: cold). ``delta_m`` 0 or 1 imposes
    ``δ_M`` (1: the smooth δ_M = 1 formula also where rounding puts the gap on the other
    side), :data:`DELTA_M_NATURAL` takes it from the sign of ``d·(M_an − M_irr)``. ``ok``
    False (``g`` and its partials NaN) where ``1 − αχ <= 0`` (module docstring)."""
    m, d, x, lv, l1, l2 = _solve(h, m_irr, ms, a, c, alpha, guess)
    he_h = 1.0 / d  # ∂H_e/∂H (the only divisions: by D, k and 1 − αχ)
    dman = ms / a * l1
    m_h = c * dman * he_h
    m_i = (1.0 - c) * he_h
    gap = ms * lv - m_irr
    if delta_m == 0.0 or (delta_m < 0.0 and direction * gap <= 0.0):  # no irreversible change
        return m, m_h, m_i, 0.0, 0.0, 0.0, True
    ddman = ms / (a * a) * l2
    dk = direction / k  # 1/(k·d)
    chi_irr = gap * dk
    chi = (1.0 - c) * chi_irr + c * dman
    q = 1.0 - alpha * chi
    if not q > 0.0:
        return m, m_h, m_i, math.nan, math.nan, math.nan, False
    inv_q = 1.0 / q
    g = chi_irr * inv_q
    he_i = alpha * m_i
    ci_h = dman * he_h * dk
    ci_i = (dman * he_i - 1.0) * dk
    ch_h = (1.0 - c) * ci_h + c * ddman * he_h
    ch_i = (1.0 - c) * ci_i + c * ddman * he_i
    return (
        m,
        m_h,
        m_i,
        g,
        (ci_h + alpha * g * ch_h) * inv_q,
        (ci_i + alpha * g * ch_i) * inv_q,
        True,
    )


@njit(cache=True)
def jiles_atherton_margins(
    h: float,
    m_irr: float,
    direction: float,
    ms: float,
    a: float,
    k: float,
    c: float,
    alpha: float,
    guess: float,
) -> tuple[float, float, float, float, float, float, float]:
    """``(M, G, ∂G/∂H, ∂G/∂M_irr, w, ∂w/∂H, ∂w/∂M_irr)`` from one solve: the switch function
    ``G = d·(M_an − M_irr)`` (``δ_M = 1`` where it is positive; smooth, whatever the side) and
    the margin ``w = 1 − αχ`` of the ``δ_M = 1`` formula (ill-posed where ``w <= 0``), with
    ``∂G/∂p = d·(M_an'·H_e,p − [p = M_irr])`` and ``∂w/∂p = −α·∂χ/∂p`` (module docstring)."""
    m, d, x, lv, l1, l2 = _solve(h, m_irr, ms, a, c, alpha, guess)
    dman = ms / a * l1
    ddman = ms / (a * a) * l2
    gap = ms * lv - m_irr
    he_h = 1.0 / d
    he_i = alpha * (1.0 - c) / d
    big_g = direction * gap
    g_h = direction * dman * he_h
    g_i = direction * (dman * he_i - 1.0)
    chi = (1.0 - c) * big_g / k + c * dman
    ch_h = (1.0 - c) * g_h / k + c * ddman * he_h
    ch_i = (1.0 - c) * g_i / k + c * ddman * he_i
    return m, big_g, g_h, g_i, 1.0 - alpha * chi, -alpha * ch_h, -alpha * ch_i


def jiles_atherton_slope_bound(
    h: float, m_irr: float, ms: float, a: float, k: float, c: float, alpha: float
) -> float | None:
    """A bound of ``dM/dH`` on every branch of a motion from ``(H, M_irr)``, or ``None`` where
    the model may reach its pole (module docstring: ``χ <= χ_s``, ``dM/dH <= χ_s/(1 − αχ_s)``
    when ``αχ_s < 1``)."""
    gap = abs(jiles_atherton_margins(h, m_irr, 1.0, ms, a, k, c, alpha, math.nan)[1])
    top = ms / (3.0 * a)  # max M_an'
    chi = (1.0 - c) * max(top, gap / k) + c * top
    if not alpha * chi < 1.0:
        return None
    return chi / (1.0 - alpha * chi)


@njit(cache=True)
def jiles_atherton_magnetization(
    h: float, m_irr: float, ms: float, a: float, c: float, alpha: float
) -> tuple[float, float, float]:
    """``(M, ∂M/∂H, ∂M/∂M_irr)`` of the output map ``M = (1−c)M_irr + c·M_an(H + αM)``
    (module docstring; safeguarded Newton in ``[−ms, ms]`` from a cold start)."""
    m, m_h, m_i, _, _, _, _ = jiles_atherton_rhs(h, m_irr, 1.0, 0.0, ms, a, 1.0, c, alpha, math.nan)
    return m, m_h, m_i


@njit(cache=True)
def jiles_atherton_slope(
    h: float,
    m_irr: float,
    direction: float,
    ms: float,
    a: float,
    k: float,
    c: float,
    alpha: float,
) -> tuple[float, float, float, bool]:
    """``(g, ∂g/∂H, ∂g/∂M_irr, ok)`` with ``g = dM_irr/dH = χ_irr/(1 − αχ)`` (module
    docstring); ``ok`` False (and ``g`` NaN) where ``1 − αχ <= 0``."""
    _, _, _, g, g_h, g_i, ok = jiles_atherton_rhs(
        h, m_irr, direction, DELTA_M_NATURAL, ms, a, k, c, alpha, math.nan
    )
    return g, g_h, g_i, ok


# -- apply: the branch ODE along a sampled record ---------------------------------------------
#: model codes of :func:`integrate_record`; parameters ``(A, β, γ, n)`` or ``(ms, a, k, c, α)``
MODEL_BOUC_WEN = 0
MODEL_JILES_ATHERTON = 1
#: status codes of :func:`integrate_record`
STATUS_OK = 0
STATUS_ILL_POSED = 1  # the step collapsed where the slope was not ok (Jiles–Atherton's pole)
STATUS_STEP_COLLAPSE = 2  # the step collapsed elsewhere (not expected for valid parameters)
#: relative tolerance of a step (error estimate of the embedded 4th-order solution against
#: ``rtol·(|z| + z_scale)``); the propagated 5th-order solution is more accurate still
RTOL = 1e-12
_SAFETY, _MIN_FACTOR, _MAX_FACTOR = 0.9, 0.2, 5.0

# Dormand–Prince 5(4) (Dormand & Prince 1980), FSAL: the 7th stage is the next step's first
_C2, _C3, _C4, _C5 = 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0
_A21 = 1.0 / 5.0
_A31, _A32 = 3.0 / 40.0, 9.0 / 40.0
_A41, _A42, _A43 = 44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0
_A51, _A52, _A53, _A54 = 19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0
_A61, _A62, _A63 = 9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0
_A64, _A65 = 49.0 / 176.0, -5103.0 / 18656.0
_B1, _B3, _B4, _B5, _B6 = 35.0 / 384.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0
# 5th-order weights minus the embedded 4th-order ones
_E1, _E3, _E4 = 71.0 / 57600.0, -71.0 / 16695.0, 71.0 / 1920.0
_E5, _E6, _E7 = -17253.0 / 339200.0, 22.0 / 525.0, -1.0 / 40.0


@njit(cache=True)
def _rhs(model, p, u, z, d):
    """``(g, ok)`` of the model (``ok`` False past Jiles–Atherton's pole)."""
    if model == MODEL_BOUC_WEN:
        return bouc_wen_slope(z, d, p[0], p[1], p[2], p[3])[0], True
    g, _, _, ok = jiles_atherton_slope(u, z, d, p[0], p[1], p[2], p[3], p[4])
    return g, ok


@njit(cache=True)
def _dp5_step(model, p, u, z, d, h, k1):
    """One Dormand–Prince step of size ``h`` (signed) from ``(u, z)`` with first stage ``k1``:
    ``(z_new, error estimate, k7, ok)``."""
    k2, ok2 = _rhs(model, p, u + _C2 * h, z + h * _A21 * k1, d)
    k3, ok3 = _rhs(model, p, u + _C3 * h, z + h * (_A31 * k1 + _A32 * k2), d)
    k4, ok4 = _rhs(model, p, u + _C4 * h, z + h * (_A41 * k1 + _A42 * k2 + _A43 * k3), d)
    k5, ok5 = _rhs(
        model, p, u + _C5 * h, z + h * (_A51 * k1 + _A52 * k2 + _A53 * k3 + _A54 * k4), d
    )
    k6, ok6 = _rhs(
        model,
        p,
        u + h,
        z + h * (_A61 * k1 + _A62 * k2 + _A63 * k3 + _A64 * k4 + _A65 * k5),
        d,
    )
    z_new = z + h * (_B1 * k1 + _B3 * k3 + _B4 * k4 + _B5 * k5 + _B6 * k6)
    k7, ok7 = _rhs(model, p, u + h, z_new, d)
    err = h * (_E1 * k1 + _E3 * k3 + _E4 * k4 + _E5 * k5 + _E6 * k6 + _E7 * k7)
    ok = ok2 and ok3 and ok4 and ok5 and ok6 and ok7 and math.isfinite(z_new)
    return z_new, abs(err), k7, ok


@njit(cache=True)
def _kink_step(model, p, u, z, d, h, k1, z_end):
    """The step ``0 < s <= |h|`` at which the one-step map reaches ``z = 0`` (Bouc–Wen's kink;
    ``z`` and ``z_end`` have opposite signs): Illinois false position on the step length,
    stopped at ``|z(s)| <= 4ε·|z|`` or a bracket of a few ulps of ``u``."""
    lo, hi, f_lo, f_hi = 0.0, abs(h), z, z_end
    side = 0
    s = hi
    for _ in range(100):
        s = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
        f = _dp5_step(model, p, u, z, d, d * s, k1)[0]
        if abs(f) <= 8.9e-16 * abs(z) or hi - lo <= 8.9e-16 * max(abs(u), hi):
            break
        if (f > 0.0) == (f_lo > 0.0):
            lo, f_lo = s, f
            if side == -1:
                f_hi *= 0.5
            side = -1
        else:
            hi, f_hi = s, f
            if side == 1:
                f_lo *= 0.5
            side = 1
    return s


@njit(cache=True)
def _ja_gap(p, h, m_irr, d):
    """``d·(M_an(He) − M_irr)`` of Jiles–Atherton: δ_M = 1 where it is positive."""
    lv = _solve(h, m_irr, p[0], p[1], p[3], p[4], math.nan)[3]
    return d * (p[0] * lv - m_irr)


@njit(cache=True)
def _switch_point(p, u, m_irr, d, u_end):
    """The input in ``[u, u_end]`` where Jiles–Atherton's ``δ_M`` switches on at frozen
    ``M_irr`` (the last input with a non-positive gap; bisection to a few ulps). ``u`` itself
    if the gap is positive at ``u`` already."""
    if _ja_gap(p, u, m_irr, d) > 0.0:
        return u
    if _ja_gap(p, u_end, m_irr, d) <= 0.0:
        return u_end
    lo, hi = u, u_end
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid == lo or mid == hi:
            break
        if _ja_gap(p, mid, m_irr, d) > 0.0:
            hi = mid
        else:
            lo = mid
    return lo


@njit(cache=True)
def integrate_record(model, p, z_scale, u_scale, inputs, u0, z0, out):
    """Integrate ``dz/du = g_d(u, z)`` from ``(u0, z0)`` through the samples ``inputs`` (each
    increment a monotone piece, ``d`` its sign), writing ``z`` at every sample into ``out``.

    Adaptive Dormand–Prince 5(4) steps (error ``<= RTOL·(|z| + z_scale)`` per step), never
    straddling a sample, a reversal or (Bouc–Wen) the kink ``z = 0``. Returns ``(status, u, z,
    samples done)``: :data:`STATUS_OK`, or where the step collapsed below
    ``1e-13·u_scale`` (:data:`STATUS_ILL_POSED` if the slope was not ok there).
    """
    eps = 2.220446049250313e-16
    ua, za = u0, z0
    d_prev, h, k1 = 0.0, 0.0, 0.0
    atol = RTOL * z_scale
    for i in range(inputs.size):
        target = inputs[i]
        if target == ua:
            out[i] = za
            continue
        d = 1.0 if target > ua else -1.0
        if d != d_prev:  # a reversal: a new ODE, a fresh first stage and step guess
            k1, ok = _rhs(model, p, ua, za, d)
            if not ok:
                return STATUS_ILL_POSED, ua, za, i
            h = 0.05 * z_scale / max(abs(k1), 1e-300)
            d_prev = d
        rejected_not_ok = False
        while ua != target:
            span = abs(target - ua)
            last = h >= span
            step = span if last else h
            z_new, err, k7, ok = _dp5_step(model, p, ua, za, d, d * step, k1)
            norm = err / (atol + RTOL * max(abs(za), abs(z_new))) if ok else math.inf
            if not norm <= 1.0:
                rejected_not_ok = not ok
                h = step * (_MIN_FACTOR if not ok else max(_MIN_FACTOR, _SAFETY * norm**-0.2))
                if h <= 1e-13 * u_scale + 8.0 * eps * abs(ua):
                    status = STATUS_ILL_POSED if rejected_not_ok else STATUS_STEP_COLLAPSE
                    return status, ua, za, i
                continue
            factor = _MAX_FACTOR if norm == 0.0 else min(_MAX_FACTOR, _SAFETY * norm**-0.2)
            h = max(h, step * factor) if last else step * factor  # clipping does not shrink h
            if model == MODEL_BOUC_WEN and za != 0.0 and (z_new > 0.0) != (za > 0.0):
                s = _kink_step(model, p, ua, za, d, d * step, k1, z_new)
                ua = ua + d * s if s < step else target
                za = 0.0
                k1 = _rhs(model, p, ua, za, d)[0]
                continue
            if model == MODEL_JILES_ATHERTON and k1 == 0.0 and k7 != 0.0:
                # δ_M switched on inside the step (g is continuous there, g' is not): M_irr
                # is frozen up to the switch, the root of the gap at fixed M_irr; restart
                # there so that no step straddles the kink (one ulp away: accept the step)
                u_switch = _switch_point(p, ua, za, d, target if last else ua + d * step)
                if u_switch != ua:
                    ua = u_switch
                    k1 = _rhs(model, p, ua, za, d)[0]
                    continue
            ua = target if last else ua + d * step
            za = z_new
            k1 = k7
        out[i] = za
    return STATUS_OK, ua, za, inputs.size


@njit(cache=True)
def jiles_atherton_outputs(inputs, m_irr, ms, a, c, alpha, out):
    """``M`` of the output map at every sample (``out``)."""
    for i in range(inputs.size):
        out[i] = jiles_atherton_magnetization(inputs[i], m_irr[i], ms, a, c, alpha)[0]
