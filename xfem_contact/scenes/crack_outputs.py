"""The outputs of a scene's cracks: K_I, K_II, J and G per tip and ring, and their lips.

:class:`CrackOutputs` is made before the solve (its rings are checked and its
interaction integrals compiled then), :meth:`CrackOutputs.summary` after it: the
``cracks`` entry of ``summary.json``.
"""

from __future__ import annotations

import numpy as np

from xfem_contact.io.crack_data import lip_samples
from xfem_contact.io.plots import interface_abscissa
from xfem_contact.mechanics.fracture import TipIntegrals
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

    def summary(self) -> dict:
        """``{name: {law, tips: [{position, direction, rings: [{r_inf, r_sup, K_I, K_II,
        J, G}]}], lips: {x, y, s, opening, slip[, lambda_n, lambda_t, status]},
        abscissa}}`` (SI units; ``s`` the arc length from the crack's first point, or
        a coordinate along it for expressions, ``abscissa`` says which). Collective."""
        crack = self.problem.cut.crack
        names = crack.tip_names
        tips = [
            {
                "position": position.tolist(),
                "direction": direction.tolist(),
                "rings": [
                    {
                        "r_inf": r.ring.r_inf,
                        "r_sup": r.ring.r_sup,
                        "K_I": r.K_I,
                        "K_II": r.K_II,
                        "J": r.J,
                        "G": r.G,
                    }
                    for r in results
                ],
            }
            for position, direction, results in zip(
                crack.tips, crack.directions, self.integrals.evaluate(), strict=True
            )
        ]
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
            mine = [tip for tip, name in zip(tips, names, strict=True) if name == spec.name]
            entry = {"law": self.problem.laws[spec.name].describe(), "tips": mine}
            summary[spec.name] = entry | {"lips": lips, "abscissa": label}
        return summary

    def lines(self, summary: dict) -> list[str]:
        """One log line per tip: its position and K on each ring (Pa m^1/2)."""
        lines = []
        for name, entry in summary.items():
            label = "crack" if len(summary) == 1 else f"crack {name!r}"
            for k, tip in enumerate(entry["tips"]):
                ks = ", ".join(f"{r['K_I']:.4g} / {r['K_II']:.4g}" for r in tip["rings"])
                x, y = tip["position"]
                lines.append(f"{label} tip {k} at ({x:.4g}, {y:.4g}): K_I / K_II per ring {ks}")
        return lines
