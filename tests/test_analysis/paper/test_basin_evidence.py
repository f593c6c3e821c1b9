"""The basin and realization evidence of the report's Discussion: from a small configuration, the
records say what the numbers say (fractions, intervals, periods, multipliers, the band's starts,
the realizations' seeds), the lines print them, the runner writes the key, and an interrupted run
resumes from the report's store."""

from __future__ import annotations

import copy
import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import analysis.dynamics.basins as basins_module
import analysis.experiments.realizations as realizations_module
from analysis.experiments.ensemble import realization_seeds
from analysis.experiments.execution import TaskError
from analysis.experiments.models import build_operator
from analysis.experiments.parameters import DAMPING_RATIO, FREQUENCY
from analysis.experiments.store import ResultStore
from analysis.paper import runner
from analysis.paper.basin_evidence import (
    BASIN_SIZES,
    BasinEvidenceSize,
    _reduced,
    basin_evidence,
    basin_lines,
)
from analysis.paper.context import SIZES, PaperContext
from oscillators import ForcedOscillator

DOCS = Path(__file__).resolve().parents[3] / "docs" / "basins"

#: a few seconds: 2 couplings on 3 × 3 grids, a 4 × 4 (q0, w0) grid, 2 realizations of N = 60
SMALL = BasinEvidenceSize(
    name="test",
    couplings=(1.74, 1.80),
    neighbourhood_grid=3,
    neighbourhood_max_periods=300,
    band_grid=4,
    band_max_periods=1500,
    lyapunov_periods=200,
    chunk=4,
    realization_spins=60,
    # C = 1 instead of 2.9: both realizations settle on periodic orbits (periods 1 and 2)
    realization_coupling=1.0,
    realizations=2,
    realization_transient=20,
    realization_periods=60,
    realization_max_periods=200,
    realization_max_period=30,
    realization_lyapunov_periods=100,
)


def _wilson(k: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """The textbook Wilson score interval (Wilson 1927), written out independently (z = 1.96,
    the toolkit's rounded 97.5 % normal quantile)."""
    p = k / n
    centre = (2 * n * p + z * z) / (2 * (n + z * z))
    half = z * math.sqrt(z * z + 4 * n * p * (1 - p)) / (2 * (n + z * z))
    return max(0.0, centre - half), min(1.0, centre + half)


@pytest.fixture(scope="module")
def evidence(tmp_path_factory):
    ctx = PaperContext(tmp_path_factory.mktemp("basins"), SIZES["smoke"], workers=1)
    return basin_evidence(ctx, SMALL)


def _records(ev):
    return [*ev["neighbourhood"], ev["band"]]


def test_fractions_sum_to_one_and_lie_in_their_wilson_intervals(evidence):
    for rec in _records(evidence):
        counts = [a["count"] for a in rec["attractors"]]
        assert sum(counts) == rec["valid_starts"]
        # n fractions k/n, each rounded once: the sum is 1 within n ulps
        total = sum(a["fraction"] for a in rec["attractors"])
        assert abs(total - 1.0) <= len(counts) * np.finfo(float).eps
        for a in rec["attractors"]:
            lo, hi = a["interval"]
            assert lo <= a["fraction"] <= hi
            # the same interval as the textbook formula, to round-off
            assert np.allclose([lo, hi], _wilson(a["count"], rec["valid_starts"]), atol=1e-12)


def test_periodic_records_carry_period_multipliers_and_transients(evidence):
    periodic = [
        a for rec in _records(evidence) for a in rec["attractors"] if a["kind"] == "periodic"
    ]
    assert periodic, "the small configuration has periodic attractors (C = 1.80: period 3)"
    for a in periodic:
        assert a["period"] >= 1 and a["residual"] < 1e-8
        mu = np.array(a["multipliers"])
        assert mu.shape == (len(a["tangent_space"]), 2)
        assert np.allclose(a["multipliers_abs"], np.hypot(mu[:, 0], mu[:, 1]), rtol=0, atol=0)
        assert a["stable"] == (max(a["multipliers_abs"]) < 1.0)
        assert 0 <= a["transient_median"] <= a["transient_max"]
    for a in (a for rec in _records(evidence) for a in rec["attractors"]):
        if a["kind"] == "chaotic":  # the labelling rule: λ_max above twice its error
            assert a["max_exponent"] > 2 * a["max_exponent_error"] and a["kaplan_yorke"] >= 1


def test_the_period_at_c_1_80_is_that_of_a_direct_run_from_the_papers_start(evidence):
    rec = next(r for r in evidence["neighbourhood"] if r["coupling"] == 1.80)
    (only,) = [a for a in rec["attractors"] if a["kind"] == "periodic"]
    system = ForcedOscillator(build_operator("erf-play"), 1.80)
    sec = system.poincare_section(60, 400, -1.0, 0.1)  # 400 periods: past the transients
    x = np.column_stack([sec.q, sec.v])
    # the section period of the direct run: the smallest k that repeats within 1e-6
    k = next(k for k in range(1, 30) if np.all(np.abs(x[k:] - x[:-k]) <= 1e-6))
    assert only["period"] == k


def test_band_counts_the_grid_points_inside_the_play_band(evidence):
    band = evidence["band"]
    q = np.linspace(-3.0, 3.0, SMALL.band_grid)
    q0, w0 = np.meshgrid(q, q)
    # the play's band |q0 − w0| <= p/2 with p = 2
    assert band["valid_starts"] == int(np.count_nonzero(np.abs(q0 - w0) <= 1.0 + 1e-12))
    assert band["starts"] == SMALL.band_grid**2


def test_realizations_are_those_of_the_ensemble_seeds(evidence):
    real = evidence["realizations"]
    seeds = realization_seeds(0, SMALL.realization_spins, SMALL.realizations)
    assert [r["seed"] for r in real["records"]] == seeds
    assert sum(real["counts"].values()) == SMALL.realizations
    for r in real["records"]:
        if r["kind"] == "periodic":
            assert r["period"] <= SMALL.realization_max_period and r["multipliers"]
        elif r["kind"] in ("chaotic", "undecided"):
            assert (r["kind"] == "chaotic") == (r["max_exponent"] > 2 * r["max_exponent_error"])


def test_regular_realizations_obey_liouville(evidence):
    """A relay switch at a threshold q = α has a saltation of determinant 1 (the force jump
    is in v', the crossing speed q' = v is continuous), and the smooth flow's divergence is
    −2ζ: so |μ1 μ2| = exp(−2ζ k T) for every period-k orbit in (q, v)."""
    regular = [r for r in evidence["realizations"]["records"] if r["kind"] == "periodic"]
    assert len(regular) == SMALL.realizations
    for r in regular:
        mu = np.array(r["multipliers"])
        assert mu.shape == (2, 2) and r["period"] >= 1 and r["residual"] < 1e-10
        expected = math.exp(-2 * DAMPING_RATIO * r["period"] * 2 * math.pi / FREQUENCY)
        # the monodromy matrix is a product of k exact period Jacobians: round-off ~ k·1e-15
        assert np.prod(np.hypot(mu[:, 0], mu[:, 1])) == pytest.approx(expected, rel=1e-9)
        assert r["max_abs_multiplier"] == pytest.approx(np.hypot(mu[:, 0], mu[:, 1]).max())


def test_lines_state_grid_periods_reduction_and_each_fraction(evidence):
    text = "\n".join(basin_lines(evidence))
    assert text.startswith("### Basins of the coexisting attractors")
    assert "3 × 3 grid" in text and "up to 300 periods per start" in text
    assert "4 × 4 grid" in text and "in the band" in text
    assert "test mode: grid 3 × 3 (full: 20 × 20)" in text
    assert "N 60 (full: 20000)" in text and "realizations 2 (full: 50)" in text
    for rec in _records(evidence):
        for a in rec["attractors"]:
            lo, hi = a["interval"]
            assert f"{100 * a['fraction']:.1f} % [{100 * lo:.1f}, {100 * hi:.1f}]" in text
    json.dumps(evidence)  # JSON-ready as it stands


def test_full_size_is_the_committed_one_and_says_nothing_reduced():
    full = BASIN_SIZES["full"]
    committed = json.loads((DOCS / "erf_C1.74" / "basins.json").read_text())
    assert full.neighbourhood_grid == committed["grid"]["size"]
    assert full.neighbourhood_max_periods == committed["max_periods"]
    band = json.loads((DOCS / "erf_C2.92_w0" / "basins.json").read_text())
    assert (full.band_grid, full.band_max_periods) == (band["grid"]["size"], band["max_periods"])
    real = json.loads((DOCS / "dimers_N20000_C2.9_realizations.json").read_text())
    assert (full.realizations, full.realization_max_periods) == (
        real["realizations"],
        real["max_periods"],
    )
    assert all(_reduced(full, part) == "" for part in ("neighbourhood", "band", "realizations"))


def test_smoke_size_has_no_basin_sizes(tmp_path):
    with pytest.raises(ValueError, match="size"):
        basin_evidence(PaperContext(tmp_path, SIZES["smoke"]))


def test_run_paper_writes_the_basins_key_and_the_discussion_lines(tmp_path, monkeypatch):
    monkeypatch.setattr(runner, "_figures", lambda: [])
    monkeypatch.setattr(runner, "orbit_evidence", lambda: None)
    tiny = replace(SMALL, couplings=(1.80,), neighbourhood_grid=2, band_grid=2, realizations=1)
    monkeypatch.setattr(runner, "basin_evidence", lambda ctx: basin_evidence(ctx, tiny))
    report = runner.run_paper(tmp_path, size="quick", workers=1)
    assert not report["errors"]
    stored = json.loads((tmp_path / "report.json").read_text())
    assert stored["basins"]["band"]["valid_starts"] == report["basins"]["band"]["valid_starts"]
    discussion = (tmp_path / "report.md").read_text().split("## Discussion", 1)[1]
    assert "### Basins of the coexisting attractors" in discussion.split("\n## ", 1)[0]


def test_an_interrupted_run_resumes_from_the_reports_store(evidence, tmp_path, monkeypatch):
    ctx = PaperContext(tmp_path, SIZES["smoke"], workers=1)
    real_task = realizations_module.realization_attractor
    calls = {"realizations": 0, "chunks": 0}

    def dies_at_the_second(**task):
        calls["realizations"] += 1
        if calls["realizations"] == 2:
            raise KeyboardInterrupt("killed")  # stands for the kill
        return real_task(**task)

    monkeypatch.setattr(realizations_module, "realization_attractor", dies_at_the_second)
    with pytest.raises((KeyboardInterrupt, TaskError)):
        basin_evidence(ctx, SMALL)
    with ResultStore(ctx.store_path) as store:
        stored = {e: len(store.keys(e)) for e in store.experiments()}
    # every chunk of starts and the first realization were written as they completed
    chunks = sum(math.ceil(n * n / SMALL.chunk) for n in [3, 3, 4])
    assert stored == {"basins": chunks, "realization-attractors": 1}

    real_chunk = basins_module.basin_chunk

    def counted_chunk(**task):
        calls["chunks"] += 1
        return real_chunk(**task)

    def counted_realization(**task):
        calls["realizations"] += 1
        return real_task(**task)

    calls["realizations"] = 0
    monkeypatch.setattr(basins_module, "basin_chunk", counted_chunk)
    monkeypatch.setattr(realizations_module, "realization_attractor", counted_realization)
    resumed = basin_evidence(ctx, SMALL)
    # the rerun computes only the missing realization
    assert calls == {"realizations": SMALL.realizations - 1, "chunks": 0}
    # and gives what an uninterrupted run in another store gave
    for key in ("neighbourhood", "band", "realizations"):
        assert json.dumps(resumed[key], sort_keys=True) == json.dumps(evidence[key], sort_keys=True)


def test_realization_lines_give_each_kind_its_numbers(evidence):
    ev = copy.deepcopy(evidence)
    ev["realizations"]["counts"] = {"periodic": 1, "chaotic": 1, "undecided": 1}
    ev["realizations"]["records"] = [
        {"index": 0, "seed": 1, "kind": "periodic", "period": 7, "transient": 12,
         "multipliers": [[0.5, 0.0], [0.1, 0.0]], "max_abs_multiplier": 0.5, "stable": True,
         "residual": 1e-13},
        {"index": 1, "seed": 2, "kind": "chaotic", "max_exponent": 0.02,
         "max_exponent_error": 0.001, "kaplan_yorke": 1.2},
        {"index": 2, "seed": 3, "kind": "undecided", "max_exponent": -0.004,
         "max_exponent_error": 0.002, "kaplan_yorke": 0.0},
    ]  # fmt: skip
    line = basin_lines(ev)[-2]
    assert "1 periodic, 1 chaotic, 1 undecided" in line
    assert "realization 0: period 7 after 12 periods, max |μ| = 0.5" in line
    assert "Chaotic: λ_max 0.0200 … 0.0200" in line
    assert "Undecided (no period <= 30" in line and "λ_max -0.0040 … -0.0040" in line
