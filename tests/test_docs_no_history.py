"""The user documentation speaks of the project as it is, not of its history (issue 32): no
issue numbers, no "Until 2026-11 this was ...", no "used to". The design record
(docs/architecture.md), the changelog and the generated paper report are exempt."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EXEMPT = {"architecture.md"}
PATTERNS = (
    re.compile(r"\bissues?\s+#?\d+", re.I),
    re.compile(r"\buntil\s+20\d\d", re.I),
    re.compile(r"\bused to be\b|\bthis was\b.*\bbefore\b", re.I),
)


def _pages() -> list[Path]:
    pages = [ROOT / "README.md"]
    for path in sorted((ROOT / "docs").rglob("*")):
        if not path.is_file() or path.suffix not in {".rst", ".md", ".txt", ".py"}:
            continue
        if path.name in EXEMPT or "paper-full" in path.parts:
            continue
        pages.append(path)
    return pages


def test_user_docs_carry_no_project_history():
    hits = []
    for page in _pages():
        for n, line in enumerate(page.read_text(encoding="utf-8").splitlines(), 1):
            if any(p.search(line) for p in PATTERNS):
                hits.append(f"{page.relative_to(ROOT)}:{n}: {line.strip()}")
    assert not hits, "\n".join(hits)


def test_the_check_sees_a_history_line():
    assert any(p.search("Until 2026-11 this was a relay") for p in PATTERNS)
    assert any(p.search("as issue 18 reported") for p in PATTERNS)
