"""``hyst continuation`` of a continuous Preisach orbit downward: the orbit grows onto the
frozen extrema its transient left (staircase changes), reported as grazings, no crash."""

from __future__ import annotations

import json

import pytest

from analysis.cli import main


@pytest.fixture(autouse=True)
def _in_tmp(tmp_path, monkeypatch):
    """Commands write to --out (default hyst-out in the working directory): keep it in tmp."""
    monkeypatch.chdir(tmp_path)


def test_downward_gaussian_continuation_exits_0_with_grazings(capsys):
    # the command of the bug report (it failed with "the orbit's staircase changed")
    argv = [
        "continuation", "--model", "preisach-gauss", "--width-spread", "0.1",
        "--start", "1", "--stop", "0.8", "--transient", "200", "--json",
    ]  # fmt: skip
    assert main(argv) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["stop_reason"] == "reached stop"
    assert d["branch"][-1]["parameter"] == 0.8
    assert d["events"] and all(e["kind"] == "grazing" for e in d["events"])
    # located to the default locate_tolerance, in continuation order
    assert all(e["bracket"][1] - e["bracket"][0] <= 1e-8 for e in d["events"])
    lams = [e["parameter"] for e in d["events"]]
    assert lams == sorted(lams, reverse=True) and 0.8 < lams[-1] < lams[0] < 1.0
