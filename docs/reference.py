"""Pages generated from the code for the documentation: the scene file reference
(every table and key of :data:`xfem_contact.scenes.schema.FIELDS`: type, allowed
values, default, meaning; the built-in boundary parts of each mesh kind; the functions
of expressions), the solver options (:data:`xfem_contact.solvers.options.SOLVER_OPTIONS`),
the problem defaults (:data:`xfem_contact.mechanics.defaults.DEFAULTS`),
the demos, and one page per benchmark result (``bench/results/NAME.md``, with the
bench script's docstring and its pictures).

Defaults of scene keys are read from the loader's source (``table.get("key", default)``
calls), not typed twice. A built-in part or an expression function without a line in
:data:`PART_MEANINGS` / :data:`FUNCTION_MEANINGS` fails the build.

The pages live in ``docs/generated/`` in the repository, so that the pages' links
resolve in a checkout too; ``python docs/reference.py`` rewrites them (the documentation
build does as well) and ``--check`` exits 1 if one is stale (``tests/test_docs.py``).
"""

from __future__ import annotations

import argparse
import ast
import inspect
import pathlib
import re
import sys

#: What each built-in boundary part of :data:`xfem_contact.scenes.schema.BUILTIN_PARTS`
#: selects (``[mesh] corners = [[x0, y0], [x1, y1]]`` or ``[[x0, y0, z0], [x1, y1, z1]]``,
#: ``radii = [r0, r1]``)
PART_MEANINGS = {
    "left": "the facets on `x = x0`",
    "right": "the facets on `x = x1`",
    "bottom": "the facets on `y = y0`",
    "top": "the facets on `y = y1`",
    "back": "the facets on `z = z0`",
    "front": "the facets on `z = z1`",
    "inner": "the facets on the circle `r = r0` (centred at the origin)",
    "outer": "the facets on the circle `r = r1`",
    "boundary": "every boundary facet",
}
#: What each function of scene expressions computes (numpy's meaning; UFL's in loads)
FUNCTION_MEANINGS = {
    "sin": "sine (radians)",
    "cos": "cosine (radians)",
    "tan": "tangent (radians)",
    "exp": "exponential",
    "log": "natural logarithm",
    "sqrt": "square root",
    "abs": "absolute value",
    "hypot": "`hypot(a, b) = sqrt(a**2 + b**2)`",
    "arctan2": "`arctan2(a, b)`: the angle of the point `(b, a)` in (-pi, pi]",
    "minimum": "the smaller of two values, point by point",
    "maximum": "the larger of two values, point by point",
    "where": "`where(condition, a, b)`: `a` where the condition holds, else `b`",
    "isclose": "`isclose(a, b)`: `a` equals `b` to numpy's default tolerances",
}


def _defaults() -> dict[str, object]:
    """``key -> default`` of the scene loader's ``.get("key", literal)`` calls."""
    from xfem_contact.scenes import run, scene

    found = {}
    for module in (scene, run):
        for node in ast.walk(ast.parse(inspect.getsource(module))):
            if (
                isinstance(node, ast.Call)
                and isinstance(node.func, ast.Attribute)
                and node.func.attr == "get"
                and len(node.args) == 2
                and isinstance(node.args[0], ast.Constant)
                and isinstance(node.args[0].value, str)
            ):
                try:
                    found.setdefault(node.args[0].value, ast.literal_eval(node.args[1]))
                except ValueError:
                    continue
    return found


def _kind(check) -> tuple[str, str]:
    """(type, allowed values) of a schema check object."""
    name = type(check).__name__
    if name == "Choice":
        return "choice", " | ".join(f"`{c!r}`" for c in check.choices)
    if name == "Number":
        low = "-inf" if check.low is None else check.low
        high = "inf" if check.high is None else check.high
        brackets = "()" if check.open else "[]"
        kind = "integer" if check.integer else "number"
        return kind, f"{brackets[0]}{low}, {high}{brackets[1]}"
    if name == "Vector":
        item, allowed = _kind(check.item)
        return f"[{', '.join([item] * check.n)}]", allowed
    if name == "Text":
        return "string", check.rule or ""
    if name in ("Scalar", "Expression"):
        return f"{check.target} or expression of {', '.join('xyz'[: check.dim])}", ""
    return getattr(check, "__name__", name), ""


def _cell(text) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def scene_reference() -> str:
    from xfem_contact.scenes.schema import (
        CRACK_SHAPE_KEYS,
        FIELDS,
        LOAD_KEYS,
        SHAPE_KEYS,
        TOP_LEVEL,
    )

    found = _defaults()
    keys = [key for fields in FIELDS.values() for key in fields]
    # a key of several tables (name, centre, ...) has no single default to read off
    defaults = {k: v for k, v in found.items() if keys.count(k) == 1}
    lines = [
        "# Scene file reference",
        "",
        "Generated from `xfem_contact.scenes.schema.FIELDS` by `python docs/reference.py`.",
        f"Top-level tables: {', '.join(f'`[{t}]`' for t in TOP_LEVEL)}. A key not listed",
        "here is an error naming the valid keys; a bad value is an error naming the key and",
        "the valid choices (one line, exit status 2 from the command line).",
        "",
        *builtin_parts(),
        *expression_functions(),
    ]
    toml = {
        "interface": "[[interfaces]] (each entry)",
        "crack": "[[cracks]] (one entry)",
        "material": "[materials.NAME] (each material)",
        "part": "[parts.NAME] (each boundary part)",
        "load": "[[loads]] (each entry)",
    }
    for table, fields in FIELDS.items():
        lines += [
            f"## `{toml.get(table, f'[{table}]')}`",
            "",
            "| key | type | allowed | default | required | meaning |",
            "|---|---|---|---|---|---|",
        ]
        for key, field in fields.items():
            kind, allowed = _kind(field.check)
            default = f"`{defaults[key]!r}`" if key in defaults else ""
            lines.append(
                f"| `{key}` | {_cell(kind)} | {_cell(allowed)} | {_cell(default)} | "
                f"{'yes' if field.required else ''} | {_cell(field.doc)} |"
            )
        lines.append("")
    lines += [
        "## Keys of each interface shape",
        "",
        "| shape | required | optional |",
        "|---|---|---|",
    ]
    for shape, (required, optional) in SHAPE_KEYS.items():
        lines.append(f"| `{shape}` | {', '.join(required)} | {', '.join(optional)} |")
    lines += [
        "",
        "## Keys of each crack shape",
        "",
        "| shape | required | optional |",
        "|---|---|---|",
    ]
    for shape, (required, optional) in CRACK_SHAPE_KEYS.items():
        lines.append(f"| `{shape}` | {', '.join(required)} | {', '.join(optional)} |")
    lines += [
        "",
        "## Keys of each load type",
        "",
        "| type | required | optional |",
        "|---|---|---|",
    ]
    for kind, (required, optional) in LOAD_KEYS.items():
        lines.append(f"| `{kind}` | {', '.join(required)} | {', '.join(optional)} |")
    return "\n".join(lines + three_d_keys()) + "\n"


def three_d_keys() -> list[str]:
    """Markdown lines: the keys whose form differs on a 3D mesh (a box, a 3D gmsh file)."""
    from xfem_contact.scenes.schema import (
        FIELDS,
        FIELDS_BY_DIM,
        MATERIAL_MODES,
        PLANE_LOAD_TYPES,
        SHAPES_BY_DIM,
    )

    lines = [
        "",
        "## On a 3D mesh",
        "",
        "A `box` mesh, or a gmsh file with volumes, makes a 3D scene. Its interface shapes are",
        f"{', '.join(f'`{s}`' for s in SHAPES_BY_DIM[3])} (those of 2D,",
        f"{', '.join(f'`{s}`' for s in SHAPES_BY_DIM[2][:-1])}, are refused naming their 3D",
        f"analogues), its material mode {MATERIAL_MODES[3][0]!r} (the plane modes are refused),",
        f"the load types {', '.join(f'`{t}`' for t in PLANE_LOAD_TYPES)} and the option",
        '`kinematics = "large"` are 2D only. Vector values of',
        "loads (`traction`, `body_force`, `displacement`) take three components, and these",
        "keys their 3D form:",
        "",
        "| table | key | type | allowed | meaning |",
        "|---|---|---|---|---|",
    ]
    for table, fields in FIELDS_BY_DIM[3].items():
        for key, field in fields.items():
            if field is FIELDS[table][key]:
                continue
            kind, allowed = _kind(field.check)
            lines.append(
                f"| `{table}` | `{key}` | {_cell(kind)} | {_cell(allowed)} | {_cell(field.doc)} |"
            )
    return lines


def solver_options() -> str:
    from xfem_contact.solvers.options import PRESETS, REFACTOR_AFTER, SOLVER_OPTIONS

    lines = [
        "# Solver options",
        "",
        "Generated from `xfem_contact.solvers.options.SOLVER_OPTIONS` and `PRESETS`. A problem",
        "takes its PETSc options (without prefix) and options prefix at construction, as",
        'DOLFINx\'s problems do: `Problem(..., petsc_options={"snes_rtol": 1e-12},',
        'petsc_options_prefix="mine_")`, or a scene\'s `[solver.petsc]` table. Without a',
        "prefix each problem makes a unique one (`xfem_problem_3_`, ...), so the options of",
        "one problem never leak into another; an empty prefix is refused.",
        "",
        "| option | type | default | solvers | meaning |",
        "|---|---|---|---|---|",
    ]
    for name, option in SOLVER_OPTIONS.items():
        kind = getattr(option.type, "__name__", str(option.type))
        lines.append(
            f"| `{name}` | {kind} | `{option.default!r}` | {', '.join(option.solvers)} | "
            f"{_cell(option.help)}"
            + (f" (one of {option.allowed})" if option.allowed else "")
            + " |"
        )
    lines += [
        "",
        "## Presets",
        "",
        "Every other set of options the solvers use, with what selects it. The rows a",
        "problem adds itself go under the user's options; the sub-solvers' rows are written",
        "under their own prefix unless the options database has them already. A Krylov",
        "method over `pc_type = lu` or `cholesky` in Newton keeps its factorisation while it",
        f"converges within {REFACTOR_AFTER} iterations (`REFACTOR_AFTER`).",
        "",
        "| preset | selected by | options | meaning |",
        "|---|---|---|---|",
    ]
    for name, row in PRESETS.items():
        shown = ", ".join(f"`{row.prefix}{k}={v}`" for k, v in row.options.items()) or "-"
        lines.append(f"| `{name}` | {_cell(row.selected_by)} | {shown} | {_cell(row.help)} |")
    return "\n".join(lines) + "\n"


def problem_defaults() -> str:
    from xfem_contact.mechanics.defaults import DEFAULTS

    lines = [
        "# Problem defaults",
        "",
        "Generated from `xfem_contact.mechanics.defaults.DEFAULTS`, which the constructors,",
        "the scene schema and the documentation read.",
        "",
        "| option | default | meaning |",
        "|---|---|---|",
    ]
    for name, default in DEFAULTS.items():
        value = f"`{default.value!r}`" if default.value is not None else "None"
        lines.append(f"| `{name}` | {value} | {_cell(default.doc)} |")
    return "\n".join(lines) + "\n"


#: Where the generated pages live: in the repository, so that links between pages
#: resolve in a checkout as on the site (``python docs/reference.py`` rewrites them)
FOLDER = pathlib.Path(__file__).resolve().parent / "generated"


def pages(root: pathlib.Path) -> dict[str, str]:
    """The generated pages of the checkout at ``root``: file name to markdown text."""
    found = {
        "scene_reference.md": scene_reference(),
        "solver_options.md": solver_options(),
        "problem_defaults.md": problem_defaults(),
    }
    for demo in sorted((root / "demos").glob("*.py")):
        found[f"demo_{demo.stem}.md"] = demo_page(demo)
    for result in sorted((root / "bench" / "results").glob("*.md")):
        found[f"bench_{result.stem}.md"] = bench_page(result)
    return found


def stale_pages(folder: pathlib.Path = FOLDER) -> list[str]:
    """The file names in ``folder`` that :func:`write` would change, add or delete."""
    wanted = pages(folder.parent.parent)
    stale = [
        name
        for name, text in wanted.items()
        if not (folder / name).exists() or (folder / name).read_text() != text
    ]
    return stale + sorted(p.name for p in folder.glob("*.md") if p.name not in wanted)


def write(folder: pathlib.Path = FOLDER) -> list[str]:
    """Write the generated pages into ``folder`` (created); the names written or deleted."""
    folder.mkdir(parents=True, exist_ok=True)
    wanted = pages(folder.parent.parent)
    changed = []
    for name, text in wanted.items():
        path = folder / name
        if not path.exists() or path.read_text() != text:  # keep Sphinx's cache valid
            path.write_text(text)
            changed.append(name)
    for stale in folder.glob("*.md"):  # pages whose source is gone (a renamed result)
        if stale.name not in wanted:
            stale.unlink()
            changed.append(stale.name)
    return changed


def demo_page(path: pathlib.Path) -> str:
    """A demo (jupytext percent format) as a page: its docstring, then its markdown
    cells as text and its code cells as code, in order."""
    source = path.read_text()
    tree = ast.parse(source)
    docstring = ast.get_docstring(tree) or path.stem
    title, _, rest = docstring.partition("\n")
    lines = [f"# {title}", "", rest.strip(), "", f"Source: `demos/{path.name}`.", ""]
    body = source[source.index('"""', source.index('"""') + 3) + 3 :]
    for cell in body.split("# %%")[1:]:
        if cell.startswith(" [markdown]"):
            text = [line[2:] if line.startswith("# ") else "" for line in cell.splitlines()[1:]]
            lines += ["\n".join(text).strip(), ""]
        elif code := cell.strip("\n"):
            lines += ["```python", code, "```", ""]
    return "\n".join(lines)


def builtin_parts() -> list[str]:
    """Markdown lines: the built-in boundary parts of each mesh kind."""
    from xfem_contact.scenes.schema import BUILTIN_PARTS

    lines = [
        "## Built-in boundary parts",
        "",
        "A load's `part` names a built-in part of the mesh kind, a part of `[parts.NAME]`",
        "(a boolean expression of the coordinates), or, for a gmsh mesh, a named physical",
        "group of dimension d - 1 of the file (curves in 2D, surfaces in 3D). Any other name",
        "is an error listing the known ones.",
        "",
        "| mesh kind | part | selects |",
        "|---|---|---|",
    ]
    for kind, names in BUILTIN_PARTS.items():
        for name in names:
            lines.append(f"| `{kind}` | `{name}` | {PART_MEANINGS[name]} |")
        if kind == "gmsh":
            group = "any physical curve's (surface's in 3D) name"
            lines.append(f"| `gmsh` | {group} | the facets of that group |")
    return [*lines, ""]


def expression_functions() -> list[str]:
    """Markdown lines: the functions and names allowed in scene expressions, found by
    compiling a call of each (the number of arguments, and whether loads take it)."""
    from xfem_contact.scenes.expressions import ALLOWED_NAMES, MAX_EXPONENT, compile_expression

    def accepts(text: str, loads: bool) -> bool:
        try:
            compile_expression(text, loads=loads)
        except ValueError:
            return False
        return True

    lines = [
        "## Expressions",
        "",
        'Level sets (`shape = "expression"`), part locators (`where`), prescribed',
        "displacements and load values may be expressions of the coordinates `x`, `y` (and",
        "`z` on a 3D mesh; on a 2D one it is an error) (m): Python arithmetic",
        f"(`+ - * / **`, the exponent of `**` a number of size at most {MAX_EXPONENT}) on",
        "numbers, the coordinates, the constant `pi` and the functions below.",
        "Locators also take comparisons and `& | ~`. Loads (pressure, traction, body force",
        "values) are evaluated by UFL and take only the functions marked so. Anything else",
        "is an error naming the allowed names.",
        "",
        "| function | arguments | in loads | meaning |",
        "|---|---|---|---|",
    ]
    for name in sorted(ALLOWED_NAMES - {"x", "y", "z", "pi"}):
        arity = next(k for k in (1, 2, 3) if accepts(f"{name}({', '.join(['x'] * k)})", False))
        in_loads = "yes" if accepts(f"{name}({', '.join(['x'] * arity)})", True) else ""
        lines.append(f"| `{name}` | {arity} | {in_loads} | {FUNCTION_MEANINGS[name]} |")
    return [*lines, ""]


def _bench_script(result: pathlib.Path) -> pathlib.Path:
    """The script that wrote ``result``: ``bench/NAME.py`` or ``bench/PREFIX.py`` for the
    longest ``PREFIX_`` that ``NAME`` starts with (``NAME.py`` if there is none)."""
    words = result.stem.split("_")
    for k in range(len(words), 0, -1):
        script = result.parents[1] / ("_".join(words[:k]) + ".py")
        if script.exists():
            return script
    return result.parents[1] / f"{result.stem}.py"


def bench_page(result: pathlib.Path) -> str:
    """The page of one benchmark result ``bench/results/NAME.md``: the bench script's
    docstring (its first paragraph), the command, the table and the pictures
    (``NAME.png``, ``NAME_*.png``). The
    script is ``bench/NAME.py`` or, for a second result of one script (``--name``),
    the one whose name ``NAME`` starts with (``iterative_large``: ``iterative.py``)."""
    script = _bench_script(result)
    docstring = ast.get_docstring(ast.parse(script.read_text())) if script.exists() else None
    text = re.sub(r":\w+:`~?([^`]+)`", r"`\1`", (docstring or "").replace("``", "`"))
    paragraphs = [" ".join(p.split()) for p in text.split("\n\n")]
    title = paragraphs[0] if paragraphs[0] else result.stem.replace("_", " ")
    about = paragraphs[1] if len(paragraphs) > 1 else ""
    lines = [f"# {title.rstrip('.')}", ""]
    if about:
        lines += [about, ""]
    lines += [
        f"Made by `python bench/{script.name}` (`make bench` runs every bench); the",
        f"numbers are in `bench/results/{result.stem}.json`. Generated from",
        f"`bench/results/{result.name}` by `python docs/reference.py`.",
        "",
        "```{include} ../../bench/results/" + result.name,
        "```",
        "",
    ]
    pictures = [
        *result.parent.glob(f"{result.stem}.png"),
        *result.parent.glob(f"{result.stem}_*.png"),
    ]
    for picture in sorted(pictures):
        lines += [f"![{picture.stem}](../../bench/results/{picture.name})", ""]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Write the generated documentation pages.")
    parser.add_argument(
        "--check", action="store_true", help="write nothing; exit 1 if a page is stale"
    )
    args = parser.parse_args(argv)
    if args.check:
        stale = stale_pages()
        if stale:
            print(
                f"stale generated pages in docs/generated: {', '.join(stale)}: run "
                "`python docs/reference.py`",
                file=sys.stderr,
            )
            return 1
        return 0
    for name in write():
        print(f"wrote docs/generated/{name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
