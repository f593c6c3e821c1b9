"""Layouts of the compiled continuous engine's flat arrays (one definition each).

The meaning of every entry is in :mod:`oscillators.engines._continuous_kernels` (module
docstring); they live here so that the kernels and :mod:`oscillators.engines._relay_landings`
(the relays of a composite) share them without importing each other.
"""

from __future__ import annotations

# ``par`` (float64)
P_ZETA, P_OMEGA, P_C, P_PHI0, P_H, P_PERIOD, P_BOUND, P_T0 = range(8)
N_PAR = 8
# ``ist`` (int64)
I_DIR, I_PERIOD, I_PARTNER, I_EVENTS, I_FREE, I_SAMPLE, I_NEV, I_RECORD = range(8)
I_K, I_OP, I_EVERETT, I_STUCK, I_PUSHED, I_OUTSIDE, I_RPTR = range(8, 15)
N_IST = 15
# ``st`` (float64)
S_TAU, S_Q, S_V, S_BP, S_U0, S_Y0, S_SLOPE, S_M, S_RELAY, S_CBP, S_RBP, S_RCOMP = range(12)
N_ST = 12
#: columns of ``rel`` (one row per relay of a composite: thresholds, weight, output ±1)
R_ALPHA, R_BETA, R_WEIGHT, R_OUT = range(4)
#: the ``kind`` of a recorded event at which relays switched (the output jumps by ``Δy``)
EVENT_SWITCH = 2
