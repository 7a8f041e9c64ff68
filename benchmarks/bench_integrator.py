"""Benchmark of the compiled generalized-alpha integrator against Exudyn's, paired in one
process: a model (``--model``, default rigid; balls, flexible) of each preset, the same run
on both integrators.

Run:  python benchmarks/bench_integrator.py [--t-end 0.3] [--presets rv40e rv221] [--repeat 2] [--split]
      [--model rigid|balls|flexible]

The run starts at rated speed (speed and load ramps shortened to 5 ms, as
benchmarks/bench_rigid.py) and lasts ``--t-end``. Three runs per repeat, alternating:
Exudyn's integrator, the compiled one (its defaults) and the compiled one with Exudyn's
predictor (compiled*, ``newton_options={"extrapolatedPredictor": False}``: the same steps and
Newton iterations as Exudyn's). The flexible rings, whose default is Exudyn's predictor with
partial Jacobians (:mod:`flexrv.model.numerics.gen_alpha`), run compiled* with the extrapolated
one and a fourth run, compiled-, without partial Jacobians (the settings before them).
Printed per preset and run:

* CPU s of the solve per simulated s (``time.process_time`` around the segment loop,
  ``Simulation.timing["solve_cpu_s"]``; the best of ``--repeat`` runs, and the spread) and
  the ratio Exudyn / compiled;
* Newton iterations, Jacobians (full; partial ones in brackets) and force-kernel calls per step;
* TE mean and peak-to-peak over t > 0.05 s [arcsec];
* the share of a compiled step outside the force kernel: 1 - (kernel calls x the
  kernel's cost per call) / solve time, the cost per call measured on the run's
  recorded states with the solver's own kernel arguments (warm starts carried from
  state to state as in the run): per state the step's number of calls, the first with
  the Jacobian, in a compiled loop, less the same loop without calls. The calls of a
  step at one state converge their inner solves at once, so this cost is a lower
  bound and the share outside the kernel an upper bound.

``--split`` measures the split inside the run instead: a copy of the generated
``fused_integrate`` with a CPU clock (libc ``clock``) read around its kernel call site
and around the whole call, so per step: the kernel (its first call of a step, the
others), the compiled loop around it (the generalized-alpha's linear algebra, the
records) and Python (the returns every ``RETURN_EVERY`` steps, tables, argument unboxing). A clock
read costs ~0.8 us (a system call; measured): of the two per kernel call about one is
counted in the kernel's share, one in the loop's (~2 us per step each). The copy is not cached
(a ctypes function is a dynamic global for numba): it compiles in every process.

One-time numba compilation/loading is done before timing (a 20-step run of each).
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
from _shared import quick_ramps

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

#: the runs of a repeat: (label, integrator, newton_options); compiled* the compiled integrator with
#: the other predictor than its default for the model (the rigid and ball models extrapolate, the
#: flexible rings keep their iteration matrix and use Exudyn's: flexrv.simulation.KEPT_MATRIX_COMPILED)
RUNS = (
    ("exudyn", "exudyn", None),
    ("compiled", "compiled", None),
    ("compiled*", "compiled", {"extrapolatedPredictor": False}),
)
#: the flexible rings' runs (their default predictor is Exudyn's); compiled- is the compiled integrator
#: without partial Jacobians, with the extrapolated predictor (its settings before the partial Jacobians)
FLEXIBLE_RUNS = (
    ("exudyn", "exudyn", None),
    ("compiled", "compiled", None),
    ("compiled*", "compiled", {"extrapolatedPredictor": True}),
    ("compiled-", "compiled", {"partialJacobian": False, "extrapolatedPredictor": True}),
)


def runs(model_name: str) -> tuple:
    """The runs of a repeat for ``model_name`` (:data:`RUNS`, :data:`FLEXIBLE_RUNS`)."""
    return FLEXIBLE_RUNS if model_name == "flexible" else RUNS


#: slots of the split's clock array: [unused (failure counters sum slot 0), kernel, whole calls,
#: the steps' first kernel calls, first calls]
_K, _CALL, _FIRST, _NFIRST = 1, 2, 3, 4


def _run(sim, integrator: str, t_end: float, options):
    res = sim.run(t_end=t_end, integrator=integrator, checkpoint_s=None, newton_options=options)
    t = res.time
    te = res["te"].values[t > 0.05]
    return res, dict(sim.timing), float(te.mean()), float(np.ptp(te))


def _kernel_cost(model, ts, qs, vs, calls_per_step: float) -> float:
    """CPU s per call of the solver's fused kernel at the run's recorded states: per state
    the step's calls (the first with the Jacobian) in one compiled loop, less the same loop
    without calls (the arguments' unboxing and the Python per state); module docstring."""
    from numba import njit

    kern = model.fused.kernel

    @njit
    def replay(q, v, f, jq, jv, reps, *packs):
        for r in range(reps):
            kern(q, v, f, jq, jv, r == 0, *packs)

    fused = model.fused
    reps = max(int(round(calls_per_step)), 1)
    for g in model.groups:
        g.reset()
    spent = []
    for n in (reps, 0, reps, 0):
        replay(qs[1], vs[1], fused.f, fused.jq, fused.jv, n, *fused.packs)  # (compile)
        c0 = time.process_time()
        for i in range(1, len(ts)):
            for g, array in fused.timed:
                g.set_time(float(ts[i]), array)
            replay(qs[i], vs[i], fused.f, fused.jq, fused.jv, n, *fused.packs)
        spent.append(time.process_time() - c0)
    return (min(spent[0], spent[2]) - min(spent[1], spent[3])) / ((len(ts) - 1) * reps)


def _clocked_integrate(model):
    """A copy of the model's generated ``fused_integrate`` with CPU clocks around its kernel
    call site and its whole call, accumulated into the last counter array (module docstring)."""
    import importlib.util
    import tempfile

    from flexrv.model.core import registry

    specs = [registry.spec_of(g) for g, _ in model.fused.slots]
    src = registry._fused_source(specs, registry._source_hash(specs))
    integrate = src.index("def fused_integrate(")
    head, body = src[:integrate], src[integrate:]
    lines = body.splitlines(keepends=True)
    # the one evaluation site: from zeroing f to the last element's kernel call
    first = next((i for i, ln in enumerate(lines) if ln.strip() == "f[:] = 0.0"), None)
    last = max((i for i, ln in enumerate(lines) if ln.lstrip().startswith(f"k{len(specs) - 1}(q, v,")), default=None)
    if first is None or last is None:
        raise RuntimeError("--split: the generated fused_integrate has no kernel call site it recognises")
    ind = lines[first][: len(lines[first]) - len(lines[first].lstrip())]
    clocked = (
        f"{ind}c0 = _clock()\n{''.join(lines[first : last + 1])}{ind}c1 = _clock() - c0\n"
        f"{ind}if not rows:\n{ind}    ctrs[-1][{_K}] += c1\n"
        f"{ind}    if st.ip[I_IT] == 0:\n{ind}        ctrs[-1][{_FIRST}] += c1\n{ind}        ctrs[-1][{_NFIRST}] += 1\n"
    )
    body = "".join(lines[:first]) + clocked + "".join(lines[last + 1 :])

    def done(pad: str) -> str:  # (the ROWS mode's counters are the element's: no clock there)
        return f"{pad}if not rows:\n{pad}    ctrs[-1][{_CALL}] += _clock() - t_call\n"

    body = (
        body.replace("    n = qs.shape[0] if rows", "    t_call = _clock()\n    n = qs.shape[0] if rows")
        .replace("                return i, 2\n", done("                ") + "                return i, 2\n")
        .replace("                return i, 1\n", done("                ") + "                return i, 1\n")
        .replace("                return i, 3\n", done("                ") + "                return i, 3\n")
        .replace("                return i + 1, 4\n", done("                ") + "                return i + 1, 4\n")
        .replace("    return n, 0\n", done("    ") + "    return n, 0\n")
    )
    src = (
        (head + body)
        .replace("import CONVERGED,", "import I_IT, CONVERGED,")
        .replace(
            "from numba import njit\n",
            "from numba import njit\nimport ctypes\n_clock = ctypes.CDLL(None).clock\n"
            "_clock.restype = ctypes.c_long\n_clock.argtypes = []\n",
        )
    )
    path = os.path.join(tempfile.mkdtemp(prefix="flexrv_split_"), "clocked_fused.py")
    with open(path, "w") as fh:
        fh.write(src)
    spec = importlib.util.spec_from_file_location("clocked_fused", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.fused_integrate


def split(name: str, t_end: float, repeat: int, model_name: str = "rigid") -> None:
    """Print the in-run split of a compiled step (``--split``; module docstring)."""
    import flexrv.model.integrator as integrator
    from flexrv.simulation import Simulation

    sim = Simulation(quick_ramps(name), model=model_name)
    model = sim.build()
    model.fused.integrate_kernel = _clocked_integrate(model)
    clocks = np.zeros(5, np.int64)  # libc clock(): microseconds
    init = integrator.CompiledIntegrator.__init__

    def with_clocks(self, *a, **k):
        init(self, *a, **k)
        self.ctrs = (*self.ctrs, clocks)

    integrator.CompiledIntegrator.__init__ = with_clocks
    try:
        for label, integ, options in runs(model_name)[1:]:
            sim.run(t_end=0.002, integrator=integ, checkpoint_s=None, newton_options=options)  # (compile)
            for _ in range(repeat):
                clocks[:] = 0
                sim.run(t_end=t_end, integrator=integ, checkpoint_s=None, newton_options=options)
                tm = sim.timing
                steps, calls = tm["steps"], model.fused.stats[0]
                solve, kern, loop = tm["solve_cpu_s"] * 1e6 / steps, clocks[_K] / steps, clocks[_CALL] / steps
                print(
                    f"  {label:9s} split: {solve:6.1f} us per step = kernel {kern:5.1f} ({100 * kern / solve:.0f} %: "
                    f"first call {clocks[_FIRST] / clocks[_NFIRST]:.1f} us, others "
                    f"{(clocks[_K] - clocks[_FIRST]) / max(calls - clocks[_NFIRST], 1):.1f} us per call) + loop "
                    f"{loop - kern:4.1f} + Python {solve - loop:4.1f}; outside the kernel "
                    f"{100 * (1 - kern / solve):.0f} %; calls {calls / steps:.2f}, Newton "
                    f"{tm['newton_iterations'] / steps:.2f} per step"
                )
    finally:
        integrator.CompiledIntegrator.__init__ = init


def bench(name: str, t_end: float, repeat: int, model_name: str = "rigid") -> dict:
    import flexrv.simulation as S
    from flexrv.simulation import Simulation

    sim = Simulation(quick_ramps(name), model=model_name)
    model = sim.build()
    for _, integ, options in runs(model_name):  # compile / load the kernels
        sim.run(t_end=0.002, integrator=integ, checkpoint_s=None, newton_options=options)
    states = {}
    orig = S._Records.__init__

    def keep(self, *a, **k):  # the run's recorded states, for the kernel's cost per call
        orig(self, *a, **k)
        states["records"] = self

    S._Records.__init__ = keep
    out = {}
    try:
        for _ in range(repeat):
            for label, integ, options in runs(model_name):
                res, timing, mean, pp = _run(sim, integ, t_end, options)
                best = out.get(label)
                cpus = [timing["solve_cpu_s"], *(best["cpus"] if best else [])]
                if best is None or timing["solve_cpu_s"] < best["cpu"]:
                    rec = states["records"]
                    out[label] = {
                        "cpu": timing["solve_cpu_s"],
                        "steps": timing["steps"],
                        "newton": timing["newton_iterations"],
                        "jacobians": timing["jacobians"],
                        "partial": timing.get("partial_jacobians", 0),
                        "calls": model.fused.stats[0],
                        "mean": mean,
                        "pp": pp,
                        "states": (rec.ts[: rec.k].copy(), rec.qs[: rec.k].copy(), rec.vs[: rec.k].copy()),
                    }
                out[label]["cpus"] = cpus
    finally:
        S._Records.__init__ = orig
    c = out["compiled"]
    if c["jacobians"] >= c["steps"]:  # (the replay computes a Jacobian at every state: not with kept ones)
        per_call = _kernel_cost(model, *c["states"], c["calls"] / c["steps"])
        c["kernel_share"] = c["calls"] * per_call / c["cpu"]
        c["per_call_us"] = per_call * 1e6
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=0.3)
    ap.add_argument("--presets", nargs="+", default=["rv40e", "rv221"])
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--split", action="store_true", help="the in-run split of a compiled step (module docstring)")
    ap.add_argument("--model", default="rigid", choices=("rigid", "balls", "flexible"))
    args = ap.parse_args()
    for name in args.presets:
        if args.split:
            print(f"\n{name}: {args.model} model, t_end {args.t_end:g} s")
            split(name, args.t_end, args.repeat, args.model)
            continue
        out = bench(name, args.t_end, args.repeat, args.model)
        e, c = out["exudyn"], out["compiled"]
        print(f"\n{name}: {args.model} model, t_end {args.t_end:g} s, {c['steps']} steps")
        for label, r in out.items():
            spread = ", ".join(f"{x / args.t_end:.3f}" for x in sorted(r["cpus"]))
            print(
                f"  {label:9s} CPU {r['cpu'] / args.t_end:7.3f} s per simulated s ({spread})   "
                f"Newton {r['newton'] / r['steps']:.2f}  Jacobians {r['jacobians'] / r['steps']:.2f} "
                f"(partial {r['partial'] / r['steps']:.2f})  "
                f"kernel calls {r['calls'] / r['steps']:.2f} per step   "
                f"TE mean {r['mean']:+.5f}  p-p {r['pp']:.4f} arcsec"
            )
        other = e["cpu"] / out["compiled*"]["cpu"]
        print(f"  ratio Exudyn / compiled CPU: {e['cpu'] / c['cpu']:.2f}x (compiled*: {other:.2f}x)")
        if "compiled-" in out:
            print(f"  compiled- / compiled CPU: {out['compiled-']['cpu'] / c['cpu']:.2f}x")
        if "kernel_share" not in c:
            print("  compiled: Jacobians kept across steps, the kernel's share: --split")
            continue
        print(
            f"  compiled: kernel {c['per_call_us']:.1f} us per call, {100 * c['kernel_share']:.0f} % of the solve; "
            f"outside the kernel {100 * (1 - c['kernel_share']):.0f} % "
            f"({(1 - c['kernel_share']) * c['cpu'] / c['steps'] * 1e6:.1f} us per step)"
        )


if __name__ == "__main__":
    main()
