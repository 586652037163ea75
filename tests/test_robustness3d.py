"""A short sweep of random inclusions with each contact law (bench/robustness3d.py runs
the long one): a sphere and an ellipsoid on P2 tetrahedra, n = 4; every solve converges in
at most 15 Newton iterations with no NaN and no error raised (Coulomb with mu = 0.1,
which slips: 5 and 6), and where the solution is the uniform stress its pressure error
is small (measured: spheres 4e-6 to 7e-6, the cut rules' quadrature error alone, 1.4e-4
before shallow boxes were subdivided; ellipsoids 3e-5 to 2e-2)."""

import importlib.util
import pathlib

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("robustness3d", ROOT / "bench" / "robustness3d.py")
robustness3d = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(robustness3d)


def test_short_sweep_of_random_inclusions():
    rows = []
    for index, placement in enumerate(robustness3d.placements(2, seed=0)):
        for law in robustness3d.LAWS:
            rows.append(robustness3d.run(placement, law, n=4, degree=2) | {"index": index})
    table = robustness3d.report(rows)
    print({law: (t["histogram"], t["max error"]) for law, t in table.items()})
    for r in rows:
        assert r["raised"] is None and r["converged"] and not r["nan"], r
        assert r["iterations"] <= robustness3d.MAX_ITERATIONS, r
        if r["law"] in robustness3d.EXACT:
            assert r["error"] < (5e-5 if r["shape"] == "sphere" else 5e-2), r
    assert all(np.isfinite(t["median error"]) for t in table.values())
    assert table["slipping"]["histogram"], table


def test_stalled_coulomb_solve_restarts_with_another_augmentation():
    """The one inclusion of the bench's slipping sweep (n = 4, seed 0) on which Newton
    cycles with period 4 at the default augmentation (its residual stays near 1e-3, on the
    multiplier of a vertex whose shape function barely reaches the interface; line
    searches stall there too): it stalls after 8 iterations and converges in 5 more with
    the augmentation doubled, with a warning saying so."""
    placement = robustness3d.placements(92, seed=0)[91]
    row = robustness3d.run(placement, "slipping", n=4, degree=2)
    assert row["raised"] is None and row["converged"], row
    assert row["iterations"] <= robustness3d.MAX_ITERATIONS, row
    assert any(w.startswith("AugmentationWarning") for w in row["warnings"]), row
