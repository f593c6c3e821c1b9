"""Shared test helpers (not collected): relay-engine calls through the seam, an independent
brute-force relay integrator, and an analytic continuous Preisach model.

The brute force is written from the paper only: scipy's DOP853 at rtol = atol = 1e-12 with
terminal events on the nearest thresholds, relays switched by hand (up once q >= alpha, down once
q < beta, all relays at one threshold together), M = Σ w·y.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.special import ndtr

from analysis.dynamics.lyapunov import lyapunov_spectrum

_METHODS = {"auto": "auto", "kernel": "nested", "generic": "generic"}


def engine_options(engine: str = "auto", taylor: bool = True) -> dict:
    """Relay-engine options by the tests' short names (``kernel`` = the nested kernel)."""
    return {"method": _METHODS[engine], "taylor": taylor}


def pc_trajectory(
    sysm,
    t_end,
    q0=-1.0,
    v0=0.1,
    operator_state=None,
    sample_dt=0.01,
    phi0=0.0,
    engine="auto",
    taylor=True,
):
    """The relay engine's trajectory through the seam."""
    return sysm.trajectory(
        t_end,
        q0,
        v0,
        operator_state,
        sample_dt,
        phi0,
        engine_options=engine_options(engine, taylor),
    )


def pc_jacobian(
    sysm,
    duration,
    q0=-1.0,
    v0=0.1,
    phi0=0.0,
    operator_state=None,
    include_phase=True,
    engine="auto",
    taylor=True,
):
    state = sysm.initial_state(q0, v0, operator_state, phi0)
    opts = engine_options(engine, taylor)
    jac, _ = sysm.jacobian(duration, state, include_phase, engine_options=opts)
    return jac


def pc_tangent(sysm, t_end, transient=0.0, include_phase=False, engine="auto", **kw):
    kw.pop("progress", None)
    return lyapunov_spectrum(
        sysm,
        t_end,
        transient,
        include_phase=include_phase,
        engine_options=engine_options(engine),
        **kw,
    )


def relay_brute_force(alpha, beta, weights, coupling, t_end, q0, v0, zeta, omega):
    """Switch events (time, q, v, ΔM) of q'' + 2ζq' + q = cos Ωt + C·Σ w y and the final relay
    outputs; the relays start rising from negative saturation to q0."""
    alpha, beta, w = (np.asarray(x, dtype=float) for x in (alpha, beta, weights))
    up = alpha <= q0
    t, x = 0.0, np.array([q0, v0])
    events = []
    while t < t_end:
        m = math.fsum(np.where(up, w, -w))
        next_up = np.min(alpha[~up]) if np.any(~up) else np.inf
        next_down = np.max(beta[up]) if np.any(up) else -np.inf

        def rhs(s, y, m=m):
            return [y[1], -2 * zeta * y[1] - y[0] + math.cos(omega * s) + coupling * m]

        def ev_up(s, y, a=next_up):
            return y[0] - a

        def ev_down(s, y, b=next_down):
            return y[0] - b

        ev_up.terminal = ev_down.terminal = True
        ev_up.direction, ev_down.direction = 1, -1
        sol = solve_ivp(
            rhs,
            (t, t_end),
            x,
            method="DOP853",
            rtol=1e-12,
            atol=1e-12,
            events=[ev_up, ev_down],
            max_step=0.05,
        )
        if sol.status != 1:
            break
        if sol.t_events[0].size:
            t, x = sol.t_events[0][0], sol.y_events[0][0].copy()
            up[alpha == next_up] = True
        else:
            t, x = sol.t_events[1][0], sol.y_events[1][0].copy()
            up[beta == next_down] = False
        events.append((t, x[0], x[1], math.fsum(np.where(up, w, -w)) - m))
    return np.array(events).reshape(-1, 4), np.where(up, 1.0, -1.0)


def gauss_everett_model(scale=1.3, lower=-6.0, upper=6.0):
    """Continuous Preisach model with the product density ∝ φ(α)φ(β): closed-form Everett
    ``((Φ(a)−Φ(b))/Z)²`` and its exact gradient."""
    from hysteresis.preisach import PreisachModel

    z = ndtr(upper / scale) - ndtr(lower / scale)

    def pdf(x):
        return np.exp(-0.5 * (np.asarray(x) / scale) ** 2) / (scale * math.sqrt(2 * math.pi))

    def everett(a, b):
        return ((ndtr(np.asarray(a) / scale) - ndtr(np.asarray(b) / scale)) / z) ** 2

    def gradient(a, b):
        diff = ndtr(np.asarray(a) / scale) - ndtr(np.asarray(b) / scale)
        return 2 * diff * pdf(a) / z**2, -2 * diff * pdf(b) / z**2

    return PreisachModel.from_everett(everett, lower, upper, gradient)
