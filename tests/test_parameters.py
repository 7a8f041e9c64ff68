"""The elements' typed parameters (each force element's ``parameters(reducer, drive)``,
the shared :mod:`flexrv.model.drive`): an element builds only what it needs (the FE
condensations, the analytic pin-load distribution behind the pin law and the housing's
compliance are built by the element that reads them, and no other), the expensive values
equal their builders' exactly, and the parameters pickle (dask workers)."""

from __future__ import annotations

import dataclasses
import pickle

import numpy as np
import pytest

from flexrv.design import load

#: module, function: the expensive builders (FE condensations, pin-load analysis, housing estimate)
EXPENSIVE = (
    ("flexrv.fem.carrier", "crank_support_compliance"),
    ("flexrv.fem.disc", "rim_compliance"),
    ("flexrv.analysis.pin_load", "pin_contact_constant"),
    ("flexrv.analysis.torsional", "housing_model_compliance"),
)


class Built(Exception):
    """Raised by a patched builder: the expensive part was asked for."""


def _forbid(monkeypatch):
    import importlib

    for module, name in EXPENSIVE:

        def boom(*args, _name=name, **kw):
            raise Built(_name)

        monkeypatch.setattr(importlib.import_module(module), name, boom)


def _elements():
    from flexrv.model.cranks_discs import CrankSupports, NeedleBearings
    from flexrv.model.gear_stage import GearMeshes
    from flexrv.model.loads import OutputLoads
    from flexrv.model.main_bearing_rigid import RigidMainBearing
    from flexrv.model.pins import PinContacts

    return GearMeshes, CrankSupports, NeedleBearings, PinContacts, RigidMainBearing, OutputLoads


def test_each_element_builds_only_what_it_needs(monkeypatch):
    """rv40e (condensed carrier and discs) with the FE condensations, the pin-load analysis
    and the housing estimate forbidden: the drive's parameters and those of the gear stage,
    the needle bearings, the rigid main bearing and the loads build; the crank supports ask
    for the carrier's FE condensation only, the pins for the pin-load analysis first; with
    a rigid carrier the crank supports build nothing expensive."""
    from flexrv.model.bodies import with_bodies
    from flexrv.model.drive import drive_parameters

    _forbid(monkeypatch)
    red = load("rv40e")
    drive = drive_parameters(red)
    assert drive.n_cranks == 3 and drive.crank_mass > 0.0 and drive.eccentricity > 0.0
    gear, supports, needles, pins, main_bearing, loads = _elements()
    for cls in (gear, needles, main_bearing, loads):
        p = cls.parameters(red, drive)
        assert dataclasses.is_dataclass(p) and type(p).__dataclass_params__.frozen
    with pytest.raises(Built, match="crank_support_compliance"):
        supports.parameters(red, drive)
    assert supports.parameters(with_bodies(red, []), drive).carrier_compliance.shape == (6, 6)
    with pytest.raises(Built, match="pin_contact_constant"):
        pins.parameters(red, drive)


def test_pin_parameters_equal_their_builders():
    """The pin law and housing compliance of the pins' parameters equal the builders' values
    exactly (rv40e: the Hertz line law of flexrv.analysis.pin_load.pin_contact_constant,
    exponent 10/9; the housing's ring estimate); the discs' rim compliance is the FE one per
    disc; dataclasses.replace overrides a field (the tests' stiffened bodies)."""
    from flexrv.analysis.pin_load import pin_contact_constant
    from flexrv.analysis.torsional import housing_model_compliance
    from flexrv.contact.hertz import LINE_EXPONENT
    from flexrv.fem.disc import rim_compliance
    from flexrv.model.drive import drive_parameters
    from flexrv.model.pins import PinContacts

    red = load("rv40e")
    p = PinContacts.parameters(red, drive_parameters(red))
    assert p.pin_k == pin_contact_constant(red).k and p.pin_exponent == LINE_EXPONENT
    assert p.housing_compliance == housing_model_compliance(red) > 0.0
    np.testing.assert_array_equal(p.disc_compliance[1], rim_compliance(red))
    q = dataclasses.replace(p, housing_compliance=0.0, pin_k=1.0)
    assert q.housing_compliance == 0.0 and q.pin_k == 1.0 and q.pin_exponent == p.pin_exponent


def test_parameters_pickle():
    """The drive's and every element's parameters of rv40e survive a pickle round trip
    field by field (dask workers receive models and parameters)."""
    from flexrv.model.drive import drive_parameters

    red = load("rv40e")
    drive = drive_parameters(red)
    for p in [drive] + [cls.parameters(red, drive) for cls in _elements()]:
        copy = pickle.loads(pickle.dumps(p))
        assert type(copy) is type(p)
        for f in dataclasses.fields(p):
            a, b = getattr(p, f.name), getattr(copy, f.name)
            if f.name in ("drive", "stage"):  # (the drive: checked on its own)
                continue
            if isinstance(a, np.ndarray):
                np.testing.assert_array_equal(a, b)
            elif isinstance(a, dict):
                assert a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)
            elif dataclasses.is_dataclass(a):  # the drive's as-built geometry
                for g in dataclasses.fields(a):
                    np.testing.assert_array_equal(getattr(a, g.name), getattr(b, g.name))
            else:
                assert a == b or (a != a and b != b), f.name  # (NaN: the roller law's linear stiffness)
