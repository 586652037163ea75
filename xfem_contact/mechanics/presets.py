"""The two problems by their law families: :class:`ElasticityProblem` (``free``,
``bonded``: one linear solve) and :class:`ContactProblem` (``frictionless``,
``coulomb``, ``sticking``: generalized Newton), each a :class:`Problem` composed
with one law built by :func:`~xfem_contact.mechanics.laws.make_law`.

Both take the law's name and, keyword-only, the problem's options (those of
:class:`Problem`) and the law's (``friction``, ``augmentation``, ``lbb``, ...: an
option the law does not take is an error). Defaults:
:data:`~xfem_contact.mechanics.defaults.DEFAULTS`."""

from __future__ import annotations

import inspect

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.mechanics.composition import Materials
from xfem_contact.mechanics.laws import CONTACT_LAWS, LINEAR_LAWS, make_law
from xfem_contact.mechanics.problem import Problem

#: Interface laws of :class:`ElasticityProblem`
INTERFACE_LAWS = LINEAR_LAWS
#: The keyword options that go to :class:`Problem` (the rest go to the law)
PROBLEM_OPTIONS = tuple(
    p.name
    for p in inspect.signature(Problem.__init__).parameters.values()
    if p.kind is p.KEYWORD_ONLY
)


class _LawFamily(Problem):
    """A :class:`Problem` whose one law is named among :attr:`LAWS`."""

    LAWS: tuple[str, ...] = ()

    def __init__(self, cut: CutMesh, degree: int, materials: Materials, law: str, **options):
        if law not in self.LAWS:
            raise ValueError(f"Unknown interface law {law!r}; valid: {self.LAWS}")
        problem = {k: options.pop(k) for k in PROBLEM_OPTIONS if k in options}
        super().__init__(cut, degree, materials, make_law(law, **options), **problem)


class ElasticityProblem(_LawFamily):
    """Small-strain elasticity of the two sides with a ``free`` or ``bonded`` interface.

    Args:
        cut, degree, materials: See :class:`Problem`.
        law: ``"free"`` (default) or ``"bonded"``.
        options: Keyword-only: :class:`Problem`'s (``ghost_penalty``, ...) and the
            law's (``lbb``, ``multiplier_stabilization``, ``multiplier_extension``,
            ``multiplier_degree``, ``stabilization_length`` for ``bonded``).
    """

    LAWS = INTERFACE_LAWS

    def __init__(
        self, cut: CutMesh, degree: int, materials: Materials, law: str = "free", **options
    ):
        super().__init__(cut, degree, materials, law, **options)


class ContactProblem(_LawFamily):
    """Two-sided elasticity with a contact law on the interface, solved by SNES.

    Args:
        cut, degree, materials: See :class:`Problem`.
        law: ``"frictionless"``, ``"coulomb"`` or ``"sticking"``.
        options: Keyword-only: :class:`Problem`'s (``ghost_penalty``, ``kinematics``,
            ``slave``, ``pairing``, ...) and the law's (``friction``, required by
            ``"coulomb"``; ``augmentation``, ``lbb``, ``multiplier_stabilization``,
            ``multiplier_extension``, ``multiplier_degree``, ``stabilization_length``).
    """

    LAWS = CONTACT_LAWS
