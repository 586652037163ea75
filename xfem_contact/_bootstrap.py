"""``import dolfinx`` in any order with the PyPI wheel ``dolfinx-solver-real``.

That wheel ships ``dolfinx``, ``petsc4py`` and ``slepc4py`` whose compiled modules
need ``libmpi.so.12`` already loaded: ``import dolfinx_solver`` must run first (it
refuses a foreign PETSc, then imports ``mpi4py.MPI``, which loads the MPI of the
PyPI ``mpich`` wheel). Otherwise ``import dolfinx`` fails with ``ImportError:
libmpi.so.12: cannot open shared object file``.

:class:`DolfinxSolverFirst` is a meta path finder that waits for the first import
of one of those three modules, removes itself, imports ``dolfinx_solver`` when it
is installed, and lets the import go on. With conda/apt DOLFINx there is no
``dolfinx_solver`` and nothing happens.

It is put on ``sys.meta_path`` at interpreter start-up: ``setup.py`` installs a
copy of this file as the top-level module ``_xfem_contact_dolfinx_solver`` and
``xfem_contact-dolfinx-solver.pth``, whose line ``import
_xfem_contact_dolfinx_solver; _xfem_contact_dolfinx_solver.install()`` Python runs
at every start (regular and editable installs). ``xfem_contact/__init__.py``
calls :func:`load_dolfinx_solver` as well, for interpreters started without the
hook (``python -S``, a checkout on ``PYTHONPATH``).

So this module runs at every interpreter start: it imports nothing but ``sys``
and only inserts the finder; it never imports ``dolfinx_solver`` (slow, and an
``MPI_Init``) unless DOLFINx is imported.
"""

import sys

#: Top-level modules of the wheel that need ``dolfinx_solver`` imported first
WHEEL_MODULES = frozenset({"dolfinx", "petsc4py", "slepc4py"})


def load_dolfinx_solver() -> bool:
    """Import ``dolfinx_solver`` if it is installed; False if it is not.

    Errors of an installed ``dolfinx_solver`` (a foreign petsc4py, no mpi4py)
    propagate: they say what to uninstall, which the ``libmpi.so.12`` error
    that would follow does not.
    """
    try:
        import dolfinx_solver  # noqa: F401
    except ModuleNotFoundError as error:
        if error.name != "dolfinx_solver":
            raise
        return False
    return True


class DolfinxSolverFirst:
    """Meta path finder: imports ``dolfinx_solver`` before the first import of
    ``dolfinx``, ``petsc4py`` or ``slepc4py``, then leaves ``sys.meta_path``."""

    @classmethod
    def find_spec(cls, name, path=None, target=None):
        if path is None and name in WHEEL_MODULES:
            uninstall()
            load_dolfinx_solver()
        return None  # the regular finders import the module itself


def install() -> None:
    """Put the finder first on ``sys.meta_path``, unless it is there already or
    ``dolfinx_solver`` or a wheel module is already imported (then too late or moot)."""
    if "dolfinx_solver" in sys.modules or not WHEEL_MODULES.isdisjoint(sys.modules):
        return
    if not any(getattr(f, "__name__", None) == "DolfinxSolverFirst" for f in sys.meta_path):
        sys.meta_path.insert(0, DolfinxSolverFirst)


def uninstall() -> None:
    """Remove every copy of the finder from ``sys.meta_path`` (the ``.pth`` file
    and this module define distinct classes of that name).

    ``sys.meta_path`` is replaced, not edited in place: the import machinery is
    iterating over the old list while the finder runs, and removing its current
    item would make it skip the next finder.
    """
    sys.meta_path = [
        f for f in sys.meta_path if getattr(f, "__name__", None) != "DolfinxSolverFirst"
    ]
