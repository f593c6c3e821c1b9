"""The periodic-orbit evidence of the report's Discussion: its formatting, its place in the
report, and (slow) the numbers themselves against the closed form and Newton."""

from __future__ import annotations

import json

import pytest

from analysis.paper.context import SIZES, PaperContext
from analysis.paper.orbit_evidence import orbit_evidence, orbit_lines
from analysis.paper.runner import write_report


def _range(extreme, kind, at, events):
    return {
        "extreme_stable_parameter": extreme,
        "ended_by": kind,
        "event_parameter": at,
        "event_max_abs_multiplier": 1.001 if at is not None else None,
        "stop_reason": "reached stop",
        "events": events,
    }


EVIDENCE = {
    "window_3_8": {
        "coupling": 3.85,
        "orbit": {"period": 5, "multipliers_abs": [0.69, 0.03, 0.0], "stable": True},
        "up": _range(3.8841, "fold", 3.88462071, [("fold", 3.88462071)]),
        "down": _range(3.7575, None, None, [("grazing", 3.76304445)]),
    },
    "window_1_7": [{"coupling": 1.7, "orbit": None, "why": "none"}],
    "cascade_onset": {
        "closed_form": 9.0,
        "continuation": 9.000000003,
        "bracket": [9.0, 9.000000006],
        "difference": 3e-9,
    },
}


def test_orbit_lines_name_the_orbits_events_and_the_onset():
    text = "\n".join(orbit_lines(EVIDENCE))
    assert text.startswith("### Periodic orbits")
    assert "period 5" in text and "fold at C = 3.88462071" in text
    assert "C = 1.7: no periodic orbit" in text
    assert "C = 9.0000000030" in text and "difference 3.0e-09" in text


def test_write_report_appends_the_orbit_evidence_to_the_discussion(tmp_path):
    ctx = PaperContext(tmp_path, SIZES["smoke"])
    report = {"size": ctx.describe(), "claims": [], "figures": [], "errors": []}
    report["orbits"] = EVIDENCE
    write_report(ctx, report)
    text = (tmp_path / "report.md").read_text()
    discussion = text.split("## Discussion", 1)[1].split("\n## ", 1)[0]
    assert "### Periodic orbits behind the disputed windows" in discussion
    assert json.loads((tmp_path / "report.json").read_text())["orbits"]["cascade_onset"]


@pytest.mark.slow
def test_orbit_evidence_numbers():
    ev = orbit_evidence()
    # the onset is a grazing of a linear orbit: exact up to the bisection width 1e-8
    assert abs(ev["cascade_onset"]["difference"]) < 1e-8
    w = ev["window_3_8"]
    assert w["orbit"]["period"] == 5 and w["orbit"]["stable"]
    # the stable period-5 orbit is lost at a fold (a multiplier through +1) near C = 3.8846
    assert w["up"]["ended_by"] == "fold"
    assert abs(w["up"]["event_max_abs_multiplier"] - 1.0) < 1e-2
    assert 3.88 < w["up"]["event_parameter"] < 3.89
    # continued downward, the period-3 orbit of C = 1.8 is stable down to its fold, where the
    # branch turns back past its start: the stable stretch reaches the fold from above, within
    # one step (0.005) of the located fold, not the start (which a turned branch had reported)
    down = next(r for r in ev["window_1_7"] if r["coupling"] == 1.8)["down"]
    assert down["ended_by"] == "fold"
    assert 0.0 <= down["extreme_stable_parameter"] - down["event_parameter"] <= 0.005
