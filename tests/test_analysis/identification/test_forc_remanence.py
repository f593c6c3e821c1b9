"""Remanence FORCs (every field point measured back at zero field) in MicroMag "Multiple
segments" exports, checked three ways on a known discrete Preisach model
(tests/data/make_forc_data.py writes tests/data/forc_micromag_remanence.frc):

* closed form: a relay (α, β) is up at zero field after positive saturation → B_a → B_b → 0
  iff β <= 0 and (β <= B_a or α <= max(B_b, 0)), so ρ_rem(B_a, B_b) = μ(B_b, B_a)·[B_a <= 0 <= B_b]
  (derivation in analysis/identification/curves.py);
* brute force: the relays driven one input at a time through the script's field sequence,
  written here with the relay rule only (up once u >= α, down once u < β);
* the toolkit: the curves reconstructed from the synthetic export and their exact cell masses.
"""

from __future__ import annotations

import importlib.util
import json

import numpy as np
import pytest
from support_paths import DATA

from analysis.cli import main
from analysis.identification import identify_from_curves
from analysis.identification.forc_io import detect_format, read_forc_file


def _maker():
    spec = importlib.util.spec_from_file_location("make_forc_data", DATA / "make_forc_data.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


MK = _maker()
REMANENCE = DATA / "forc_micromag_remanence.frc"
TABLE = MK.remanence_model().relay_table()
ALPHA, BETA, W = (np.asarray(x, dtype=float) for x in (TABLE.alpha, TABLE.beta, TABLE.weights))
# the file's moments were summed by the model's incremental switching (up to 400 relay switches
# per curve, each adding a rounding of at most ε = 2.2e-16 to outputs in [-1, 1]: <= 9e-14) and
# written with 16 significant digits (1e-15); a cell mass is a sum of four such moments
ROUND = 4e-13


def brute_force_remanence(b_a: float, fields: np.ndarray) -> np.ndarray:
    """Zero-field moment after each field of the curve, relay by relay through the protocol:
    positive saturation, B_a, then B_b, 0 for every field B_b in turn."""
    y = np.ones(ALPHA.size)  # positive saturation: every relay up
    out = []
    for k, u in enumerate(np.ravel(np.column_stack([fields, np.zeros_like(fields)]))):
        y = np.where(u >= ALPHA, 1.0, np.where(u < BETA, -1.0, y))
        if k % 2:  # back at zero field
            out.append(float(W @ y))
    return np.array(out)


def closed_form_remanence(b_a: float, b_b: float) -> float:
    up = (BETA <= 0) & ((BETA <= b_a) | (ALPHA <= max(b_b, 0.0)))
    return float(W @ np.where(up, 1.0, -1.0))


def test_remanence_export_is_detected_and_read_as_remanence_curves():
    assert detect_format(REMANENCE) == "segments"
    data = read_forc_file(REMANENCE)
    assert data.curves.kind == "remanence" and data.in_field_curves.kind == "in-field"
    assert data.curves.n_curves == 16 and data.complete
    assert data.calibration_moments.size == 16
    assert data.notes[0].startswith("remanence FORC protocol: 16 curves")
    # the in-field companion file of the same script is an in-field FORC
    assert read_forc_file(DATA / "forc_micromag_segments.frc").curves.kind == "in-field"


def test_remanent_moments_closed_form_brute_force_and_reconstruction_agree():
    curves = read_forc_file(REMANENCE).curves
    for b_a, h, m in zip(curves.reversal_field, curves.fields, curves.moments, strict=True):
        brute = brute_force_remanence(b_a, h)
        closed = np.array([closed_form_remanence(b_a, b) for b in h])
        # the brute force and the closed form count the same relays: equal to summation order
        np.testing.assert_allclose(brute, closed, rtol=0, atol=1e-13)
        np.testing.assert_allclose(m, brute, rtol=0, atol=ROUND)


def test_remanence_cell_masses_are_the_remanence_carriers_of_the_in_field_density():
    data = read_forc_file(REMANENCE)
    rem = identify_from_curves(data.curves, grid="native")
    infield = identify_from_curves(data.in_field_curves, grid="native")
    assert rem.curve_kind == "remanence" and infield.curve_kind == "in-field"
    a, b = rem.alpha, rem.beta  # α = B_b (fields), β = B_a (reversal fields); 0 is a node
    # closed form: the weight of the relays in each cell with β <= 0 < α
    i = np.searchsorted(a, ALPHA, side="left")  # α in (a[i-1], a[i]]
    j = np.searchsorted(b, BETA, side="left")
    carriers = (BETA <= 0) & (ALPHA > 0)
    expected = np.zeros(rem.cell_mass.shape)
    np.add.at(expected, (i[carriers] - 1, j[carriers] - 1), W[carriers])
    np.testing.assert_allclose(rem.cell_mass, expected, rtol=0, atol=ROUND)
    # ... which is the in-field density restricted to the quadrant B_a <= 0 <= B_b
    quadrant = (a[1:, None] > 0) & (b[None, 1:] <= 0)
    np.testing.assert_allclose(rem.cell_mass[~quadrant], 0.0, atol=ROUND)
    np.testing.assert_allclose(
        rem.cell_mass[quadrant], infield.cell_mass[quadrant], rtol=0, atol=ROUND
    )
    # and the brute-force mixed differences of the zero-field moments, cell by cell
    e = np.zeros((a.size, b.size))
    for jj, (b_a, h) in enumerate(zip(data.curves.reversal_field, data.curves.fields, strict=True)):
        brute = brute_force_remanence(b_a, h)
        e[np.searchsorted(a, h), jj] = 0.5 * (brute - brute[0])
    brute_mass = e[1:, :-1] - e[:-1, :-1] - e[1:, 1:] + e[:-1, 1:]
    np.testing.assert_allclose(rem.cell_mass, brute_mass, rtol=0, atol=ROUND)
    assert rem.total_mass == pytest.approx(W[carriers].sum(), abs=ROUND)
    # a real split: the model has relays on both sides (the in-field masses differ)
    assert min(W[carriers].sum(), W[~carriers].sum()) > 0.1


def test_remanence_run_stopped_before_a_zero_field_point(tmp_path):
    lines = REMANENCE.read_text(encoding="utf-8").splitlines()
    end = lines.index("MicroMag 2900/3900 Data File ends")
    data_rows = [k for k, line in enumerate(lines) if line.count(",") == 1 and line[:1] in "+-"]
    # the run stops after the reversal point (5.25 mT) of the last curve: its zero-field point
    # and the last field (6 mT) are missing, the script ends with the segment that measured it;
    # the curve is left without any remanence point
    n = len(data_rows) - 3
    keep = [
        line
        for line in lines[: data_rows[0]]
        if line.count(",") != 6 or int(line.split(",")[6]) <= n
    ]
    cut = keep + [lines[k] for k in data_rows[:n]] + lines[end:]
    path = tmp_path / "stopped.frc"
    path.write_text("\r\n".join(cut), encoding="utf-8")
    data = read_forc_file(path)
    assert not data.complete and "no zero-field point" in data.notes[1]
    full = read_forc_file(REMANENCE)
    assert data.curves.n_curves == full.curves.n_curves - 1
    for a, b in zip(data.curves.moments, full.curves.moments[:-1], strict=True):
        np.testing.assert_array_equal(a, b)


def test_field_point_followed_by_a_field_point_is_refused(tmp_path):
    lines = REMANENCE.read_text(encoding="utf-8").splitlines()
    rows = [k for k, line in enumerate(lines) if line.count(",") == 6]
    # make the 5th segment (the first zero-field point) a field point at 0.5 mT
    cells = lines[rows[4]].split(",")
    cells[2] = cells[4] = "+5.000000000000000E-04"
    lines[rows[4]] = ",".join(cells)
    path = tmp_path / "broken.frc"
    path.write_text("\r\n".join(lines), encoding="utf-8")
    with pytest.raises(ValueError, match=r"^line \d+: the field point has no zero-field"):
        read_forc_file(path)


def test_cli_names_the_remanence_diagram(tmp_path):
    out = tmp_path / "out"
    assert main(["identify", "--input", str(REMANENCE), "--out", str(out), "--quiet"]) == 0
    report = json.loads((out / "identify.json").read_text())
    assert report["curve_kind"] == "remanence FORC"
    assert report["figure_title"].startswith("Remanence FORC diagram")
    assert (out / "identify_forc_micromag_remanence.png").exists()
