"""Filippov sliding on a relay threshold: the closed form the relay engines integrate.

A group of zero-width relays at one threshold ``θ`` (``Relay(θ, θ)``, the reversible flips of
non-hysteretic dimers, diagonal relays of a discrete Preisach model) switches both ways at
``θ``: the output is ``m_lo`` with the group down (``q < θ``) and ``m_hi`` with it up
(``q >= θ``). When the flow pushes into ``θ`` from both sides — ``q'' > 0`` with ``m_lo``,
``q'' < 0`` with ``m_hi`` (only possible for ``C < 0`` when the group's weights are positive) — the exact relay motion chatters
across ``θ`` with excursions that shrink towards the set ``q = θ, v = 0``; the Filippov solution
(the limit of the chattering, and of every regularisation of the relay) *slides* along it.

Sliding motion (plain reading)::

    q = θ, v = 0; q'' = −2ζv − q + cos φ + C·M = 0 gives the equivalent control
        M_eq(t) = (θ − cos φ(t)) / C
    valid while m_lo < M_eq < m_hi (strictly inside the range the group can produce);
    exit at the first φ ahead with cos φ = θ − C·m_end, m_end ∈ {m_lo, m_hi} (closed form:
        φ = ±arccos(θ − C·m_end) mod 2π); the motion then continues with the group at m_end
        (q leaves θ on the side where that output is the relay law's);
    ∫ M dt over a slide from φ_a to φ_b (time Δ) = (θ·Δ − (sin φ_b − sin φ_a)/Ω) / C.
    If neither θ − C·m_lo nor θ − C·m_hi lies in [−1, 1] the slide never ends.

Entering the slide (``should_slide``): at a switch that reverses the previous switch at the
same threshold with the opposite jump (so the switching group is zero-width), when the flow
pushes in from both sides and the excursion just begun lasts ``2|v|/|q''| <=`` the engine's
``slide_hop`` (:data:`~oscillators.engines.base.SLIDE_EXCURSION`/ρ), the state is set on the
sliding set (``v := 0``). The exact chattering converges to the slide; setting ``v := 0`` at
that point changes ``v`` by ``|v| <= ½|q''|·slide_hop`` and ``q`` not at all (the switch is
on ``θ``), and the chattering motion stays within ``v²/(2|q''|)`` of ``θ`` around the slide.

Tangent flow through a slide: every orbit that reaches the sliding set is on ``q = θ, v = 0``
whatever its deviation, so entering a slide sets ``δq = δv = 0`` (rank drops by two: the
directions collapse, ``λ = −∞``); the exit phase depends on nothing but the phase, so ``δφ``
carries through; at the exit ``(v, q'') = (0, 0)``, so a phase shift moves the state by
``ẋ·δφ/Ω = 0`` and ``(δq, δv)`` leave the slide at zero.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "SLIDE_DTYPE",
    "equivalent_output",
    "pushes_in",
    "slide_exit",
    "slide_integral",
    "should_slide",
]

#: Fields of ``records()["slides"]`` of the relay engines: ``kind`` +1 slide-in, −1 slide-out;
#: time, the threshold q, v (the speed set to 0 at slide-in) and the output M at that instant.
SLIDE_DTYPE = np.dtype([("time", "f8"), ("q", "f8"), ("v", "f8"), ("kind", "i1"), ("M", "f8")])


def equivalent_output(theta: float, coupling: float, cos_phi: float) -> float:
    """``M_eq = (θ − cos φ)/C``: the output that keeps ``q = θ, v = 0``."""
    return (theta - cos_phi) / coupling


def pushes_in(
    q: float,
    v: float,
    cos_phi: float,
    zeta: float,
    coupling: float,
    m_below: float,
    m_above: float,
) -> bool:
    """The flow pushes into ``q`` from both sides: ``q'' > 0`` with the output ``m_below`` of
    the group down (``q < θ``) and ``q'' < 0`` with the output ``m_above`` of the group up."""
    base = cos_phi - q - 2.0 * zeta * v
    return base + coupling * m_below > 0.0 and base + coupling * m_above < 0.0


def should_slide(
    q: float,
    v: float,
    cos_phi: float,
    zeta: float,
    coupling: float,
    m_below: float,
    m_above: float,
    m_now: float,
    slide_hop: float,
) -> bool:
    """Set the motion on the sliding set now (see the module docstring): the flow pushes in
    from both sides and the excursion with the output ``m_now`` lasts at most ``slide_hop``."""
    if not pushes_in(q, v, cos_phi, zeta, coupling, m_below, m_above):
        return False
    a_now = cos_phi - q - 2.0 * zeta * v + coupling * m_now
    return 2.0 * abs(v) <= slide_hop * abs(a_now)


def slide_exit(
    phi: float, theta: float, coupling: float, m_lo: float, m_hi: float, omega: float
) -> tuple[float, float]:
    """Time from phase ``phi`` (mod 2π) to the end of the slide and the output there.

    Returns ``(delta, m_end)``: the first ``delta >= 0`` at which ``M_eq`` reaches ``m_lo`` or
    ``m_hi`` (``cos(phi + Ω·delta) = θ − C·m_end``), ``(inf, nan)`` if it never does. An
    ``M_eq`` already at or beyond an end exits at once (``delta = 0``).
    """
    m_now = equivalent_output(theta, coupling, math.cos(phi))
    if m_now <= m_lo:
        return 0.0, m_lo
    if m_now >= m_hi:
        return 0.0, m_hi
    two_pi = 2.0 * math.pi
    best, m_end = math.inf, math.nan
    for m in (m_lo, m_hi):
        x = theta - coupling * m
        if not -1.0 <= x <= 1.0:
            continue
        a = math.acos(x)
        for target in (a, two_pi - a):
            d = math.fmod(target - phi, two_pi)
            if d < 0.0:
                d += two_pi
            if d < best:
                best, m_end = d, m
    return (best / omega, m_end) if math.isfinite(best) else (math.inf, math.nan)


def slide_integral(
    theta: float, coupling: float, omega: float, sin_a: float, sin_b: float, delta: float
) -> float:
    """``∫ M_eq dt`` over a slide of length ``delta`` from phase a to phase b (their sines)."""
    return (theta * delta - (sin_b - sin_a) / omega) / coupling
