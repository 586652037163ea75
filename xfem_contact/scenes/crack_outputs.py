"""The outputs of a scene's cracks: K_I, K_II, J and G per tip and ring, and their lips.

:class:`CrackOutputs` is made before the solve (its rings are checked and its
interaction integrals compiled then), :meth:`CrackOutputs.summary` after it: the
``cracks`` entry of ``summary.json``.
"""

from __future__ import annotations

import numpy as np

from xfem_contact.io.crack_data import lip_samples
from xfem_contact.io.crack_report import Reference, crack_table, load_words, tip_records
from xfem_contact.io.plots import interface_abscissa
from xfem_contact.mechanics.fracture import TipIntegrals, effective_modulus
from xfem_contact.scenes.crack_builder import crack_path, default_rings
from xfem_contact.scenes.schema import Scene, SceneError


class CrackOutputs:
    """The stress intensity factors and lips of the cracks of a scene's problem.

    Args:
        problem: The scene's problem (its cut has the cracks ``scene.cracks``, their
            rings shared).
        scene: The scene.

    Collective. Raises :class:`SceneError` (``cracks[0].rings``) for rings the mesh
    cannot hold.
    """

    def __init__(self, problem, scene: Scene):
        self.problem, self.specs = problem, scene.cracks
        rings = self.specs[0].rings or default_rings(problem)
        try:
            self.integrals = TipIntegrals(problem, rings)
        except ValueError as error:
            raise SceneError("cracks[0].rings", " ".join(str(error).split())) from None
        self.rings = [(float(a), float(b)) for a, b in rings]

    def tips(self) -> list[dict]:
        """K_I, K_II, J, G of every tip on every ring, now (:func:`tip_records`, the
        order of ``problem.cut.crack.tips``). Collective."""
        crack = self.problem.cut.crack
        return tip_records(crack.tips, crack.directions, self.integrals.evaluate())

    def per_crack(self, tips: list[dict]) -> dict[str, list[dict]]:
        """``tips`` (:meth:`tips`) grouped by crack: name to its tips' records."""
        names = self.problem.cut.crack.tip_names
        return {
            spec.name: [tip for tip, name in zip(tips, names, strict=True) if name == spec.name]
            for spec in self.specs
        }

    def summary(self, tips: list[dict] | None = None) -> dict:
        """``{name: {law, tips: [{position, direction, rings: [{r_inf, r_sup, K_I, K_II,
        J, G}]}], lips: {x, y, s, opening, slip[, lambda_n, lambda_t, status]},
        abscissa[, reference: {K_I, K_II, source}]}}`` (SI units; ``s`` the arc length
        from the crack's first point, or a coordinate along it for expressions,
        ``abscissa`` says which) of the current solution; ``tips``: :meth:`tips` if
        evaluated already. Collective."""
        grouped = self.per_crack(self.tips() if tips is None else tips)
        summary = {}
        for spec in self.specs:
            lips = lip_samples(self.problem, spec.name)
            path = crack_path(spec)
            if path is not None:
                lips["s"] = path.arclength(np.array([lips["x"], lips["y"]])).tolist()
                label = "arc length along the crack (m)"
            else:
                s, label = interface_abscissa(np.array(lips["x"]), np.array(lips["y"]))
                lips["s"] = s.tolist()
            entry = {"law": self.problem.laws[spec.name].describe(), "tips": grouped[spec.name]}
            if spec.reference_K is not None:
                K_I, K_II = spec.reference_K
                entry["reference"] = {"K_I": K_I, "K_II": K_II, "source": spec.reference_source}
            summary[spec.name] = entry | {"lips": lips, "abscissa": label}
        return summary

    def lines(self, summary: dict) -> list[str]:
        """The table of each crack (:func:`~xfem_contact.io.crack_report.crack_table`):
        K per tip and ring, J, G, the reference, the law and the loads."""
        material = self.problem.bulk.materials[1]
        modulus = effective_modulus(material.E, material.nu, material.plane)
        loads = load_words(self.problem.loads)
        lines = []
        for name, entry in summary.items():
            given = entry.get("reference")
            reference = None if given is None else Reference(**given)
            lines += crack_table(name, entry["tips"], entry["law"], loads, reference, modulus)
        return lines
