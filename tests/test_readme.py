"""The README's two commands are the project's contract with a newcomer and with CI."""

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _ci_command() -> str:
    lines = (ROOT / ".ci" / "run").read_text().splitlines()
    return [ln for ln in lines if "pytest" in ln and not ln.startswith("#")][-1].strip()


def test_ci_runs_exactly_the_readme_test_command():
    readme = (ROOT / "README.md").read_text()
    command = _ci_command()
    assert "python -m pytest" in command
    assert command in readme, "the test command in .ci/run must appear verbatim in README.md"


def test_readme_main_command_runs_the_quick_paper_reproduction():
    readme = (ROOT / "README.md").read_text()
    assert "hyst paper --quick" in readme


def test_readme_api_tour_runs():
    """Every ```python block of the README runs as written (in order, one namespace)."""
    import re

    readme = (ROOT / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", readme, flags=re.S)
    assert len(blocks) >= 3
    namespace: dict = {}
    for block in blocks:
        exec(compile(block, "README.md", "exec"), namespace)
