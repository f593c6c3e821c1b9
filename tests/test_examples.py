"""Every script in examples/ runs from a clean process and writes its figure; its default run
is small or documented as the full size.

Each script is started with ``--smoke --out DIR`` (scripts without a ``--smoke`` option, e.g.
``drive_operators.py``, with ``--out DIR`` only) in a subprocess of this interpreter; the test
asserts exit code 0 and at least one non-empty PNG in DIR. The scripts run two at a time in one
module-level fixture (about 30 s in total on two cores), then each gets its own test result.

Every script's ``--help`` (all in one subprocess, a few seconds) must either offer ``--full``
with a duration in its help (the default is then the small run) or say "the defaults are the
full size" with a duration: an example defaulting to an hours-long study cannot slip in.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((ROOT / "examples").glob("*.py"))
TIMEOUT = 300  # s per script; a smoke run takes a few seconds
#: an example's help says its defaults are the full size, or has a ``--full`` option ...
FULL_SIZE = re.compile(r"defaults? (?:is|are) the full size", re.IGNORECASE)
FULL_OPTION = re.compile(r"^\s+--full\b(.*?)(?=^\s+-|\Z)", re.MULTILINE | re.DOTALL)
#: ... and either way says how long the full run takes ("about 20 s", "10 min", "hours")
DURATION = re.compile(r"\d\s*(?:s|min|minutes?|h|hours?)\b|\b(?:minutes|hours|days)\b")


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


#: prints every example's ``--help`` (run as ``__main__``, as a user would) as one JSON object,
#: in one process: the scripts' imports are paid once
_HELP_DRIVER = """
import contextlib, io, json, runpy, sys
out = {}
for path in sys.argv[1:]:
    sys.argv = [path, "--help"]
    buf = io.StringIO()
    code = None
    with contextlib.redirect_stdout(buf):
        try:
            runpy.run_path(path, run_name="__main__")
        except SystemExit as stop:
            code = stop.code
    out[path] = (code, buf.getvalue())
print(json.dumps(out))
"""


@pytest.fixture(scope="module")
def helps() -> dict[str, tuple[int | None, str]]:
    env = dict(os.environ, MPLBACKEND="Agg", COLUMNS="100")
    proc = subprocess.run(
        [sys.executable, "-c", _HELP_DRIVER, *map(str, EXAMPLES)],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=TIMEOUT, check=False,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-4000:]
    return {Path(k).name: tuple(v) for k, v in json.loads(proc.stdout).items()}


@pytest.mark.parametrize("script", [s.name for s in EXAMPLES])
def test_example_default_is_small_or_documented_full_size(script: str, helps: dict) -> None:
    """A user runs an example as it comes: its default must finish in about two minutes, with
    the paper-size run behind ``--full`` (whose help says how long it takes), or its help must
    say the defaults are already the full size and how long that takes. A new example that
    defaults to an hours-long study fails here instead of silently."""
    code, text = helps[script]
    assert code in (0, None), f"{script} --help exited with {code}"
    option = FULL_OPTION.search(text)
    if option is not None:
        text = " ".join(option.group(1).split())
        assert DURATION.search(text), f"{script}: --full's help gives no duration: {text!r}"
        return
    text = " ".join(text.split())
    assert FULL_SIZE.search(text), (
        f"{script}: no --full option and the help does not say the defaults are the full size"
    )
    assert DURATION.search(text), f"{script}: the help does not say how long the run takes"


def test_example_sources_use_public_api_only() -> None:
    """Examples are what users copy: they must not reach into the paper-reproduction package."""
    for script in EXAMPLES:
        text = script.read_text()
        assert "analysis.paper" not in text, f"{script.name} imports analysis.paper"
