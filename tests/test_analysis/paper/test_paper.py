"""``hyst paper --smoke`` produces every figure of the paper and a report whose claims parse."""

import json

from analysis.cli import main
from analysis.paper import FIGURES

EXPECTED = {
    "fig:elem_hys",
    "fig:elem_hys_ex",
    "fig:N=2_schema",
    "fig:N=4_traj",
    "fig:play",
    "fig:preis_dens",
    "fig:bif_0",
    "fig:bif",
    "fig:erf_10000",
    "fig:dim",
    "fig:sap",
    "fig:mboa",
    "fig:mag",
    "fig:mag_his",
}


def test_every_computational_figure_of_the_paper_has_a_builder():
    labels = {spec.label for spec in FIGURES}
    assert EXPECTED <= labels


def test_paper_smoke_writes_every_figure_and_a_parsable_report(tmp_path):
    out = tmp_path / "paper"
    assert main(["paper", "--smoke", "--quiet", "--out", str(out)]) == 0
    for label in EXPECTED:
        stem = label.replace(":", "_").replace("=", "")
        for ext in ("png", "pdf", "npz"):
            path = out / f"{stem}.{ext}"
            assert path.is_file() and path.stat().st_size > 0, path
    report = json.loads((out / "report.json").read_text())
    assert report["errors"] == []
    assert report["size"]["name"] == "smoke"
    assert len(report["claims"]) >= 20
    for claim in report["claims"]:
        assert set(claim) >= {"claim", "paper", "measured", "run", "verdict"}
        assert claim["verdict"] in ("agree", "disagree", "inconclusive at this run size")
        assert set(claim) >= {"evidence", "explanation", "figure"}
        if claim["verdict"] != "agree":
            assert claim["evidence"], claim["claim"]
        assert claim["claim"] and claim["paper"] and claim["measured"] and claim["run"]
    text = (out / "report.md").read_text()
    assert "| figure | claim | paper | measured | run | verdict |" in text
    counts = {v: sum(c["verdict"] == v for c in report["claims"]) for v in ("agree", "disagree")}
    inconclusive = len(report["claims"]) - counts["agree"] - counts["disagree"]
    assert (
        f"{counts['agree']} of {len(report['claims'])} claims agree, {counts['disagree']} "
        f"disagree, {inconclusive} inconclusive at this run size"
    ) in text
    assert "## Discussion" in text
