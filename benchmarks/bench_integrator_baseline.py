"""The compiled integrator of this checkout against the Exudyn path of another checkout
(the code before the compiled integrator existed), paired: alternating child processes
in one session; with ``--elements``, the force kernel's cost per step by element in both.

Run:  python benchmarks/bench_integrator_baseline.py --baseline DIR [--presets rv40e rv221]
      [--t-end 0.2] [--repeat 2] [--model rigid|balls|flexible] [--elements]

``DIR`` is a checkout of the earlier code (e.g. ``git worktree add --detach /tmp/base REV``);
its numba cache is warmed by a first untimed run. Per preset and repeat, three children run
the model (``--model``, default rigid) from rated speed (ramps shortened to 5 ms, as ``_shared.quick_ramps``) for
``--t-end`` simulated seconds after a 2 ms warm-up run in the same process:

* ``baseline exudyn``: ``DIR``'s flexrv, Exudyn's integrator (its only one);
* ``exudyn``: this checkout's flexrv, ``integrator="exudyn"``;
* ``compiled``: this checkout's flexrv, ``integrator="compiled"``.

Printed: CPU s of the solve per simulated s (``Simulation.timing["solve_cpu_s"]``, the best
of ``--repeat`` and the spread), steps, Newton iterations per step, TE mean and p-p over
t > 0.05 s [arcsec], and the ratios baseline / compiled and exudyn / compiled. The children
run from a neutral folder (``python -c`` puts the working folder first on the path).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from _shared import ROOT

#: the child's program: argv = preset, t_end, integrator ("" for the checkout's default path), model
_CHILD = r"""
import inspect, json, sys
import numpy as np
from flexrv.design import load
from flexrv.simulation import Simulation

name, t_end, integ, model = sys.argv[1], float(sys.argv[2]), sys.argv[3], sys.argv[4]
r = load(name)
op = r.operating.model_copy(update={"speed_ramp_time_s": 0.005, "load_ramp_start_s": 0.0, "load_ramp_end_s": 0.005})
sim = Simulation(r.model_copy(update={"operating": op}), model=model)
kw = {"checkpoint_s": None}
if integ:
    kw["integrator"] = integ
elif "integrator" in inspect.signature(sim.run).parameters:
    kw["integrator"] = "exudyn"
sim.run(t_end=0.002, **kw)
res = sim.run(t_end=t_end, **kw)
t = np.asarray(res.time)
te = np.asarray(res["te"].values)
te = te[t > 0.05] if (t > 0.05).any() else te
tm = sim.timing
print("RESULT " + json.dumps({"cpu": tm["solve_cpu_s"], "steps": tm["steps"],
      "newton": tm["newton_iterations"], "mean": float(te.mean()), "pp": float(np.ptp(te))}))
"""


#: the ``--elements`` child: argv = preset, t_end, folder of this checkout's benchmarks
_ELEMENTS = r"""
import json, sys
sys.path.insert(0, sys.argv[3])
from _shared import quick_ramps
from bench_rigid import _record_calls, _replay_costs
from flexrv.simulation import Simulation

sim = Simulation(quick_ramps(sys.argv[1]))
model = sim.build()
seq = _record_calls(sim, float(sys.argv[2]))
steps, calls = seq["steps"], len(seq["t"])
costs = _replay_costs(model, seq)
out = {k: v / steps for k, v in costs.items() if k != "pin_evaluations"}
out["pin evaluations per call"] = costs.get("pin_evaluations", 0) / calls
out["calls per step"] = calls / steps
print("RESULT " + json.dumps(out))
"""


def _child(
    checkout: Path, preset: str, t_end: float, integ: str, cwd: str, program: str = _CHILD, model: str = "rigid"
) -> dict:
    env = dict(os.environ, PYTHONPATH=str(checkout), OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    out = subprocess.run(
        [sys.executable, "-c", program, preset, str(t_end), integ, model],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    line = next((ln for ln in out.stdout.splitlines() if ln.startswith("RESULT ")), None)
    if out.returncode != 0 or line is None:
        raise RuntimeError(f"{checkout} {preset} {integ or 'default'} failed:\n{out.stderr[-3000:]}")
    return json.loads(line[len("RESULT ") :])


def elements(baseline: Path, presets, t_end: float, repeat: int, cwd: str) -> None:
    """Print the per-element kernel cost of both checkouts (``--elements``)."""
    runs = (("baseline", baseline), ("this", Path(ROOT)))
    bench_dir = str(Path(ROOT) / "benchmarks")
    for preset in presets:
        best: dict[str, dict] = {}
        for _ in range(repeat):
            for label, checkout in runs:
                r = _child(checkout, preset, t_end, bench_dir, cwd, program=_ELEMENTS)
                best[label] = {k: min(v, best.get(label, {}).get(k, np.inf)) for k, v in r.items()}
        b, t = best["baseline"], best["this"]
        print(f"\n{preset}: fused kernel by element, CPU us per step (least of {repeat}); baseline -> this")
        for key in b:
            if key in t:
                change = f"{100 * (t[key] / b[key] - 1):+.0f} %" if b[key] > 0.5 else ""
                print(f"  {key:26s} {b[key]:8.2f} -> {t[key]:8.2f}  {change}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", type=Path, required=True, help="checkout of the earlier code")
    ap.add_argument("--presets", nargs="+", default=["rv40e", "rv221"])
    ap.add_argument("--t-end", type=float, default=0.2)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--model", default="rigid", help="rigid, balls or flexible (not with --elements)")
    ap.add_argument("--elements", action="store_true", help="the kernel's cost per step by element")
    args = ap.parse_args()
    if args.elements:
        elements(args.baseline.resolve(), args.presets, args.t_end, args.repeat, tempfile.mkdtemp(prefix="flexrv_"))
        return
    runs = (
        ("baseline exudyn", args.baseline.resolve(), ""),
        ("exudyn", ROOT, "exudyn"),
        ("compiled", ROOT, "compiled"),
    )
    cwd = tempfile.mkdtemp(prefix="flexrv_bench_")
    for preset in args.presets:
        for _, checkout, integ in runs:  # (numba caches warm, bodies built)
            _child(checkout, preset, 0.003, integ, cwd, model=args.model)
        best: dict[str, dict] = {}
        for _ in range(args.repeat):
            for label, checkout, integ in runs:
                r = _child(checkout, preset, args.t_end, integ, cwd, model=args.model)
                r["cpus"] = [r["cpu"], *best.get(label, {}).get("cpus", [])]
                if label not in best or r["cpu"] < best[label]["cpu"]:
                    best[label] = r
                else:
                    best[label]["cpus"] = r["cpus"]
        print(f"\n{preset}: {args.model} model, t_end {args.t_end:g} s")
        for label, r in best.items():
            spread = ", ".join(f"{x / args.t_end:.3f}" for x in sorted(r["cpus"]))
            print(
                f"  {label:16s} CPU {r['cpu'] / args.t_end:7.3f} s per simulated s ({spread})  steps {r['steps']}  "
                f"Newton {r['newton'] / r['steps']:.2f} per step  TE mean {r['mean']:+.5f}  p-p {r['pp']:.4f} arcsec"
            )
        c = best["compiled"]["cpu"]
        print(
            f"  ratio baseline exudyn / compiled: {best['baseline exudyn']['cpu'] / c:.2f}x; "
            f"exudyn / compiled: {best['exudyn']['cpu'] / c:.2f}x"
        )


if __name__ == "__main__":
    main()
