"""Benchmark of the quasi-static loaded-TE solver (``flexrv te``).

Prints, per preset, paired in one process (CPU seconds, BLAS pinned to one thread: the
21x21 solves are far too small for threads):

* the loaded curve (warm-started Newton), its iterations and residual calls per position;
* the no-load curve by the position-by-position route, by the periodic route
  (:func:`flexrv.model.quasi_static.equilibrium_path` with ``periodic=True``: from the second
  crank revolution on, each position starts from its image one revolution earlier) and by the
  periodic route that evaluates only every 8th imaged start from the third revolution on
  (``check_every``, what ``loaded_te`` does for a design without errors), with the largest TE
  differences between them;
* the whole ``loaded_te`` call (loaded + no-load + outputs + catalog points) and its ratio to
  the loaded curve alone, and the TE statistics, so speed never buys a different answer.

With ``--command`` it also times the whole ``flexrv te`` process (CPU of the child);
``benchmarks/bench_startup.py`` splits that process into its phases.

Goals: one output revolution of rv40e with 8 points per cycloid-mesh period (12,480
positions) in <= 2 s per curve on one core; the whole command <= 1.3 x its loaded curve.

    python benchmarks/bench_te.py [--crank-revolutions N] [--full] [--command]

``--full`` times one whole output revolution of rv40e (the goals' case).
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np
from threadpoolctl import threadpool_limits

from flexrv.design import load
from flexrv.model.quasi_static import (
    NO_LOAD_CHECK_EVERY,
    StaticModel,
    equilibrium_path,
    loaded_te,
    positions_for,
    ramp_to,
)
from flexrv.units import ARCSEC_PER_RAD


def _curve(sm, angles, q, periodic=False, check_every=1):
    t0, c0 = time.process_time(), sm.calls
    qs, its = equilibrium_path(sm, angles, q, periodic=periodic, check_every=check_every)
    return qs, its, time.process_time() - t0, (sm.calls - c0) / len(angles)


def bench(name: str, crank_revolutions: float, output_revolutions: float | None = None) -> float:
    red = load(name)
    kw = {"output_revolutions": output_revolutions} if output_revolutions else {"crank_revolutions": crank_revolutions}
    angles = positions_for(red, points_per_mesh=8, **kw)
    sm = StaticModel(red)
    rated = red.operating.rated_torque_Nm
    sm.torque = 0.0
    q = ramp_to(sm, angles[0], sm.kinematic_pose(angles[0]), rated)
    q_l, its, t_l, calls = _curve(sm, angles, q)
    n = len(angles)
    print(
        f"{name}: {n} positions; loaded curve {t_l:.2f} s CPU, {t_l / n * 1e6:.0f} us/position "
        f"({np.mean(its):.2f} iterations, {calls:.2f} residual calls per position)"
    )
    q_small = ramp_to(sm, angles[0], q_l[0], 0.01 * rated)
    te = {}
    routes = {
        "position by position": (False, 1),
        "periodic route": (True, 1),
        f"periodic route checked every {NO_LOAD_CHECK_EVERY}th": (True, NO_LOAD_CHECK_EVERY),
    }
    for route, (periodic, every) in routes.items():
        q_n, its_n, t_n, calls_n = _curve(sm, angles, q_small, periodic=periodic, check_every=every)
        te[route] = (q_n[:, sm.i_theta] - angles / sm.p.ratio) * ARCSEC_PER_RAD
        print(
            f"   no-load curve, {route}: {t_n:.2f} s CPU "
            f"= {t_n / t_l:.2f} x the loaded curve ({np.mean(its_n):.2f} iterations, {calls_n:.2f} calls per "
            f"position); p-p {np.ptp(te[route]):.6f} arcsec"
        )
    base, *others = routes
    for route in others:
        print(f"   largest no-load TE difference, {route} - {base}: {np.max(np.abs(te[route] - te[base])):.2e} arcsec")
    t0 = time.process_time()
    r = loaded_te(red, points_per_mesh=8, **kw)
    total = time.process_time() - t0
    s = r.summary()
    print(
        f"   whole loaded_te (loaded + no-load + outputs + catalog) {total:.2f} s CPU "
        f"= {total / t_l:.2f} x the loaded curve"
    )
    split = ", ".join(f"{k.replace('_', ' ')} {v:.2f}" for k, v in getattr(r, "timing", {}).items())
    if split:
        print(f"   its phases (s CPU): {split}")
    print(
        f"   TE p-p {s['te_pp_arcsec']:.4f} arcsec, mean {s['te_mean_arcsec']:.3f} arcsec, no-load p-p "
        f"{s['no_load_te_pp_arcsec']:.4f} arcsec, lost motion {s['lost_motion_arcmin']:.4f} arcmin, "
        f"rigidity {s['torsional_rigidity_Nm_per_arcmin']:.2f} N m/arcmin"
    )
    return t_l


def command(name: str, loaded_s: float) -> None:
    """CPU of a whole ``flexrv te NAME`` process (warm caches) against the loaded curve."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run(
            [sys.executable, "-m", "flexrv", "te", name, "--out", os.path.join(tmp, "te"), "--json"],
            check=True,
            capture_output=True,
            env=dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg"),
        )
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime
    print(f"   whole `flexrv te {name}` process {cpu:.2f} s CPU = {cpu / loaded_s:.2f} x the loaded curve")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--crank-revolutions", type=float, default=4.0)
    ap.add_argument("--full", action="store_true", help="one whole output revolution of rv40e")
    ap.add_argument("--command", action="store_true", help="also time the whole `flexrv te` process (--full: rv40e)")
    a = ap.parse_args()
    with threadpool_limits(1):
        if a.full:
            t_l = bench("rv40e", 0.0, output_revolutions=1.0)
            if a.command:
                command("rv40e", t_l)
        else:
            for name in ("rv40e", "rv221"):
                bench(name, a.crank_revolutions)


if __name__ == "__main__":
    main()
