"""Benchmark of the compiled generalized-alpha integrator against Exudyn's, paired in one
process: rigid model of each preset, the same run on both integrators.

Run:  python benchmarks/bench_integrator.py [--t-end 0.3] [--presets rv40e rv221] [--repeat 2]

The run starts at rated speed (speed and load ramps shortened to 5 ms, as
benchmarks/bench_rigid.py) and lasts ``--t-end``. Printed per preset and integrator:

* CPU s of the solve per simulated s (``time.process_time`` around the segment loop,
  ``Simulation.timing["solve_cpu_s"]``; the best of ``--repeat`` runs) and the ratio
  Exudyn / compiled;
* Newton iterations, Jacobians and force-kernel calls per step;
* TE mean and peak-to-peak over t > 0.05 s [arcsec] of both (the same answer);
* the share of a compiled step outside the force kernel: 1 - (kernel calls x the
  kernel's cost per call) / solve time, the cost per call measured on the run's
  recorded states with the solver's own kernel arguments (warm starts carried from
  state to state as in the run): per state the step's number of calls, the first with
  the Jacobian, in a compiled loop, less the same loop without calls. The calls of a
  step at one state converge their inner solves at once, so this cost is a lower
  bound and the share outside the kernel an upper bound.

One-time numba compilation/loading is done before timing (a 20-step run of each).
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
from _shared import quick_ramps

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def _run(sim, integrator: str, t_end: float):
    res = sim.run(t_end=t_end, integrator=integrator, checkpoint_s=None)
    t = res.time
    te = res["te"].values[t > 0.05]
    return res, dict(sim.timing), float(te.mean()), float(np.ptp(te))


def _kernel_cost(model, ts, qs, vs, calls_per_step: float) -> float:
    """CPU s per call of the solver's fused kernel at the run's recorded states: per state
    the step's calls (the first with the Jacobian) in one compiled loop, less the same loop
    without calls (the arguments' unboxing and the Python per state); module docstring."""
    from numba import njit

    kern = model.fused.kernel

    @njit
    def replay(q, v, f, jq, jv, reps, *packs):
        for r in range(reps):
            kern(q, v, f, jq, jv, r == 0, *packs)

    fused = model.fused
    reps = max(int(round(calls_per_step)), 1)
    for g in model.groups:
        g.reset()
    spent = []
    for n in (reps, 0, reps, 0):
        replay(qs[1], vs[1], fused.f, fused.jq, fused.jv, n, *fused.packs)  # (compile)
        c0 = time.process_time()
        for i in range(1, len(ts)):
            for g, array in fused.timed:
                g.set_time(float(ts[i]), array)
            replay(qs[i], vs[i], fused.f, fused.jq, fused.jv, n, *fused.packs)
        spent.append(time.process_time() - c0)
    return (min(spent[0], spent[2]) - min(spent[1], spent[3])) / ((len(ts) - 1) * reps)


def bench(name: str, t_end: float, repeat: int) -> dict:
    import flexrv.simulation as S
    from flexrv.simulation import Simulation

    sim = Simulation(quick_ramps(name))
    model = sim.build()
    for integ in ("exudyn", "compiled"):  # compile / load the kernels
        sim.run(t_end=0.002, integrator=integ, checkpoint_s=None)
    states = {}
    orig = S._Records.__init__

    def keep(self, *a, **k):  # the run's recorded states, for the kernel's cost per call
        orig(self, *a, **k)
        states["records"] = self

    S._Records.__init__ = keep
    out = {}
    try:
        for _ in range(repeat):
            for integ in ("exudyn", "compiled"):
                res, timing, mean, pp = _run(sim, integ, t_end)
                best = out.get(integ)
                if best is None or timing["solve_cpu_s"] < best["cpu"]:
                    rec = states["records"]
                    out[integ] = {
                        "cpu": timing["solve_cpu_s"],
                        "steps": timing["steps"],
                        "newton": timing["newton_iterations"],
                        "jacobians": timing["jacobians"],
                        "calls": model.fused.stats[0],
                        "mean": mean,
                        "pp": pp,
                        "states": (rec.ts[: rec.k].copy(), rec.qs[: rec.k].copy(), rec.vs[: rec.k].copy()),
                    }
    finally:
        S._Records.__init__ = orig
    c = out["compiled"]
    per_call = _kernel_cost(model, *c["states"], c["calls"] / c["steps"])
    c["kernel_share"] = c["calls"] * per_call / c["cpu"]
    c["per_call_us"] = per_call * 1e6
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=0.3)
    ap.add_argument("--presets", nargs="+", default=["rv40e", "rv221"])
    ap.add_argument("--repeat", type=int, default=2)
    args = ap.parse_args()
    for name in args.presets:
        out = bench(name, args.t_end, args.repeat)
        e, c = out["exudyn"], out["compiled"]
        print(f"\n{name}: rigid model, t_end {args.t_end:g} s, {c['steps']} steps")
        for key, r in (("exudyn", e), ("compiled", c)):
            print(
                f"  {key:9s} CPU {r['cpu'] / args.t_end:7.3f} s per simulated s   "
                f"Newton {r['newton'] / r['steps']:.2f}  Jacobians {r['jacobians'] / r['steps']:.2f}  "
                f"kernel calls {r['calls'] / r['steps']:.2f} per step   "
                f"TE mean {r['mean']:+.5f}  p-p {r['pp']:.4f} arcsec"
            )
        print(f"  ratio Exudyn / compiled CPU: {e['cpu'] / c['cpu']:.2f}x")
        print(
            f"  compiled: kernel {c['per_call_us']:.1f} us per call, {100 * c['kernel_share']:.0f} % of the solve; "
            f"outside the kernel {100 * (1 - c['kernel_share']):.0f} % "
            f"({(1 - c['kernel_share']) * c['cpu'] / c['steps'] * 1e6:.1f} us per step)"
        )


if __name__ == "__main__":
    main()
