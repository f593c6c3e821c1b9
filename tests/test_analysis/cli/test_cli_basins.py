"""``hyst basins`` (issue 19 item 4): the JSON record, the files, resume, one-line refusals."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from analysis.cli import main

#: a 3 x 3 map of the bistable erf play (C = 1.74: period 3 and chaos) in a few seconds
SMALL = [
    "basins", "--model", "erf-play", "--coupling", "1.74", "--grid", "3",
    "--q0-range", "-3", "1", "--v0-range", "-1.9", "2.1", "--transient", "0",
    "--periods", "100", "--max-periods", "400", "--lyapunov-periods", "200", "--quiet",
    "--workers", "1",
]  # fmt: skip


@pytest.fixture(autouse=True)
def _in_tmp(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)


def test_json_record_files_and_resume(capsys, tmp_path):
    assert main([*SMALL, "--json", "--out", "run"]) == 0
    record = json.loads(capsys.readouterr().out)
    attractors = record["attractors"]
    assert record["starts"] == record["valid_starts"] == 9
    assert math.isclose(sum(a["fraction"] for a in attractors), 1.0)
    for a in attractors:
        lo, hi = a["interval"]
        assert 0.0 <= lo <= a["fraction"] <= hi <= 1.0
        assert a["interval_method"] == "Wilson score, 95 %"
        if a["kind"] == "periodic":
            assert a["period"] >= 1 and all(len(m) == 2 for m in a["multipliers"])
        elif a["kind"] == "chaotic":
            assert a["max_exponent"] > 0 and "kaplan_yorke" in a
    with np.load(tmp_path / "run" / "basins.npz") as z:
        labels = z["labels"]
        assert z["label_grid"].shape == (3, 3)
    assert (tmp_path / "run" / "basins.png").stat().st_size > 0
    assert json.loads((tmp_path / "run" / "basins.json").read_text())["attractors"] == attractors
    # a rerun reads every chunk from the store and gives the same labels
    assert main([*SMALL, "--json", "--out", "run"]) == 0
    again = json.loads(capsys.readouterr().out)
    assert [a["count"] for a in again["attractors"]] == [a["count"] for a in attractors]
    with np.load(tmp_path / "run" / "basins.npz") as z:
        np.testing.assert_array_equal(z["labels"], labels)


@pytest.mark.parametrize(
    ("extra", "option"),
    [
        (["--w0-range", "-1", "1"], "--w0-range"),  # with --v0-range
        (["--max-period", "60"], "--max-period"),
        (["--max-periods", "50"], "--max-periods"),
        (["--q0-range", "1", "-1"], "--q0-range"),
        (["--grid", "1"], "--grid"),
        (["--match-tolerance", "1e-9"], "--match-tolerance"),
        (["--coupling", "nan"], "--coupling"),
    ],
)
def test_bad_options_are_refused_in_one_line(extra, option, capsys):
    assert main([*SMALL, *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and option in err, err


def test_w0_range_needs_play_type_memory(capsys):
    argv = ["basins", "--model", "relay", "--coupling", "1", "--grid", "2", "--w0-range", "-1", "1"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--w0-range" in err and "play-type" in err


def test_recurrences_method_records_its_settings_and_resumes(capsys, tmp_path):
    """``--method recurrences``: the record names the method, the mapper's knobs and why the
    starts stopped; the npz carries the periods each start ran; a rerun reads the store."""
    argv = [*SMALL, "--max-periods", "2000", "--method", "recurrences", "--json", "--out", "rec"]
    assert main(argv) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["method"] == "recurrences"
    assert record["recurrence"]["cell_size"] == 0.05
    assert sum(record["stops"].values()) == record["starts"] == 9
    assert {a["kind"] for a in record["attractors"]} <= {"periodic", "chaotic", "undecided"}
    with np.load(tmp_path / "rec" / "basins.npz") as z:
        steps, labels = z["steps"], z["labels"]
    assert steps.shape == (9,) and np.all((steps >= 1) & (steps <= 2000))
    assert main(argv) == 0
    assert json.loads(capsys.readouterr().out)["attractors"] == record["attractors"]
    with np.load(tmp_path / "rec" / "basins.npz") as z:
        np.testing.assert_array_equal(z["labels"], labels)
