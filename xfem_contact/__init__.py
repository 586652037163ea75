"""xfem_contact: X-FEM contact mechanics with quadratic elements on curved interfaces.

A FEniCSx (DOLFINx 0.11) plugin. Import it before or after ``dolfinx``: the
PyPI wheel ``dolfinx-solver-real`` needs ``dolfinx_solver`` imported first, which
is done here when that wheel is installed.
"""

try:  # The PyPI wheel loads its MPI/PETSc libraries through this module.
    import dolfinx_solver  # noqa: F401
except ImportError:  # conda/apt DOLFINx: nothing to do
    pass

__version__ = "0.1.0"

from xfem_contact.fem.cutmesh import CutMesh  # noqa: E402
from xfem_contact.fem.forms import form  # noqa: E402
from xfem_contact.mechanics.materials import Material  # noqa: E402
from xfem_contact.mechanics.presets import ContactProblem, ElasticityProblem  # noqa: E402
from xfem_contact.mechanics.problem import Problem  # noqa: E402
from xfem_contact.quadrature.cell_rules import CellRules  # noqa: E402
from xfem_contact.solvers.newton import NewtonFailure  # noqa: E402

__all__ = [
    "CellRules",
    "ContactProblem",
    "CutMesh",
    "ElasticityProblem",
    "Material",
    "NewtonFailure",
    "Problem",
    "form",
]
