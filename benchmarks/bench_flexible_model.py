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
        [--ring-options '{"condense": false}'] [--split] [--rows] [--integrator compiled|exudyn]

``--split``: where a step's CPU goes on Exudyn's integrator (the preset with 5 ms ramps, the
flexible-rings model): the fused element's force and Jacobian calls (the bearing rows and the other
contacts, compiled, and their Python glue) and the rest (Exudyn: assembly, sparse LU, Newton,
hooks); the compiled integrator's split: ``bench_integrator.py --model flexible --split``; then
one factorisation of a matrix of the model's structure (the balls' dense blocks, the other
coordinates) by block elimination (:mod:`flexrv.model.numerics.block_lu`), by the dense
compiled LU and by LAPACK (scipy), CPU per factorisation.

``--rows``: the condensed rows' own cost on the compiled integrator (the preset with 5 ms ramps,
the flexible-rings model): a run's local solves (chord iterations per solve, solves per step), then
per recorded state of that run (each state once, in order, the warm starts carried as in the run; best
of 3 passes, one BLAS thread as in a simulation) the cost of both rows' calls by phase: kinematics and
pass 1, the compliance factors of every ring at the balls' azimuths, the front (pass 1 with the
contacts and the condensed rings' local solves), the force call and the call with the Jacobian.

``--paired-newton JSON``: the flexible-rings model (5 ms ramps) with the simulation's Newton
settings and with these ``newton_options`` on top, alternating, twice each in one process:
solve CPU per step and per simulated s, Newton iterations, Jacobians and TE of each run.

Goal: the flexible-rings model (condensed rings, main bearing flexible) <= 15 CPU s per
simulated second on rv221 and on rv40e (dt 1e-4, one BLAS thread). Measured figures with date and
machine: docs/benchmarks.md; their history: CHANGELOG.md.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time

import numpy as np

#: flexrv.model.bearing_kernel once :func:`rows` imported it (a global of the compiled phases)
bk = None


def run(
    preset: str, model: str, t_end: float, options: dict, window: float | None = None, integrator: str | None = None
) -> dict:
    from flexrv.simulation import Simulation

    # warm-up: numba cache loads and one-time imports of the outputs path (xarray's first DataArray
    # imports its duck-array modules, ~0.36 s, which a 0.1 s run would count as 3.6 s per simulated s)
    Simulation(preset, model=model, model_options=options).run(t_end=2e-3, integrator=integrator)
    sim = Simulation(preset, model=model, model_options=options)
    t0 = time.perf_counter()
    m = sim.build()
    build = time.perf_counter() - t0
    c0 = time.process_time()
    res = sim.run(t_end=t_end, integrator=integrator)
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


def _timed_method(owner, attr: str, acc: list) -> None:
    """Accumulate the CPU time and the calls of ``owner.attr`` (a class: every instance) in ``acc``."""
    fn = getattr(owner, attr)

    if isinstance(owner, type):

        def timed(self, *args, **kw):
            c0 = time.process_time()
            out = fn(self, *args, **kw)
            acc[0] += time.process_time() - c0
            acc[1] += 1
            return out

    else:

        def timed(*args, **kw):
            c0 = time.process_time()
            out = fn(*args, **kw)
            acc[0] += time.process_time() - c0
            acc[1] += 1
            return out

    setattr(owner, attr, timed)


def split(preset: str, t_end: float, window: float) -> None:
    """Print the CPU per step of the flexible-rings model by part (module docstring, ``--split``)."""
    from _shared import quick_ramps

    from flexrv.simulation import Simulation

    sim = Simulation(quick_ramps(preset), model="flexible", model_options={"parts": ["main_bearing"]})
    model = sim.build()
    sim.run(t_end=2e-3, segment_steps=5, integrator="exudyn")  # numba loads, one-time imports
    acc = {k: [0.0, 0] for k in ("fused force", "fused Jacobian")}
    _timed_method(model.fused, "residual", acc["fused force"])
    _timed_method(model.fused, "jacobian", acc["fused Jacobian"])
    res = sim.run(t_end=t_end, integrator="exudyn")
    tm = sim.timing
    steps = max(tm["steps"], 1)
    solve = tm["solve_cpu_s"]
    te = res["te"].sel(time=slice(t_end - window, None)).values
    print(
        f"{preset} flexible rings, 5 ms ramps, {t_end:g} s: {steps} steps, "
        f"Newton {tm['newton_iterations'] / steps:.2f} and Jacobians {tm['jacobians'] / steps:.3f} per step; "
        f"solve CPU {1e3 * solve / steps:.3f} ms per step"
    )
    for key, (cpu, calls) in acc.items():
        print(
            f"  {key:15s} {calls / steps:6.2f} calls per step, {1e6 * cpu / max(calls, 1):7.1f} us each, "
            f"{1e3 * cpu / steps:6.3f} ms per step ({cpu / solve:5.1%})"
        )
    rest = solve - sum(v[0] for v in acc.values())
    print(f"  {'rest (Exudyn)':15s} {1e3 * rest / steps:48.3f} ms per step ({rest / solve:5.1%})")
    print(f"  TE over the last {window:g} s: mean {te.mean():.4f}, p-p {np.ptp(te):.4f} arcsec")
    factorisations(model)


def factorisations(model, repeat: int = 30) -> None:
    """Print the CPU of one factorisation of an n x n matrix with the model's ball blocks
    (members ``main_bearing_balls*``: dense, uncoupled between rows) by block elimination, by
    the dense compiled LU and by LAPACK's getrf (scipy), and the block solve's error."""
    import scipy.linalg

    from flexrv.model.numerics import block_lu, linalg

    n = model.n
    spans = [(m.offset, m.n) for name, m in model.members.items() if name.startswith("main_bearing_balls")]
    blocks, xs = block_lu.block_structure(n, spans)
    rng = np.random.default_rng(0)
    s = rng.normal(size=(n, n)) + n * np.eye(n)
    for i, (a0, am) in enumerate(blocks):
        for j, (b0, bm) in enumerate(blocks):
            if i != j:
                s[a0 : a0 + am, b0 : b0 + bm] = 0.0
    nx, nb = len(xs), int(blocks[:, 1].sum())
    w, piv, ys = s.copy(), np.zeros(n, np.int64), np.zeros((nb, nx))
    dk = np.zeros(block_lu.work_sizes(blocks, xs)[1])
    schur, xpiv, lu, by = np.zeros((nx, nx)), np.zeros(nx, np.int64), np.zeros((n, n)), np.zeros((nx, nx))

    def cpu(fn) -> float:
        fn()
        c0 = time.process_time()
        for _ in range(repeat):
            fn()
        return 1e3 * (time.process_time() - c0) / repeat

    def blocked():
        block_lu.block_factor(w, blocks, xs, piv, ys, dk, schur, xpiv, by)

    t_block = cpu(blocked)
    t_dense = cpu(lambda: linalg.lu_factor(s, lu, piv))
    t_lapack = cpu(lambda: scipy.linalg.lu_factor(s))
    r, x = rng.normal(size=n), np.zeros(n)
    blocked()
    block_lu.block_solve(w, blocks, xs, piv, ys, dk, schur, xpiv, r, x, np.zeros(nx), np.zeros(nx))
    err = np.max(np.abs(x - np.linalg.solve(s, r))) / np.max(np.abs(x))
    print(
        f"  factorisation of {n} coordinates (blocks {[int(b) for b in blocks[:, 1]]}, {nx} others): block "
        f"elimination {t_block:.3f} ms, dense compiled LU {t_dense:.3f} ms, LAPACK getrf {t_lapack:.3f} ms "
        f"(block solve within {err:.1e} of numpy's)"
    )


def _row_phases(qs, vs, pack, mode, jac):
    """One pass of both rows over the recorded states (``--rows``), phase ``mode``: 0 the call
    (row_eval), 1 the front (pass 1, contacts, local solves), 2 kinematics and pass 1, 3 that and the
    condensed rings' compliance factors at the balls' azimuths; a checksum. Compiled by :func:`rows`
    (``bk``: flexrv.model.bearing_kernel, set there)."""
    tot = 0.0
    for i in range(1, qs.shape[0]):
        for part in pack.parts:
            idx, qe, ve, f, jq, jv, rec, _, _, _, p = part
            for e in range(idx.shape[0]):
                qe[e] = qs[i, idx[e]]
                ve[e] = vs[i, idx[e]]
            nz = p.ball_ref.shape[0]
            b0 = idx.shape[0] - 3 * nz
            for j in range(nz):
                for c in range(3):
                    qe[b0 + 3 * j + c] -= p.ball_ref[j, c]
            if mode == 0:
                bk.row_eval(qe, ve, p, bk._mode(jac), rec, f, jq, jv)
                tot += f[0]
            elif mode == 1:
                tot += bk._row_front(qe, ve, p, bk._mode(jac))[4].load_i[0]
            else:
                pre = bk._row_pass1(qe, ve, p, bk._mode(jac))[2]
                tot += pre.e0_i[0, 0]
                if mode == 3:
                    for psi, comp, zs in ((pre.psi_i, p.comp_i, p.zsign[0]), (pre.psi_o, p.comp_o, p.zsign[1])):
                        if comp.shape[0] > 0:
                            wl = np.empty((nz, 3, comp.shape[2]))
                            bk._local_factors(psi, comp, zs, wl)
                            tot += wl[0, 0, 0]
    return tot


def rows(preset: str, t_end: float) -> None:
    """Print the condensed rows' cost by phase (module docstring, ``--rows``)."""
    global bk
    from _shared import quick_ramps
    from numba import njit

    import flexrv.simulation as S
    from flexrv.model import bearing_kernel
    from flexrv.model.kernels import single_thread_blas
    from flexrv.simulation import Simulation

    bk = bearing_kernel  # (a global of the compiled _row_phases)
    sim = Simulation(quick_ramps(preset), model="flexible", model_options={"parts": ["main_bearing"]})
    model = sim.build()
    sim.run(t_end=2e-3, segment_steps=5, integrator="compiled")  # numba loads, one-time imports
    ((_, pack),) = [(g, p) for (g, _), p in zip(model.fused.slots, model.fused.packs) if g.kind == "bearing_rows"]
    kept, orig = {}, S._Records.__init__

    def keep(self, *a, **k):
        orig(self, *a, **k)
        kept["records"] = self

    s0 = [part[10].state.copy() for part in pack.parts]
    S._Records.__init__ = keep
    try:
        sim.run(t_end=t_end, integrator="compiled", checkpoint_s=None)
    finally:
        S._Records.__init__ = orig
    steps = max(sim.timing["steps"], 1)
    p = pack.parts[0][10]
    print(
        f"{preset} flexible rings, 5 ms ramps, {t_end:g} s compiled: {steps} steps, Z = {p.ball_ref.shape[0]}, "
        f"ring modes {p.comp_i.shape[2]} / {p.comp_o.shape[2]}"
    )
    for k, (part, a) in enumerate(zip(pack.parts, s0)):
        d = part[10].state - a
        print(
            f"  row {k}: {d[3] / steps:.2f} local solves per step, {d[2] / max(d[3], 1):.2f} chord iterations "
            f"per solve, {d[0]} not converged"
        )
    rec = kept["records"]
    qs, vs = rec.qs[: rec.k].copy(), rec.vs[: rec.k].copy()
    phases = njit(_row_phases)
    cost = {}
    for label, mode, jac in (
        ("kinematics, pass 1", 2, False),
        ("+ compliance factors", 3, False),
        ("front (+ local solves)", 1, False),
        ("force call", 0, False),
        ("call with the Jacobian", 0, True),
    ):
        best = np.inf
        with single_thread_blas():  # as in a simulation: the Jacobian's LAPACK inverse and BLAS products
            phases(qs, vs, pack, mode, jac)  # compile, warm starts
            for _ in range(3):
                for g in model.groups:
                    g.reset()
                c0 = time.process_time()
                phases(qs, vs, pack, mode, jac)
                best = min(best, time.process_time() - c0)
        cost[label] = 1e6 * best / (qs.shape[0] - 1)
        print(f"  {label:24s} {cost[label]:8.1f} us per state (both rows)")
    c = list(cost.values())
    print(
        f"  by difference: compliance factors {c[1] - c[0]:.1f}, contacts and local solves {c[2] - c[1]:.1f}, "
        f"pass 2 {c[3] - c[2]:.1f}, the Jacobian {c[4] - c[3]:.1f} us"
    )


def paired_newton(
    preset: str, t_end: float, window: float, options: dict, repeat: int = 2, integrator: str | None = None
) -> None:
    """Print the flexible-rings model's solve with the default Newton settings and with
    ``options`` on top, alternating ``repeat`` times (module docstring, ``--paired-newton``;
    ``integrator``: the model's default if None)."""
    from _shared import quick_ramps

    from flexrv.simulation import Simulation

    print(f"{preset} flexible rings, 5 ms ramps, {t_end:g} s; TE over the last {window:g} s [arcsec]")
    for _ in range(repeat):
        for opts in (None, options):
            sim = Simulation(quick_ramps(preset), model="flexible", model_options={"parts": ["main_bearing"]})
            sim.build()
            sim.run(t_end=2e-3, segment_steps=5, newton_options=opts, integrator=integrator)  # numba loads
            res = sim.run(t_end=t_end, newton_options=opts, integrator=integrator)
            tm = sim.timing
            steps = max(tm["steps"], 1)
            te = res["te"].sel(time=slice(t_end - window, None)).values
            print(
                f"  {json.dumps(opts or {}):44s} {steps:5d} steps, Newton {tm['newton_iterations'] / steps:.2f}, "
                f"Jacobians {tm['jacobians'] / steps:.3f} per step; solve {1e3 * tm['solve_cpu_s'] / steps:.3f} ms "
                f"per step, {tm['solve_cpu_s'] / tm['simulated_s']:.1f} s per simulated s; TE {te.mean():.5f}, "
                f"p-p {np.ptp(te):.5f}",
                flush=True,
            )


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
    parser.add_argument("--split", action="store_true", help="CPU per step by part (flexible rings, 5 ms ramps)")
    parser.add_argument("--rows", action="store_true", help="the condensed rows' cost by phase (compiled)")
    parser.add_argument("--paired-newton", default=None, help="newton_options (JSON) against the defaults, paired")
    parser.add_argument("--integrator", default=None, choices=("compiled", "exudyn"), help="default: the model's")
    args = parser.parse_args()
    if args.paired_newton:
        paired_newton(
            args.preset,
            args.t_end,
            0.5 * args.t_end if args.window is None else args.window,
            json.loads(args.paired_newton),
            integrator=args.integrator,
        )
        return
    if args.rows:
        rows(args.preset, args.t_end)
        return
    if args.split:
        split(args.preset, args.t_end, 0.5 * args.t_end if args.window is None else args.window)
        return
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
        r = run(args.preset, model, args.t_end, opts, args.window, args.integrator)
        print(
            f"{r['model']:10s} {r['coordinates']:5d} {r['build_s']:8.2f} {r['solve_s']:8.2f} "
            f"{r['wall_per_sim_s']:8.1f} {r['cpu_per_sim_s']:8.1f} {r['ms_per_step']:8.2f} "
            f"{r['newton_per_step']:9.2f} {r['jacobians']:9d} {r['te_mean']:10.4f} {r['te_pp']:8.4f} "
            f"{r['max_ball_load']:10.2f} {r['ring_um']:8.4f}  {r['status']}",
            flush=True,
        )


if __name__ == "__main__":
    main()
