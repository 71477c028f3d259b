"""The user's documents (README.md, ARCHITECTURE.md, the examples' READMEs) stand on their own in
a clone: every relative link is a file of the repository and no text sends the reader outside
it (the project's shared folder of specifications is beside the repository, for development)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
DOCUMENTS = [
    REPO / "README.md",
    REPO / "ARCHITECTURE.md",
    *sorted((REPO / "examples").rglob("README.md")),
]
LINK = re.compile(r"\]\(([^)\s]+)\)")


@pytest.mark.parametrize("document", DOCUMENTS, ids=lambda p: str(p.relative_to(REPO)))
def test_documents_point_only_into_the_repository(document):
    text = document.read_text()
    for target in LINK.findall(text):
        if re.match(r"[a-z]+:", target) or target.startswith("#"):
            continue  # a web address or an anchor
        found = (document.parent / target.split("#")[0]).resolve()
        assert found.is_relative_to(REPO) and found.exists(), f"{document.name}: link {target}"
    assert not re.search(r"\.\./shared\b", text), f"{document.name} points at ../shared"
