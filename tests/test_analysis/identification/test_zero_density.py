"""A FORC measurement of constant moment has a FORC density exactly 0 (every Everett value and
cell mass is 0): there is no peak, and the identification says so (NaN and one warning line)
instead of reporting the largest round-off value (±1e-16) of the smoothed density as a peak
with a bootstrap interval."""

from __future__ import annotations

import csv
import json
import math
import warnings

import numpy as np
import pytest
from support_paths import DATA

from analysis.cli import main
from analysis.identification import identify_from_curves
from analysis.identification.forc_io import read_forc_file
from analysis.identification.peak_bootstrap import peak_bootstrap
from analysis.identification.uncertainty import summarize_uncertainty

SOURCE = DATA / "forc_erf_play_mayergoyz.csv"


def _constant_file(tmp_path, moment: str = "0.5"):
    """The protocol of the erf-play test file with every moment replaced by ``moment``."""
    lines = SOURCE.read_text().splitlines()
    rows = [",".join([*line.split(",")[:2], moment]) for line in lines[2:]]
    path = tmp_path / "constant.csv"
    path.write_text("\n".join([*lines[:2], *rows]) + "\n")
    return path


@pytest.mark.parametrize("kwargs", [dict(smoothing=(3.0, 3.0)), dict(smoothing="auto")])
def test_constant_moment_has_no_peak(tmp_path, kwargs):
    curves = read_forc_file(_constant_file(tmp_path)).curves
    ident = identify_from_curves(curves, output_range=(-math.inf, math.inf), **kwargs)
    assert not np.any(ident.cell_mass)  # the density is exactly 0
    assert ident.density_is_zero
    with pytest.warns(RuntimeWarning, match="no peak") as caught:
        peak = ident.density_peak()
    assert all(math.isnan(x) for x in peak)
    assert len(caught) == 1 and "\n" not in str(caught[0].message)


def test_constant_moment_has_no_bootstrap_interval(tmp_path):
    curves = read_forc_file(_constant_file(tmp_path, "1234.5678")).curves
    ident = identify_from_curves(
        curves, smoothing=(3.0, 3.0), output_range=(-math.inf, math.inf), uncertainty=True
    )
    with pytest.raises(ValueError, match="zero everywhere") as exc:
        peak_bootstrap(ident)
    assert "\n" not in str(exc.value)
    with pytest.warns(RuntimeWarning, match="no peak"):
        u = summarize_uncertainty(ident, n_boot=20)
    assert all(math.isnan(x) for x in (u.peak_bc, u.peak_bu, u.peak_rho, u.peak_rho_se))
    assert all(math.isnan(x) for x in (*u.peak_bc_interval, *u.peak_bu_interval))
    assert u.irreversible_mass == 0.0


def test_a_measured_density_keeps_its_peak():
    curves = read_forc_file(SOURCE).curves
    ident = identify_from_curves(curves, smoothing=(3.0, 3.0), output_range=(-1.0, 1.0))
    assert not ident.density_is_zero
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        bc, bu, rho = ident.density_peak()
    assert rho > 0 and math.isfinite(bc) and math.isfinite(bu)


@pytest.mark.parametrize("extra", [["--smoothing", "auto"], ["--uncertainty"]])
def test_cli_reports_no_peak(tmp_path, capsys, extra):
    path = _constant_file(tmp_path)
    argv = ["identify", "--input", str(path), *extra, "--out", str(tmp_path / "o"), "--json"]
    assert main(argv) == 0
    captured = capsys.readouterr()
    rep = json.loads(captured.out)
    # a missing value is null (not the strict-JSON NaN string "nan"), on stdout and on disk
    written = json.loads((tmp_path / "o" / "identify.json").read_text())
    for r in (rep, written):
        assert r["peak_bc_mT"] is None and r["peak_bu_mT"] is None and r["peak_rho"] is None
        if "--uncertainty" in extra:
            assert r["peak_bc_interval_mT"] == [None, None]
            assert r["peak_bu_interval_mT"] == [None, None]
            assert r["peak_rho_se"] is None
    assert r["irreversible_mass"] == 0.0  # measured values stay numbers
    notes = [line for line in captured.err.splitlines() if "no peak" in line]
    assert len(notes) == 1


def test_cli_batch_summary_leaves_a_missing_peak_blank(tmp_path, capsys):
    folder = tmp_path / "in"
    folder.mkdir()
    path = _constant_file(folder)
    assert main(["identify", "--input", str(path), "--out", str(tmp_path / "one")]) == 0
    assert "; no FORC peak (the density is zero);" in capsys.readouterr().out
    out = tmp_path / "out"
    assert main(["identify", "--input", str(folder), "--uncertainty", "--out", str(out)]) == 0
    (row,) = list(csv.DictReader(open(out / "summary.csv", encoding="utf-8")))
    assert row["status"] == "ok"
    for key in ("peak_bc_mT", "peak_bu_mT", "peak_bc_lo_mT", "peak_bu_hi_mT", "peak_rho"):
        assert row[key] == "", (key, row[key])
