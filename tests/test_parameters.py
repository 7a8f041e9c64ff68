"""The model parameters (flexrv.model.parameters): the expensive ones (the elastic bodies'
FE condensations, the analytic pin-load distribution behind the pin law, the housing's
compliance) are built only when an element reads them, once, and equal the eager values."""

from __future__ import annotations

import dataclasses
import pickle

import pytest

import flexrv.model.parameters as mp
from flexrv.design import load

EXPENSIVE = ("body_compliance_matrices", "pin_contact_constant", "housing_model_compliance")


class Built(Exception):
    """Raised by a patched builder: the expensive part was asked for."""


def _forbid(monkeypatch):
    for name in EXPENSIVE:

        def boom(*args, _name=name, **kw):
            raise Built(_name)

        monkeypatch.setattr(mp, name, boom)


def test_cheap_parameters_build_nothing_expensive(monkeypatch):
    """rigid_parameters and every cheap field (masses, geometry, the support law) run with
    the FE condensation, the pin-load analysis and the housing estimate forbidden; the first
    read of a lazy field calls its builder (and only then)."""
    _forbid(monkeypatch)
    p = mp.rigid_parameters(load("rv40e"))
    assert p.n_cranks == 3 and p.crank_mass > 0.0 and p.support_law.shape == (7,) and p.eccentricity > 0.0
    for field, builder in (
        ("carrier_compliance", "body_compliance_matrices"),
        ("disc_compliance", "body_compliance_matrices"),
        ("pin_k", "pin_contact_constant"),
        ("pin_exponent", "pin_contact_constant"),
        ("housing_compliance", "housing_model_compliance"),
    ):
        with pytest.raises(Built, match=builder):
            getattr(p, field)


def test_lazy_values_equal_the_builders_and_are_built_once(monkeypatch):
    """The lazy pin law and housing compliance equal the builders' values exactly (rv40e:
    the Hertz line law of flexrv.analysis.pin_load.pin_contact_constant, exponent 10/9, the
    housing's ring estimate); a builder runs once however often the fields are read, and a
    pickled copy builds its own."""
    from flexrv.analysis.pin_load import pin_contact_constant
    from flexrv.analysis.torsional import housing_model_compliance
    from flexrv.contact.hertz import LINE_EXPONENT

    red = load("rv40e")
    calls = []

    def counted(r):
        calls.append(1)
        return pin_contact_constant(r)

    monkeypatch.setattr(mp, "pin_contact_constant", counted)
    p = mp.rigid_parameters(red)
    copy = pickle.loads(pickle.dumps(p))
    assert not calls
    assert p.pin_k == pin_contact_constant(red).k and p.pin_exponent == LINE_EXPONENT
    assert p.pin_k == p.pin_k and p.pin_exponent == LINE_EXPONENT
    assert len(calls) == 1
    assert p.housing_compliance == housing_model_compliance(red) > 0.0
    assert copy.pin_k == p.pin_k and len(calls) == 2


def test_replace_overrides_a_lazy_field(monkeypatch):
    """dataclasses.replace sets a lazy field like any other (the tests' stiffened bodies)."""
    p = mp.rigid_parameters(load("rv40e"))
    q = dataclasses.replace(p, housing_compliance=0.0, pin_k=1.0)
    assert q.housing_compliance == 0.0 and q.pin_k == 1.0 and q.pin_exponent == p.pin_exponent
