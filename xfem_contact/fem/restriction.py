"""Deprecated name of :mod:`xfem_contact.fem.prolongation` (removed in the next release):
``restriction_matrix`` is :func:`~xfem_contact.fem.prolongation.prolongation_matrix`."""

import warnings

from xfem_contact.fem.prolongation import MultiplierProlongation, prolongation_matrix

__all__ = ["MultiplierProlongation", "restriction_matrix"]

warnings.warn(
    "xfem_contact.fem.restriction is deprecated and will be removed in the next release: "
    "use xfem_contact.fem.prolongation (restriction_matrix is prolongation_matrix there)",
    DeprecationWarning,
    stacklevel=2,
)
restriction_matrix = prolongation_matrix
