"""The version of xfem-contact (one source: pyproject.toml) and of the stack below it."""

from __future__ import annotations

import importlib.metadata
import platform
from pathlib import Path

DISTRIBUTION = "xfem-contact"
#: Reported when neither a checkout's pyproject.toml nor installed metadata is found
UNKNOWN = "0+unknown"


def package_version() -> str:
    """The version in pyproject.toml.

    Imported from a source checkout (an editable install, or the checkout on
    ``PYTHONPATH``), read from the checkout's pyproject.toml: the metadata of an
    editable install is a copy taken at install time, and the metadata found on
    ``sys.path`` may belong to another installed copy. Otherwise (a wheel
    install) from the installed metadata, which the build wrote from
    pyproject.toml. ``"0+unknown"`` when there is neither.
    """
    pyproject = Path(__file__).resolve().parent.parent / "pyproject.toml"
    if pyproject.is_file():
        import tomllib

        try:
            project = tomllib.loads(pyproject.read_text(encoding="utf-8")).get("project", {})
        except (OSError, tomllib.TOMLDecodeError):
            project = {}
        if project.get("name") == DISTRIBUTION and "version" in project:
            return str(project["version"])
    try:
        return importlib.metadata.version(DISTRIBUTION)
    except importlib.metadata.PackageNotFoundError:
        return UNKNOWN


def versions() -> dict[str, str | None]:
    """Versions of xfem-contact, DOLFINx, Basix, FFCx, UFL, PETSc and Python, e.g.
    for a run's summary.json. PETSc is None if petsc4py cannot be imported (a
    DOLFINx built without PETSc). Imports DOLFINx."""
    import basix
    import dolfinx
    import ffcx
    import ufl

    try:
        from petsc4py import PETSc

        petsc = "{}.{}.{}".format(*PETSc.Sys.getVersion())
    except ImportError:
        petsc = None
    return {
        DISTRIBUTION: package_version(),
        "dolfinx": dolfinx.__version__,
        "basix": basix.__version__,
        "ffcx": ffcx.__version__,
        "ufl": ufl.__version__,
        "petsc": petsc,
        "python": platform.python_version(),
    }
