"""Crank bending between the support journals and the eccentrics (issue 14): the
FE condensation of the crankshaft onto the eccentrics' lateral DOF relative to the
supports (flexrv.fem.crankshaft.crank_bending_compliance) vs the Timoshenko
stepped-shaft law the models use (flexrv.analysis.torsional.crank_bending)."""

from __future__ import annotations

import numpy as np
import pytest

from flexrv.analysis.torsional import crank_bending
from flexrv.design import load
from flexrv.fem.crankshaft import crank_bending_compliance


@pytest.mark.parametrize("name,tol", [("rv40e", 0.03), ("rv221", 0.08)])
def test_fe_bending_vs_timoshenko_stepped_shaft(name, tol):
    """Symmetric crank-centre stiffness k_sym = 4 / sum C_ij and the compliance
    matrix entries: FE (Tet10, default mesh, distributing interfaces: the supports'
    mean displacement held, loads spread over the eccentric surfaces) vs the
    Timoshenko stepped shaft simply supported at the journal centres. Measured:
    rv40e k_sym +0.6 % (+-0.2 % on a 0.6x mesh), rv221 +4.7 % (its short, thick
    segments, L/d ~ 0.5, are less beam-like: the plane-section assumption and the
    load spread over the journal length). Tolerances: 3 % / 8 % on k_sym, twice
    that on single entries (the FE eccentric offsets 2e make C_11, C_22 differ
    by up to 7 %, which the beam cannot see)."""
    r = load(name)
    fe = crank_bending_compliance(r)
    beam = crank_bending(r)
    assert fe.k_symmetric == pytest.approx(beam.k_symmetric, rel=tol)
    np.testing.assert_allclose(fe.compliance, beam.compliance, rtol=2 * tol)
    # each direction's condensed compliance is positive definite
    for c in (fe.compliance_x, fe.compliance_y):
        assert np.all(np.linalg.eigvalsh(c) > 0)
