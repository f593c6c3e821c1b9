"""A folder searched for FORC files by content (:func:`find_forc_files`), and a drift correction
asked of a file without calibration points (a one-line warning, the curves as read)."""

from __future__ import annotations

import gzip
import shutil
import warnings

import numpy as np
import pytest
from support_paths import DATA, ROOT

from analysis.identification.forc_io import (
    find_forc_files,
    read_forc_file,
    write_csv,
    write_micromag,
)

PUBLIC = DATA / "forc_public"


def test_find_forc_files_by_content_recursively(tmp_path):
    shutil.copy(DATA / "forc_erf_play_mayergoyz.csv", tmp_path / "curves.dat")  # no telling name
    nested = tmp_path / "lab" / "2023"
    nested.mkdir(parents=True)
    shutil.copy(PUBLIC / "B-9-3-85-87-FORC-1.5T_excerpt.csv", nested / "ls.csv")
    shutil.copy(PUBLIC / "ps97-085-3-d472_9.irforc", nested / "ir.txt")
    shutil.copy(PUBLIC / "MSM33-60-1-d416_2.remforc", tmp_path / "lab" / "rem.frc")
    shutil.copy(ROOT / "README.md", tmp_path / "README.md")
    (tmp_path / "empty.txt").write_bytes(b"")
    (nested / "loop.frc").write_text(
        "MicroMag 2900/3900 Data File (Series 0016.002)\nHysteresis loop\n\n+1.0E+00,+2.0E-06\n"
    )
    (nested / "ls.csv.gz").write_bytes(gzip.compress((nested / "ls.csv").read_bytes()))
    hidden = tmp_path / ".cache"
    hidden.mkdir()
    shutil.copy(DATA / "forc_erf_play_mayergoyz.csv", hidden / "curves.csv")
    shutil.copy(DATA / "forc_erf_play_mayergoyz.csv", tmp_path / ".curves.csv")

    recognised, skipped = find_forc_files(tmp_path)
    assert recognised == [
        tmp_path / "curves.dat",
        nested / "ir.txt",
        nested / "ls.csv",
        tmp_path / "lab" / "rem.frc",
    ]
    assert skipped == [
        (tmp_path / "README.md", "not a FORC file this toolkit recognises"),
        (tmp_path / "empty.txt", "an empty file (no text), not a FORC file"),
        (
            nested / "loop.frc",
            "line 2: MicroMag hysteresis-loop export is not supported; export the measurement "
            "as 'First-order reversal curves'",
        ),
        (nested / "ls.csv.gz", "not a text FORC file (gzip-compressed data; decompress it first)"),
    ]
    assert all("\n" not in reason for _, reason in skipped)
    # every file it recognises, its reader reads
    for path in recognised:
        assert read_forc_file(path).curves.n_curves > 0
    with pytest.raises(ValueError, match=r"README\.md: not a folder$"):
        find_forc_files(tmp_path / "README.md")


def test_large_file_is_recognised_from_its_first_lines(tmp_path, monkeypatch):
    # the recognition reads the first 64 KiB, not the whole file (3.3 MB Lake Shore exports)
    big = tmp_path / "big.csv"
    text = (PUBLIC / "B-9-3-85-87-FORC-1.5T_excerpt.csv").read_bytes()
    big.write_bytes(text + b"\xff" * 200_000)  # not a FORC row: the reader would refuse it
    read_sizes = []
    real_open = open

    def spying_open(path, mode="r", *args, **kwargs):
        fh = real_open(path, mode, *args, **kwargs)
        if "b" in mode and str(path) == str(big):
            read = fh.read
            fh.read = lambda n=-1: read_sizes.append(n) or read(n)  # type: ignore[method-assign]
        return fh

    monkeypatch.setattr("builtins.open", spying_open)
    recognised, skipped = find_forc_files(tmp_path)
    assert recognised == [big] and skipped == []
    assert read_sizes and all(0 < n <= 65537 for n in read_sizes)


def _no_calibration_micromag(tmp_path, curves):
    return write_micromag(tmp_path / "nocal.frc", curves)


@pytest.mark.parametrize("mode", [True, "multiplicative", "additive"])
def test_drift_correction_without_calibration_points_warns(tmp_path, mode):
    csv_path = DATA / "forc_erf_play_mayergoyz.csv"
    plain = read_forc_file(csv_path)
    mm_path = _no_calibration_micromag(tmp_path, plain.curves.mirrored())
    for path in (csv_path, mm_path):
        expected = read_forc_file(path)
        with pytest.warns(UserWarning) as caught:
            data = read_forc_file(path, drift_correction=mode)
        assert len(caught) == 1
        message = str(caught[0].message)
        name = "multiplicative" if mode is True else mode
        assert message == (
            f"{path}: drift_correction={name!r} not applied: the file has no calibration points"
        )
        assert caught[0].filename == __file__  # points at the caller
        for a, b in zip(data.curves.moments, expected.curves.moments, strict=True):
            np.testing.assert_array_equal(a, b)
    # no warning without a drift correction, and a file with calibration points corrects
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_forc_file(csv_path)
        corrected = read_forc_file(
            PUBLIC / "B-9-3-85-87-FORC-1.5T_excerpt.csv", drift_correction=mode
        )
    assert any("drift correction from 28 calibration points" in n for n in corrected.notes)


def test_drift_correction_is_refused_where_calibration_points_are_not_used(tmp_path):
    with pytest.raises(ValueError, match=r"^drift_correction='additive': not implemented for "):
        read_forc_file(PUBLIC / "ps97-085-3-d472_9.irforc", drift_correction="additive")
    with pytest.raises(ValueError, match="drift_correction must be"):
        read_forc_file(
            write_csv(
                tmp_path / "c.csv", read_forc_file(DATA / "forc_erf_play_mayergoyz.csv").curves
            ),
            drift_correction="cubic",
        )


def _stub_one_file(args, path, out):
    """A batch worker that identifies nothing: the report of a file read, for the summary."""
    data = read_forc_file(path)
    return {"input": str(path), "status": "ok", "n_curves": data.curves.n_curves}


def test_batch_helper_searches_directories_and_lists_the_skipped(tmp_path, capsys):
    import csv
    import json

    from analysis.cli import build_parser
    from analysis.cli._identify_batch import forc_input_files, run_batch
    from analysis.cli._parsing import CliError

    folder = tmp_path / "in"
    (folder / "sub").mkdir(parents=True)
    shutil.copy(PUBLIC / "ps97-085-3-d472_9.irforc", folder / "sub" / "ir.txt")
    shutil.copy(ROOT / "README.md", folder / "README.md")
    single = DATA / "forc_erf_play_mayergoyz.csv"
    files, skipped = forc_input_files([single, folder])
    assert files == [single, folder / "sub" / "ir.txt"]
    assert skipped == [(folder / "README.md", "not a FORC file this toolkit recognises")]
    out = tmp_path / "out"
    args = build_parser().parse_args(["identify", "--input", str(folder), "--out", str(out)])
    assert run_batch(args, files, _stub_one_file, skipped) == 0
    rows = list(csv.DictReader(open(out / "summary.csv", encoding="utf-8")))
    assert [(r["status"], r["n_curves"]) for r in rows] == [
        ("ok", "25"),
        ("ok", "40"),
        ("skipped", ""),
    ]
    assert rows[2]["warnings"] == "not a FORC file this toolkit recognises"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["n_files"] == 2 and summary["n_failed"] == 0 and summary["n_skipped"] == 1
    assert "1 files skipped (no FORC file)" in capsys.readouterr().out
    (folder / "sub" / "ir.txt").unlink()
    with pytest.raises(CliError, match=r"no FORC file in the directory \(1 files skipped; README"):
        forc_input_files([folder])
