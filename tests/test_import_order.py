"""``import dolfinx`` works before ``import xfem_contact``.

With the PyPI wheel dolfinx-solver-real, ``import dolfinx`` fails with
``libmpi.so.12: cannot open shared object file`` unless ``dolfinx_solver`` is
imported first; the start-up hook that xfem-contact installs into site-packages
(``xfem_contact-dolfinx-solver.pth``, see ``xfem_contact/_bootstrap.py``) does that.
Each check runs a fresh interpreter: in this process xfem_contact (conftest) has
long imported DOLFINx.
"""

import importlib.util
import pathlib
import subprocess
import sys
import textwrap

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
BOOTSTRAP = ROOT / "xfem_contact" / "_bootstrap.py"
HOOK_MODULE = "_xfem_contact_dolfinx_solver"
HOOK_PTH = "xfem_contact-dolfinx-solver.pth"


def python(code: str, *flags: str, cwd: pathlib.Path) -> subprocess.CompletedProcess:
    """Run ``code`` in a fresh interpreter (this venv's) from ``cwd``."""
    return subprocess.run(
        [sys.executable, *flags, "-c", textwrap.dedent(code)],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=300,
    )


def hook_hint() -> str:
    spec = importlib.util.find_spec(HOOK_MODULE)
    where = spec.origin if spec else "nowhere on sys.path"
    return (
        f"\n(start-up hook module {HOOK_MODULE}: {where}; a missing hook means xfem-contact "
        "was not installed with pip from this checkout: pip install -e '.[test]')"
    )


def test_dolfinx_first(tmp_path):
    """The user's order: DOLFINx, UFL, dolfinx.fem.petsc, then xfem_contact last."""
    result = python(
        """
        import dolfinx, ufl
        import dolfinx.fem.petsc
        from mpi4py import MPI

        mesh = dolfinx.mesh.create_unit_square(MPI.COMM_SELF, 2, 2)
        V = dolfinx.fem.functionspace(mesh, ("Lagrange", 1))
        u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
        A = dolfinx.fem.petsc.assemble_matrix(dolfinx.fem.form(u * v * ufl.dx))
        A.assemble()
        import xfem_contact
        print(dolfinx.__version__, A.getSize())
        """,
        cwd=tmp_path,
    )
    assert result.returncode == 0, result.stderr + hook_hint()
    assert "(9, 9)" in result.stdout


@pytest.mark.parametrize("module", ["petsc4py.PETSc", "slepc4py.SLEPc"])
def test_other_wheel_modules_first(tmp_path, module):
    """petsc4py and slepc4py come with the same wheel and need the same order."""
    if importlib.util.find_spec(module.split(".")[0]) is None:
        pytest.skip(f"{module} is not installed")
    result = python(f"import {module}; import dolfinx", cwd=tmp_path)
    assert result.returncode == 0, result.stderr + hook_hint()


def test_hook_is_lazy(tmp_path):
    """At start-up the hook only inserts its finder: no dolfinx_solver, no MPI."""
    result = python(
        """
        import sys
        finders = [getattr(f, "__name__", "") for f in sys.meta_path]
        print("DolfinxSolverFirst" in finders, "dolfinx_solver" in sys.modules,
              "mpi4py" in sys.modules)
        """,
        cwd=tmp_path,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["True", "False", "False"], result.stdout + hook_hint()


def test_installed_hook_is_current():
    """The installed hook is a copy of xfem_contact/_bootstrap.py taken at install time."""
    spec = importlib.util.find_spec(HOOK_MODULE)
    assert spec is not None, hook_hint()
    installed = pathlib.Path(spec.origin)
    assert (installed.parent / HOOK_PTH).is_file(), f"{HOOK_PTH} missing beside {installed}"
    assert installed.read_text() == BOOTSTRAP.read_text(), (
        f"{installed} differs from {BOOTSTRAP}: reinstall (pip install -e '.[test]')"
    )


# -- the finder itself, on fake modules (no MPI, no site-packages: python -S) --------


def fake_stack(tmp_path, dolfinx_solver: str | None) -> pathlib.Path:
    """A directory with a fake ``dolfinx`` that records whether ``dolfinx_solver``
    was imported before it, and optionally a fake ``dolfinx_solver``."""
    (tmp_path / "dolfinx").mkdir(parents=True)
    (tmp_path / "dolfinx" / "__init__.py").write_text(
        "import sys\nSOLVER_FIRST = 'dolfinx_solver' in sys.modules\n"
    )
    if dolfinx_solver is not None:
        (tmp_path / "dolfinx_solver.py").write_text(dolfinx_solver)
    return tmp_path


RUN_FINDER = f"""
import importlib.util, sys
sys.path[:0] = [{{path!r}}]
spec = importlib.util.spec_from_file_location("boot", {str(BOOTSTRAP)!r})
boot = importlib.util.module_from_spec(spec)
spec.loader.exec_module(boot)
boot.install()
import dolfinx
left = any(getattr(f, "__name__", "") == "DolfinxSolverFirst" for f in sys.meta_path)
print(dolfinx.SOLVER_FIRST, left)
"""


def test_finder_imports_dolfinx_solver_first(tmp_path):
    path = fake_stack(tmp_path, dolfinx_solver="")
    result = python(RUN_FINDER.format(path=str(path)), "-S", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["True", "False"]  # solver first, finder gone


def test_finder_harmless_without_dolfinx_solver(tmp_path):
    """conda/apt DOLFINx: no dolfinx_solver, dolfinx imports as without the hook."""
    path = fake_stack(tmp_path, dolfinx_solver=None)
    result = python(RUN_FINDER.format(path=str(path)), "-S", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["False", "False"]


def test_finder_passes_on_dolfinx_solver_errors(tmp_path):
    """dolfinx_solver's own refusal (e.g. a foreign petsc4py) reaches the user."""
    path = fake_stack(tmp_path, dolfinx_solver="raise ImportError('foreign petsc4py')\n")
    result = python(RUN_FINDER.format(path=str(path)), "-S", cwd=tmp_path)
    assert result.returncode != 0
    assert "ImportError: foreign petsc4py" in result.stderr


def test_finder_does_not_hide_the_next_finder(tmp_path):
    """The finder leaves sys.meta_path while the import machinery iterates it: the
    finder after it must still be asked (here the only one that knows dolfinx)."""
    fake_stack(tmp_path / "elsewhere", dolfinx_solver=None)
    code = RUN_FINDER.replace(
        "boot.install()",
        f"""
class Serve:
    @classmethod
    def find_spec(cls, name, path=None, target=None):
        if name == "dolfinx":
            init = {str(tmp_path / "elsewhere" / "dolfinx" / "__init__.py")!r}
            return importlib.util.spec_from_file_location(name, init)
sys.meta_path.insert(0, Serve)
boot.install()
""",
    )
    result = python(code.format(path=str(tmp_path)), "-S", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["False", "False"]
