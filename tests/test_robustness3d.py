"""A short sweep of random inclusions, each contact law once (bench/robustness3d.py runs
the long one, and the inclusion whose Newton cycles until the augmentation restarts):
a sphere and an ellipsoid on P2 tetrahedra, n = 4; every solve converges in at most 15
Newton iterations with no NaN and no error raised (Coulomb with mu = 0.1 slips), and
where the solution is the uniform stress its pressure error is small (measured: spheres
4e-6 to 7e-6, the cut rules' quadrature error alone; ellipsoids 3e-5 to 2e-2)."""

import importlib.util
import pathlib

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("robustness3d", ROOT / "bench" / "robustness3d.py")
robustness3d = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(robustness3d)

pytestmark = pytest.mark.assembly_bound


#: The short sweep's solves: every law once, on a sphere and on an ellipsoid
SHORT = {0: ("sticking", "frictionless"), 1: ("coulomb", "slipping")}


def test_short_sweep_of_random_inclusions():
    rows = []
    for index, placement in enumerate(robustness3d.placements(2, seed=0)):
        for law in SHORT[index]:
            rows.append(robustness3d.run(placement, law, n=4, degree=2) | {"index": index})
    table = robustness3d.report(rows)
    print({law: (t["histogram"], t["max error"]) for law, t in table.items()})
    assert sorted(table) == sorted(robustness3d.LAWS)
    for r in rows:
        assert r["raised"] is None and r["converged"] and not r["nan"], r
        assert r["iterations"] <= robustness3d.MAX_ITERATIONS, r
        if r["law"] in robustness3d.EXACT:
            assert r["error"] < (5e-5 if r["shape"] == "sphere" else 5e-2), r
    assert all(np.isfinite(t["median error"]) for t in table.values())
