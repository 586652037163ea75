"""Large sliding: contact between the two lips of an interface that slide far apart.

The interface is a level set in the reference configuration; after a large relative
motion its two lips (side -1 and side +1 of the Heaviside-enriched field) no longer
face each other at the same reference point. Every slave quadrature point is paired,
in the deformed configuration, with its closest point on the deformed master lip
(:mod:`~xfem_contact.mechanics.sliding.lips`, :mod:`~xfem_contact.mechanics.sliding.projection`),
the slave pieces first broken where their feet cross master-piece ends, one Gauss rule
per sub-segment (:mod:`~xfem_contact.mechanics.sliding.segments`);
the hybrid element of each pair couples the slave cell's displacement and multiplier
dofs with the master cell's displacement dofs
(:mod:`~xfem_contact.mechanics.sliding.element`), assembled outside UFL into the same
Newton system (:mod:`~xfem_contact.mechanics.sliding.coupling`). The law object that
asks for it is :class:`~xfem_contact.mechanics.laws.sliding.SlidingFrictionless`.
"""
