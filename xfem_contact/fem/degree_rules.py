"""The rules of a cut's measures for an integrand's polynomial degree: what
:class:`~xfem_contact.fem.cutmesh.CutMesh`'s ``compression`` integrates the cut cells with.

For an integrand of degree ``p`` (as :func:`xfem_contact.form` passes it) and
``d = min(p, quadrature_degree)``:

- affine P1 tetrahedra: the exact planar cut's rules of degree ``d``
  (:func:`~xfem_contact.fem.cut3d_state.planar_cut_rules`), at any ``d < quadrature_degree``;
- other simplices: :func:`~xfem_contact.quadrature.compression.compress_rules` to degree
  ``d``, for ``dim P_d <= MAX_MOMENTS``, each rule of more than ``2 dim P_d`` points.

Both have the moments of degree ``<= d`` of the full rules, with fewer points.
"""

from __future__ import annotations

from collections.abc import Mapping

from xfem_contact._timers import phase, seconds
from xfem_contact.fem.cut3d_state import planar_cut_rules
from xfem_contact.fem.cut_state import INTERFACE, CutState
from xfem_contact.quadrature.compression import compress_rules, num_moments
from xfem_contact.quadrature.rules import RuleSet

__all__ = ["MAX_MOMENTS", "DegreeRules"]

MAX_MOMENTS = 20
"""The largest ``dim P_d`` that rules are compressed to (the cost grows as its cube per
rule): ``d <= 3`` in 3D, ``d <= 5`` in 2D."""


class DegreeRules:
    """The rules of one cut's measures per integrand degree, made on first use.

    Args:
        state: The cut.
        quadrature_degree: The degree of the cut's full rules.
        planar: The cut is of affine P1 tetrahedra (the exact planar cut).
        interface_base: The measure id of the first named interface; ids from it on are
            the named interfaces, in the order of ``state.interface_names``.
    """

    def __init__(self, state: CutState, quadrature_degree: int, planar: bool, interface_base: int):
        self.state = state
        self.quadrature_degree = quadrature_degree
        self.planar = planar
        self.interface_base = interface_base
        self._rules: dict[tuple[int, int], RuleSet] = {}
        self._planar: dict[int, Mapping[int, RuleSet]] = {}

    def rules(self, sid: int, degree: int) -> RuleSet | None:
        """The rules of measure id ``sid`` (a side, the interface or a named interface) for
        an integrand of polynomial ``degree``; ``None`` where the full rules serve. Timed as
        DOLFINx's ``"xfem_contact: rule compression"``. Not collective."""
        d = min(degree, self.quadrature_degree)
        tdim = self.state.maps.mesh.topology.dim
        if self.planar and d == self.quadrature_degree:
            return None
        if not self.planar and num_moments(tdim, d) > MAX_MOMENTS:
            return None
        if (sid, d) not in self._rules:
            timer = phase("rule compression")
            if self.planar:
                if d not in self._planar:
                    self._planar[d] = planar_cut_rules(self.state, d)
                rules = self._of_measure(sid, self._planar[d])
            else:
                full = self._of_measure(sid, self.state.rules)
                rules = compress_rules(full, d, keep=2 * num_moments(tdim, d))
            seconds(timer)
            self._rules[sid, d] = rules
        return self._rules[sid, d]

    def _of_measure(self, sid: int, rules: Mapping[int, RuleSet]) -> RuleSet:
        """Of ``rules`` by measure id (sides, interface), those of measure ``sid``: a named
        interface's are the interface rules of its cells."""
        if sid >= self.interface_base:
            return rules[INTERFACE].select(self.state.cell_interface == sid - self.interface_base)
        return rules[sid]
