"""Stiffness budget (issue 14): the analytic series model of ``flexrv design``
against the quasi-static model's strain-energy budget of ``flexrv te``."""

from __future__ import annotations

import pytest

from flexrv.analysis.torsional import stiffness_budget
from flexrv.design import load
from flexrv.model.quasi_static import StaticModel, ramp_to


def test_analytic_and_quasi_static_budgets_agree():
    """rv40e at the rated torque, input locked, crank angle 0: the quasi-static
    tangent compliance 1/k_t and the analytic series total agree within 10 %
    (measured: analytic total 4.5 % below; the needle element is 17 % softer in the
    quasi-static model, where the cranks and discs share the load unevenly, while
    the analytic model splits it statically determinately, and the pins 8 % stiffer);
    the crank-support element (tapered-roller pairs + crank bending,
    the same compiled law in both) agrees within 3 % (measured 0.1 %)."""
    r = load("rv40e")
    sm = StaticModel(r)
    sm.torque = 0.0
    q = ramp_to(sm, 0.0, sm.kinematic_pose(0.0), r.operating.rated_torque_Nm)
    c_qs = 1.0 / sm.tangent_rigidity(0.0, q)
    shares = sm.compliance_budget(0.0, q)
    b = stiffness_budget(r)
    assert b.total == pytest.approx(c_qs, rel=0.10)
    support = b.compliances["support_bearings"] + b.compliances["crank_bending"]
    assert shares["crank_supports"] * c_qs == pytest.approx(support, rel=0.03)
