"""Disorder ensembles: per-realization physics, aggregation, executors, the CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest

from analysis.experiments.ensemble import (
    EXPERIMENT,
    aggregate_ensemble,
    ensemble_task,
    ensemble_tasks,
    realization_seeds,
    run_ensemble,
)
from analysis.experiments.one_pass import one_pass_measurements, section_and_magnetization
from analysis.experiments.store import ResultStore

ZETA = 0.05


def _system(operator, coupling):
    from oscillators import ForcedOscillator

    return ForcedOscillator(operator, coupling, damping_ratio=ZETA, frequency=1.0)


def test_magnetization_average_is_exact_and_section_matches():
    from hysteresis.spin_dimers import SpinDimerEnsemble

    system = _system(SpinDimerEnsemble.random(40, 2.0, 1.0, 2.0, 5), 4.0)
    t_end, transient = 40 * system.period, 10 * system.period
    q, v, m_t, window = section_and_magnetization(system, t_end, transient, chunk_periods=7)
    assert window == pytest.approx(30 * system.period)
    # the chunked section equals one uninterrupted section (short enough that chaos does not
    # amplify round-off beyond 1e-9)
    sec = system.poincare_section(30, 10)
    assert np.allclose(q, sec.q, atol=1e-9) and np.allclose(v, sec.v, atol=1e-9)
    # independent estimate: midpoint rule on a fine grid of the sampled M(t)
    start = system.poincare_section(1, 10).final
    dt = system.period / 4000
    traj = system.trajectory(
        30 * system.period, start.q, start.v, start.operator_state, sample_dt=dt
    )
    sampled = np.mean(traj.M[:-1])
    # the sampled average errs by at most (number of switches) · |ΔM| · dt / window
    bound = traj.switches.size * (2.0 / 40) * dt / window
    assert abs(m_t - sampled) <= bound + 1e-12
    assert bound < 1e-2  # the check is sharp


@pytest.mark.parametrize("model", ["dimers", "preisach"])
def test_one_pass_equals_separate_runs(model):
    # one integration with the tangent flow gives the same section, M_T and spectrum as the
    # separate Lyapunov run and the chunked section/magnetization run (the trajectory does not
    # depend on the tangent flow; 300 time units keep chaotic amplification of round-off small)
    from analysis.dynamics.lyapunov import lyapunov_spectrum
    from analysis.experiments.models import build_operator

    extra = {"spin_coupling": 2.0} if model == "dimers" else {"width_spread": 0.3}
    op = build_operator(model, spins=200, seed=3, width=2.0, spread=1.0, **extra)
    system = _system(op, 2.9)
    period = system.period
    ly, q, v, m_t, window = one_pass_measurements(system, 400.0, 100.0)
    q2, v2, m_t2, window2 = section_and_magnetization(system, 400.0, 100.0, chunk_periods=9)
    assert q.size == 47 == q2.size  # periods 16 .. 62 of [100, 400]
    assert window == pytest.approx(window2) and window == pytest.approx(47 * period)
    assert np.allclose(q, q2, atol=1e-9) and np.allclose(v, v2, atol=1e-9)
    assert m_t == pytest.approx(m_t2, abs=1e-12)
    ref = lyapunov_spectrum(system, 63 * period, 16 * period, renormalize_dt=period)
    assert np.allclose(ly.exponents, ref.exponents, atol=1e-9)


def test_output_integral_kernel_equals_generic_and_switch_sum():
    # the kernel's running ∫M dt against the Python reference loop and against the switch
    # records (∫M = M0·Δ + Σ ΔM_j (Δ − t_j)), for the nested (dimers) and heap (random widths)
    # tables
    from analysis.experiments.models import build_operator

    for op in (
        build_operator("dimers", spins=60, seed=2, width=2.0, spread=1.0, spin_coupling=2.0),
        build_operator("preisach", spins=60, seed=2, width=2.0, spread=1.0, width_spread=0.4),
    ):
        system = _system(op, 3.5)
        state = system.initial_state(-1.0, 0.1)
        length = 12.5 * system.period
        values = []
        for method in ("auto", "generic"):
            eng = system.engine(state, method=method)
            out = np.empty((1, 3))
            eng.advance(np.array([0.0]), out)
            m0 = out[0, 2]
            eng.advance(np.array([length]), record=True)
            sw = eng.records()["switches"]
            assert sw.size > 20
            by_switches = m0 * length + np.sum(sw["jump"] * (length - sw["time"]))
            assert eng.output_integral() == pytest.approx(by_switches, abs=1e-11)
            values.append(eng.output_integral())
        assert values[0] == pytest.approx(values[1], abs=1e-11)


def test_output_integral_refused_where_not_exact():
    from hysteresis import PlayOperator
    from oscillators import ForcedOscillator

    eng = ForcedOscillator(PlayOperator(2.0), 0.5).engine()
    with pytest.raises(NotImplementedError, match="integral"):
        eng.output_integral()


def test_regular_realization_single_dimer_above_grazing():
    # one dimer b = (1, -1), J = 2 at C = 9.5 > 9: the orbit stays on the sheet M = -1 (see
    # test_bifurcation), so M_T = -1, D_KY = 0 and the section is one point (D_BC = 0)
    from analysis.experiments.ensemble import section_dimension
    from hysteresis.spin_dimers import SpinDimerEnsemble

    system = _system(SpinDimerEnsemble(fields=[[1.0, -1.0]], spin_coupling=2.0), 9.5)
    q, v, m_t, _ = section_and_magnetization(system, 1500.0, 1000.0)  # e^(-ζ·1000) ~ 1e-22
    assert m_t == pytest.approx(-1.0, abs=1e-12)  # round-off of the chunk sums only
    assert np.allclose(q, -9.5, atol=1e-6) and np.allclose(v, 10.0, atol=1e-6)
    d_bc, _, period = section_dimension(q, v, 0.1, 8.0)
    assert d_bc == 0.0 and period == 1


def test_ensemble_task_chaotic_realization_invariants():
    res = ensemble_task(
        2000,
        4.0,
        seed=3,
        t_end=3000.0,
        transient=48 * 2 * np.pi,  # --transient counts forcing periods T = 2 pi
        box_max_fill=0.3,
        box_min_boxes=4.0,
    )
    lam = res["exponents"]
    assert lam.shape == (2,)
    # phase space volume in the section (q, v) contracts at rate 2ζ (paper: Σλ = −2ζ)
    assert lam.sum() == pytest.approx(-2 * ZETA, abs=1e-3)
    assert res["max_exponent"] > 0.01  # chaotic (paper: C = 4.0 is chaotic)
    assert res["kaplan_yorke"] == pytest.approx(1.0 + lam[0] / abs(lam[1]))
    assert 1.0 < res["box_counting"] < 2.0
    assert res["section_period"] == 0
    assert -1.0 <= res["magnetization"] <= 1.0
    assert res["section_points"] == int(3000.0 / (2 * np.pi)) - int(np.ceil(300.0 / (2 * np.pi)))


def test_aggregate_closed_forms():
    records = []
    dky = [0.0, 1.2, 1.4, 0.0]
    dbc = [0.0, 1.3, float("nan"), 0.0]
    m = [0.1, -0.1, 0.3, -0.3]
    for i in range(4):
        records.append(
            (
                {"spins": 100, "coupling": 2.9, "seed": i},
                {
                    "kaplan_yorke": dky[i],
                    "box_counting": dbc[i],
                    "magnetization": m[i],
                    "max_exponent": -0.05 if dky[i] == 0 else 0.03,
                },
            )
        )
    records.append(
        (
            {"spins": 200, "coupling": 2.9, "seed": 0},
            {"kaplan_yorke": 0.0, "box_counting": 0.0, "magnetization": 0.5, "max_exponent": -0.05},
        )
    )
    pts = aggregate_ensemble(records)
    assert [(p.spins, p.coupling, p.realizations) for p in pts] == [(100, 2.9, 4), (200, 2.9, 1)]
    p = pts[0]
    assert p.mean_kaplan_yorke == pytest.approx(0.65)
    assert p.sap_kaplan_yorke == pytest.approx((np.mean(np.square(dky)) - 0.65**2) / 0.65**2)
    assert p.mean_box_counting == pytest.approx(1.3 / 3)  # nan left out
    assert p.var_magnetization == pytest.approx(np.mean(np.square(m)))  # mean 0
    assert p.regular_count == 2
    assert np.isnan(pts[1].sap_kaplan_yorke)  # all regular: SAP undefined
    js = p.to_json()
    for key in (
        "spins",
        "coupling",
        "realizations",
        "mean_kaplan_yorke",
        "sap_kaplan_yorke",
        "mean_box_counting",
        "sap_box_counting",
        "var_magnetization",
        "regular_count",
    ):
        assert key in js
    json.dumps([q.to_json() for q in pts])  # nan -> None keeps it valid JSON
    assert json.loads(json.dumps(pts[1].to_json()))["sap_kaplan_yorke"] is None


def test_seeds_shared_across_couplings_independent_across_sizes():
    tasks = ensemble_tasks([20, 40], [2.9, 4.0], 3, base_seed=7, t_end=10.0, transient=1.0)
    assert len(tasks) == 12
    seeds = {(t["spins"], t["coupling"]): [] for t in tasks}
    for t in tasks:
        seeds[(t["spins"], t["coupling"])].append(t["seed"])
    assert seeds[(20, 2.9)] == seeds[(20, 4.0)] == realization_seeds(7, 20, 3)
    assert set(seeds[(20, 2.9)]).isdisjoint(seeds[(40, 2.9)])


def test_small_ensemble_identical_serial_and_pool(tmp_path):
    kw = dict(
        spins_list=[20, 40],
        couplings=[4.0],
        realizations=3,
        base_seed=1,
        t_end=400.0,
        transient=50.0,
        progress=False,
        box_max_fill=0.3,
        box_min_boxes=4.0,
    )
    serial = run_ensemble(workers=1, store=tmp_path / "serial.sqlite", **kw)
    pool = run_ensemble(workers=2, store=tmp_path / "pool.sqlite", **kw)
    for a, b in zip(serial, pool, strict=True):
        assert a.to_json() == b.to_json()
        for field in ("kaplan_yorke", "box_counting", "magnetization", "max_exponent"):
            assert getattr(a, field).tobytes() == getattr(b, field).tobytes()
    with ResultStore(tmp_path / "pool.sqlite") as store:
        assert len(store.keys(EXPERIMENT)) == 6
    # a rerun is served from the store
    again = run_ensemble(workers=1, store=tmp_path / "serial.sqlite", **kw)
    assert [p.to_json() for p in again] == [p.to_json() for p in serial]


def test_cli_ensemble_json(tmp_path, capsys):
    from analysis.cli import main

    code = main(
        [
            "ensemble", "--model", "dimers", "--spins", "20", "--coupling", "4.0", "2.9",
            "--realizations", "2", "--t-end", "300", "--transient", "8", "--workers", "1",
            "--store", str(tmp_path / "s.sqlite"), "--out", str(tmp_path / "out"), "--json",
            "--box-max-fill", "0.3", "--box-min-boxes", "4",
        ]
    )  # fmt: skip
    assert code == 0
    record = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert [(p["spins"], p["coupling"]) for p in record["points"]] == [(20, 2.9), (20, 4.0)]
    for p in record["points"]:
        assert p["realizations"] == 2 and 0 <= p["regular_count"] <= 2
        assert set(p) >= {
            "mean_kaplan_yorke",
            "sap_kaplan_yorke",
            "mean_box_counting",
            "sap_box_counting",
            "var_magnetization",
        }
    assert (tmp_path / "out" / "ensemble.json").exists()
    assert (tmp_path / "out" / "ensemble.npz").exists()


def test_cli_bifurcation_and_dimension(tmp_path, capsys):
    from analysis.cli import main

    code = main(
        [
            "bifurcation", "--model", "dimers", "--fields", "1", "-1", "--start", "9.5",
            "--stop", "8.5", "--steps", "5", "--periods", "40", "--transient", "100",
            "--lyapunov-t", "200", "--out", str(tmp_path / "bif"), "--json",
        ]
    )  # fmt: skip
    assert code == 0
    rec = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert rec["distinct_points"][:2] == [1, 1]  # C = 9.5, 9.25 above grazing
    data = np.load(tmp_path / "bif" / "bifurcation.npz")
    assert data["q"].shape == (5, 40) and data["values"][0] == 9.5
    assert (tmp_path / "bif" / "bifurcation.png").stat().st_size > 1000

    code = main(
        [
            "dimension", "--model", "dimers", "--spins", "2000", "--seed", "3", "--coupling",
            "4.0", "--t-end", "3000", "--transient", "48", "--max-fill", "0.3",
            "--min-boxes", "4", "--out", str(tmp_path / "dim"), "--json", "--quiet",
        ]
    )  # fmt: skip
    assert code == 0
    rec = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    task = ensemble_task(
        2000,
        4.0,
        seed=3,
        t_end=3000.0,
        transient=48 * 2 * np.pi,  # --transient counts forcing periods T = 2 pi
        box_max_fill=0.3,
        box_min_boxes=4.0,
    )
    assert rec["kaplan_yorke"] == pytest.approx(task["kaplan_yorke"], rel=1e-12)
    # the section points are a different (chaotically diverged) sample of the same attractor
    assert 1.0 < rec["box_counting"] < 2.0
    assert (tmp_path / "dim" / "dimension.png").exists()
