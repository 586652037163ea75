"""The wheel is a working package on its own, not only the source tree.

``pip wheel`` builds it from a copy of the project's files (offline: no build
isolation, no dependencies); the test
checks what it carries (package, bundled scenes and ``.geo`` files, the start-up
hook, the console script) and runs the installed copy, with this venv's
dependencies but none of the source tree: ``xfem-contact scenes``, ``--version`` and
``run case2_sticking_inclusion``.
"""

import os
import pathlib
import shutil
import subprocess
import sys
import zipfile

import pytest

import xfem_contact

ROOT = pathlib.Path(__file__).resolve().parents[1]
SCENES = sorted(
    p.name for p in (ROOT / "xfem_contact" / "scenes").iterdir() if p.suffix in (".toml", ".geo")
)


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """``(wheel, target)``: the wheel and a directory it is installed into."""
    out = tmp_path_factory.mktemp("wheel")
    # Build from a copy of the project's files: no stale build/ of an earlier build
    # can slip into the wheel, and the tree is left as it was
    source = out / "source"
    files = subprocess.run(
        ["git", "ls-files", "-co", "--exclude-standard"],
        cwd=ROOT,
        check=True,
        capture_output=True,
        text=True,
    ).stdout.split()
    for name in files:
        if (ROOT / name).is_file():
            (source / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / name, source / name)
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check", "-q"]
    subprocess.run(
        [*pip, "wheel", "--no-deps", "--no-build-isolation", "-w", str(out), str(source)],
        check=True,
        capture_output=True,
        cwd=out,
    )
    (wheel,) = out.glob("xfem_contact-*.whl")
    target = out / "site"
    subprocess.run(
        [*pip, "install", "--no-deps", "--target", str(target), str(wheel)],
        check=True,
        capture_output=True,
    )
    return wheel, target


def _run(target: pathlib.Path, *args: str, cwd) -> str:
    """Run Python on the installed copy (PYTHONPATH beats the editable install)."""
    env = os.environ | {"PYTHONPATH": str(target)}
    result = subprocess.run(
        [sys.executable, *args], env=env, cwd=cwd, capture_output=True, text=True, timeout=600
    )
    assert result.returncode == 0, result.stdout + result.stderr
    return result.stdout


def test_wheel_contents(installed):
    wheel, _ = installed
    names = zipfile.ZipFile(wheel).namelist()
    for scene in SCENES:
        assert f"xfem_contact/scenes/{scene}" in names
    assert "xfem_contact-dolfinx-solver.pth" in names  # the import-order hook
    assert "_xfem_contact_dolfinx_solver.py" in names
    entry_points = next(n for n in names if n.endswith("entry_points.txt"))
    text = zipfile.ZipFile(wheel).read(entry_points).decode()
    assert "xfem-contact = xfem_contact.scenes.cli:main" in text
    assert not any(n.startswith(("tests/", "bench/", "demos/")) for n in names)


def test_installed_copy_runs(installed, tmp_path):
    _, target = installed
    where = _run(target, "-c", "import xfem_contact; print(xfem_contact.__file__)", cwd=tmp_path)
    assert pathlib.Path(where.strip()).is_relative_to(target)  # not the source tree
    cli = ["-m", "xfem_contact.scenes.cli"]
    listed = _run(target, *cli, "scenes", cwd=tmp_path)
    assert "case2_sticking_inclusion" in listed and "plate_with_hole_inclusion" in listed
    assert xfem_contact.__version__ in _run(target, *cli, "--version", cwd=tmp_path)
    _run(target, *cli, "run", "case2_sticking_inclusion", "--out", "out", cwd=tmp_path)
    assert (tmp_path / "out" / "summary.json").is_file()
