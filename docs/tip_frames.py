"""Draw the tip frames of a crack and the sign of K_II: ``docs/figures/crack_tip_frames.png``.

An inclined crack of half length 1 m is cut on a mesh (``CutMesh(..., tangent=psi)``);
the figure shows, as the code reads them from the cut, each tip's frame (``e1 =
cut.crack.directions[k]``, the crack ahead of the tip; ``e2`` turned by +90 degrees) and
its upper lip (``cut.crack.upper_sides[k]``: the side on the ``+e2`` side, ``theta =
pi``), and the relative sliding of the lips that is a positive K_II at that tip: the
upper lip moving along ``+e1`` relative to the lower lip. Under a remote shear both tips
read the same sign (Westergaard's ``K_II = S12 sqrt(pi a)``, ``S12`` in the crack frame
of either tip's ``e1``, ``e2`` pair).

Run: ``python docs/tip_frames.py`` (one process).
"""

import math
import pathlib

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import dolfinx.mesh
import matplotlib
import numpy as np
from mpi4py import MPI

from xfem_contact.fem.cutmesh import CutMesh

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

OUT = pathlib.Path(__file__).parent / "figures" / "crack_tip_frames.png"
ANGLE, CENTRE, HALF = 0.3, np.array([0.0123, 0.0271]), 1.0


def main() -> None:
    d = np.array([math.cos(ANGLE), math.sin(ANGLE)])
    n = np.array([-d[1], d[0]])
    mesh = dolfinx.mesh.create_rectangle(MPI.COMM_SELF, [[-2, -2], [2, 2]], [16, 16])
    cut = CutMesh(
        mesh,
        lambda x: (x[0] - CENTRE[0]) * n[0] + (x[1] - CENTRE[1]) * n[1],
        degree=1,
        tangent=lambda x: np.abs((x[0] - CENTRE[0]) * d[0] + (x[1] - CENTRE[1]) * d[1]) - HALF,
    )
    crack = cut.crack
    fig, ax = plt.subplots(figsize=(7.0, 4.2))
    ends = np.array([CENTRE - HALF * d, CENTRE + HALF * d])
    ax.plot(ends[:, 0], ends[:, 1], "k-", lw=2.5)
    ax.annotate(
        "side +1 (phi > 0)", CENTRE + 0.45 * n, ha="center", va="center", fontsize=9, color="0.3"
    )
    ax.annotate(
        "side -1 (phi < 0)", CENTRE - 0.45 * n, ha="center", va="center", fontsize=9, color="0.3"
    )
    L = 0.45
    for k, (tip, e1, upper) in enumerate(
        zip(crack.tips, crack.directions, crack.upper_sides, strict=True)
    ):
        e2 = np.array([-e1[1], e1[0]])
        ax.plot(*tip, "ko", ms=5)
        for v, label, colour in ((e1, "e1", "tab:blue"), (e2, "e2", "tab:green")):
            ax.annotate("", tip + L * v, tip, arrowprops=dict(arrowstyle="->", color=colour, lw=2))
            ax.text(*(tip + 1.18 * L * v), label, color=colour, ha="center", va="center")
        ax.text(
            *(tip + 0.35 * e1 - 0.42 * e2),
            f"tip {k}\nupper lip: side {int(upper):+d}",
            fontsize=8,
            ha="center",
            va="center",
        )
        # positive K_II: the upper lip (+e2 side) slides along +e1 relative to the lower one
        behind = tip - 0.55 * e1
        for sign, colour in ((1, "tab:red"), (-1, "tab:purple")):
            start = behind + sign * 0.09 * e2 - sign * 0.13 * e1
            ax.annotate(
                "",
                start + sign * 0.26 * e1,
                start,
                arrowprops=dict(arrowstyle="->", color=colour, lw=1.8),
            )
    ax.plot([], [], color="tab:red", label="upper lip (+e2 side)")
    ax.plot([], [], color="tab:purple", label="lower lip (-e2 side)")
    ax.set_title("K_II > 0 at a tip: its upper lip slides along +e1 relative to its lower lip")
    ax.title.set_fontsize(9)
    ax.legend(loc="lower right", fontsize=8)
    ax.set_aspect("equal")
    ax.set_xlim(-1.9, 1.9)
    ax.set_ylim(-1.0, 1.1)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    fig.tight_layout()
    OUT.parent.mkdir(exist_ok=True)
    fig.savefig(OUT, dpi=110)
    print(
        f"wrote {OUT}: tips {crack.tips.round(3).tolist()}, e1 {crack.directions.round(3).tolist()}"
    )


if __name__ == "__main__":
    main()
