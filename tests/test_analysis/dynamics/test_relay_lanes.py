"""Systems side by side in the vector units (``lyapunov_spectra``, ``ensemble_batch``) give, for
every system, the bits of the system run alone.

Independent truth: ``lyapunov_spectrum`` / ``ensemble_task`` of each system alone (the scalar
event loop and the compiled Benettin loop, themselves checked against the Python loop in
test_relay_benettin.py). Bit for bit, because a result must not depend on which systems
shared a batch (``run_tasks`` batches whatever is pending).
"""

import numpy as np
import pytest

import analysis.dynamics.lyapunov as lyapunov
from analysis.dynamics.lyapunov import LANES, lyapunov_spectra, lyapunov_spectrum
from analysis.experiments.ensemble import ensemble_batch, ensemble_task, ensemble_tasks
from hysteresis import Relay, SpinDimerEnsemble
from oscillators import ForcedOscillator


@pytest.fixture
def lane_counts(monkeypatch):
    """Intervals done in lanes per system, for every call of ``qr_intervals_lanes``."""
    calls = []
    real = lyapunov.qr_intervals_lanes

    def counted(*args, **kwargs):
        out = real(*args, **kwargs)
        calls.append([None if o is None else o[0] for o in out])
        return out

    monkeypatch.setattr(lyapunov, "qr_intervals_lanes", counted)
    return calls


def _same_result(a, b) -> None:
    for name in ("exponents", "history_t", "history"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert a.n_switches == b.n_switches and a.kaplan_yorke == b.kaplan_yorke
    assert (a.final.q, a.final.v, a.final.t) == (b.final.q, b.final.v, b.final.t)


def _dimers(seed: int, coupling: float) -> ForcedOscillator:
    return ForcedOscillator(SpinDimerEnsemble.random(300, 2.0, 1.0, 2.0, seed=seed), coupling)


def test_spectra_side_by_side_equal_each_spectrum_alone(lane_counts):
    # ten realizations at C = 2.9 (eight in one lane group, two in a second) and one at
    # C = 4.0 (other parameters: it runs alone)
    systems = [_dimers(seed, 2.9) for seed in range(10)] + [_dimers(3, 4.0)]

    def run(many: bool):
        args = (250.0, 50.0)
        kw = dict(renormalize_dt=4.0, history_points=9)
        if many:
            return lyapunov_spectra(systems, *args, **kw)
        return [lyapunov_spectrum(s, *args, **kw) for s in systems]

    together, alone = run(True), run(False)
    for a, b in zip(together, alone, strict=True):
        _same_result(a, b)
    # which systems ran in lanes: the two groups, every interval (ceil(200 / 4) = 50)
    (done,) = lane_counts
    assert done[:10] == [50] * 10 and done[10] is None
    assert LANES == 8


def test_a_sliding_lane_hands_its_interval_back(lane_counts):
    """Single relays with negative feedback (ζ = 0.5, C = -5): the zero-width one slides from
    t ≈ 21 on (test_relay_benettin.py); its lane hands the interval where the slide starts to
    the Python loop, the other lanes go on, and every result is the one alone."""
    systems = [
        ForcedOscillator(Relay(a, -a), coupling=-5, damping_ratio=0.5) for a in (0.0, 0.05, 0.2)
    ]
    t_end = 16 * systems[0].period
    together = lyapunov_spectra(systems, t_end, 0.0, renormalize_dt=1.0)
    alone = [lyapunov_spectrum(s, t_end, 0.0, renormalize_dt=1.0) for s in systems]
    for a, b in zip(together, alone, strict=True):
        _same_result(a, b)
    assert np.all(np.isneginf(together[0].exponents))  # the slide collapses (δq, δv)
    (done,) = lane_counts
    n_steps = int(np.ceil(t_end / 1.0 - 1e-9))
    assert 15 <= done[0] <= 22 and done[1:] == [n_steps, n_steps]


def test_ensemble_batch_equals_each_task_alone():
    # N = 2000 realizations at two couplings share lanes per coupling; N = 100 runs alone
    tasks = ensemble_tasks([2000], [2.9, 4.0], 3, 5, 900.0, 100.0) + ensemble_tasks(
        [100], [2.9], 2, 5, 900.0, 100.0
    )
    batch = ensemble_batch(tasks)
    for task, got in zip(tasks, batch, strict=True):
        want = ensemble_task(**task)
        assert got.keys() == want.keys()
        for key in want:
            np.testing.assert_array_equal(np.asarray(got[key]), np.asarray(want[key]), key)
