"""Flexible (reduced) bearing rings in the ball-resolved main bearing.

References: the full FE static solution of the clamped ring under the same ball
loads (patch-distributed as in the reduction, :mod:`flexrv.fem.reduction`), the
rigid-ring bearing (stiff-ring limit), Hamrock–Dowson film and Hertz pressure for
the per-ball outputs.
"""

from __future__ import annotations

import numpy as np
import pytest

from flexrv.design import load
from flexrv.fem.body import _assemble, build_reduced_body, material_dict, raceway_spec_for
from flexrv.fem.modal import factorize, free_dofs
from flexrv.fem.reduction import nodal_areas, raceway_weights
from flexrv.meshing import build_mesh, spec_for
from flexrv.model.flexible_bearing import (RING_EIGENMODES, RING_HARMONICS, ModalRing, rows_from_design,
                                           rxyz_matrices)
from tests.test_model_flexible_bearing import _static_rig

SIZE, LOCAL = 0.015, 0.01  # coarse rv221 rings (as tests/test_fem_reduction.py)
#: seed 001's first external load case: 20 kN radial, 15 kN axial
SEED001_FORCE = (20000.0, 0.0, 15000.0)


@pytest.fixture(scope="module")
def rings(tmp_path_factory):
    """rv221 outer and inner rings, coarse mesh, reduced with the dynamic model's
    default basis (RING_HARMONICS, RING_EIGENMODES); full FE kept for reference."""
    import os
    os.environ["FLEXRV_CACHE"] = str(tmp_path_factory.mktemp("cache"))
    rv = load("rv221")
    out = {}
    for part in ("outer_ring", "inner_ring"):
        mres = build_mesh(rv, part, size=SIZE, local_size=LOCAL)
        mat = material_dict(rv, part)
        fe = _assemble(mres.data, mat)
        spec = raceway_spec_for(spec_for(rv, part), None, RING_HARMONICS)
        body = build_reduced_body(mres, mat, n_eig=RING_EIGENMODES, raceway=spec, fe=fe)
        out[part] = (mres, fe, body)
    yield rv, out
    del os.environ["FLEXRV_CACHE"]


def fe_contact_deflection(rv, part, mres, fe, azimuth, forces):
    """Full-FE patch-mean raceway displacement (n, 3) [m] under patch loads
    ``forces`` (n, 3) [N] at ``azimuth`` (n,), fit clamped."""
    d = mres.data
    rs = raceway_spec_for(spec_for(rv, part), None, 0)
    race = d.node_set("raceway")
    w = raceway_weights(d.nodes, race, nodal_areas(d.nodes, d.faces("raceway")), rs, azimuth).toarray()
    f = np.zeros(fe.n_dof)
    for c in range(3):
        f[3 * race + c] = w.T @ forces[:, c]
    idofs = free_dofs(fe.n_dof, d.node_set("fit"))
    u = np.zeros(fe.n_dof)
    u[idofs] = factorize(fe.K[idofs][:, idofs])(f[idofs])
    return w @ u.reshape(-1, 3)[race]


def _flexible_rows(rv, out, scale=1.0, rings=("inner", "outer")):
    kw = {}
    for label in rings:
        body = out[f"{label}_ring"][2]
        kw[label] = [ModalRing(body, stiffness_scale=scale), ModalRing(body, stiffness_scale=scale, mirror=True)]
    return rows_from_design(rv, ehl="dry", **kw)


def test_ring_deflection_under_ball_loads_matches_full_fe(rings):
    """Seed 001's 20 kN radial + 15 kN axial case: the static bearing with both
    rings flexible gives ball loads and modal ring coordinates; the reduced ring's
    raceway deflection at every loaded ball (along its contact normal) equals the
    full FE solution of the clamped ring under the same ball loads within 1 % of
    the largest deflection (measured 0.08 %; outer and inner ring, both rows; the second row is the
    mirror image z -> -z of the meshed ring, so its loads are mirrored for the
    FE reference)."""
    rv, out = rings
    rows, evals, frame_q, qs = _static_rig(rv, SEED001_FORCE, rows=_flexible_rows(rv, out), coordinates=True)
    checked = 0
    for k, (row, ev) in enumerate(zip(rows, evals)):
        for label, st in (("outer", ev.outer), ("inner", ev.inner)):
            mres, fe, body = out[f"{label}_ring"]
            loaded = st.load > 0.02 * st.load.max()
            load_on_ring = (-st.force_ball)[loaded]  # force of the ball on the ring (global frame)
            if label == "inner":  # inner ring: its frame is the (slightly displaced) carrier frame
                a_mat = rxyz_matrices(frame_q[3:6])[0]
                local = (ev.ball_pos[loaded] - frame_q[0:3]) @ a_mat
                load_on_ring = load_on_ring @ a_mat
                normal = st.normal[loaded] @ a_mat
            else:
                local = ev.ball_pos[loaded]
                normal = st.normal[loaded]
            psi = np.arctan2(local[:, 1], local[:, 0])
            mirror = np.array([1.0, 1.0, -1.0 if k == 1 else 1.0])
            ref = fe_contact_deflection(rv, f"{label}_ring", mres, fe, psi, load_on_ring * mirror) * mirror
            ring = getattr(row, label)
            _, si, so, _ = row.slices()
            q_modal = qs[k][si] if label == "inner" else qs[k][so]
            red = np.einsum("nkm,m->nk", ring.groove_basis(psi), q_modal)
            ref_n = np.einsum("nk,nk->n", ref, normal)
            red_n = np.einsum("nk,nk->n", red, normal)
            assert ref_n.max() > 5e-7  # a real deflection of the order of um
            assert np.abs(red_n - ref_n).max() < 0.01 * np.abs(ref_n).max(), (k, label, red_n, ref_n)
            checked += 1
    assert checked == 4
