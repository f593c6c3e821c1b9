"""Filippov sliding on a relay threshold: the closed form the relay engines integrate.

A group of zero-width relays at one threshold ``θ`` (``Relay(θ, θ)``, the reversible flips of
non-hysteretic dimers, diagonal relays of a discrete Preisach model) switches both ways at
``θ``: the output is ``m_lo`` with the group down (``q < θ``) and ``m_hi`` with it up
(``q >= θ``). When the flow pushes into ``θ`` from both sides — ``q'' > 0`` with ``m_lo``,
``q'' < 0`` with ``m_hi`` (with positive weights only possible for ``C < 0``) — the exact
relay motion chatters across ``θ`` with excursions that shrink towards the set
``q = θ, v = 0``; the Filippov solution (the limit of the chattering, and of every
regularisation of the relay) *slides* along it.

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

from oscillators.engines import _relay_kernels as kern
from oscillators.engines.base import (
    SLIDE_EXCURSION,
    SWITCH_BUDGET_FLOOR,
    SWITCHES_PER_RELAY_AND_TIME,
    SlidingError,
    SwitchBudgetError,
    wrap_phase,
)

__all__ = [
    "SLIDE_DTYPE",
    "SlidingMixin",
    "budget_error",
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


def budget_error(
    par: np.ndarray,
    t: float,
    c: float,
    q: float,
    v: float,
    m_now: float,
    jump: float,
    direction: int,
    budget: int,
) -> Exception:
    """The error when an ``advance`` call spent its switch budget, right after a switch at
    ``q`` (output ``m_now`` after it, ``m_now - jump`` before it, ``direction`` +1 up / -1 down;
    ``c`` = cos φ now).

    Sliding (Filippov): on the threshold the acceleration with the output of the side below
    points up and the one with the output of the side above points down, so the motion is
    pushed into the threshold from both sides and the exact integration chatters across it.
    """
    coupling = par[kern.P_C]
    base = -2.0 * par[kern.P_ZETA] * v - q + c
    a_now = base + coupling * m_now
    a_before = base + coupling * (m_now - jump)
    if direction != 0 and direction * a_before > 0.0 and direction * a_now < 0.0:
        a_below, a_above = (a_before, a_now) if direction > 0 else (a_now, a_before)
        return SlidingError(
            f"chattering towards a sliding motion on the relay threshold q = {q!r} at t = {t!r}: "
            f"the flow pushes into the threshold from both sides (q'' = {float(a_below)!r} with "
            f"the output below it, {float(a_above)!r} with the output above it, v = {v!r}), but "
            f"the excursions did not shrink to SLIDE_EXCURSION = {SLIDE_EXCURSION:g} (times "
            "1/max(1, Ω, 2ζ)), where the Filippov sliding motion takes over, within the "
            f"budget of {budget} switches of this call",
            time=t,
            threshold=q,
        )
    return SwitchBudgetError(
        f"switch budget exceeded at t = {t!r} (q = {q!r}, v = {v!r}): more than {budget} "
        f"switches in one advance call, the cap of {SWITCHES_PER_RELAY_AND_TIME} switches per "
        f"relay and per unit time (times max(1, Ω)) plus {SWITCH_BUDGET_FLOOR} per call "
        "(oscillators.engines.base.SWITCHES_PER_RELAY_AND_TIME)",
        time=t,
        budget=budget,
    )


class _Slide:
    """A sliding motion in progress: threshold, the output of the relays as they are
    (``m_table``) and with the zero-width group switched in direction ``to_other``
    (``m_other``), the exit clock (period index, period time; None: never) and output."""

    __slots__ = ("theta", "m_table", "m_other", "to_other", "exit_clock", "m_end")

    def __init__(self, theta, m_table, m_other, to_other, exit_clock, m_end) -> None:
        self.theta = theta
        self.m_table = m_table
        self.m_other = m_other
        self.to_other = to_other
        self.exit_clock = exit_clock
        self.m_end = m_end


class SlidingMixin:
    """The slide bookkeeping of the relay engines (:class:`~oscillators.engines.relay.RelayEngine`):
    entering the sliding set, sliding on to a clock reading, leaving at the exit. The engine
    provides ``_clock()``, ``_par``, ``_phi0``, ``_omega``, ``_period``, ``_t0``, ``_y``,
    ``_ntan``, the attributes ``_slide``, ``_slide_events``, ``_collapsed``, and the two
    engine-specific moves ``_slide_set_clock`` and ``_slide_switch``."""

    @property
    def sliding(self) -> bool:
        """The motion slides along a relay threshold now (``q = θ, v = 0``, ``M = M_eq``)."""
        return self._slide is not None

    def _slide_output(self, tau: float) -> float:
        """``M_eq`` at period time ``tau`` of the slide in progress."""
        ph = self._phi0 + self._omega * tau
        return equivalent_output(self._slide.theta, float(self._par[kern.P_C]), math.cos(ph))

    def _enter_slide(
        self, theta: float, v: float, m_table: float, m_other: float, to_other: int, record: bool
    ) -> None:
        """Set the motion on the sliding set ``q = θ, v = 0`` now. ``m_table`` is the output of
        the relays as they are, ``m_other`` the output after switching the zero-width group at
        ``θ`` in direction ``to_other``."""
        n, tau = self._clock()
        m_below, m_above = (m_table, m_other) if to_other > 0 else (m_other, m_table)
        coupling = float(self._par[kern.P_C])
        phi = wrap_phase(self._phi0 + self._omega * tau)
        delta, m_end = slide_exit(
            phi, theta, coupling, min(m_below, m_above), max(m_below, m_above), self._omega
        )
        exit_clock = None
        if math.isfinite(delta):
            n_e, tau_e = n, tau + delta
            while tau_e >= self._period:
                tau_e -= self._period
                n_e += 1
            exit_clock = (n_e, tau_e)
        self._slide = _Slide(theta, m_table, m_other, to_other, exit_clock, m_end)
        if self._ntan:
            # every orbit reaching the sliding set is on q = θ, v = 0: (δq, δv) collapse
            self._y[:2, :] = 0.0
            self._collapsed = True
        if record:
            t = self._t0 + n * self._period + tau
            self._slide_events.append((t, theta, v, 1, self._slide_output(tau)))
        self._slide_set_clock(n, tau, 0.0)

    def _slide_move(self, n: int, tau: float) -> None:
        """Slide on to clock (n, tau) (not past the exit): the clock, q = θ, v = 0, ∫M dt."""
        n0, tau0 = self._clock()
        delta = (n - n0) * self._period + (tau - tau0)
        sin_a = math.sin(self._phi0 + self._omega * tau0)
        sin_b = math.sin(self._phi0 + self._omega * tau)
        c = float(self._par[kern.P_C])
        self._slide_set_clock(
            n, tau, slide_integral(self._slide.theta, c, self._omega, sin_a, sin_b, delta)
        )

    def _slide_to(self, n: int, tau: float, record: bool) -> bool:
        """Slide towards clock (n, tau); at the exit (if it comes first) leave the
        Returns True if (n, tau) was reached while still sliding."""
        ex = self._slide.exit_clock
        if ex is None or (n, tau) <= ex:
            self._slide_move(n, tau)
            return True
        self._slide_move(*ex)
        sl = self._slide
        if sl.m_end != sl.m_table:
            self._slide_switch(sl.to_other)
        if record:
            t = self._t0 + ex[0] * self._period + ex[1]
            self._slide_events.append((t, sl.theta, 0.0, -1, sl.m_end))
        self._slide = None
        return False

    def _slide_set_clock(self, n: int, tau: float, integral: float) -> None:
        """Clock := (n, tau), q := θ, v := 0, ∫M dt += integral (engine-specific)."""
        raise NotImplementedError

    def _slide_switch(self, direction: int) -> None:
        """Switch the zero-width group at the threshold in ``direction`` (engine-specific)."""
        raise NotImplementedError
