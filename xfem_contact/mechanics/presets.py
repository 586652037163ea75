"""The two problems by their law names: :class:`ElasticityProblem` (``free``,
``bonded``: one linear solve) and :class:`ContactProblem` (``frictionless``,
``coulomb``, ``sticking``: generalized Newton), each a :class:`Problem` composed
with one law built by :func:`~xfem_contact.mechanics.laws.make_law`."""

from __future__ import annotations

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.mechanics.composition import Materials
from xfem_contact.mechanics.laws import CONTACT_LAWS, LINEAR_LAWS, make_law
from xfem_contact.mechanics.problem import Problem

#: Interface laws of :class:`ElasticityProblem`
INTERFACE_LAWS = LINEAR_LAWS


class ElasticityProblem(Problem):
    """Small-strain elasticity of the two sides with a ``free`` or ``bonded`` interface.

    Args:
        cut, degree, materials, ghost_penalty, min_support_fraction: See :class:`Problem`.
        interface: ``"free"`` or ``"bonded"``.
        multiplier_stabilization, multiplier_extension: Options of ``bonded`` (see
            :class:`~xfem_contact.mechanics.laws.MultiplierLaw`).
    """

    LAWS = INTERFACE_LAWS

    def __init__(
        self,
        cut: CutMesh,
        degree: int,
        materials: Materials,
        interface: str = "free",
        min_support_fraction: float | None = None,
        ghost_penalty: float = 0.01,
        multiplier_stabilization: float = 0.1,
        multiplier_extension: float = 1e-12,
    ):
        if interface not in self.LAWS:
            raise ValueError(f"Unknown interface law {interface!r}; valid: {self.LAWS}")
        law = make_law(
            interface,
            multiplier_stabilization=multiplier_stabilization,
            multiplier_extension=multiplier_extension,
        )
        super().__init__(
            cut,
            degree,
            materials,
            law,
            ghost_penalty=ghost_penalty,
            min_support_fraction=min_support_fraction,
        )


class ContactProblem(Problem):
    """Two-sided elasticity with a contact law on the interface, solved by SNES.

    Args:
        cut, degree, materials, ghost_penalty: See :class:`Problem`.
        law: ``"frictionless"``, ``"coulomb"`` or ``"sticking"``.
        friction: Coulomb coefficient (>= 0), required by ``"coulomb"``.
        augmentation: Dimensionless factor of ``r = augmentation * E / h`` (> 0).
        lbb: ``"stabilized"`` (default), ``"restriction"`` (vital vertices) or ``"none"``.
        multiplier_stabilization, multiplier_extension: See
            :class:`~xfem_contact.mechanics.laws.MultiplierLaw`.
    """

    LAWS = CONTACT_LAWS

    def __init__(
        self,
        cut: CutMesh,
        degree: int,
        materials: Materials,
        law: str,
        friction: float | None = None,
        augmentation: float = 1.0,
        lbb: str = "stabilized",
        multiplier_stabilization: float = 0.1,
        multiplier_extension: float = 1e-12,
        ghost_penalty: float = 0.01,
    ):
        if law not in self.LAWS:
            raise ValueError(f"Unknown interface law {law!r}; valid: {self.LAWS}")
        interface_law = make_law(
            law,
            friction=friction,
            augmentation=augmentation,
            lbb=lbb,
            multiplier_stabilization=multiplier_stabilization,
            multiplier_extension=multiplier_extension,
        )
        super().__init__(cut, degree, materials, interface_law, ghost_penalty=ghost_penalty)
