"""Benchmark: the reducer model with the ball-resolved / flexible main bearing.

Runs the rigid, the ball-bearing (rigid rings) and the flexible-ring model of a
preset over the same short interval and prints wall time per simulated second,
steps, Newton iterations and Jacobians per step, and the time of the model build
(meshing + CMS of the four rings; ``--cold`` builds them in an empty cache).

    python benchmarks/bench_flexible_model.py [--preset rv221] [--t-end 0.05] [--cold]
        [--models rigid,balls,flexible] [--harmonics K] [--parts main_bearing,crankshaft]

Goal of the flexible-bearing issue: <= 60 s wall per simulated second.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time


def run(preset: str, model: str, t_end: float, options: dict) -> dict:
    from flexrv.simulation import Simulation

    sim = Simulation(preset, model=model, model_options=options)
    t0 = time.perf_counter()
    m = sim.build()
    build = time.perf_counter() - t0
    sim.run(t_end=t_end)
    t = sim.timing
    steps = max(t["steps"], 1)
    return {"model": model, "coordinates": m.n, "build_s": build, "solve_s": t["solve_s"],
            "wall_per_sim_s": t["solve_s"] / t["simulated_s"], "ms_per_step": 1e3 * t["solve_s"] / steps,
            "newton_per_step": t["newton_iterations"] / steps, "jacobians": t["jacobians"]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--preset", default="rv221")
    parser.add_argument("--t-end", type=float, default=0.05)
    parser.add_argument("--models", default="rigid,balls,flexible")
    parser.add_argument("--harmonics", type=int, default=None, help="raceway harmonics K of the rings")
    parser.add_argument("--parts", default="main_bearing", help="flexible parts of the flexible model")
    parser.add_argument("--cold", action="store_true", help="mesh and reduce the rings in an empty cache")
    args = parser.parse_args()
    if args.cold:
        os.environ["FLEXRV_CACHE"] = tempfile.mkdtemp(prefix="flexrv-bench-")
    print(f"preset {args.preset}, t_end {args.t_end} s, dt 1e-4 s")
    print(f"{'model':10s} {'n':>5s} {'build s':>8s} {'solve s':>8s} {'s/sim-s':>8s} {'ms/step':>8s} "
          f"{'Newton/step':>11s} {'Jacobians':>9s}")
    for model in args.models.split(","):
        opts = {}
        if model == "flexible":
            opts["parts"] = args.parts.split(",")
            if args.harmonics is not None:
                opts["ring_options"] = {"harmonics": args.harmonics}
        r = run(args.preset, model, args.t_end, opts)
        print(f"{r['model']:10s} {r['coordinates']:5d} {r['build_s']:8.2f} {r['solve_s']:8.2f} "
              f"{r['wall_per_sim_s']:8.1f} {r['ms_per_step']:8.2f} {r['newton_per_step']:11.2f} {r['jacobians']:9d}")


if __name__ == "__main__":
    main()
