"""Analytic propagator of the linear oscillator with constant extra force.

Between two output switches of a piecewise-constant operator the paper's eq. (eom_4) is linear:

    q'' + 2ζ q' + q = cos(φ) + F,    φ' = Ω,    F = C·M_k constant.

Its solution is a particular part plus a damped homogeneous part,

    q_p(φ) = A cos φ + B sin φ + F,   A = (1 − Ω²)/D,  B = 2ζΩ/D,  D = (1 − Ω²)² + (2ζΩ)²,
    (q, v)(h) = Φ(h) [(q, v)(0) − P(φ_0)] + P(φ_0 + Ωh),   P(φ) = (q_p(φ), q_p'(φ)),

with the homogeneous propagator ``Φ(h) = exp(h·[[0, 1], [−1, −2ζ]])``, in closed form

    Φ(h) = e^{−ζh} [[c + ζ s, s], [−s, c − ζ s]],

where ``c = cos(ω_d h)``, ``s = sin(ω_d h)/ω_d`` with ``ω_d = sqrt(1 − ζ²)`` (ζ < 1), ``c = 1``,
``s = h`` (ζ = 1) and ``c = cosh(ω_h h)``, ``s = sinh(ω_h h)/ω_h`` with ``ω_h = sqrt(ζ² − 1)``
(ζ > 1). The undamped resonance ζ = 0, Ω = 1 has no bounded particular solution and is rejected.

The same closed forms give the tangent (variational) flow of a segment: ``Φ(h)`` for the
(δq, δv) block and, for a perturbation of the forcing phase, the column
``∂(q, v)(h)/∂φ_0 = P'(φ_0 + Ωh) − Φ(h) P'(φ_0)``.

The numba functions here are shared by the event-driven kernels
(``oscillators.engines._relay_kernels``); the plain functions at the bottom are the validated
public entry points.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from oscillators.parameters import DEFAULT_DAMPING_RATIO, DEFAULT_FREQUENCY, check_oscillator

__all__ = [
    "forced_response",
    "homogeneous_propagator",
    "propagate",
    "segment_jacobian",
]


@njit(cache=True)
def particular_amplitudes(zeta: float, omega: float) -> tuple[float, float]:
    """Amplitudes (A, B) of the periodic particular solution ``A cos φ + B sin φ``."""
    one_m = 1.0 - omega * omega
    two_zo = 2.0 * zeta * omega
    den = one_m * one_m + two_zo * two_zo
    return one_m / den, two_zo / den


@njit(cache=True)
def hom_cs(h: float, zeta: float) -> tuple[float, float]:
    """``e^{−ζh}·c(h)`` and ``e^{−ζh}·s(h)`` of the homogeneous propagator (see module doc)."""
    if zeta < 1.0:
        wd = math.sqrt(1.0 - zeta * zeta)
        e = math.exp(-zeta * h)
        return e * math.cos(wd * h), e * math.sin(wd * h) / wd
    if zeta == 1.0:
        e = math.exp(-h)
        return e, e * h
    # ζ > 1: eigenvalues λ₁ = −1/(ζ + ω_h) (the slow one, not ω_h − ζ: that difference of two
    # numbers ≈ ζ loses log10(ζ²) digits, 1e-4 relative at ζ = 1e6) and λ₂ = −(ζ + ω_h);
    # e^{λ₁h} − e^{λ₂h} = −e^{λ₁h}·expm1(−2ω_h h) has no cancellation for small h or ω_h
    wh = math.sqrt((zeta - 1.0) * (zeta + 1.0))
    big = zeta + wh
    a = math.exp(-h / big)
    b = math.exp(-big * h)
    return 0.5 * (a + b), -0.5 * a * math.expm1(-2.0 * wh * h) / wh


@njit(cache=True)
def hom_matrix(h: float, zeta: float) -> tuple[float, float, float, float]:
    """Entries (m00, m01, m10, m11) of ``Φ(h)``."""
    ec, es = hom_cs(h, zeta)
    return ec + zeta * es, es, -es, ec - zeta * es


@njit(cache=True)
def exact_step(
    q: float,
    v: float,
    c0: float,
    s0: float,
    c1: float,
    s1: float,
    force: float,
    h: float,
    zeta: float,
    omega: float,
    amp_a: float,
    amp_b: float,
) -> tuple[float, float]:
    """Exact (q, v) after time ``h``; (c0, s0), (c1, s1) are cos/sin of the phase at both ends."""
    qp0 = amp_a * c0 + amp_b * s0 + force
    vp0 = omega * (amp_b * c0 - amp_a * s0)
    qp1 = amp_a * c1 + amp_b * s1 + force
    vp1 = omega * (amp_b * c1 - amp_a * s1)
    m00, m01, m10, m11 = hom_matrix(h, zeta)
    x = q - qp0
    y = v - vp0
    return m00 * x + m01 * y + qp1, m10 * x + m11 * y + vp1


@njit(cache=True)
def phase_column(
    m00: float,
    m01: float,
    m10: float,
    m11: float,
    c0: float,
    s0: float,
    c1: float,
    s1: float,
    omega: float,
    amp_a: float,
    amp_b: float,
) -> tuple[float, float]:
    """``∂(q, v)(h)/∂φ_0 = P'(φ_1) − Φ(h) P'(φ_0)`` for the segment with propagator entries m."""
    g0q = amp_b * c0 - amp_a * s0
    g0v = -omega * (amp_a * c0 + amp_b * s0)
    g1q = amp_b * c1 - amp_a * s1
    g1v = -omega * (amp_a * c1 + amp_b * s1)
    return g1q - (m00 * g0q + m01 * g0v), g1v - (m10 * g0q + m11 * g0v)


# -- validated public functions ------------------------------------------------------------------
def forced_response(damping_ratio: float, frequency: float) -> tuple[float, float]:
    """Amplitudes (A, B) of the periodic response ``A cos φ + B sin φ`` to ``cos φ``."""
    zeta, omega = check_oscillator(damping_ratio, frequency)
    return particular_amplitudes(zeta, omega)


def homogeneous_propagator(h: float, damping_ratio: float) -> np.ndarray:
    """The 2×2 matrix ``Φ(h) = exp(h·[[0, 1], [−1, −2ζ]])`` (closed form)."""
    zeta, _ = check_oscillator(damping_ratio, 2.0)
    m00, m01, m10, m11 = hom_matrix(float(h), zeta)
    return np.array([[m00, m01], [m10, m11]])


def propagate(
    q: float,
    v: float,
    phi: float,
    h: float,
    force: float = 0.0,
    damping_ratio: float = DEFAULT_DAMPING_RATIO,
    frequency: float = DEFAULT_FREQUENCY,
) -> tuple[float, float, float]:
    """Exact solution of ``q'' + 2ζq' + q = cos(φ) + F``, ``φ' = Ω`` after time ``h``.

    Returns ``(q, v, φ + Ωh)``. ``force`` is the constant ``F`` (``C·M`` in the oscillator).
    """
    zeta, omega = check_oscillator(damping_ratio, frequency)
    amp_a, amp_b = particular_amplitudes(zeta, omega)
    phi1 = phi + omega * h
    q1, v1 = exact_step(
        float(q),
        float(v),
        math.cos(phi),
        math.sin(phi),
        math.cos(phi1),
        math.sin(phi1),
        float(force),
        float(h),
        zeta,
        omega,
        amp_a,
        amp_b,
    )
    return q1, v1, phi1


def segment_jacobian(
    phi: float,
    h: float,
    damping_ratio: float = DEFAULT_DAMPING_RATIO,
    frequency: float = DEFAULT_FREQUENCY,
) -> np.ndarray:
    """3×3 Jacobian of the segment flow in (q, v, φ) over time ``h`` (no switch inside)."""
    zeta, omega = check_oscillator(damping_ratio, frequency)
    amp_a, amp_b = particular_amplitudes(zeta, omega)
    m00, m01, m10, m11 = hom_matrix(float(h), zeta)
    phi1 = phi + omega * h
    pq, pv = phase_column(
        m00,
        m01,
        m10,
        m11,
        math.cos(phi),
        math.sin(phi),
        math.cos(phi1),
        math.sin(phi1),
        omega,
        amp_a,
        amp_b,
    )
    return np.array([[m00, m01, pq], [m10, m11, pv], [0.0, 0.0, 1.0]])
