"""The uncut cells' and interior facets' part of a bilinear form on a mixed space, field by field.

On the uncut cells of side ``s`` a Jacobian on ``W = (u_-, u_+, lambda, ...)`` is the
bulk of side ``s`` alone, yet assembled on ``W`` every one of those cells' element
matrices spans all the fields around a much smaller nonzero block, each entry sent
through the mixed space's dof map. :func:`uncut_field_blocks` takes the uncut-cell integrals
of the side measures (:meth:`CutMesh.dx <xfem_contact.fem.cutmesh.CutMesh.dx>`) out of
the form: the diagonal block of each field, ``a(P_i u, P_i v)``, becomes a form on that
field's own space ``V_i``, which DOLFINx assembles as a plain vector form (2 x 2 blocks
inserted at once); what couples two fields on those cells (nothing, for the bulk models
here) stays on ``W`` with the cut cells. Interior-facet integrals (the ghost penalty)
are separated the same way. The sum of the pieces is the form.
"""

from __future__ import annotations

import itertools
import typing
from collections.abc import Callable

import dolfinx.fem
import numpy as np
import numpy.typing as npt
import ufl
from ufl.algorithms import expand_derivatives


class FieldBlock(typing.NamedTuple):
    """The uncut cells' diagonal block of field ``field``: ``form`` (UFL, bilinear on
    ``space``), and ``parent``, the local dof of ``W`` of each local dof of ``space``
    (owned and ghost, unrolled)."""

    field: int
    form: ufl.Form
    space: dolfinx.fem.FunctionSpace
    parent: npt.NDArray[np.int32]


class FieldBlocks(typing.NamedTuple):
    """``a`` as ``rest`` (UFL, bilinear on ``W``: cut cells, interface, facets and any
    cross-field term of the uncut cells) plus the :class:`FieldBlock` forms."""

    rest: ufl.Form
    blocks: list[FieldBlock]


def _embedded(x, offsets: list[int], field: int) -> ufl.core.expr.Expr:
    """A ``W``-shaped vector holding ``x`` (an expression of the field's own shape,
    or ``W``-shaped, then its field components) in the field's components, 0 elsewhere."""
    first, last = offsets[field], offsets[field + 1]
    own = x.ufl_shape != (offsets[-1],)
    if own and x.ufl_shape == ():
        x = ufl.as_vector([x])
    return ufl.as_vector(
        [
            (x[k - first] if own else x[k]) if first <= k < last else ufl.zero()
            for k in range(offsets[-1])
        ]
    )


def _canonical_facets(form: ufl.Form) -> ufl.Form:
    """``form`` with its interior-facet integrals relabelled: the facets of subdomain
    ``k`` become subdomain 1 (their entities kept), so that the blocks of two fields
    whose integrands agree but for which facet set they integrate on (the ghost
    penalty of each side) have one signature, so one compiled form."""
    facets = [i for i in form.integrals() if i.integral_type() == "interior_facet"]
    ids = {i.subdomain_id() for i in facets}
    if len(ids) != 1 or not isinstance(facets[0].subdomain_data(), list | tuple):
        return form
    (sid,) = ids
    entities = dict(facets[0].subdomain_data())[sid]
    data = [(1, entities)]
    return ufl.Form(
        [
            i.reconstruct(subdomain_id=1, subdomain_data=data) if i in facets else i
            for i in form.integrals()
        ]
    )


def _empty(form: ufl.Form) -> bool:
    return expand_derivatives(form).empty()


def uncut_field_blocks(
    a: ufl.Form,
    field_space: Callable[[int], tuple[dolfinx.fem.FunctionSpace, npt.NDArray[np.int32]]],
) -> FieldBlocks | None:
    """Separate the bilinear form ``a`` (test and trial on one mixed space ``W``) into the
    diagonal field blocks of its uncut-cell and interior-facet integrals (the ghost
    penalty) and the rest (see the module docstring).

    Args:
        a: Bilinear UFL form (derivatives allowed) whose cut-cell measures are a
            :class:`~xfem_contact.fem.cutmesh.CutMesh`'s.
        field_space: ``field_space(i)`` gives field ``i``'s own space and the parent
            dof of each of its local dofs, e.g. :meth:`EnrichedSpace.field_space
            <xfem_contact.fem.enrichment.EnrichedSpace.field_space>`. Called
            (collectively) for the fields that have a block.

    Returns:
        The :class:`FieldBlocks`, or ``None`` when there is no field block (``W`` is not
        mixed, or ``a`` integrates no side measure). Collective when
        ``field_space`` is.
    """
    test, trial = a.arguments()
    W = test.ufl_function_space()
    element = W.ufl_element()
    if trial.ufl_function_space() != W or not element.is_mixed:
        return None
    rest, uncut = [], []
    for itg in a.integrals():
        if itg.integral_type() == "interior_facet":  # e.g. the ghost penalty
            uncut.append(itg)
            continue
        data = itg.subdomain_data()
        ids = None
        if itg.integral_type() == "cell" and hasattr(data, "side_measure_ids"):
            ids = data.side_measure_ids(itg.subdomain_id())
        if ids is None:
            rest.append(itg)
            continue
        uncut.append(itg.reconstruct(subdomain_id=ids[0]))
        rest.append(itg.reconstruct(subdomain_id=ids[1]))
    if not uncut:
        return None
    uncut = expand_derivatives(ufl.Form(uncut))  # once, not in every replace below
    offsets = [0, *itertools.accumulate(e.reference_value_size for e in element.sub_elements)]
    fields = range(len(element.sub_elements))

    def block(i: int, j: int, u, v) -> ufl.Form:
        return ufl.replace(uncut, {trial: _embedded(u, offsets, i), test: _embedded(v, offsets, j)})

    blocks = []
    for i in fields:
        if _empty(block(i, i, trial, test)):
            continue
        V, parent = field_space(i)
        form = block(i, i, ufl.TrialFunction(V), ufl.TestFunction(V))
        form = _canonical_facets(expand_derivatives(form))  # grad([0, v]) -> [0, grad v]
        blocks.append(FieldBlock(i, form, V, parent))
    rest = ufl.Form(rest)
    for i, j in itertools.permutations(fields, 2):  # trial field i, test field j
        cross = block(i, j, trial, test)
        if not _empty(cross):
            rest += cross
    return FieldBlocks(rest, blocks)
