"""Structured meshes with exact curved boundaries (Q2 geometry) for the paper's cases."""

from __future__ import annotations

import basix.ufl
import dolfinx.mesh
import numpy as np
from mpi4py import MPI


def ghosted_partitioner():
    """A cell partitioner that ghosts the cells across shared facets.

    The ghost penalty and the cut-cell data need the cells on both sides of every
    interior facet; ``dolfinx.mesh.create_mesh`` and ``dolfinx.io.gmsh`` default to
    no ghosts (``create_rectangle`` ghosts shared facets already).
    """
    return dolfinx.mesh.create_cell_partitioner(dolfinx.mesh.GhostMode.shared_facet, 2)


def _quad_cells(ni: int, nj: int, node, degree: int) -> np.ndarray:
    """Cells of an ni x nj structured grid of quads in DOLFINx node order.

    ``node(i, j)`` numbers the grid points of a (degree*ni+1) x (degree*nj+1) lattice.
    """
    d = degree
    cells = []
    for j in range(nj):
        for i in range(ni):
            a, b = d * i, d * j
            if d == 1:
                cells.append([node(a, b), node(a + 1, b), node(a, b + 1), node(a + 1, b + 1)])
            else:
                cells.append(
                    [
                        node(a, b),
                        node(a + 2, b),
                        node(a, b + 2),
                        node(a + 2, b + 2),
                        node(a + 1, b),
                        node(a, b + 1),
                        node(a + 2, b + 1),
                        node(a + 1, b + 2),
                        node(a + 1, b + 1),
                    ]
                )
    return np.array(cells, dtype=np.int64)


def annulus(
    comm: MPI.Comm,
    r_inner: float,
    r_outer: float,
    n_radial: int,
    n_angular: int,
    geometry_degree: int = 2,
) -> dolfinx.mesh.Mesh:
    """Structured quadrilateral mesh of the annulus ``r_inner <= r <= r_outer`` (m).

    ``geometry_degree=2`` gives curved 9-node cells whose nodes lie on exact circles
    (the circles are then represented to O(h^3)); 1 gives straight-edged cells (a
    polygonal annulus). Collective; the mesh is built on rank 0 and distributed.
    """
    if not 0 < r_inner < r_outer:
        raise ValueError(f"Need 0 < r_inner < r_outer, got {r_inner}, {r_outer}")
    if geometry_degree not in (1, 2):
        raise ValueError(f"geometry_degree must be 1 or 2, got {geometry_degree}")
    if n_radial < 1 or n_angular < 3:
        raise ValueError(f"Need n_radial >= 1 and n_angular >= 3, got {n_radial}, {n_angular}")
    d = geometry_degree
    nr, nt = d * n_radial + 1, d * n_angular  # lattice points (angle periodic)
    r = np.linspace(r_inner, r_outer, nr)
    theta = np.linspace(0.0, 2.0 * np.pi, nt, endpoint=False)
    R, T = np.meshgrid(r, theta, indexing="xy")  # shape (nt, nr)
    x = np.c_[(R * np.cos(T)).ravel(), (R * np.sin(T)).ravel()]

    def node(i, j):
        return i + nr * (j % nt)

    cells = _quad_cells(n_radial, n_angular, node, d)
    element = basix.ufl.element("Lagrange", "quadrilateral", d, shape=(2,))
    if comm.rank != 0:
        x, cells = np.zeros((0, 2)), np.zeros((0, cells.shape[1]), dtype=np.int64)
    return dolfinx.mesh.create_mesh(comm, cells, element, x, partitioner=ghosted_partitioner())


def curved_square(comm: MPI.Comm, n: int, amplitude: float = 0.05) -> dolfinx.mesh.Mesh:
    """Unit square meshed by n x n curved 9-node quadrilaterals: a smooth interior
    distortion of amplitude ``amplitude`` (m) bends the cell edges (boundary kept)."""
    m = 2 * n + 1
    s = np.linspace(0.0, 1.0, m)
    X, Y = np.meshgrid(s, s, indexing="xy")
    x = np.c_[X.ravel(), Y.ravel()]
    bump = amplitude * np.sin(np.pi * x[:, 0]) * np.sin(np.pi * x[:, 1])
    x = x + np.c_[bump * np.cos(3 * x[:, 1]), bump * np.sin(2 * x[:, 0])]
    cells = _quad_cells(n, n, lambda i, j: i + m * j, 2)
    element = basix.ufl.element("Lagrange", "quadrilateral", 2, shape=(2,))
    if comm.rank != 0:
        x, cells = np.zeros((0, 2)), np.zeros((0, 9), dtype=np.int64)
    return dolfinx.mesh.create_mesh(comm, cells, element, x, partitioner=ghosted_partitioner())
