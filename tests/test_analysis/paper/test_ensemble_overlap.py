"""The disorder ensemble computed in a background process (``start_ensemble_data``, the overlap of
``hyst paper``) is the one computed in sequence; its errors reach the figure that waits."""

import pytest

import analysis.paper.ensemble_tasks as ensemble_tasks
from analysis._json import to_json
from analysis.paper.context import SIZES, PaperContext
from analysis.paper.ensemble_tasks import ensemble_data, start_ensemble_data


def _as_text(data: dict) -> str:
    points = {f"{n} {c}": p.to_json() for (n, c), p in data["points"].items()}
    iid = data["iid"]
    rest = {k: v for k, v in data.items() if k not in ("points", "iid")}
    return to_json({"points": points, "iid": repr(iid), **rest})


def test_background_ensemble_equals_the_sequential_one(tmp_path):
    background = PaperContext(tmp_path / "a", SIZES["smoke"], workers=2)
    start_ensemble_data(background)
    start_ensemble_data(background)  # started once
    sequential = PaperContext(tmp_path / "b", SIZES["smoke"], workers=1)
    assert _as_text(ensemble_data(background)) == _as_text(ensemble_data(sequential))
    assert ensemble_data(background) is ensemble_data(background)  # cached


def test_background_error_is_raised_where_the_data_is_needed(tmp_path, monkeypatch):
    def fail(ctx):
        raise RuntimeError("ensemble failed")

    monkeypatch.setattr(ensemble_tasks, "_ensemble_data", fail)
    ctx = PaperContext(tmp_path, SIZES["smoke"], workers=2)
    start_ensemble_data(ctx)
    with pytest.raises(RuntimeError, match="ensemble failed"):
        ensemble_data(ctx)
