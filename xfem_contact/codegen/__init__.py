"""FFCx code-generation back end for runtime (per-cell) quadrature rules.

FFCx resolves ``form_compiler_options["language"]`` with :func:`importlib.import_module`;
passing ``"xfem_contact.codegen"`` makes FFCx use this package, whose ``form``,
``expression`` and ``file`` modules are FFCx's own C modules and whose ``integral``
module generates, for *runtime integrals* only, kernels that read the number of
quadrature points, the weights and every point-dependent basis table from memory
at run time (see :mod:`xfem_contact.codegen.runtime_abi` for the memory layout).

A runtime integral is one whose integrand contains a *marker* coefficient: a
function on :func:`marker_element`, a quadrature element on fixed placeholder
points. FFCx builds the integral's intermediate representation on those points;
the marker's dofs carry, per cell, the rule index and the address of the rule
registry, and the marker counts as 1 in the integrand.

The first step of the layout: it imports FFCx, UFL, Basix and numpy and no other
``xfem_contact`` sub-package, so that FFCx can load it on its own.
"""

from xfem_contact.codegen import expression, file, form, integral
from xfem_contact.codegen.runtime_abi import (
    LANGUAGE,
    is_marker_element,
    marker_element,
    placeholder_points,
)

__all__ = [
    "LANGUAGE",
    "expression",
    "file",
    "form",
    "integral",
    "is_marker_element",
    "marker_element",
    "placeholder_points",
]
