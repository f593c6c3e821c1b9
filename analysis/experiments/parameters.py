"""The paper's parameter values and the run sizes of its reproduction, named once.

Zech, Otto & Radons, Tables I and II: every model default
(:class:`~analysis.experiments.models.ModelParameters`), every oscillator default of the analyses
and the command line, and the ensembles and figures of ``hyst paper`` read these names.
The paper's initial position is the oscillator library's :data:`oscillators.DEFAULT_Q0`.

:class:`RunSize` holds every knob that sets how long the reproduction runs; :data:`SIZES` are
the ``smoke``, ``quick`` and ``full`` (the paper's scale) sizes of ``hyst paper``.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from oscillators import DEFAULT_DAMPING_RATIO, DEFAULT_FREQUENCY, DEFAULT_Q0, DEFAULT_V0

__all__ = [
    "DAMPING_RATIO",
    "DEFAULT_Q0",
    "ENSEMBLE_COUPLINGS",
    "FREQUENCY",
    "PAPER_LARGEST_N",
    "PAPER_REGULAR_FRACTION",
    "PLAYS",
    "SEED",
    "SIZES",
    "SPIN_COUPLING",
    "SPINS",
    "SPREAD",
    "V0",
    "WIDTH",
    "WIDTH_SPREAD",
    "RunSize",
]

# -- Table I: the hysteresis operators ---------------------------------------------------------
#: p, the loop width of a spin dimer (2 × a relay's half-width)
WIDTH = 2.0
#: R, the standard deviation of the loop centres (local fields)
SPREAD = 1.0
#: J, the spin-spin coupling of the dimers (``0 < p < 2J``)
SPIN_COUPLING = 2.0
#: N, the number of spins of the paper's large ensembles and of its fig:bif / fig:erf_10000
SPINS = 20000
#: the disorder seed of a single realization
SEED = 0
#: σ_r, the spread of the relay half-widths of the ``preisach`` models (not in the paper, whose
#: relays all have the width p; ``0`` reproduces it)
WIDTH_SPREAD = 0.2
#: K, the number of plays of the Prandtl–Ishlinskii model (not in the paper)
PLAYS = 10

# -- Table II: the oscillator and its initial condition ---------------------------------------
# (defined once, as the oscillator's defaults, in oscillators/parameters.py)
#: ζ, the damping ratio
DAMPING_RATIO = DEFAULT_DAMPING_RATIO
#: Ω, the forcing frequency
FREQUENCY = DEFAULT_FREQUENCY
#: q'(0), the initial velocity (q(0) is :data:`DEFAULT_Q0` = -1, all spins down)
V0 = DEFAULT_V0

# -- the ensembles (fig:dim, fig:sap, fig:mag, fig:mag_his) -----------------------------------
#: the two couplings C of the paper's ensemble section
ENSEMBLE_COUPLINGS = (2.9, 4.0)
#: the largest N of the paper's ensembles and of its fig:bif / fig:erf_10000 dimers: the claims
#: "at large N" are about it, and a run whose largest N is smaller cannot decide them
PAPER_LARGEST_N = SPINS
#: paper fig:sap(b): "nearly 100 of the 500 disorder realizations lead to D_KY = 0" at C = 2.9
PAPER_REGULAR_FRACTION = 100 / 500


# -- run sizes of ``hyst paper`` ------------------------------------------------------------------


@dataclass(frozen=True)
class RunSize:
    """Every knob that sets how long the reproduction runs.

    ``full`` is the paper's scale; ``quick`` takes about five minutes on two cores; ``smoke``
    only checks that every figure and claim is produced.
    """

    name: str
    # fig:bif_0 (N = 2, b = (1, -1)): couplings stepped downward
    bif0_couplings: int = 200
    bif0_c_range: tuple[float, float] = (0.5, 10.0)
    bif0_periods: int = 60
    bif0_transient: int = 200
    bif0_lyapunov_t: float = 2000.0
    # fig:bif (N = 20 000 vs the erf-play limit)
    bif_spins: int = SPINS
    bif_couplings: int = 301
    bif_c_range: tuple[float, float] = (1.5, 4.5)
    bif_periods: int = 60
    bif_transient: int = 100
    bif_lyapunov_t: float = 2000.0
    # attractors and single-system Lyapunov runs
    attractor_periods: int = 2000
    dky_t_end: float = 2.0e4
    dky_transient: float = 1.0e3
    # fig:mboa: initial conditions per panel
    mboa_points: int = 40
    # disorder ensembles (fig:dim, fig:sap, fig:mag, fig:mag_his)
    ensemble_spins: tuple[int, ...] = (100, 500, 1000, 5000, 10000, 15000, 20000)
    ensemble_realizations: int = 500
    ensemble_t_end: float = 2.0e4
    ensemble_transient: float = 1.0e3
    # iid-input reference
    iid_spins: tuple[int, ...] = (100, 300, 1000, 3000, 10000, 20000)
    iid_realizations: int = 500
    iid_steps: int = 10000
    # fig:preis_dens
    identification_spins: int = SPINS
    identification_step: float = 0.1
    extra: dict = field(default_factory=dict)


_FULL = RunSize(name="full")
_QUICK = replace(
    _FULL,
    name="quick",
    bif0_couplings=200,
    bif0_periods=40,
    bif0_transient=100,
    bif0_lyapunov_t=500.0,
    bif_spins=20000,
    bif_couplings=61,
    bif_periods=40,
    bif_transient=60,
    bif_lyapunov_t=3000.0,
    attractor_periods=1000,
    dky_t_end=2.0e4,
    dky_transient=1.0e3,
    mboa_points=12,
    # t_end >= 5000: fewer than ~700 section points leave box counting no scaling region
    ensemble_spins=(100, 1000, 5000, 20000),
    ensemble_realizations=100,
    ensemble_t_end=1.0e4,
    ensemble_transient=500.0,
    iid_spins=(100, 300, 1000, 3000, 10000),
    iid_realizations=200,
    iid_steps=5000,
    identification_spins=20000,
    identification_step=0.1,
)
_SMOKE = replace(
    _QUICK,
    name="smoke",
    bif0_couplings=6,
    bif0_periods=10,
    bif0_transient=10,
    bif0_lyapunov_t=50.0,
    bif_spins=400,
    bif_couplings=3,
    bif_periods=8,
    bif_transient=5,
    bif_lyapunov_t=40.0,
    attractor_periods=30,
    dky_t_end=200.0,
    dky_transient=20.0,
    mboa_points=2,
    ensemble_spins=(20, 60),
    ensemble_realizations=3,
    ensemble_t_end=100.0,
    ensemble_transient=10.0,
    iid_spins=(20, 60, 200),
    iid_realizations=20,
    iid_steps=200,
    identification_spins=400,
    identification_step=0.25,
)

SIZES: dict[str, RunSize] = {s.name: s for s in (_SMOKE, _QUICK, _FULL)}
