"""FE assembly (scikit-fem P2), eigenmodes, Hurty–Craig–Bampton reduction with
Fourier raceway-load modes, reduced-body files and Exudyn loaders.

Public API
----------
- :func:`flexrv.fem.assembly.assemble` -> FEModel (K, M in Exudyn node-wise order)
- :func:`flexrv.fem.modal.eigenmodes` (free-free / clamped, shift-invert)
- :func:`flexrv.fem.body.reduce_part` -> :class:`ReducedBody` with
  ``raceway_displacement(q, azimuth)``, ``raceway_load_vector(azimuth, F)`` and
  ``add_modal_body(mbs)`` (NodeGenericODE2 + ObjectGenericODE2), the one Exudyn glue path
  of a reduced body
- :func:`flexrv.fem.body.part_modes` (free and constrained frequencies)
- :func:`flexrv.fem.stress.nodal_stress`, :func:`flexrv.fem.stress.von_mises`

Only this package (and model/) imports exudyn, lazily inside functions.
"""

from flexrv.fem.body import PartModes, ReducedBody, build_reduced_body, part_modes, reduce_part

__all__ = ["ReducedBody", "PartModes", "build_reduced_body", "part_modes", "reduce_part"]
