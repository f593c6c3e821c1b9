"""``hyst fit``: a record written as CSV is fitted (parameters with errors as JSON, the figure),
and malformed files are refused in one line naming the file, the line and the column."""

from __future__ import annotations

import json

import numpy as np
import pytest

from analysis.cli import main
from analysis.identification.record_io import read_record, write_record
from hysteresis import JilesAtherton

JA = {"ms": 1.2e6, "a": 800.0, "k": 600.0, "c": 0.15, "alpha": 5e-4}


@pytest.fixture(scope="module")
def bh_csv(tmp_path_factory):
    """A noisy B–H record (columns H, M) of a known Jiles–Atherton material."""
    n = 600
    t = np.arange(n)
    h = 5000.0 * np.sin(2 * np.pi * t / (n / 4)) * (0.6 + 0.4 * np.cos(2 * np.pi * t / (0.9 * n)))
    op = JilesAtherton(**JA)
    m, _ = op.apply(h, op.state(0.0, h[0]))
    noise = 0.01 * float(np.max(np.abs(m)))
    m = m + np.random.default_rng(0).normal(0.0, noise, n)
    path = tmp_path_factory.mktemp("rec") / "bh.csv"
    write_record(path, h, m, columns=("H", "M"))
    return path, noise


def test_fit_jiles_atherton_json_and_figure(bh_csv, tmp_path, capsys):
    path, noise = bh_csv
    out = tmp_path / "out"
    argv = ["fit", "--model", "jiles-atherton", "--input", str(path), "--columns", "H", "M"]
    assert main([*argv, "--out", str(out), "--json", "--quiet"]) == 0
    rec = json.loads(capsys.readouterr().out)
    assert rec["columns"] == ["H", "M"] and rec["samples"] == 600
    assert rec["validation_rms"] <= 2.0 * noise
    for name, value in JA.items():
        assert abs(rec["parameters"][name] - value) <= 4.0 * rec["standard_errors"][name], name
    assert (out / "fit.png").is_file() and (out / "fit.pdf").is_file()
    assert json.loads((out / "fit.json").read_text())["parameters"] == rec["parameters"]


def test_fit_pi_on_the_same_record_text_output(bh_csv, tmp_path, capsys):
    path, noise = bh_csv
    argv = ["fit", "--model", "pi", "--input", str(path), "--columns", "H", "M", "--plays", "8"]
    assert main([*argv, "--out", str(tmp_path)]) == 0
    text = capsys.readouterr().out
    assert "a_0 = " in text and "+-" in text and "validation" in text
    rec = json.loads((tmp_path / "fit.json").read_text())
    assert len(rec["widths"]) == 9  # 8 widths and the linear term
    assert rec["validation_rms"] > 2.0 * noise  # a non-saturating model on a saturating loop


def _error(argv, capsys) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err  # one line
    return err


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("x,output\n" + "1,2\n" * 30, "no column 'input' (its columns: x, output)"),
        ("input,output\n" + "1,2\n" * 5 + "1,abc\n" + "1,2\n" * 30, "line 7, column 'output'"),
        ("input,output\n" + "1,2\n" * 5, "5 samples; a fit needs at least 20"),
        ("input,output\n" + "1,2\n" * 5 + "nan,2\n" + "1,2\n" * 30, "'nan' is not finite"),
        ("input,output\n" + "1,2\n" * 5 + "3\n" + "1,2\n" * 30, "line 7: 1 fields"),
        ("", "no data"),
    ],
    ids=["missing-column", "non-numeric", "too-few", "nan", "short-row", "empty"],
)
def test_malformed_files_are_refused_in_one_line(content, message, tmp_path, capsys):
    path = tmp_path / "rec.csv"
    path.write_text(content)
    argv = ["fit", "--model", "bouc-wen", "--input", str(path), "--out", str(tmp_path)]
    err = _error(argv, capsys)
    assert err.startswith("hyst fit: error: argument --input: ") and message in err, err


def test_option_and_file_refusals(tmp_path, capsys):
    err = _error(["fit", "--model", "bouc-wen", "--input", str(tmp_path / "none.csv")], capsys)
    assert "cannot be read" in err
    path = write_record(tmp_path / "r.csv", np.arange(30.0), np.arange(30.0))
    err = _error(["fit", "--model", "bouc-wen", "--input", str(path), "--plays", "4"], capsys)
    assert "argument --plays: only for --model pi" in err
    err = _error(["fit", "--model", "pi", "--input", str(path), "--train-fraction", "0"], capsys)
    assert "--train-fraction" in err


def test_read_record_without_header_by_position(tmp_path):
    path = tmp_path / "r.txt"
    path.write_text("# a comment\n" + "".join(f"{k} {k * 0.5} {k * 2}\n" for k in range(25)))
    rec = read_record(path, ("1", "3"))
    np.testing.assert_array_equal(rec.u, np.arange(25.0))
    np.testing.assert_array_equal(rec.y, 2.0 * np.arange(25.0))
    with pytest.raises(ValueError, match="positions 1 to 3; got '4'"):
        read_record(path, ("1", "4"))
