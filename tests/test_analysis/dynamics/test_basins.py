"""Basins of attraction (issue 19 item 3): classification of starts, one label per attractor,
fractions with Wilson intervals, resume after an interruption, disorder realizations.

The bistable case is the erf-play limit (p = 2, R = 1, ζ = 0.05, Ω = 1) at C = 1.74: a
period-3 orbit coexists with a chaotic attractor (λ_max ≈ 0.11 > 0); the paper's start
(q0, v0) = (−1, 0.1) is in the chaotic basin.
"""

from __future__ import annotations

import functools
import math
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

import analysis.dynamics.basins as basins_module
from analysis.dynamics.attractors import (
    PERIODIC,
    periodic_attractor,
    same_cycle,
    section_run,
    start_state,
)
from analysis.dynamics.basins import BasinGrid, basins
from analysis.dynamics.bifurcation import orbit_period
from analysis.dynamics.statistics import wilson_interval
from analysis.experiments.execution import run_tasks
from analysis.experiments.models import build_operator
from hysteresis import Relay
from oscillators import ForcedOscillator

# a short run: every start settles or shows chaos within 400 periods on this grid
RUN = dict(transient=0, periods=100, max_periods=400, lyapunov_periods=500)
GRID = BasinGrid((-3.0, 1.0), (-1.9, 2.1), 5)


@pytest.fixture(scope="module")
def bistable():
    system = ForcedOscillator(build_operator("erf-play"), 1.74)
    return system, basins(system, GRID, **RUN)


def test_bistable_map_is_covered_by_two_basins(bistable):
    _, bm = bistable
    kinds = sorted(a["kind"] for a in bm.attractors)
    assert kinds == ["chaotic", "periodic"], bm.attractors
    # the union of the basins is the whole grid: every start has an attractor's label
    assert np.all(bm.labels >= 0)
    assert sum(a["count"] for a in bm.attractors) == bm.labels.size
    assert math.isclose(sum(a["fraction"] for a in bm.attractors), 1.0)
    per = next(a for a in bm.attractors if a["kind"] == "periodic")
    chaos = next(a for a in bm.attractors if a["kind"] == "chaotic")
    assert per["period"] == 3 and per["stable"] and per["refined"]
    # the orbit closes: P^3(x) = x to the rounding of a few hundred periods of the kernel
    assert per["residual"] < 1e-9
    # chaos: λ_max significantly positive; D_KY between 1 and 2 for a flow section with a
    # contracting (q, v) pair and the collapsed w direction (λ = −inf)
    assert chaos["max_exponent"] > 2 * chaos["max_exponent_error"] > 0
    assert 1.0 < chaos["kaplan_yorke"] < 2.0
    # the fractions' intervals are Wilson's
    for a in bm.attractors:
        assert a["interval"] == list(wilson_interval(a["count"], bm.labels.size))
    d = bm.to_dict()
    assert d["valid_starts"] == 25 and len(d["attractors"]) == 2
    assert all(len(m) == 2 for m in d["attractors"][0 if per["label"] == 0 else 1]["multipliers"])


def test_each_label_is_reproduced_by_a_direct_run(bistable):
    """Every start, run again by ``poincare_section`` and classified here by ``orbit_period`` on
    (q, v): a periodic start repeats the attractor's orbit points (cyclic shift, 1e-4 = the
    match tolerance); a chaotic start shows no period up to 32 over 400 periods and stays in the
    chaotic attractor's section box."""
    system, bm = bistable
    per = next(a for a in bm.attractors if a["kind"] == "periodic")
    chaos_label = next(a["label"] for a in bm.attractors if a["kind"] == "chaotic")
    orbit_qv = np.asarray(per["points"])[:, :2]
    # the chaotic attractor's box from a long run of the paper's start (in its basin)
    ref = system.poincare_section(2000, 200, -1.0, 0.1)
    box_lo = np.array([ref.q.min(), ref.v.min()]) - 0.05
    box_hi = np.array([ref.q.max(), ref.v.max()]) + 0.05
    for (q0, v0, _), label in zip(bm.starts, bm.labels, strict=True):
        sec = system.poincare_section(401, 0, q0, v0)
        window_q, window_v = sec.q[-100:], sec.v[-100:]
        k = orbit_period(window_q, window_v, tolerance=1e-6, max_period=32)
        if label == per["label"]:
            assert k == per["period"], (q0, v0)
            cycle = np.column_stack([window_q[-k:], window_v[-k:]])
            assert same_cycle(cycle, orbit_qv, 1e-4), (q0, v0)
        else:
            assert label == chaos_label
            assert k == 0, (q0, v0)
            pts = np.column_stack([window_q, window_v])
            assert np.all((pts >= box_lo) & (pts <= box_hi)), (q0, v0)


def test_interrupted_run_resumes_to_identical_labels(bistable, tmp_path, monkeypatch):
    system, full = bistable
    store = tmp_path / "basins.sqlite"
    calls = []
    real_chunk = basins_module.basin_chunk

    def interrupted(**task):
        if len(calls) == 2:
            raise KeyboardInterrupt  # a kill after two stored chunks
        calls.append(1)
        return real_chunk(**task)

    monkeypatch.setattr(basins_module, "basin_chunk", interrupted)
    # the store-backed runner the CLI and the paper pass: every finished task is stored
    runner = functools.partial(run_tasks, "basins", store=store, workers=1, progress=False)
    with pytest.raises(KeyboardInterrupt):
        basins(system, GRID, chunk=5, executor=runner, system_key="erf C=1.74", **RUN)
    resumed = []

    def counting(**task):
        resumed.append(1)
        return real_chunk(**task)

    monkeypatch.setattr(basins_module, "basin_chunk", counting)
    again = basins(system, GRID, chunk=5, executor=runner, system_key="erf C=1.74", **RUN)
    assert len(resumed) == 5 - 2  # only the chunks that were not stored ran
    np.testing.assert_array_equal(again.labels, full.labels)
    np.testing.assert_array_equal(again.transients, full.transients)


def test_linear_oscillator_orbit_multipliers_closed_form():
    """C = 0: the relay does not act; the stroboscopic map is affine with the multipliers
    exp((−ζ ± i√(1−ζ²))·T) (both of modulus e^{−ζT}), period 1 from any start."""
    zeta = 0.05
    system = ForcedOscillator(Relay(0.5, -0.5), 0.0, zeta, 1.0)
    run = section_run(system, start_state(system, 0.3, -0.2), 800, 100, keep_state=True)
    assert run.status == PERIODIC and run.period == 1
    orbit = periodic_attractor(system, run.final, 1)
    mu = np.sort_complex(orbit["multipliers"])
    t = system.period
    expected = np.sort_complex(np.exp((-zeta + np.array([-1j, 1j]) * math.sqrt(1 - zeta**2)) * t))
    # the closed-form propagation of the relay engine is exact to rounding
    np.testing.assert_allclose(mu, expected, atol=1e-10)
    assert orbit["tangent_space"] == ("q", "v")


def test_w0_grid_blanks_the_starts_outside_the_play_band():
    system = ForcedOscillator(build_operator("erf-play"), 1.74)
    grid = BasinGrid((-1.0, 1.0), (-2.5, 2.5), 3, axis="w0")
    bm = basins(system, grid, transient=0, periods=20, max_periods=40, lyapunov_periods=100)
    starts = grid.starts()
    outside = np.abs(starts[:, 0] - starts[:, 2]) > 1.0  # p/2 = 1
    assert outside.any() and not outside.all()
    np.testing.assert_array_equal(bm.labels < 0, outside)
    assert sum(a["count"] for a in bm.attractors) == np.count_nonzero(~outside)


def test_wilson_interval_closed_forms():
    # k = 0: the upper end is z²/(n + z²); k = n: the lower end is n/(n + z²)
    z = 1.96
    assert wilson_interval(0, 10) == pytest.approx((0.0, z * z / (10 + z * z)))
    assert wilson_interval(10, 10) == pytest.approx((10 / (10 + z * z), 1.0))
    lo, hi = wilson_interval(50, 100)
    assert lo == pytest.approx(1 - hi) and lo < 0.5 < hi


def test_realization_attractor_dimers():
    from analysis.experiments.realizations import realization_attractors

    out = realization_attractors(
        [20],
        [2.9],
        2,
        0,
        transient=200,
        periods=100,
        max_periods=1000,
        lyapunov_periods=200,
        workers=1,
    )
    assert [r["spins"] for r in out] == [20, 20]
    for r in out:
        assert r["kind"] in ("periodic", "chaotic", "undecided")
        if r["kind"] == "periodic":
            # relays conserve phase-space area up to damping: μ1·μ2 = e^{−2ζkT}
            mu = np.asarray(r["multipliers"])
            prod = complex(*mu[0]) * complex(*mu[1])
            assert abs(prod) == pytest.approx(math.exp(-0.1 * r["period"] * 2 * math.pi), rel=1e-6)
        else:
            # λ1 + λ2 = −2ζ exactly for relays (saltation determinant 1)
            assert sum(r["exponents"]) == pytest.approx(-0.1, abs=1e-9)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        (dict(periods=1), "periods"),
        (dict(max_period=60), "max_period"),
        (dict(max_periods=50), "max_periods"),
        (dict(tolerance=0.0), "tolerance"),
        (dict(method="fast"), "method"),
    ],
)
def test_bad_arguments_are_refused(kwargs, message, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    system = ForcedOscillator(build_operator("erf-play"), 1.74)
    with pytest.raises(ValueError, match=message):
        basins(system, [[0.0, 0.0]], **{"transient": 0, "periods": 100, **kwargs})


def test_list_start_outside_the_band_is_refused():
    system = ForcedOscillator(build_operator("erf-play"), 1.74)
    with pytest.raises(ValueError, match="w0"):
        basins(system, [[0.0, 0.0, 5.0]], transient=0, periods=10)


def test_positive_feedback_runs_are_labelled_divergent():
    """The plain play at C = 1.5 > 1 (stiffness 1 − C < 0 on the walls) runs away from every
    start: one 'divergent' basin covering the list."""
    from hysteresis import PlayOperator

    with pytest.warns(RuntimeWarning, match="positive-feedback"):
        system = ForcedOscillator(PlayOperator(2.0), 1.5)
    bm = basins(system, [[0.0, 0.0], [5.0, 0.0], [-0.5, 0.2]], transient=0, periods=20)
    assert [(a["kind"], a["count"]) for a in bm.attractors] == [("divergent", 3)]
    assert np.all(bm.labels == 0) and np.all(bm.transients == -1)


def test_transient_length_matches_the_linear_closed_form():
    """C = 0 (relay thresholds never reached, M constant): the section map is affine,
    ``x_{n+1} − x* = Φ(T)(x_n − x*)`` with ``Φ = expm(A·T)``, ``A = [[0, 1], [−1, −2ζ]]`` and
    the fixed point from the particular solution ``Re(e^{iΩt}/(1 − Ω² + 2iζΩ))``. The transient
    is the first n after which ``|x_{i+1} − x_i|_∞ = |Φ^i (Φ − I) d_0|_∞ <= tol`` for good."""
    from scipy.linalg import expm

    zeta, omega, tol = 0.05, 1.0, 1e-6
    system = ForcedOscillator(Relay(100.0, -100.0), 0.0, zeta, omega)
    d = 1.0 - omega**2 + 2j * zeta * omega
    x_star = np.array([(1 / d).real, (1j * omega / d).real])
    d0 = np.array([1.0, 0.0])
    run = section_run(
        system, start_state(system, *(x_star + d0)), 0, 100, max_periods=2000, tolerance=tol
    )
    phi = expm(np.array([[0.0, 1.0], [-1.0, -2 * zeta]]) * system.period)
    diffs, y = [], (phi - np.eye(2)) @ d0
    for _ in range(2000):
        diffs.append(np.max(np.abs(y)))
        y = phi @ y
    expected = int(np.flatnonzero(np.array(diffs) > tol)[-1] + 1)
    assert run.status == PERIODIC and run.period == 1
    assert run.transient == expected
    # and a start on the orbit has no transient
    on = section_run(system, start_state(system, *x_star), 0, 10, tolerance=tol, max_period=5)
    assert on.transient == 0


def test_process_pool_and_dask_give_the_serial_labels(tmp_path):
    """The system travels to the workers with the task function (pickled); chunks of two starts
    on a process pool (an Executor, and run_tasks' own pool) and on a Dask cluster give the
    serial run's labels and transients."""
    distributed = pytest.importorskip("distributed")
    system = ForcedOscillator(build_operator("erf-play"), 1.80)  # period 3 from every start
    starts = [[-1.0, 0.1], [-0.5, 0.3], [0.5, -0.2], [1.5, 0.0]]
    kw = dict(transient=0, periods=60, max_periods=300, chunk=2)
    serial = basins(system, starts, **kw)
    with ProcessPoolExecutor(2) as ex:
        executor = basins(system, starts, executor=ex, **kw)
    pool = basins(system, starts, executor=functools.partial(run_tasks, "basins", workers=2), **kw)
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None
    ) as cluster:
        runner = functools.partial(run_tasks, "basins", scheduler=cluster.scheduler_address)
        dask = basins(system, starts, executor=runner, **kw)
    for other in (executor, pool, dask):
        np.testing.assert_array_equal(other.labels, serial.labels)
        np.testing.assert_array_equal(other.transients, serial.transients)
    assert [a["kind"] for a in serial.attractors] == ["periodic"]
