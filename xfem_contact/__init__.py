"""xfem_contact: X-FEM contact mechanics with quadratic elements on curved interfaces.

A FEniCSx (DOLFINx 0.11) plugin. Import it before or after ``dolfinx``: the
PyPI wheel ``dolfinx-solver-real`` needs ``dolfinx_solver`` imported first, which
the start-up hook installed with this package does before any ``import dolfinx``
(see ``xfem_contact/_bootstrap.py``), and which is done here too.
"""

import logging

from xfem_contact._bootstrap import load_dolfinx_solver

load_dolfinx_solver()  # the PyPI wheel: MPI first; conda/apt DOLFINx: nothing to do

from xfem_contact._version import package_version, versions  # noqa: E402

__version__ = package_version()
logging.getLogger(__name__).addHandler(logging.NullHandler())  # shown only where asked

from xfem_contact.fem.cutmesh import CutMesh  # noqa: E402
from xfem_contact.fem.forms import form  # noqa: E402
from xfem_contact.mechanics.materials import Material  # noqa: E402
from xfem_contact.mechanics.presets import ContactProblem, ElasticityProblem  # noqa: E402
from xfem_contact.mechanics.problem import Problem  # noqa: E402
from xfem_contact.quadrature.cell_rules import CellRules  # noqa: E402
from xfem_contact.solvers.report import LinearSolveFailure, NewtonFailure, SolveError  # noqa: E402

__all__ = [
    "CellRules",
    "ContactProblem",
    "CutMesh",
    "ElasticityProblem",
    "LinearSolveFailure",
    "Material",
    "NewtonFailure",
    "Problem",
    "SolveError",
    "form",
    "versions",
]
