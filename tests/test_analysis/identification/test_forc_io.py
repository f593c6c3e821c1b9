"""FORC file input/output: round trips, shipped synthetic files, malformed files."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest
from scipy.stats import norm
from support_paths import DATA

from analysis.identification import (
    identify_from_curves,
    identify_preisach,
    measure_reversal_curves,
    regular_grid,
)
from analysis.identification.forc_io import (
    read_csv,
    read_forc,
    read_micromag,
    write_csv,
    write_micromag,
)
from hysteresis.play import GeneralizedPlay


def _maker():
    spec = importlib.util.spec_from_file_location("make_forc_data", DATA / "make_forc_data.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


# ----------------------------------------------------------------------------------------------
# shipped files and round trips
# ----------------------------------------------------------------------------------------------
def test_shipped_csv_identifies_like_the_operator():
    mk = _maker()
    curves = read_csv(mk.CSV_FILE)
    assert curves.convention == "mayergoyz" and curves.n_curves == 25
    from_file = identify_from_curves(curves)
    direct = identify_preisach(mk.operator(), 0.5, mk.SATURATION)
    np.testing.assert_array_equal(from_file.alpha, direct.alpha)
    np.testing.assert_allclose(from_file.cell_mass, direct.cell_mass, rtol=0, atol=1e-15)
    assert from_file.step == pytest.approx(0.5)


def test_shipped_micromag_irregular_lattice_exact_at_the_ridge():
    mk = _maker()
    data = read_micromag(mk.MICROMAG_FILE)
    assert data.curves.convention == "pike"
    assert data.calibration_field == pytest.approx(6.0)
    assert data.calibration_moments.size == data.curves.n_curves == 31
    ident = identify_from_curves(data.curves)
    assert ident.step is None  # irregular lattice: no regridding
    nodes = mk.irregular_nodes()
    np.testing.assert_allclose(ident.alpha, nodes, atol=1e-15)
    # exact mass of every native cell: relays at alpha = s + p/2, beta = s - p/2, s ~ N(0, 1);
    # cell (a0, a1] x (b0, b1] holds P(max(a0 - 1, b0 + 1) < s <= min(a1 - 1, b1 + 1))
    a0, a1 = nodes[:-1, None], nodes[1:, None]
    b0, b1 = nodes[None, :-1], nodes[None, 1:]
    lo = np.maximum(a0 - 1, b0 + 1)
    hi = np.minimum(a1 - 1, b1 + 1)
    expected = np.where(hi > lo, norm.cdf(hi) - norm.cdf(lo), 0.0)
    np.testing.assert_allclose(ident.cell_mass, expected, atol=1e-12)
    direct = identify_from_curves(mk.curves_micromag())
    np.testing.assert_allclose(ident.cell_mass, direct.cell_mass, atol=1e-15)


@pytest.mark.parametrize("convention", ["mayergoyz", "pike"])
@pytest.mark.parametrize("header", [True, False])
def test_csv_round_trip(tmp_path, convention, header):
    op = GeneralizedPlay.erf(2.0, 1.0)
    grid = regular_grid(0.4, 6.0)
    curves = measure_reversal_curves(op, grid, convention=convention, saturation=6.4)
    path = write_csv(tmp_path / "c.csv", curves, header=header)
    back = read_csv(path)
    assert back.convention == convention
    for h0, h1, m0, m1 in zip(
        curves.fields, back.fields, curves.moments, back.moments, strict=True
    ):
        np.testing.assert_array_equal(h0, h1)
        np.testing.assert_array_equal(m0, m1)
    np.testing.assert_array_equal(
        identify_from_curves(back).cell_mass, identify_from_curves(curves).cell_mass
    )
    # without the convention comment the direction of the fields decides
    text = path.read_text().splitlines()
    (tmp_path / "n.csv").write_text("\n".join(text[1:]) + "\n")
    assert read_csv(tmp_path / "n.csv").convention == convention


def test_micromag_round_trip_and_drift_correction(tmp_path):
    op = GeneralizedPlay.erf(2.0, 1.0)
    nodes = np.sort(np.concatenate([regular_grid(0.5, 5.0), [0.13, 1.71, -2.2]]))
    curves = measure_reversal_curves(op, nodes, nodes, convention="pike", saturation=5.0)
    path = write_micromag(tmp_path / "f.txt", curves)
    back = read_forc(path, "micromag")
    np.testing.assert_array_equal(
        identify_from_curves(back).cell_mass, identify_from_curves(curves).cell_mass
    )
    # drift linear in time (file line t): every data line, calibration points included, is
    # distorted; a final calibration point closes the last curve, so the correction is exact
    cal = float(op.apply(np.array([5.0]), op.initial_state(5.0))[0][0])
    path = write_micromag(
        tmp_path / "d.txt",
        curves,
        calibration_field=5.0,
        calibration_moments=[cal] * curves.n_curves,
    )
    text = path.read_text().splitlines()
    end = text.index("MicroMag 2900/3900 Data File ends")
    text[end:end] = [f"{5.0:+.16E},{cal:+.16E}", ""]
    first_cal = None
    for mode, distort in (
        ("multiplicative", lambda m, t: m * (1.0 + 1e-3 * t)),
        ("additive", lambda m, t: m + 1e-3 * t),
    ):
        lines = list(text)
        for k, line in enumerate(lines):
            if line[:1] in "+-" and "," in line:
                h, m = (float(x) for x in line.split(","))
                first_cal = k + 1 if first_cal is None else first_cal
                lines[k] = f"{h:+.16E},{distort(m, k + 1):+.16E}"
        (tmp_path / f"{mode}.txt").write_text("\n".join(lines) + "\n")
        data = read_micromag(tmp_path / f"{mode}.txt", drift_correction=mode)
        assert data.calibration_moments.size == curves.n_curves + 1
        for m0, m1 in zip(curves.moments, data.curves.moments, strict=True):
            np.testing.assert_allclose(m1, distort(m0, first_cal), rtol=1e-12, atol=1e-12)
        raw = read_micromag(tmp_path / f"{mode}.txt").curves
        assert np.max(np.abs(raw.moments[-1] - curves.moments[-1])) > 1e-2


def test_micromag_writer_needs_pike_curves(tmp_path):
    op = GeneralizedPlay.erf(2.0, 1.0)
    curves = measure_reversal_curves(op, regular_grid(1.0, 3.0))
    with pytest.raises(ValueError, match="Pike"):
        write_micromag(tmp_path / "x.txt", curves)


# ----------------------------------------------------------------------------------------------
# malformed files -> ValueError naming the line
# ----------------------------------------------------------------------------------------------
GOOD_CSV = """# convention = mayergoyz
reversal_field,field,moment
-1.0,-1.0,-1.0
0.0,0.0,0.0
0.0,-1.0,-0.5
1.0,1.0,1.0
1.0,0.0,0.5
1.0,-1.0,-1.0
"""


def _csv(tmp_path, text):
    p = tmp_path / "bad.csv"
    p.write_text(text)
    return p


def test_good_csv_parses(tmp_path):
    curves = read_csv(_csv(tmp_path, GOOD_CSV))
    assert curves.n_curves == 3 and curves.n_points == 6


@pytest.mark.parametrize(
    "line, replacement, pattern",
    [
        (5, "0.0,-1.0,abc", r"line 5: moment 'abc' is not a number"),
        (6, "1.0,1.0,nan", r"line 6: moment must be finite"),
        (7, "1.0,0.0", r"line 7: expected 3 columns"),
        (7, "1.0,0.0,0.5,9", r"line 7: expected 3 columns"),
        (4, "0.0,0.1,0.0", r"line 4: a curve must start at its reversal field"),
        (8, "1.0,0.5,-1.0", r"line 8: fields must strictly decrease"),
        (8, "-1.0,-1.0,-1.0", r"line 8: reversal field -1.0 appears in two separate curves"),
        (1, "# convention = sideways", r"line 1: convention must be one of"),
    ],
)
def test_malformed_csv(tmp_path, line, replacement, pattern):
    lines = GOOD_CSV.splitlines()
    lines[line - 1] = replacement
    with pytest.raises(ValueError, match=pattern):
        read_csv(_csv(tmp_path, "\n".join(lines) + "\n"))


def test_empty_csv(tmp_path):
    with pytest.raises(ValueError, match="no data rows"):
        read_csv(_csv(tmp_path, "# nothing\nreversal_field,field,moment\n"))


GOOD_MM = """MicroMag 2900/3900 Data File (Series 0016)
First-order reversal curves

NCrv = 3
NData = 6
HCal = 2.0

Field, Moment

+2.0,+1.0

-1.0,-1.0

+2.0,+1.0

+0.0,+0.0
+1.0,+0.5

+2.0,+1.0

+1.0,+0.5
+1.5,+0.9
+2.0,+1.0

MicroMag 2900/3900 Data File ends
"""


def _mm(tmp_path, text):
    p = tmp_path / "bad.micromag"
    p.write_text(text)
    return p


def test_good_micromag_parses(tmp_path):
    data = read_micromag(_mm(tmp_path, GOOD_MM))
    assert data.curves.n_curves == 3 and data.curves.n_points == 6
    np.testing.assert_array_equal(data.calibration_moments, [1.0, 1.0, 1.0])


@pytest.mark.parametrize(
    "line, replacement, pattern",
    [
        (4, "", r"line 10: missing header field NCrv"),
        (4, "NCrv = 2", r"line 21: the header announces 2 curves but the file holds more"),
        (5, "NData = 5", r"line 5: header NData = 5 but the file holds 6 curve points"),
        (5, "NData = six", r"line 5: header field NData must be a non-negative integer"),
        (16, "+1.0,+zz", r"line 16: moment '\+zz' is not a number"),
        (17, "+1.0,nan", r"line 17: moment must be finite"),
        (21, "+1.5", r"line 21: expected 'field,moment'"),
        (22, "+0.9,+1.0", r"line 22: fields must strictly increase"),
        # a one-point block away from HCal is a curve: one curve too many
        (14, "+0.5,+0.0", r"line 21: the header announces 3 curves but the file holds more"),
        (15, "+0.5,+0.0", r"line 15: fields must strictly increase along a pike curve"),
    ],
)
def test_malformed_micromag(tmp_path, line, replacement, pattern):
    lines = GOOD_MM.splitlines()
    lines[line - 1] = replacement
    with pytest.raises(ValueError, match=pattern):
        read_micromag(_mm(tmp_path, "\n".join(lines) + "\n"))


def test_micromag_ragged_calibration_block(tmp_path):
    text = GOOD_MM.replace("+2.0,+1.0\n\n-1.0,-1.0", "+2.0,+1.0\n+2.0,+1.0\n\n-1.0,-1.0", 1)
    with pytest.raises(ValueError, match=r"line 11: fields must strictly increase"):
        read_micromag(_mm(tmp_path, text))
    with pytest.raises(ValueError, match="drift_correction must be"):
        read_micromag(_mm(tmp_path, GOOD_MM), drift_correction="linear")


def test_micromag_optional_ndata_and_aborted_measurement(tmp_path):
    lines = GOOD_MM.splitlines()
    lines[4] = "Remark = none"  # no NData: optional
    data = read_micromag(_mm(tmp_path, "\n".join(lines) + "\n"))
    assert data.complete and data.curves.n_points == 6
    lines[3] = "NCrv = 4"  # one curve more announced than measured: an aborted run
    data = read_micromag(_mm(tmp_path, "\n".join(lines) + "\n"))
    assert not data.complete and data.curves.n_curves == 3
    assert "announces 4 curves" in data.notes[0]


def test_micromag_without_data(tmp_path):
    with pytest.raises(ValueError, match="no data lines"):
        read_micromag(_mm(tmp_path, "MicroMag\nNCrv = 1\nNData = 1\n"))


def test_csv_with_crlf_and_cp1252_comment(tmp_path):
    text = "# sample: Fe3O4, 20 °C, moments in µAm²\r\n" + GOOD_CSV.replace("\n", "\r\n")
    p = tmp_path / "w.csv"
    p.write_bytes(text.encode("cp1252"))
    curves = read_csv(p)
    assert curves.n_curves == 3 and curves.n_points == 6
    np.testing.assert_array_equal(curves.moments[2], [1.0, 0.5, -1.0])
