"""A short fuzz of random 3D cuts (bench/cut3d.py runs the long one): spheres, ellipsoids,
tori and planes, a third through a node exactly; every weight positive, the side
volumes adding up to the cell volume to 1e-12 and the interface area exact where it is
known (planes to 1e-10; spheres on their exact zero sets within ``h^2 (h / R)^3``, against
Gauss-Bonnet), with no failure; the P2 / Q2 rules also on the exact zero sets of the
random level sets (CutMesh's exact_zero_set)."""

import importlib.util
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("cut3d_bench", ROOT / "bench" / "cut3d.py")
cut3d = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(cut3d)


@pytest.mark.parametrize(
    "kind, count, exact",
    [
        ("tet-P1", 2000, False),
        ("hex-Q1", 1000, False),
        ("hex-Q2", 500, False),
        ("tet-P2", 500, False),
        ("hex-Q2", 150, True),
        ("tet-P2", 150, True),
    ],
)
def test_fuzz(kind, count, exact):
    counts = cut3d.fuzz_cells(kind, count, seed=7, callable_=exact)
    print(kind, exact, counts)
    assert counts["cut"] > count // 4  # the cases do cut cells
    assert counts["checked"] > count // 5  # and many have a known area
    assert counts["weights"] == counts["volume"] == counts["area"] == counts["errors"] == 0, counts
