"""Benchmark of the rigid reducer model: force residual and Jacobian cost per call,
real-time factor and the TE statistics (so speed never buys a different answer).

Run:  python benchmarks/bench_rigid.py [--t-end 0.05] [--dt 1e-4] [--presets rv40e rv221]

The run starts at rated speed (speed and load ramps shortened to 5 ms) so the
timing measures steady operation under the preset's load torque. Printed per preset:

* ``residual`` / ``jacobian``: wall µs per call of the Python force user
  function(s) and Jacobian user function(s) during the run (all groups of one
  residual together);
* ``compiled kernel``: wall µs per time step inside the compiled entry point of the
  fused kernel (the physics), and everything else of the solve per step (Exudyn's
  own work, the Python glue of every call, the pre-step hook): the real-time factor
  the model would have at zero physics cost;
* ``generalized_forces``: µs per call of ``AssembledModel.generalized_forces`` with
  the Jacobian at a loaded state (the quasi-static solver's path);
* real-time factor = solve wall s per simulated s, and post-processing wall s
  (outputs of every group recomputed from the recorded states; one-time imports
  excluded);
* CPU seconds (time.process_time, robust on a shared machine) of the solve and of
  the outputs, and the real-time factor of both together (goal: <= 1);
* TE mean and peak-to-peak over t > 0.02 s [arcsec].

It runs unchanged on a model of Python force elements and on the fused compiled
element, so both sides of a comparison come from the same script. One-time numba
compilation/loading (the kernels and the outputs' paths: a 20-step run in 5-step
segments) is done before timing.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
from _shared import quick_ramps

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def _instrument(model):
    """Accumulate wall time and calls of the Python force/Jacobian user functions:
    the fused element (``model.fused``) if present, else every group's
    evaluate/jacobian (one residual = one call of every group)."""
    acc = {"res": [0.0, 0], "jac": [0.0, 0], "kernel": [0.0, 0]}

    def wrap(obj, attr, key, count=True, single_state_only=False):
        fn = getattr(obj, attr)

        def timed(*args, **kw):
            if single_state_only and np.ndim(args[1]) != 1:  # post-processing, not solver time
                return fn(*args, **kw)
            t0 = time.perf_counter()
            r = fn(*args, **kw)
            acc[key][0] += time.perf_counter() - t0
            acc[key][1] += count
            return r

        setattr(obj, attr, timed)

    fused = getattr(model, "fused", None)
    if fused is not None:
        wrap(fused, "residual", "res")
        wrap(fused, "jacobian", "jac")
        if getattr(fused, "_entry", None) is not None:  # the compiled kernel alone (found by the warm-up run)
            wrap(fused, "_entry", "kernel")
    else:
        python_groups = [g for g in model.groups if type(g).__name__ != "RigidMainBearing"]
        for i, g in enumerate(python_groups):
            wrap(g, "evaluate", "res", count=(i == 0), single_state_only=True)
            if g.analytic_jacobian:
                wrap(g, "jacobian", "jac", count=(i == 0))
    return acc


def _loaded_state(model):
    """A state with the discs turned into the pins and the drive flanks loaded."""
    q = model.q0.copy()
    for k in range(model.params.n_discs):
        q[model.slice(f"disc{k}").start + 2] += 1.5e-4
    for j in range(model.params.n_cranks):
        q[model.slice(f"crank{j}").start + 2] += 5e-5
    return q


def _gf_time(model, reps: int = 300) -> float:
    """µs per call of generalized_forces(t, q, v) with the Jacobian."""
    q, v = _loaded_state(model), np.zeros(model.n)
    model.generalized_forces(0.0, q, v)
    t0 = time.perf_counter()
    for i in range(reps):
        model.generalized_forces(0.0, q + 1e-9 * (i % 7), v)
    return (time.perf_counter() - t0) / reps * 1e6


def bench(name: str, t_end: float, dt: float) -> dict:
    from flexrv.simulation import Simulation

    sim = Simulation(quick_ramps(name))
    model = sim.build()
    t0 = time.perf_counter()
    gf_us = _gf_time(model, reps=3)  # loads/compiles the kernels
    import xarray as xr

    xr.Variable(("t",), np.zeros(3))  # one-time imports of the results path (~0.4 s), not post-processing cost
    # loads/compiles the outputs' paths too: the integrator's records and (at the segment starts,
    # where the integrator's last call is not at the recorded state) the compiled history pass
    sim.run(t_end=20 * dt, dt=dt, segment_steps=5)
    t_warm = time.perf_counter() - t0
    gf_us = _gf_time(model)
    acc = _instrument(model)
    t0, c0 = time.perf_counter(), time.process_time()
    res = sim.run(t_end=t_end, dt=dt)
    total, total_cpu = time.perf_counter() - t0, time.process_time() - c0
    tm = sim.timing
    solve = tm["solve_s"]
    solve_cpu = tm.get("solve_cpu_s", float("nan"))  # absent before the segmented runs
    te = res["te"]
    sel = te.values[te["time"].values > 0.02]
    return {
        "preset": name,
        "dt_s": dt,
        "simulated_s": tm["simulated_s"],
        "solve_wall_s": solve,
        "post_wall_s": total - solve,
        "real_time_factor": solve / tm["simulated_s"],
        "steps": tm["steps"],
        "newton_iterations_per_step": tm["newton_iterations"] / max(tm["steps"], 1),
        "jacobian_updates": tm["jacobians"],
        "warm_up_s": t_warm,
        "residual_us": acc["res"][0] / max(acc["res"][1], 1) * 1e6,
        "residual_calls": acc["res"][1],
        "jacobian_us": acc["jac"][0] / max(acc["jac"][1], 1) * 1e6,
        "jacobian_calls": acc["jac"][1],
        "user_function_share": (acc["res"][0] + acc["jac"][0]) / solve,
        "generalized_forces_us": gf_us,
        "kernel_us_per_step": acc["kernel"][0] / max(tm["steps"], 1) * 1e6,
        "kernel_calls_per_step": acc["kernel"][1] / max(tm["steps"], 1),
        "rest_us_per_step": (
            (solve - acc["kernel"][0]) / max(tm["steps"], 1) * 1e6 if acc["kernel"][1] else float("nan")
        ),
        "te_mean_arcsec": float(np.mean(sel)),
        "te_pp_arcsec": float(np.ptp(sel)),
        "solve_cpu_s": solve_cpu,
        "post_cpu_s": total_cpu - solve_cpu,
        "run_cpu_s": total_cpu,
        "rtf_cpu": total_cpu / tm["simulated_s"],
        "status": res.attrs.get("status", "?") if hasattr(res, "attrs") else "?",
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=0.05)
    ap.add_argument("--dt", type=float, default=1e-4)
    ap.add_argument("--presets", nargs="*", default=["rv40e", "rv221"])
    a = ap.parse_args()
    import flexrv

    print(f"flexrv from {os.path.dirname(flexrv.__file__)}")
    for name in a.presets:
        r = bench(name, a.t_end, a.dt)
        print(f"{r['preset']}: dt = {r['dt_s']:g} s, {r['steps']} steps for {r['simulated_s']:.3g} s simulated")
        print(
            f"  residual {r['residual_us']:.1f} us/call ({r['residual_calls']} calls), "
            f"jacobian {r['jacobian_us']:.1f} us/call ({r['jacobian_calls']} calls), "
            f"user functions {100 * r['user_function_share']:.0f} % of solve"
        )
        if r["kernel_calls_per_step"]:
            print(
                f"  compiled kernel {r['kernel_us_per_step']:.0f} us/step ({r['kernel_calls_per_step']:.2f} calls); "
                f"everything else (Exudyn, Python glue, pre-step hook) {r['rest_us_per_step']:.0f} us/step = "
                f"real-time factor {r['rest_us_per_step'] * 1e-6 / r['dt_s']:.2f} at zero physics cost"
            )
        print(f"  generalized_forces with Jacobian {r['generalized_forces_us']:.1f} us/call")
        print(
            f"  solve wall {r['solve_wall_s']:.2f} s -> real-time factor {r['real_time_factor']:.2f}; "
            f"post-processing {r['post_wall_s']:.2f} s; Newton iterations/step "
            f"{r['newton_iterations_per_step']:.2f}, Jacobian updates {r['jacobian_updates']}"
        )
        print(
            f"  CPU: solve {r['solve_cpu_s']:.3f} s, outputs {r['post_cpu_s']:.3f} s -> real-time factor "
            f"(solve + outputs, CPU) {r['rtf_cpu']:.2f}"
        )
        print(f"  TE (t > 0.02 s): mean {r['te_mean_arcsec']:.4f} arcsec, p-p {r['te_pp_arcsec']:.4f} arcsec")
        print(f"  warm-up (numba load/compile) {r['warm_up_s']:.2f} s")


if __name__ == "__main__":
    main()
