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
    "bouc_wen_slope",
    "jiles_atherton_magnetization",
    "jiles_atherton_slope",
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


@njit(cache=True)
def _magnetization(h, m_irr, ms, a, c, alpha):
    """``(M, D, x)``: the output map's root, ``D = 1 − αc·M_an'(H_e)``, ``x = H_e/a``."""
    base = (1.0 - c) * m_irr
    if c == 0.0 or alpha == 0.0:
        x = (h + alpha * base) / a if c == 0.0 else h / a
        lv, l1, _ = langevin(x)
        return base + c * ms * lv, 1.0 - alpha * c * ms / a * l1, x
    lo, hi = -ms, ms
    m = base + c * ms * langevin((h + alpha * m_irr) / a)[0]  # one fixed-point step from M_irr
    eps = 2.220446049250313e-16
    for _ in range(100):
        x = (h + alpha * m) / a
        lv, l1, _ = langevin(x)
        f = m - base - c * ms * lv
        d = 1.0 - alpha * c * ms / a * l1
        if f > 0.0:
            hi = m
        elif f < 0.0:
            lo = m
        else:
            return m, d, x
        step = f / d
        nxt = m - step
        if not lo < nxt < hi:  # Newton left the bracket: bisect
            nxt = 0.5 * (lo + hi)
        # F is rounded to a few ulps of ms, so M is known to ~4ε·ms/F' at best: stop there
        if abs(nxt - m) <= 4.0 * eps * ms / d or hi - lo <= 4.0 * eps * ms:
            x = (h + alpha * nxt) / a
            return nxt, 1.0 - alpha * c * ms / a * langevin(x)[1], x
        m = nxt
    return m, 1.0 - alpha * c * ms / a * langevin((h + alpha * m) / a)[1], (h + alpha * m) / a


@njit(cache=True)
def jiles_atherton_magnetization(
    h: float, m_irr: float, ms: float, a: float, c: float, alpha: float
) -> tuple[float, float, float]:
    """``(M, ∂M/∂H, ∂M/∂M_irr)`` of the output map ``M = (1−c)M_irr + c·M_an(H + αM)``
    (module docstring; safeguarded Newton in ``[−ms, ms]``, stopped at ``4ε·ms/F'``)."""
    m, d, x = _magnetization(h, m_irr, ms, a, c, alpha)
    dman = ms / a * langevin(x)[1]
    return m, c * dman / d, (1.0 - c) / d


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
    m, d, x = _magnetization(h, m_irr, ms, a, c, alpha)
    lv, l1, l2 = langevin(x)
    man = ms * lv
    dman = ms / a * l1
    ddman = ms / (a * a) * l2
    gap = man - m_irr
    if direction * gap <= 0.0:  # δ_M = 0: no irreversible change
        return 0.0, 0.0, 0.0, True
    chi_irr = gap / (k * direction)
    chi = (1.0 - c) * chi_irr + c * dman
    q = 1.0 - alpha * chi
    if not q > 0.0:
        return math.nan, math.nan, math.nan, False
    g = chi_irr / q
    he_h = 1.0 / d
    he_i = alpha * (1.0 - c) / d
    ci_h = dman * he_h / (k * direction)
    ci_i = (dman * he_i - 1.0) / (k * direction)
    ch_h = (1.0 - c) * ci_h + c * ddman * he_h
    ch_i = (1.0 - c) * ci_i + c * ddman * he_i
    return g, (ci_h + alpha * g * ch_h) / q, (ci_i + alpha * g * ch_i) / q, True
