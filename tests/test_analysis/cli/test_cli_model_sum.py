"""``--model`` as a weighted sum of registry names (issue 28, the command line): the command runs
the sum the library builds, its JSON names the sum canonically, a mixed sum's engine warning is
one line, and every malformed text is one error line with exit status 2."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from analysis.cli import main
from analysis.experiments.models import model_record


@pytest.fixture(autouse=True)
def _in_tmp(tmp_path, monkeypatch):
    """Commands write to --out (default hyst-out in the working directory): keep it in tmp."""
    monkeypatch.chdir(tmp_path)


def test_lyapunov_of_a_mixed_sum_runs_compiled_and_names_the_sum():
    proc = subprocess.run(
        [sys.executable, "-m", "analysis.cli", "lyapunov", "--model",
         "0.70*erf-play+0.3 * preisach", "--spins", "50", "--coupling", "3", "--t-end", "50",
         "--quiet", "--json"],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=Path.cwd(),
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    # a play plus relays runs on the compiled continuous engine (relays as switching events)
    assert proc.stderr == ""
    rec = json.loads(proc.stdout)
    expected = model_record("0.7*erf-play + 0.3*preisach", spins=50)
    assert {k: rec[k] for k in expected} == expected
    assert rec["model"] == "0.7*erf-play + 0.3*preisach"
    assert rec["engine"] == "compiled continuous engine"
    # tangent space: (q, v) and the play's wagon (the sum's part 0); relays switch
    assert rec["tangent_space"] == ["q", "v", "0:w"]
    assert rec["switches"] > 0 and "w0" not in rec


def test_a_sum_on_the_python_path_warns_in_one_line():
    proc = subprocess.run(
        [sys.executable, "-m", "analysis.cli", "lyapunov", "--model",
         "0.7*erf-play + 0.3*preisach-gauss", "--coupling", "2", "--t-end", "10", "--quiet",
         "--json"],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=Path.cwd(),
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    lines = proc.stderr.splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith("hyst lyapunov: warning: ") and "generic continuous" in lines[0]
    assert ".py" not in lines[0]  # no source location, no traceback
    assert "Python path" in json.loads(proc.stdout)["engine"]


def test_a_relay_type_sum_runs_on_the_relay_engine_without_warning(capsys):
    argv = ["poincare", "--model", "0.5*preisach + 0.5*dimers", "--spins", "40", "--coupling",
            "3", "--periods", "10", "--transient", "2", "--json"]  # fmt: skip
    assert main(argv) == 0
    captured = capsys.readouterr()
    assert captured.err == ""
    rec = json.loads(captured.out)
    assert rec["model"] == "0.5*preisach + 0.5*dimers"
    assert rec["weights"] == {"preisach": 0.5, "dimers": 0.5} and rec["points"] == 10


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--model", "0.7*erf-play +"], "argument --model: '0.7*erf-play +': '+' at column 14"),
        (["--model", "0.5*foo + play"], "got 'foo' in '0.5*foo + play'"),
        (["--model", "foo"], "or a weighted sum of them such as"),
        (["--model", "(play + relay)"], "parentheses"),
        (["--model", "play + play"], "'play' appears twice"),
        (["--model", "1e999*play"], "not finite"),
        (["--model", "0.5"], "has no model name"),
        # options checked against every part of the sum
        (["--model", "play + relay", "--fields", "1", "-1"], "--fields: only for --model dimers"),
        (["--model", "dimers + play", "--spins", "3"], "--spins: dimers need an even N"),
        (["--model", "0.5*erf-play + 0.5*play", "--w0", "-1"], "--w0: only for play-type"),
    ],
)
def test_bad_sums_are_one_error_line(argv, message, capsys):
    assert main(["trajectory", *argv, "--coupling", "1", "--t-end", "1"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("hyst trajectory: error: argument --")
    assert message in err[0]


def test_commands_with_restricted_models_check_every_part(capsys):
    # ensemble draws one disorder model per realization: no sums
    assert main(["ensemble", "--model", "0.5*dimers + 0.5*preisach", "--coupling", "1"]) == 2
    err = capsys.readouterr().err
    assert "takes no sum of models" in err and len(err.splitlines()) == 1
    # identify takes sums of its own models only
    assert main(["identify", "--model", "0.5*dimers + 0.5*preisach"]) == 2
    err = capsys.readouterr().err
    assert "for this command; got 'preisach' in '0.5*dimers + 0.5*preisach'" in err


def test_help_explains_sums(capsys):
    assert main(["lyapunov", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "weighted sum of these names, e.g. '0.7*erf-play + 0.3*preisach'" in text
    assert "apply to every part" in text
