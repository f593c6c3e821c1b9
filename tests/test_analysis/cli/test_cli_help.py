"""What ``hyst`` prints before any work: no command, and the paper's run sizes."""

from __future__ import annotations

from analysis.cli import main


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
    assert "25-35 min" in full
    assert "(the default size)" in text[text.index("--quick ") : text.index("--full ")]
