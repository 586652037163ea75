"""Compression of cut-cell rules keeps the moments of degree <= q with positive weights."""

import basix
import numpy as np
import pytest

from xfem_contact.quadrature.compression import compress_rules, num_moments
from xfem_contact.quadrature.cut3d_rules import classify_3d, cut_rules_3d


def monomial_moments(rules, q):
    x, y, z = rules.points.T
    return np.array(
        [
            rules.sums(rules.weights * x**a * y**b * z**c)
            for a in range(q + 1)
            for b in range(q + 1 - a)
            for c in range(q + 1 - a - b)
        ]
    )


@pytest.mark.parametrize("q", [2, 4])
def test_compressed_p2_tet_rules_keep_moments(q):
    element = basix.create_element(
        basix.ElementFamily.P, basix.CellType.tetrahedron, 2, basix.LagrangeVariant.gll_warped
    )
    rng = np.random.default_rng(3)
    centres, radii = rng.uniform(-0.2, 1.2, (40, 3)), rng.uniform(0.3, 1.0, 40)
    phi = ((element.points[None] - centres[:, None]) ** 2).sum(-1) - radii[:, None] ** 2
    phi = phi[classify_3d("tetrahedron", 2, phi) == 0][:2]
    assert phi.shape[0] == 2
    cut = cut_rules_3d("tetrahedron", 2, phi, q)
    for rules in (cut.minus, cut.plus, cut.interface):
        small = compress_rules(rules, q)
        assert (np.diff(small.offsets) <= num_moments(3, q)).all()
        assert np.diff(rules.offsets).max() > num_moments(3, q)  # something was removed
        assert (small.weights > 0).all()
        full, kept = monomial_moments(rules, q), monomial_moments(small, q)
        assert np.abs(kept - full).max() <= 1e-12 * np.abs(full).max()
        if rules.normals is not None:
            assert small.normals.shape == small.points.shape


def test_bad_degree():
    cut = cut_rules_3d("tetrahedron", 1, np.array([[-1.0, 1.0, 1.0, 1.0]]), 2)
    with pytest.raises(ValueError, match="compression degree"):
        compress_rules(cut.minus, -1)
