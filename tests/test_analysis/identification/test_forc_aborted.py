"""An aborted FORC run (the last curve stops part-way) gave a negative irreversible mass with
every smoothing (tests/data/forc_micromag_0016_si_aborted.frc: −3.86e-7 A·m² before, +3.37e-6
after). The cause: on the protocol lattice a curve was held constant beyond its last point, so
the cells between the partial curve and the curve above it received minus that curve's rise
(E(α, β_0) constant, E(α, β_1) rising: mixed difference −ΔE(α, β_1)). A curve now continues
parallel to the curve above it, which puts zero mass into the cells it did not measure."""

from __future__ import annotations

import json
import math
from types import SimpleNamespace

import numpy as np
import pytest
from support_paths import DATA

from analysis.cli import main
from analysis.cli._identify_measured import data_warnings
from analysis.identification import identify_from_curves, measure_reversal_curves
from analysis.identification.curves import ReversalCurves
from analysis.identification.forc_io import read_forc_file
from hysteresis.preisach import PreisachModel

ABORTED = DATA / "forc_micromag_0016_si_aborted.frc"
COMPLETE = DATA / "forc_micromag_0016_hybrid_si.frc"
STEP = 0.5
NODES = STEP * np.arange(-12, 13)  # −6 … 6


def _relays():
    rng = np.random.default_rng(5)
    s = rng.normal(0.0, 1.0, 600)
    r = np.abs(rng.normal(2.0, 0.7, 600))
    return np.clip(s + r, -5.9, 5.9), np.clip(s - r, -5.9, 5.9)


def _curves():
    """Exact Pike curves of a discrete Preisach model on the lattice, and the same run aborted
    on its last (lowest) curve after 7 points."""
    alpha, beta = _relays()
    full = measure_reversal_curves(
        PreisachModel.from_relays(alpha, beta),
        NODES[:-1],
        fields=NODES,
        convention="pike",
        saturation=6.0,
    )
    fields = list(full.fields)
    moments = list(full.moments)
    low = int(np.argmin(full.reversal_field))
    fields[low], moments[low] = fields[low][:7], moments[low][:7]
    cut = ReversalCurves(full.reversal_field, tuple(fields), tuple(moments), "pike")
    return full, cut, float(fields[low][-1])


def test_partial_last_curve_adds_no_mass_where_it_was_not_measured():
    alpha, beta = _relays()
    full, cut, end = _curves()
    kw = {"grid": "protocol", "step": STEP, "output_range": (-math.inf, math.inf)}
    a = identify_from_curves(full, **kw)
    b = identify_from_curves(cut, **kw)
    np.testing.assert_allclose(a.alpha, NODES, atol=1e-12)
    np.testing.assert_allclose(b.alpha, NODES, atol=1e-12)
    # exact data on the lattice: every cell of the full run holds the relays inside it
    # (rounding of outputs in [−1, 1] summed over 600 relays: < 1e-12)
    i = np.searchsorted(NODES, alpha, side="left") - 1
    j = np.searchsorted(NODES, beta, side="left") - 1
    truth = np.zeros(a.cell_mass.shape)
    np.add.at(truth, (i, j), 1.0 / alpha.size)
    np.testing.assert_allclose(a.cell_mass, truth, atol=1e-12)
    # the aborted run: the same masses, except the strip between the partial curve (β_0) and
    # the curve above it beyond the partial curve's end, where nothing was measured: zero
    strip = np.zeros(truth.shape, dtype=bool)
    strip[NODES[:-1] >= end, 0] = True
    np.testing.assert_allclose(b.cell_mass, np.where(strip, 0.0, truth), atol=1e-12)
    assert b.irreversible_mass == pytest.approx(
        a.irreversible_mass - truth[strip & ~a._diagonal_cells()].sum(), abs=1e-12
    )
    # the old extension (the partial curve constant beyond its end), written out here: the
    # strip gets minus the rise of the curve above, the total telescopes to the partial curve's
    # own rise, whatever the sample holds
    e = np.array(b.everett, dtype=float)
    beyond = NODES > end
    e[beyond, 0] = e[NODES == end, 0][0]
    old = e[1:, :-1] - e[:-1, :-1] - e[1:, 1:] + e[:-1, 1:]
    rise_above = e[-1, 1] - e[NODES == end, 1][0]
    assert old[strip].sum() == pytest.approx(-rise_above, abs=1e-12)
    assert old[strip].sum() < -0.1  # a tenth of the saturation moment, negative


def test_shipped_aborted_file_has_a_positive_irreversible_mass_and_a_warning(tmp_path):
    ab = identify_from_curves(
        read_forc_file(ABORTED).curves, output_range=(-math.inf, math.inf), step=2.0
    )
    co = identify_from_curves(
        read_forc_file(COMPLETE).curves, output_range=(-math.inf, math.inf), step=2.0
    )
    curves = read_forc_file(ABORTED).curves
    end = curves.fields[-1][-1]
    # beyond the partial curve's end its strip holds no mass (E ~ 1e-6 A·m², rounding 1e-22)
    assert np.max(np.abs(ab.cell_mass[ab.alpha[:-1] >= end, 0])) < 1e-20
    # the same as the complete file's irreversible mass over the reversal fields both measured
    # fully: the two files hold the same numbers there; the lattices differ by 0.0065 mT
    # (anchoring, 0.3 % of the step), which moves ~0.3 % of the masses at the cell boundaries
    # (3.4e-6 irreversible, 0.7e-6 reversible: <= 1.2e-8); bound 3e-8
    full_rows = co.beta[:-1] >= ab.beta[1] - 1.0
    off_diag = np.where(co._diagonal_cells(), 0.0, co.cell_mass)
    assert ab.irreversible_mass > 0
    assert ab.irreversible_mass == pytest.approx(off_diag[:, full_rows].sum(), abs=3e-8)
    out = tmp_path / "out"
    assert main(["identify", "--input", str(ABORTED), "--out", str(out), "--quiet"]) == 0
    report = json.loads((out / "identify.json").read_text())
    assert report["irreversible_mass"] > 0
    (warning,) = report["warnings"]
    assert warning.startswith("aborted measurement (header announces 46 curves")
    assert "its last curve (B_r = -38.06 mT) stops at -26.07 mT" in warning


def test_warnings_name_their_cause():
    complete = read_forc_file(COMPLETE)
    assert (
        data_warnings(complete, SimpleNamespace(irreversible_mass=4e-6, density_alpha_beta=None))
        == []
    )
    (negative,) = data_warnings(
        complete, SimpleNamespace(irreversible_mass=-2e-9, density_alpha_beta=None)
    )
    assert negative.startswith("the irreversible mass is negative (-2e-09): the measured curves")
    aborted = read_forc_file(ABORTED)
    (warning,) = data_warnings(
        aborted, SimpleNamespace(irreversible_mass=3e-6, density_alpha_beta=None)
    )
    assert "cover reversal fields >= -38.06 mT only" in warning
