"""Vital vertices and the prolongation of the reduced multiplier space
(``xfem_contact.mechanics.lbb``, pure numpy)."""

from __future__ import annotations

import numpy as np
import pytest

from xfem_contact.mechanics import lbb


def grid_cut_edges(n: int, phi) -> tuple[np.ndarray, np.ndarray]:
    """Cut edges of the n x n quad grid of the unit square (vertex ``i + (n+1) j``
    at ``(i/n, j/n)``, horizontal and vertical edges); side -1 where ``phi < 0``."""
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)  # [j, i]
    x, y = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1))
    side = np.where(phi(x, y) < 0, -1, 1).astype(np.int8).ravel()
    edges = np.concatenate(
        [
            np.stack([idx[:, :-1].ravel(), idx[:, 1:].ravel()], axis=1),
            np.stack([idx[:-1, :].ravel(), idx[1:, :].ravel()], axis=1),
        ]
    ).astype(np.int64)
    sides = side[edges]
    cut = sides[:, 0] != sides[:, 1]
    return edges[cut], sides[cut]


def circle(x, y):
    return np.hypot(x - 0.5, y - 0.5) - 0.2


def dense_p(edges, vital):
    rows, cols, vals, reduced = lbb.prolongation(edges, vital)
    verts = np.unique(edges)
    p = np.zeros((verts.size, reduced.size))
    np.add.at(p, (np.searchsorted(verts, rows), cols), vals)
    return verts, p, reduced, rows


CASES = {
    "vertical": (10, lambda x, y: x - 0.45),
    "diagonal": (10, lambda x, y: x + y - 0.45),
    "point": (10, lambda x, y: np.hypot(x - 0.5, y - 0.5) - 0.05),
    "circle10": (10, circle),
    "circle40": (40, circle),
}


@pytest.fixture(params=list(CASES))
def case(request):
    n, phi = CASES[request.param]
    return (n, *grid_cut_edges(n, phi))


def test_one_vital_end_per_edge(case):
    _, edges, sides = case
    vital = lbb.vital_vertices(edges, sides)
    assert vital.shape == (edges.shape[0],) and vital.dtype == np.int64
    assert np.all((vital == edges[:, 0]) | (vital == edges[:, 1]))
    # a non-vital vertex has all its cut edges assigned to the other end
    reduced = np.unique(vital)
    other = edges.sum(axis=1) - vital
    nonvital = np.setdiff1d(np.unique(edges), reduced)
    assert not np.any(np.isin(vital, nonvital))
    assert np.all(np.isin(other[~np.isin(other, reduced)], nonvital))


def test_order_independence(case):
    _, edges, sides = case
    vital = lbb.vital_vertices(edges, sides)
    rng = np.random.default_rng(0)
    for _ in range(3):
        perm = rng.permutation(edges.shape[0])
        flip = rng.random(edges.shape[0]) < 0.5
        e, s = edges[perm].copy(), sides[perm].copy()
        e[flip] = e[flip, ::-1]
        s[flip] = s[flip, ::-1]
        assert np.array_equal(lbb.vital_vertices(e, s), vital[perm])
        got = lbb.prolongation(e, lbb.vital_vertices(e, s))
        ref = lbb.prolongation(edges, vital)
        for a, b in zip(got, ref, strict=True):
            np.testing.assert_array_equal(a, b)


def test_duplicates_merged():
    edges, sides = grid_cut_edges(10, circle)
    vital = lbb.vital_vertices(edges, sides)
    e2 = np.concatenate([edges, edges[:5, ::-1]])
    s2 = np.concatenate([sides, sides[:5, ::-1]])
    v2 = lbb.vital_vertices(e2, s2)
    assert np.array_equal(v2[: edges.shape[0]], vital)
    assert np.array_equal(v2[edges.shape[0] :], vital[:5])
    for a, b in zip(lbb.prolongation(e2, v2), lbb.prolongation(edges, vital), strict=True):
        np.testing.assert_array_equal(a, b)


def test_vertical_interface():
    # x = 0.45 cuts the 11 horizontal edges between columns i = 4 and 5; they are
    # disjoint, every vertex covers one edge, ties go to the smaller id (i = 4).
    edges, sides = grid_cut_edges(10, CASES["vertical"][1])
    assert edges.shape[0] == 11
    vital = lbb.vital_vertices(edges, sides)
    np.testing.assert_array_equal(np.sort(vital), 4 + 11 * np.arange(11))
    stats = lbb.restriction_stats(edges, vital)
    assert stats["n_cut_edges"] == 11 and stats["n_edge_vertices"] == 22
    assert stats["n_vital"] == 11 and stats["n_equality"] == 11


def test_diagonal_interface():
    # x + y = 0.45: the side -1 front i + j = 4 (5 vertices, 2 cut edges each) and
    # the side +1 front i + j = 5 (6 vertices) form a zigzag path of 10 edges. Greedy
    # picks (4,0), (3,1), (2,2), (1,3), (0,4): 5 vital vertices for 11.
    edges, sides = grid_cut_edges(10, CASES["diagonal"][1])
    vital = lbb.vital_vertices(edges, sides)
    np.testing.assert_array_equal(np.unique(vital), [4, 14, 24, 34, 44])
    stats = lbb.restriction_stats(edges, vital)
    assert (stats["n_cut_edges"], stats["n_edge_vertices"], stats["n_vital"]) == (10, 11, 5)
    assert (stats["n_equality"], stats["n_average"], stats["n_both_vital_edges"]) == (2, 4, 0)


def test_single_vertex_inside():
    # only the centre vertex (5, 5) = 60 is on side -1: 4 cut edges, 1 vital vertex.
    edges, sides = grid_cut_edges(10, CASES["point"][1])
    vital = lbb.vital_vertices(edges, sides)
    assert edges.shape[0] == 4 and np.all(vital == 60)
    rows, cols, vals, reduced = lbb.prolongation(edges, vital)
    np.testing.assert_array_equal(reduced, [60])
    np.testing.assert_array_equal(rows, [49, 59, 60, 61, 71])
    np.testing.assert_array_equal(vals, np.ones(5))


@pytest.mark.parametrize("n", [10, 20, 40, 80])
def test_circle_counts(n):
    edges, sides = grid_cut_edges(n, circle)
    vital = lbb.vital_vertices(edges, sides)
    stats = lbb.restriction_stats(edges, vital)
    assert stats["n_cut_edges"] == edges.shape[0]
    assert stats["n_edge_vertices"] == np.unique(edges).size
    assert stats["n_vital"] < stats["n_edge_vertices"]
    assert stats["n_vital"] <= 0.6 * stats["n_edge_vertices"]
    assert stats["n_vital"] >= np.ceil(stats["n_cut_edges"] / 4)
    assert stats["max_edges_per_vital"] <= 4


def test_prolongation_reproduces_constants(case):
    _, edges, sides = case
    vital = lbb.vital_vertices(edges, sides)
    verts, p, reduced, rows = dense_p(edges, vital)
    np.testing.assert_array_equal(np.unique(rows), verts)  # one row per edge vertex
    np.testing.assert_allclose(p @ np.ones(reduced.size), 1.0, rtol=0, atol=1e-14)
    np.testing.assert_array_equal(p[np.searchsorted(verts, reduced)], np.eye(reduced.size))
    assert np.all(p >= 0)


def test_prolongation_relations(case):
    n, edges, sides = case
    vital = lbb.vital_vertices(edges, sides)
    verts, p, reduced, _ = dense_p(edges, vital)
    # a linear function sampled at the vital vertices
    xy = np.stack([reduced % (n + 1), reduced // (n + 1)], axis=1) / n
    x = 1.0 + 2.0 * xy[:, 0] - 3.0 * xy[:, 1]
    lam = p @ x
    at = dict(zip(verts.tolist(), lam, strict=True))
    xv = dict(zip(reduced.tolist(), x, strict=True))
    other = edges.sum(axis=1) - vital
    deg = dict(zip(*np.unique(other, return_counts=True), strict=True))
    checked = 0
    for (a, b), v, w in zip(edges.tolist(), vital.tolist(), other.tolist(), strict=True):
        assert at[v] == pytest.approx(xv[v])
        if w not in xv:  # non-vital end: average of its vital neighbours
            nbrs = vital[other == w]
            assert at[w] == pytest.approx(np.mean([xv[u] for u in nbrs.tolist()]))
            if deg[w] == 1:  # equality relation: both ends carry the vital value
                assert at[a] == pytest.approx(xv[v]) and at[b] == pytest.approx(xv[v])
                checked += 1
    assert checked > 0


def test_empty_and_errors():
    empty = np.zeros((0, 2), dtype=np.int64)
    vital = lbb.vital_vertices(empty, empty.astype(np.int8))
    assert vital.shape == (0,)
    rows, cols, vals, reduced = lbb.prolongation(empty, vital)
    assert rows.size == cols.size == vals.size == reduced.size == 0
    assert lbb.restriction_stats(empty, vital)["n_vital"] == 0
    with pytest.raises(ValueError, match="same side"):
        lbb.vital_vertices([[0, 1]], [[1, 1]])
    with pytest.raises(ValueError, match="both sides"):
        lbb.vital_vertices([[0, 1], [1, 2]], [[-1, 1], [-1, 1]])
    with pytest.raises(ValueError, match="not an end"):
        lbb.prolongation([[0, 1]], [2])


def test_nearer_end():
    """Given distances, each edge's vital vertex is its end nearer the interface (ties:
    the smaller id), whatever the order of the rows or of the ends."""
    edges = np.array([[0, 1], [2, 1], [2, 3], [4, 3]])
    sides = np.array([[-1, 1], [-1, 1], [-1, 1], [-1, 1]])
    distance = np.array([0.3, 0.1, 0.2, 0.2, 0.05])
    vital = lbb.vital_vertices(edges, sides, distance[edges])
    assert vital.tolist() == [1, 1, 2, 4]
    flipped = edges[::-1, ::-1]
    assert lbb.vital_vertices(flipped, sides[::-1, ::-1], distance[flipped]).tolist() == [
        4,
        2,
        1,
        1,
    ]
    with pytest.raises(ValueError, match="distances has shape"):
        lbb.vital_vertices(edges, sides, distance[edges][:3])


def test_near_crossings_before_the_covering():
    """A far vertex on three cut edges whose crossings lie within a tenth of the edge
    from their other ends: the covering alone makes it the one vital vertex (the three
    near ends its mean), the near crossings make their ends vital first, and a vertex so
    made vital takes all its cut edges. Order independent."""
    edges = np.array([[0, 2], [1, 2], [5, 2], [5, 6]])
    sides = np.tile([1, -1], (4, 1))
    distance = np.array([0.05, 0.05, 0.95, 0.0, 0.0, 0.05, 0.4])
    assert lbb.vital_vertices(edges, sides).tolist() == [2, 2, 2, 5]
    vital = lbb.vital_vertices(edges, sides, distance[edges], near_share=0.25)
    assert vital.tolist() == [0, 1, 5, 5]
    flipped = edges[::-1, ::-1]
    again = lbb.vital_vertices(flipped, sides[::-1, ::-1], distance[flipped], near_share=0.25)
    assert again.tolist() == [5, 5, 1, 0]
    with pytest.raises(ValueError, match="near_share must be in"):
        lbb.vital_vertices(edges, sides, distance[edges], near_share=0.7)
