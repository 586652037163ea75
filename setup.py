"""Build steps that pyproject.toml cannot declare: the start-up hook.

Everything else (metadata, packages, package data) is in pyproject.toml.

Two files go into site-packages: ``xfem_contact-dolfinx-solver.pth``, whose one
``import`` line Python runs at every start-up, and the module it imports,
``_xfem_contact_dolfinx_solver.py``, a copy of ``xfem_contact/_bootstrap.py``:
its ``install()`` puts a meta path finder on ``sys.meta_path`` that imports
``dolfinx_solver`` before the first import of ``dolfinx``, so that ``import dolfinx``
works before ``import xfem_contact`` with the PyPI wheel ``dolfinx-solver-real``
(see that module). A module rather than code in the ``.pth`` line: pip
byte-compiles it, and importing it costs less than compiling its source at
every start-up.

* Regular wheels (``pip install .``, ``pip wheel .``): ``build_py`` writes both
  files at the root of ``build_lib``, the root of the wheel, which pip unpacks
  into site-packages.
* Editable installs (``pip install -e .``): setuptools (>= 64) builds an editable
  wheel from its own ``.pth`` file and import finder, and drops whatever build
  commands write into ``build_lib``. ``editable_wheel`` below adds both files to
  that wheel through the strategy object setuptools writes its own ``.pth`` with
  (``_select_strategy``, internal to setuptools, there since setuptools 64).
  Should a later setuptools stop calling it, the build fails instead of
  installing without the hook.

Both files are copies taken at install time, in editable installs too: after
editing ``_bootstrap.py``, reinstall (the Makefile reinstalls when pyproject.toml
changes).
"""

from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py as _build_py
from setuptools.command.editable_wheel import editable_wheel as _editable_wheel

PTH_NAME = "xfem_contact-dolfinx-solver.pth"
MODULE = "_xfem_contact_dolfinx_solver"
SOURCE = Path(__file__).resolve().parent / "xfem_contact" / "_bootstrap.py"


def hook_files() -> dict[str, str]:
    """File name -> text of the files that go into site-packages."""
    pth = (
        "# xfem-contact: import dolfinx_solver before the first import of dolfinx\n"
        "# (PyPI wheel dolfinx-solver-real); source: xfem_contact/_bootstrap.py\n"
        f"import {MODULE}; {MODULE}.install()\n"
    )
    return {PTH_NAME: pth, f"{MODULE}.py": SOURCE.read_text(encoding="utf-8")}


class build_py(_build_py):
    """Also writes the start-up hook at the root of ``build_lib`` (regular wheels)."""

    def run(self):
        super().run()
        if not self.editable_mode:
            self.mkpath(self.build_lib)
            for name, text in hook_files().items():
                Path(self.build_lib, name).write_text(text, encoding="utf-8")

    def get_outputs(self, include_bytecode=True):
        outputs = list(super().get_outputs(include_bytecode))
        if not self.editable_mode:
            outputs += [str(Path(self.build_lib, name)) for name in hook_files()]
        return outputs


class _WithStartupHook:
    """Wraps setuptools' editable strategy: writes its files, then the hook."""

    def __init__(self, strategy):
        self.strategy, self.written = strategy, False

    def __enter__(self):
        self.strategy.__enter__()
        return self

    def __exit__(self, *exc):
        return self.strategy.__exit__(*exc)

    def __call__(self, wheel, files, mapping):
        self.strategy(wheel, files, mapping)
        for name, text in hook_files().items():
            wheel.writestr(name, text.encode("utf-8"))
        self.written = True


class editable_wheel(_editable_wheel):
    """Adds the start-up hook to the editable wheel (see the module docstring)."""

    def _select_strategy(self, *args, **kwargs):
        self._hook = _WithStartupHook(super()._select_strategy(*args, **kwargs))
        return self._hook

    def run(self):
        self._hook = None
        super().run()
        if self._hook is None or not self._hook.written:
            raise RuntimeError(
                f"setuptools built the editable wheel without calling the strategy that "
                f"adds {PTH_NAME}: `import dolfinx` before `import xfem_contact` would fail. "
                "Adapt setup.py to this setuptools version."
            )


setup(cmdclass={"build_py": build_py, "editable_wheel": editable_wheel})
