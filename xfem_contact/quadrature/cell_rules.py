"""Per-cell runtime quadrature rules and the memory their kernels read.

A :class:`CellRules` holds one quadrature rule per cell (points in the cell's
reference coordinates, weights in the reference measure) for the cells of this
process it lists, and everything a runtime kernel reads from memory (layout in
:mod:`xfem_contact.codegen.runtime_abi`): the marker function, the registry, and
one block of tabulated basis tables per kernel. Rules are local to a process.
"""

from __future__ import annotations

import itertools
import typing

import dolfinx.fem
import numpy as np
import numpy.typing as npt
import ufl

from xfem_contact.codegen import marker_element
from xfem_contact.codegen.tables import RuntimeIntegral, tabulate

_INITIAL_CAPACITY = 16
_counter = itertools.count()


def _address(array: np.ndarray) -> int:
    return int(array.ctypes.data)


def marker_space(mesh: dolfinx.mesh.Mesh) -> dolfinx.fem.FunctionSpace:
    """The space of the marker coefficients of rules on ``mesh`` (one may serve all the
    rules of a mesh: each has its own :class:`dolfinx.fem.Function` on it). Collective."""
    return dolfinx.fem.functionspace(mesh, marker_element(mesh.basix_cell().name))


class IntegrationPart(typing.NamedTuple):
    """One piece of a cut measure, as the ``integration_parts`` of its source lists it.

    Attributes:
        integral_type: ``"cell"`` or ``"exterior_facet"`` for a standard part;
            runtime parts are always cell integrals.
        entities: Standard-rule entities: cells ``(n,)`` or flattened
            ``(cell, local facet)`` pairs ``(2 n,)``; ``None`` for a runtime part.
        rules: Runtime rules, or ``None`` for a standard part.
        replace: UFL replacements applied to the runtime integrand (e.g. the
            facet normal of a boundary piece integrated as a cell integral).
        metadata: Overrides of the integral's metadata for a standard part (e.g. its
            own ``quadrature_degree``).
    """

    integral_type: str
    entities: np.ndarray | None = None
    rules: CellRules | None = None
    replace: dict | None = None
    metadata: dict | None = None


class CellRules:
    """Quadrature rules given per cell, for use in UFL forms through :func:`xfem_contact.form`.

    Args:
        mesh: The mesh the cells belong to.
        cells: Local indices of the cells, shape ``(n,)``. Owned cells only:
            DOLFINx integrates every listed cell, ghosts included.
        points: Reference coordinates of all points, shape ``(N, tdim)``.
        weights: Weights in the reference measure, shape ``(N,)``; FFCx
            multiplies them by ``|det J|`` of the cell map.
        offsets: Shape ``(n + 1,)``; rule ``i`` (cell ``cells[i]``) is
            ``points[offsets[i]:offsets[i + 1]]``.
        marker_space: The space of :attr:`marker` (:func:`marker_space` of ``mesh``),
            to share one among the rules of a mesh; made here if not given.
    """

    #: The rules do not depend on the integrand's degree (see :func:`xfem_contact.form`)
    compression = False

    def __init__(
        self,
        mesh: dolfinx.mesh.Mesh,
        cells: npt.ArrayLike,
        points: npt.ArrayLike,
        weights: npt.ArrayLike,
        offsets: npt.ArrayLike,
        marker_space: dolfinx.fem.FunctionSpace | None = None,
    ):
        self.mesh = mesh
        self._marker_space = marker_space
        self.cells = np.ascontiguousarray(cells, dtype=np.int32)
        self.points = np.ascontiguousarray(points, dtype=np.float64)
        self.weights = np.ascontiguousarray(weights, dtype=np.float64)
        self.offsets = np.ascontiguousarray(offsets, dtype=np.int64)
        tdim = mesh.topology.dim
        n, npts = self.cells.size, self.weights.size
        if self.points.shape != (npts, tdim):
            raise ValueError(f"points must have shape ({npts}, {tdim}), got {self.points.shape}")
        if self.offsets.shape != (n + 1,) or self.offsets[0] != 0 or self.offsets[-1] != npts:
            raise ValueError(f"offsets must have shape ({n + 1},), start at 0 and end at {npts}")
        if np.any(np.diff(self.offsets) < 0):
            raise ValueError("offsets must be non-decreasing")
        if not (np.all(np.isfinite(self.points)) and np.all(np.isfinite(self.weights))):
            raise ValueError("quadrature points and weights must be finite")
        num_cells = mesh.topology.index_map(tdim).size_local
        if n and (self.cells.min() < 0 or self.cells.max() >= num_cells):
            raise ValueError(f"cells must be owned cells of this process, in [0, {num_cells})")
        self.id = next(_counter)
        self._registry = np.zeros(1 + 2 * _INITIAL_CAPACITY, dtype=np.int64)
        self._blocks: dict[int, list[np.ndarray]] = {}
        self._marker: dolfinx.fem.Function | None = None

    @property
    def num_points(self) -> int:
        """Number of quadrature points of all rules on this process."""
        return int(self.weights.size)

    @property
    def marker(self) -> dolfinx.fem.Function:
        """The marker coefficient that routes runtime kernels to these rules."""
        if self._marker is None:
            space = self._marker_space or marker_space(self.mesh)
            self._marker = dolfinx.fem.Function(space, name="xfem_marker")
            self._write_marker()
        return self._marker

    def _write_marker(self) -> None:
        values = self._marker.x.array
        values[:] = 0.0
        dofs = self._marker.function_space.dofmap.list[self.cells]
        values[dofs[:, 0]] = np.arange(self.cells.size, dtype=np.float64)
        values[dofs[:, 1]] = np.array([_address(self._registry)], np.int64).view(np.float64)[0]

    def register(self, kernel: RuntimeIntegral, cell: ufl.Cell) -> None:
        """Tabulate a kernel's runtime tables at all points and register them (once per kernel)."""
        if kernel.key in self._blocks:
            return
        tables = [tabulate(spec, self.points, cell) for spec in kernel.tables]
        block = np.concatenate(
            [
                [self.cells.size],
                self.offsets,
                [_address(self.weights)],
                [_address(t) for t in tables],
            ]
        ).astype(np.int64)
        self._blocks[kernel.key] = [block, *tables]
        count = int(self._registry[0])
        if 1 + 2 * (count + 1) > self._registry.size:
            grown = np.zeros(2 * self._registry.size - 1, dtype=np.int64)
            grown[: self._registry.size] = self._registry
            self._registry = grown
            if self._marker is not None:
                self._write_marker()
        self._registry[1 + 2 * count : 3 + 2 * count] = (kernel.key, _address(block))
        self._registry[0] = count + 1

    def measure(self, **kwargs) -> ufl.Measure:
        """A UFL cell measure that integrates with these rules (``expr * rules.measure()``)."""
        return ufl.Measure("dx", domain=self.mesh, subdomain_data=self, subdomain_id=0, **kwargs)

    def integration_parts(self, subdomain_id: int, degree: int | None = None) -> list:
        """The one part of :meth:`measure`: these runtime rules, whatever the integrand's
        polynomial ``degree`` (for :func:`xfem_contact.form`)."""
        return [IntegrationPart("cell", rules=self)]
