"""Shared fixtures: small meshes, affine and distorted, on 1 or more ranks."""

import xfem_contact  # noqa: F401  (loads DOLFINx's MPI first when the wheel is used)

# isort: split
import dolfinx.mesh
import numpy as np
import pytest
from mpi4py import MPI

CELLS = {
    "quadrilateral": dolfinx.mesh.CellType.quadrilateral,
    "triangle": dolfinx.mesh.CellType.triangle,
}


def unit_square(n: int, cell: str, distorted: bool = False, comm=MPI.COMM_WORLD):
    """[0,1]^2 mesh with n x n cells; ``distorted`` moves interior nodes smoothly
    (non-affine quadrilaterals, still straight-edged)."""
    mesh = dolfinx.mesh.create_unit_square(comm, n, n, CELLS[cell])
    if distorted:
        x = mesh.geometry.x
        x[:, 0] += 0.15 / n * np.sin(2 * np.pi * x[:, 0]) * np.sin(3 * np.pi * x[:, 1]) * n / 2
        x[:, 1] += 0.15 / n * np.sin(3 * np.pi * x[:, 0]) * np.sin(2 * np.pi * x[:, 1]) * n / 2
    return mesh


@pytest.fixture(params=list(CELLS))
def cell(request):
    return request.param
