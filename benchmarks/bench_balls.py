"""Benchmark of the ball-bearing model (``--model balls``: ball-resolved main bearing,
rigid rings): CPU seconds per simulated second (solve + outputs), the cost per call
of the bearing rows and of the fused compiled element, Newton iterations per step,
and the TE statistics (so speed never buys a different answer).

    python benchmarks/bench_balls.py [--presets rv221 rv40e] [--t-end 0.1] [--newton '{"...": ...}']
                                     [--options '{"ball_inertia": true}']

The preset's default ramps are kept; a short warm-up run (0.002 s) loads or
compiles the numba kernels first (a cold compile inside the timed run cost
~50 s, which bench_flexible_model.py counted as solve time). CPU time
(time.process_time) is robust on a shared machine; wall time is not printed.

Goal (issue 15): <= 5 CPU s per simulated second, dt 1e-4 s, one BLAS thread.

Measured 2026-11-24 (branch rowspeed; paired runs alternating the code before,
4db34e6, and after on the same loaded 2-core machine, CPU of run() per simulated
s, solve in brackets, 0.1 s from rest):

=====  =================================  =================================  ==========================
preset before                             after                              Newton/step, Jacobians
=====  =================================  =================================  ==========================
rv221  7.63, 7.80 (solve 6.89, 7.04)       7.10, 7.17 (solve 6.38, 6.41)      5.13 / 26 -> 5.00 / 62
rv40e  11.15, 11.43 (solve 10.12, 10.38)   9.72, 9.93 (solve 7.96, 8.31)      3.45 / 474 -> 3.64 / 488
=====  =================================  =================================  ==========================

Per call (this script, after): row residual ~21 us (rv221) / ~28 us (rv40e), of
which the EHL film iteration is about half; row Jacobian 37-59 us (was 88-152:
block-sparse for rigid rings). The "after" outputs include a one-off numba cache
load of the fused history pass (~0.07 s) that the warm-up did not trigger. The
goal is not reached: the steps need 5.0 (rv221) / 3.6 (rv40e) Newton iterations
with a Jacobian that goes stale within a step (contact stiffness of lightly
loaded balls); ``--newton '{"modifiedNewtonContractivity": 0.25}'`` gives rv221
5.5-5.7 s/s (2.9 Newton/step, 272 Jacobians) and leaves rv40e unchanged.
Later the same day (paired against f6e224e, two runs each): the rows' outputs
recorded from the integrator's calls (flexrv.model.kernels.HistoryRecorder)
instead of a history pass: rv221 5.48, 5.49 -> 5.36, 5.34; rv40e 8.75, 8.65 ->
8.51, 8.69 (outputs 0.048 -> 0.017 s and 0.100 -> 0.058 s per 0.1 s; the solve
+3 %: the per-step copy of the records into fresh pages). Same TE statistics.
TE statistics in this start-up window move at the Newton-tolerance level
(default 1e-3); converged (tolerance 1e-5) the code before and after agree
(tests/reference_values.py, balls_rv40e note).
Then (paired against 3e05f72, two runs each) each contact's film iteration
started from its film of the previous call (flexrv.model.bearing_kernel._normal_load:
the same fixed point within 1e-14; row force 21.8 -> 19.7 us on rv221, 1 film
evaluation per contact instead of 3 when the state moved little) and one curve
evaluation less per pin: rv40e 8.51, 8.66 -> 7.81, 8.04; rv221 5.31, 5.42 ->
5.32, 5.42 (its Jacobians 253 -> 309: the modified Newton's update decisions
moved with the round-off). The start-up window's TE moved with them (rv221 mean
11.2913 -> 10.4327", p-p 21.8931 -> 23.7735"; rv40e -21.1915 -> -21.3084",
14.0568 -> 13.2864"); the same runs to 0.4 s agree over the steady window
(0.30-0.40 s): rv40e TE mean -166.36759" and p-p 0.39236" both, rv221 at
3000 N m -139.60677 / -139.60676" and 3.1625 / 3.1658" (rv221 at its preset's
light load lands on one of its two steady responses, tests/test_time_step.py),
and the converged regression case balls_rv40e is unchanged.
Then (branch qs2, paired against 9b988b1, two runs each, 2026-11-24) the balls became
quasi-static by default (``ball_inertia = false``: massless, solved inside the row
kernel, flexrv.model.bearing_kernel.quasi_static_balls; both rows in one 6-coordinate
element on the carrier): rv221 5.32, 5.32 -> **4.40, 4.43**, rv40e 7.94 (the other run
of the old code recompiled its kernels) -> **4.96, 4.97** CPU s per simulated s: the goal
is met. The system shrinks from
174 / 249 to 18 / 21 coordinates and the Newton iterations per step from ~3.1-3.3 to
1.8 / 2.1 with a fresh (small, dense) Jacobian per step, as the rigid model; per call
of both rows ~46 / ~61 us (each row's local Newton from the prediction b + S dx:
0.77 steps per solve on rv40e at the 1e-6 force tolerance) and ~49 / ~64 us for the
condensed Jacobian. The start-up window's TE moves (the balls' inertia shows in the
start-up: rv221 mean 10.4327 -> 11.7080", p-p 23.7735 -> 21.4495"; rv40e -21.3084 ->
-20.7907", 13.2864 -> 17.7748"); the steady window
of a 0.4 s run does not: rv40e -166.36759 / 0.39236" (inertia) against -166.36764 /
0.39239" (quasi-static), rv221 at 3000 N m -139.60677 / 3.1625" against -139.60685 /
3.1598". ``--options '{"ball_inertia": true}'`` measures the balls with inertia.
Then (paired against 8e32984, two runs each, 2026-11-24) the fused element's Jacobians
came with the step's first residual call (flexrv.model.kernels.FusedForces.residual):
rv221 4.44, 4.61 -> 4.39, 4.44; rv40e 5.08, 5.08 -> 4.93, 4.99. Those Jacobians differ
from a second call's at the same state by ~1e-11 (the inner solves restart from their
own converged state there), which moves the Newton path and the start-up window's TE
(rv221 11.7080 -> 11.1585", 21.4495 -> 23.8637"; rv40e -20.7907 -> -20.8299", 17.7748
-> 17.8421"; the same window moves by 0.2" (mean) and 2.8" (p-p) between Newton
tolerances 1e-3 and 1e-6 with either code); the steady window of a 0.4 s run: rv40e
-166.36764 / 0.39239" both, rv221 at 3000 N m -139.60685 / 3.1598" -> -139.60671 /
3.1443" (p-p is not converged in dt, tests/test_time_step.py).

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


def _timed_method(cls, attr, acc, key):
    """Accumulate CPU time and calls of the method cls.attr (every instance) in acc[key]."""
    fn = getattr(cls, attr)

    def timed(self, *args, **kw):
        c0 = time.process_time()
        r = fn(self, *args, **kw)
        acc[key][0] += time.process_time() - c0
        acc[key][1] += 1
        return r

    setattr(cls, attr, timed)


def bench(name: str, t_end: float, newton: dict | None, options: dict | None = None) -> dict:
    from flexrv.simulation import Simulation

    sim = Simulation(name, model="balls", model_options=options)
    model = sim.build()
    # numba load/compile, not timed (5-step segments: the segment starts take the outputs' history pass)
    sim.run(t_end=0.002, newton_options=newton, segment_steps=5)
    acc = {"row": [0.0, 0], "row_jac": [0.0, 0], "fused": [0.0, 0], "fused_jac": [0.0, 0]}
    from flexrv.model.flexible_bearing import RowElement  # the row elements' user functions (glue + kernel)

    saved = RowElement.force, RowElement.jacobian
    _timed_method(RowElement, "force", acc, "row")
    _timed_method(RowElement, "jacobian", acc, "row_jac")
    if model.fused is not None:
        _timed(model.fused, "residual", acc, "fused")
        _timed(model.fused, "jacobian", acc, "fused_jac")
    c0 = time.process_time()
    res = sim.run(t_end=t_end, newton_options=newton)
    cpu = time.process_time() - c0
    RowElement.force, RowElement.jacobian = saved
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
    a = ap.parse_args()
    import flexrv

    newton = json.loads(a.newton) if a.newton else None
    options = json.loads(a.options) if a.options else None
    print(f"flexrv from {os.path.dirname(flexrv.__file__)}; newton_options {newton}; model options {options}")
    for name in a.presets:
        r = bench(name, a.t_end, newton, options)
        print(
            f"{r['preset']} balls: n = {r['n']}, {r['steps']} steps for {r['simulated_s']:.3g} s, "
            f"Newton/step {r['newton_per_step']:.2f}, Jacobians {r['jacobians']}"
        )
        print(
            f"  CPU per simulated s: {r['cpu_per_s']:.2f} (solve {r['solve_cpu_per_s']:.2f}; outputs "
            f"{r['outputs_cpu_s']:.3f} s)"
        )
        print(
            f"  row force {r['row_us']:.1f} us x {r['row_calls']}, row Jacobian {r['row_jac_us']:.1f} us x "
            f"{r['row_jac_calls']}, fused residual {r['fused_us']:.1f} us x {r['fused_calls']}, fused Jacobian "
            f"{r['fused_jac_us']:.1f} us x {r['fused_jac_calls']}"
        )
        print(
            f"  TE (t >= {0.5 * a.t_end:g} s): mean {r['te_mean']:.4f} arcsec, p-p {r['te_pp']:.4f} arcsec; "
            f"max inner ball load {r['max_ball_load']:.3f} N; {r['status']}",
            flush=True,
        )


if __name__ == "__main__":
    main()
