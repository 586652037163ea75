"""Scenes: declarative TOML simulations, their builder and runner, and the command line.

Owns the scene schema and validated records (:mod:`~xfem_contact.scenes.schema`),
loading and validation (:mod:`~xfem_contact.scenes.scene`), safe expressions of the
coordinates (:mod:`~xfem_contact.scenes.expressions`), the effect-selective builder
and runner (:mod:`~xfem_contact.scenes.run`), the ``xfem-contact`` command
(:mod:`~xfem_contact.scenes.cli`) and the bundled scene files (``*.toml``,
``*.geo``). The top step of the layout: it may import every other sub-package
(:mod:`xfem_contact.codegen` up to :mod:`xfem_contact.cases`); none imports it.
"""
