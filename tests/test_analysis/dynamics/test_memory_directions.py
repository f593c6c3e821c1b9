"""Memory directions of the Lyapunov spectrum: neutral exponents of frozen extrema, block errors,
and the exponents without long-lived memory (analysis.dynamics.memory)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from analysis.dynamics.lyapunov import LyapunovResult, lyapunov_spectrum
from analysis.dynamics.memory import (
    exponent_block_errors,
    memory_frozen_exponents,
    neutral_count,
)
from hysteresis import ContinuousPreisachModel, GeneralizedPlay
from oscillators import ForcedOscillator

ZETA = 0.05


def _uncoupled_decay():
    # C = 0: the Preisach staircase is driven by q but does not act back. Started at q0 = 2
    # off resonance (Ω = 3, forced amplitude ≈ 1/8), the free oscillation decays by e^{-2πζ}
    # ≈ 0.73 per cycle, so every extremum of the transient stays in memory for ever (a decaying
    # oscillation never wipes one out).
    op = ContinuousPreisachModel.gaussian(2.0, 1.0, 0.2)
    return ForcedOscillator(op, 0.0, damping_ratio=ZETA, frequency=3.0)


def test_frozen_extrema_are_exactly_neutral():
    system = _uncoupled_decay()
    res = lyapunov_spectrum(system, 10.0 + 30 * system.period, 10.0, q0=2.0, v0=0.0)
    n_memory = len(res.tangent_space) - 2
    assert n_memory >= 2  # extrema of the transient are remembered at the window's start
    # their rows are never written again and, with C = 0, never feed back: an identity block,
    # so their exponents are 0 up to round-off of the Householder QR (a few ulp per step)
    lam = np.asarray(res.exponents)
    assert np.count_nonzero(np.abs(lam) <= 1e-12) >= n_memory
    # ... and counted as neutral within their (block) error
    assert neutral_count(lam, exponent_block_errors(res, 4)) >= n_memory
    # the Kaplan–Yorke formula counts each of them as a dimension
    assert res.kaplan_yorke >= n_memory - 1e-9


def test_memory_frozen_exponents_are_the_oscillators():
    system = _uncoupled_decay()
    t_end, transient = 10.0 + 30 * system.period, 10.0
    fr = memory_frozen_exponents(system, t_end, transient, q0=2.0, v0=0.0, projection_periods=1)
    assert fr.zeroed_mean > 1  # long-lived extrema were dropped
    window = 30 * system.period
    # with C = 0 the (q, v) rows evolve by the damped oscillator's fundamental matrix
    # Φ(t) = V e^{Λt} V⁻¹ (Λ = −ζ ± iω_d): the product of the QR diagonals is |det Φ| =
    # e^{−2ζ W} exactly, and ‖Φ(W) x‖ lies within a factor κ(V) of e^{−ζW}‖x‖
    a = np.array([[0.0, 1.0], [-1.0, -2 * ZETA]])
    kappa = np.linalg.cond(np.linalg.eig(a)[1])
    assert fr.exponents.sum() == pytest.approx(-2 * ZETA, abs=1e-9)
    assert np.all(np.abs(fr.exponents + ZETA) <= math.log(kappa) / window + 1e-9)


def test_play_memory_is_never_frozen_and_both_estimates_agree():
    # the play's memory w is reset at every wall hit: nothing survives a forcing period, the
    # projection drops nothing, and the two loops follow the same 2-D subspace; they differ
    # only in the norm ((q, v, w) against (q, v)), i.e. by log(norm ratio of the final
    # vectors)/W. |δw| is δq at the last wall hit, less than half a period ago: a ratio below
    # 10 (a growth e^{λ_max T/2} ≈ 1.3 and the (q, v) direction's angle), so log(10)/W.
    system = ForcedOscillator(GeneralizedPlay.erf(2.0, 1.0), 2.9, damping_ratio=ZETA)
    t_end, transient = 400 * system.period, 100 * system.period
    full = lyapunov_spectrum(system, t_end, transient)
    fr = memory_frozen_exponents(system, t_end, transient, projection_periods=1)
    assert fr.zeroed_mean == 0.0
    bound = math.log(10.0) / (t_end - transient)
    assert fr.exponents[0] == pytest.approx(full.exponents[0], abs=bound)
    assert fr.exponents.sum() == pytest.approx(full.exponents[:2].sum(), abs=bound)


def _unnormalised_memory_frozen(system, t_end, transient, q0, v0, projection_periods):
    """The memory-frozen exponents by brute force, on the engine directly, without any
    renormalisation: ``Z := P_n Φ_n ⋯ P_1 Φ_1 [e_q, e_v]`` (``Φ_i`` the tangent map of interval
    i, ``P_i`` zeroing the memory rows whose probe survived it; the probe column rides beside
    Z exactly as in the Benettin loop), then one QR of Z's ``(q, v)`` rows at the end.

    Why it is the same quantity: the loop's ``Y_i = Z_i (R_i ⋯ R_1)^{-1}`` with orthonormal
    ``(q, v)`` rows, so ``Z_n[q, v] = Q_n R_n ⋯ R_1`` and the final ``|R_jj|`` are the products
    of the interval ``|R_jj|``. The engine is restarted where the loop restarts it (memory
    appearing while only two vectors are tracked), at the same elapsed times, so the base
    trajectory is the same to the last bit."""
    period = system.period
    dt = projection_periods * period
    n = int(math.floor((t_end - transient) / dt + 1e-9))
    eng = system.engine(system.initial_state(q0, v0))
    eng.advance(transient)
    eng.start_tangent(False)
    z = np.eye(len(eng.tangent_space), 2)
    origin, now, zeroed = 0.0, transient, 0
    for i in range(n):
        k = eng.deviations().shape[1]
        start = np.zeros((len(eng.tangent_space), k))
        start[: z.shape[0], :2] = z
        if k >= 3:
            start[2:, 2] = 1.0
        eng.set_deviations(start)
        now = now + (transient + (i + 1) * dt - origin - now)
        eng.advance(now)
        dev = eng.deviations()
        z = dev[:, :2].copy()
        if k >= 3:
            survived = dev[2:, 2] == 1.0
            z[2:][survived] = 0.0
            zeroed += int(np.count_nonzero(survived))
        elif z.shape[0] > 2:  # restart with the memory rows as coordinates
            origin, now = origin + now, 0.0
            eng = system.engine(eng.state())
            eng.advance(0.0)
            eng.start_tangent(False)
    r = np.linalg.qr(z[:2])[1]
    return -np.sort(-np.log(np.abs(np.diag(r))) / (n * dt)), zeroed / n


@pytest.mark.parametrize(
    ("q0", "projection_periods"),
    [(2.0, 1), (-3.0, 2)],
    ids=["memory-at-start", "restart"],
)
def test_memory_frozen_exponents_equal_the_unnormalised_product(q0, projection_periods):
    # the Gaussian model at C = 1 (the memory feeds back through C·M, so the carried memory
    # rows matter), 24 forcing periods; at q0 = −3 the start has no memory row (the engine is
    # restarted once memory appears). Both exponents are near −0.13, their gap small, so Z's
    # two columns stay far from parallel over the run: the final QR loses nothing, and the
    # two computations differ by round-off of ~2·24 logs and products (1e-14 in the sums, over
    # t ≈ 150 about 1e-16): 1e-12 has a margin of 1e4
    system = ForcedOscillator(ContinuousPreisachModel.gaussian(2.0, 1.0, 0.1), 1.0)
    t_end, transient = 26 * system.period, 2 * system.period
    want, zeroed = _unnormalised_memory_frozen(
        system, t_end, transient, q0, 0.0, projection_periods
    )
    fr = memory_frozen_exponents(
        system, t_end, transient, q0, 0.0, projection_periods=projection_periods
    )
    print("loop", fr.exponents, "brute force", want, "zeroed", fr.zeroed_mean, zeroed)
    assert np.max(np.abs(fr.exponents - want)) < 1e-12
    assert fr.zeroed_mean == zeroed > 0


def _synthetic(rates: np.ndarray, per_block: int) -> LyapunovResult:
    """A result whose running log sums grow at ``rates[b]`` in block ``b`` (rows sorted)."""
    n_blocks, k = rates.shape
    t0 = 5.0
    t = t0 + np.arange(1, n_blocks * per_block + 1, dtype=float)
    steps = np.repeat(rates, per_block, axis=0)
    sums = np.cumsum(steps, axis=0)
    hist = sums / (t - t0)[:, None]
    return LyapunovResult(
        exponents=hist[-1].copy(),
        tangent_space=("q", "v"),
        history_t=t,
        history=hist,
        n_switches=0,
        t_end=float(t[-1]),
        transient=t0,
        kaplan_yorke=0.0,
        final=None,
    )


def test_block_errors_are_the_batch_means_standard_error():
    rng = np.random.default_rng(3)
    rates = np.column_stack(
        [0.1 + 0.02 * rng.standard_normal(8), -0.2 + 0.01 * rng.standard_normal(8)]
    )
    res = _synthetic(rates, per_block=5)
    err = exponent_block_errors(res, blocks=8)
    assert np.allclose(err, rates.std(axis=0, ddof=1) / math.sqrt(8), rtol=1e-12)
    assert np.allclose(res.exponents, rates.mean(axis=0), rtol=1e-12)
    assert neutral_count(np.array([0.001, -0.2]), np.array([0.001, 0.01])) == 1
    assert neutral_count(np.array([0.0, -np.inf]), np.array([0.0, np.nan])) == 1


def test_block_errors_refuse_too_few_estimates():
    res = _synthetic(np.zeros((2, 2)), per_block=1)
    with pytest.raises(ValueError, match="blocks=4 needs at least 4"):
        exponent_block_errors(res, blocks=4)
    with pytest.raises(ValueError, match="blocks"):
        exponent_block_errors(res, blocks=1)
