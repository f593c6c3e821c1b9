"""Lyapunov spectra of forced oscillators with hysteresis (paper Sec. "Lyapunov exponents").

The tangent flow is propagated by the system's integrator: closed-form fundamental matrices
between switches and the saltation matrix ``X`` (paper eq. salt_matrix) at every relay switch for
piecewise-constant operators, the play-limit linearization (paper eqs. limit_W_0/1, V_in/V_out)
for the play. The exponents come from QR re-orthonormalisation at fixed time intervals
(Benettin et al. 1980; Geist et al. 1990), averaged over ``[transient, t_end]``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from analysis.dimensions import kaplan_yorke_dimension
from oscillators.results import OscillatorState

__all__ = ["LyapunovResult", "lyapunov_spectrum"]


@dataclass(frozen=True)
class LyapunovResult:
    """Lyapunov spectrum of one run.

    Attributes
    ----------
    exponents:
        Descending; ``-inf`` allowed (the play limit's slaved direction).
    tangent_space:
        The basis of the tangent space the flow was run in, e.g. ``("q", "v")`` for relays and
        dimers, ``("q", "v", "w")`` for the play limit, with ``"phi"`` if the phase direction is
        included. The exponents belong to no single coordinate.
    history_t, history:
        Running estimates (rows) at times ``history_t`` — the convergence record.
    n_switches:
        Output switches (piecewise-constant) or wall events (play) during the run.
    t_end:
        End time; the average runs over ``[transient, t_end]``.
    kaplan_yorke:
        ``D_KY`` of the exponents (paper eq. kaplan_yorke). With ``include_phase`` the zero
        phase exponent is included, as requested.
    final:
        System state at ``t_end`` (to continue a run, e.g. along a parameter continuation).
    """

    exponents: np.ndarray
    tangent_space: tuple[str, ...]
    history_t: np.ndarray
    history: np.ndarray
    n_switches: int
    t_end: float
    transient: float
    kaplan_yorke: float
    final: OscillatorState
    extra: dict = field(default_factory=dict)

    @property
    def max_exponent(self) -> float:
        """λ_max = λ_1."""
        return float(self.exponents[0])


def lyapunov_spectrum(
    system: Any,
    t_end: float,
    transient: float = 0.0,
    q0: float = -1.0,
    v0: float = 0.1,
    operator_state: Any = None,
    w0: float | None = None,
    include_phase: bool = False,
    progress: bool = True,
) -> LyapunovResult:
    """Lyapunov spectrum of ``system`` (a :class:`~oscillators.system.ForcedOscillator`).

    Parameters
    ----------
    t_end:
        End of the run; exponents are averaged over ``[transient, t_end]``.
    transient:
        Time integrated without the tangent flow first.
    q0, v0, operator_state, w0:
        Initial condition (``w0``: play wagon position, play-type operators only). The defaults
        are the paper's Table II.
    include_phase:
        Also follow the forcing-phase direction φ (its exponent is 0). The paper's spectrum
        neglects it (Poincaré section φ = 0): (q, v) for relays/dimers, (q, v, w) for the play.
    progress:
        tqdm progress bar on long runs.
    """
    kwargs: dict[str, Any] = {"include_phase": bool(include_phase), "progress": bool(progress)}
    if w0 is not None:
        kwargs["w0"] = w0
    raw = system.tangent(t_end, transient, q0, v0, operator_state, **kwargs)
    exps = np.asarray(raw.exponents, dtype=float)
    # The integrators report the exponents in descending order already; after QR they belong to
    # no coordinate, so ``tangent_space`` names the basis the tangent flow was run in.
    if np.any(np.diff(exps) > 0):
        raise RuntimeError(f"tangent integrator returned unsorted exponents {exps}")
    history = np.asarray(raw.history, dtype=float)
    return LyapunovResult(
        exponents=exps,
        tangent_space=tuple(raw.labels),
        history_t=np.asarray(raw.history_t, dtype=float),
        history=history,
        n_switches=int(raw.n_switches),
        t_end=float(raw.t_end),
        transient=float(transient),
        kaplan_yorke=kaplan_yorke_dimension(exps),
        final=raw.final,
        extra=dict(raw.extra),
    )
