"""``hyst lyapunov`` / ``hyst trajectory`` / ``hyst poincare`` command lines."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from analysis.cli import main
from analysis.dynamics.dimensions import kaplan_yorke_dimension


@pytest.fixture(autouse=True)
def _in_tmp(tmp_path, monkeypatch):
    """Commands write to --out (default hyst-out in the working directory): keep it in tmp."""
    monkeypatch.chdir(tmp_path)


def run_cli(*args):
    proc = subprocess.run(
        [sys.executable, "-m", "analysis.cli", *args],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=Path.cwd(),
    )
    assert proc.returncode == 0, proc.stderr
    return proc.stdout


def test_lyapunov_dimers_json():
    out = run_cli(
        "lyapunov",
        "--model",
        "dimers",
        "--spins",
        "200",
        "--coupling",
        "4.0",
        "--t-end",
        "200",
        "--json",
    )
    rec = json.loads(out)
    assert len(rec["exponents"]) == 2
    lam = np.array(rec["exponents"], dtype=float)
    assert lam[0] >= lam[1]
    assert abs(lam.sum() + 2 * 0.05) < 1e-6
    assert rec["switches"] > 100 and rec["t_end"] == 200.0
    assert rec["spins"] == 200 and rec["seed"] == 0 and rec["damping_ratio"] == 0.05
    assert isinstance(rec["kaplan_yorke"], float)
    # no memory rows: the full-space value, no second run
    assert rec["kaplan_yorke_source"] == "full space"
    assert rec["kaplan_yorke"] == rec["kaplan_yorke_full_space"]
    assert rec["memory_frozen_exponents"] is None


def test_lyapunov_include_phase_and_fields(capsys):
    code = main(
        [
            "lyapunov",
            "--model",
            "dimers",
            "--fields",
            "2",
            "0",
            "-0.5",
            "-2.5",
            "--coupling",
            "2.9",
            "--t-end",
            "300",
            "--include-phase",
            "--json",
        ]
    )
    assert code == 0
    rec = json.loads(capsys.readouterr().out)
    assert len(rec["exponents"]) == 3
    assert min(abs(float(x)) for x in rec["exponents"]) < 1e-9
    assert rec["fields"] == [[2.0, 0.0], [-0.5, -2.5]]


def test_lyapunov_relay_and_bad_input(capsys):
    assert (
        main(["lyapunov", "--model", "relay", "--coupling", "2", "--t-end", "300", "--json"]) == 0
    )
    rec = json.loads(capsys.readouterr().out)
    assert rec["alpha"] == 1.0 and rec["beta"] == -1.0
    assert (
        main(
            [
                "lyapunov",
                "--model",
                "dimers",
                "--spins",
                "20",
                "--coupling",
                "2",
                "--damping-ratio",
                "-1",
                "--json",
            ]
        )
        == 2
    )
    err = capsys.readouterr().err
    assert "--damping-ratio" in err and len(err.strip().splitlines()) == 1


def test_lyapunov_play_limit_minus_inf(capsys):
    pytest.importorskip("oscillators.engines.play")
    code = main(
        ["lyapunov", "--model", "erf-play", "--coupling", "4.0", "--t-end", "100", "--json"]
    )
    assert code == 0
    rec = json.loads(capsys.readouterr().out)
    assert len(rec["exponents"]) == 3
    assert rec["exponents"][-1] == "-inf"
    assert rec["w0"] == -2.0
    # the play's w is reset, never neutral: the full-space value is reported
    assert rec["kaplan_yorke_source"] == "full space"
    assert rec["kaplan_yorke"] == rec["kaplan_yorke_full_space"]
    lam = [float(x) for x in rec["exponents"]]
    assert rec["kaplan_yorke"] == kaplan_yorke_dimension(lam)


def test_lyapunov_preisach_gauss_reports_the_attractor_value(capsys):
    # continuous Preisach staircase at C = 4: neutral memory (long-lived extrema) distorts the
    # full spectrum; the reported D_KY is the memory-frozen one, the full-space one alongside
    argv = ["lyapunov", "--model", "preisach-gauss", "--coupling", "4", "--t-end", "3000"]
    assert main([*argv, "--json"]) == 0
    rec = json.loads(capsys.readouterr().out)
    lam = [float(x) for x in rec["exponents"]]
    assert rec["kaplan_yorke_source"] == "memory-frozen"
    assert rec["kaplan_yorke"] == kaplan_yorke_dimension(rec["memory_frozen_exponents"])
    assert rec["kaplan_yorke_full_space"] == kaplan_yorke_dimension(lam)
    assert "neutral memory" in rec["kaplan_yorke_note"]
    # the two differ by far more than the reported value's finite-time error
    assert 0 < rec["kaplan_yorke_error"] < 0.05
    assert abs(rec["kaplan_yorke_full_space"] - rec["kaplan_yorke"]) > 5 * rec["kaplan_yorke_error"]
    # the width-disorder study's range of the attractor's D_KY at C = 4 (1.38-1.41 at t = 2e4),
    # widened by 3 errors of this shorter run
    assert 1.38 - 3 * rec["kaplan_yorke_error"] <= rec["kaplan_yorke"]
    assert rec["kaplan_yorke"] <= 1.41 + 3 * rec["kaplan_yorke_error"]
    # the text says which value it used
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert f"D_KY = {rec['kaplan_yorke']:.4f}" in text and "memory-frozen" in text
    assert f"D_KY full space = {rec['kaplan_yorke_full_space']:.4f}" in text


def test_trajectory_and_poincare_files(tmp_path, capsys):
    assert (
        main(
            [
                "trajectory",
                "--model",
                "dimers",
                "--spins",
                "200",
                "--coupling",
                "4",
                "--t-end",
                "20",
                "--out",
                str(tmp_path),
            ]
        )
        == 0
    )
    data = np.load(tmp_path / "trajectory.npz")
    assert data["t"][-1] == pytest.approx(20.0) and data["switch_time"].size > 10
    assert (tmp_path / "trajectory.png").stat().st_size > 1000
    assert (
        main(
            [
                "poincare",
                "--model",
                "dimers",
                "--spins",
                "200",
                "--coupling",
                "4",
                "--periods",
                "30",
                "--transient-periods",
                "5",
                "--out",
                str(tmp_path),
            ]
        )
        == 0
    )
    sec = np.load(tmp_path / "poincare.npz")
    assert sec["q"].size == 30
    assert (tmp_path / "poincare.png").stat().st_size > 1000


def test_drawing_commands_keep_the_callers_matplotlib_backend(tmp_path):
    """A program that chose a backend and calls the commands (or imports their modules) keeps it:
    the commands draw without ``matplotlib.use``."""
    relay = ["--model", "relay", "--out", str(tmp_path), "--quiet"]
    commands = [
        ["trajectory", *relay, "--coupling", "2", "--t-end", "10"],
        ["poincare", *relay, "--coupling", "2", "--periods", "10", "--transient-periods", "2"],
        ["bifurcation", *relay, "--values", "1", "2", "--periods", "4", "--transient", "2",
         "--lyapunov-t", "0"],
        ["dimension", *relay, "--coupling", "2", "--t-end", "600", "--transient", "20"],
    ]  # fmt: skip
    code = (
        "import sys, json, matplotlib; matplotlib.use('svg'); "
        "from analysis.cli import main; "
        "codes = [main(argv) for argv in json.loads(sys.argv[1])]; "
        "print(codes, matplotlib.get_backend())"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code, json.dumps(commands)],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=tmp_path,
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip().splitlines()[-1] == "[0, 0, 0, 0] svg"
    for name in ("trajectory", "poincare", "bifurcation", "dimension"):
        assert (tmp_path / f"{name}.png").stat().st_size > 1000


def test_dimension_reports_the_attractor_value_like_lyapunov(tmp_path, capsys):
    # hyst dimension applies the same rule: the memory-frozen D_KY where neutral memory exists
    argv = ["dimension", "--model", "preisach-gauss", "--coupling", "4", "--t-end", "3000"]
    assert main([*argv, "--transient", "20", "--out", str(tmp_path), "--json"]) == 0
    rec = json.loads(capsys.readouterr().out)
    lam = [float(x) for x in rec["exponents"]]
    assert rec["kaplan_yorke_source"] == "memory-frozen"
    assert rec["kaplan_yorke"] == kaplan_yorke_dimension(rec["memory_frozen_exponents"])
    assert rec["kaplan_yorke_full_space"] == kaplan_yorke_dimension(lam)
    assert abs(rec["kaplan_yorke_full_space"] - rec["kaplan_yorke"]) > 5 * rec["kaplan_yorke_error"]
