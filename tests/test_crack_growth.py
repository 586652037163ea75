"""Quasi-static crack growth (mechanics/fracture/growth.py): the kink angle, a polyline
crack's level sets, and an inclined crack under tension that turns towards mode I."""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import math

import numpy as np
import pytest

from xfem_contact.cases.cracks import plate_in_tension
from xfem_contact.mechanics.fracture.growth import (
    GrowthPath,
    grow,
    kink_angle,
    paris_increment,
)


def test_kink_angle():
    assert kink_angle(1.0, 0.0) == 0.0
    # pure mode II: arccos(1/3) = 70.53 degrees, against the sign of K_II
    assert kink_angle(0.0, 1.0) == pytest.approx(-math.acos(1 / 3))
    assert kink_angle(0.0, -1.0) == pytest.approx(math.acos(1 / 3))
    assert kink_angle(1.0, 0.5) < 0 < kink_angle(1.0, -0.5)


def test_polyline_level_sets():
    path = GrowthPath([[-1.0, 0.0], [0.0, 0.0], [1.0, 1.0]])
    x = np.array([[-0.5, 0.5, -2.0, 2.0, 0.5], [0.3, 0.0, -0.2, 2.0, 0.6], [0, 0, 0, 0, 0]])
    phi, psi = path.phi(x), path.psi(x)
    # signed distance to the path (rays beyond its ends), left positive
    assert phi[0] == pytest.approx(0.3)
    assert phi[1] == pytest.approx(-0.5 / math.sqrt(2))
    assert phi[2] == pytest.approx(-0.2)  # beyond the first end: its ray
    assert phi[3] == pytest.approx(0.0, abs=1e-15)  # on the last segment's ray
    # psi: negative along the crack, positive beyond either end
    assert psi[0] < 0 and psi[4] < 0 and psi[2] > 0 and psi[3] > 0
    with pytest.raises(ValueError, match="distinct"):
        GrowthPath([[0.0, 0.0], [0.0, 0.0]])
    with pytest.raises(ValueError, match="da must be a positive length"):
        grow(None, path, 0.0, [(0.1, 0.2)])


def test_inclined_crack_turns_towards_mode_one():
    W, a, angle = 2.0, 0.5, 0.5
    centre = np.array([0.0123, 0.0271])
    d = np.array([math.cos(angle), math.sin(angle)])
    path = GrowthPath([centre - a * d, centre + a * d])
    problem = plate_in_tension(path, 24, tip_radius=0.35, width=W)
    problem.solve()
    ratios = []
    for _ in range(2):
        step = grow(problem, path, 0.34, [(0.25, 0.5)])
        for K, angle in zip(step.K, step.angles, strict=True):
            assert angle == pytest.approx(kink_angle(*K))
        ratios.append(max(abs(K_II / K_I) for K_I, K_II in step.K))
    # the first kink takes most of the mode II away (0.54 -> 0.2)
    assert ratios[1] < 0.5 * ratios[0]
    # the two tips grow symmetrically about the centre
    first, last = path.points[0], path.points[-1]
    assert np.linalg.norm((first - centre) + (last - centre)) < 1e-2
    assert len(path.points) == 6
    with pytest.raises(ValueError, match="out of the body"):
        grow(problem, path, 5.0, [(0.25, 0.5)])
    assert len(path.points) == 6  # the path is left as it was


def test_paris_increment():
    assert paris_increment(10.0, 1e-12, 3.0, 1e5) == pytest.approx(1e-4)
    with pytest.raises(ValueError, match="cycles"):
        paris_increment(10.0, 1e-12, 3.0, -1.0)
