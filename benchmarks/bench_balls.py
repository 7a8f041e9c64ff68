"""Benchmark of the ball-bearing model (``--model balls``: ball-resolved main bearing,
rigid rings): CPU seconds per simulated second (solve + outputs), on Exudyn's integrator the
cost per call of the fused compiled element (the bearing rows and the other contacts), Newton
iterations per step, and the TE statistics (so speed never buys a different answer). The paired
comparison of the integrators: ``bench_integrator.py --model balls``.

    python benchmarks/bench_balls.py [--presets rv221 rv40e] [--t-end 0.1] [--newton '{"...": ...}']
                                     [--options '{"ball_inertia": true}'] [--integrator compiled|exudyn]

The preset's default ramps are kept; a short warm-up run (0.002 s) loads or
compiles the numba kernels first (a cold compile inside the timed run cost
~50 s, which bench_flexible_model.py counted as solve time). CPU time
(time.process_time) is robust on a shared machine; wall time is not printed.

Goal: <= 5 CPU s per simulated second, dt 1e-4 s, one BLAS thread. Measured figures with date
and machine: docs/benchmarks.md; their history: CHANGELOG.md.
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def _timed(obj, attr, acc, key):
    """Accumulate CPU time and calls of obj.attr in acc[key]."""
    fn = getattr(obj, attr)

    def timed(*args, **kw):
        c0 = time.process_time()
        r = fn(*args, **kw)
        acc[key][0] += time.process_time() - c0
        acc[key][1] += 1
        return r

    setattr(obj, attr, timed)


def bench(name: str, t_end: float, newton: dict | None, options: dict | None = None, integrator=None) -> dict:
    from flexrv.simulation import Simulation

    sim = Simulation(name, model="balls", model_options=options)
    model = sim.build()
    # numba load/compile, not timed (5-step segments: the segment starts take the outputs' history pass)
    sim.run(t_end=0.002, newton_options=newton, segment_steps=5, integrator=integrator)
    acc = {"fused": [0.0, 0], "fused_jac": [0.0, 0]}  # (Exudyn's integrator: its user functions)
    if model.fused is not None:
        _timed(model.fused, "residual", acc, "fused")
        _timed(model.fused, "jacobian", acc, "fused_jac")
    c0 = time.process_time()
    res = sim.run(t_end=t_end, newton_options=newton, integrator=integrator)
    cpu = time.process_time() - c0
    tm = sim.timing
    te = res["te"]
    sel = te.values[te["time"].values >= 0.5 * t_end]
    steps = max(tm["steps"], 1)
    return {
        "preset": name,
        "n": model.n,
        "simulated_s": tm["simulated_s"],
        "cpu_per_s": cpu / tm["simulated_s"],
        "solve_cpu_per_s": tm["solve_cpu_s"] / tm["simulated_s"],
        "outputs_cpu_s": cpu - tm["solve_cpu_s"],
        "newton_per_step": tm["newton_iterations"] / steps,
        "jacobians": tm["jacobians"],
        "steps": steps,
        **{f"{k}_us": v[0] / max(v[1], 1) * 1e6 for k, v in acc.items()},
        **{f"{k}_calls": v[1] for k, v in acc.items()},
        "te_mean": float(np.mean(sel)),
        "te_pp": float(np.ptp(sel)),
        "max_ball_load": float(np.max(res["ball_load_inner"].values[-1])) if "ball_load_inner" in res else np.nan,
        "status": res.attrs.get("status"),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--presets", nargs="*", default=["rv221", "rv40e"])
    ap.add_argument("--t-end", type=float, default=0.1)
    ap.add_argument("--newton", default=None, help="newton_options as JSON")
    ap.add_argument("--options", default=None, help="model options as JSON, e.g. '{\"ball_inertia\": true}'")
    ap.add_argument("--integrator", default=None, choices=("compiled", "exudyn"), help="default: the model's")
    a = ap.parse_args()
    import flexrv

    newton = json.loads(a.newton) if a.newton else None
    options = json.loads(a.options) if a.options else None
    print(f"flexrv from {os.path.dirname(flexrv.__file__)}; newton_options {newton}; model options {options}")
    for name in a.presets:
        r = bench(name, a.t_end, newton, options, a.integrator)
        print(
            f"{r['preset']} balls: n = {r['n']}, {r['steps']} steps for {r['simulated_s']:.3g} s, "
            f"Newton/step {r['newton_per_step']:.2f}, Jacobians {r['jacobians']}"
        )
        print(
            f"  CPU per simulated s: {r['cpu_per_s']:.2f} (solve {r['solve_cpu_per_s']:.2f}; outputs "
            f"{r['outputs_cpu_s']:.3f} s)"
        )
        print(
            f"  fused residual {r['fused_us']:.1f} us x {r['fused_calls']}, fused Jacobian "
            f"{r['fused_jac_us']:.1f} us x {r['fused_jac_calls']}"
        )
        print(
            f"  TE (t >= {0.5 * a.t_end:g} s): mean {r['te_mean']:.4f} arcsec, p-p {r['te_pp']:.4f} arcsec; "
            f"max inner ball load {r['max_ball_load']:.3f} N; {r['status']}",
            flush=True,
        )


if __name__ == "__main__":
    main()
