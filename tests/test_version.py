"""One version (pyproject.toml's), reported with the stack's by versions() and
``xfem-contact --version``."""

import importlib.metadata
import importlib.util
import pathlib
import shutil
import tomllib

import pytest

import xfem_contact
from xfem_contact.scenes.cli import main

ROOT = pathlib.Path(__file__).resolve().parent.parent
PYPROJECT_VERSION = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
NAMES = ["xfem-contact", "dolfinx", "basix", "ffcx", "ufl", "petsc", "python"]


def test_version_is_pyprojects():
    assert xfem_contact.__version__ == PYPROJECT_VERSION


def test_version_outside_a_checkout_from_metadata(tmp_path):
    """A copy of _version.py with no pyproject.toml beside its package: installed
    metadata, or 0+unknown when xfem-contact is not installed."""
    (tmp_path / "pkg").mkdir()
    shutil.copy(ROOT / "xfem_contact" / "_version.py", tmp_path / "pkg" / "_version.py")
    spec = importlib.util.spec_from_file_location("v", tmp_path / "pkg" / "_version.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    try:
        expected = importlib.metadata.version("xfem-contact")
    except importlib.metadata.PackageNotFoundError:
        expected = "0+unknown"
    assert module.package_version() == expected


def test_versions():
    import dolfinx

    found = xfem_contact.versions()
    assert list(found) == NAMES
    assert found["xfem-contact"] == PYPROJECT_VERSION
    assert found["dolfinx"] == dolfinx.__version__
    assert all(isinstance(v, str) and v[0].isdigit() for v in found.values()), found


def test_cli_version(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0
    lines = dict(line.split(maxsplit=1) for line in capsys.readouterr().out.splitlines())
    assert list(lines) == NAMES
    assert lines["xfem-contact"] == PYPROJECT_VERSION
    assert lines == {k: str(v) for k, v in xfem_contact.versions().items()}
