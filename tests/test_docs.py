"""The documentation in the repository: the generated pages are current, and every relative
link of README.md and the docs pages resolves to a file of the checkout (and a heading of
it, for a ``#anchor``), as it does on the site."""

import ast
import importlib.util
import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
PAGES += sorted((ROOT / "docs" / "generated").glob("*.md"))
#: The hand-written pages of docs/
DOCS = sorted((ROOT / "docs").glob("*.md"))
#: ``[text](target)`` and ``![alt](target)`` of markdown, outside code
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
FENCE = re.compile(r"^(`{3,}|~{3,})")


def _reference():
    spec = importlib.util.spec_from_file_location("reference", ROOT / "docs" / "reference.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def links(text: str) -> list[tuple[int, str]]:
    """``(line, target)`` of the markdown links of ``text`` outside fenced blocks and
    inline code."""
    found, fenced = [], False
    for number, line in enumerate(text.splitlines(), start=1):
        if FENCE.match(line.strip()):
            fenced = not fenced
            continue
        if fenced:
            continue
        line = re.sub(r"`[^`]*`", "", line)
        found += [(number, m.group(1)) for m in LINK.finditer(line)]
    return found


def anchors(text: str) -> set[str]:
    """The anchors of the headings of a markdown page (GitHub's and MyST's slugs:
    lower case, punctuation dropped, spaces to hyphens)."""
    slugs = set()
    for line in text.splitlines():
        if m := re.match(r"^#{1,6}\s+(.*)$", line):
            title = re.sub(r"[`*_]", "", m.group(1)).strip().lower()
            slugs.add(re.sub(r"\s", "-", re.sub(r"[^\w\s-]", "", title)))
    return slugs


def broken(page: pathlib.Path) -> list[str]:
    """The relative links of ``page`` that resolve to no file (or no heading) of the checkout."""
    problems = []
    for line, target in links(page.read_text(encoding="utf-8")):
        if re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("#"):
            continue  # a web address, mailto:, or a heading of the page itself
        path, _, anchor = target.partition("#")
        resolved = (page.parent / path).resolve()
        where = f"{page.relative_to(ROOT)}:{line}: {target}"
        if not resolved.exists():
            problems.append(f"{where}: no file {resolved.relative_to(ROOT, walk_up=True)}")
        elif anchor and resolved.suffix == ".md":
            if anchor not in anchors(resolved.read_text(encoding="utf-8")):
                problems.append(f"{where}: no heading #{anchor}")
    return problems


@pytest.mark.parametrize("page", PAGES, ids=[str(p.relative_to(ROOT)) for p in PAGES])
def test_relative_links_resolve(page):
    assert broken(page) == []


def test_link_check_finds_a_broken_link(tmp_path):
    page = tmp_path / "docs" / "page.md"
    page.parent.mkdir()
    (tmp_path / "docs" / "other.md").write_text("# Other page\n\n## A part\n")
    page.write_text(
        "[fine](other.md#a-part), [web](https://example.org), ![ok](other.md)\n"
        "[gone](generated/missing.md) and [bad anchor](other.md#nowhere)\n"
        "```\n[in code](nowhere.md)\n```\n`[inline](nowhere.md)`\n"
    )
    global ROOT
    saved, ROOT = ROOT, tmp_path
    try:
        problems = broken(page)
    finally:
        ROOT = saved
    assert len(problems) == 2
    assert "no file docs/generated/missing.md" in problems[0]
    assert "no heading #nowhere" in problems[1]


def test_generated_pages_current():
    """``docs/generated/`` is what ``python docs/reference.py`` writes (run it if not)."""
    assert _reference().stale_pages() == []


#: An issue number ("issue 26", "issues 11", "(#26)"): history belongs to git
ISSUE = re.compile(r"\bissues?\s+#?\d+|\(#\d+\)", re.IGNORECASE)
#: A commit hash: 7 to 40 hex digits with a letter and a digit, not part of a number
#: (``6.263744e-3``) or a word
COMMIT = re.compile(r"(?<![.\w-])(?=[0-9a-f]*[a-f])(?=[0-9a-f]*\d)[0-9a-f]{7,40}(?![\w.-])")
SOURCES = sorted(
    p
    for folder in ("xfem_contact", "bench", "tests", "docs")
    for p in (ROOT / folder).rglob("*.py")
    if p.name != "test_docs.py"
    # not hidden folders: bench/.peer-venv holds the optional peer's installed packages
    and not any(part.startswith(".") for part in p.relative_to(ROOT).parts)
)

#: The nodes that carry a docstring besides the module
DOCUMENTED = (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)


def history(text: str) -> list[str]:
    """The issue numbers and commit hashes in ``text``, each as ``line: match``."""
    return [
        f"{number}: {m.group(0)}"
        for number, line in enumerate(text.splitlines(), start=1)
        for m in [*ISSUE.finditer(line), *COMMIT.finditer(line)]
    ]


def docstrings(path: pathlib.Path) -> str:
    """The docstrings of a Python file (module, classes, functions), one after another."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    nodes = [tree, *(n for n in ast.walk(tree) if isinstance(n, DOCUMENTED))]
    return "\n".join(ast.get_docstring(n) or "" for n in nodes)


@pytest.mark.parametrize("page", PAGES, ids=[str(p.relative_to(ROOT)) for p in PAGES])
def test_page_has_no_history(page):
    """Docs say what the code does today: no issue numbers, no commit hashes."""
    assert history(page.read_text(encoding="utf-8")) == []


def test_code_has_no_history():
    """No issue number in any source or comment, no commit hash in a docstring."""
    found = []
    for path in SOURCES:
        text = path.read_text(encoding="utf-8")
        found += [f"{path.relative_to(ROOT)}:{m}" for m in history(text) if "issue" in m.lower()]
        found += [f"{path.relative_to(ROOT)} (docstring) {m}" for m in history(docstrings(path))]
    assert found == []


def test_history_check_finds_issues_and_hashes():
    text = "fixed in issue 26 (#12), at 79f8539, error 6.263744e-3, 1234567 dofs, cafe"
    assert [m.split(": ", 1)[1] for m in history(text)] == ["issue 26", "(#12)", "79f8539"]


#: A measured figure in a table: a number in exponent form, or with a unit of time,
#: memory or a percentage
MEASURED = re.compile(r"\d(\.\d+)?e-?\d+|\d\s?(s|MB|GB|%)(?![\w])")


def unmarked_tables(text: str) -> list[int]:
    """The first lines of the tables of ``text`` that hold measured figures but are
    neither marked as a static example nor pointed at a generated page in the text of
    their section before them."""
    lines, found, start = text.splitlines(), [], 0
    for number, line in enumerate(lines):
        if line.startswith("#"):
            start = number
        if line.startswith("|") and not (number and lines[number - 1].startswith("|")):
            table = []
            for row in lines[number:]:
                if not row.startswith("|"):
                    break
                table.append(row)
            before = "\n".join(lines[start:number])
            marked = "static example" in before or "generated/" in before
            if MEASURED.search("\n".join(table)) and not marked:
                found.append(number + 1)
    return found


@pytest.mark.parametrize("page", DOCS, ids=[str(p.relative_to(ROOT)) for p in DOCS])
def test_measured_tables_are_generated_or_marked(page):
    """Every table of measured figures is a generated page's or marked as a static
    example (with the command that printed it)."""
    assert unmarked_tables(page.read_text(encoding="utf-8")) == []


def test_table_check_finds_an_unmarked_table():
    text = "# Page\n\n| n | time |\n|---|---|\n| 8 | 1.2 s |\n\n## Marked\n\n"
    text += "A static example:\n\n| n | error |\n|---|---|\n| 8 | 1e-3 |\n"
    assert unmarked_tables(text) == [3]
