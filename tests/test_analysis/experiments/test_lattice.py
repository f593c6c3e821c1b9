"""The lattice study (analysis.experiments.lattice): resume after an interruption, the JSON's
fields, the registry model rfim, and physics checks against independent truth."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import analysis.experiments.lattice as lat
import analysis.experiments.lattice_control as lattice_control
from analysis.cli import main
from analysis.dynamics.lyapunov import lyapunov_spectrum
from analysis.experiments.models import build_operator, describe_model, model_record
from analysis.experiments.parameters import DAMPING_RATIO
from hysteresis import PreisachModel, RandomFieldIsing
from oscillators import ForcedOscillator

T = 2 * math.pi
TINY = dict(
    disorders=(2.16, 3.5), sides=(6,), couplings=(4.0,), realizations=2, periods=30,
    transient_periods=10, barkhausen_periods=5, identification_nodes=24, margin=1.0,
)  # fmt: skip


class _Stop(Exception):
    pass


def test_store_resumes_after_an_interruption_with_equal_results(tmp_path, monkeypatch):
    """A run killed after two tasks resumes from the store: only the missing tasks run, and
    the record equals an uninterrupted run's."""
    real = lat.lattice_task
    calls = []

    def failing(**task):
        if len(calls) == 2:
            raise _Stop
        calls.append(task)
        return real(**task)

    monkeypatch.setattr(lat, "lattice_task", failing)
    store = tmp_path / "s.sqlite"
    with pytest.raises(Exception):  # noqa: B017 (run_tasks wraps the worker's error)
        lat.run_study("small", store=store, workers=1, **TINY)
    assert len(calls) == 2
    counted = []

    def counting(**task):
        counted.append(task)
        return real(**task)

    monkeypatch.setattr(lat, "lattice_task", counting)
    resumed = lat.run_study("small", store=store, workers=1, **TINY)
    assert len(counted) == 4 - 2
    fresh = lat.run_study("small", store=None, workers=1, **TINY)
    for a, b in zip(resumed["points"], fresh["points"], strict=True):
        a, b = dict(a), dict(b)
        a.pop("seconds"), b.pop("seconds")
        assert json.dumps(a, sort_keys=True, default=str) == json.dumps(
            b, sort_keys=True, default=str
        )


def test_small_run_json_has_every_field_and_the_flips_add_up(tmp_path, capsys):
    rc = main(["lattice", "--sides", "6", "--disorders", "3.5", "--realizations", "1",
               "--periods", "30", "--transient-periods", "10", "--barkhausen-periods", "5",
               "--out", str(tmp_path), "--quiet", "--workers", "1"])  # fmt: skip
    assert rc == 0
    line = capsys.readouterr().out.strip().splitlines()
    assert len(line) == 1 and line[0].startswith("lattice: ")
    rec = json.loads((tmp_path / "lattice.json").read_text())
    assert (tmp_path / "lattice.png").stat().st_size > 0
    assert len(rec["points"]) == 2  # the default couplings 2.9 and 4.0
    keys = {
        "disorder", "side", "n_spins", "coupling", "realizations", "lattice", "preisach",
        "same_attractor_type", "lambda_max_difference", "operator_error_rms",
        "operator_error_on_nodes_rms", "operator_error_on_nodes_max", "barkhausen_flips_match",
        "coupled_avalanches_per_period", "coupled_mean_size", "coupled_largest_fraction",
        "coupled_tau", "sweep_mean_size", "sweep_largest_fraction", "sweep_tau",
        "coupled_histogram", "sweep_histogram", "bin_edges", "major_largest_fraction",
        "major_tau", "major_histogram", "identification_residual_rms",
        "identification_negative_mass", "identification_relays", "identification_scale",
        "seconds", "congruency_violation", "congruency_mean_violation",
        "congruency_violation_values", "same_attractor_values",
    }  # fmt: skip
    side = {"lambda_max", "kaplan_yorke", "box_counting", "magnetization", "fraction_regular"}
    for p in rec["points"]:
        assert keys <= set(p)
        assert side <= set(p["lattice"]) and side <= set(p["preisach"])
        # the avalanche sizes of the coupled motion sum to the flips the engine counted
        assert p["barkhausen_flips_match"] is True
        # the lattice's minor loops are not congruent (R = 3.5, L = 6: violation >= 2/N)
        assert p["congruency_violation"][0] >= 2 / 216
    assert rec["answer"] == line[0]


def test_rfim_registry_model_builds_and_couples():
    op = build_operator("rfim", lattice=(5, 5, 5), disorder=2.6, seed=4)
    ref = RandomFieldIsing.lattice((5, 5, 5), 2.6, seed=4)
    assert isinstance(op, RandomFieldIsing) and op.n_spins == 125
    assert np.array_equal(op.fields, ref.fields) and op.spin_coupling == 1.0
    rec = model_record("rfim", lattice=(5, 5, 5), disorder=2.6, seed=4)
    assert rec == {"model": "rfim", "lattice": (5, 5, 5), "disorder": 2.6, "seed": 4}
    assert describe_model(rec) == "rfim L=5x5x5 R=2.6 seed=4"
    with pytest.raises(ValueError, match=r"^lattice must be 1 to 3 integers >= 3"):
        build_operator("rfim", lattice=(2, 5))
    with pytest.raises(ValueError, match=r"^disorder must be"):
        build_operator("rfim", lattice=(5, 5, 5), disorder=-1.0)
    # coupled: the piecewise-constant operator leaves the (q, v) flow's volume contraction
    # alone (saltations have det 1), so λ1 + λ2 = −2ζ exactly up to rounding
    system = ForcedOscillator(op, 2.9, damping_ratio=DAMPING_RATIO)
    res = lyapunov_spectrum(system, 40 * T, 10 * T, q0=-1.0, v0=0.1)
    assert sum(res.exponents) == pytest.approx(-2 * DAMPING_RATIO, abs=1e-9)
    assert res.n_switches > 0


def test_cli_rfim_lyapunov(tmp_path, capsys):
    argv = ["lyapunov", "--model", "rfim", "--lattice", "6", "6", "6", "--disorder", "2.6"]
    rc = main([*argv, "--coupling", "2.9", "--t-end", "60", "--out", str(tmp_path), "--quiet"])
    assert rc == 0
    bad = ["lyapunov", "--model", "dimers", "--disorder", "3", "--coupling", "2.9"]
    assert main([*bad, "--out", str(tmp_path)]) != 0
    assert "--disorder: only for --model rfim" in capsys.readouterr().err


def test_coupled_avalanches_replay_through_the_operator():
    """The switches of the coupled trajectory are the avalanches the operator itself finds
    when driven through the inputs at which they happened (independent: the sweep kernel)."""
    op = RandomFieldIsing.lattice((8, 8, 8), 2.6, seed=2)
    system = ForcedOscillator(op, 4.0)
    traj = system.trajectory(6 * T, -1.0, 0.1, sample_dt=T)
    sw = traj.switches
    sizes = np.rint(np.abs(sw["jump"]) * op.n_spins / 2).astype(np.int64)
    # replay: each switch's input, nudged past the trigger in the direction of the jump
    u = np.where(sw["jump"] > 0, sw["q"] + 1e-9, sw["q"] - 1e-9)
    _, replay, _ = op.avalanches(np.concatenate([[-1.0], u]))
    assert np.array_equal(np.sort(replay), np.sort(sizes))
    assert sizes.sum() == replay.sum()


@pytest.mark.parametrize("nodes", [30, 150])
def test_identified_model_reproduces_the_major_loop_at_large_disorder(nodes):
    """At R = 3.5 (far above R_c) the identified Preisach model's major loop on the grid nodes
    matches the lattice's within the identification's own bound √n·rms on the Everett function
    (an output is twice an Everett value, so |ΔM| <= 2√n·rms), and its scale is 1; on the
    coarse grid (dense NNLS) and on a fine one (the sparse second-difference solve)."""
    op = RandomFieldIsing.lattice((8, 8, 8), 3.5, seed=1)
    model, info = lat.identify_lattice(op, 8.0, nodes)
    assert info["scale"] == pytest.approx(1.0, abs=1e-9)
    grid = np.asarray(info["grid"])
    up = np.concatenate([grid, grid[::-1][1:]])
    m_l, _ = op.apply(up, op.initial_state(grid[0]))
    m_p, _ = model.apply(up, model.initial_state(grid[0]))
    assert np.max(np.abs(m_l - m_p)) <= 2 * info["residual_bound"] + 1e-12
    # from_identification is the same projection
    assert isinstance(model, PreisachModel)


def test_avalanche_statistics_closed_form():
    """The MLE exponent of sizes drawn from a discrete power law (inverse transform of the
    continuous approximation) recovers τ within 4 standard errors plus the approximation's own
    bias at S_MIN = 2 (rounding x >= 1.5 to integers; a few percent, Clauset, Shalizi and
    Newman 2009, fig. 3: 0.03 here, bounded by 0.05)."""
    rng = np.random.default_rng(0)
    tau = 2.0
    s = np.floor((lat.S_MIN - 0.5) * (1 - rng.random(20000)) ** (-1 / (tau - 1)) + 0.5)
    st = lat.avalanche_statistics(s.astype(np.int64), 10**9)
    assert abs(st["tau"] - tau) < 4 * st["tau_err"] + 0.05
    assert st["total"] == int(s.sum()) and sum(st["histogram"]) == s.size


def test_grid_control_is_exact_on_the_coarse_nodes():
    """The control's coarse model is a Preisach model identified from a Preisach model (the
    lattice's fine model): on the coarse grid's nodes it reproduces its parent exactly (no
    non-Preisach part; the error is the NNLS residual, here round-off), between them the
    staircase remains."""
    seed = lat.lattice_seeds(0, 6, 1)[0]
    out = lattice_control.grid_control_task(2.6, 6, seed, [4.0], 30, 10, 5, 1.0, 60, 16)
    (rec,) = out["couplings"]
    assert rec["operator_error_on_nodes"]["max"] <= 1e-12
    assert rec["operator_error"]["max"] > 0.01
    assert out["relays"][0] >= out["relays"][1] > 0
