"""The displacement fields loads act on: both sides of a cut mesh, or one plain field.

:class:`SideFields` (the enriched space: fields 0 and 1, sides -1 and +1, cut
measures) and :class:`PlainFields` (one vector Lagrange space, standard measures)
tell :class:`~xfem_contact.mechanics.loads.Loads` the same things: the sides, each
side's sub-space, test function and measures.
"""

from __future__ import annotations

import dolfinx.fem
import numpy as np
import ufl
from mpi4py import MPI

from xfem_contact.fem.evaluation import cell_dofs, lagrange_element


class SideFields:
    """Sides -1 and +1 of an :class:`~xfem_contact.fem.enrichment.EnrichedSpace`."""

    sides = (-1, 1)

    def __init__(self, space):
        self.space, self.mesh = space, space.cut.mesh

    def subspace(self, side: int) -> dolfinx.fem.FunctionSpace:
        """The displacement sub-space of ``side`` (a view ``W.sub(i)``)."""
        return self.space.W.sub(self.sides.index(side))

    def test(self, side: int):
        return self.space.test()[self.sides.index(side)]

    def ds(self, side: int, facets: np.ndarray) -> ufl.Measure:
        return self.space.cut.ds(side, facets)

    def dx(self, side: int) -> ufl.Measure:
        return self.space.cut.dx(side)

    def zero_form(self) -> ufl.Form:
        return ufl.ZeroBaseForm((ufl.TestFunction(self.space.W),))

    def rotated_nodes(self, facets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """See :func:`rotated_nodes`. Collective."""
        return rotated_nodes(self.space, facets)


class PlainFields:
    """One displacement field on a whole (uncut) mesh; its only side is ``None``."""

    sides = (None,)

    def __init__(self, V: dolfinx.fem.FunctionSpace):
        self.V, self.mesh = V, V.mesh
        #: Facet sets of the ds measures, shared by every ds of the forms (by tag)
        self._facet_sets: list[tuple[int, np.ndarray]] = []
        self._tags: dict[bytes, int] = {}

    def subspace(self, side: None) -> dolfinx.fem.FunctionSpace:
        return self.V

    def test(self, side: None):
        return ufl.TestFunction(self.V)

    def ds(self, side: None, facets: np.ndarray) -> ufl.Measure:
        """The measure of exterior ``facets`` (tagged in the order parts come)."""
        key = np.asarray(facets, dtype=np.int32).tobytes()
        if key not in self._tags:
            tdim = self.mesh.topology.dim
            self.mesh.topology.create_connectivity(tdim - 1, tdim)
            entities = dolfinx.fem.compute_integration_domains(
                dolfinx.fem.IntegralType.exterior_facet, self.mesh.topology, facets
            )
            self._tags[key] = len(self._facet_sets) + 1
            self._facet_sets.append((self._tags[key], entities))
        measure = ufl.Measure("ds", domain=self.mesh, subdomain_data=self._facet_sets)
        return measure(self._tags[key])

    def dx(self, side: None) -> ufl.Measure:
        return ufl.dx(domain=self.mesh)

    def zero_form(self) -> ufl.Form:
        return ufl.ZeroBaseForm((ufl.TestFunction(self.V),))

    def rotated_nodes(self, facets: np.ndarray) -> None:
        """None: a plain problem is linear and needs no rotation predictor."""
        return None


def rotated_nodes(space, facets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The displacement nodes of the bodies touching boundary ``facets``: the local
    dofs of ``W`` (one row per node, ``(k, 2)``) and the nodes' reference positions
    (m), ``(k, 2)``, over the local cells (owned and ghost) of each side whose cells
    hold those facets, in the same regions (the inclusion, for side -1). Collective."""
    cut = space.cut
    mesh, tdim = cut.mesh, cut.mesh.topology.dim
    mesh.topology.create_connectivity(tdim - 1, tdim)
    f2c = mesh.topology.connectivity(tdim - 1, tdim)
    touching = np.unique(np.concatenate([f2c.links(f) for f in facets] or [[]])).astype(np.int32)
    side = cut.side_indicator()
    sides = np.rint(side.x.array[side.function_space.dofmap.list[:, 0]]).astype(np.int64)
    regions = cut.cell_regions()
    region = np.rint(regions.x.array[regions.function_space.dofmap.list[:, 0]]).astype(np.int64)
    comm = mesh.comm
    dofs, nodes = [np.zeros((0, 2), dtype=np.int32)], [np.zeros((0, 2))]
    for field, s in ((0, -1), (1, 1)):
        here = touching[(sides[touching] == s) | (sides[touching] == 0)]
        held = np.unique(np.concatenate(comm.allgather(region[here] if s == -1 else here[:0])))
        if comm.allreduce(here.size, op=MPI.SUM) == 0:
            continue
        body = (sides == s) | (sides == 0)
        if s == -1:
            body &= np.isin(region, held)
        cells = np.flatnonzero(body).astype(np.int32)
        V = space.W.sub(field)
        points = lagrange_element(V).points
        X = cut.maps.push_forward_lattice(cells, points)[:, :2]
        d = cell_dofs(V, cells).reshape(-1, 2)
        d, first = np.unique(d, axis=0, return_index=True)
        dofs.append(d)
        nodes.append(X[first])
    return np.concatenate(dofs), np.concatenate(nodes)
