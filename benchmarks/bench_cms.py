"""Benchmark: mesh + assemble + reduce (HCB) the rv221 outer ring at ~20k, 50k and
100k DOF. Prints wall time and the process peak RSS after each stage.

Run: ``python benchmarks/bench_cms.py [--eig 20] [--harmonics 0]``
(uses a temporary FLEXRV_CACHE so nothing is reused).
"""

from __future__ import annotations

import argparse
import os
import resource
import tempfile
import time


def peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--eig", type=int, default=20, help="fixed-interface eigenmodes")
    ap.add_argument("--harmonics", type=int, default=0, help="raceway Fourier harmonics K (0: none)")
    ap.add_argument("--sizes", type=str, default="12.5,7.2,5.6", help="mesh sizes [mm] (uniform)")
    args = ap.parse_args()
    os.environ["FLEXRV_CACHE"] = tempfile.mkdtemp(prefix="flexrv-bench-")

    import numpy as np

    from flexrv.design import load
    from flexrv.fem.assembly import assemble
    from flexrv.fem.body import build_reduced_body, material_dict, raceway_spec_for
    from flexrv.meshing import build_mesh, spec_for

    rv = load("rv221")
    mat = material_dict(rv, "outer_ring")
    print(
        f"{'DOF':>8} {'mesh s':>7} {'assemble s':>10} {'reduce s':>9} {'modes':>6} {'total s':>8} {'peak RSS MB':>11}"
    )
    for size_mm in (float(s) for s in args.sizes.split(",")):
        h = size_mm * 1e-3
        t0 = time.perf_counter()
        mres = build_mesh(rv, "outer_ring", size=h, local_size=h, cache=False)
        t1 = time.perf_counter()
        fe = assemble(mres.data.nodes, mres.data.tets, mat["E"], mat["nu"], mat["rho"])
        t2 = time.perf_counter()
        rw = raceway_spec_for(spec_for(rv, "outer_ring"), None, args.harmonics) if args.harmonics else None
        body = build_reduced_body(mres, mat, n_eig=args.eig, raceway=rw, fe=fe, cache=False)
        t3 = time.perf_counter()
        print(
            f"{fe.n_dof:8d} {t1 - t0:7.2f} {t2 - t1:10.2f} {t3 - t2:9.2f} {body.n_modes:6d} {t3 - t0:8.2f} "
            f"{peak_mb():11.0f}   lowest clamped f = {np.round(body.frequencies_hz[:2], 0)} Hz"
        )


if __name__ == "__main__":
    main()
