"""The element registry (flexrv.model.core.registry): a force element defined here, in
this test module, with ONE registry line, appears in the fused kernel, the outputs,
the friction sum, the summary and the budget without any other file knowing it, and
builds its own typed parameters from the design; and every registered element declares
what the guide in CONTRIBUTING.md asks for."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import pytest
from numba import njit

import flexrv.model.kernels  # noqa: F401  (the built-in elements first: the toy is called last)
from flexrv.model.base import KernelGroup, Output, SummaryRow
from flexrv.model.core.params import empty_pack, law_type, pack_type
from flexrv.model.core.registry import ELEMENTS, register

# ------------------------------------------------------------------ the toy element
#: a torsional spring and viscous damper between the carrier and the (fixed) housing
ToyLaw = law_type("ToyLaw", k=float, c=float)
ToyPack = pack_type(
    "ToyPack", ("idx", (np.int64, 1)), ("law", ToyLaw), ("torque", (np.float64, (1,))), ("power", (np.float64, (1,)))
)


@njit(cache=True)
def toy_kernel(q, v, f, jq, jv, jac, pack):
    """Torque M = -k theta - c omega on the carrier's rotation (idx[2]); its damper's
    power c omega^2 (dissipated, declared as friction)."""
    i = pack.idx[2]
    m = -pack.law.k * q[i] - pack.law.c * v[i]
    f[i] += m
    pack.torque[0] = m
    pack.power[0] = pack.law.c * v[i] * v[i]
    if jac:
        jq[i, i] -= pack.law.k
        jv[i, i] -= pack.law.c


@dataclass(frozen=True)
class ToyParameters:
    """The toy's typed parameters: spring k [N m/rad], damper c [N m s/rad]."""

    k: float
    c: float


def toy_parameters(reducer, drive) -> ToyParameters:
    """From the design: a spring that holds the rated torque at a twist of 2 mrad, damped at
    30 % of critical on the carrier's polar inertia (the shared drive parameters)."""
    k = reducer.operating.rated_torque_Nm / 2e-3
    return ToyParameters(k=k, c=2.0 * 0.3 * math.sqrt(k * drive.carrier_inertia))


class ToyTorsion(KernelGroup):
    """The toy element (members: carrier)."""

    name = "toy_torsion"
    kind = "toy_torsion"
    kernel = staticmethod(toy_kernel)
    members = ("carrier",)
    friction_outputs = ("toy_damper_power",)
    summary_rows = (
        SummaryRow("max_toy_torque_Nm", "N m", "largest |torque| of the toy spring", "toy_torque", "max_abs"),
    )

    parameters = staticmethod(toy_parameters)

    def __init__(self, params: ToyParameters):
        self.params = params
        self.law = ToyLaw.of(k=params.k, c=params.c)
        self.torque, self.power = np.zeros(1), np.zeros(1)

    def pack(self, idx, history=False):
        return ToyPack(idx, self.law, self.torque, self.power)

    @staticmethod
    def empty_pack():
        return empty_pack(ToyPack)

    def record_sources(self):
        return {"torque": self.torque, "power": self.power}

    def outputs(self, t, rec):
        return {
            "toy_torque": Output(rec["torque"][..., 0], ("time",), "N m", "torque of the toy spring on the carrier"),
            "toy_damper_power": Output(rec["power"][..., 0], ("time",), "W", "power dissipated by the toy damper"),
        }


register(ToyTorsion)  # the one registry line


def _toy_constants():
    from flexrv.design import load
    from flexrv.model.drive import drive_parameters

    red = load("rv40e")
    p = toy_parameters(red, drive_parameters(red))
    return p.k, p.c


K_TOY, C_TOY = _toy_constants()  # rv40e: the closed forms below read the toy's own parameters


def _states(model, n=5, seed=4):
    """A few loaded states: discs turned into the pins, the carrier turned and turning."""
    rng = np.random.default_rng(seed)
    q = np.tile(model.q0, (n, 1))
    v = np.zeros_like(q)
    for k in range(model.params.n_discs):
        q[:, model.slice(f"disc{k}").start + 2] += 1.5e-4
    for j in range(model.params.n_cranks):
        q[:, model.slice(f"crank{j}").start + 2] += 5e-5
    c = model.slice("carrier").start + 2
    q[:, c] += np.linspace(1e-4, 3e-4, n)
    v[:, c] = np.linspace(-0.5, 0.5, n)
    return q + rng.normal(scale=1e-8, size=q.shape), v


@pytest.fixture(scope="module")
def toy_model():
    from flexrv.design import load
    from flexrv.model.factory import build_model

    base = build_model(load("rv40e"), exudyn=False)
    toy = build_model(load("rv40e"), exudyn=False)
    toy.groups.append(ToyTorsion.from_design(load("rv40e"), toy.params))  # its own parameters, from the design
    assert (toy.groups[-1].params.k, toy.groups[-1].params.c) == (K_TOY, C_TOY)
    return base, toy


def test_toy_element_is_in_the_fused_kernel(toy_model):
    """The fused kernel of the model with the toy element (generated from the registry)
    gives the model's forces and Jacobians plus exactly the toy's: on the carrier's
    rotation -k theta - c omega (closed form), Jacobian entries -k, -c; every other
    entry bit-identical to the model without it."""
    base, toy = toy_model
    assert [s.kind for s in ELEMENTS.values()][-1] == "toy_torsion"
    q, v = _states(base, n=1)
    f0, dq0, dv0 = base.generalized_forces(0.0, q[0], v[0])
    f1, dq1, dv1 = toy.generalized_forces(0.0, q[0], v[0])
    assert "toy_torsion" in [g.kind for g, _ in toy.fused.slots]
    c = base.slice("carrier").start + 2
    expected = -K_TOY * q[0, c] - C_TOY * v[0, c]
    assert f1[c] - f0[c] == pytest.approx(expected, rel=1e-12)
    other = np.arange(len(f0)) != c
    np.testing.assert_array_equal(f1[other], f0[other])
    assert dq1[c, c] - dq0[c, c] == pytest.approx(-K_TOY, rel=1e-9)
    assert dv1[c, c] - dv0[c, c] == pytest.approx(-C_TOY, rel=1e-12)


def test_toy_element_in_outputs_friction_and_summary(toy_model, tmp_path):
    """Results built from states of the toy model (flexrv.post.results_from_states) carry
    the toy's declared outputs (its torque equals the closed form at every sample), the
    friction sum includes its damper power c omega^2, and the run summary (summary.json
    and summary.md, rendered by flexrv.post) lists its declared summary row with the
    largest |torque| of the window."""
    import json

    from flexrv.post.io import save
    from flexrv.post.results import results_from_states

    base, toy = toy_model
    q, v = _states(toy)
    t = np.linspace(0.0, 4e-4, len(q))
    res = results_from_states(toy, t, q, v, dt=1e-4)
    ref = results_from_states(base, t, q, v, dt=1e-4)
    c = toy.slice("carrier").start + 2
    torque = -K_TOY * q[:, c] - C_TOY * v[:, c]
    np.testing.assert_allclose(res.ds["toy_torque"].values, torque, rtol=1e-12)
    assert res.ds["toy_damper_power"].attrs["role"] == "friction"
    damper = C_TOY * v[:, c] ** 2
    base_fric = ref.ds["friction_power"].values if "friction_power" in ref.ds else 0.0
    np.testing.assert_allclose(res.ds["friction_power"].values, base_fric + damper, rtol=1e-12, atol=1e-12)
    res.attrs.update(steady_start_s=0.0, steady_end_s=float(t[-1]))
    d = save(res, tmp_path / "run")
    summ = json.loads((d / "summary.json").read_text())
    row = summ["elements"]["max_toy_torque_Nm"]
    assert row["value"] == pytest.approx(np.abs(torque).max(), rel=1e-12) and row["units"] == "N m"
    assert summ["mean_toy_damper_power_W"] == pytest.approx(damper.mean(), rel=1e-12)
    md = (d / "summary.md").read_text()
    assert "max_toy_torque_Nm" in md and "mean_toy_damper_power_W" in md


def test_every_registered_element_declares_its_parts():
    """The guide's "add a force element" list (CONTRIBUTING.md), checked on every
    registered element: a kind, a compiled kernel, a typed-parameters builder
    ``parameters(reducer, drive)`` whose result the constructor takes first, a pack type
    whose absent-element pack is derived (empty_pack), record sources and outputs, and at least one summary
    row, each on an output it declares, with a known reduction and a key of its own (no
    other element's, none of the run summary's table flexrv.post.stats.SUMMARY_KEYS); an
    element lacking outputs or summary rows fails here."""
    import inspect

    from flexrv.post.stats import _REDUCE, SUMMARY_KEYS

    keys = {row.key for row in SUMMARY_KEYS}
    for kind, spec in ELEMENTS.items():
        cls = spec.group
        assert cls.kind == kind and hasattr(spec.kernel, "py_func"), kind
        assert "empty_pack" in vars(cls) or any("empty_pack" in vars(b) for b in cls.__mro__[:-1]), kind
        assert cls.outputs is not KernelGroup.outputs, f"{kind}: declares no outputs"
        assert cls.record_sources is not KernelGroup.record_sources, f"{kind}: records nothing"
        src = inspect.getsource(cls.outputs)
        assert cls.summary_rows, f"{kind}: declares no summary rows"
        for row in cls.summary_rows:
            assert f'"{row.source}"' in src, f"{kind}: summary row {row.key} reads an undeclared output"
            assert row.reduce in _REDUCE and row.units, f"{kind}: summary row {row.key}"
            assert row.key not in keys, f"{kind}: summary key {row.key} is taken"
            keys.add(row.key)
        for name in cls.friction_outputs:
            assert f'"{name}"' in src, f"{kind}: friction output {name} is not declared"
        build = inspect.getattr_static(cls, "parameters", None)
        assert isinstance(build, staticmethod), f"{kind}: declares no parameters builder"
        assert list(inspect.signature(build.__func__).parameters)[:2] == ["reducer", "drive"], kind
        first = list(inspect.signature(cls.__init__).parameters)[1]
        assert first == "params", f"{kind}: the constructor takes the typed parameters first"


def test_toy_element_in_the_stiffness_budget():
    """The model route of the stiffness budget (flexrv.analysis.budget.stiffness_budget with
    the quasi-static model's strain-energy shares, as ``flexrv te``) lists the toy element by
    its group name with nothing else changed. Closed form (Castigliano): the toy spring
    holds the output against the housing in parallel with the reducer, so under a unit
    output torque it turns by the total compliance C and stores k C^2 / 2: its share is
    k C and its budget compliance k C^2 (to 1e-9: the shares come from the same tangent);
    the shares of all groups sum to 1."""
    from flexrv.analysis.budget import ModelShares, stiffness_budget
    from flexrv.design import load
    from flexrv.model.quasi_static import StaticModel, ramp_to

    red = load("rv40e")
    sm = StaticModel(red)
    sm.model.groups.append(ToyTorsion(dataclasses.replace(ToyTorsion.parameters(red, sm.p), c=0.0)))
    sm.model.fused = None  # the fused kernel of the groups with the toy
    theta = 0.1
    q = ramp_to(sm, theta, sm.kinematic_pose(theta), red.operating.rated_torque_Nm)
    shares = sm.compliance_budget(theta, q)
    c = 1.0 / sm.tangent_rigidity(theta, q)
    assert sum(shares.values()) == pytest.approx(1.0, rel=1e-9)
    assert shares["toy_torsion"] == pytest.approx(K_TOY * c, rel=1e-9)
    budget = stiffness_budget(red, model=ModelShares(shares, c), route="quasi_static")
    assert budget.compliances["toy_torsion"] == pytest.approx(K_TOY * c * c, rel=1e-9)
    assert "toy_torsion" in budget.to_dict()["elements"]


def test_compiled_run_has_one_entry_point_with_one_call_site_per_kernel():
    """The generated ``fused_integrate`` (the compiled integrator) calls every element's kernel at
    exactly one site and neither ``fused_kernel`` nor ``fused_history``: numba links a copy of every
    callee into each compiled entry point and generates its machine code again there, so a run on
    the compiled integrator, whose evaluations from Python go through the same function (ROWS mode,
    FusedForces.drive_with), compiles the elements' code once more, not three times (rv221 rigid:
    the background job's compile CPU 58.7 -> 42.2 s with the block elimination pruned,
    benchmarks/bench_compile.py). Each kernel appears in fused_kernel once as well."""
    import re

    from flexrv.model.core.registry import ELEMENTS, _fused_source

    specs = list(ELEMENTS.values())
    src = _fused_source(specs, "0" * 16)
    bodies = dict(re.findall(r"\ndef (\w+)\((.*?)(?=\n\n\n|\Z)", src, flags=re.S))
    assert set(bodies) == {"fused_kernel", "fused_history", "fused_integrate"}
    integrate, kernel = bodies["fused_integrate"], bodies["fused_kernel"]
    for i in range(len(specs)):
        assert len(re.findall(rf"\bk{i}\(", integrate)) == 1, i
        assert len(re.findall(rf"\bk{i}\(", kernel)) == 1, i
    assert "fused_kernel(" not in integrate and "fused_history(" not in integrate
    assert "after_eval(st, f, jq, jv, blocks)" in integrate  # the block elimination pruned when blocks is None
    # array copies are loops: a slice assignment from an array compiles numba's error-message formatting
    assert set(re.findall(r"\[[^\]]*:\] = (.+)", src)) == {"0.0"}
