"""Paths the tests share: the repository root and the test data folder (tests/ mirrors the
packages, so a test file's own folder says nothing about where these are)."""

from pathlib import Path

TESTS = Path(__file__).resolve().parent
DATA = TESTS / "data"
ROOT = TESTS.parent
