"""The report explains itself: three verdicts, evidence and readings, a Discussion section, and
the decision functions that say when a claim cannot be decided at a run's size."""

import json
import math
from dataclasses import asdict

import numpy as np
import pytest

from analysis.dynamics.period_adding import period_adding
from analysis.paper import decisions as dec
from analysis.paper.context import SIZES, Claim, PaperContext, reading
from analysis.paper.figures_bifurcations import _cascade_claim
from analysis.paper.runner import write_report
from analysis.paper.verdicts import (
    cascade_verdict,
    is_period_adding,
    sap_falls,
    std_ratio_verdict,
)

INC = "inconclusive at this run size"


def _claim(verdict: str, tag: str, **kw) -> Claim:
    return Claim(
        claim=f"claim {tag}",
        paper=f"paper says {tag}",
        measured=f"measured {tag}",
        run=f"run {tag}",
        verdict=verdict,
        figure=f"fig:{tag}",
        **kw,
    )


# --------------------------------------------------------------------------------------------
# Claim
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("bad", ["agrees", "Agree", "inconclusive", "", "unknown"])
def test_claim_rejects_an_unknown_verdict(bad):
    with pytest.raises(ValueError, match="verdict"):
        _claim(bad, "x")


def test_claim_accepts_the_three_verdicts_and_defaults_evidence_to_empty():
    for v in ("agree", "disagree", INC):
        c = _claim(v, "x")
        assert c.verdict == v and c.evidence == "" and c.explanation == ""


def test_claim_evidence_must_be_text():
    with pytest.raises(TypeError, match="evidence"):
        _claim("disagree", "x", evidence={"n": 3})


def test_reading_picks_the_text_of_the_verdict():
    texts = {"disagree": "why it disagrees", "inconclusive": "why undecided"}
    assert reading("agree", **texts) == ""
    assert reading("disagree", **texts) == "why it disagrees"
    assert reading(INC, **texts) == "why undecided"
    with pytest.raises(ValueError):
        reading("maybe", **texts)


# --------------------------------------------------------------------------------------------
# write_report
# --------------------------------------------------------------------------------------------


def _write(tmp_path, claims):
    ctx = PaperContext(tmp_path, SIZES["smoke"])
    report = {
        "size": ctx.describe(),
        "claims": [asdict(c) for c in claims],
        "figures": [],
        "errors": [],
    }
    write_report(ctx, report)
    return (tmp_path / "report.md").read_text(), json.loads((tmp_path / "report.json").read_text())


def test_write_report_discusses_disagree_and_inconclusive_claims_only(tmp_path):
    claims = [
        _claim("agree", "ok", evidence="EVIDENCE-OK", explanation="READING-OK"),
        _claim("disagree", "bad", evidence="EVIDENCE-BAD: 12 realizations", explanation="R-BAD"),
        _claim(INC, "open", evidence="EVIDENCE-OPEN: N=60 < 20000", explanation="R-OPEN"),
        _claim("agree", "ok2"),
    ]
    text, payload = _write(tmp_path, claims)
    assert "2 of 4 claims agree, 1 disagree, 1 inconclusive at this run size" in text
    head, discussion = text.split("## Discussion", 1)
    discussion = discussion.split("\n## ", 1)[0]
    # one subsection per non-agreeing claim, with claim, paper, measurement, evidence, reading
    assert discussion.count("\n### ") == 2
    for tag, ev, rd, v in (
        ("bad", "EVIDENCE-BAD: 12 realizations", "R-BAD", "disagree"),
        ("open", "EVIDENCE-OPEN: N=60 < 20000", "R-OPEN", INC),
    ):
        section = discussion.split(f"claim {tag} — {v}", 1)[1].split("\n### ", 1)[0]
        assert f"paper says {tag}" in section
        assert f"measured {tag}" in section
        assert ev in section
        assert rd in section
    # nothing of the agreeing claims in the discussion
    assert "EVIDENCE-OK" not in discussion and "READING-OK" not in discussion
    assert "claim ok" not in discussion and "claim ok2" not in discussion
    # report.json: the same fields, the old keys kept, and the counts
    assert payload["claims"][1]["evidence"] == "EVIDENCE-BAD: 12 realizations"
    assert payload["claims"][2]["explanation"] == "R-OPEN"
    assert payload["claims"][2]["verdict"] == INC
    for c in payload["claims"]:
        assert set(c) >= {"claim", "paper", "measured", "run", "verdict", "figure"}
    assert set(payload) >= {"size", "claims", "figures", "errors"}
    assert payload["summary"]["agree"] == 2
    assert payload["summary"]["disagree"] == 1
    assert payload["summary"]["inconclusive"] == 1
    assert payload["summary"]["claims"] == 4


def test_write_report_with_every_claim_agreeing_has_an_empty_discussion(tmp_path):
    text, payload = _write(tmp_path, [_claim("agree", "a"), _claim("agree", "b")])
    assert "2 of 2 claims agree, 0 disagree, 0 inconclusive at this run size" in text
    discussion = text.split("## Discussion", 1)[1].split("\n## ", 1)[0]
    assert "### " not in discussion
    assert payload["summary"]["disagree"] == 0


def test_write_report_lists_disagreements_before_inconclusive_claims(tmp_path):
    claims = [_claim(INC, "first"), _claim("disagree", "second")]
    text, _ = _write(tmp_path, claims)
    discussion = text.split("## Discussion", 1)[1]
    assert discussion.index("claim second") < discussion.index("claim first")


# --------------------------------------------------------------------------------------------
# decision functions (synthetic numbers; expectations worked out by hand)
# --------------------------------------------------------------------------------------------


def test_mean_within_straddling_the_tolerance_is_inconclusive():
    # D̄_KY = 1.31 vs limit 1.42, criterion 0.1: deviation 0.11
    assert dec.mean_within(1.31, 0.010, 1.42, 0.1) == INC  # 0.11 ± 0.0196 straddles 0.1
    assert dec.mean_within(1.31, 0.002, 1.42, 0.1) == "disagree"  # 0.11 ± 0.004 > 0.1
    assert dec.mean_within(1.40, 0.005, 1.42, 0.1) == "agree"  # 0.02 ± 0.0098 < 0.1
    assert dec.mean_within(1.40, float("nan"), 1.42, 0.1) == INC  # one realization: no SEM


def test_below_decides_only_outside_the_interval():
    assert dec.below(0.8, 0.1, 1.0) == "agree"
    assert dec.below(1.2, 0.1, 1.0) == "disagree"
    assert dec.below(0.95, 0.1, 1.0) == INC
    assert dec.below(1.05, 0.1, 1.0) == INC


def test_fraction_claim_is_inconclusive_when_the_interval_is_wider_than_the_fraction():
    assert dec.fraction_matches(20, 100, 0.2) == "agree"  # [0.13, 0.29], width 0.16
    assert dec.fraction_matches(96, 500, 0.2) == "agree"  # the paper-scale result
    assert dec.fraction_matches(0, 100, 0.2) == "disagree"  # [0, 0.037] excludes 0.2
    assert dec.fraction_matches(5, 500, 0.2) == "disagree"
    assert dec.fraction_matches(1, 3, 0.2) == INC  # [0.06, 0.79] holds 0.2 and much else
    assert dec.fraction_matches(0, 3, 0.2) == INC  # [0, 0.56]: cannot tell 20 % from none
    assert dec.fraction_matches(0, 0, 0.2) == INC


def test_onset_measured_on_a_grid_coarser_than_the_tolerance_is_inconclusive():
    assert dec.onset_within(9.008, 9.0, 0.25, 0.023) == "agree"
    # 0.3 from the target, known to ±0.165: could be 0.135 or 0.465 away
    assert dec.onset_within(9.3, 9.0, 0.25, 0.33) == INC
    assert dec.onset_within(10.0, 9.0, 0.25, 0.02) == "disagree"
    # a coarse grid still decides an onset far from the target
    assert dec.onset_within(12.0, 9.0, 0.25, 0.33) == "disagree"
    assert dec.onset_within(float("nan"), 9.0, 0.25, 0.02) == "disagree"  # no transition


def test_cascade_verdict():
    assert cascade_verdict(9.008, 0.023, True, 80) == "agree"
    assert cascade_verdict(9.3, 0.33, True, 6) == INC
    # onset right but no period adding with plenty of values below it: disagree
    assert cascade_verdict(9.008, 0.023, False, 80) == "disagree"
    # too few values below the onset to hold three windows of two values
    assert cascade_verdict(9.008, 0.023, False, 4) == INC
    # the sweep never resolved the period-1 orbit above the onset: no onset to place
    assert cascade_verdict(float("nan"), 0.33, False, 8, first_period=0) == INC
    # the sweep stayed on the period-1 orbit throughout: no cascade at all
    assert cascade_verdict(float("nan"), 0.023, False, 0, first_period=1) == "disagree"


def test_is_period_adding():
    cs = 9.5 - 0.1 * np.arange(12)
    # three wide windows falling by 2, unresolved periods at the onset
    assert is_period_adding(period_adding(cs, [1, 1, 0, 0, 31, 31, 29, 29, 27, 27, 25, 25]))
    # steps of -1 are adding too (a cascade of all periods)
    assert is_period_adding(period_adding(cs, [1, 1, 24, 24, 23, 23, 22, 22, 21, 21, 1, 1]))
    # two wide windows only
    assert not is_period_adding(period_adding(cs, [1, 1, 0, 0, 31, 31, 29, 29, 1, 1, 1, 1]))
    # a step of -4: not small
    assert not is_period_adding(period_adding(cs, [1, 1, 0, 0, 31, 31, 27, 27, 25, 25, 1, 1]))
    # periods growing away from the onset
    assert not is_period_adding(period_adding(cs, [1, 1, 0, 0, 21, 21, 23, 23, 25, 25, 1, 1]))
    # short periods at the onset
    assert not is_period_adding(period_adding(cs, [1, 1, 9, 9, 7, 7, 5, 5, 3, 3, 1, 1]))
    # no onset
    assert not is_period_adding(period_adding(cs, [1] * 12))


#: the Claim of fig:bif_0 on hand-made zoom sweeps, as the report printed it before the
#: detector moved to analysis.dynamics.period_adding (the text must not change)
_CASCADE_TEXT = {
    "clean": (
        (
            "period-1 orbit (no switch) down to C=8.840; onset C≈8.763; periodic windows (>= 2 "
            "successive C) in sweep order [31, 29, 27, 25, 23] (steps [-2]); narrow windows "
            "between them []; C:period 8.69:>30, 8.53:>30, 8.38:31, 8.23:31, 8.07:29, 7.92:29, "
            "7.77:27, 7.61:27, 7.46:25, 7.31:25"
        ),
        (
            "zoom grid step ΔC = 0.153: the onset is known to ±0.077 against the tolerance 0.25; "
            "12 grid values below the onset (all if none found; three windows of >= 2 values "
            "need >= 6); 5 wide windows found; periods are resolved up to 30 forcing periods (60 "
            "section points per C)"
        ),
        "inconclusive at this run size",
    ),
    "narrow": (
        (
            "period-1 orbit (no switch) down to C=8.946; onset C≈8.858; periodic windows (>= 2 "
            "successive C) in sweep order [31, 29, 27] (steps [-2]); narrow windows between them "
            "[45, 3, 5, 25]; C:period 8.77:>30, 8.59:45, 8.42:31, 8.24:31, 8.06:3, 7.88:29, "
            "7.71:29, 7.53:27, 7.35:27, 7.18:5"
        ),
        (
            "zoom grid step ΔC = 0.177: the onset is known to ±0.088 against the tolerance 0.25; "
            "11 grid values below the onset (all if none found; three windows of >= 2 values "
            "need >= 6); 3 wide windows found; periods are resolved up to 30 forcing periods (60 "
            "section points per C)"
        ),
        "agree",
    ),
    "not_adding": (
        (
            "period-1 orbit (no switch) down to C=8.882; onset C≈8.777; periodic windows (>= 2 "
            "successive C) in sweep order [3, 7, 5, 9] (steps [-2, 4]); narrow windows between "
            "them [4]; C:period 8.67:3, 8.46:3, 8.25:7, 8.05:7, 7.84:5, 7.63:5, 7.42:9, 7.21:9, "
            "7.00:4"
        ),
        (
            "zoom grid step ΔC = 0.209: the onset is known to ±0.105 against the tolerance 0.25; "
            "9 grid values below the onset (all if none found; three windows of >= 2 values need "
            ">= 6); 4 wide windows found; periods are resolved up to 30 forcing periods (60 "
            "section points per C)"
        ),
        "disagree",
    ),
    "no_onset": (
        (
            "period-1 orbit (no switch) down to C=7.000; onset C≈nan; periodic windows (>= 2 "
            "successive C) in sweep order [] (steps []); narrow windows between them []; "
            "C:period "
        ),
        (
            "zoom grid step ΔC = 0.329: the onset is known to ±0.164 against the tolerance 0.25; "
            "0 grid values below the onset (all if none found; three windows of >= 2 values need "
            ">= 6); 0 wide windows found; periods are resolved up to 30 forcing periods (60 "
            "section points per C)"
        ),
        "disagree",
    ),
}

_CASCADE_SWEEPS = {
    "clean": (16, [1, 1, 1, 1, 0, 0, 31, 31, 29, 29, 27, 27, 25, 25, 23, 23]),
    "narrow": (14, [1, 1, 1, 0, 45, 31, 31, 3, 29, 29, 27, 27, 5, 25]),
    "not_adding": (12, [1, 1, 1, 3, 3, 7, 7, 5, 5, 9, 9, 4]),
    "no_onset": (8, [1] * 8),
}


@pytest.mark.parametrize("name", sorted(_CASCADE_SWEEPS))
def test_cascade_claim_text_is_unchanged(name):
    n, periods = _CASCADE_SWEEPS[name]
    zoom = {"couplings": np.linspace(9.3, 7.0, n).tolist(), "period": periods}
    claim = _cascade_claim(zoom, 60, "zoom run")
    assert (claim.measured, claim.evidence, claim.verdict) == _CASCADE_TEXT[name]


def test_ks_claim_within_its_sampling_scale_is_inconclusive():
    # the sampling scale 1.36·sqrt(60/900) = 0.351 for 30 points each straddles 0.15
    assert dec.ks_below(0.20, 30, 30, 0.15) == INC
    assert dec.ks_below(0.02, 1000, 1000, 0.15) == "agree"  # scale 0.061
    assert dec.ks_below(0.50, 1000, 1000, 0.15) == "disagree"


def test_power_law_exponent():
    assert dec.power_law_exponent(-0.996, 0.021, -1.0, 0.1) == "agree"
    assert dec.power_law_exponent(-0.6, 0.05, -1.0, 0.1) == "disagree"  # 0.4 > max(0.15, 0.1)
    # agrees only through a huge σ: the 3σ interval also holds 0 (no decay)
    assert dec.power_law_exponent(-0.9, 0.4, -1.0, 0.1) == INC
    assert dec.power_law_exponent(-1.0, float("nan"), -1.0, 0.1) == INC


def test_std_ratio_verdict_straddling_the_midpoint_is_inconclusive():
    # C claims (does not narrow): ratio 0.9, CLT 0.5, midpoint 0.75
    assert std_ratio_verdict(0.9, 0.5, 100, narrows=False) == INC  # ±0.177
    assert std_ratio_verdict(0.9, 0.5, 500, narrows=False) == "agree"  # ±0.079
    assert std_ratio_verdict(0.5, 0.5, 500, narrows=False) == "disagree"
    # iid claim (narrows): ratio 0.55 with CLT sqrt(3000/10000) = 0.548
    assert std_ratio_verdict(0.55, math.sqrt(0.3), 200, narrows=True) == "agree"
    assert std_ratio_verdict(0.75, 0.5, 20, narrows=True) == INC
    assert std_ratio_verdict(float("nan"), 0.5, 100, narrows=True) == INC


def test_sap_falls():
    assert sap_falls(np.array([0.5, 0.1, 0.01]), 100) == "agree"
    assert sap_falls(np.array([0.10, 0.09]), 100) == INC  # 10 % change, sampling scale ~40 %
    assert sap_falls(np.array([0.01, 0.5]), 100) == "disagree"
    assert sap_falls(np.array([0.1, 0.05]), 3) == INC  # three realizations
    assert sap_falls(np.array([0.3, 0.0]), 100) == "agree"  # all alike at the largest N


def test_large_n_claims_need_the_papers_largest_n():
    assert dec.needs_size("agree", 60, 20000) == INC
    assert dec.needs_size("disagree", 60, 20000) == INC
    assert dec.needs_size("disagree", 20000, 20000) == "disagree"


def test_window_claims():
    # "every C": a counterexample disagrees at any count; agreement needs >= 3 values
    assert dec.every_in_window(0, 0) == INC
    assert dec.every_in_window(2, 2) == INC
    assert dec.every_in_window(1, 2) == "disagree"
    assert dec.every_in_window(5, 5) == "agree"
    # "at least half": needs >= 3 values either way
    assert dec.majority_in_window(0, 1) == INC
    assert dec.majority_in_window(2, 3) == "agree"
    assert dec.majority_in_window(1, 3) == "disagree"


def test_combine():
    assert dec.combine("agree", "agree") == "agree"
    assert dec.combine("agree", INC) == INC
    assert dec.combine(INC, "disagree") == "disagree"
