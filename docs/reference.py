"""Pages generated from the code for the documentation: the scene file reference
(every table and key of :data:`xfem_contact.scenes.schema.FIELDS`: type, allowed
values, default, meaning) and the solver options
(:data:`xfem_contact.solvers.options.SOLVER_OPTIONS`).

Defaults of scene keys are read from the loader's source (``table.get("key", default)``
calls), not typed twice.
"""

from __future__ import annotations

import ast
import inspect
import pathlib


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
        return f"{check.target} or expression of x, y", ""
    return getattr(check, "__name__", name), ""


def _cell(text) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def scene_reference() -> str:
    from xfem_contact.scenes.schema import FIELDS, LOAD_KEYS, SHAPE_KEYS, TOP_LEVEL

    found = _defaults()
    keys = [key for fields in FIELDS.values() for key in fields]
    # a key of several tables (name, centre, ...) has no single default to read off
    defaults = {k: v for k, v in found.items() if keys.count(k) == 1}
    lines = [
        "# Scene file reference",
        "",
        "Generated from `xfem_contact.scenes.schema.FIELDS` at every documentation build.",
        f"Top-level tables: {', '.join(f'`[{t}]`' for t in TOP_LEVEL)}. A key not listed",
        "here is an error naming the valid keys; a bad value is an error naming the key and",
        "the valid choices (one line, exit status 2 from the command line).",
        "",
    ]
    toml = {
        "interface": "[[interfaces]] (each entry)",
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
        "## Keys of each load type",
        "",
        "| type | required | optional |",
        "|---|---|---|",
    ]
    for kind, (required, optional) in LOAD_KEYS.items():
        lines.append(f"| `{kind}` | {', '.join(required)} | {', '.join(optional)} |")
    return "\n".join(lines) + "\n"


def solver_options() -> str:
    from xfem_contact.solvers.options import LINEAR_PRESETS, SOLVER_OPTIONS

    lines = [
        "# Solver options",
        "",
        "Generated from `xfem_contact.solvers.options.SOLVER_OPTIONS`. Every solver runs",
        "under a unique PETSc options prefix (`xfem_newton_3_`, ...), so options given to",
        "one solve never leak into another; pass them without prefix, e.g.",
        '`problem.solve({"snes_rtol": 1e-12})`, or in a scene\'s `[solver.petsc]` table.',
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
    lines += ["", "## Linear solver presets (`[solver] linear`)", ""]
    for name, options in LINEAR_PRESETS.items():
        shown = ", ".join(f"`{k}={v}`" for k, v in options.items()) or "MUMPS LU (the defaults)"
        lines.append(f"- `{name}`: {shown}")
    return "\n".join(lines) + "\n"


def write(folder: pathlib.Path) -> None:
    """Write the generated pages into ``folder`` (created)."""
    folder.mkdir(parents=True, exist_ok=True)
    pages = {"scene_reference.md": scene_reference(), "solver_options.md": solver_options()}
    for demo in sorted((folder.parent.parent / "demos").glob("*.py")):
        pages[f"demo_{demo.stem}.md"] = demo_page(demo)
    for name, text in pages.items():
        path = folder / name
        if not path.exists() or path.read_text() != text:  # keep Sphinx's cache valid
            path.write_text(text)


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
