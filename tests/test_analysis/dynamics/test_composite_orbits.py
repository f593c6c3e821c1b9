"""Periodic orbits of composite operators (a play plus relays): the orbit closes under the
stroboscopic map, and its Floquet multipliers agree with the Lyapunov spectrum of the same
attractor (two independent computations)."""

from __future__ import annotations

import numpy as np

from analysis.dynamics.lyapunov import lyapunov_spectrum
from analysis.dynamics.periodic_orbits import find_periodic_orbit
from hysteresis import GeneralizedPlay, PreisachModel
from oscillators import ForcedOscillator


def test_play_plus_relays_orbit_closes_and_matches_the_spectrum():
    rng = np.random.default_rng(1)
    beta = rng.uniform(-1.5, 1.0, 8)
    alpha = beta + rng.uniform(0.2, 1.0, 8)
    op = 0.6 * GeneralizedPlay.erf(1.0, 0.7) + 0.4 * PreisachModel.from_relays(alpha, beta)
    system = ForcedOscillator(op, coupling=1.0, damping_ratio=0.1, frequency=1.0)
    orbit = find_periodic_orbit(system, transient=100)
    state = orbit.start
    for _ in range(orbit.period):
        state = system.stroboscopic_map(state)
    # closes to the Newton tolerance, plus the integration over k periods
    assert abs(state.q - orbit.start.q) < 1e-8 and abs(state.v - orbit.start.v) < 1e-8
    lam = np.log(np.max(np.abs(orbit.multipliers))) / (orbit.period * system.period)
    spectrum = lyapunov_spectrum(system, t_end=600.0, transient=100.0)
    # the Benettin estimate over 500 time units: error ~ (log-distance of the start)/t
    assert abs(spectrum.exponents[0] - lam) < 0.01
