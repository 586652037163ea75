"""The layout of ``xfem_contact``: its layer order, and the table of modules in the docs.

The sub-packages are the steps of the data flow, lowest first (:data:`LAYERS`); each
may import only the ones before it. ``tests/test_layout.py`` checks that by parsing the
sources (nothing is imported), together with the module sizes (:data:`LONG_MODULE_LINES`,
:data:`LONG_MODULES`) and :data:`MAX_ROOT_MODULES`. This script writes the table of
modules (package | module | what it is: the summary of each module's docstring) between
the markers
``<!-- layout:start -->`` and ``<!-- layout:end -->`` of ``docs/architecture.md``::

    python docs/layout.py          # rewrite the tables
    python docs/layout.py --check  # exit 1 if a table is stale (tests/test_layout.py runs this)

To change a description, edit the module's docstring summary and run the script.
"""

from __future__ import annotations

import argparse
import ast
import collections
import pathlib
import re
import sys

#: Sub-packages of ``xfem_contact``, lowest first: each may import only those before it.
LAYERS = (
    "codegen",
    "geometry",
    "quadrature",
    "fem",
    "solvers",
    "mechanics",
    "io",
    "cases",
    "scenes",
)
#: A module longer than this (lines) is a prompt to split it by concept: it must be listed
#: in :data:`LONG_MODULES` with the reason it is one concept.
LONG_MODULE_LINES = 500
#: Modules allowed beyond :data:`LONG_MODULE_LINES`: path -> (lines at most, why one concept).
LONG_MODULES: dict[str, tuple[int, str]] = {
    "xfem_contact/fem/cutmesh.py": (
        520,
        "one class, the cut's public face (its constructor's options, measures, the "
        "current state's accessors, integration parts); the cut itself, its rules and "
        "boundary parts live in their own modules already",
    ),
    "xfem_contact/mechanics/problem.py": (
        520,
        "one class, the problem's public face (construction, forms, solve, interface "
        "queries); its parts (composition, contexts, loads, solvers) live in their own "
        "modules already",
    ),
}
#: Modules allowed directly in ``xfem_contact/`` (``__init__.py`` included).
MAX_ROOT_MODULES = 6

PACKAGE = "xfem_contact"
ROOT = pathlib.Path(__file__).resolve().parents[1]
TARGETS = ("docs/architecture.md",)
START, END = "<!-- layout:start -->", "<!-- layout:end -->"


def modules(root: pathlib.Path = ROOT) -> list[pathlib.Path]:
    """The ``.py`` files of the package under ``root``, sorted."""
    return sorted(p for p in (root / PACKAGE).rglob("*.py") if "__pycache__" not in p.parts)


def layer(path: pathlib.Path, root: pathlib.Path = ROOT) -> str | None:
    """The sub-package (first level below ``xfem_contact``) of a module; ``None`` at the root."""
    parts = path.relative_to(root / PACKAGE).parts
    return parts[0] if len(parts) > 1 else None


def summary(path: pathlib.Path) -> str:
    """The summary of a module's docstring: its first paragraph on one line ('' if none)."""
    doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"))) or ""
    return " ".join(doc.strip().split("\n\n")[0].split())


def markdown(text: str) -> str:
    """reST inline markup of a docstring summary as markdown, safe in a table cell."""
    text = re.sub(r":[a-z]+:`~(?:[\w.]*\.)?(\w+)`", r"`\1`", text)  # :class:`~a.b.C` -> `C`
    text = re.sub(r":[a-z]+:`([^`]+)`", r"`\1`", text)  # :mod:`a.b` -> `a.b`
    text = re.sub(r"``([^`]+)``", r"`\1`", text)
    return text.replace("|", "\\|")


def _order(package: str | None) -> tuple[int, str]:
    if package is None:
        return (-1, "")
    return (LAYERS.index(package), "") if package in LAYERS else (len(LAYERS), package)


def table(root: pathlib.Path = ROOT) -> str:
    """The generated text between the markers: the layer order and the module table."""
    by_package = collections.defaultdict(list)
    for path in modules(root):
        by_package[layer(path, root)].append(path)
    rows = ["| package | module | what it is |", "| --- | --- | --- |"]
    for package in sorted(by_package, key=_order):
        folder = root / PACKAGE if package is None else root / PACKAGE / package
        name = PACKAGE if package is None else f"{PACKAGE}.{package}"
        paths = sorted(by_package[package], key=lambda p: (p.name != "__init__.py", p))
        for i, path in enumerate(paths):
            module = path.relative_to(folder).as_posix()
            cell = f"`{name}`" if i == 0 else ""
            rows.append(f"| {cell} | `{module}` | {markdown(summary(path))} |")
        if package is not None:
            data = collections.Counter(
                p.suffix
                for p in folder.rglob("*")
                if p.is_file()
                and p.suffix not in (".py", ".pyc")
                and not any(part.startswith((".", "__pycache__")) for part in p.parts)
            )
            if data:
                files = ", ".join(f"`*{suffix}` ({n})" for suffix, n in sorted(data.items()))
                rows.append(f"|  | {files} | package data |")
    order = " < ".join(f"`{name}`" for name in LAYERS)
    return "\n".join(
        [
            "<!-- generated by docs/layout.py from the module docstrings: edit those, then run"
            " `python docs/layout.py` -->",
            "",
            f"Sub-packages, lowest first: {order}. Each imports only the ones before it; a module"
            f" over {LONG_MODULE_LINES} lines is listed in `LONG_MODULES` of `docs/layout.py`"
            f" with the reason it is one concept; at most {MAX_ROOT_MODULES} modules sit at the"
            " package root (checked by `tests/test_layout.py`).",
            "",
            *rows,
            "",
        ]
    )


def replace_block(text: str, block: str, name: str = "") -> str:
    """``text`` with what lies between the markers replaced by ``block``."""
    if text.count(START) != 1 or text.count(END) != 1 or text.index(START) > text.index(END):
        raise ValueError(f"{name or 'text'}: needs one {START} followed by one {END}")
    head, rest = text.split(START)
    tail = rest.split(END)[1]
    return f"{head}{START}\n{block}{END}{tail}"


def main(argv: list[str] | None = None, root: pathlib.Path = ROOT) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--check", action="store_true", help="write nothing; exit 1 if a table is stale"
    )
    args = parser.parse_args(argv)
    block = table(root)
    stale = []
    for target in TARGETS:
        path = root / target
        text = path.read_text(encoding="utf-8")
        try:
            new = replace_block(text, block, target)
        except ValueError as error:
            print(f"error: {error}", file=sys.stderr)
            return 2
        if new != text:
            stale.append(target)
            if not args.check:
                path.write_text(new, encoding="utf-8")
                print(f"wrote {target}")
    if args.check and stale:
        print(
            f"stale module table in {', '.join(stale)}: run `python docs/layout.py`",
            file=sys.stderr,
        )
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
