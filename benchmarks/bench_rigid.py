"""Benchmark of the rigid reducer model on the compiled integrator: the force kernel's
cost per time step, split by element, and the share of a step outside it.

Run:  python benchmarks/bench_rigid.py [--t-end 0.1] [--presets rv40e rv221] [--sequences DIR]

``--sequences DIR``: the recorded call sequence of each preset is read from
``DIR/<preset>_<t-end>.npz`` if there, else recorded and written there, so that two checkouts
(an A/B pair) replay the same calls.

The run starts at rated speed (speed and load ramps shortened to 5 ms,
``_shared.quick_ramps``) so the timing measures steady operation under the preset's
load torque. Per preset:

* the compiled integrator's run (``Simulation.run(integrator="compiled")``): CPU s of the
  solve per simulated s, steps, Newton iterations, force-kernel calls per step, TE mean
  and peak-to-peak over t > 0.02 s [arcsec];
* the solver's call sequence: the same window on Exudyn's integrator (which takes the same
  steps and Newton iterations, tests/test_integrator.py) with every call of the fused
  kernel recorded (time, q, v, with or without the Jacobian), then replayed in ONE
  compiled loop from fresh element states (warm starts carried from call to call as in
  the run): CPU us per step of the whole kernel and of each element alone (the same
  sequence through that element's kernel), less the same loop without kernel calls;
* the pins: pin-kernel evaluations per call (the rim condensation's Newton; 1 with rigid
  discs and housing) and pins evaluated per evaluation (the others proved open);
* the share of a compiled step outside the kernel: 1 - (replayed kernel CPU per step x
  steps) / the compiled run's solve CPU (goal < 15 %).

One-time numba compilation/loading is done before timing (a 20-step run of each integrator).
"""

from __future__ import annotations

import argparse
import inspect
import os
import time

import numpy as np
from _shared import quick_ramps

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def _record_calls(sim, t_end: float) -> dict:
    """Run ``t_end`` on Exudyn's integrator and record every call of the fused kernel:
    {"t", "q", "v", "jac"} (calls,) / (calls, n) on the element's coordinates."""
    fused = sim.build().fused
    seq = {"t": [], "q": [], "v": [], "jac": []}
    orig = fused._call

    def rec(t, q, v, jac):
        seq["t"].append(float(t))
        seq["q"].append(np.array(q, dtype=float))
        seq["v"].append(np.array(v, dtype=float))
        seq["jac"].append(bool(jac))
        return orig(t, q, v, jac)

    fused._call = rec
    try:
        # (a checkout older than the compiled integrator has only Exudyn's: bench_integrator_baseline.py)
        only = "integrator" not in inspect.signature(sim.run).parameters
        res = sim.run(t_end=t_end, checkpoint_s=None, **({} if only else {"integrator": "exudyn"}))
    finally:
        del fused._call
    out = {k: np.array(v) for k, v in seq.items()}
    if not fused.is_full:
        out["q"], out["v"] = out["q"][:, fused.index], out["v"][:, fused.index]
    out["steps"] = sim.timing["steps"]
    out["te"] = res["te"].values
    return out


def _replay_functions():
    """Compiled replays of calls [i0, i1) of a sequence through the fused kernel or one
    element's kernel (``call`` False: the same loop without the kernel)."""
    from numba import njit

    def make(kern):
        @njit
        def replay(i0, i1, qs, vs, jacs, tables, live, f, jq, jv, call, packs):
            for i in range(i0, i1):
                for j in range(len(tables)):
                    live[j][:] = tables[j][i]
                if call:
                    kern(qs[i], vs[i], f, jq, jv, jacs[i], *packs)

        return replay

    return make


def _arrays(pack) -> list:
    """The arrays of a pack (nested packs included): the elements' states to snapshot."""
    out = []
    for value in pack:
        if isinstance(value, np.ndarray):
            out.append(value)
        elif isinstance(value, tuple) and hasattr(value, "_fields"):
            out += _arrays(value)
    return out


def _chunked_cpu(replay, args, call, packs, n, chunk, repeats) -> float:
    """CPU s of the whole sequence, the sum over chunks of ``chunk`` calls of the least of
    ``repeats`` runs of each chunk, every run from the state before the chunk (the packs'
    arrays restored): robust to the other jobs of a shared machine."""
    arrays = [a for p in packs for a in _arrays(p)]
    total = 0.0
    for i0 in range(0, n, chunk):
        i1 = min(n, i0 + chunk)
        saved = [a.copy() for a in arrays]
        best = np.inf
        for _ in range(repeats):
            for a, b in zip(arrays, saved):
                np.copyto(a, b)
            c0 = time.process_time()
            replay(i0, i1, *args, call, packs)
            best = min(best, time.process_time() - c0)
        total += best
    return total


def _replay_costs(model, seq, chunk: int = 100, repeats: int = 5) -> dict:
    """CPU us per call sequence of the fused kernel and of every element alone (module
    docstring), and the pins' evaluation count."""
    from flexrv.model.core.registry import spec_of

    fused = model.fused
    make = _replay_functions()
    n = len(seq["t"])
    live = tuple(a for _, a in fused.timed)
    tables = tuple(
        np.ascontiguousarray(np.broadcast_to(g.time_inputs_many(seq["t"]), (n, a.size)), dtype=float)
        for g, a in fused.timed
    )
    if not live:  # (numba needs a typed tuple)
        live, tables = (np.zeros(0),), (np.zeros((n, 0)),)
    kernels = [("fused", fused.kernel, tuple(fused.packs))]
    for (g, _), p in zip(fused.slots, fused.packs):
        kernels.append((g.name, spec_of(g).kernel, (p,)))
    args = (seq["q"], seq["v"], seq["jac"], tables, live, fused.f, fused.jq, fused.jv)
    pins = next((g for g in model.groups if g.kind == "pins"), None)
    counter = None if pins is None else getattr(pins, "calls", getattr(pins, "ctr", None))
    out = {}
    for name, kern, packs in kernels:
        replay = make(kern)
        for g in model.groups:
            g.reset()
        replay(0, n, *args, True, packs)  # (compile)
        for g in model.groups:
            g.reset()
        c_before = int(counter[0]) if counter is not None else 0
        spent = _chunked_cpu(replay, args, True, packs, n, chunk, repeats)
        if name == "fused" and counter is not None:  # (each chunk's last run carries on)
            out["pin_evaluations"] = int(counter[0]) - c_before
        empty = _chunked_cpu(replay, args, False, packs, n, chunk, repeats)
        out[name] = (spent - empty) * 1e6
    return out


def _sequence(sim, name: str, t_end: float, folder: str | None) -> dict:
    """The recorded call sequence (:func:`_record_calls`), from ``folder`` if saved there."""
    path = None if folder is None else os.path.join(folder, f"{name}_{t_end:g}.npz")
    if path is not None and os.path.exists(path):
        with np.load(path) as z:
            return {k: z[k] for k in z.files}
    seq = _record_calls(sim, t_end)
    if path is not None:
        os.makedirs(folder, exist_ok=True)
        np.savez(path, **seq)
    return seq


def bench(name: str, t_end: float, sequences: str | None = None) -> dict:
    from flexrv.simulation import Simulation

    sim = Simulation(quick_ramps(name))
    model = sim.build()
    for integ in ("compiled", "exudyn"):  # compile / load
        sim.run(t_end=0.002, integrator=integ, checkpoint_s=None)
    calls0 = model.fused.stats[0]
    res = sim.run(t_end=t_end, integrator="compiled", checkpoint_s=None)
    tm = dict(sim.timing)
    calls = model.fused.stats[0] - calls0
    te = res["te"].values[res.time > 0.02]
    seq = _sequence(sim, name, t_end, sequences)
    costs = _replay_costs(model, seq)
    steps = tm["steps"]
    n_calls = len(seq["t"])
    return {
        "preset": name,
        "steps": steps,
        "solve_cpu_s": tm["solve_cpu_s"],
        "cpu_per_sim_s": tm["solve_cpu_s"] / tm["simulated_s"],
        "newton_per_step": tm["newton_iterations"] / steps,
        "calls_per_step": calls / steps,
        "replayed_calls_per_step": n_calls / seq["steps"],
        "replayed_steps": seq["steps"],
        "kernel_us_per_step": costs["fused"] / seq["steps"],
        "elements_us_per_step": {
            k: v / seq["steps"] for k, v in costs.items() if k not in ("fused", "pin_evaluations")
        },
        "pin_evaluations_per_call": costs.get("pin_evaluations", 0) / n_calls,
        "te_mean_arcsec": float(np.mean(te)),
        "te_pp_arcsec": float(np.ptp(te)),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=0.1)
    ap.add_argument("--presets", nargs="*", default=["rv40e", "rv221"])
    ap.add_argument("--sequences", default=None, help="folder of recorded call sequences (read, else written)")
    a = ap.parse_args()
    import flexrv

    print(f"flexrv from {os.path.dirname(flexrv.__file__)}")
    for name in a.presets:
        r = bench(name, a.t_end, a.sequences)
        outside = 1.0 - r["kernel_us_per_step"] * 1e-6 * r["steps"] / r["solve_cpu_s"]
        print(
            f"{name}: compiled integrator, {r['steps']} steps, CPU {r['cpu_per_sim_s']:.3f} s per simulated s, "
            f"Newton {r['newton_per_step']:.2f}/step, kernel calls {r['calls_per_step']:.2f}/step "
            f"(replayed sequence {r['replayed_calls_per_step']:.2f}/step over {r['replayed_steps']} steps)"
        )
        print(
            f"  kernel {r['kernel_us_per_step']:.1f} us/step; outside the kernel {100 * outside:.0f} % of a step; "
            f"elements alone (us/step): " + ", ".join(f"{k} {v:.1f}" for k, v in r["elements_us_per_step"].items())
        )
        print(f"  pins: {r['pin_evaluations_per_call']:.2f} pin-kernel evaluations per call")
        print(f"  TE (t > 0.02 s): mean {r['te_mean_arcsec']:.5f} arcsec, p-p {r['te_pp_arcsec']:.5f} arcsec")


if __name__ == "__main__":
    main()
