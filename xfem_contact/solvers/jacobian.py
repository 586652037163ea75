"""The Jacobian of a residual on a mixed space, as the forms the Newton solver uses.

:class:`JacobianForms` compiles ``dF/dw``: with the fields' own spaces (and a
prolongation that selects dofs) the field blocks of the uncut cells and interior
facets apart from the rest
(:func:`xfem_contact.fem.field_blocks.uncut_field_blocks`), for
:class:`~xfem_contact.solvers.assembly.ReducedMatrix`; and lifts a residual with the
whole Jacobian where the iterate misses its Dirichlet data, compiling the whole
form only then.
"""

from __future__ import annotations

from collections.abc import Callable

import dolfinx.fem
import dolfinx.fem.petsc
import ufl
from petsc4py import PETSc

from xfem_contact.fem.field_blocks import uncut_field_blocks
from xfem_contact.fem.forms import form


class JacobianForms:
    """The compiled Jacobian ``dF/dw`` of ``residual``. Construction is collective.

    Args:
        residual: UFL residual on the mixed space of ``w``.
        w: The unknown.
        field_space: ``field_space(i)``: field ``i``'s own space and parent dofs, to
            take the field blocks of the uncut cells and interior facets apart;
            ``None``: no field blocks.

    Attributes:
        rest: The form :class:`~xfem_contact.solvers.assembly.ReducedMatrix` assembles
            on ``W`` (the whole Jacobian without field blocks).
        blocks: ``(form, parent, constant)`` of each field block, on the field's own
            space; ``constant`` when it does not depend on ``w`` (a linear bulk).
    """

    def __init__(self, residual: ufl.Form, w: dolfinx.fem.Function, field_space: Callable | None):
        jacobian = ufl.derivative(residual, w, ufl.TrialFunction(w.function_space))
        parts = None if field_space is None else uncut_field_blocks(jacobian, field_space)
        self.rest = form(jacobian if parts is None else parts.rest)
        self.blocks = [
            (form(b.form), b.parent, w not in b.form.coefficients())
            for b in ([] if parts is None else parts.blocks)
        ]
        self._ufl, self._whole = (None, self.rest) if parts is None else (jacobian, None)
        self._gap: PETSc.Vec | None = None

    @property
    def whole(self) -> dolfinx.fem.Form:
        """The whole Jacobian on ``W`` (compiled on first use with field blocks). Collective."""
        if self._whole is None:
            self._whole = form(self._ufl)
        return self._whole

    def lift(self, b: PETSc.Vec, bcs: list, x: PETSc.Vec) -> None:
        """``b += J (g - x)`` on the Dirichlet columns (``bcs``), where the iterate ``x``
        misses its Dirichlet data ``g`` (e.g. the first iterate of a load step);
        nothing to add (nor to assemble) where it meets them to round-off (``|g - x|
        <= 1e-14 |x|``, as after a Newton step). Collective."""
        if self._gap is None:
            self._gap = b.duplicate()
        with self._gap.localForm() as local:
            local.set(0.0)
        dolfinx.fem.petsc.set_bc(self._gap, bcs, x, 1.0)  # g - x at the Dirichlet dofs
        infinity = PETSc.NormType.NORM_INFINITY
        if self._gap.norm(infinity) > 1e-14 * x.norm(infinity):
            dolfinx.fem.petsc.apply_lifting(b, [self.whole], bcs=[bcs], x0=[x], alpha=-1.0)

    def destroy(self) -> None:
        """Destroy the PETSc vector made here. Collective."""
        if self._gap is not None:
            self._gap.destroy()
            self._gap = None
