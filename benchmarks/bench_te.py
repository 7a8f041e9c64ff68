"""Benchmark of the quasi-static loaded-TE solver (``flexrv te``).

Prints, per preset, the cost per position of the loaded curve (warm-started
Newton), of the whole ``loaded_te`` call (loaded + no-load curves + catalog
points), Newton iterations per position and the TE statistics, so speed never
buys a different answer. BLAS is pinned to one thread (the 21x21 solves are
far too small for threads).

Goal: one output revolution of rv40e with 8 points per
cycloid-mesh period (12,480 positions) in <= 2 s on one core.

    python benchmarks/bench_te.py [--crank-revolutions N] [--full]

``--full`` times one whole output revolution of rv40e (the goal's case).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from threadpoolctl import threadpool_limits

from flexrv.design import load
from flexrv.model.quasi_static import StaticModel, equilibrium_path, loaded_te, positions_for, ramp_to


def bench(name: str, crank_revolutions: float, output_revolutions: float | None = None) -> None:
    red = load(name)
    kw = {"output_revolutions": output_revolutions} if output_revolutions else {"crank_revolutions": crank_revolutions}
    angles = positions_for(red, points_per_mesh=8, **kw)
    sm = StaticModel(red)
    sm.torque = 0.0
    q = ramp_to(sm, angles[0], sm.kinematic_pose(angles[0]), red.operating.rated_torque_Nm)
    t0 = time.perf_counter()
    c0 = sm.calls
    _, its = equilibrium_path(sm, angles, q)
    dt = time.perf_counter() - t0
    calls = (sm.calls - c0) / len(angles)
    t0 = time.perf_counter()
    r = loaded_te(red, points_per_mesh=8, **kw)
    total = time.perf_counter() - t0
    s = r.summary()
    print(
        f"{name}: {len(angles)} positions; loaded curve {dt / len(angles) * 1e6:.0f} us/position "
        f"({np.mean(its):.2f} iterations, {calls:.2f} residual+Jacobian calls per position), "
        f"{dt:.2f} s; whole loaded_te (loaded + no-load + catalog) {total:.2f} s"
    )
    print(
        f"   TE p-p {s['te_pp_arcsec']:.4f} arcsec, mean {s['te_mean_arcsec']:.3f} arcsec, no-load p-p "
        f"{s['no_load_te_pp_arcsec']:.4f} arcsec, lost motion {s['lost_motion_arcmin']:.4f} arcmin, "
        f"rigidity {s['torsional_rigidity_Nm_per_arcmin']:.2f} N m/arcmin"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--crank-revolutions", type=float, default=1.0)
    ap.add_argument("--full", action="store_true", help="one whole output revolution of rv40e")
    a = ap.parse_args()
    with threadpool_limits(1):
        if a.full:
            bench("rv40e", 0.0, output_revolutions=1.0)
        else:
            for name in ("rv40e", "rv221"):
                bench(name, a.crank_revolutions)


if __name__ == "__main__":
    main()
