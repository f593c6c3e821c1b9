"""Progress bars stay visible on a terminal that reports zero columns."""

from __future__ import annotations

import io
import shutil
import subprocess
import sys

import pytest

import hysteresis._progress as progress


def test_zero_column_terminal_gets_the_fallback_width(monkeypatch):
    monkeypatch.setattr(progress, "_terminal_columns", lambda: 0)
    out = io.StringIO()
    bar = progress.progress_bar(range(3), desc="work", file=out, mininterval=0)
    assert bar.ncols == progress.FALLBACK_COLUMNS and not bar.dynamic_ncols
    for _ in bar:
        pass
    bar.close()
    assert "work" in out.getvalue() and "3/3" in out.getvalue()


def test_sized_terminal_resizes_dynamically(monkeypatch):
    monkeypatch.setattr(progress, "_terminal_columns", lambda: 120)
    bar = progress.progress_bar(range(2), file=io.StringIO())
    assert bar.dynamic_ncols
    bar.close()


@pytest.mark.skipif(shutil.which("script") is None, reason="needs util-linux script (a pty)")
def test_bar_is_drawn_in_a_pseudo_terminal_without_a_size(tmp_path):
    # `script` runs the command in a pty that reports 0 columns: plain tqdm draws nothing there
    code = (
        "from hysteresis._progress import progress_bar\n"
        "for _ in progress_bar(range(3), desc='work', mininterval=0): pass\n"
    )
    log = tmp_path / "log.txt"
    cmd = f'{sys.executable} -c "{code}"'
    subprocess.run(
        ["script", "-qfc", cmd, str(log)], check=True, stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=60,
    )  # fmt: skip
    assert "3/3" in log.read_text(errors="replace")
