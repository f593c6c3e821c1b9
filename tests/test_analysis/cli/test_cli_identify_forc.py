"""``hyst identify --input``: VARIFORC, uncertainty, units and normalisation from the command line.

Physics of the estimators is tested in tests/test_analysis/identification/test_variforc.py;
here: the options reach the library, the report says what was done, the one-line errors name
the option, and the units convert (cgs, SI, Hybrid SI -> A·m²/T², mass normalisation).
"""

from __future__ import annotations

import importlib.util
import io
import json
from contextlib import redirect_stdout
from pathlib import Path

import numpy as np
import pytest
from support_paths import DATA

from analysis.cli import main
from analysis.identification.normalization import normalized_unit, sample_amount

HYBRID = DATA / "forc_micromag_0016_hybrid_si.frc"
CGS = DATA / "forc_micromag_0015_cgs.frc"


def _maker():
    spec = importlib.util.spec_from_file_location("make_forc_data", DATA / "make_forc_data.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def run_json(argv: list[str]) -> dict:
    buf = io.StringIO()
    with redirect_stdout(buf):
        assert main(["identify", *argv, "--json", "--quiet"]) == 0
    return json.loads(buf.getvalue())


def test_variforc_and_uncertainty_from_the_command_line(tmp_path):
    rep = run_json(
        [
            "--input",
            str(HYBRID),
            "--smoothing",
            "variforc",
            "--sc0",
            "2",
            "--lambda",
            "0.1",
            "--uncertainty",
            "--out",
            str(tmp_path),
        ]
    )
    assert rep["smoothing_method"] == "variforc" and rep["smoothing_factor"] is None
    assert rep["variforc"] == {
        "sc0": 2.0,
        "sc1": 7.0,
        "sb0": 3.0,
        "sb1": 7.0,
        "lam": 0.1,
        "bu0": 0.0,
    }
    lo, hi = rep["peak_bc_interval_mT"]
    assert lo <= rep["peak_bc_mT"] <= hi
    lo, hi = rep["peak_bu_interval_mT"]
    assert lo <= rep["peak_bu_mT"] <= hi
    assert rep["irreversible_mass_se"] > 0 and rep["peak_rho_se"] > 0
    assert rep["peak_interval_method"] == "parametric bootstrap, 200 replicates, 95 %"
    assert rep["rho_unit"] == "A·m²/T²"
    npz = np.load(next(Path(tmp_path).glob("*.npz")))
    assert {"rho", "rho_se", "significance"} <= set(npz.files)
    both = np.isfinite(npz["rho"]) & np.isfinite(npz["rho_se"])
    np.testing.assert_allclose(npz["significance"][both], (npz["rho"] / npz["rho_se"])[both])


@pytest.mark.parametrize(
    "argv, option",
    [
        (["--smoothing", "variforc", "--sc0", "0.5"], "--sc0"),
        (["--smoothing", "variforc", "--lambda", "1.5"], "--lambda"),
        (["--sc1", "4"], "--sc1"),
        (["--smoothing", "variforc", "--window", "pike"], "--window"),
        (["--smoothing", "abc"], "--smoothing"),
        (["--normalize", "mass"], "--normalize"),  # the header says Mass N/A
        (["--mass", "1e-3"], "--mass"),
        (["--cmap", "no-such-map"], "--cmap"),
        (["--uncertainty", "--bootstrap", "5"], "--bootstrap"),
        (["--bootstrap", "50"], "--bootstrap"),  # without --uncertainty: not ignored
        (["--bootstrap-seed", "3"], "--bootstrap-seed"),
    ],
)
def test_bad_options_are_one_line_errors(argv, option, tmp_path, capsys):
    assert main(["identify", "--input", str(HYBRID), *argv, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"argument {option}:" in err[0]


@pytest.mark.parametrize(
    "argv", [["--smoothing", "variforc"], ["--uncertainty"], ["--cmap", "viridis"]]
)
def test_model_runs_refuse_the_measured_options(argv, capsys):
    assert main(["identify", "--model", "erf-play", *argv]) == 2
    err = capsys.readouterr().err
    assert f"argument {argv[0]}: " in err and "only for measured data" in err


def test_units_round_trip_to_Am2_per_T2(tmp_path):
    """The same measurement written in cgs (Oe, emu), SI and Hybrid SI (T, A·m²) gives one ρ in
    A·m²/T². The files round every value to 7 significant digits: a relative 5e-7 of a moment
    of ~5e-6 A·m², 2000 times below the measurement noise (1e-3 of the saturation moment); the
    estimator is linear in the moments, so the rounding moves ρ by well under 1 % of its noise
    standard error (the bound asserted)."""
    mk = _maker()
    si = tmp_path / "si.frc"
    si.write_bytes(mk.micromag_0016(mk.measure(), units="SI").encode("cp1252"))
    reps = [
        run_json(["--input", str(p), "--uncertainty", "--out", str(tmp_path / p.stem)])
        for p in (CGS, si, HYBRID)
    ]
    ref = reps[-1]
    for rep in reps:
        assert rep["rho_unit"] == "A·m²/T²"
        assert abs(rep["peak_rho"] - ref["peak_rho"]) <= 0.01 * ref["peak_rho_se"]
        assert (rep["peak_bc_mT"], rep["peak_bu_mT"]) == pytest.approx(
            (ref["peak_bc_mT"], ref["peak_bu_mT"]), abs=1e-3
        )
    # cgs: ρ in emu/Oe² is 1e5 A·m²/T² per unit; the report is already converted
    assert reps[0]["units_of_measure"] == "cgs" and ref["units_of_measure"] == "Hybrid SI"


def test_mass_normalisation_from_the_header(tmp_path):
    text = (
        HYBRID.read_bytes()
        .decode("cp1252")
        .replace(
            "Mass                            N/A",
            "Mass                            +2.500000E+01 mg",
        )
    )
    path = tmp_path / "with_mass.frc"
    path.write_bytes(text.encode("cp1252"))
    plain = run_json(["--input", str(HYBRID), "--out", str(tmp_path / "a")])
    per_kg = run_json(["--input", str(path), "--normalize", "mass", "--out", str(tmp_path / "b")])
    assert per_kg["rho_unit"] == "A·m²/kg/T²" and per_kg["mass_unit"] == "A·m²/kg"
    assert per_kg["normalized_by"] == pytest.approx(25e-6, rel=1e-15)
    assert per_kg["peak_rho"] == pytest.approx(plain["peak_rho"] / 25e-6, rel=1e-12)
    assert per_kg["irreversible_mass"] == pytest.approx(
        plain["irreversible_mass"] / 25e-6, rel=1e-12
    )
    # the volume from the header, with its unit (A·m²/m³ = A/m), and the refusals
    assert sample_amount({"Volume": "+2.0E+00 mm³"}, "volume") == pytest.approx(2e-9, rel=1e-15)
    assert normalized_unit("A·m²", "volume") == "A/m"
    for header in ({"Mass": "N/A"}, {"Mass": "+1.0E+00"}, {}):
        with pytest.raises(ValueError, match="pass it with --mass|pass --mass"):
            sample_amount(header, "mass")


def test_readme_is_not_a_forc_file(tmp_path, capsys):
    readme = Path(__file__).resolve().parents[3] / "README.md"
    assert main(["identify", "--input", str(readme), "--out", str(tmp_path)]) == 2
    assert "not a FORC file" in capsys.readouterr().err


def test_automatic_smoothing_is_reported(tmp_path):
    rep = run_json(["--input", str(CGS), "--smoothing", "auto", "--out", str(tmp_path)])
    choice = rep["smoothing_choice"]
    assert choice["chosen_s1"] in choice["candidates_s1"]
    assert rep["variforc"]["sc1"] == choice["chosen_s1"] and rep["smoothing_method"] == "variforc"
    assert "chosen automatically" in rep["figure_title"]


def test_batch_of_a_directory_writes_a_summary(tmp_path, capsys):
    import csv
    import shutil

    folder = tmp_path / "in"
    (folder / "sub").mkdir(parents=True)
    shutil.copy(DATA / "forc_micromag_0015_cgs.frc", folder / "forc_micromag_0015_cgs.frc")
    shutil.copy(DATA / "forc_lakeshore_8600.csv", folder / "sub" / "forc_lakeshore_8600.csv")
    shutil.copy(DATA / "make_forc_data.py", folder / "make_forc_data.py")
    out = tmp_path / "out"
    # the folder is searched recursively; a file no reader recognises is listed as skipped,
    # not failed, and the batch succeeds
    assert main(["identify", "--input", str(folder), "--out", str(out), "--quiet"]) == 0
    rows = list(csv.DictReader(open(out / "summary.csv", encoding="utf-8")))
    status = {Path(r["file"]).name: r["status"] for r in rows}
    assert status == {
        "forc_micromag_0015_cgs.frc": "ok",
        "forc_lakeshore_8600.csv": "ok",
        "make_forc_data.py": "skipped",
    }
    summary = json.loads((out / "summary.json").read_text())
    assert summary["n_skipped"] == 1 and summary["n_failed"] == 0
    rows = [r for r in rows if r["status"] == "ok"]
    for row in rows:
        stem = Path(row["file"]).stem.replace(".", "_")
        assert (out / stem / "identify.json").exists()
        assert (out / stem / f"identify_{stem}.png").exists()
    # a file named explicitly that is not a FORC file fails, the batch goes on, exit status 2
    files = [str(folder / "forc_micromag_0015_cgs.frc"), str(folder / "make_forc_data.py")]
    assert main(["identify", "--input", *files, "--out", str(tmp_path / "o3"), "--quiet"]) == 2
    assert "1 of 2 files failed" in capsys.readouterr().err
    # the same files on two workers: the same numbers
    files = [
        str(folder / "forc_micromag_0015_cgs.frc"),
        str(folder / "sub/forc_lakeshore_8600.csv"),
    ]
    rep = run_json(["--input", *files, "--workers", "2", "--out", str(tmp_path / "out2")])
    by_name = {Path(r["file"]).name: float(r["peak_bc_mT"]) for r in rows[:2]}
    assert {Path(r["file"]).name: r["peak_bc_mT"] for r in rep["files"]} == by_name


def test_batch_summary_carries_the_data_warnings(tmp_path):
    """An aborted measurement in a batch: its summary row names the cause (the reversal-field
    range the masses cover), as the file's own identify.json does."""
    import csv
    import shutil

    folder = tmp_path / "in"
    folder.mkdir()
    shutil.copy(DATA / "forc_micromag_0016_si_aborted.frc", folder / "aborted.frc")
    out = tmp_path / "out"
    assert main(["identify", "--input", str(folder), "--out", str(out), "--quiet"]) == 0
    (row,) = list(csv.DictReader(open(out / "summary.csv", encoding="utf-8")))
    single = json.loads((out / "aborted" / "identify.json").read_text())
    assert single["warnings"] and all(w in row["warnings"] for w in single["warnings"])
    assert "aborted measurement" in row["warnings"]


def test_drift_correction_without_calibration_points_is_a_note(tmp_path, capsys):
    """--drift-correction on a file with no calibration points: one note on stderr, the
    identification runs (exit 0), nothing corrected."""
    out = tmp_path / "out"
    argv = ["identify", "--input", str(DATA / "forc_erf_play_mayergoyz.csv"), "--out", str(out)]
    assert main([*argv, "--drift-correction", "additive", "--quiet"]) == 0
    err = capsys.readouterr().err
    notes = [line for line in err.splitlines() if "note:" in line]
    assert len(notes) == 1 and "no calibration points" in notes[0]
    with_note = json.loads((out / "identify.json").read_text())
    assert main([*argv[:-1], str(tmp_path / "plain"), "--quiet"]) == 0
    plain = json.loads((tmp_path / "plain" / "identify.json").read_text())
    assert with_note["peak_bc_mT"] == plain["peak_bc_mT"]
