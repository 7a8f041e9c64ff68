"""Declared outputs (flexrv/model/outputs.py) and the rule that only the model layer knows the
member names and the state layout (issue 16).

Above ``flexrv/model/`` (post, viz, simulation, sweep, studies, workflows, cli) no code may
slice the state vector by member (``model.slice(...)``, ``model.group_state(...)``,
``model.members[...]``, a member's ``offset``) or spell a member name (``"crank0"``,
``f"crank{j}"``, ``"disc1"``, ``f"planet{j}"``, ``"carrier"`` as a member key): results are read
by name from the declared outputs.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1] / "flexrv"
#: the code above the model layer
ABOVE_MODEL = ("post", "viz", "simulation.py", "sweep.py", "studies", "workflows", "cli")

_MEMBER_PREFIXES = ("crank", "disc", "planet", "carrier", "main_bearing_balls", "main_bearing_")
_MEMBER_CONSTANT = re.compile(r"^(crank|disc|planet)\d+$")
_STATE_CALLS = {"slice", "group_state"}


def member_literals(source: str, filename: str = "<string>") -> list[str]:
    """Where ``source`` uses the state layout or spells a member name (see module docstring)."""
    found = []
    for node in ast.walk(ast.parse(source, filename)):
        line = f"{filename}:{getattr(node, 'lineno', '?')}"
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr in _STATE_CALLS:
            found.append(f"{line}: .{node.func.attr}(...) slices the state by member")
        elif isinstance(node, ast.Subscript) and isinstance(node.value, ast.Attribute) and node.value.attr == "members":
            found.append(f"{line}: .members[...] looks a member up by name")
        elif isinstance(node, ast.Attribute) and node.attr == "offset":
            found.append(f"{line}: .offset is a member's position in the state vector")
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) and _MEMBER_CONSTANT.match(node.value):
            found.append(f"{line}: member name {node.value!r}")
        elif isinstance(node, ast.JoinedStr):
            parts = node.values
            for a, b in zip(parts, parts[1:]):
                if (
                    isinstance(a, ast.Constant)
                    and isinstance(a.value, str)
                    and isinstance(b, ast.FormattedValue)
                    and re.search(r"(^|[^A-Za-z_])(" + "|".join(_MEMBER_PREFIXES) + r")$", a.value)
                ):
                    found.append(f"{line}: member name f-string {a.value!r}{{...}}")
    return found


def _files_above_model():
    for name in ABOVE_MODEL:
        path = ROOT / name
        yield from ([path] if path.is_file() else sorted(path.rglob("*.py")))


def test_scanner_finds_planted_member_literals():
    """The scanner flags each kind of member-name / state-index use and passes the by-name
    reads post uses (a scanner that cannot fail would be a defect)."""
    bad = """
cs = model.slice("carrier")
crank = [q[:, model.slice(f"crank{j}")] for j in range(3)]
d = model.members["disc0"].mass_matrix
o = member.offset
x = state["planet1"]
qg = model.group_state(g, q)
"""
    hits = member_literals(bad)
    assert len(hits) == 8, hits  # slice x2, f"crank{", members[], "disc0", offset, "planet1", group_state
    good = """
th = res["theta_out"].values
w = res["crank_speed"].values[:, 0]
label = f"crank {j}"
names = {"carrier": "output (carrier)", "crank_rotation": "crank"}
"""
    assert member_literals(good) == []


def test_no_member_name_or_state_index_outside_model():
    """post/, viz/, simulation.py, sweep.py, studies/, workflows/ and cli/ read results by
    name: no member-name literal and no state slicing anywhere in them."""
    hits = [
        h
        for path in _files_above_model()
        for h in member_literals(path.read_text(encoding="utf-8"), str(path.relative_to(ROOT.parent)))
    ]
    assert not hits, "member names / state layout used above the model layer:\n" + "\n".join(hits)


def test_declared_outputs_have_units_and_names():
    """Every member-state and derived output declares dims (time first), a unit and a long
    name; the member roles cover carrier, cranks and discs."""
    from flexrv.model.outputs import ROLES, STATE_OUTPUTS, declared_outputs

    decl = declared_outputs()
    assert {
        "theta_in",
        "theta_out",
        "omega_in",
        "omega_out",
        "crank_x",
        "disc_speed",
        "carrier_tilt",
        "kinetic_energy",
        "angular_momentum",
        "input_torque",
        "output_torque",
    } <= set(decl)
    for name, (dims, units, long_name) in decl.items():
        assert dims[0] == "time" and units and long_name, name
    assert {s.role for s in STATE_OUTPUTS} == set(ROLES)
    assert all(s.state in ("q", "v") for s in STATE_OUTPUTS)


@pytest.fixture(scope="module")
def run():
    """A short rigid rv40e run and its model (states kept for independent checks)."""
    from flexrv.simulation import Simulation

    sim = Simulation("rv40e")
    res = sim.run(t_end=0.004, dt=1e-4)
    return sim, res


def test_results_are_the_declared_outputs(run):
    """The Results variables carry the declared units and long names; TE, the powers and
    the energy bookkeeping follow from the outputs by name: TE = (theta_out - theta_in / i)
    * 206264.806 arcsec/rad, P_out = T_load omega_out, P_in = T_in omega_in (exact)."""
    from flexrv.model.outputs import declared_outputs

    _, res = run
    for name, (dims, units, long_name) in declared_outputs().items():
        da = res[name]
        assert da.dims == dims and da.attrs["units"] == units and da.attrs["long_name"] == long_name, name
    te = (res["theta_out"].values - res["theta_in"].values / res.attrs["ratio"]) * 206264.80624709636
    assert np.allclose(res["te"].values, te, rtol=1e-12, atol=1e-12)
    assert np.array_equal(res["power_out"].values, res["output_torque"].values * res["omega_out"].values)
    assert np.array_equal(res["power_in"].values, res["input_torque"].values * res["omega_in"].values)
    rel = res["crank_speed"].values - res["omega_out"].values[:, None]
    assert np.array_equal(res["crank_speed_relative"].values, rel)


def test_member_outputs_match_the_state_vector():
    """model_outputs against the state vector read independently (member slices, here in the
    test): the carrier's theta and x, every crank's phi speed and every disc's y; kinetic
    energy = sum 1/2 v^T M v + 1/2 J_in omega_in^2 on random states (machine precision)."""
    from flexrv.design import load
    from flexrv.model.factory import build_model
    from flexrv.model.outputs import model_outputs

    model = build_model(load("rv40e"), "rigid")
    rng = np.random.default_rng(3)
    t = np.linspace(0.0, 0.01, 5)
    q = model.q0[None, :] + 1e-4 * rng.standard_normal((len(t), model.n))
    v = rng.standard_normal((len(t), model.n))
    out = model_outputs(model, t, q, v)
    car = model.members["carrier"].offset
    assert np.array_equal(out["theta_out"].values, q[:, car + 2])
    assert np.array_equal(out["carrier_x"].values, q[:, car])
    assert np.allclose(out["carrier_tilt"].values, np.hypot(q[:, car + 4], q[:, car + 5]))
    p = model.params
    for j in range(p.n_cranks):
        assert np.array_equal(out["crank_speed"].values[:, j], v[:, model.members[f"crank{j}"].offset + 2])
    for k in range(p.n_discs):
        assert np.array_equal(out["disc_y"].values[:, k], q[:, model.members[f"disc{k}"].offset + 1])
    ke = sum(
        0.5 * np.einsum("ti,ij,tj->t", v[:, m.offset : m.offset + m.n], m.mass_matrix, v[:, m.offset : m.offset + m.n])
        for m in model.members.values()
    )
    ke = ke + 0.5 * p.input_inertia * np.asarray(model.input_speed(t)) ** 2
    assert np.allclose(out["kinetic_energy"].values, ke, rtol=1e-13, atol=0)
    assert out["crank_x"].dims == ("time", "crank") and out["disc_y"].values.shape == (len(t), p.n_discs)


def test_post_has_no_output_name_triggers():
    """TE, the powers and the friction sum are declared outputs of the model
    (flexrv.model.outputs): post/results.py builds the dataset from the declared outputs
    without computing variables on the sight of a name (``if name == "omega_out"``), and
    post/stats.py finds the friction outputs by their declared role, not by a list of names."""
    import re
    from pathlib import Path

    post = Path(__file__).resolve().parents[1] / "flexrv" / "post"
    results = (post / "results.py").read_text()
    assert not re.search(r"if name == \"", results)
    stats = (post / "stats.py").read_text()
    assert "pin_friction_power" not in stats and "needle_friction_power" not in stats
