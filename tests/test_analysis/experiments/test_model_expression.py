"""Weighted sums of model names (analysis.experiments.model_expression, read through the
registry's parse_model / build_operator / model_record).

Truths: the weights written in the text (read by hand here), Python's own ``float`` of each
literal, the parts built one by one and summed in numpy (the sum's outputs are the weighted sum
of the parts' outputs, accumulated in the written order), and the plain registry name.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from analysis.experiments.model_expression import (
    ModelExpression,
    ModelExpressionError,
    ModelTerm,
    parse_model_expression,
)
from analysis.experiments.models import (
    MODELS,
    build_operator,
    canonical_model,
    describe_model,
    model_record,
    parse_model,
)
from hysteresis import BranchSum, RelaySum

VALID = [
    # text, (name, weight) pairs, canonical text
    ("play", [("play", 1.0)], "play"),
    ("1*play", [("play", 1.0)], "play"),
    ("play*1.0", [("play", 1.0)], "play"),
    ("-play", [("play", -1.0)], "-play"),
    ("0.7*erf-play + 0.3*preisach", [("erf-play", 0.7), ("preisach", 0.3)],
     "0.7*erf-play + 0.3*preisach"),
    ("0.70*erf-play+.3*preisach", [("erf-play", 0.7), ("preisach", 0.3)],
     "0.7*erf-play + 0.3*preisach"),
    ("  0.7 * erf-play\t+ preisach * 0.3 ", [("erf-play", 0.7), ("preisach", 0.3)],
     "0.7*erf-play + 0.3*preisach"),
    ("erf-play-preisach", [("erf-play", 1.0), ("preisach", -1.0)], "erf-play - preisach"),
    ("0.7*erf-play-0.3*preisach", [("erf-play", 0.7), ("preisach", -0.3)],
     "0.7*erf-play - 0.3*preisach"),
    ("preisach-gauss - 2.*pi", [("preisach-gauss", 1.0), ("pi", -2.0)],
     "preisach-gauss - 2*pi"),
    ("- 1e-3*relay + 2E+1*n4", [("relay", -1e-3), ("n4", 20.0)], "-0.001*relay + 20*n4"),
    ("1_000.5*dimers - play*0.25", [("dimers", 1000.5), ("play", -0.25)],
     "1000.5*dimers - 0.25*play"),
    ("2*n2 + 3*n4 + 4*relay", [("n2", 2.0), ("n4", 3.0), ("relay", 4.0)],
     "2*n2 + 3*n4 + 4*relay"),
    ("1e300*play", [("play", 1e300)], "1e+300*play"),
]  # fmt: skip


@pytest.mark.parametrize(("text", "terms", "canonical"), VALID)
def test_valid_forms_read_their_weights_and_canonical_text_round_trips(text, terms, canonical):
    expr = parse_model(text)
    assert [(t.name, t.weight) for t in expr.terms] == terms
    assert str(expr) == canonical == canonical_model(text)
    assert parse_model(canonical) == expr  # the canonical text reads back as the same sum
    for _, weight in terms:
        assert math.isfinite(weight) and weight != 0.0


def test_numbers_are_python_float_literals():
    for literal in ("3", "3.", ".5", "0.125", "1e-3", "1E3", "2.5e+2", "1_0.0_1", "007"):
        expr = parse_model(f"{literal}*play + relay")
        assert expr.weights == (float(literal), 1.0)


def test_a_plain_name_is_the_model_itself():
    assert parse_model("pi").plain == "pi" and parse_model("1*pi").plain == "pi"
    assert parse_model("2*pi").plain is None and parse_model("-pi").plain is None
    for name in MODELS:
        assert canonical_model(name) == name
        assert model_record(f"1*{name}") == model_record(name)
    # same class and same parameters as the plain name, not a one-part sum
    assert repr(build_operator("1*play", width=3.0)) == repr(build_operator("play", width=3.0))
    one = build_operator("preisach*1", spins=40, seed=2)
    ref = build_operator("preisach", spins=40, seed=2)
    assert type(one) is type(ref)
    np.testing.assert_array_equal(one.alpha, ref.alpha)


#: a registry of the test's own, independent of the models: longest spelling at a '-'
SPELLINGS = {"a": "a", "b": "b", "b-c": "b-c", "c": "c", "old_a": "a"}


def test_names_are_the_longest_accepted_spelling_cut_at_a_minus():
    expr = parse_model_expression("b-c-a", SPELLINGS)
    assert expr == ModelExpression((ModelTerm("b-c", 1.0), ModelTerm("a", -1.0)))
    expr = parse_model_expression("b - c-a", SPELLINGS)
    assert expr.names == ("b", "c", "a") and expr.weights == (1.0, -1.0, -1.0)
    expr = parse_model_expression("2*old_a", SPELLINGS)
    assert expr.names == ("a",) and expr.terms[0].spelling == "old_a"
    assert expr == ModelExpression((ModelTerm("a", 2.0),))  # the spelling is no part of it
    assert [str(ModelTerm("a", w)) for w in (1.0, -1.0, 2.0, -0.5)] == ["a", "-a", "2*a", "-0.5*a"]


ERRORS = [
    ("", r"'': empty"),
    ("   ", r"empty"),
    ("play +", r"'\+' at column 6 is not followed by a term"),
    ("play -", r"'-' at column 6 is not followed by a term"),
    ("-", r"'-' at column 1 is not followed by a term"),
    ("+play", r"'\+' at column 1 does not start a term"),
    ("play + + relay", r"'\+' at column 6 is not followed by a term"),
    ("play +- relay", r"'\+' at column 6 is not followed by a term"),
    ("*play", r"'\*' at column 1 does not start a term"),
    ("play*", r"'\*' at column 5 is not followed by a number"),
    ("0.5*", r"'\*' at column 4 is not followed by a model name"),
    ("0.5*+play", r"'\*' at column 4 is not followed by a model name"),
    ("0.5", r"the weight 0.5 at column 1 has no model name"),
    ("0.5 + play", r"the weight 0.5 at column 1 has no model name"),
    ("play + 0.5", r"the weight 0.5 at column 8 has no model name"),
    ("2*play*3", r"the term of 'play' has two weights"),
    ("play*2*3", r"the term of 'play' has two weights"),
    ("0.5*0.5*play", r"two weights in a row"),
    ("play relay", r"expected '\+' or '-' before 'relay' at column 6"),
    ("0.5*play 0.5*relay", r"expected '\+' or '-' before '0.5' at column 10"),
    ("(play)", r"parentheses are not part of a model sum"),
    ("0.5*(play + relay)", r"parentheses"),
    ("play[0]", r"parentheses"),
    ("play/2", r"unexpected character '/' at column 5"),
    ("play**2", r"'\*' at column 5 is not followed by a number"),
    ("play, relay", r"unexpected character ','"),
    ("play^2", r"unexpected character '\^'"),
    ("2play", r"'2play' at column 1 is not a number"),
    ("1j*play", r"'1j' at column 1 is not a number"),
    ("1.2.3*play", r"'1.2.3' at column 1 is not a number"),
    ("1__0*play", r"'1__0' at column 1 is not a number"),
    ("1e*play", r"'1e' at column 1 is not a number"),
    (".*play", r"'\.' at column 1 is not a number"),
    ("\u0663*play", r"unexpected character"),  # a non-ASCII digit
    ("1e999*play", r"the weight 1e999 at column 1 is not finite"),
    ("inf*play", r"the weight inf at column 1 is not finite"),
    ("play*nan", r"the weight nan at column 6 is not finite"),
    ("Infinity*play", r"not finite"),
    ("0*play + relay", r"the weight of 'play' \(column 3\) is 0; leave the term out"),
    ("1e-400*play", r"is 0"),  # underflows to 0
    ("play + play", r"'play' appears twice; every part"),
    ("erf_play - erf-play", r"'erf-play' appears twice \(as 'erf_play' and 'erf-play'\)"),
]  # fmt: skip


@pytest.mark.parametrize(("text", "match"), ERRORS)
def test_every_malformed_text_is_refused_in_one_line_naming_the_parameter(text, match):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        with pytest.raises(ModelExpressionError, match=match) as exc:
            parse_model(text)
    message = str(exc.value)
    assert message.startswith("model ") and "\n" not in message
    assert message == f"model {exc.value.detail}" and exc.value.unknown is None
    assert isinstance(exc.value, ValueError)
    with pytest.raises(ValueError, match=match):  # every entry point refuses it the same way
        build_operator(text)


def test_unknown_names_list_the_registry():
    names = ", ".join(MODELS)
    with pytest.raises(ModelExpressionError) as exc:
        parse_model("foo")
    # a plain unknown name: the message of canonical_model_name, as before
    assert str(exc.value) == f"model must be one of {names}; got 'foo'"
    assert exc.value.unknown == "foo"
    with pytest.raises(ModelExpressionError) as exc:
        parse_model("0.7*erf-play + 0.3*preisachh")
    assert str(exc.value) == (
        f"model must be one of {names}; got 'preisachh' in '0.7*erf-play + 0.3*preisachh'"
    )
    with pytest.raises(ModelExpressionError, match="got 'gauss'"):
        parse_model("erf-play-gauss")  # erf-play minus an unknown 'gauss'
    with pytest.raises(ModelExpressionError, match="got 'Play'"):
        parse_model("Play")  # names are case sensitive
    with pytest.raises(TypeError, match="model must be a str"):
        parse_model(3.0)  # type: ignore[arg-type]


def test_deprecated_spelling_in_a_sum_warns_and_is_canonicalised():
    with pytest.warns(DeprecationWarning, match="'erf_play' is deprecated; use 'erf-play'"):
        assert canonical_model("0.5*erf_play + 0.5*play") == "0.5*erf-play + 0.5*play"


def test_the_sum_is_the_weighted_sum_of_the_parts_built_one_by_one():
    params = {"spins": 60, "seed": 3, "width": 1.5, "spread": 0.8}
    text = "0.7*erf-play - 0.3*preisach + 2*pi"
    op = build_operator(text, **params)
    assert isinstance(op, BranchSum)  # continuous parts: the branch-flow sum
    parts = [build_operator(n, **params) for n in ("erf-play", "preisach", "pi")]
    u = np.concatenate([np.linspace(-1, 4, 40), np.linspace(4, -3, 50), np.linspace(-3, 2, 30)])
    u0 = -1.0
    y, _ = op.apply(u, op.initial_state(u0))
    outs = [p.apply(u, p.initial_state(u0))[0] for p in parts]
    expected = 0.0 + 0.7 * outs[0] + (-0.3) * outs[1] + 2.0 * outs[2]
    # same products, summed in the written order (the algebra's promise): equal to the bit
    np.testing.assert_array_equal(y, expected)
    # every part read the same parameters (same seed): its relays are the registry's
    np.testing.assert_array_equal(op.parts[1].alpha, parts[1].alpha)


def test_relay_type_sums_stay_relay_type():
    op = build_operator("0.5*preisach + 0.5*dimers", spins=40)
    assert isinstance(op, RelaySum) and op.piecewise_constant
    np.testing.assert_array_equal(op.weights, [0.5, 0.5])
    # a negative weight is no relay table with weights >= 0: the branch-flow sum
    assert isinstance(build_operator("preisach - 0.5*relay", spins=40), BranchSum)


def test_records_and_titles_describe_a_sum_by_its_canonical_text():
    rec = model_record("0.70*erf-play+.3*preisach", spins=50)
    assert rec == {
        "model": "0.7*erf-play + 0.3*preisach",
        "weights": {"erf-play": 0.7, "preisach": 0.3},
        # what any part reads, once each (erf-play: p, R; preisach: N, seed, p, R, σ_r)
        "width": 2.0,
        "spread": 1.0,
        "spins": 50,
        "seed": 0,
        "width_spread": 0.2,
    }
    title = describe_model(rec, [("C", 3.0)])
    assert title == "(0.7*erf-play + 0.3*preisach) p=2 R=1 N=50 seed=0 σ_r=0.2, C=3"
    # the special cases of one model keep their reading inside a sum
    rec = model_record("relay + 0.5*preisach-uniform", width=2.0, spread=1.0)
    assert rec["alpha"] == 1.0 and rec["beta"] == -1.0 and rec["half_extent"] == 6.0
    rec = model_record("dimers - n2", fields=[[1.0, -1.0]])
    assert rec["fields"] == [[1.0, -1.0]] and rec["spin_coupling"] == 2.0
    assert "spins" not in rec
