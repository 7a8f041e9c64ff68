"""Compiled force kernels (issue 15): the groups' compiled kernels and the fused
element reproduce the numpy groups they replaced, their Jacobians match finite
differences, the as-built fields act as their formulas say, a skipped pin is a
failure, and a short rigid run gives the same TE."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from flexrv.model.factory import build_model

REF = Path(__file__).parent / "data" / "force_reference.npz"
CASES = [("rv40e", "empirical"), ("rv40e", "rollers"), ("rv221", "empirical"), ("rv221", "rollers")]


def _variant(name, needle):
    import importlib.util

    spec = importlib.util.spec_from_file_location("make_force_reference", REF.with_name("make_force_reference.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.variant(name, needle)


def _close(a, b, rel=1e-9, what=""):
    """|a - b| <= rel * max|b| (+ a 1e-300 floor for all-zero references)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    assert a.shape == b.shape, (what, a.shape, b.shape)
    scale = max(np.max(np.abs(b), initial=0.0), 1e-300)
    err = np.max(np.abs(a - b), initial=0.0)
    assert err <= rel * scale, f"{what}: max error {err:.3g} vs scale {scale:.3g}"


@pytest.fixture(scope="module")
def ref():
    return np.load(REF)


@pytest.mark.parametrize("name,needle", CASES)
def test_groups_match_reference(ref, name, needle):
    """Each group's compiled kernel (evaluate, jacobian, outputs on the 20 states as
    a history) equals the numpy groups of before issue 15 (tests/data/
    make_force_reference.py) within 1e-9 of each array's largest entry. The angular
    outputs of rollers compare modulo 2 pi."""
    key = f"{name}-{needle}"
    m = build_model(_variant(name, needle), exudyn=False)
    t, q, v = ref[f"{key}/t"], ref[f"{key}/q"], ref[f"{key}/v"]
    for g in m.groups:
        qg, vg = m.group_state(g, q), m.group_state(g, v)
        for i in range(len(t)):
            g.reset()
            f, _ = g.evaluate(float(t[i]), qg[i], vg[i])
            _close(f, ref[f"{key}/{g.name}/force"][i], what=f"{key} {g.name} force {i}")
            g.reset()
            jq, jv = g.jacobian(float(t[i]), qg[i], vg[i])
            _close(jq, ref[f"{key}/{g.name}/jac_q"][i], what=f"{key} {g.name} jac_q {i}")
            _close(jv, ref[f"{key}/{g.name}/jac_v"][i], what=f"{key} {g.name} jac_v {i}")
        g.reset()
        _, out = g.evaluate(t, qg, vg, want_outputs=True)
        names = {k.split("/out/")[1] for k in ref.files if k.startswith(f"{key}/{g.name}/out/")}
        assert set(out) == names, g.name
        for k, o in out.items():
            r = ref[f"{key}/{g.name}/out/{k}"]
            if k == "roller_angle":
                d = np.angle(np.exp(1j * (o.values - r)))
                _close(d + np.pi, np.full_like(r, np.pi), what=k)
            else:
                _close(o.values, r, what=f"{key} {g.name} {k}")


@pytest.mark.parametrize("name,needle", CASES)
def test_fused_generalized_forces_match_reference(ref, name, needle):
    """AssembledModel.generalized_forces (ONE call of the fused compiled kernel)
    equals the sum of the reference groups' forces and Jacobians (1e-9 rel.)."""
    from flexrv.model.base import group_index

    key = f"{name}-{needle}"
    m = build_model(_variant(name, needle), exudyn=False)
    t, q, v = ref[f"{key}/t"], ref[f"{key}/q"], ref[f"{key}/v"]
    for i in range(len(t)):
        for g in m.groups:
            g.reset()
        f, dq, dv = m.generalized_forces(float(t[i]), q[i], v[i])
        fr, dqr, dvr = np.zeros(m.n), np.zeros((m.n, m.n)), np.zeros((m.n, m.n))
        for g in m.groups:
            ix = np.arange(m.n)[group_index([m.members[n].offset for n in g.members],
                                            [m.members[n].n for n in g.members])]
            fr[ix] += ref[f"{key}/{g.name}/force"][i]
            dqr[np.ix_(ix, ix)] += ref[f"{key}/{g.name}/jac_q"][i]
            dvr[np.ix_(ix, ix)] += ref[f"{key}/{g.name}/jac_v"][i]
        _close(f, fr, what="force")
        _close(dq, dqr, what="jac_q")
        _close(dv, dvr, what="jac_v")
