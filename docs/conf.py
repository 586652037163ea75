"""Sphinx configuration of the xfem-contact documentation (``make docs``).

The pages are markdown (MyST); the API reference comes from the docstrings
(autodoc + napoleon, Google style); the scene file reference, the solver options
table, the demo pages and the benchmark pages (from ``bench/results/``) are generated
(:mod:`reference`) into ``docs/generated/``, kept in the repository so that links resolve
in a checkout too; every build rewrites them, so they cannot drift from what the
package accepts and measures.
"""

import pathlib
import sys

import xfem_contact  # before dolfinx (the PyPI wheel's MPI)

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import reference  # noqa: E402

project = "xfem-contact"
author = "the xfem-contact developers"
release = version = xfem_contact.__version__
extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.viewcode",
]
myst_enable_extensions = ["colon_fence"]
myst_heading_anchors = 3
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
exclude_patterns = ["_build", "README.md"]
html_theme = "alabaster"
html_theme_options = {"page_width": "1100px", "sidebar_width": "240px"}
html_title = f"xfem-contact {release}"
autodoc_member_order = "bysource"
autodoc_typehints = "none"  # the docstrings state units and shapes
autodoc_default_options = {"members": True, "show-inheritance": True}
napoleon_google_docstring = True
napoleon_numpy_docstring = False
napoleon_use_ivar = True  # attributes as fields: no second description of tuple fields


def setup(app):
    reference.write(reference.FOLDER)
