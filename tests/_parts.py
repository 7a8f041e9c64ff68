"""Small test geometries shared by several test modules."""

from __future__ import annotations

import math

from flexrv.meshing.parts import CarrierSpec

#: a small steel carrier (3 cranks, 3 pillars): meshes in a second, for exactness and convergence tests
MINI_CARRIER = CarrierSpec(
    plate_radius=0.03,
    input_thickness=0.006,
    output_thickness=0.006,
    gap=0.012,
    crank_circle_radius=0.014,
    crank_bore_radius=0.005,
    n_cranks=3,
    center_bore_radius=0.003,
    pillar_circle_radius=0.016,
    pillar_radius=0.003,
    pillar_angles=tuple(math.pi / 3 + 2 * math.pi * k / 3 for k in range(3)),
)
