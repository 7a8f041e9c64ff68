"""Benchmark: cold-cache cost of the FE carrier and cycloid-disc bodies.

Run: python benchmarks/bench_bodies.py [--presets rv40e rv221] [--carrier-size MM] [--disc-size MM]

Each body is built in its own child process on an empty cache directory (what a
first ``flexrv design`` or a CI run pays): the carrier condensation
(:func:`flexrv.fem.carrier.carrier_compliance` without the rigid-bore bound, as the
models' crank supports and the budget read it; ``--rbe2`` adds the bound) and the disc patch sweep
(:func:`flexrv.fem.disc.disc_torsion_sweep`, the models' rim compliance and the
budget). The phases are timed by wrapping the executors (no second copy of the
pipeline): meshing (gmsh, :func:`flexrv.meshing.mesh.generate_mesh`), assembly
(scikit-fem P2 stiffness and mass, :func:`flexrv.fem.assembly.assemble`) and the
rest (factorisation, solves, condensation). CPU time is ``time.process_time`` of
the child (immune to the other jobs on a shared machine, unlike wall time), peak
memory its ``ru_maxrss``; the child's import baseline is printed beside it.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile

CHILD = r"""
import json, os, resource, sys, time
os.environ.setdefault("OMP_NUM_THREADS", "1"); os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
import flexrv.meshing.mesh as M
import flexrv.fem.assembly as A
from flexrv.design import load
preset, body, size = sys.argv[1], sys.argv[2], (None if sys.argv[3] == "none" else float(sys.argv[3]) * 1e-3)
base_rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
t = {"mesh": 0.0, "assemble": 0.0}
def wrap(mod, name, key):
    f = getattr(mod, name)
    def g(*a, **k):
        c0 = time.process_time()
        try:
            return f(*a, **k)
        finally:
            t[key] += time.process_time() - c0
    setattr(mod, name, g)
wrap(M, "generate_mesh", "mesh")
wrap(A, "assemble", "assemble")
import flexrv.meshing as MS
MS.generate_mesh = M.generate_mesh
r = load(preset)
c0 = time.process_time(); w0 = time.perf_counter()
if body == "carrier":
    from flexrv.fem.carrier import carrier_compliance
    res = carrier_compliance(r, size=size, rigid_bound=(os.environ.get("BENCH_RBE2") == "1"))
    value = res.torsional
else:
    from flexrv.fem.disc import disc_torsion_sweep
    res = disc_torsion_sweep(r, size=size)
    value = res.mean
cpu = time.process_time() - c0
print(json.dumps({"preset": preset, "body": body, "n_nodes": res.n_nodes, "size_mm": res.size * 1e3,
                  "value": value, "cpu": cpu, "wall": time.perf_counter() - w0, "mesh": t["mesh"],
                  "assemble": t["assemble"], "solve": cpu - t["mesh"] - t["assemble"],
                  "peak_MB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, "base_MB": base_rss}))
"""


def run(preset: str, body: str, size_mm: float | None) -> dict:
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg")
    with tempfile.TemporaryDirectory() as tmp:
        env["FLEXRV_CACHE_DIR"] = tmp
        out = subprocess.run(
            [sys.executable, "-c", CHILD, preset, body, "none" if size_mm is None else str(size_mm)],
            env=env,
            capture_output=True,
            text=True,
            check=True,
        )
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--presets", nargs="+", default=["rv40e", "rv221"])
    ap.add_argument("--bodies", nargs="+", default=["carrier", "disc"])
    ap.add_argument("--carrier-size", type=float, default=None, help="carrier mesh size [mm] (part default)")
    ap.add_argument("--disc-size", type=float, default=None, help="disc mesh size [mm] (part default)")
    ap.add_argument("--rbe2", action="store_true", help="carrier: also the rigid-bore bound (a second factorisation)")
    args = ap.parse_args()
    if args.rbe2:
        os.environ["BENCH_RBE2"] = "1"
    print(
        f"{'preset':6} {'body':8} {'size mm':>7} {'nodes':>7} {'mesh s':>7} {'asm s':>6} {'solve s':>7} "
        f"{'CPU s':>6} {'wall s':>6} {'peak MB':>7} {'base MB':>7}  value [rad/(N m)]"
    )
    total = 0.0
    for p in args.presets:
        for b in args.bodies:
            size = args.carrier_size if b == "carrier" else args.disc_size
            d = run(p, b, size)
            total += d["cpu"]
            print(
                f"{p:6} {b:8} {d['size_mm']:7.3g} {d['n_nodes']:7d} {d['mesh']:7.1f} {d['assemble']:6.1f} "
                f"{d['solve']:7.1f} {d['cpu']:6.1f} {d['wall']:6.1f} {d['peak_MB']:7.0f} {d['base_MB']:7.0f}  "
                f"{d['value']:.5e}",
                flush=True,
            )
    print(f"total child CPU {total:.1f} s")


if __name__ == "__main__":
    main()
