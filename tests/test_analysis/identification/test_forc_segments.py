"""Irregular FORC protocols in MicroMag "Direct moment vs. field; Multiple segments" exports:
the curves reconstructed from the segment script give the density of the regular FORC file
of the same known Preisach model (tests/data/make_forc_data.py writes both)."""

from __future__ import annotations

import numpy as np
import pytest
from support_paths import DATA

from analysis.cli import main
from analysis.identification import identify_from_curves
from analysis.identification.forc_io import detect_format, read_forc_file

SEGMENTS = DATA / "forc_micromag_segments.frc"
REGULAR = DATA / "forc_micromag_segments_regular.frc"


def test_irregular_export_gives_the_density_of_the_regular_file():
    assert detect_format(SEGMENTS) == "segments" and detect_format(REGULAR) == "micromag"
    seg, reg = read_forc_file(SEGMENTS), read_forc_file(REGULAR)
    assert seg.curves.n_curves == reg.curves.n_curves == 30
    assert seg.units_of_measure == "Hybrid SI" and seg.field_unit == "mT"
    for kw in ({"smoothing": 3}, {"smoothing": "variforc", "uncertainty": True}):
        a = identify_from_curves(seg.curves, extend=False, **kw)
        b = identify_from_curves(reg.curves, extend=False, **kw)
        np.testing.assert_allclose(a.alpha, b.alpha, rtol=0, atol=1e-12)
        peak = np.nanmax(np.abs(b.density_alpha_beta))
        # the two files hold the same numbers to 16 significant digits (the segments file in
        # T with %.15E, converted to mT): rounding ~1e-15 of the values, amplified by the
        # regression's second difference over the smallest cell (~0.1 of the field range)
        same = np.isfinite(b.density_alpha_beta)
        assert np.array_equal(same, np.isfinite(a.density_alpha_beta))
        assert np.max(np.abs(a.density_alpha_beta - b.density_alpha_beta)[same]) <= 1e-10 * peak
        np.testing.assert_allclose(a.cell_mass, b.cell_mass, rtol=0, atol=1e-12)


def test_remanence_scripts_are_refused(tmp_path):
    text = SEGMENTS.read_text(encoding="utf-8").splitlines()
    # the 6th data row (a point of the first rising segment) measured back at zero field
    data_rows = [k for k, line in enumerate(text) if line.count(",") == 1 and line[:1] in "+-"]
    k = data_rows[5]
    text[k] = "+0.000000000000000E+00," + text[k].split(",")[1]
    path = tmp_path / "rem.frc"
    path.write_text("\r\n".join(text), encoding="utf-8")
    with pytest.raises(ValueError, match=rf"line {k + 1}: .*remanence FORC"):
        read_forc_file(path)


def test_cli_identifies_the_irregular_export(tmp_path):
    out = tmp_path / "out"
    assert (
        main(["identify", "--input", str(SEGMENTS), "--uncertainty", "--out", str(out), "--quiet"])
        == 0
    )
    assert (out / "identify_forc_micromag_segments.png").exists()
