"""Reference forces of the rigid model's force groups, for tests/test_kernel.py.

Written BEFORE the groups were moved to compiled kernels (issue 15): it evaluates
every group of the rigid model (gear stage, crank supports, needle bearings,
pins, main bearing, loads) at 20 seeded random states near the nominal pose of
rv40e and rv221, each with both needle-bearing models, and stores the
generalized forces, the analytic Jacobians and the output dictionaries
(evaluated on the 20 states as one history) in tests/data/force_reference.npz.

With ``--te`` it instead runs a short rigid rv40e simulation (speed and load
ramps shortened to 5 ms, t_end 0.05 s, dt 1e-4, default Newton tolerance) and
writes the TE statistics over t > 0.02 s to tests/data/te_reference.json.
Both files were written with the code before issue 15 (commit 5cab5cb).

Run from the repository root:  python tests/data/make_force_reference.py [--te]
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

N_STATES = 20
PATH = Path(__file__).with_name("force_reference.npz")
TE_PATH = Path(__file__).with_name("te_reference.json")


#: crank supports of the presets when the references were written: one linear spring
#: per support bearing, rigid crank (issue 14 replaced them by tapered-roller pairs in
#: series with the crank's bending; the references keep the law they were written with)
LEGACY_SUPPORT_N_PER_M = {"rv40e": 2.0e8, "rv221": 5.0e8}
#: needle bearings' radial internal clearance (total play) of the presets when the references were written
LEGACY_NEEDLE_CLEARANCE_UM = {"rv40e": 6.0, "rv221": 10.0}


def legacy_supports(r, name: str):
    """Design ``r`` with the crank-support law of the references (linear, rigid crank)
    and, like them, rigidly seated pins (no [housing] table: issue 14 put the pin seats
    in series with the pin-disc contact; the references keep the pin law they were
    written with), no friction, none of the torque-path compliances of
    flexrv.analysis.path_compliances (rigid crank torsion, no [path_estimates]) and the needle
    clearance they were written with (:data:`LEGACY_NEEDLE_CLEARANCE_UM`)."""
    from flexrv.design import from_dict

    data = r.model_dump()
    data.pop("housing", None)
    data.pop("path_estimates", None)
    data["ranges"] = {k: v for k, v in data.get("ranges", {}).items() if not k.startswith("path_estimates.")}
    cs = {
        k: v
        for k, v in data["crankshaft"].items()
        if not k.startswith("support_bearing_") or k == "support_bearing_damping_Ns_per_m"
    }
    cs.update(
        support_bearing_model="linear",
        bending_model="rigid",
        torsion_model="rigid",
        support_bearing_radial_stiffness_N_per_m=LEGACY_SUPPORT_N_PER_M[name],
    )
    # frictionless, as when the references were written (issue 14 added friction, default on in the presets)
    contact = dict(data["contact"], friction=False)
    needle = dict(data["needle_bearing"], radial_clearance_um=LEGACY_NEEDLE_CLEARANCE_UM[name])
    return from_dict(
        {**data, "crankshaft": cs, "contact": contact, "needle_bearing": needle},
        source=f"{name} with the legacy crank supports, frictionless",
    )


def short_run_reducer(name: str = "rv40e"):
    """Preset with speed and load ramps shortened to 5 ms (steady after ~0.02 s)."""
    from flexrv.design import load
    from flexrv.model.bodies import with_bodies

    r = with_bodies(legacy_supports(load(name), name), [])  # rigid carrier and discs (issue 14: tests/test_bodies.py)
    op = r.operating.model_copy(update={"speed_ramp_time_s": 0.005, "load_ramp_start_s": 0.0, "load_ramp_end_s": 0.005})
    return r.model_copy(update={"operating": op})


def te_statistics(name: str = "rv40e", t_end: float = 0.05, dt: float = 1e-4) -> dict:
    """TE mean and peak-to-peak [arcsec] over t > 0.02 s of a short rigid run."""
    from flexrv.simulation import Simulation

    res = Simulation(short_run_reducer(name)).run(t_end=t_end, dt=dt)
    te = res["te"]
    sel = te.values[te["time"].values > 0.02]
    return {
        "preset": name,
        "t_end": t_end,
        "dt": dt,
        "te_mean_arcsec": float(np.mean(sel)),
        "te_pp_arcsec": float(np.ptp(sel)),
        "samples": int(len(sel)),
    }


def variant(name: str, needle: str):
    """Preset ``name`` with the needle model ``needle``, the load torque ramped in over
    0..4 ms and external radial/axial force and tilting moment (so the loads group
    is exercised at the sampled times)."""
    from flexrv.design import load
    from flexrv.model.bodies import with_bodies

    r = with_bodies(legacy_supports(load(name), name), [])  # rigid carrier and discs (issue 14: tests/test_bodies.py)
    op = r.operating.model_copy(
        update={
            "load_ramp_start_s": 0.0,
            "load_ramp_end_s": 0.004,
            "external_radial_force_N": 5000.0,
            "external_axial_force_N": 2000.0,
            "tilting_moment_Nm": 300.0,
        }
    )
    return r.model_copy(
        update={"needle_bearing": r.needle_bearing.model_copy(update={"model": needle}), "operating": op}
    )


def states(model, seed: int):
    """(t, q, v) of N_STATES random states near the nominal pose: discs turned into
    the pins (0.5..2e-4 rad), cranks turned +-1e-4 rad (drive and coast flanks),
    positions scattered by ~2 um, speeds ~1e-3 (m/s, rad/s), t in [0, 0.004] s (sun
    angle below 3e-4 rad, so mesh deflections of a few um)."""
    rng = np.random.default_rng(seed)
    p = model.params
    n = model.n
    t = rng.uniform(0.0, 0.004, N_STATES)
    q = np.tile(model.q0, (N_STATES, 1))
    q += rng.normal(scale=2e-6, size=q.shape)
    for k in range(p.n_discs):
        q[:, model.slice(f"disc{k}").start + 2] += rng.uniform(0.5e-4, 2e-4, N_STATES)
    for j in range(p.n_cranks):
        q[:, model.slice(f"crank{j}").start + 2] += rng.uniform(-1e-4, 1e-4, N_STATES)
    q[:, model.slice("carrier").start + 2] += rng.normal(scale=1e-5, size=N_STATES)
    v = rng.normal(scale=1e-3, size=(N_STATES, n))
    return t, q, v


def evaluate_groups(model, t, q, v) -> dict[str, np.ndarray]:
    """Forces, Jacobians (one state at a time, groups reset before each state)
    and outputs (the states as one history) of every group."""
    data: dict[str, np.ndarray] = {}
    for g in model.groups:
        qg, vg = model.group_state(g, q), model.group_state(g, v)
        fs, jqs, jvs = [], [], []
        for i in range(len(t)):
            g.reset()
            f, _ = g.evaluate(float(t[i]), qg[i], vg[i])
            g.reset()
            jq, jv = g.jacobian(float(t[i]), qg[i], vg[i])
            fs.append(f)
            jqs.append(jq)
            jvs.append(jv)
        data[f"{g.name}/force"] = np.array(fs)
        data[f"{g.name}/jac_q"] = np.array(jqs)
        data[f"{g.name}/jac_v"] = np.array(jvs)
        g.reset()
        _, out = g.evaluate(t, qg, vg, want_outputs=True)
        for name, o in (out or {}).items():
            data[f"{g.name}/out/{name}"] = np.asarray(o.values, dtype=float)
        g.reset()
    return data


def main() -> None:
    from flexrv.model.factory import build_model

    arrays: dict[str, np.ndarray] = {}
    for seed, (name, needle) in enumerate(
        [("rv40e", "empirical"), ("rv40e", "rollers"), ("rv221", "empirical"), ("rv221", "rollers")]
    ):
        model = build_model(variant(name, needle), exudyn=False)
        t, q, v = states(model, seed)
        key = f"{name}-{needle}"
        arrays[f"{key}/t"], arrays[f"{key}/q"], arrays[f"{key}/v"] = t, q, v
        for k, a in evaluate_groups(model, t, q, v).items():
            arrays[f"{key}/{k}"] = a
        print(key, model.n, "coordinates")
    np.savez_compressed(PATH, **arrays)
    print(f"wrote {PATH} ({PATH.stat().st_size / 1024:.0f} kB, {len(arrays)} arrays)")


if __name__ == "__main__":
    import json
    import sys

    if "--te" in sys.argv:
        TE_PATH.write_text(json.dumps(te_statistics(), indent=1) + "\n")
        print(TE_PATH.read_text())
    else:
        main()
