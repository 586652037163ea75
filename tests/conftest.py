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


CELLS_3D = {
    "tetrahedron": dolfinx.mesh.CellType.tetrahedron,
    "hexahedron": dolfinx.mesh.CellType.hexahedron,
}


def unit_cube(n: int, cell: str, distorted: bool = False, comm=MPI.COMM_WORLD):
    """[0,1]^3 mesh with n x n x n cubes (6 tetrahedra each, or hexahedra); ``distorted``
    moves the nodes smoothly (tetrahedra of varied shapes, non-affine hexahedra)."""
    mesh = dolfinx.mesh.create_unit_cube(comm, n, n, n, CELLS_3D[cell])
    if distorted:
        x = mesh.geometry.x
        bubble = x * (1.0 - x)  # zero on the faces normal to each axis: boundary kept
        x[:, 0] += 0.2 * bubble[:, 0] * (1.0 + x[:, 1]) * (1.0 + 2.0 * x[:, 2]) / n
        x[:, 1] += 0.2 * bubble[:, 1] * (1.0 + 2.0 * x[:, 2]) * (1.0 + x[:, 0]) / n
        x[:, 2] += 0.2 * bubble[:, 2] * (1.0 + 2.0 * x[:, 0]) * (1.0 + x[:, 1]) / n
    return mesh


@pytest.fixture(scope="module", autouse=True)
def _assembled_kernels_optimized(request, tmp_path_factory):
    """Modules marked ``assembly_bound`` compile their kernels with the library's own
    flags (:data:`~xfem_contact.fem.forms.JIT_DEFAULTS`, -O1) instead of the suite's
    -O0: they assemble large 3D kernels many times, so optimised code costs them less
    than its compilation. An empty DOLFINx configuration folder for the module's time."""
    if request.node.get_closest_marker("assembly_bound") is None:
        yield
        return
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("XDG_CONFIG_HOME", str(tmp_path_factory.mktemp("library-jit-options")))
        yield


def pytest_collection_modifyitems(config, items):
    """Tests marked ``parallel`` compare a run on all ranks with serial runs: on one
    rank they would compare a run with itself, so the serial suite skips them."""
    if MPI.COMM_WORLD.size > 1:
        return
    skip = pytest.mark.skip(reason="compares 1 and 2 ranks: runs in the MPI suite")
    for item in items:
        if "parallel" in item.keywords:
            item.add_marker(skip)


@pytest.fixture(params=list(CELLS))
def cell(request):
    return request.param
