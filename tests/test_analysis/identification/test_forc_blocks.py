"""Data-only FORC files (two columns, no header, a blank line after every curve): read with the
columns inferred or given, and identified exactly as the CSV of the same curves."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.cli import main
from analysis.identification import identify_from_curves, measure_reversal_curves, regular_grid
from analysis.identification.forc_io import (
    detect_format,
    read_forc_file,
    write_blocks,
    write_csv,
)
from hysteresis.play import GeneralizedPlay


@pytest.fixture(scope="module")
def curves():
    grid = regular_grid(0.25, 6.0)
    # reversal fields below saturation: every curve has two points or more (a one-point block
    # is a calibration point)
    return measure_reversal_curves(
        GeneralizedPlay.erf(2.0, 1.0), grid[:-1], fields=grid, convention="pike", saturation=6.0
    )


@pytest.mark.parametrize("columns", ["field,moment", "moment,field"])
def test_data_only_file_gives_the_density_of_the_csv(tmp_path, curves, columns):
    cal = (6.0, np.full(curves.n_curves, 1.0))
    path = write_blocks(tmp_path / "data.txt", curves, calibration=cal, columns=columns)
    if columns == "field,moment":
        assert detect_format(path) == "blocks"
    data = read_forc_file(path, "blocks", columns=columns)
    assert data.field_unit is None and data.calibration_moments.size == curves.n_curves
    assert any("calibration" in n for n in data.notes)
    ref = read_forc_file(write_csv(tmp_path / "data.csv", curves))
    a = identify_from_curves(data.curves, smoothing=3, uncertainty=True, extend=False)
    b = identify_from_curves(ref.curves, smoothing=3, uncertainty=True, extend=False)
    # the same numbers (repr precision both ways): the same density, bit for bit
    np.testing.assert_array_equal(a.density_alpha_beta, b.density_alpha_beta)
    np.testing.assert_array_equal(a.cell_mass, b.cell_mass)


def test_bad_rows_name_their_line(tmp_path, curves):
    path = write_blocks(tmp_path / "data.txt", curves)
    lines = path.read_text().splitlines()
    lines[3] = "1.0, 2.0, 3.0"
    path.write_text("\n".join(lines))
    with pytest.raises(ValueError, match=r"line 4: expected 2 columns"):
        read_forc_file(path, "blocks")


def test_cli_reads_a_data_only_file(tmp_path, curves, capsys):
    path = write_blocks(tmp_path / "data.txt", curves, columns="moment,field")
    out = tmp_path / "out"
    argv = ["identify", "--input", str(path), "--format", "blocks", "--out", str(out)]
    assert main([*argv, "--columns", "moment,field", "--quiet"]) == 0
    assert (out / "identify.json").exists()
    assert (
        main(
            [
                "identify",
                "--input",
                str(path),
                "--columns",
                "field,moment",
                "--format",
                "csv",
                "--out",
                str(out),
            ]
        )
        == 2
    )
    assert "argument --columns" in capsys.readouterr().err
