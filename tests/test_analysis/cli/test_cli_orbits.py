"""``hyst orbit`` / ``hyst continuation`` command lines: the JSON interface and one-line errors."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from analysis.cli import main


@pytest.fixture(autouse=True)
def _in_tmp(tmp_path, monkeypatch):
    """Commands write to --out (default hyst-out in the working directory): keep it in tmp."""
    monkeypatch.chdir(tmp_path)


def _json(capsys, *argv):
    assert main(list(argv)) == 0
    return json.loads(capsys.readouterr().out)


def test_orbit_json_linear_oscillator(capsys):
    # C = 0: period 1 with the multipliers exp((−ζ ± i√(1−ζ²))·2π) of the free oscillator
    d = _json(capsys, "orbit", "--model", "relay", "--coupling", "0", "--json")
    assert d["period"] == 1 and d["stable"] is True
    assert d["tangent_space"] == ["q", "v"]
    mu = np.array([complex(re, im) for re, im in d["multipliers"]])
    zeta = 0.05
    expected = np.exp((-zeta + 1j * np.array([1, -1]) * math.sqrt(1 - zeta**2)) * 2 * math.pi)
    assert np.max(np.abs(np.sort_complex(mu) - np.sort_complex(expected))) < 1e-10
    assert d["residual"] <= 1e-10 * 10


def test_orbit_json_play_has_minus_inf_string(capsys):
    d = _json(capsys, "orbit", "--model", "erf-play", "--coupling", "3.85", "--w0", "-2", "--json")
    assert d["period"] == 5
    assert d["exponents"][-1] == "-inf"
    assert d["tangent_space"] == ["q", "v", "w"]
    assert {"period", "multipliers", "exponents", "tangent_space", "residual", "stable"} <= set(d)


def test_continuation_json_finds_the_n2_onset(capsys):
    d = _json(
        capsys,
        "continuation", "--model", "dimers", "--fields", "1", "-1",
        "--start", "9.5", "--stop", "8.98", "--max-period", "4", "--transient", "20", "--json",
    )  # fmt: skip
    assert d["branch"][0]["period"] == 1
    assert all({"parameter", "period", "max_abs_multiplier"} <= set(p) for p in d["branch"])
    kinds = [e["kind"] for e in d["events"]]
    assert kinds and kinds[0] == "grazing"
    assert abs(d["events"][0]["parameter"] - 9.0) < 1e-6


@pytest.mark.parametrize(
    ("argv", "option"),
    [
        (["orbit", "--coupling", "1", "--max-period", "0"], "--max-period"),
        (["orbit", "--coupling", "1", "--tolerance", "-1"], "--tolerance"),
        (["orbit", "--coupling", "1", "--transient", "1.5"], "--transient"),
        (["continuation", "--start", "1", "--stop", "1"], "--start"),
        (["continuation", "--start", "1", "--stop", "2", "--coupling", "1"], "--coupling"),
        (["continuation", "--start", "1", "--stop", "2", "--method", "x"], "--method"),
        (["continuation", "--start", "1", "--stop", "nan"], "--stop"),
    ],
)
def test_bad_options_are_one_line_naming_the_option(argv, option, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert option in err.splitlines()[-1]


def test_no_orbit_is_one_line(capsys):
    argv = ["orbit", "--model", "erf-play", "--coupling", "2.9", "--max-period", "4"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "OrbitNotFoundError" in err[0]


def test_orbit_neutral_when_every_state_is_periodic(capsys):
    # ζ = 0, C = 0, Ω = 0.7: P^7 is the identity, multipliers 1 within round-off: neutral
    argv = ["orbit", "--model", "erf-play", "--coupling", "0", "--damping-ratio", "0"]
    argv += ["--frequency", "0.7", "--max-period", "10"]
    d = _json(capsys, *argv, "--json")
    assert d["period"] == 7 and d["stability"] == "neutral" and d["stable"] is False
    assert main(argv) == 0
    assert "period 7, neutral," in capsys.readouterr().out
