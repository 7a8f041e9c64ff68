"""Benchmark of the rigid reducer model: wall time per simulated second (real-time
factor), steps/s, Newton iterations and the share of time spent in the Python
force-element groups, for each preset at the default step.

Run:  python benchmarks/bench_rigid.py [--t-end 0.05] [--dt 1e-4] [--profile]

The run starts at rated speed (ramps shortened to 5 ms) so the timing measures
steady operation under the preset's load torque. Every group is evaluated once
before the timed run, so the one-time load of the numba-compiled kernels
(printed as warm-up) is not counted in the solve time.
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def _fast(name: str):
    from flexrv.design import load

    r = load(name)
    op = r.operating.model_copy(update={"speed_ramp_time_s": 0.005, "load_ramp_start_s": 0.0, "load_ramp_end_s": 0.005})
    return r.model_copy(update={"operating": op})


def _instrument(model):
    """Wrap each group's evaluate/jacobian to accumulate wall time."""
    acc = {}
    for g in model.groups:
        acc[g.name] = [0.0, 0.0]
        ev, jac = g.evaluate, getattr(g, "jacobian", None)

        def timed_ev(t, q, v, want_outputs=False, _ev=ev, _a=acc[g.name]):
            if np.ndim(q) != 1:  # post-processing of the time history: not solver time
                return _ev(t, q, v, want_outputs)
            t0 = time.perf_counter()
            r = _ev(t, q, v, want_outputs)
            _a[0] += time.perf_counter() - t0
            return r

        def timed_jac(t, q, v, _jac=jac, _a=acc[g.name]):
            t0 = time.perf_counter()
            r = _jac(t, q, v)
            _a[1] += time.perf_counter() - t0
            return r

        g.evaluate = timed_ev
        if jac is not None:
            g.jacobian = timed_jac
    return acc


def _warm_up(model) -> float:
    """Evaluate every group once at the initial state (loads the numba-compiled
    kernels, a one-time cost per process of ~1 s, ~40 s on the very first run
    while numba compiles and caches them); return its wall time [s]."""
    t0 = time.perf_counter()
    q0, v0 = model.q0, np.zeros(model.n)
    for g in model.groups:
        g.evaluate(0.0, model.group_state(g, q0), model.group_state(g, v0))
        if g.analytic_jacobian:
            g.jacobian(0.0, model.group_state(g, q0), model.group_state(g, v0))
        g.reset()
    return time.perf_counter() - t0


def bench(name: str, t_end: float, dt: float, profile: bool = False) -> dict:
    from flexrv.simulation import Simulation

    sim = Simulation(_fast(name))
    model = sim.build()
    t_warm = _warm_up(model)
    acc = _instrument(model)
    t0 = time.perf_counter()
    if profile:
        import cProfile
        import pstats

        pr = cProfile.Profile()
        pr.enable()
    sim.run(t_end=t_end, dt=dt)
    if profile:
        pr.disable()
        pstats.Stats(pr).sort_stats("tottime").print_stats(15)
    total = time.perf_counter() - t0
    tm = sim.timing
    solve = tm["solve_s"]
    py = sum(a[0] + a[1] for a in acc.values())
    return {"preset": name, "dt_s": dt, "simulated_s": tm["simulated_s"], "solve_wall_s": solve,
            "post_wall_s": total - solve, "real_time_factor": solve / tm["simulated_s"],
            "steps": tm["steps"], "steps_per_s": tm["steps"] / solve,
            "newton_iterations_per_step": tm["newton_iterations"] / max(tm["steps"], 1),
            "jacobian_updates": tm["jacobians"], "warm_up_s": t_warm,
            "user_function_share": py / solve,
            "group_time_s": {k: round(a[0] + a[1], 3) for k, a in acc.items()}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=0.05)
    ap.add_argument("--dt", type=float, default=1e-4)
    ap.add_argument("--profile", action="store_true")
    ap.add_argument("--presets", nargs="*", default=["rv40e", "rv221"])
    a = ap.parse_args()
    for name in a.presets:
        r = bench(name, a.t_end, a.dt, a.profile)
        print(f"{r['preset']}: dt = {r['dt_s']:g} s, {r['steps']} steps for {r['simulated_s']:.3g} s simulated")
        print(f"  solve wall {r['solve_wall_s']:.2f} s  -> real-time factor {r['real_time_factor']:.1f} "
              f"(wall s per simulated s), {r['steps_per_s']:.0f} steps/s")
        print(f"  Newton iterations/step {r['newton_iterations_per_step']:.2f}, Jacobian updates {r['jacobian_updates']}")
        print(f"  Python force-element share of solve time {100 * r['user_function_share']:.0f} %: {r['group_time_s']}")
        print(f"  post-processing {r['post_wall_s']:.2f} s; warm-up before timing (numba load) {r['warm_up_s']:.2f} s")


if __name__ == "__main__":
    main()
