"""Bad-input corpus of the ``hyst`` command line (issue 12).

Every case gives one command an invalid value for one option (NaN, inf, text, out of range,
wrong kind, inconsistent with another option, missing). Each must end at once with exit status
2 and exactly one line on stderr that names the option — no traceback, no output files, no
work done. The table covers every command and every kind of option.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import pytest
from support_paths import DATA

from analysis.cli import main

#: (argv, text the one stderr line must contain)
CASES: list[tuple[list[str], str]] = [
    # -- hyst lyapunov: model options ------------------------------------------------------
    (["lyapunov", "--coupling", "nan"], "--coupling"),
    (["lyapunov", "--coupling", "inf"], "--coupling"),
    (["lyapunov", "--coupling", "four"], "--coupling"),
    (["lyapunov", "--coupling", "1+2j"], "--coupling"),
    (["lyapunov"], "--coupling"),
    (["lyapunov", "--coupling", "4", "--model", "bogus"], "--model"),
    (["lyapunov", "--coupling", "4", "--spins", "0"], "--spins"),
    (["lyapunov", "--coupling", "4", "--spins", "101"], "--spins"),
    (["lyapunov", "--coupling", "4", "--spins", "1.5"], "--spins"),
    (["lyapunov", "--coupling", "4", "--spins", "1000000000000"], "--spins"),
    (["lyapunov", "--coupling", "4", "--seed", "-1"], "--seed"),
    (["lyapunov", "--coupling", "4", "--width", "-2"], "--width"),
    (["lyapunov", "--coupling", "4", "--width", "5"], "--width"),
    (["lyapunov", "--coupling", "4", "--spread", "0"], "--spread"),
    (["lyapunov", "--coupling", "4", "--spin-coupling", "0"], "--spin-coupling"),
    (["lyapunov", "--coupling", "4", "--width-spread", "-0.1"], "--width-spread"),
    (
        ["lyapunov", "--coupling", "4", "--model", "preisach-gauss", "--width-spread", "0"],
        "--width-spread",
    ),
    (["lyapunov", "--coupling", "4", "--fields", "1", "2", "3"], "--fields"),
    (["lyapunov", "--coupling", "4", "--model", "play", "--fields", "1", "-1"], "--fields"),
    (
        ["lyapunov", "--coupling", "4", "--model", "relay", "--alpha", "-1", "--beta", "1"],
        "--alpha",
    ),
    (["lyapunov", "--coupling", "4", "--model", "pi", "--plays", "0"], "--plays"),
    (["lyapunov", "--coupling", "4", "--alpha", "1"], "--alpha"),
    # oscillator options
    (["lyapunov", "--coupling", "4", "--damping-ratio", "-1"], "--damping-ratio"),
    (
        ["lyapunov", "--coupling", "4", "--model", "erf-play", "--damping-ratio", "1.5"],
        "--damping-ratio",
    ),
    (
        ["lyapunov", "--coupling", "4", "--damping-ratio", "0", "--frequency", "1"],
        "--damping-ratio",
    ),
    (["lyapunov", "--coupling", "4", "--frequency", "0"], "--frequency"),
    (["lyapunov", "--coupling", "4", "--frequency", "1e-300"], "--frequency"),
    # initial condition
    (["lyapunov", "--coupling", "4", "--q0", "nan"], "--q0"),
    (["lyapunov", "--coupling", "4", "--v0", "-inf"], "--v0"),
    (["lyapunov", "--coupling", "4", "--model", "play", "--w0", "5"], "--w0"),
    (["lyapunov", "--coupling", "4", "--w0", "0"], "--w0"),
    # run options
    (["lyapunov", "--coupling", "4", "--t-end", "-5"], "--t-end"),
    (["lyapunov", "--coupling", "4", "--t-end", "10", "--transient", "100"], "--transient"),
    (["lyapunov", "--coupling", "4", "--transient", "-1"], "--transient"),
    (["lyapunov", "--coupling", "4", "--t-end", "1e300"], "--t-end"),
    # -- hyst trajectory -------------------------------------------------------------------
    (["trajectory", "--coupling", "4", "--t-end", "1e12", "--sample-dt", "1e6"], "--t-end"),
    (["trajectory", "--coupling", "4", "--sample-dt", "0"], "--sample-dt"),
    (["trajectory", "--coupling", "4", "--sample-dt", "1e-9", "--t-end", "1e6"], "--sample-dt"),
    (["trajectory", "--coupling", "4", "--t-end", "0"], "--t-end"),
    (["trajectory", "--coupling", "4", "--model", "erf_pla"], "--model"),
    # -- hyst poincare ---------------------------------------------------------------------
    (["poincare", "--coupling", "4", "--periods", "0"], "--periods"),
    (["poincare", "--coupling", "4", "--periods", "1e3"], "--periods"),
    (["poincare", "--coupling", "4", "--periods", "10000000000"], "--periods"),
    (["poincare", "--coupling", "4", "--transient", "-1"], "--transient"),
    (["poincare", "--coupling", "4", "--transient-periods", "2.5"], "--transient"),
    (["poincare", "--coupling", "4", "--transient", "1000000000000"], "--transient"),
    # -- hyst bifurcation ------------------------------------------------------------------
    (["bifurcation"], "--start"),
    (["bifurcation", "--values", "1", "--start", "2", "--stop", "1"], "--values"),
    (["bifurcation", "--start", "2", "--stop", "1", "--steps", "0"], "--steps"),
    (["bifurcation", "--parameter", "frequency", "--values", "1", "2"], "--coupling"),
    (["bifurcation", "--coupling", "2", "--values", "1", "2"], "--coupling"),
    (
        ["bifurcation", "--parameter", "frequency", "--coupling", "2", "--values", "1", "0"],
        "--values",
    ),
    (["bifurcation", "--values", "1", "--lyapunov-t", "-1"], "--lyapunov-t"),
    (["bifurcation", "--values", "1", "--parameter", "mass"], "--parameter"),
    (["bifurcation", "--values", "nan"], "--values"),
    (["bifurcation", "--values", "1", "--lyapunov-t", "1e15"], "--lyapunov-t"),
    # -- hyst dimension --------------------------------------------------------------------
    (["dimension", "--coupling", "4", "--max-fill", "0"], "--max-fill"),
    (["dimension", "--coupling", "4", "--max-fill", "2"], "--max-fill"),
    (["dimension", "--coupling", "4", "--min-boxes", "0.5"], "--min-boxes"),
    (["dimension", "--coupling", "4", "--points", "1"], "--points"),
    (["dimension", "--coupling", "4", "--transient", "0", "--t-end", "5"], "--t-end"),
    # -- hyst ensemble ---------------------------------------------------------------------
    (["ensemble", "--spins", "101", "--coupling", "4", "--realizations", "2"], "--spins"),
    (["ensemble", "--spins", "20", "--coupling", "4", "--realizations", "0"], "--realizations"),
    (["ensemble", "--spins", "20", "--coupling", "4"], "--realizations"),
    (
        ["ensemble", "--spins", "20", "--coupling", "4", "--realizations", "1", "--t-end", "1e20"],
        "--t-end",
    ),
    (
        ["ensemble", "--spins", "20", "--coupling", "4", "--realizations", "1", "--workers", "0"],
        "--workers",
    ),
    (
        ["ensemble", "--spins", "20", "--coupling", "4", "--realizations", "1", "--model", "play"],
        "--model",
    ),
    (["ensemble", "--spins", "20", "--coupling", "4", "nan", "--realizations", "1"], "--coupling"),
    (
        [
            "ensemble",
            "--spins",
            "20",
            "--coupling",
            "4",
            "--realizations",
            "1",
            "--box-max-fill",
            "1.5",
        ],
        "--box-max-fill",
    ),  # fmt: skip
    (
        [
            "ensemble",
            "--spins",
            "20",
            "--coupling",
            "4",
            "--realizations",
            "1",
            "--fields",
            "1",
            "-1",
        ],
        "--fields",
    ),  # fmt: skip
    (
        [
            "ensemble",
            "--spins",
            "20",
            "--coupling",
            "4",
            "--realizations",
            "1",
            "--workers",
            "1",
            "--scheduler",
            "tcp://127.0.0.1:1",
        ],
        "--workers",
    ),  # fmt: skip
    # -- hyst paper ------------------------------------------------------------------------
    (["paper", "--only", "fig:nonexistent"], "--only"),
    (["paper", "--workers", "0"], "--workers"),
    (["paper", "--workers", "two"], "--workers"),
    (["paper", "--smoke", "--full"], "--full"),
    # -- hyst identify: model options, grid, smoothing, measured files -----------------------
    (["identify", "--model", "bogus"], "--model"),
    (["identify", "--model", "relay"], "--model"),
    (["identify", "--spins", "x"], "--spins"),
    (["identify", "--spins", "101"], "--spins"),
    (["identify", "--seed", "-1"], "--seed"),
    (["identify", "--width", "nan"], "--width"),
    (["identify", "--width", "5"], "--width"),
    (["identify", "--spread", "-1"], "--spread"),
    (["identify", "--spin-coupling", "0"], "--spin-coupling"),
    (["identify", "--model", "play", "--fields", "1", "-1"], "--fields"),
    (["identify", "--step", "0"], "--step"),
    (["identify", "--step", "-0.1"], "--step"),
    (["identify", "--step", "inf"], "--step"),
    (["identify", "--step", "1e-5"], "--step"),
    (["identify", "--model", "play", "--step", "1e-5"], "--step"),
    (["identify", "--saturation", "0"], "--saturation"),
    (["identify", "--saturation", "1e300", "--model", "erf-play"], "--step"),
    (["identify", "--model", "preisach-uniform", "--saturation", "nan"], "--saturation"),
    (["identify", "--smoothing", "0"], "--smoothing"),
    (["identify", "--smoothing", "nan"], "--smoothing"),
    (["identify", "--smoothing", "1", "2", "3"], "--smoothing"),
    (["identify", "--input", "no-such-file.frc"], "--input"),
    (["identify", "--input", "."], "--input"),
    (["identify", "--input", str(DATA / "make_forc_data.py")], "--input"),
    (["identify", "--input", str(DATA / "forc_micromag_irregular.frc")], "--input"),
    (
        ["identify", "--input", str(DATA / "forc_lakeshore_8600.csv"), "--format", "micromag"],
        "--input",
    ),  # fmt: skip
    (["identify", "--format", "xml"], "--format"),
    (["identify", "--format", "csv"], "--format"),
    (["identify", "--window", "hann"], "--window"),
    (["identify", "--drift-correction", "cubic"], "--drift-correction"),
    (["identify", "--drift-correction", "additive"], "--drift-correction"),
    (["identify", "--grid-step", "0"], "--grid-step"),
    (
        ["identify", "--input", str(DATA / "forc_erf_play_mayergoyz.csv"), "--grid-step", "0.1"],
        "--grid-step",
    ),  # fmt: skip
    (
        ["identify", "--input", str(DATA / "forc_erf_play_mayergoyz.csv"), "--step", "0.1"],
        "--step",
    ),  # fmt: skip
    (
        ["identify", "--input", str(DATA / "forc_erf_play_mayergoyz.csv"), "--saturation", "3"],
        "--saturation",
    ),  # fmt: skip
    (["identify", "--grid-step", "0.1"], "--grid-step"),
    (
        [
            "identify",
            "--input",
            str(DATA / "forc_micromag_0016_hybrid_si.frc"),
            "--grid-step",
            "1e-9",
        ],
        "--grid-step",
    ),
    (
        [
            "identify",
            "--input",
            str(DATA / "forc_micromag_0016_hybrid_si.frc"),
            "--grid-step",
            "1e9",
        ],
        "--grid-step",
    ),
    (["identify", "--reversible-ridge"], "--reversible-ridge"),
    (["identify", "--out", "x", "--json", "--quiet", "--bogus"], "--bogus"),
    # -- hyst basins -----------------------------------------------------------------------
    (["basins", "--coupling", "2"], "--grid"),
    (["basins", "--coupling", "2", "--grid", "1"], "--grid"),
    (["basins", "--coupling", "nan", "--grid", "3"], "--coupling"),
    (["basins", "--coupling", "2", "--grid", "3", "--q0-range", "1", "0"], "--q0-range"),
    (["basins", "--coupling", "2", "--grid", "3", "--q0-range", "0"], "--q0-range"),
    (
        ["basins", "--coupling", "2", "--grid", "3", "--model", "relay", "--w0-range", "-1", "1"],
        "--w0-range",
    ),
    (
        [
            "basins",
            "--coupling",
            "2",
            "--grid",
            "3",
            "--w0-range",
            "-1",
            "1",
            "--v0-range",
            "0",
            "1",
        ],
        "--w0-range",
    ),  # fmt: skip
    (
        ["basins", "--coupling", "2", "--grid", "3", "--periods", "10", "--max-period", "6"],
        "--max-period",
    ),  # fmt: skip
    (["basins", "--coupling", "2", "--grid", "3", "--max-periods", "5"], "--max-periods"),
    (
        ["basins", "--coupling", "2", "--grid", "3", "--workers", "2", "--scheduler", "tcp://x:1"],
        "--workers",
    ),
    # -- hyst ------------------------------------------------------------------------------
    (["bogus"], "invalid choice"),
]


def _ids() -> list[str]:
    return [f"{i:02d}-{' '.join(argv)[:60]}" for i, (argv, _) in enumerate(CASES)]


@pytest.mark.parametrize(("argv", "needle"), CASES, ids=_ids())
def test_bad_option_is_one_line_exit_2_before_any_work(argv, needle, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the default --out (hyst-out) would land here
    start = time.perf_counter()
    code = main(argv)
    elapsed = time.perf_counter() - start
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert code == 2, captured.err
    assert len(lines) == 1, captured.err
    assert needle in lines[0], lines[0]
    assert lines[0].startswith("hyst"), lines[0]
    assert "Traceback" not in captured.err
    assert captured.out == ""
    # validation happens before any work: nothing written, and fast
    assert not (tmp_path / "hyst-out").exists() and not (tmp_path / "x").exists()
    assert elapsed < 20.0


def test_corpus_size_and_coverage():
    commands = {argv[0] for argv, _ in CASES}
    assert len(CASES) >= 30
    assert commands >= {
        "lyapunov", "trajectory", "poincare", "bifurcation", "dimension", "ensemble", "paper",
        "identify", "basins",
    }  # fmt: skip


def test_out_that_is_a_file_is_refused(tmp_path, capsys):
    target = tmp_path / "afile"
    target.write_text("x")
    code = main(["lyapunov", "--coupling", "4", "--spins", "20", "--out", str(target)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--out" in err[0]
    assert target.read_text() == "x"


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["ensemble", "--spins", "101", "--coupling", "4", "--realizations", "2"], "--spins"),
        (["paper", "--only", "fig:nonexistent"], "--only"),
        (["paper", "--workers", "0"], "--workers"),
    ],
)
def test_real_process_one_line_exit_2(argv, needle, tmp_path):
    """The installed entry point, as a user runs it (issue 12's examples)."""
    start = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "analysis.cli", *argv],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=tmp_path,
    )
    elapsed = time.perf_counter() - start
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2, proc.stderr
    assert len(lines) == 1 and needle in lines[0], proc.stderr
    assert elapsed < 30.0
    assert not (tmp_path / "hyst-out").exists()


def _failing_task(x: int) -> dict:
    raise ValueError(f"spins must be even, got {x}\n(second line of the message)")


def test_error_inside_a_worker_process_is_one_line(monkeypatch, tmp_path, capsys):
    """An exception raised in a worker process of an ensemble reaches the user as one line."""
    import analysis.cli.ensemble
    from analysis.experiments.execution import run_tasks

    def fake_run_ensemble(*args, **kwargs):
        return run_tasks(
            "corpus-fail", [{"x": 101}, {"x": 103}], _failing_task, workers=2, progress=False
        )

    monkeypatch.setattr(analysis.cli.ensemble, "run_ensemble", fake_run_ensemble)
    code = main(
        ["ensemble", "--spins", "20", "--coupling", "4", "--realizations", "1",
         "--out", str(tmp_path), "--quiet"]
    )  # fmt: skip
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and "spins must be even" in err[0] and "Traceback" not in err[0]


def test_unexpected_library_error_is_one_line(monkeypatch, capsys):
    import analysis.cli.lyapunov

    def boom(*args, **kwargs):
        raise RuntimeError("tangent integrator returned unsorted exponents\n[1, 2]")

    monkeypatch.setattr(analysis.cli.lyapunov, "lyapunov_spectrum", boom)
    code = main(["lyapunov", "--coupling", "4", "--spins", "20", "--quiet", "--out", "/tmp"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1
    assert err[0].startswith("hyst lyapunov: error: RuntimeError: tangent integrator")


# -- results stores: damaged, foreign, or written by another code version ---------------------

_ENSEMBLE_ARGV = ["ensemble", "--spins", "4", "--coupling", "4", "--realizations", "1",
                  "--t-end", "60", "--transient", "2", "--workers", "1", "--quiet"]  # fmt: skip


def _one_line_error(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert "Traceback" not in err[0]
    return err[0]


@pytest.mark.parametrize("command", ["ensemble", "paper"])
@pytest.mark.parametrize(
    "content", [b"not a database\n" * 10, b"SQLite format 3\x00" + b"\xff" * 200]
)
def test_damaged_or_foreign_store_is_one_line_and_left_untouched(
    command, content, tmp_path, capsys
):
    store = tmp_path / "results.sqlite"
    store.write_bytes(content)
    argv = _ENSEMBLE_ARGV if command == "ensemble" else ["paper", "--smoke", "--quiet"]
    code = main([*argv, "--store", str(store), "--out", str(tmp_path / "o")])
    line = _one_line_error(capsys)
    assert code == 2
    assert line.startswith(f"hyst {command}: error: argument --store: ")
    assert str(store) in line
    assert store.read_bytes() == content  # nothing overwritten
    assert not (tmp_path / "o").exists()  # refused before any work


def _store_of_another_version(path: Path, experiment: str) -> None:
    import sqlite3

    from analysis.experiments.store import ResultStore

    with ResultStore(path) as store:
        store.put(experiment, {"x": 1}, {"y": 2.0})
    with sqlite3.connect(path) as conn:
        conn.execute("UPDATE tasks SET code_version = 'hysteresis-toolkit 0.0.1 (git 0000000)'")


def _rows(path: Path) -> list[tuple]:
    import sqlite3

    with sqlite3.connect(path) as conn:
        return conn.execute("SELECT * FROM tasks ORDER BY key").fetchall()


def test_store_of_another_code_version_needs_allow_version_mismatch(tmp_path, capsys):
    from analysis.experiments.ensemble import EXPERIMENT

    store = tmp_path / "results.sqlite"
    _store_of_another_version(store, EXPERIMENT)
    before = _rows(store)
    argv = [*_ENSEMBLE_ARGV, "--store", str(store), "--out", str(tmp_path / "o"), "--json"]
    assert main(argv) == 2
    line = _one_line_error(capsys)
    assert "argument --store:" in line and "0.0.1" in line
    assert "--allow-version-mismatch" in line  # the advice names the option, not the kwarg
    assert _rows(store) == before  # the stored results are left as they were
    assert main([*argv, "--allow-version-mismatch"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert [p["realizations"] for p in record["points"]] == [1]


def _paper_task(x: int) -> dict:
    return {"y": x}


def test_paper_store_version_error_stops_the_run_as_one_line(tmp_path, monkeypatch, capsys):
    """A store error inside a figure is the whole run's (every figure shares the store): it
    ends ``hyst paper`` with one line, and --allow-version-mismatch reaches run_tasks."""
    import analysis.paper.runner as runner
    from analysis.paper.context import FigureSpec

    store = tmp_path / "results.sqlite"
    _store_of_another_version(store, "corpus-paper")
    seen: list[list[dict]] = []

    def build(ctx):
        seen.append(ctx.run("corpus-paper", [{"x": 3}], _paper_task))
        return []

    monkeypatch.setattr(runner, "_figures", lambda: [FigureSpec("fig:x", "x", build)])
    monkeypatch.setattr(runner, "check_only", lambda only: None)
    argv = ["paper", "--smoke", "--quiet", "--store", str(store), "--out", str(tmp_path / "o")]
    assert main(argv) == 2
    line = _one_line_error(capsys)
    assert "argument --store:" in line and "--allow-version-mismatch" in line
    assert seen == []
    assert main([*argv, "--allow-version-mismatch"]) == 0
    assert seen == [[{"y": 3}]]
