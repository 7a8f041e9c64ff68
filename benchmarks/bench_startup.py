"""Where the time of a warm ``flexrv te rv40e`` and ``flexrv simulate rv221 --model rigid
--t-end 0.4`` goes, as whole processes: imports, design, model build, the computation
itself, outputs, files, figures.

    python benchmarks/bench_startup.py [--only te|simulate] [--checkout DIR ...] [--repeat N] [--in-process RUNS]

Each command runs in a child process twice per checkout (``--checkout``, default this one;
give several, e.g. ``--checkout /path/to/main --checkout .``, to pair them in one session,
alternating): once plain, timed from outside (wall from start to exit, CPU of the child),
and once with phase timers (a driver that wraps the library functions of each phase as
their modules are imported, so no import moves; a phase's CPU is the process's CPU spent
inside it, nested phases excluded). The remainder of the instrumented run is the
interpreter, the imports done outside the phases and the CLI's own glue. The caches must
be warm (run each command once before); one unmeasured run per checkout and command compiles
the modules' bytecode (into a folder outside the checkouts, as an installed package has it).
The floor (the CPU of ``python -c`` programs that only import the libraries and load one
cached numba kernel) is printed last. ``--in-process RUNS`` instead runs each command RUNS times in
one process (the instrumented driver, per checkout, alternating) and prints every run's CPU and wall
and the last run's phases: what a warm process (a notebook, a study calling the CLI) pays per command.

Ratios (the goals, paired in one process):

* ``te``: the whole process's CPU over its loaded curve's CPU (the warm-started
  position-by-position path at the operating torque, what ``benchmarks/bench_te.py``
  times as "the loaded curve"), goal <= 1.3;
* ``simulate``: the process wall over the simulation's own wall (the integration,
  ``Simulation.timing["solve_s"]``), goal <= 2; also the CPU ratio.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _shared import ROOT, children_cpu_s

#: the measured commands: name -> arguments of ``python -m flexrv``
COMMANDS = {
    "te": ["te", "rv40e", "--json"],
    "simulate": ["simulate", "rv221", "--model", "rigid", "--t-end", "0.4", "--json"],
}

#: phases of each command: (label, "module:qualified.name") of the functions timed; the first
#: phase whose function is running takes the time (nested phases are excluded from the outer)
PHASES = {
    "te": [
        ("design", "flexrv.design:load"),
        ("model build", "flexrv.model.quasi_static:StaticModel.__init__"),
        ("curves", "flexrv.model.quasi_static:equilibrium_path"),
        ("catalog points", "flexrv.model.quasi_static:_catalog_levels"),
        ("catalog points", "flexrv.model.quasi_static:StaticModel.tangent_rigidity"),
        ("catalog points", "flexrv.model.quasi_static:StaticModel.compliance_budget"),
        ("loaded_te other (ramps, outputs)", "flexrv.model.quasi_static:loaded_te"),
        ("post (dataset, summary, budgets)", "flexrv.post.te:te_dataset"),
        ("post (dataset, summary, budgets)", "flexrv.post.te:te_summary"),
        ("post (dataset, summary, budgets)", "flexrv.cli.te:quasi_static_budget"),
        ("post (dataset, summary, budgets)", "flexrv.cli.design:analytic_budget"),
        ("files", "flexrv.post.te:save_te"),
        ("figures", "flexrv.viz.te_plots:te_plots"),
        ("table / json", "flexrv.cli._common:emit"),
    ],
    "simulate": [
        ("design", "flexrv.simulation:Simulation.__init__"),
        ("model build", "flexrv.simulation:Simulation.build"),
        ("solve", "flexrv.simulation:_segment_loop"),
        ("results (outputs)", "flexrv.post.results:results_from_states"),
        ("figures", "flexrv.viz.plots:PlottedResults.write_figures"),
        ("files", "flexrv.post.io:save"),
        ("run other (integrator set-up)", "flexrv.simulation:Simulation.run"),
        ("summary", "flexrv.post.results:Results.summary"),
        ("table / json", "flexrv.cli._common:emit"),
    ],
}

#: the child's driver: wraps the phase functions when their modules are imported, runs the CLI
#: FLEXRV_BENCH_RUNS times in the one process, writes the last run's {phase: [cpu, wall]}, curves' CPU and
#: solve wall, and every run's [cpu, wall], to the file FLEXRV_BENCH_OUT
DRIVER = r"""
import functools, importlib.machinery, json, os, sys, time
T0, W0 = time.process_time(), time.perf_counter()
specs = json.loads(os.environ["FLEXRV_BENCH_PHASES"])
acc, stack, curves, solve = {}, [], [], []

def wrap(label, fn, name):
    @functools.wraps(fn)
    def timed(*a, **k):
        c0, w0 = time.process_time(), time.perf_counter()
        stack.append([label, 0.0, 0.0])
        try:
            return fn(*a, **k)
        finally:
            dc, dw = time.process_time() - c0, time.perf_counter() - w0
            _, inner_c, inner_w = stack.pop()
            a_ = acc.setdefault(label, [0.0, 0.0])
            a_[0] += dc - inner_c
            a_[1] += dw - inner_w
            if stack:
                stack[-1][1] += dc
                stack[-1][2] += dw
            if name == "equilibrium_path":
                curves.append(dc)
            if name == "_segment_loop":
                solve.append(dw)
    return timed

by_module = {}
for label, target in specs:
    mod, qual = target.split(":")
    by_module.setdefault(mod, []).append((label, qual))

def patch(module):
    for label, qual in by_module.get(module.__name__, []):
        obj = module
        parts = qual.split(".")
        for p in parts[:-1]:
            obj = getattr(obj, p)
        fn = getattr(obj, parts[-1], None)
        if fn is not None:
            setattr(obj, parts[-1], wrap(label, fn, parts[-1]))

class Hook:
    def find_spec(self, name, path=None, target=None):
        if name not in by_module:
            return None
        spec = importlib.machinery.PathFinder.find_spec(name, path)
        if spec is None or spec.loader is None:
            return spec
        run = spec.loader.exec_module
        def exec_and_patch(module):
            run(module)
            patch(module)
        spec.loader.exec_module = exec_and_patch
        return spec

sys.meta_path.insert(0, Hook())
from flexrv.cli import main
code, runs = 0, []
for _ in range(int(os.environ.get("FLEXRV_BENCH_RUNS", "1"))):
    acc.clear(); del curves[:], solve[:]
    c0, w0 = time.process_time(), time.perf_counter()
    try:
        main(sys.argv[1:])
    except SystemExit as exc:
        code = exc.code or 0
    runs.append([time.process_time() - c0, time.perf_counter() - w0])
    if code:
        break
out = {"phases": acc, "cpu": time.process_time() - T0, "wall": time.perf_counter() - W0,
       "curves_cpu": curves, "solve_wall": solve, "code": code, "runs": runs}
with open(os.environ["FLEXRV_BENCH_OUT"], "w") as f:
    json.dump(out, f)
sys.exit(code)
"""


#: compiled bytecode of the children's modules, outside the checkouts (an installed flexrv has its .pyc; a
#: process that recompiles every module from source spends ~0.2 s CPU on it)
PYCACHE = os.path.join(tempfile.gettempdir(), "flexrv-bench-pycache")


def _env(checkout: str) -> dict:
    env = dict(os.environ, PYTHONPATH=checkout, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg")
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    env["PYTHONPYCACHEPREFIX"] = PYCACHE
    return env


#: the floor of a process: what any flexrv command that simulates pays before its own work, as
#: ``python -c`` programs (label, code), each adding to the one before: the interpreter, the numerical
#: libraries, numba's first load of a cached kernel (its target context: a one-line kernel of a module
#: in a temporary folder, compiled by an unmeasured first run), the results' and figures' libraries,
#: flexrv's CLI (the design model and the command modules)
_KERNEL = "from numba import njit\n\n\n@njit(cache=True)\ndef one(x):\n    return x + 1.0\n"
_LIBS = "import numpy, scipy, numba, exudyn"
_FIRST = _LIBS + "\nimport floor_kernel\nfloor_kernel.one(1.0)"
_OUT = _FIRST + "\nimport xarray, h5netcdf, matplotlib.figure, matplotlib.backends.backend_agg"
FLOORS = [
    ("python -c pass", "pass"),
    ("import numpy, scipy, numba, exudyn", _LIBS),
    ("+ numba's first cached kernel", _FIRST),
    ("+ xarray, h5netcdf, matplotlib (Agg)", _OUT),
    ("+ import flexrv.cli", _OUT + "\nimport flexrv.cli"),
]


def floors(checkout: str, repeat: int) -> None:
    """CPU of the :data:`FLOORS` programs (medians of ``repeat``)."""
    import statistics as st

    print(f"floor [{checkout}] (CPU of a child process, median of {repeat}):")
    with tempfile.TemporaryDirectory(prefix="flexrv-floor-") as folder:
        Path(folder, "floor_kernel.py").write_text(_KERNEL)
        env = dict(_env(checkout), PYTHONPATH=os.pathsep.join([folder, checkout]), NUMBA_CACHE_DIR=folder)
        subprocess.run([sys.executable, "-c", _FIRST], env=env, cwd=folder, check=True)  # compiles the kernel
        for label, code in FLOORS:
            cpu = []
            for _ in range(repeat):
                c0 = children_cpu_s()
                subprocess.run([sys.executable, "-c", code], env=env, cwd=folder, check=True)
                cpu.append(children_cpu_s() - c0)
            print(f"   {label:40s} {st.median(cpu):6.2f} s CPU")


def plain(checkout: str, args: list[str], out: str) -> dict:
    """Wall and CPU of ``python -m flexrv ARGS --out OUT`` (and its solve wall from --json)."""
    c0, t0 = children_cpu_s(), time.perf_counter()
    p = subprocess.run(
        [sys.executable, "-m", "flexrv", *args, "--out", out, "--overwrite"],
        env=_env(checkout),
        cwd=checkout,
        capture_output=True,
        text=True,
    )
    wall, cpu = time.perf_counter() - t0, children_cpu_s() - c0
    if p.returncode != 0:
        raise SystemExit(f"{' '.join(args)} in {checkout} exited {p.returncode}:\n{p.stderr[-3000:]}")
    data = json.loads(p.stdout)
    return {"wall": wall, "cpu": cpu, "solve_wall": data.get("wall_time_s")}


def instrumented(checkout: str, name: str, args: list[str], out: str, runs: int = 1) -> dict:
    """The phase split of one run (the driver above); with ``runs`` > 1 the command runs that many
    times in one process and the split is the last run's."""
    with tempfile.NamedTemporaryFile(suffix=".json", delete=False) as f:
        path = f.name
    env = dict(
        _env(checkout),
        FLEXRV_BENCH_OUT=path,
        FLEXRV_BENCH_PHASES=json.dumps(PHASES[name]),
        FLEXRV_BENCH_RUNS=str(runs),
    )
    p = subprocess.run(
        [sys.executable, "-c", DRIVER, *args, "--out", out, "--overwrite"],
        env=env,
        cwd=checkout,
        capture_output=True,
        text=True,
    )
    if p.returncode != 0:
        raise SystemExit(f"instrumented {' '.join(args)} in {checkout} exited {p.returncode}:\n{p.stderr[-3000:]}")
    data = json.loads(Path(path).read_text())
    os.unlink(path)
    return data


def report(name: str, checkout: str, runs: list[dict], splits: list[dict]) -> None:
    """Print the medians of the plain runs and the split of the instrumented ones."""
    import statistics as st

    wall = st.median(r["wall"] for r in runs)
    cpu = st.median(r["cpu"] for r in runs)
    print(f"{name} [{checkout}]: whole process wall {wall:.2f} s, CPU {cpu:.2f} s (median of {len(runs)})")
    phases: dict[str, list[float]] = {}
    for s in splits:
        for label, (c, _) in s["phases"].items():
            phases.setdefault(label, []).append(c)
    total = st.median(s["cpu"] for s in splits)
    inside = 0.0
    seen = []
    for label, _ in PHASES[name]:
        if label in seen or label not in phases:
            continue
        seen.append(label)
        c = st.median(phases[label])
        inside += c
        print(f"   {label:34s} {c:6.2f} s CPU")
    print(f"   {'imports, interpreter, CLI glue':34s} {total - inside:6.2f} s CPU (instrumented total {total:.2f})")
    if name == "te":
        loaded = st.median(s["curves_cpu"][0] for s in splits)
        no_load = st.median(s["curves_cpu"][1] for s in splits) if all(len(s["curves_cpu"]) > 1 for s in splits) else 0
        print(
            f"   loaded curve {loaded:.2f} s CPU, no-load curve {no_load:.2f} s CPU; whole process / loaded curve "
            f"= {total / loaded:.2f} in the instrumented process, {cpu / loaded:.2f} with the plain process's CPU "
            "(goal <= 1.3)"
        )
    else:
        solve = st.median(r["solve_wall"] for r in runs)
        solve_cpu = st.median(phases["solve"])
        print(
            f"   solve wall {solve:.2f} s (its CPU {solve_cpu:.2f} s); whole process / solve = "
            f"{wall / solve:.2f} wall (goal <= 2), {cpu / solve_cpu:.2f} CPU"
        )


def in_process(name: str, checkouts: list[str], repeat: int, runs: int, tmp: str) -> None:
    """The command run ``runs`` times in one process per checkout (a warm process: imports, bodies and
    kernels loaded by the first run), ``repeat`` processes per checkout, alternating; prints every run's
    CPU and wall (medians over the processes) and the last run's phase split."""
    import statistics as st

    data = {c: [] for c in checkouts}
    for i in range(repeat):
        for k, c in enumerate(checkouts):
            data[c].append(instrumented(c, name, COMMANDS[name], os.path.join(tmp, f"warm-{name}-{i}-{k}"), runs))
    labels = list(dict.fromkeys(label for label, _ in PHASES[name]))
    for c in checkouts:
        per_run = [
            (st.median(d["runs"][r][0] for d in data[c]), st.median(d["runs"][r][1] for d in data[c]))
            for r in range(runs)
        ]
        print(f"{name} in one process [{c}], {runs} runs (medians of {repeat} processes):")
        print("   runs' CPU  " + "  ".join(f"{cpu:6.2f}" for cpu, _ in per_run) + " s")
        print("   runs' wall " + "  ".join(f"{wall:6.2f}" for _, wall in per_run) + " s")
        inside = 0.0
        for label in labels:
            cs = [d["phases"][label][0] for d in data[c] if label in d["phases"]]
            if cs:
                inside += st.median(cs)
                print(f"   last run: {label:34s} {st.median(cs):6.3f} s CPU")
        print(f"   last run: {'outside the phases':34s} {per_run[-1][0] - inside:6.3f} s CPU")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", choices=sorted(COMMANDS), action="append", help="measure only this command")
    ap.add_argument("--checkout", action="append", help="flexrv checkout to run (default: this one); repeatable")
    ap.add_argument("--repeat", type=int, default=1, help="plain and instrumented runs per checkout (medians)")
    ap.add_argument("--no-floor", action="store_true", help="skip the floor programs")
    ap.add_argument(
        "--in-process", type=int, metavar="RUNS", default=0, help="instead: each command RUNS times in one process"
    )
    a = ap.parse_args()
    checkouts = [str(Path(c).resolve()) for c in (a.checkout or [ROOT])]
    with tempfile.TemporaryDirectory(prefix="flexrv-startup-") as tmp:
        if a.in_process:
            for name in a.only or list(COMMANDS):
                in_process(name, checkouts, a.repeat, a.in_process, tmp)
            return
        for name in a.only or list(COMMANDS):
            for c in checkouts:  # unmeasured: compiles the bytecode of the modules the command imports
                plain(c, COMMANDS[name], os.path.join(tmp, f"warm-{name}"))
            runs = {c: [] for c in checkouts}
            splits = {c: [] for c in checkouts}
            for i in range(a.repeat):
                for c in checkouts:  # alternating: a slow spell of the machine hits every checkout
                    out = os.path.join(tmp, f"{name}-{len(runs[c])}-{checkouts.index(c)}")
                    runs[c].append(plain(c, COMMANDS[name], out))
                    splits[c].append(instrumented(c, name, COMMANDS[name], out + "-i"))
            for c in checkouts:
                report(name, c, runs[c], splits[c])
        if not a.no_floor:
            floors(checkouts[-1], max(a.repeat, 3))


if __name__ == "__main__":
    main()
