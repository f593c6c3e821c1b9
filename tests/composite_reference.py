"""Shared test helper (not collected): an independent integrator of the forced oscillator coupled
to a weighted sum of plays and relays, written from the paper only.

    q'' + 2ζ q' + q = cos(φ0 + Ω t) + C·M,
    M = Σ_k c_k f_k(w_k) + Σ_j d_j y_j

with plays ``k`` (half-width ``r_k``, wagon ``w_k``, shape ``f_k`` the identity or
``erf(w/(√2 R))``; a Prandtl–Ishlinskii operator is a sum of identity plays) and relays ``j``
(thresholds ``α_j >= β_j``, output ``y_j = ±1``). Nothing of the library is used: the operators'
states are the arrays ``w`` and ``y`` here, moved by hand.

While ``q`` moves in direction ``d = sign v`` every wagon is either *frozen* (strictly inside,
``w_k`` constant) or *slaved* (the finger on the wall it pushes, ``w_k = q − d·r_k``), and every
relay output is constant. Such a segment is integrated by ``scipy.integrate.solve_ivp`` (DOP853,
rtol = atol = 1e-12) with two terminal events: the reversal ``v = 0`` (direction flips; the slaved
wagons freeze where they are) and the nearest *breakpoint* ahead, ``q = bp``, the least of the
frozen wagons' walls ``w_k + d·r_k`` and the thresholds of the relays that switch in direction
``d`` (``α`` of the down relays when rising, ``β`` of the up relays when falling). At a
breakpoint ``q := bp`` exactly, a wagon whose wall it is becomes slaved and the relays with that
threshold switch (a rising input switches at ``u = α``; a falling one just below ``β``, which in
continuous time is the same instant). If the input passes a breakpoint and turns back inside one
solver step (the event function has the same sign at both step ends) the reversal reveals it,
and the crossing is located on the monotone segment's dense output.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.special import erf

#: tolerances of the reference's DOP853 integration
RTOL = ATOL = 1e-12
#: largest step: keeps a breakpoint passed and re-crossed inside one step rare (it is handled)
MAX_STEP = 0.25


@dataclass(frozen=True)
class PlayTerm:
    """``weight · f(w)`` of a play of ``width``; ``f`` the identity (``spread=None``) or
    ``erf(w/(√2·spread))``."""

    weight: float
    width: float
    spread: float | None = None

    def f(self, w):
        if self.spread is None:
            return w
        return erf(np.asarray(w) / (math.sqrt(2.0) * self.spread))


@dataclass(frozen=True)
class RelayTerm:
    """``weight · y`` of a relay with thresholds ``alpha >= beta``."""

    weight: float
    alpha: float
    beta: float


@dataclass(frozen=True)
class Model:
    """``M = Σ plays + Σ relays`` (either may be empty)."""

    plays: tuple[PlayTerm, ...] = ()
    relays: tuple[RelayTerm, ...] = ()

    @property
    def half_widths(self) -> np.ndarray:
        return np.array([0.5 * p.width for p in self.plays])

    @property
    def alpha(self) -> np.ndarray:
        return np.array([r.alpha for r in self.relays])

    @property
    def beta(self) -> np.ndarray:
        return np.array([r.beta for r in self.relays])

    def output(self, w: np.ndarray, y: np.ndarray) -> float:
        """``M`` with wagons at ``w`` and relay outputs ``y``."""
        plays = sum(p.weight * float(p.f(wk)) for p, wk in zip(self.plays, w, strict=True))
        relays = sum(r.weight * yj for r, yj in zip(self.relays, y, strict=True))
        return float(plays + relays)

    def rising_start(self, q0: float) -> tuple[np.ndarray, np.ndarray]:
        """Memory after rising from negative saturation to ``q0``: every wagon on its right
        wall (``w = q0 − r``), the relays with ``α <= q0`` up."""
        return q0 - self.half_widths, np.where(self.alpha <= q0, 1.0, -1.0)


@dataclass
class Reference:
    """The reference's state (mutable; one orbit) and its event log.

    ``events`` rows: ``(t, kind, q, v, ΔM, rate)``, kind +2 relays switched, +1 another
    breakpoint (a wall hit), −1 a reversal, rate
    the speed of the event function there (``v*``, or the acceleration at a reversal);
    ``switches`` the times at which relays switched (``M`` jumps there)."""

    model: Model
    coupling: float
    zeta: float
    omega: float
    phi0: float
    t: float
    q: float
    v: float
    w: np.ndarray
    y: np.ndarray
    events: list = field(default_factory=list)

    def __post_init__(self) -> None:
        self.w = np.array(self.w, dtype=float)
        self.y = np.array(self.y, dtype=float)
        if self.v != 0.0:
            self.d = 1 if self.v > 0.0 else -1
        else:
            acc = (
                -self.q
                + math.cos(self.phi0 + self.omega * self.t)
                + self.coupling * (self.model.output(self.w, self.y))
            )
            self.d = 1 if acc >= 0.0 else -1

    @property
    def switches(self) -> np.ndarray:
        return np.array([e[0] for e in self.events if e[4] != 0.0])

    # -- one segment's mode ---------------------------------------------------------------------
    def _slaved(self) -> np.ndarray:
        r = self.model.half_widths
        tol = 8.0 * np.finfo(float).eps * np.maximum(np.maximum(abs(self.q), r), 1.0)
        return self.d * (self.q - self.w) >= r - tol

    def _breakpoint(self, slaved: np.ndarray) -> float:
        d, m = self.d, self.model
        walls = (self.w + d * m.half_widths)[~slaved]
        thresholds = m.alpha[self.y < 0] if d > 0 else m.beta[self.y > 0]
        ahead = np.concatenate([walls, thresholds])
        if not ahead.size:
            return d * math.inf
        return float(ahead.min() if d > 0 else ahead.max())

    def _force(self, slaved: np.ndarray):
        """``M(q)`` on the segment: frozen wagons and relays constant, slaved wagons at
        ``q − d·r``."""
        d, m = self.d, self.model
        r = m.half_widths
        fixed = sum(
            p.weight * float(p.f(wk))
            for p, wk, s in zip(m.plays, self.w, slaved, strict=True)
            if not s
        ) + sum(rl.weight * yj for rl, yj in zip(m.relays, self.y, strict=True))
        moving = [(p, rk) for p, rk, s in zip(m.plays, r, slaved, strict=True) if s]

        def force(q):
            return fixed + sum(p.weight * float(p.f(q - d * rk)) for p, rk in moving)

        return force

    # -- driving --------------------------------------------------------------------------------
    def run(self, times: np.ndarray) -> np.ndarray:
        """Advance to ``times[-1]`` (sorted, not before now); rows ``(q, v, M)`` at ``times``."""
        times = np.asarray(times, dtype=float)
        out = np.empty((times.size, 3))
        i = 0
        zeta, omega, c, phi0 = self.zeta, self.omega, self.coupling, self.phi0
        while True:
            slaved = self._slaved()
            force = self._force(slaved)
            while i < times.size and times[i] <= self.t:
                out[i] = (self.q, self.v, force(self.q))
                i += 1
            if i == times.size:
                return out
            d = self.d
            bp = self._breakpoint(slaved)

            def rhs(t, x, force=force):
                return [
                    x[1],
                    -2.0 * zeta * x[1] - x[0] + math.cos(phi0 + omega * t) + c * force(x[0]),
                ]

            def reversal(t, x):
                return x[1]

            def breakpoint(t, x, bp=bp):
                return x[0] - bp

            reversal.terminal = breakpoint.terminal = True
            reversal.direction, breakpoint.direction = -d, d
            events = [reversal] + ([breakpoint] if math.isfinite(bp) else [])
            sol = solve_ivp(
                rhs,
                (self.t, times[-1]),
                [self.q, self.v],
                method="DOP853",
                rtol=RTOL,
                atol=ATOL,
                max_step=MAX_STEP,
                events=events,
                dense_output=True,
            )
            if sol.status < 0:
                raise RuntimeError(sol.message)
            if sol.status == 0:
                t_stop, x_stop, kind = float(sol.t[-1]), sol.y[:, -1], None
            elif sol.t_events[0].size:
                t_stop, x_stop, kind = float(sol.t_events[0][0]), sol.y_events[0][0], "reversal"
                if math.isfinite(bp) and d * (x_stop[0] - bp) >= 0.0:
                    # passed bp and turned back within one step: q is monotone on [t, t_stop]
                    t_stop = brentq(
                        lambda s, sol=sol, bp=bp: sol.sol(s)[0] - bp,
                        self.t,
                        t_stop,
                        xtol=1e-15,
                        rtol=4 * np.finfo(float).eps,
                    )
                    x_stop, kind = sol.sol(t_stop), "breakpoint"
            else:
                t_stop, x_stop, kind = float(sol.t_events[1][0]), sol.y_events[1][0], "breakpoint"
            inside = i + int(np.searchsorted(times[i:], t_stop, side="left"))
            if kind is None:
                inside = times.size  # the end: every remaining sample lies on this segment
            if inside > i:
                x = sol.sol(times[i:inside])
                out[i:inside, 0], out[i:inside, 1] = x[0], x[1]
                out[i:inside, 2] = [force(qs) for qs in x[0]]
                i = inside
            self._finish(t_stop, x_stop, kind, slaved, bp)
            if kind is None:
                return out

    def _finish(self, t, x, kind, slaved, bp) -> None:
        """Move the memory to the stop and apply the event."""
        d, m = self.d, self.model
        self.t, self.q, self.v = t, float(x[0]), float(x[1])
        if kind == "breakpoint":
            self.q = bp
        if kind == "reversal":
            self.v = 0.0
        self.w[slaved] = self.q - d * m.half_widths[slaved]
        if kind is None:
            return
        before = m.output(self.w, self.y)
        if kind == "breakpoint":
            if d > 0:
                self.y[(self.y < 0) & (m.alpha == bp)] = 1.0
            else:
                self.y[(self.y > 0) & (m.beta == bp)] = -1.0
        else:
            self.d = -d
        after = m.output(self.w, self.y)
        # how fast the event function crosses zero: v* at a breakpoint, the acceleration at a
        # reversal (M is continuous there); an error δ in the state moves the event by δ/rate
        rate = self.v
        if kind == "reversal":
            rate = -self.q + math.cos(self.phi0 + self.omega * t) + self.coupling * after
        # the library's event codes: +2 relays switched (M jumped), +1 another breakpoint
        code = -1 if kind == "reversal" else (2 if after != before else 1)
        self.events.append((t, code, self.q, self.v, after - before, rate))


def reference(
    model: Model,
    coupling: float,
    zeta: float,
    omega: float,
    q0: float,
    v0: float,
    phi0: float = 0.0,
    w0=None,
    y0=None,
) -> Reference:
    """A reference orbit started at ``t = 0``; memory ``w0``, ``y0`` (default: rising from
    negative saturation to ``q0``)."""
    w_rise, y_rise = model.rising_start(q0)
    return Reference(
        model,
        coupling,
        zeta,
        omega,
        phi0,
        0.0,
        q0,
        v0,
        w_rise if w0 is None else w0,
        y_rise if y0 is None else y0,
    )


def near_switch(times: np.ndarray, switches: np.ndarray, window: float) -> np.ndarray:
    """Samples within ``window`` of a relay switch (``M`` jumps there: the two integrators may
    place the jump on either side of such a sample)."""
    if not switches.size:
        return np.zeros(times.shape, dtype=bool)
    k = np.searchsorted(switches, times)
    left = np.abs(times - switches[np.clip(k - 1, 0, switches.size - 1)])
    right = np.abs(times - switches[np.clip(k, 0, switches.size - 1)])
    return np.minimum(left, right) <= window
