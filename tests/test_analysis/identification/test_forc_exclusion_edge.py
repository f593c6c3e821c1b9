"""The FORC peak at the ridge exclusion's edge on coarse grids (issue 32): the peak search skips
``B_c`` below 3 grid steps (PmagPy's convention, kept); on a 6.66 mT grid (15–20 mT excluded)
the smoothed density of a real file rises toward the ridge across the edge, and the peak there
is reported as unresolved (a warning, ``peak_at_exclusion_edge``, a ``B_c`` interval from 0)
instead of as a peak with a zero-width interval. Truth: the smoothed density itself, row by
row in ``B_c``."""

from __future__ import annotations

import json
import math

import numpy as np

from analysis.cli import main
from analysis.identification import identify_from_curves
from analysis.identification.datasets import forc_sample
from analysis.identification.forc_io import read_forc_file
from analysis.identification.result import RIDGE_EXCLUSION_STEPS


def _ident(name: str):
    curves = read_forc_file(forc_sample(name)).curves
    return identify_from_curves(curves, smoothing=(3.0, 3.0), output_range=(-math.inf, math.inf))


def _row_maxima(ident):
    """The largest smoothed density per B_c row (in half grid steps), from the density."""
    dens = ident.density_alpha_beta
    bc = 0.5 * (ident.alpha[:, None] - ident.beta[None, :]) / ident.grid_step
    rows = np.round(2 * bc) / 2
    keys = np.unique(rows[np.isfinite(dens)])
    return {float(k): float(np.nanmax(np.where(rows == k, dens, np.nan))) for k in keys}


def test_coarse_irregular_file_peak_at_the_edge_is_flagged():
    ident = _ident("micromag-data-only")
    bc, _, rho = ident.density_peak()
    edge = RIDGE_EXCLUSION_STEPS * ident.grid_step
    assert abs(bc - edge) < 1e-6 * edge  # the search's maximum sits on the edge row
    rows = _row_maxima(ident)
    inside = [v for k, v in rows.items() if k < RIDGE_EXCLUSION_STEPS]
    assert inside and max(inside) > rho  # the density is larger across the edge
    assert ident.peak_at_exclusion_edge()


def test_interior_peak_on_a_coarse_grid_is_not_flagged():
    # MSM33 remanence FORC (5.25 mT grid): the row maxima peak 4 steps out, inside the search
    ident = _ident("micromag-remanence")
    bc, _, _ = ident.density_peak()
    rows = _row_maxima(ident)
    best = max(rows, key=rows.get)
    assert best > RIDGE_EXCLUSION_STEPS and abs(bc - best * ident.grid_step) < 1e-6 * bc
    assert not ident.peak_at_exclusion_edge()


def test_cli_reports_the_edge_with_an_interval_from_zero(tmp_path, capsys):
    path = forc_sample("micromag-data-only")
    argv = ["identify", "--input", str(path), "--uncertainty", "--bootstrap", "20"]
    assert main([*argv, "--out", str(tmp_path), "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["peak_at_exclusion_edge"] is True
    assert rep["peak_bc_interval_mT"][0] == 0.0
    assert rep["peak_bc_interval_mT"][1] >= rep["peak_bc_mT"]
    assert any("exclusion edge" in w for w in rep["warnings"])
