"""What ``hyst`` prints before any work: no command, and the paper's run sizes."""

from __future__ import annotations

import argparse

from analysis.cli import build_parser, main
from analysis.paper.runner import figure_labels


def test_no_command_is_a_usage_error(capsys):
    """``hyst`` alone prints the usage on stderr and fails (exit 2), as a bad option does."""
    assert main([]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith("usage: hyst") and "paper" in captured.err


def test_paper_help_states_the_sizes_without_a_default_under_each(capsys):
    """The default size is named once, under --quick; --full states the measured time."""
    assert main(["paper", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    text = text[text.index("options:") :]  # past the usage line
    full = text[text.index("--full ") : text.index("--smoke ")]
    smoke = text[text.index("--smoke ") : text.index("run:")]
    assert "default" not in full and "default" not in smoke
    assert "12.2 min measured" in full
    assert "(the default size)" in text[text.index("--quick ") : text.index("--full ")]


def _actions_with_choices():
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name, command in sub.choices.items():
        for action in command._actions:
            if action.choices is not None and not isinstance(action.choices, dict):
                yield name, command, action


def test_choices_print_as_choices(capsys):
    """Every option with choices shows each choice whole: argparse's ``{a,b}`` is kept only
    where no choice holds a comma (``--columns`` 'field,moment' would read as two words)."""
    seen = 0
    for name, command, action in _actions_with_choices():
        text = " ".join(command.format_help().split())
        choices = [str(c) for c in action.choices]
        if any("," in c for c in choices):
            assert action.metavar is not None, (name, action.dest)
            assert all(f"'{c}'" in text for c in choices), (name, action.dest)
        else:
            assert "{" + ",".join(choices) + "}" in text, (name, action.dest)
        seen += 1
    assert seen >= 10


def test_paper_help_lists_the_figure_labels(capsys):
    assert main(["paper", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    only = text[text.index("--only LABEL [LABEL ...] ") : text.index("output:")]
    assert all(label in only for label in figure_labels())
