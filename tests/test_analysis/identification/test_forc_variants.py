"""Instrument FORC exports: every variant reads (or is refused in one line), units convert, the
protocol grid and smoother agree with an independent textbook Pike (1999) estimator, and the
peak of the FORC distribution sits where the synthetic sample puts it."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import norm
from support_paths import DATA

from analysis.identification import ReversalCurves, identify_from_curves
from analysis.identification.forc_io import (
    detect_format,
    read_forc_file,
    read_lakeshore_csv,
    read_micromag,
)


def _maker():
    spec = importlib.util.spec_from_file_location("make_forc_data", DATA / "make_forc_data.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


MK = _maker()
SEQ = MK.measure()  # the measurement every shipped sample file was written from (seeded)
CURVES = [(h, m) for kind, h, m in SEQ if kind == "curve"]
CALS = [(h[0], m[0]) for kind, h, m in SEQ if kind == "cal"]


def _check_against_sequence(data, n_curves, rtol_field, rtol_moment):
    c = data.curves
    assert c.convention == "pike" and c.n_curves == n_curves
    for k in range(n_curves):
        h, m = CURVES[k]
        n = c.fields[k].size
        np.testing.assert_allclose(c.fields[k], h[:n], rtol=rtol_field)
        np.testing.assert_allclose(c.moments[k], m[:n], rtol=rtol_moment)


@pytest.mark.parametrize(
    "key, fmt, units",
    [
        ("0015", "micromag", "cgs"),
        ("0016", "micromag", "Hybrid SI"),
        ("lakeshore", "lakeshore", None),
    ],
)
def test_each_export_reads_in_mT_and_Am2(key, fmt, units):
    path = MK.SAMPLE_FILES[key]
    assert detect_format(path) == fmt
    data = read_forc_file(path)
    assert data.field_unit == "mT" and data.moment_unit == "A·m²"
    assert data.units_of_measure == units
    assert data.complete
    # 7 significant digits in the file (MicroMag) -> relative 1e-6 after unit conversion
    _check_against_sequence(data, len(CURVES), 1e-6, 1e-6)
    assert data.calibration_moments.size == len(CALS)
    np.testing.assert_allclose(data.calibration_fields, [h for h, _ in CALS], rtol=1e-6)
    assert data.calibration_field == pytest.approx(MK.H_CAL)


def test_series_0016_is_cp1252_with_crlf_and_a_date_line():
    raw = MK.SAMPLE_FILES["0016"].read_bytes()
    assert b"\r\n" in raw and b"Am\xb2" in raw and b"\xb5V" in raw  # cp1252 ², µ
    with pytest.raises(UnicodeDecodeError):
        raw.decode("utf-8")
    lines = raw.decode("cp1252").splitlines()
    assert lines[2][0].isdigit()  # the date/time line is header, not data
    data = read_micromag(MK.SAMPLE_FILES["0016"])
    assert data.header["Units of measure"] == "Hybrid SI"
    assert data.header["Temperature in"] == "°C"


def test_aborted_measurement_reads_what_was_measured():
    data = read_micromag(MK.SAMPLE_FILES["aborted"])
    assert not data.complete
    assert data.units_of_measure == "SI"
    assert data.curves.n_curves == 30 and data.curves.fields[-1].size == 7
    assert any("announces 46 curves" in n for n in data.notes)
    _check_against_sequence(data, 30, 1e-6, 1e-6)


def test_irregular_export_is_refused_in_one_line():
    with pytest.raises(ValueError, match=r"^line 2: .*Multiple segments.* not supported") as e:
        read_micromag(MK.SAMPLE_FILES["irregular"])
    assert "\n" not in str(e.value)


def test_linear_drift_correction_recovers_the_drift_free_moments():
    """The sample's gain drifts linearly in time; the calibration points see the same gain.
    The correction to the first calibration moment removes it up to the calibration points'
    own field drift (<= 2 mT on a reversible slope) and the noise."""
    data = read_micromag(MK.SAMPLE_FILES["0016"], drift_correction="multiplicative")
    raw = read_micromag(MK.SAMPLE_FILES["0016"])
    model = MK.sample()
    gain0 = 1.0 + MK.GAIN_DRIFT * 0  # the first calibration point is measured at t = 0
    err_raw, err_corr = [], []
    for k in (0, 20, 45):
        h = data.curves.fields[k]
        truth = MK.true_moment(model, h, h[0]) * gain0
        err_raw.append(np.max(np.abs(raw.curves.moments[k] - truth)))
        err_corr.append(np.max(np.abs(data.curves.moments[k] - truth)))
    # uncorrected: the gain has drifted by up to ~0.5 % of the moment at the last curve
    assert err_raw[-1] > 10 * MK.NOISE * MK.MOMENT
    # corrected: noise (5 sigma) + calibration-field drift on the reversible slope
    slope = MK.MOMENT * MK.REV_FRACTION / MK.REV_FIELD  # d(moment)/dB at saturation, upper bound
    bound = 5 * MK.NOISE * MK.MOMENT + MK.MOMENT * 1e-3 + slope * MK.CAL_DRIFT
    assert max(err_corr) < bound


def test_malformed_instrument_lines_name_the_line(tmp_path):
    text = MK.SAMPLE_FILES["0015"].read_text().splitlines()
    first = next(i for i, line in enumerate(text) if line.startswith("+"))
    bad = list(text)
    bad[first + 3] = "+1.0E+02;+3.0E-03"
    (tmp_path / "a.frc").write_text("\n".join(bad) + "\n")
    with pytest.raises(ValueError, match=rf"^line {first + 4}: "):
        read_micromag(tmp_path / "a.frc")
    bad = list(text)
    bad[4] = "Units of measure = furlongs"
    (tmp_path / "b.frc").write_text("\n".join(bad) + "\n")
    with pytest.raises(ValueError, match=r"^line 5: Units of measure must be cgs, SI or Hybrid"):
        read_micromag(tmp_path / "b.frc")
    ls = MK.SAMPLE_FILES["lakeshore"].read_text().splitlines()
    ls[3] = "Time Stamp [s],Field (µ0H) [furlong],Moment (m) [A·m²]"
    (tmp_path / "c.csv").write_text("\n".join(ls) + "\n")
    with pytest.raises(ValueError, match=r"^line 4: cannot tell the unit of the field column"):
        read_lakeshore_csv(tmp_path / "c.csv")
    (tmp_path / "d.frc").write_bytes(b"MicroMag 2900\nFirst-order reversal curves\n\xff\xfe\n")
    with pytest.raises(ValueError, match="no data lines"):
        read_micromag(tmp_path / "d.frc")


# ----------------------------------------------------------------------------------------------
# FORC diagram: protocol grid, NaN outside the data, independent Pike (1999) estimator
# ----------------------------------------------------------------------------------------------
def _pike_1999(curves: ReversalCurves, at_h, at_hr, sf: int, step: float) -> np.ndarray:
    """Textbook Pike et al. (1999): at (H_r0, H0), least squares of
    M = a1 + a2 H + a3 H² + a4 H_r + a5 H_r² + a6 H H_r over the (2 SF + 1)² measured points
    nearest in H and H_r (selected by distance <= (SF + ½)·step), ρ = −a6/2. Written here
    independently of the toolkit's gridded, FFT-based estimator."""
    rows = curves.as_rows()
    hr, h, m = rows[:, 0], rows[:, 1], rows[:, 2]
    out = np.empty(len(at_h))
    for k, (h0, hr0) in enumerate(zip(at_h, at_hr, strict=True)):
        w = (np.abs(h - h0) <= (sf + 0.5) * step) & (np.abs(hr - hr0) <= (sf + 0.5) * step)
        x, y = h[w] - h0, hr[w] - hr0
        design = np.column_stack([np.ones(x.size), x, x * x, y, y * y, x * y])
        coef = np.linalg.lstsq(design, m[w], rcond=None)[0]
        out[k] = -0.5 * coef[5]
    return out


@pytest.mark.parametrize("sf", [2, 3])
def test_forc_density_agrees_with_pike_1999_and_the_known_peak(sf):
    data = read_micromag(MK.SAMPLE_FILES["0016"], drift_correction="multiplicative")
    ident = identify_from_curves(data.curves, smoothing=sf, extend=False, window="pike")
    assert ident.step == pytest.approx(MK.STEP, rel=1e-3)  # the protocol's step, not 10⁻⁴ cells
    bc, bu, peak = ident.density_peak()
    # the sample: B_c ~ N(30, 6²), B_u ~ N(0, 5²) mT -> mode at (30, 0)
    assert abs(bc - MK.BC_MEAN) <= MK.STEP and abs(bu) <= MK.STEP
    # rho = -1/2 d2M/dBr dB of the irreversible part: M (1 - f) p(B_c) p(B_u) / 2 at the mode;
    # a quadratic fit over +-SF steps flattens a Gaussian peak of width 5-6 mT (only downward)
    true_peak = MK.MOMENT * (1 - MK.REV_FRACTION) * norm.pdf(0, 0, MK.BC_SD)
    true_peak *= norm.pdf(0, 0, MK.BU_SD) / 2
    assert 0.8 * true_peak < peak < 1.0 * true_peak
    aa, bb = np.meshgrid(ident.alpha, ident.beta, indexing="ij")
    dens = ident.density_alpha_beta
    sel = np.isfinite(dens) & (dens > 0.2 * peak)
    assert sel.sum() > 100
    pike = _pike_1999(data.curves, aa[sel], bb[sel], sf, ident.step)
    # same data, same estimator; differences only from interpolating the jittered fields
    # (0.05 mT on a 2 mT step) onto the lattice: well below 2 % of the peak
    assert np.max(np.abs(pike - dens[sel])) < 0.02 * peak


def test_density_is_nan_outside_the_measured_region_and_ridge_switch():
    data = read_micromag(MK.SAMPLE_FILES["0016"])
    irr = identify_from_curves(data.curves, smoothing=3)  # measured data: no ridge by default
    assert irr.reversible_ridge is False
    rev = identify_from_curves(data.curves, smoothing=3, extend=True)
    aa, bb = np.meshgrid(irr.alpha, irr.beta, indexing="ij")
    beyond = (aa > MK.H_MAX + MK.STEP) | (bb > MK.HR_MAX + MK.STEP) | (bb > aa)
    assert np.all(np.isnan(irr.density_alpha_beta[beyond]))
    assert np.all(np.isnan(rev.density_alpha_beta[beyond]))
    # no spikes: every finite value within 1.5x the true peak in magnitude
    _, _, peak = irr.density_peak()
    assert np.nanmax(np.abs(irr.density_alpha_beta)) <= 1.5 * peak
    # the reversible part (0.15 tanh(B/60)) appears as a ridge next to B_c = 0 only with the
    # extension; without it the band within the window of the diagonal has no data below the
    # diagonal and is blank (NaN), not a ridge
    near = np.isclose(aa - bb, irr.step) & (np.abs(aa) < 20)
    assert np.all(np.isnan(irr.density_alpha_beta[np.isclose(aa, bb)]))
    assert np.all(np.isnan(irr.density_alpha_beta[near]))
    noise = np.nanstd(irr.density_alpha_beta[(aa - bb) / 2 > 60])  # no sample there: noise
    assert np.isfinite(irr.density_alpha_beta[(aa - bb) / 2 > 60]).sum() > 50
    assert np.nanmean(rev.density_alpha_beta[near]) > 5 * noise
    # the cell masses split into reversible (diagonal) and irreversible parts: the sample's
    # reversible moment change between the lowest and highest nodes, 0.15 (tanh(90/60) -
    # tanh(-70/60)) M / 2, is in the diagonal cells
    expected_rev = 0.5 * MK.MOMENT * (MK.reversible(irr.alpha[-1]) - MK.reversible(irr.alpha[0]))
    assert irr.reversible_mass == pytest.approx(expected_rev, rel=0.05)


def test_cli_measured_json_and_figures(tmp_path, capsys):
    from analysis.cli import main

    args = ["identify", "--input", str(MK.SAMPLE_FILES["0016"]), "--out", str(tmp_path)]
    assert main(args + ["--json", "--smoothing", "2", "--drift-correction", "multiplicative"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["format"] == "micromag" and rep["units_of_measure"] == "Hybrid SI"
    assert rep["n_curves"] == 46 and rep["n_points"] == len(np.concatenate([h for h, _ in CURVES]))
    assert rep["grid_step_mT"] == pytest.approx(2.0, rel=1e-3)
    assert rep["smoothing_factor"] == [2.0, 2.0]
    assert abs(rep["peak_bc_mT"] - 30.0) <= 2.0 and abs(rep["peak_bu_mT"]) <= 2.0
    assert rep["reversible_ridge"] is False
    assert rep["irreversible_mass"] == pytest.approx(MK.MOMENT * (1 - MK.REV_FRACTION), rel=0.05)
    for key in ("total_mass", "s_cdf_distance_gaussian", "r_centre", "width", "spread"):
        assert key not in rep
    for p in rep["figures"]:
        assert Path(p).stat().st_size > 0
    assert main(args + ["--json", "--reversible-ridge"]) == 0
    assert json.loads(capsys.readouterr().out)["reversible_ridge"] is True
    # an aborted run and the Lake Shore export go through the same path
    assert (
        main(
            [
                "identify",
                "--input",
                str(MK.SAMPLE_FILES["aborted"]),
                "--out",
                str(tmp_path),
                "--json",
            ]
        )
        == 0
    )
    rep = json.loads(capsys.readouterr().out)
    assert rep["complete"] is False and rep["n_curves"] == 30 and rep["units_of_measure"] == "SI"
    assert (
        main(
            [
                "identify",
                "--input",
                str(MK.SAMPLE_FILES["lakeshore"]),
                "--out",
                str(tmp_path),
                "--json",
                "--window",
                "pike",
            ]
        )
        == 0
    )
    rep = json.loads(capsys.readouterr().out)
    assert rep["format"] == "lakeshore" and rep["n_curves"] == 46 and rep["window"] == "pike"
    assert abs(rep["peak_bc_mT"] - 30.0) <= 2.0 and abs(rep["peak_bu_mT"]) <= 2.0
    # refused or malformed files: exit code 2 and one line on stderr, no traceback
    code = main(["identify", "--input", str(MK.SAMPLE_FILES["irregular"]), "--out", str(tmp_path)])
    err = capsys.readouterr().err
    assert code == 2 and "line 2:" in err and "Multiple segments" in err
    assert err.count("\n") == 1 and "Traceback" not in err


@pytest.mark.parametrize("window", ["rs", "pike"])
def test_fft_smoother_equals_per_node_least_squares(window):
    """grid_quadratic_density solves the normal equations of every node at once (FFT
    correlations); a plain lstsq per node over the same valid lattice points must agree."""
    from analysis.identification import grid_quadratic_density

    rng = np.random.default_rng(7)
    n, step, sf = 30, 0.5, 2.0
    x = step * np.arange(n)
    aa, bb = np.meshgrid(x, x, indexing="ij")
    E = np.sin(aa) * np.cos(0.7 * bb) + 0.05 * rng.normal(size=aa.shape)
    valid = (rng.random(aa.shape) > 0.1) & (bb <= aa + 2 * step)
    evaluate = bb <= aa
    fast = grid_quadratic_density(E, valid, evaluate, step, sf, sf, window)
    checked = 0
    for i, j in zip(*np.nonzero(np.isfinite(fast)), strict=True):
        di = aa - aa[i, j]
        dj = bb - bb[i, j]
        if window == "pike":
            win = (np.abs(di) <= sf * step + 1e-9) & (np.abs(dj) <= sf * step + 1e-9)
        else:
            win = (np.abs(di - dj) / 2 <= sf * step + 1e-9) & (
                np.abs(di + dj) / 2 <= sf * step + 1e-9
            )
        win &= valid
        X = np.column_stack(
            [np.ones(win.sum()), di[win], dj[win], di[win] ** 2, dj[win] ** 2, di[win] * dj[win]]
        )
        coef = np.linalg.lstsq(X, E[win], rcond=None)[0]
        assert fast[i, j] == pytest.approx(-coef[5], abs=1e-9 * max(1.0, abs(coef[5])))
        checked += 1
    assert checked > 100
    # nodes whose window is not covered on both sides are NaN, never extrapolated
    assert np.all(np.isnan(fast[~evaluate]))


def test_irregular_protocol_reversal_and_field_steps():
    """Reversal fields every 4 mT, field steps 1.5 mT near the reversal and 3 mT beyond: the
    lattice takes the median step, the regression does the rest; the peak stays within a step
    of the sample's mode and the irreversible mass is the sample's."""
    model = MK.sample()
    rng = np.random.default_rng(0)
    revs, fields, moments = [], [], []
    for hr in np.arange(20.0, -70.1, -4.0):
        h = np.concatenate([hr + np.arange(0, 12, 1.5), hr + 12 + np.arange(0, 90 - hr - 12, 3.0)])
        h = h + rng.normal(0, 0.05, h.size)
        h[0] = hr
        m = MK.true_moment(model, h, h[0]) + rng.normal(0, MK.NOISE * MK.MOMENT, h.size)
        revs.append(hr)
        fields.append(h)
        moments.append(m)
    ident = identify_from_curves(
        ReversalCurves(np.array(revs), tuple(fields), tuple(moments), "pike"), smoothing=3
    )
    assert ident.step == pytest.approx(3.0, rel=0.02)
    bc, bu, _ = ident.density_peak()
    assert abs(bc - MK.BC_MEAN) <= ident.step and abs(bu) <= ident.step
    expected = MK.MOMENT * (1 - MK.REV_FRACTION)  # every relay inside the measured range
    assert ident.irreversible_mass == pytest.approx(expected, rel=0.01)
