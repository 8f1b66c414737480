"""The course bibliography (docs/bibliography.md) and the sources the library's docstrings cite.

A reader of a docstring who meets "Baram (1980)" must find the paper: every author-year citation
in a docstring of ``course`` has an entry in the bibliography, every module whose docstrings cite
a source links the bibliography page from its module docstring, and no docstring or documentation
page names a file under ``shared/`` or ``seeds/`` (the course's copies of its sources, which
students do not have).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest
from test_notebooks_text import SOURCE_PATH

ROOT = Path(__file__).resolve().parents[1]
BIBLIOGRAPHY = ROOT / "docs" / "bibliography.md"
MODULES = sorted((ROOT / "course").rglob("*.py"))
# the README and the pages of the website; docs/api/modules/ is generated from the docstrings
# (checked below)
DOC_PAGES = sorted(ROOT.glob("*.md")) + sorted(
    p
    for p in (ROOT / "docs").rglob("*")
    if p.suffix in {".md", ".rst", ".txt"} and (ROOT / "docs" / "api" / "modules") not in p.parents
)

#: The one way a module docstring links the bibliography: a Sphinx cross-reference to the page
#: (a link on the website's API pages, and readable in ``help()``).
LINK = ":doc:`/docs/bibliography`"

YEAR = r"(1[89]\d\d|20[0-2]\d)"
# "Baram (1980", "Baram 1980", "Imhof's (1961)", "Tiberius et al. (2021", "(Wilks 1938)":
# the name written right before the year (for several authors, the last one).
AUTHOR_YEAR = re.compile(r"\b([A-Z][A-Za-z\-]+)(?:'s?)?(?: et al\.)?,? \(?" + YEAR + r"\b")
# the surname of each author of an entry: "Surname, I." in the entry's bold author block
SURNAME = re.compile(r"([A-Z][\w\-]+), (?:[A-Z]\.[ -]?)+")


# sources named without an author-year: the lecture slides, the poster, the MUDE book
NICKNAMES = re.compile(r"\b(LiU lecture|lecture on test quantities|poster|MUDE)\b")


def _entries() -> list[str]:
    """The bibliography's entries: one paragraph each, starting with its bold author block."""
    text = BIBLIOGRAPHY.read_text(encoding="utf-8")
    return [" ".join(p.split()) for p in re.split(r"\n\s*\n", text) if p.startswith("**")]


def _docstrings(path: Path) -> tuple[str, str]:
    """(module docstring, all docstrings of the module) with whitespace normalised."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    nodes = [tree] + [
        n
        for n in ast.walk(tree)
        if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef))
    ]
    docs = [" ".join((ast.get_docstring(n) or "").split()) for n in nodes]
    return docs[0], " ".join(docs)


def _citations(text: str) -> set[tuple[str, str]]:
    return {(m.group(1), m.group(2)) for m in AUTHOR_YEAR.finditer(text)}


def _cited_names() -> re.Pattern:
    """Any author of a bibliography entry, as a whole word ("Chiani's", "Cochran's theorem")."""
    names = {name for entry in _entries() for name in SURNAME.findall(entry.split("**")[1])}
    return re.compile(r"\b(" + "|".join(sorted(map(re.escape, names))) + r")\b")


def test_the_bibliography_has_its_entries():
    entries = _entries()
    assert len(entries) >= 20
    names = _cited_names().pattern
    for author in ("Baram", "Imhof", "Davies", "Chiani", "Johnstone", "Tiberius", "Forsling"):
        assert author in names


def test_the_citation_pattern():
    found = _citations(
        "Imhof's (1961) bound; (Baram 1980, (A17)); Tiberius et al. (2021, Chapter 10); "
        "Liu, Tang & Zhang (2009); (Reiter 1987; de Kleer and Williams 1987); W. Baarda (1968)"
    )
    assert found == {
        ("Imhof", "1961"),
        ("Baram", "1980"),
        ("Tiberius", "2021"),
        ("Zhang", "2009"),
        ("Reiter", "1987"),
        ("Williams", "1987"),
        ("Baarda", "1968"),
    }
    assert not _citations("at m = 2000 the tiles; eq. (2.14); Theory 63(7) (2017) 4521")


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_cited_source_is_in_the_bibliography(path):
    _, docs = _docstrings(path)
    entries = _entries()
    missing = sorted(
        f"{name} ({year})"
        for name, year in _citations(docs)
        if not any(f"({year})" in entry and name in entry for entry in entries)
    )
    assert not missing, (
        f"{path.relative_to(ROOT)} cites {', '.join(missing)}, which docs/bibliography.md does "
        "not list: add the full reference there"
    )


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(ROOT)))
def test_a_module_that_cites_a_source_links_the_bibliography(path):
    module_doc, docs = _docstrings(path)
    cited = _cited_names().search(docs) or AUTHOR_YEAR.search(docs) or NICKNAMES.search(docs)
    if cited:
        assert LINK in module_doc, (
            f"{path.relative_to(ROOT)} cites {cited.group(0)!r}: its module docstring must link "
            f"the course bibliography as {LINK}"
        )


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(ROOT)))
def test_no_docstring_names_a_source_file(path):
    _, docs = _docstrings(path)
    found = SOURCE_PATH.search(docs)
    assert found is None, f"{path.relative_to(ROOT)}: {found.group(0)!r}; cite the publication"


@pytest.mark.parametrize("path", DOC_PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_no_documentation_page_names_a_source_file(path):
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        found = SOURCE_PATH.search(line)
        assert found is None, (
            f"{path.relative_to(ROOT)}:{number}: {found.group(0)!r} names a file the reader "
            "does not have; cite the publication (docs/bibliography.md)"
        )
