"""The side measures of a cracked cut mesh with the tip zone at its own quadrature degree.

The crack-tip branch functions (``sqrt(r)`` times trigonometric functions of the angle)
live only on the cells where a branch dof is active: the zone of radius ``r_e`` around
each tip (and its ramp) or the tip cells' patch. Their integrands are far from
polynomials and need a high degree (the cut's ``quadrature_degree``); everywhere else
the integrand of a polynomial space is a polynomial of low degree. :class:`TipZone` is a
source of cut measures (``integration_parts``, as :class:`~xfem_contact.fem.cutmesh.CutMesh`)
that divides the uncut cells of each side measure into the zone, with the zone's
metadata, and the rest, with the measure's own: the same integrals, at a fraction of
the points. Cut cells keep their runtime rules.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import numpy.typing as npt
import ufl

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.fem.enrichment import EnrichedSpace
from xfem_contact.quadrature.cell_rules import IntegrationPart

__all__ = ["TipZone", "branch_cells"]


def branch_cells(space: EnrichedSpace) -> npt.NDArray[np.int32]:
    """Owned cells with an active branch dof of ``space`` (sorted; empty without a
    crack's tip enrichment). Not collective."""
    if space.branch_field is None:
        return np.zeros(0, dtype=np.int32)
    V, parent = space.field_space(space.branch_field)
    bs = V.dofmap.index_map_bs
    active = space.active[parent].reshape(-1, bs).any(axis=1)
    owned = space.cut.cell_sides.size
    return np.flatnonzero(active[V.dofmap.list[:owned]].any(axis=1)).astype(np.int32)


class TipZone:
    """The side measures of ``cut`` with the uncut cells of ``cells()`` integrated with
    ``metadata`` (e.g. ``{"quadrature_degree": 16}``).

    Args:
        cut: The cut mesh.
        cells: Returns the zone's owned cells (sorted), read at every form built (the
            zone follows the crack), e.g. ``lambda: branch_cells(space)``.
        metadata: Metadata of the zone's uncut cells, over the measure's.
    """

    def __init__(self, cut: CutMesh, cells: Callable[[], npt.NDArray[np.int32]], metadata: dict):
        self.cut, self.cells, self.metadata = cut, cells, dict(metadata)

    @property
    def id(self) -> int:
        """The cut's id (orders the measures of a form)."""
        return self.cut.id

    @property
    def compression(self) -> bool:
        """Whether the cut's rules depend on the integrand's degree (its ``compression``)."""
        return self.cut.compression

    def dx(self, side: int, metadata: dict | None = None) -> ufl.Measure:
        """As :meth:`CutMesh.dx <xfem_contact.fem.cutmesh.CutMesh.dx>`: ``metadata``
        applies to the uncut cells outside the zone."""
        return self.cut.dx(side, metadata).reconstruct(subdomain_data=self)

    def side_measure_ids(self, subdomain_id: int) -> tuple[int, int] | None:
        """See :meth:`CutMesh.side_measure_ids
        <xfem_contact.fem.cutmesh.CutMesh.side_measure_ids>`."""
        return self.cut.side_measure_ids(subdomain_id)

    def integration_parts(
        self, subdomain_id: int, degree: int | None = None
    ) -> list[IntegrationPart]:
        """The cut's parts, each standard cell part divided into the zone's cells (with
        :attr:`metadata`) and the others. Every process returns the same parts."""
        parts = []
        for part in self.cut.integration_parts(subdomain_id, degree):
            if part.rules is not None or part.integral_type != "cell":
                parts.append(part)
                continue
            inside = np.isin(part.entities, self.cells())
            parts.append(part._replace(entities=part.entities[~inside]))
            parts.append(part._replace(entities=part.entities[inside], metadata=self.metadata))
        return parts
