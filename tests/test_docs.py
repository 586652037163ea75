"""The documentation in the repository: the generated pages are current, and every relative
link of README.md and the docs pages resolves to a file of the checkout (and a heading of
it, for a ``#anchor``), as it does on the site."""

import importlib.util
import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
PAGES += sorted((ROOT / "docs" / "generated").glob("*.md"))
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
