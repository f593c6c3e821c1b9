"""Issue 32: a model option the model does not read is refused (one model's feature: the user
meant another model) or warned about in one line (an option the models share), never silently
ignored; an option at its default, or a model that reads it, says nothing."""

from __future__ import annotations

import argparse
import itertools
import warnings

import numpy as np
import pytest

from analysis.cli import build_parser, main
from analysis.cli._build import MODEL_SHARED, MODEL_SPECIFIC, check_model_options
from analysis.cli._parsing import given_options
from analysis.experiments.models import MODELS, ModelParameters, build_operator, parameters_read


def _args(*argv: str) -> argparse.Namespace:
    return build_parser().parse_args(["orbit", "--coupling", "1", *argv])


def _check(*argv: str) -> list[str]:
    """The warnings ``check_model_options`` gives (a refusal raises)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_model_options(_args(*argv))
    return [str(w.message) for w in caught]


def test_only_options_given_on_the_command_line_are_recorded():
    assert given_options(_args()) == frozenset()
    # given at its default value still counts as given
    assert given_options(_args("--spins", "20000", "--model", "dimers")) == {"spins", "model"}
    assert _check("--model", "erf-play") == []  # every default: nothing to say


@pytest.mark.parametrize("name", list(MODELS))
def test_parameters_read_are_those_that_change_the_operator(name):
    """Independent truth: a parameter outside parameters_read leaves the operator's output on
    a probe input unchanged; one inside changes it."""
    base = ModelParameters(spins=40, width_spread=0.3, resolution=64)
    read = parameters_read(name, base)
    turns = [0.0, 3.0, -3.0, 1.15, -1.15, 0.5, -0.2]
    probe = np.concatenate([np.linspace(a, b, 30) for a, b in itertools.pairwise(turns)])

    def outputs(p: ModelParameters) -> list[float]:
        return [float(m) for m in build_operator(name, p).apply(probe)[0]]

    changes = {
        "spins": 42, "seed": 5, "width": 2.6, "spread": 1.3, "spin_coupling": 2.5,
        "width_spread": 0.4, "plays": 4, "bw_a": 1.3, "bw_beta": 0.6, "bw_gamma": 0.3,
        "bw_n": 1.5, "ja_ms": 1.1, "ja_a": 0.25, "ja_k": 0.35, "ja_c": 0.3, "ja_alpha": 0.05,
        "lattice": (4, 4, 4), "disorder": 1.0,
    }  # fmt: skip
    ref = outputs(base)
    for field, value in changes.items():
        moved = outputs(ModelParameters(**{**vars(base), field: value}))
        if field not in read:
            assert moved == ref, (name, field)
        elif (name, field) != ("dimers", "spin_coupling"):
            # (the paper's disorder fixes each loop's width p whatever J: J moves the fields
            # b = -s +- (J - p/2) and bounds p < 2J, not the output)
            assert moved != ref, (name, field)


def test_parameters_read_follow_the_values():
    assert parameters_read("relay", alpha=1.0, beta=-1.0) == {"alpha", "beta"}
    assert "width" in parameters_read("relay", alpha=1.0)
    assert parameters_read("dimers", fields=((1.0, -1.0),)) == {"fields", "spin_coupling"}
    assert "width" not in parameters_read("preisach-uniform", half_extent=3.0)
    assert parameters_read("0.5*erf-play + 0.5*pi") == {"width", "spread", "plays"}


@pytest.mark.parametrize(
    ("argv", "option", "readers"),
    [
        (["--model", "erf-play", "--plays", "3"], "--plays", "pi"),
        (["--model", "dimers", "--width-spread", "0.2"], "--width-spread", "preisach or"),
        (["--model", "0.5*erf-play + 0.5*play", "--plays", "2"], "--plays", "pi"),
    ],
)
def test_an_option_of_another_model_is_refused_in_one_line(argv, option, readers, capsys):
    assert main(["orbit", "--coupling", "1", *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"hyst orbit: error: argument {option}: ")
    assert f"only for --model {readers}" in err


def test_a_shared_option_the_model_does_not_read_is_one_warning():
    (msg,) = _check("--model", "erf-play", "--spins", "10", "--seed", "3")
    assert msg.startswith("--model erf-play does not read --spins, --seed: ignored")
    (msg,) = _check("--model", "relay", "--alpha", "1", "--beta", "-1", "--width", "3")
    assert "--width" in msg and "--alpha" not in msg.split(":")[0]
    (msg,) = _check("--model", "dimers", "--fields", "1", "-1", "--spread", "2")
    assert "does not read --spread" in msg


def test_a_sum_reads_what_any_part_reads():
    assert _check("--model", "0.5*erf-play + 0.5*preisach", "--spins", "10", "--seed", "2") == []
    assert _check("--model", "preisach", "--width-spread", "0.1", "--spins", "10") == []
    assert _check("--model", "relay", "--alpha", "1", "--width", "3") == []  # beta = -p/2


def test_the_warning_is_one_line_before_the_run(capsys):
    # an out-of-range coupling stops the run right after the options' checks
    assert main(["orbit", "--model", "n2", "--width", "3", "--coupling", "1e9"]) == 2
    lines = capsys.readouterr().err.splitlines()
    assert lines[0] == (
        "hyst orbit: warning: --model n2 does not read --width: ignored (it reads --spin-coupling)"
    )
    assert lines[1].startswith("hyst orbit: error: argument --coupling")


@pytest.mark.parametrize("option", [["--model", "dimers"], ["--spins", "4"], ["--width", "2"]])
def test_identify_refuses_model_options_with_input(option, tmp_path, capsys):
    argv = ["identify", "--input", str(tmp_path / "none.csv"), *option]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"hyst identify: error: argument {option[0]}: a model option, not ")
    assert err.count("\n") == 1


def test_identify_grid_reads_width_and_spread():
    """``hyst identify --model play --spread 3``: the grid's 5R + p/2 reads --spread (no
    warning); without the grid nothing does."""
    args = build_parser().parse_args(["identify", "--model", "play", "--spread", "3"])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_model_options(args, ("width", "spread"))
    with pytest.warns(UserWarning, match="does not read --spread"):
        check_model_options(args)


def test_every_model_option_is_classified():
    assert set(MODEL_SHARED) | set(MODEL_SPECIFIC) == {
        "spins", "seed", "width", "spread", "spin_coupling", "width_spread", "plays",
        "fields", "alpha", "beta", "bw_a", "bw_beta", "bw_gamma", "bw_n", "ja_ms", "ja_a",
        "ja_k", "ja_c", "ja_alpha", "lattice", "disorder",
    }  # fmt: skip
