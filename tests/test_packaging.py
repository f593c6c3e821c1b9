"""Packaging a scientist can cite: version, license, citation, typing marker, and the check that
no unrelated distribution claims the toolkit's import names (issue 12)."""

from __future__ import annotations

from importlib import metadata
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
TESTS = ROOT / "tests"


class _FakeDist:
    def __init__(self, name: str, version: str, top_level: str | None) -> None:
        self.metadata = {"Name": name}
        self.version = version
        self._top = top_level

    def read_text(self, filename: str) -> str | None:
        return self._top if filename == "top_level.txt" else None


@pytest.fixture
def fake_environment(monkeypatch):
    """Install fake distributions into importlib.metadata's view of the environment."""
    from hysteresis import _distribution

    def install(*dists: _FakeDist) -> None:
        by_name = {d.metadata["Name"].lower(): d for d in dists}

        def distribution(name: str):
            try:
                return by_name[name.lower()]
            except KeyError:
                raise metadata.PackageNotFoundError(name) from None

        monkeypatch.setattr(_distribution.metadata, "distributions", lambda: iter(dists))
        monkeypatch.setattr(_distribution.metadata, "distribution", distribution)
        _distribution._claims.cache_clear()

    yield install
    _distribution._claims.cache_clear()


def test_conflicting_distribution_is_named(fake_environment):
    from hysteresis._distribution import check_import_name, conflicting_distributions

    fake_environment(
        _FakeDist("hysteresis-toolkit", "0.2.0", "analysis\nhysteresis\noscillators\n"),
        _FakeDist("hysteresis", "2.0.5", None),  # claims the name by its own name
        _FakeDist("some-analysis-kit", "0.1.7", "analysis\n"),  # claims it in top_level.txt
        _FakeDist("numpy", "2.0", "numpy\n"),
    )
    assert conflicting_distributions("hysteresis") == ("hysteresis 2.0.5",)
    assert conflicting_distributions("analysis") == ("some-analysis-kit 0.1.7",)
    assert conflicting_distributions("oscillators") == ()
    with pytest.raises(ImportError, match=r"hysteresis 2\.0\.5.*virtual environment"):
        check_import_name("hysteresis")
    with pytest.raises(ImportError, match="some-analysis-kit 0.1.7"):
        check_import_name("analysis")
    check_import_name("oscillators")  # no conflict, no error


def test_own_distribution_alone_is_no_conflict(fake_environment):
    from hysteresis._distribution import IMPORT_NAMES, check_import_name

    fake_environment(_FakeDist("hysteresis_toolkit", "0.2.0", "analysis\nhysteresis\n"))
    for name in IMPORT_NAMES:
        check_import_name(name)


def test_this_environment_has_no_conflict():
    from hysteresis._distribution import IMPORT_NAMES, _claims, conflicting_distributions

    _claims.cache_clear()
    assert all(conflicting_distributions(n) == () for n in IMPORT_NAMES)


def test_one_version_everywhere():
    import analysis
    import hysteresis
    import oscillators
    from analysis.cli import build_parser

    assert hysteresis.__version__ == oscillators.__version__ == analysis.__version__
    try:
        installed = metadata.version("hysteresis-toolkit")
    except metadata.PackageNotFoundError:  # running from a source tree
        installed = None
    if installed is not None:
        assert installed == hysteresis.__version__
    with pytest.raises(SystemExit):
        build_parser().parse_args(["--version"])


def test_license_citation_changelog_and_typing_markers():
    assert (ROOT / "LICENSE").read_text().startswith("MIT License")
    for pkg in ("hysteresis", "oscillators", "analysis"):
        assert (ROOT / pkg / "py.typed").is_file()
    cff = (ROOT / "CITATION.cff").read_text()
    for name in ("Zech", "Otto", "Radons", "driven harmonic oscillator"):
        assert name in cff
    assert "## [0.2.0]" in (ROOT / "CHANGELOG.md").read_text()
    manifest = (ROOT / "MANIFEST.in").read_text()
    for needed in ("tests/data", "tests *.py", "examples *.py"):
        assert needed in manifest


def test_pyproject_uses_an_spdx_license_expression():
    tomllib = pytest.importorskip("tomllib")
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert meta["project"]["license"] == "MIT"
    assert meta["project"]["license-files"] == ["LICENSE"]
    assert any(r.startswith("setuptools>=77") for r in meta["build-system"]["requires"])
    # napoleon (numpydoc-style docstrings) ships with Sphinx: one dependency builds the docs
    assert "sphinx>=7" in meta["project"]["optional-dependencies"]["test"]


def test_test_module_basenames_are_unique():
    # the test folders have no __init__.py (rootdir-relative imports): two test modules with one
    # basename make pytest's collection fail with "import file mismatch" on a fresh checkout
    names: dict[str, list[str]] = {}
    for path in sorted(TESTS.rglob("test_*.py")):
        names.setdefault(path.name, []).append(str(path.relative_to(TESTS)))
    duplicates = {name: paths for name, paths in names.items() if len(paths) > 1}
    assert not duplicates, f"test modules share a basename: {duplicates}"
