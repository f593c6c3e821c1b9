"""Every script in examples/ runs from a clean process and writes its figure.

Each script is started with ``--smoke --out DIR`` (scripts without a ``--smoke`` option, e.g.
``drive_operators.py``, with ``--out DIR`` only) in a subprocess of this interpreter; the test
asserts exit code 0 and at least one non-empty PNG in DIR. The scripts run two at a time in one
module-level fixture (about 30 s in total on two cores), then each gets its own test result.
"""

from __future__ import annotations

import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((ROOT / "examples").glob("*.py"))
TIMEOUT = 300  # s per script; a smoke run takes a few seconds


def _run(script: Path, out: Path) -> subprocess.CompletedProcess:
    args = [sys.executable, str(script), "--out", str(out)]
    if "--smoke" in script.read_text():
        args.insert(2, "--smoke")
    env = dict(os.environ, MPLBACKEND="Agg")
    return subprocess.run(
        args, cwd=ROOT, env=env, capture_output=True, text=True, timeout=TIMEOUT, check=False
    )


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple]:
    base = tmp_path_factory.mktemp("examples")
    outs = {s.name: base / s.stem for s in EXAMPLES}
    with ThreadPoolExecutor(max_workers=2) as pool:
        futures = {s.name: pool.submit(_run, s, outs[s.name]) for s in EXAMPLES}
        return {name: (f.result(), outs[name]) for name, f in futures.items()}


def test_examples_exist() -> None:
    names = {s.name for s in EXAMPLES}
    expected = {
        "fig_elem_hys.py",
        "fig_elem_hys_ex.py",
        "fig_n2_section.py",
        "fig_n4_trajectory.py",
        "fig_play.py",
        "fig_preis_dens.py",
        "fig_bif_0.py",
        "fig_bif.py",
        "fig_attractors.py",
        "fig_dky_initial_conditions.py",
        "fig_ensembles.py",
        "custom_operator.py",
    }
    assert expected <= names, f"missing: {sorted(expected - names)}"


@pytest.mark.parametrize("script", [s.name for s in EXAMPLES])
def test_example_runs_and_writes_png(script: str, runs: dict[str, tuple]) -> None:
    proc, out = runs[script]
    assert proc.returncode == 0, f"{script} failed:\n{proc.stdout[-2000:]}\n{proc.stderr[-4000:]}"
    pngs = [p for p in out.glob("*.png") if p.stat().st_size > 0]
    assert pngs, f"{script} wrote no PNG into {out}; files: {sorted(p.name for p in out.glob('*'))}"


def test_example_sources_use_public_api_only() -> None:
    """Examples are what users copy: they must not reach into the paper-reproduction package."""
    for script in EXAMPLES:
        text = script.read_text()
        assert "analysis.paper" not in text, f"{script.name} imports analysis.paper"
