"""Benchmark of the ball-bearing model (``--model balls``: ball-resolved main bearing,
rigid rings): CPU seconds per simulated second (solve + outputs), on Exudyn's integrator the
cost per call of the fused compiled element (the bearing rows and the other contacts), Newton
iterations per step, and the TE statistics (so speed never buys a different answer). The paired
comparison of the integrators: ``bench_integrator.py --model balls``.

    python benchmarks/bench_balls.py [--presets rv221 rv40e] [--t-end 0.1] [--newton '{"...": ...}']
                                     [--options '{"ball_inertia": true}'] [--integrator compiled|exudyn]
    python benchmarks/bench_balls.py --row-modes [--presets rv40e]

``--row-modes``: the rows' own cost (one row, quasi-static balls, at a solved state of a short
compiled run, 5 ms ramps) per evaluation mode of ``row_eval`` (force, the ball solve's blocks, the
condensed Jacobian, the front phases alone), and the Jacobian call of every row at the run's recorded
states, paired in one process: the ball solve then a separate CONDENSED_BALLS evaluation at the
solution, against the solve that returns the condensed Jacobian of its last evaluation (the
library's order), with the largest difference of the two Jacobians.

The preset's default ramps are kept; a short warm-up run (0.002 s) loads or
compiles the numba kernels first (a cold compile inside the timed run cost
~50 s, which bench_flexible_model.py counted as solve time). CPU time
(time.process_time) is robust on a shared machine; wall time is not printed.

Goal: <= 5 CPU s per simulated second, dt 1e-4 s, one BLAS thread. Measured figures with date
and machine: docs/benchmarks.md; their history: CHANGELOG.md.
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def _timed(obj, attr, acc, key):
    """Accumulate CPU time and calls of obj.attr in acc[key]."""
    fn = getattr(obj, attr)

    def timed(*args, **kw):
        c0 = time.process_time()
        r = fn(*args, **kw)
        acc[key][0] += time.process_time() - c0
        acc[key][1] += 1
        return r

    setattr(obj, attr, timed)


def bench(name: str, t_end: float, newton: dict | None, options: dict | None = None, integrator=None) -> dict:
    from flexrv.simulation import Simulation

    sim = Simulation(name, model="balls", model_options=options)
    model = sim.build()
    # numba load/compile, not timed (5-step segments: the segment starts take the outputs' history pass)
    sim.run(t_end=0.002, newton_options=newton, segment_steps=5, integrator=integrator)
    acc = {"fused": [0.0, 0], "fused_jac": [0.0, 0]}  # (Exudyn's integrator: its user functions)
    if model.fused is not None:
        _timed(model.fused, "residual", acc, "fused")
        _timed(model.fused, "jacobian", acc, "fused_jac")
    c0 = time.process_time()
    res = sim.run(t_end=t_end, newton_options=newton, integrator=integrator)
    cpu = time.process_time() - c0
    tm = sim.timing
    te = res["te"]
    sel = te.values[te["time"].values >= 0.5 * t_end]
    steps = max(tm["steps"], 1)
    return {
        "preset": name,
        "n": model.n,
        "simulated_s": tm["simulated_s"],
        "cpu_per_s": cpu / tm["simulated_s"],
        "solve_cpu_per_s": tm["solve_cpu_s"] / tm["simulated_s"],
        "outputs_cpu_s": cpu - tm["solve_cpu_s"],
        "newton_per_step": tm["newton_iterations"] / steps,
        "jacobians": tm["jacobians"],
        "steps": steps,
        **{f"{k}_us": v[0] / max(v[1], 1) * 1e6 for k, v in acc.items()},
        **{f"{k}_calls": v[1] for k, v in acc.items()},
        "te_mean": float(np.mean(sel)),
        "te_pp": float(np.ptp(sel)),
        "max_ball_load": float(np.max(res["ball_load_inner"].values[-1])) if "ball_load_inner" in res else np.nan,
        "status": res.attrs.get("status"),
    }


def row_modes(name: str) -> None:
    """Print the ``--row-modes`` costs (module docstring)."""
    from _shared import quick_ramps
    from numba import njit

    import flexrv.simulation as S
    from flexrv.model import bearing_kernel as bk
    from flexrv.simulation import Simulation

    sim = Simulation(quick_ramps(name), model="balls")
    model = sim.build()
    kept = {}
    orig = S._Records.__init__

    def keep(self, *a, **k):
        orig(self, *a, **k)
        kept["records"] = self

    S._Records.__init__ = keep
    try:
        sim.run(t_end=0.012, integrator="compiled", checkpoint_s=None)
    finally:
        S._Records.__init__ = orig
    rec = kept["records"]
    qs, vs = rec.qs[: rec.k].copy(), rec.vs[: rec.k].copy()
    ((_, pack),) = [(g, p) for (g, _), p in zip(model.fused.slots, model.fused.packs) if g.kind == "bearing_rows"]
    row_eval, solve_balls, front, as_mode = bk.row_eval, bk.quasi_static_balls, bk._row_front, bk._mode
    cb, bb = bk.CONDENSED_BALLS, bk.BALL_BLOCKS

    @njit
    def modes(q, v, p, mode, reps, rec, f, a, b):
        for _ in range(reps):
            if mode < 0:
                front(q, v, p, as_mode(bb))
            else:
                row_eval(q, v, p, as_mode(mode), rec, f, a, b)

    @njit
    def jacobian_calls(qs, vs, separate, pack, out):
        for i in range(1, qs.shape[0]):
            for part in pack.parts:
                idx, qe, ve, f, _, _, rec, kbb, kx, cx, p = part
                for e in range(idx.shape[0]):
                    qe[e] = qs[i, idx[e]]
                    ve[e] = vs[i, idx[e]]
                if separate:
                    solve_balls(qe, ve, p, as_mode(False), rec, f, kbb, kx, cx)
                    row_eval(qe, ve, p, as_mode(cb), np.empty((0, rec.shape[1])), f, kx, cx)
                else:
                    solve_balls(qe, ve, p, as_mode(True), rec, f, kbb, kx, cx)
                out[i] += np.abs(kx).sum() + 1e3 * np.abs(cx).sum()

    _, qe, ve, f, _, _, _, kbb, kx, cx, p = pack.parts[0]
    q, v, no_rec, empty = qe.copy(), ve.copy(), np.empty((0, bk.N_RECORD)), np.empty((0, 0))
    print(f"{name}: one row, Z = {p.ball_ref.shape[0]}, per evaluation at a solved state:")
    for label, mode, a, b in (
        ("force", 0, empty, empty),
        ("ball solve's blocks", bb, kbb, empty),
        ("condensed Jacobian", cb, kx, cx),
        ("front phases alone", -1, empty, empty),
    ):
        modes(q, v, p, mode, 1, no_rec, f, a, b)
        c0 = time.process_time()
        modes(q, v, p, mode, 3000, no_rec, f, a, b)
        print(f"  {label:22s} {(time.process_time() - c0) / 3000 * 1e6:7.2f} us")
    spent, sums = {True: [], False: []}, {}
    for separate in (True, False, True, False, True, False):
        for g in model.groups:
            g.reset()
        out = np.zeros(qs.shape[0])
        c0 = time.process_time()
        jacobian_calls(qs, vs, separate, pack, out)
        spent[separate].append(time.process_time() - c0)
        sums[separate] = out
    per = {k: min(t[1:]) / (qs.shape[0] - 1) * 1e6 for k, t in spent.items()}
    diff = np.max(np.abs(sums[True] - sums[False])) / np.max(np.abs(sums[True]))
    print(
        f"  Jacobian call of all rows at {qs.shape[0] - 1} recorded states: solve + separate evaluation "
        f"{per[True]:.1f} us, the solve's own {per[False]:.1f} us ({per[True] / per[False]:.2f}x); "
        f"Jacobians' sums equal within {diff:.1e} relative"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--presets", nargs="*", default=["rv221", "rv40e"])
    ap.add_argument("--t-end", type=float, default=0.1)
    ap.add_argument("--newton", default=None, help="newton_options as JSON")
    ap.add_argument("--options", default=None, help="model options as JSON, e.g. '{\"ball_inertia\": true}'")
    ap.add_argument("--integrator", default=None, choices=("compiled", "exudyn"), help="default: the model's")
    ap.add_argument("--row-modes", action="store_true", help="the rows' own cost per evaluation mode (docstring)")
    a = ap.parse_args()
    if a.row_modes:
        for name in a.presets:
            row_modes(name)
        return
    import flexrv

    newton = json.loads(a.newton) if a.newton else None
    options = json.loads(a.options) if a.options else None
    print(f"flexrv from {os.path.dirname(flexrv.__file__)}; newton_options {newton}; model options {options}")
    for name in a.presets:
        r = bench(name, a.t_end, newton, options, a.integrator)
        print(
            f"{r['preset']} balls: n = {r['n']}, {r['steps']} steps for {r['simulated_s']:.3g} s, "
            f"Newton/step {r['newton_per_step']:.2f}, Jacobians {r['jacobians']}"
        )
        print(
            f"  CPU per simulated s: {r['cpu_per_s']:.2f} (solve {r['solve_cpu_per_s']:.2f}; outputs "
            f"{r['outputs_cpu_s']:.3f} s)"
        )
        print(
            f"  fused residual {r['fused_us']:.1f} us x {r['fused_calls']}, fused Jacobian "
            f"{r['fused_jac_us']:.1f} us x {r['fused_jac_calls']}"
        )
        print(
            f"  TE (t >= {0.5 * a.t_end:g} s): mean {r['te_mean']:.4f} arcsec, p-p {r['te_pp']:.4f} arcsec; "
            f"max inner ball load {r['max_ball_load']:.3f} N; {r['status']}",
            flush=True,
        )


if __name__ == "__main__":
    main()
