"""Wall time per simulated second: rv40e with rigid vs flexible crankshafts.

Runs the :cite:`seed002` drive (1215 r/min ramp, 412 N m load ramp) for ``T_END`` s with
each model (same dt), after building the model once untimed so that the FE
condensation of the crankshaft (cached under flexrv.cache.cache_dir()) is not in
the figure; the cold condensation time is printed separately.

Run: ``python benchmarks/bench_flexible_crank.py [t_end]``.
"""

from __future__ import annotations

import sys
import time

T_END = 0.1  #: simulated time per run [s]


def main(t_end: float = T_END) -> dict:
    from flexrv.design import load
    from flexrv.fem.crankshaft import crank_compliance
    from flexrv.simulation import Simulation

    red = load("rv40e")
    t0 = time.perf_counter()
    comp = crank_compliance(red, cache=False)
    cold = time.perf_counter() - t0
    crank_compliance(red)  # warm the cache for the timed runs
    out = {"condensation_cold_s": cold, "k_t_Nm_per_rad": comp.torsional, "lowest_clamped_hz": comp.lowest_clamped_hz}
    for label, model, opts in (("rigid crank", "rigid", {}), ("flexible crank", "flexible", {"parts": ["crankshaft"]})):
        sim = Simulation(red, model=model, model_options=opts)
        t0 = time.perf_counter()
        res = sim.run(t_end=t_end)
        wall = time.perf_counter() - t0
        out[label] = {"wall_s": wall, "wall_per_simulated_s": wall / t_end, "steps": int(len(res.time))}
    print(
        f"rv40e, t_end = {t_end:g} s (seed002 drive); crank FE condensation cold: {cold:.2f} s "
        f"(k_t = {comp.torsional:.4g} N m/rad, lowest clamped mode {comp.lowest_clamped_hz:.4g} Hz)"
    )
    for label in ("rigid crank", "flexible crank"):
        o = out[label]
        print(f"  {label:15s} wall {o['wall_s']:7.2f} s   {o['wall_per_simulated_s']:7.1f} s per simulated s")
    print(f"  flexible / rigid: {out['flexible crank']['wall_s'] / out['rigid crank']['wall_s']:.2f}")
    return out


if __name__ == "__main__":
    main(float(sys.argv[1]) if len(sys.argv) > 1 else T_END)
