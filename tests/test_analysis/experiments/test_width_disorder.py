"""The width-disorder study (analysis.experiments.width_disorder) on a tiny configuration: its
numbers against direct calls, resume from the store, the hyst width-disorder command."""

from __future__ import annotations

import dataclasses
import functools
import json
import math
import subprocess
import sys

import numpy as np
import pytest

import analysis.experiments.ensemble as ensemble_module
import analysis.experiments.width_disorder as wd
from analysis._json import to_json
from analysis.cli import main
from analysis.dynamics.lyapunov import lyapunov_spectrum
from hysteresis import GeneralizedPlay
from oscillators import ForcedOscillator

T = 2 * math.pi
#: tiny sizes: every step runs, the continuous Preisach point by the engine select_engine picks
TINY = dict(
    t_end=10 * T,
    transient_periods=2,
    section_t_end=14 * T,
    blocks=4,
    projection_periods=(1,),
    spins=(60,),
    realizations=2,
    finite_t_end=12 * T,
    finite_transient_periods=2,
)


def _counting(monkeypatch, module, name):
    calls = []
    real = getattr(module, name)

    @functools.wraps(real)  # validate_ensemble reads the task function's signature
    def wrapper(**task):
        calls.append(task)
        return real(**task)

    monkeypatch.setattr(module, name, wrapper)
    return calls


def test_quick_study_numbers_and_resume(tmp_path, monkeypatch):
    store = tmp_path / "s.sqlite"
    cont_calls = _counting(monkeypatch, wd, "continuum_task")
    ens_calls = _counting(monkeypatch, ensemble_module, "ensemble_task")
    rec1 = wd.run_study("quick", store=store, workers=1, initial_conditions=1, **TINY)
    # one initial condition: the play and σ_r = 0.2 at C = 4; finite N: σ_r ∈ {0, 0.2}
    assert len(cont_calls) == 2 and len(ens_calls) == 2 * 2
    assert [(p["coupling"], p["width_spread"]) for p in rec1["continuum"]] == [
        (4.0, 0.0),
        (4.0, 0.2),
    ]
    play = rec1["continuum"][0]["runs"][0]
    # the study's play point is the plain lyapunov_spectrum of the erf play (the same orbit)
    system = ForcedOscillator(GeneralizedPlay.erf(2.0, 1.0), 4.0, damping_ratio=0.05)
    direct = lyapunov_spectrum(system, 10 * T, 2 * T, q0=-1.0, v0=0.1)
    assert np.allclose(np.asarray(play["exponents"], dtype=float), direct.exponents, rtol=1e-12)
    assert play["tangent_space"] == ["q", "v", "w"] and play["live_memory_max"] == 1
    # the section: one point per period from the window, continued to section_t_end
    assert play["section_points"] == (10 - 2) + (14 - 10)
    # the play's memory never outlives a period: the frozen loop drops nothing and follows the
    # same orbit, so λ_1 differs only by the norm of the final vector, (q, v, w) against (q, v)
    # (|δw| is δq at the last wall hit, within a factor 10: log(10)/W)
    assert play["frozen_exponents"][0][0] == pytest.approx(
        float(play["exponents"][0]), abs=math.log(10) / (8 * T)
    )
    pre = rec1["continuum"][1]["runs"][0]
    assert pre["tangent_space"][:2] == ["q", "v"] and pre["live_memory_min"] >= 0
    assert pre["finite_exponents"] <= len(pre["tangent_space"])
    fin = {(r["width_spread"], r["spins"], r["coupling"]): r for r in rec1["finite"]}
    assert set(fin) == {(0.0, 60, 4.0), (0.2, 60, 4.0)}
    assert all(r["realizations"] == 2 for r in fin.values())

    # resume: nothing is recomputed, the record is the same
    cont_calls.clear()
    ens_calls.clear()
    rec2 = wd.run_study("quick", store=store, workers=1, initial_conditions=1, **TINY)
    assert cont_calls == [] and ens_calls == []
    for part in ("continuum", "finite"):  # compared as JSON text (nan == nan there)
        assert to_json(rec2[part]) == to_json(rec1[part])
    # a larger run computes only the new initial condition (the list is prefix-stable)
    rec3 = wd.run_study(
        "quick", store=store, workers=1, initial_conditions=2, parts=("continuum",), **TINY
    )
    assert len(cont_calls) == 2 and {c["q0"] for c in cont_calls} == {
        wd.initial_conditions(2)[1][0]
    }
    assert all(len(p["runs"]) == 2 for p in rec3["continuum"])


def test_initial_conditions_are_seeded_and_prefix_stable():
    a, b = wd.initial_conditions(4, seed=1), wd.initial_conditions(2, seed=1)
    assert a[:2] == b and a[0] == (-1.0, 0.1)
    assert wd.initial_conditions(3, seed=2)[1:] != a[1:3]
    with pytest.raises(ValueError, match="initial_conditions"):
        wd.initial_conditions(0)


def test_run_study_refuses_bad_arguments():
    with pytest.raises(ValueError, match="size must be one of"):
        wd.run_study("huge")
    with pytest.raises(ValueError, match="parts"):
        wd.run_study("quick", parts=("everything",))
    with pytest.raises(ValueError, match="t_end"):
        wd.continuum_tasks(
            wd.SIZES["quick"].__class__(**{**wd.SIZES["quick"].__dict__, "t_end": 1.0})
        )
    # a section shorter than the spectrum's run would silently be cut to t_end
    quick = wd.SIZES["quick"]
    with pytest.raises(ValueError, match=r"^section_t_end=.* must be >= t_end") as exc:
        wd.continuum_tasks(dataclasses.replace(quick, section_t_end=quick.t_end - 1.0))
    assert "\n" not in str(exc.value)
    assert wd.continuum_tasks(dataclasses.replace(quick, section_t_end=quick.t_end))


def test_cli_finite_part_writes_json_and_figure(tmp_path, capsys):
    code = main(
        [
            "width-disorder",
            "--quick",
            "--part",
            "finite",
            "--spins",
            "40",
            "--realizations",
            "2",
            "--workers",
            "1",
            "--out",
            str(tmp_path / "wd"),
            "--quiet",
        ]
    )
    assert code == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("width-disorder: 0 continuum points")
    rec = json.loads((tmp_path / "wd" / "width_disorder.json").read_text())
    assert {(r["width_spread"], r["spins"]) for r in rec["finite"]} == {(0.0, 40), (0.2, 40)}
    assert (tmp_path / "wd" / "width_disorder.png").stat().st_size > 10_000
    assert (tmp_path / "wd" / "results.sqlite").exists()


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["--spins", "101"], "argument --spins: must be even"),
        (["--t-end", "1"], "argument --t-end"),
        (["--t-end", "200", "--section-t-end", "150"], "argument --section-t-end: section_t_end"),
        (["--width-spreads", "-0.1"], "argument --width-spreads"),
        (["--part", "all"], "argument --part"),
        (["--initial-conditions", "0"], "argument --initial-conditions"),
        (["--spins", "40", "60", "--realizations", "1", "2", "3"], "argument --realizations"),
    ],
)
def test_cli_errors_are_one_line(argv, needle, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    code = main(["width-disorder", "--quick", *argv])
    lines = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(lines) == 1 and needle in lines[0], lines
    assert lines[0].startswith("hyst width-disorder: error: ")
    assert not (tmp_path / "hyst-out").exists()


def test_cli_error_from_a_real_process(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "analysis.cli", "width-disorder", "--spins", "7"],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=tmp_path,
    )
    assert proc.returncode == 2
    assert (
        proc.stderr.strip() == "hyst width-disorder: error: argument --spins: must be even, got 7"
    )


def test_plot_study_keeps_the_callers_matplotlib_backend(tmp_path):
    """Importing and calling the plot leaves the backend a program chose (no ``matplotlib.use``)."""
    row = {"width_spread": 0.2, "spins": 40, "coupling": 2.9, "realizations": 2}
    record = {
        "continuum": [],
        "finite": [{**row, "mean_kaplan_yorke": 1.5, "mean_box_counting": 1.2}],
        "size": {
            "projection_periods": [],
            "t_end": 10,
            "finite_t_end": 10,
            "initial_conditions": 1,
        },
    }
    code = (
        "import sys, json, matplotlib; matplotlib.use('svg'); "
        "from analysis.experiments.width_disorder_plot import plot_study; "
        "plot_study(json.loads(sys.argv[1]), sys.argv[2]); print(matplotlib.get_backend())"
    )
    png = tmp_path / "wd.png"
    proc = subprocess.run(
        [sys.executable, "-c", code, json.dumps(record), str(png)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "svg"
    assert png.stat().st_size > 10_000
