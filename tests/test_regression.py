"""Reference-value regression of short runs of every model (the pinned table in
tests/reference_values.py, Exudyn's runTestSuiteRefSol pattern): any drift of a
headline number beyond its stated tolerance fails; an intended change is made there
and recorded in CHANGELOG.md."""

from __future__ import annotations

import pytest

from tests import regression_cases
from tests.reference_values import REFERENCE, SLOW

CASES = [pytest.param(name, marks=pytest.mark.slow) if name in SLOW else name for name in REFERENCE]


@pytest.mark.parametrize("name", CASES)
def test_reference_values(name):
    ref = REFERENCE[name]
    got = getattr(regression_cases, name)()
    assert ref["source"], "every pinned entry says where its values and tolerances come from"
    for key, value in ref["values"].items():
        assert got[key] == pytest.approx(value, rel=ref["rtol"][key]), f"{name}.{key} drifted"
