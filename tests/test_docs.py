"""The repository stands on its own in a clone. The user's documents (README.md, ARCHITECTURE.md,
QUIRKS.md, the examples' READMEs): every relative link is a file of the repository and no text
sends the reader outside it. The code's comments state the rule they apply instead of pointing at
the project's specification documents (kept beside the repository during development)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
DOCUMENTS = [
    REPO / "README.md",
    REPO / "ARCHITECTURE.md",
    REPO / "QUIRKS.md",
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


# What a pointer to a document outside the repository looks like in a comment: a section sign
# ("spec §7.2"), a specification file ("goby-moos-apps.md 5.3"), an id from a specification's
# quirk ledger ("Quirk A14", "(Q18 fixed)"), a seed document ("seed 003"), "the spec", or a label
# of the frontseat rule tables ("(T7)", "E1-E4"). QUIRKS.md's own ids (Q-ACOMMS-14) do not count.
CITATIONS = re.compile(
    r"§"
    r"|\b(?:acomms|dccl|moos|netsim|goby-moos-apps)\.md\b"
    r"|\bgoby-moos-apps\s+(?:§|\d)"
    r"|\b[Qq]uirks?\s+[A-Z]{1,2}\d+"
    r"|\b[AQ]\d{1,2}\s+(?:fixed|reproduced|sane|faithful)\b"
    r"|\bseeds?\s+0\d\d\b"
    r"|\bspec(?:'s)?\s+(?:§|\d|sections?\s+\d)"
    r"|\bthe spec(?:'s)?\b"
    r"|\b[TE][1-9]\b"
)
MAX_CITATIONS = 10


def citations(text: str) -> list[str]:
    return [line.strip() for line in text.splitlines() if CITATIONS.search(line)]


@pytest.mark.parametrize(
    "line",
    [
        '"""Bool codec (spec §8): 1 bit required."""',
        "# Quirk A14 (sane)",
        "        # the posts, nothing published (Q18 fixed)",
        "(seed 003 §2.3.8): a string value",
        "goby-moos-apps.md 5.3, 5.7). Sans-I/O",
        "// Run-time MAC cycle changes (spec acomms.md §4.8).",
        "# Message types (moos.md 6.1).",
        "if cleared:  # T8",
        "error check E1-E4 with the helm rule",
        "Every ACOMMS_* variable of the spec's table is published",
    ],
)
def test_the_citation_pattern_catches_each_form(line):
    assert citations(line) == [line.strip()]


def test_the_citation_pattern_leaves_plain_code_and_quirk_ids():
    text = "spec = split_spec(name)\nfor spec in names:  # see QUIRKS.md Q-ACOMMS-14\nT = 10.0\n"
    assert citations(text) == []


def test_code_states_its_rules_instead_of_citing_outside_documents():
    """The comments and docstrings of src/ say the rule they apply in a sentence; upstream
    behaviours reproduced or fixed are listed in QUIRKS.md."""
    found = [
        f"{path.relative_to(REPO)}: {line}"
        for path in sorted((REPO / "src").rglob("*"))
        if path.suffix in (".py", ".proto", ".js", ".html", ".css")
        for line in citations(path.read_text(encoding="utf-8"))
    ]
    assert len(found) <= MAX_CITATIONS, "\n".join(found)


QUIRK_ID = re.compile(r"\bQ-[A-Z0-9]+-\d+\b")


def test_every_quirk_id_in_the_code_is_listed_with_modules_that_exist():
    """QUIRKS.md has a row for every id a comment (or the README) gives, and each row's modules
    are files of the repository."""
    rows = {
        match.group(1): line
        for line in (REPO / "QUIRKS.md").read_text().splitlines()
        if (match := re.match(r"\| (Q-[A-Z0-9]+-\d+) \|", line))
    }
    used = {
        found
        for path in [*(REPO / "src").rglob("*.py"), *(REPO / "src").rglob("*.proto")]
        for found in QUIRK_ID.findall(path.read_text(encoding="utf-8"))
    } | set(QUIRK_ID.findall((REPO / "README.md").read_text()))
    assert used - rows.keys() == set()
    for quirk, row in rows.items():
        where = row.rstrip(" |").rsplit("|", 1)[1]
        modules = re.findall(r"`([^`]+)`", where)
        assert modules, f"{quirk}: no module named"
        for module in modules:
            path = REPO / module if module.startswith("examples/") else REPO / "src/pygoby" / module
            assert path.is_file(), f"{quirk}: {module} does not exist"
