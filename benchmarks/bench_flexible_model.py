"""Benchmark: the reducer model with the ball-resolved / flexible main bearing.

Runs the rigid, the ball-bearing (rigid rings) and the flexible-ring model of a
preset over the same short interval and prints, per model: wall and CPU
(``time.process_time``) seconds of the solve per simulated second, steps, Newton
iterations and Jacobians per step, the model build time (meshing + CMS of the
rings; ``--cold`` builds them in an empty cache) and the TE statistics of the run
(mean and peak-to-peak over the last half of the interval, max inner ball load),
so a speed change can be checked for an unchanged answer.

    python benchmarks/bench_flexible_model.py [--preset rv221] [--t-end 0.1] [--cold]
        [--models rigid,balls,flexible] [--harmonics K] [--parts main_bearing,crankshaft]
        [--ring-options '{"condense": false}']

Goal (issue 15): flexible rings model (condensed rings, main bearing flexible)
<= 15 s per simulated second on rv221 and on rv40e (dt 1e-4, one BLAS thread).
Machine note: 2 shared cores: quote the CPU column (wall is noisy).

Measured 2026-11-24 (``--t-end 0.3 --window 0.1 --models flexible``, CPU of
run() per simulated s; before = commit b1eee8d, uncondensed massless ring modes):

=====  ===================  =================  ======================  ======================
preset CPU before -> after  coordinates        TE mean before / after  TE p-p before / after
=====  ===================  =================  ======================  ======================
rv221  64.8 -> 27.1 s/s     650 -> 174         -20.4392 / -20.4446"    2.9228 / 3.0010"
rv40e  363.3 -> 55.3 s/s    989 -> 249         -131.4744 / -131.4744"  0.3147 / 0.3154"
=====  ===================  =================  ======================  ======================

Row-kernel speed (issue 15, commits after fa2019e), paired runs of this script on
the same machine, base = fa2019e (tapered-roller crank supports), CPU of run()
per simulated s, two runs each:

=====  ======================  ===================================  ============================
preset CPU before -> after     TE mean before / after               TE p-p before / after
=====  ======================  ===================================  ============================
rv221  25.2, 25.3 -> 16.6, 16.3  -20.2155 / -20.2978"               3.7491 / 3.2266"
rv40e  54.0, 51.7 -> 34.0, 34.5  -134.3837 / -134.3837"             0.3110 / 0.3110"
=====  ======================  ===================================  ============================

(rv40e: max inner ball load 19.80 N and ring deflection 0.0198 um both, 3.66/3.67
Newton iterations per step, 1029/1015 Jacobians.) Final code (one-pass modal
amplitudes added), ``--models balls,flexible``, paired again: flexible rv221
27.8, 25.1 -> 16.4, 14.7; rv40e 55.1, 55.3 -> 31.7, 33.2 s/s (same TE as above);
the ball model (rigid rings, whose contacts share the normal law's speed terms)
rv221 12.5, 11.8 -> 8.8, 8.8 and rv40e 16.5, 16.5 -> 13.6, 13.6 s/s (rv40e TE mean
-134.3837 / -134.3836", p-p 0.3106" both, max ball load 20.49 N both). Every row call agrees with the
previous kernel within 2e-13 relative (ball loads, forces; Jacobian 5e-15), but
the integrator's Newton tolerance (1e-3 relative) carries such differences into
the trajectory: rv221 at its preset 20 N m has two steady responses chosen by
tolerance-level differences of the start-up (tests/test_time_step.py), so its
TE p-p moves between runs of equivalent code (3.04-3.75"). Loaded, where the
response is unique (rv221 at 3000 N m, same script's settings): TE mean
-82.644858 / -82.644868", p-p 2.7197 / 2.7202", max inner ball load 105.1828 /
105.1905 N. Where the time goes (cProfile, rv40e, 0.1 s): row residuals
~25 % (~115 us per row call, was ~255), row Jacobians ~25 % (~0.95 ms per row,
was ~1.4; 1 per 3 steps), Exudyn's own work (sparse LU, assembly) ~20 %, the
fused kernel of the other groups ~6 %, the outputs pass ~9 %; rv221: row residuals
~42 % (~55 us per row call, was ~110). Fewer Jacobians do not pay: Exudyn's
modifiedNewtonContractivity 0.8 (0.95 with 12 modified iterations) cut them to
725 (432) but raised the iterations to 5.6 (6.6) per step: 39.8 (36.4) against
34.2 s/s. The goal (15 s/s) is not reached.

Row glue and kernel (branch rowspeed, 2026-11-24): paired runs alternating the
code before (4db34e6) and after, CPU of run() per simulated s (solve in
brackets), 0.1 s from rest, ``--models flexible``:

=====  ===================================  ===================================  =====================
preset before                               after                                Newton/step, Jacobians
=====  ===================================  ===================================  =====================
rv221  15.46, 15.49 (solve 13.25, 13.44)     14.31, 14.05 (solve 12.36, 12.12)     5.19 / 49 -> 5.25 / 51
rv40e  36.98, 37.49 (solve 32.87, 33.53)     30.22, 30.92 (solve 26.53, 26.96)     3.62 / 602 -> 3.50 / 472
=====  ===================================  ===================================  =====================

(this script, one pair on a more loaded machine: rv221 20.4 -> 18.5, rv40e 47.3 -> 37.3 s/s.)
What changed: the element glue is one compiled call into preallocated arrays;
the inner ring's groove geometry is computed per ball without small BLAS calls
and allocations; the condensed rings' local factors and solve scratch live in
their work arrays (the 165 kB factor array was allocated, page-faulted and zeroed
on every call); the film Newton stops once its step is below 1e-8; the films'
speed term is in d f/d q_t; Exudyn no longer differentiates the member objects
numerically (factory). rv221 meets the goal; rv40e does not: each row residual
is ~100 us (two condensed rings of 38 balls and 165/181 modes: the factor
interpolation and the local solve), each row Jacobian ~1-2 ms (the dense
(I - K C)^-1 K of 114 x 114 per ring), and 3.5 Newton iterations per step with a
Jacobian every second step.

Condensed tangent through a 2Z x 2Z inverse (2026-11-24, evening): the contact
blocks factored as K_j = -V_j V_j^T (rank 2: the normal and the geometric term,
``bearing_kernel._contact_factors``), so (I - K C)^-1 K = -V S^-1 V^T with
S = I + P P^T, P = V^T W: no 114 x 114 Gram matrix or inverse. Per ring and
Jacobian 360 -> 190 us (rv40e), row Jacobian 800 -> 560 us; the Jacobian equals
the old one within 5.5e-11 (jq) / 1.4e-10 (jv) of its largest entry at a running
state. This script, same session: rv40e 30.7 -> 28.5, rv221 13.2 -> 12.9 s/s.
Its TE over the start-up window moved (rv40e mean -21.16 -> -21.18", p-p 14.28 ->
15.02"; rv221 mean 9.57 -> 9.90", p-p 22.44 -> 22.02"): Newton-tolerance scatter,
since a Jacobian change of 5e-11 changes which iterations the modified Newton
takes; at the regression table's converged tolerance (flexible_rv221) the two
give the same answer to 9e-6" (mean) and 1.1e-6" (p-p).

Then the rows' outputs recorded from the integrator's calls (no history pass of
the rows; paired against f6e224e, two runs each): rv221 13.0, 12.9 -> 12.5, 12.7;
rv40e 30.3, 27.3 -> 25.8, 25.3 s/s; TE statistics unchanged to the printed digits.

Then the films' warm starts (the film iteration from each contact's film of the
previous call, also inside the condensed rings' local solve) and one curve
evaluation less per pin (paired against 3e05f72 on a busier machine, two runs
each): rv221 11.7, 11.8 -> 11.4, 11.2; rv40e 26.3, 27.8 -> 26.5, 26.0 s/s (the
condensed rings' linear algebra, not the films, dominates their rows). Start-up
window TE moved with the round-off (rv221 9.8983 -> 10.0439", p-p 22.0241 ->
20.8366"; rv40e -21.1817 -> -21.2698", 15.0181 -> 13.2064"); to 0.4 s the steady
window (0.30-0.40 s) of rv40e is the same, TE mean -166.36764" and p-p 0.39327"
both, and the converged regression case flexible_rv221 is unchanged.

Then (branch qs2, issue 15) the row kernel's azimuth cosines and sines from the
coordinates (no cos/sin of the atan2) and each ball's Jacobian blocks assembled once
(scattered here, condensed for the ball model's quasi-static balls; the flexible model
keeps balls with inertia, as a condensed ring couples every ball of its row): paired
against 9b988b1, rv221 11.1, 11.2 -> 10.9, 11.1 s/s (unchanged); start-up window TE
moved with the round-off (rv221 10.0439 -> 10.3052", p-p 20.8366 -> 19.6546"); the
0.4 s run of rv40e gives the same steady window, -166.36764" and 0.39327", and the
converged regression case flexible_rv221 is unchanged.

Where the time goes (2026-11-24, 0.1 s from rest, CPU per step; user functions timed
around their calls; scratch measurement, not printed by this script):

=====  ========  ================================  ===============================  ============  ============
preset per step  rows' residuals                   rows' Jacobians                  fused groups  the rest
=====  ========  ================================  ===============================  ============  ============
rv221  1125 us   618 us (12.0 calls, 51 us each)   31 us (0.11 calls, 277 us each)  162 us        314 us
rv40e  2600 us   876 us (9.2 calls, 96 us each)    640 us (1.10 calls, 581 us each) 168 us        916 us
=====  ========  ================================  ===============================  ============  ============

(Newton iterations / Jacobians per step: rv221 5.0 / 0.056, rv40e 3.6 / 0.55; "the rest" is
Exudyn's own work -- the sparse LU of the 249-coordinate system, ~0.8 ms per Jacobian on
rv40e, the assembly and back-substitutions -- and the pre-step hook.) rv40e's goal (<= 15 s
per simulated s, 1.5 ms per step) is not met, and these did not bring it closer (measured
the same way): Exudyn's Newton contractivity 0.25 / 0.8 instead of 0.5: 25.3 / 25.7 s/s
against 26.1 (3.3 / 5.3 iterations, the Jacobians traded for iterations); a fresh
Jacobian every step: 36.3 s/s (2.1 iterations, 1.13 Jacobians per step); Exudyn's dense
solver for the 249 coordinates: 142 s/s. A low-rank ring compliance is not available:
the compliance factor tables (rv40e 165 / 181 modes, rv221 99 / 115) have a flat
singular-value spectrum, the smallest s^2 0.7-0.8 % of the largest, so every mode
counts at the raceway (the compliance there is local, not a few ring modes). Quasi-static
balls with the condensed rings (as the ball model's) would shrink the system to 21
coordinates but need the row's dense 3Z x 3Z ball solve inside every residual call:
estimated (~2 calls per step x 2 rows x ~3 row evaluations of 96 us, ~1.2 ms, plus a
Jacobian per step, ~1.2 ms for the two rows and their dense 114 x 114 condensations)
no faster than today, so not built.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time

import numpy as np


def run(preset: str, model: str, t_end: float, options: dict, window: float | None = None) -> dict:
    from flexrv.simulation import Simulation

    # warm-up: numba cache loads and one-time imports of the outputs path (xarray's first DataArray
    # imports its duck-array modules, ~0.36 s, which a 0.1 s run would count as 3.6 s per simulated s)
    Simulation(preset, model=model, model_options=options).run(t_end=2e-3)
    sim = Simulation(preset, model=model, model_options=options)
    t0 = time.perf_counter()
    m = sim.build()
    build = time.perf_counter() - t0
    c0 = time.process_time()
    res = sim.run(t_end=t_end)
    cpu = time.process_time() - c0
    t = sim.timing
    steps = max(t["steps"], 1)
    sim_s = max(t["simulated_s"], 1e-12)
    te = res["te"].sel(time=slice(t_end - (0.5 * t_end if window is None else window), None)).values
    ball = float(np.max(res["ball_load_inner"].values[-1])) if "ball_load_inner" in res else float("nan")
    ring = float(np.max(res["ring_deformation_outer"].values[-1])) if "ring_deformation_outer" in res else float("nan")
    return {
        "model": model,
        "coordinates": m.n,
        "build_s": build,
        "solve_s": t["solve_s"],
        "wall_per_sim_s": t["solve_s"] / sim_s,
        "cpu_per_sim_s": cpu / sim_s,
        "ms_per_step": 1e3 * t["solve_s"] / steps,
        "newton_per_step": t["newton_iterations"] / steps,
        "jacobians": t["jacobians"],
        "te_mean": float(te.mean()),
        "te_pp": float(np.ptp(te)),
        "max_ball_load": ball,
        "ring_um": 1e6 * ring,
        "status": res.attrs.get("status"),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--preset", default="rv221")
    parser.add_argument("--t-end", type=float, default=0.1)
    parser.add_argument("--models", default="rigid,balls,flexible")
    parser.add_argument("--harmonics", type=int, default=None, help="raceway harmonics K of the rings")
    parser.add_argument("--parts", default="main_bearing", help="flexible parts of the flexible model")
    parser.add_argument("--ring-options", default="{}", help="extra ring options (JSON), e.g. '{\"condense\": false}'")
    parser.add_argument(
        "--window",
        type=float,
        default=None,
        help="TE statistics over the last WINDOW s "
        "(default: the last half; past the load ramp 0.1-0.2 s use --t-end 0.3 --window 0.1)",
    )
    parser.add_argument("--cold", action="store_true", help="mesh and reduce the rings in an empty cache")
    args = parser.parse_args()
    if args.cold:
        os.environ["FLEXRV_CACHE"] = tempfile.mkdtemp(prefix="flexrv-bench-")
    window = 0.5 * args.t_end if args.window is None else args.window
    print(
        f"preset {args.preset}, t_end {args.t_end} s, dt 1e-4 s; TE over the last {window:g} s [arcsec]; "
        f"cpu/sim: CPU of run() (solve + outputs) per simulated s"
    )
    print(
        f"{'model':10s} {'n':>5s} {'build s':>8s} {'solve s':>8s} {'wall/sim':>8s} {'cpu/sim':>8s} {'ms/step':>8s} "
        f"{'Newton/st':>9s} {'Jacobians':>9s} {'TE mean':>10s} {'TE p-p':>8s} {'max Q_i N':>10s} {'ring um':>8s}"
    )
    for model in args.models.split(","):
        opts = {}
        if model == "flexible":
            opts["parts"] = args.parts.split(",")
            ring = json.loads(args.ring_options)
            if args.harmonics is not None:
                ring["harmonics"] = args.harmonics
            if ring:
                opts["ring_options"] = ring
        r = run(args.preset, model, args.t_end, opts, args.window)
        print(
            f"{r['model']:10s} {r['coordinates']:5d} {r['build_s']:8.2f} {r['solve_s']:8.2f} "
            f"{r['wall_per_sim_s']:8.1f} {r['cpu_per_sim_s']:8.1f} {r['ms_per_step']:8.2f} "
            f"{r['newton_per_step']:9.2f} {r['jacobians']:9d} {r['te_mean']:10.4f} {r['te_pp']:8.4f} "
            f"{r['max_ball_load']:10.2f} {r['ring_um']:8.4f}  {r['status']}",
            flush=True,
        )


if __name__ == "__main__":
    main()
