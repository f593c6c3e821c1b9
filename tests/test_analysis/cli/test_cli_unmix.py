"""``hyst unmix``: a synthetic series of FORC files (forc_series.py) with a broken file and a
file that is no FORC file; the summary files, the figures, the one-line errors, and the
shipped instrument files end to end."""

from __future__ import annotations

import csv
import json
import re

import numpy as np
import pytest
from forc_series import core_proportions, mixed_curves
from support_paths import DATA

from analysis.cli import main
from analysis.identification.forc_io import write_csv
from analysis.identification.unmixing import unmix_forc

NOISE = 3e-3


@pytest.fixture(scope="module")
def series_dir(tmp_path_factory):
    """Six samples (the three pure populations first) as CSV files, a broken FORC file and a
    text file that is none."""
    folder = tmp_path_factory.mktemp("series")
    truth = core_proportions(6, seed=2)
    rng = np.random.default_rng(9)
    for k, p in enumerate(truth):
        write_csv(folder / f"core_{k:02d}.csv", mixed_curves(p, NOISE, rng))
    (folder / "core_99.csv").write_text("reversal_field,field,moment\n0.5,0.5,1\n0.5,0.4\n")
    (folder / "notes.txt").write_text("depths of the core, in cm\n")
    return folder, truth


def _rows(path):
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def test_unmix_a_folder(series_dir, tmp_path, capsys):
    folder, truth = series_dir
    out = tmp_path / "out"
    assert main(["unmix", "--input", str(folder), "--out", str(out), "--json", "--quiet"]) == 0
    captured = capsys.readouterr()
    report = json.loads(captured.out)
    # the broken file is said on stderr even with --quiet, and the batch went on
    assert "core_99.csv" in captured.err and "line 3" in captured.err
    assert report["n_components"] == 3 and report["chosen_by"] == "noise"
    rows = _rows(out / "summary.csv")
    status = {r["file"].rsplit("/", 1)[-1]: r["status"] for r in rows}
    assert status == {
        **{f"core_{k:02d}.csv": "ok" for k in range(6)},
        "core_99.csv": "left out",
        "notes.txt": "skipped",
    }
    ok = [r for r in rows if r["status"] == "ok"]
    props = np.array([[float(r[f"p{k}"]) for k in (1, 2, 3)] for r in ok])
    np.testing.assert_allclose(props.sum(axis=1), 1.0, atol=1e-12)
    # the same numbers as the library's, on the same files
    lib = unmix_forc(sorted(folder.glob("core_0*.csv")))
    np.testing.assert_allclose(props, lib.proportions, atol=1e-12)
    # the pure samples are the end-members (EM1..EM3 by median Bc: soft population first)
    assert [r["end_member"] for r in ok[:3]] == ["EM3", "EM2", "EM1"]
    for k in (1, 2, 3):  # intervals hold the estimates
        lo, hi = (np.array([float(r[f"p{k}_{e}"]) for r in ok]) for e in ("lo", "hi"))
        assert np.all(lo <= props[:, k - 1] + 1e-12) and np.all(props[:, k - 1] <= hi + 1e-12)
    for name in ("scores", "end_members", "proportions"):
        for ext in ("png", "pdf"):
            assert (out / f"unmix_{name}.{ext}").stat().st_size > 1000
    with np.load(out / "unmix.npz") as npz:
        assert npz["end_members"].shape[0] == 3 and npz["diagrams"].shape[0] == 6
    summary = json.loads((out / "summary.json").read_text())
    assert summary["skipped"][0]["file"].endswith("notes.txt")
    assert summary["component_test"][2]["accepted"] is True


def test_end_members_by_name_or_position(series_dir, tmp_path, capsys):
    folder, _ = series_dir
    files = [str(p) for p in sorted(folder.glob("core_0*.csv"))]
    base = ["unmix", "--input", *files, "--json", "--quiet"]
    assert main([*base, "--out", str(tmp_path / "a"), "--end-members", "1", "2", "3"]) == 0
    by_position = json.loads(capsys.readouterr().out)
    names = ["core_02.csv", "core_01.csv", "core_00.csv"]
    assert main([*base, "--out", str(tmp_path / "b"), "--end-members", *names]) == 0
    by_name = json.loads(capsys.readouterr().out)
    assert by_name["chosen_by"] == "end_members"
    p1, p2 = np.array(by_position["proportions"]), np.array(by_name["proportions"])
    np.testing.assert_allclose(p1, p2[:, ::-1], atol=1e-12)  # columns in the order given


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--end-members", "core_77.csv"], "argument --end-members: 'core_77.csv' is neither"),
        (["--components", "9"], r"argument --components: n_components must lie in \[1, 6\]"),
        (["--normalize", "mass"], "argument --input: inputs: fewer than two usable .* no mass"),
        (["--smoothing", "0"], "argument --smoothing: must be > 0"),
    ],
)
def test_one_line_errors(series_dir, tmp_path, capsys, extra, message):
    folder, _ = series_dir
    files = [str(p) for p in sorted(folder.glob("core_0*.csv"))]
    code = main(["unmix", "--input", *files, "--out", str(tmp_path / "o"), "--quiet", *extra])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert err[-1].startswith("hyst unmix: error: ")
    assert re.search(message, err[-1]), err[-1]


def test_shipped_instrument_files(tmp_path, capsys):
    out = tmp_path / "real"
    folder = DATA / "forc_public"
    assert main(["unmix", "--input", str(folder), "--out", str(out), "--json", "--quiet"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["lattice"]["step"] == pytest.approx(6.657385, rel=1e-6)
    assert [s["file"].rsplit("/", 1)[-1] for s in report["skipped"]] == ["README.md"]
    rows = _rows(out / "summary.csv")
    assert sum(r["status"] == "ok" for r in rows) == len(report["samples"]) >= 2
