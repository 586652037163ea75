"""The package layout: layered imports, module sizes, the root, and the generated docs.

Every module of ``xfem_contact`` is parsed with :mod:`ast` (nothing is imported). The
layer order, the size limits and the module table live in ``docs/layout.py``.
"""

import ast
import importlib.util
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("layout", ROOT / "docs" / "layout.py")
layout = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(layout)

PACKAGE = layout.PACKAGE
LAYERS = layout.LAYERS
MODULES = layout.modules(ROOT)


def imported_modules(tree: ast.AST, module: str, is_package: bool) -> list[tuple[int, str]]:
    """``(line, dotted name)`` of every import in ``tree``, at any depth (functions,
    classes, ``if TYPE_CHECKING:``), relative ones resolved against ``module``; for
    ``from a import b`` both ``a`` and ``a.b`` (``b`` may be a sub-module; only ``a.b``
    when ``a`` is the package itself), and the constant argument of
    ``importlib.import_module`` / ``__import__`` calls."""
    here = module.split(".") if is_package else module.split(".")[:-1]
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = here[: len(here) - node.level + 1]
                name = ".".join(base + ([node.module] if node.module else []))
            else:
                name = node.module
            if name != PACKAGE:  # ``from xfem_contact import x`` imports only ``x``
                found.append((node.lineno, name))
            found += [(node.lineno, f"{name}.{alias.name}") for alias in node.names]
        elif (
            isinstance(node, ast.Call)
            and (
                (isinstance(node.func, ast.Attribute) and node.func.attr == "import_module")
                or (
                    isinstance(node.func, ast.Name)
                    and node.func.id in ("import_module", "__import__")
                )
            )
            and node.args
            and isinstance(node.args[0], ast.Constant)
            and isinstance(node.args[0].value, str)
        ):
            found.append((node.lineno, node.args[0].value))
    return found


def layer_violations(relative: str, source: str) -> list[str]:
    """The imports of the module at ``relative`` (a path like ``xfem_contact/fem/forms.py``)
    that break the layering: a sub-package may import itself and the sub-packages before
    it in ``LAYERS``, never a later step nor the names of the package root (the public
    face, free to import any step), except the private root modules (``_version``,
    ``_bootstrap``: plumbing below every step). Modules at the root may import anything."""
    parts = pathlib.PurePosixPath(relative).with_suffix("").parts
    is_package = parts[-1] == "__init__"
    parts = parts[:-1] if is_package else parts
    if len(parts) < 2 + (not is_package):  # a module at the package root
        return []
    step = parts[1]
    if step not in LAYERS:
        return [f"{relative}: sub-package {step!r} is not a step of LAYERS in docs/layout.py"]
    allowed = set(LAYERS[: LAYERS.index(step) + 1])
    bad = {}  # one per import statement and step: (line, step) -> message
    tree = ast.parse(source, filename=relative)
    for line, name in imported_modules(tree, ".".join(parts), is_package):
        top = name.split(".")
        if top[0] != PACKAGE:
            continue
        if len(top) > 1 and top[1].startswith("_") and top[1] not in ("__init__",):
            continue  # private root modules (_version, _bootstrap): below every step
        if len(top) == 1 or top[1] not in LAYERS:  # the root, its modules or its names
            message = f"{relative}:{line}: {step} imports {name} from the package root"
            bad.setdefault((line, None), message)
        elif top[1] not in allowed:
            message = f"{relative}:{line}: {step} imports {name} (a higher step)"
            bad.setdefault((line, top[1]), message)
    return [bad[key] for key in sorted(bad, key=lambda key: (key[0], key[1] or ""))]


def relative(path: pathlib.Path) -> str:
    return path.relative_to(ROOT).as_posix()


def test_the_modules_are_found():
    assert len(MODULES) > 40
    assert {layout.layer(p, ROOT) for p in MODULES} >= set(LAYERS)


def test_every_sub_package_is_a_step():
    found = {layout.layer(p, ROOT) for p in MODULES} - {None}
    assert found <= set(LAYERS), f"not in LAYERS of docs/layout.py: {sorted(found - set(LAYERS))}"
    for step in LAYERS:
        assert (ROOT / PACKAGE / step / "__init__.py").is_file(), step


def test_sub_packages_import_only_lower_steps():
    bad = [v for p in MODULES for v in layer_violations(relative(p), p.read_text("utf-8"))]
    order = " < ".join(LAYERS)
    assert not bad, f"imports against the layering ({order}):\n" + "\n".join(bad)


def long_modules(lines: dict[str, int], allowed: dict[str, tuple[int, str]]) -> dict[str, int]:
    """The modules of ``lines`` (path -> line count) over ``LONG_MODULE_LINES`` that
    ``allowed`` does not list, or lists with fewer lines or no reason."""
    return {
        path: n
        for path, n in lines.items()
        if n > layout.LONG_MODULE_LINES
        and not (path in allowed and n <= allowed[path][0] and allowed[path][1].strip())
    }


def test_long_modules_are_listed_with_a_reason():
    lines = {relative(p): len(p.read_text("utf-8").splitlines()) for p in MODULES}
    long = long_modules(lines, layout.LONG_MODULES)
    assert not long, (
        f"modules over {layout.LONG_MODULE_LINES} lines: split them by concept, or list them in"
        f" LONG_MODULES of docs/layout.py with the reason they are one concept: {long}"
    )
    stale = sorted(set(layout.LONG_MODULES) - set(lines))
    assert not stale, f"LONG_MODULES lists modules that do not exist: {stale}"


def test_the_size_check_catches_unlisted_long_modules():
    limit = layout.LONG_MODULE_LINES
    lines = {"a.py": limit, "b.py": limit + 1, "c.py": limit + 50, "d.py": limit + 9}
    allowed = {"c.py": (limit + 60, "one state machine"), "d.py": (limit + 5, "x")}
    assert long_modules(lines, allowed) == {"b.py": limit + 1, "d.py": limit + 9}
    assert long_modules({"c.py": limit + 50}, {"c.py": (limit + 60, " ")}) == {"c.py": limit + 50}


def test_the_package_root_keeps_few_modules():
    root = sorted(p.name for p in MODULES if layout.layer(p, ROOT) is None)
    assert "__init__.py" in root
    assert len(root) <= layout.MAX_ROOT_MODULES, root


def test_the_module_tables_are_current():
    check = subprocess.run(
        [sys.executable, str(ROOT / "docs" / "layout.py"), "--check"],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert check.returncode == 0, check.stderr + check.stdout


@pytest.mark.parametrize(
    "path, source, expected",
    [
        (
            "xfem_contact/geometry/cut.py",
            "import numpy\nfrom xfem_contact.geometry import roots",
            0,
        ),
        ("xfem_contact/fem/forms.py", "from xfem_contact.codegen import LANGUAGE", 0),
        ("xfem_contact/geometry/cut.py", "from xfem_contact.fem.cutmesh import CutMesh", 1),
        ("xfem_contact/codegen/tables.py", "import xfem_contact.geometry.cut", 1),
        ("xfem_contact/fem/forms.py", "def f():\n    from xfem_contact.scenes import run", 1),
        ("xfem_contact/fem/forms.py", "from xfem_contact import scenes", 1),
        ("xfem_contact/fem/forms.py", "from xfem_contact import CutMesh", 1),
        ("xfem_contact/fem/forms.py", "import xfem_contact", 1),
        ("xfem_contact/solvers/linear.py", "from ..mechanics import materials", 1),
        ("xfem_contact/solvers/linear.py", "from . import newton\nfrom ..fem import forms", 0),
        ("xfem_contact/io/__init__.py", "from .pictures import plot_cut", 0),
        ("xfem_contact/io/__init__.py", "from ..cases import paper", 1),
        ("xfem_contact/mechanics/laws/coulomb.py", "from xfem_contact.io import output", 1),
        ("xfem_contact/mechanics/laws/coulomb.py", "from ...solvers import newton", 0),
        ("xfem_contact/fem/forms.py", "importlib.import_module('xfem_contact.scenes.cli')", 1),
        ("xfem_contact/notastep/x.py", "import numpy", 1),
        ("xfem_contact/__init__.py", "from xfem_contact.scenes import cli", 0),
    ],
)
def test_the_layering_check_catches_forbidden_imports(path, source, expected):
    assert len(layer_violations(path, source)) == expected, layer_violations(path, source)


def test_a_stale_table_fails_the_check(tmp_path):
    for target in layout.TARGETS:
        (tmp_path / target).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / target).write_text(f"# x\n{layout.START}\nold\n{layout.END}\n")
    (tmp_path / PACKAGE / "geometry").mkdir(parents=True)
    (tmp_path / PACKAGE / "__init__.py").write_text('"""The root."""\n')
    (tmp_path / PACKAGE / "geometry" / "__init__.py").write_text('"""Shapes: ``phi``."""\n')
    assert layout.main(["--check"], root=tmp_path) == 1
    assert layout.main([], root=tmp_path) == 0
    assert layout.main(["--check"], root=tmp_path) == 0
    text = (tmp_path / layout.TARGETS[0]).read_text()
    assert "| `xfem_contact.geometry` | `__init__.py` | Shapes: `phi`. |" in text
    assert text.startswith("# x\n") and text.endswith(f"{layout.END}\n")
