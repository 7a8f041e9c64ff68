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

#: a carrier whose slender pillars dominate its torsion (3 pillars of r = 3 mm, 40 mm long, between
#: 8 mm plates): the pillar-frame closed form's test case
PILLAR_FRAME = CarrierSpec(
    plate_radius=0.04,
    input_thickness=0.008,
    output_thickness=0.008,
    gap=0.04,
    crank_circle_radius=0.015,
    crank_bore_radius=0.005,
    n_cranks=3,
    center_bore_radius=0.0,
    pillar_circle_radius=0.025,
    pillar_radius=0.003,
    pillar_angles=tuple(math.pi / 3 + 2 * math.pi * k / 3 for k in range(3)),
)

#: the coarsest mesh of the rv40e carrier [m], for tests: at most the 6.5 mm ligament between the
#: 27 mm centre bore and the crank bores
RV40E_CARRIER_COARSE = 0.006
