"""Issue 21: the CLI's one-line promise with warnings, the instability warning's slope, and
a divergence error that names C, ζ, Ω."""

from __future__ import annotations

import subprocess
import sys
import warnings
from pathlib import Path

import pytest

from analysis.cli._build import naming_divergence
from hysteresis import PlayOperator, PrandtlIshlinskii
from oscillators import ForcedOscillator
from oscillators.engines import DivergenceError


def test_warning_only_where_c_times_the_largest_slope_reaches_one():
    pi = PrandtlIshlinskii([1.0, 2.0, 3.0], [0.2, 0.2, 0.2])
    assert pi.max_slope == pytest.approx(0.6)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ForcedOscillator(pi, 1.03)  # stiffness 1 - 1.03 * 0.6 > 0: stable, no warning
    with pytest.warns(RuntimeWarning, match="positive-feedback"):
        ForcedOscillator(pi, 1 / 0.6 + 0.01)
    assert PlayOperator(1.0).max_slope == 1.0
    with pytest.warns(RuntimeWarning, match="positive-feedback"):
        ForcedOscillator(PlayOperator(1.0), 1.0)
    # negative weights do not add to the largest slope
    assert PrandtlIshlinskii([0.0, 1.0], [1.0, -0.5]).max_slope == 1.0


def test_diverging_run_warns_and_fails_in_one_line_each(tmp_path):
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "analysis.cli",
            "lyapunov",
            "--model",
            "play",
            "--coupling",
            "3",
            "--t-end",
            "100",
            "--quiet",
            "--out",
            str(tmp_path),
        ],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=Path(tmp_path),
    )
    assert proc.returncode == 2
    lines = proc.stderr.splitlines()
    assert len(lines) == 2, proc.stderr
    assert lines[0].startswith("hyst lyapunov: warning: ") and "positive-feedback" in lines[0]
    assert ".py" not in lines[0]  # no source path
    assert lines[1].startswith("hyst lyapunov: error: DivergenceError")
    assert lines[1].endswith("(coupling C = 3, ζ = 0.05, Ω = 1)")
    assert proc.stdout == ""


def test_divergence_in_a_sweep_names_the_value_and_warns_once(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "analysis.cli", "bifurcation", "--model", "pi", "--plays", "2",
         "--values", "0.5", "2.5", "3", "--periods", "5", "--transient", "5", "--lyapunov-t", "0",
         "--quiet", "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=Path(tmp_path),
    )  # fmt: skip
    assert proc.returncode == 2
    lines = proc.stderr.splitlines()
    # one warning line for the two unstable values (checked up front, then swept), one error
    assert len(lines) == 2, proc.stderr
    assert lines[0].startswith("hyst bifurcation: warning: ") and "C = 2.5" in lines[0]
    assert lines[1].startswith("hyst bifurcation: error: DivergenceError")
    assert lines[1].endswith("(coupling C = 2.5, ζ = 0.05, Ω = 1)")


def test_naming_divergence_attaches_the_running_system_and_an_inner_one_wins():
    outer, inner = object(), object()
    with pytest.raises(DivergenceError) as exc:
        with naming_divergence(lambda: outer):
            raise DivergenceError("diverged")
    assert exc.value.system is outer
    with pytest.raises(DivergenceError) as exc:
        with naming_divergence(lambda: outer), naming_divergence(lambda: inner):
            raise DivergenceError("diverged")
    assert exc.value.system is inner
    # other errors pass untouched
    with pytest.raises(ValueError) as other:
        with naming_divergence(lambda: outer):
            raise ValueError("bad")
    assert not hasattr(other.value, "system")
