"""The options of a :class:`~xfem_contact.fem.cutmesh.CutMesh`, checked against its mesh
and resolved to their defaults (see the constructor's arguments for their meaning)."""

from __future__ import annotations

from dataclasses import dataclass

import dolfinx.mesh

__all__ = ["CELLS", "CutOptions", "cut_options"]

CELLS = ("triangle", "quadrilateral", "tetrahedron", "hexahedron")
"""The cell kinds of the meshes :class:`~xfem_contact.fem.cutmesh.CutMesh` cuts."""


@dataclass(frozen=True)
class CutOptions:
    """A cut's resolved options."""

    #: The mesh's cell kind, one of :data:`CELLS`
    cell: str
    #: Degree of the rules on each sub-cell and interface piece
    quadrature_degree: int
    #: Whether a callable level set is cut on its exact zero set
    exact_zero_set: bool
    #: Whether the user asked for the exact zero set (then a Function is refused)
    exact_required: bool
    #: Affine P1 tetrahedra: the exact planar cut gives rules of any degree directly
    planar: bool
    #: Whether the cut cells are integrated with compressed rules
    compression: bool
    #: Whether the cut is a crack's (a tangential level set given)
    crack: bool


def cut_options(
    mesh: dolfinx.mesh.Mesh,
    degree: int,
    quadrature_degree: int | None,
    crack: bool,
    compression: bool | None,
    exact_zero_set: bool | None,
) -> CutOptions:
    """Check a cut's options against ``mesh`` and resolve their defaults; a ``ValueError``
    of one line naming the argument and the valid choices for bad ones. Not collective."""
    tdim = mesh.topology.dim
    kinds = [t.name for t in mesh.topology.entity_types[tdim]]
    if len(kinds) > 1:
        raise ValueError(
            f"mesh: a mixed-topology mesh ({' + '.join(kinds)}) cannot be cut; valid: "
            f"one cell kind of {list(CELLS)}"
        )
    cell = kinds[0]
    if cell not in CELLS:
        raise ValueError(f"mesh: cells of kind {cell!r} cannot be cut; valid: {list(CELLS)}")
    if exact_zero_set and tdim == 3 and degree == 1:
        raise ValueError(
            "exact_zero_set: a P1/Q1 cut in 3D follows the level set's interpolant (planar "
            "on tetrahedra); valid: degree=2, or exact_zero_set=False"
        )
    if tdim == 3 and crack:
        raise ValueError("tangent: cracks are cut on triangle and quadrilateral meshes only")
    if quadrature_degree is None:
        quadrature_degree = 16 if crack else 6
    if quadrature_degree < 1:
        raise ValueError(f"quadrature_degree must be >= 1, got {quadrature_degree}")
    simplex = cell in ("triangle", "tetrahedron")
    planar = cell == "tetrahedron" and degree == 1 and mesh.geometry.cmaps[0].degree == 1
    if compression is None:
        compression = cell == "tetrahedron" and (degree == 2 or planar)
    if compression and (not simplex or crack):
        raise ValueError(
            f"compression: rules are compressed on triangles and tetrahedra without a "
            f"crack, not on {cell}s{' with a crack' if crack else ''}; "
            "valid: compression=False"
        )
    return CutOptions(
        cell=cell,
        quadrature_degree=quadrature_degree,
        exact_zero_set=tdim == 2 if exact_zero_set is None else bool(exact_zero_set),
        exact_required=bool(exact_zero_set),
        planar=planar,
        compression=bool(compression),
        crack=crack,
    )
