"""Run a reducer model in time and return named results.

>>> from flexrv.simulation import Simulation             # doctest: +SKIP
>>> res = Simulation("rv40e").run(t_end=0.3, dt=1e-4)     # doctest: +SKIP
>>> res["TE [arcsec]"]                                    # doctest: +SKIP

Integration: Exudyn's implicit generalized-alpha (spectral radius 0.5 to damp
the stiff contact modes numerically) with modified Newton and analytic group
Jacobians; adaptive step reduction on Newton failure. States are recorded by a
pre-step hook every ``output_every`` steps, so a run that fails (Newton failure,
NaN, penetration beyond the physical limit) or is interrupted with Ctrl-C still
returns the results up to that time: :class:`flexrv.errors.SimulationError`
carries them as ``exc.results`` (and saves them if ``save_to`` was given); an
interrupted run returns results with ``status = "interrupted"``.

Newton tolerances (relative 1e-3, absolute 0.1 N residual per coordinate):
tightening them to 1e-4/1e-2 changed the steady TE of rv40e by < 0.001 arcsec
and doubled the Newton iterations. Cost (benchmarks/bench_rigid.py, 2 shared
cores): ~3.7-4.9 Newton iterations per step at dt = 1e-4 s, ~2.2-2.6 ms per step,
~90 % of it in the Python force kernels (per-call overhead of small array
operations, not arithmetic): real-time factor ~21-25. The closest-point
iteration of the pin gap and the impact law run numba-compiled when numba is
installed (same kernels and bit-identical results, plain numpy otherwise).
"""

from __future__ import annotations

import math
import signal
import time as _time
from pathlib import Path
from typing import Callable

import numpy as np

from flexrv.design import load
from flexrv.errors import InputError, SimulationError
from flexrv.post.results import Results  # noqa: F401  (re-exported: flexrv.Results)
from flexrv.units import ARCMIN_PER_RAD

#: systems with more coordinates than this use Exudyn's sparse linear solver
SPARSE_ABOVE = 100

#: default step [s]: ~25 steps per pin-mesh period of both presets at rated speed
DEFAULT_DT = 1e-4


class Simulation:
    """A reducer design + a model name, ready to run.

    Parameters
    ----------
    preset_or_config : preset name, TOML path or :class:`flexrv.design.Reducer`.
    model : model name in :data:`flexrv.model.factory.MODELS` (``"rigid"``).
    drive : ``"ramp"`` (seed input-speed step) or ``"locked"`` (input held).
    torque : optional load-torque program T(t) [N m] replacing the seed step.
    model_options : keyword options of the model builder, e.g. for ``"flexible"``
        ``{"parts": ("main_bearing", "crankshaft"), "ring_options": {"harmonics": 24}}``
        (:func:`flexrv.model.factory.build_flexible`).
    """

    def __init__(self, preset_or_config, model: str = "rigid", drive: str = "ramp", torque: Callable | None = None,
                 model_options: dict | None = None):
        self.reducer = load(preset_or_config)
        self.model_name = model
        self.model_options = dict(model_options or {})
        self.drive = drive
        self.torque = torque
        self.model = None
        self.timing: dict = {}

    def build(self):
        from flexrv.model.factory import build_model

        t0 = _time.perf_counter()
        self.model = build_model(self.reducer, self.model_name, drive=self.drive, torque=self.torque,
                                 **self.model_options)
        self.timing["build_s"] = _time.perf_counter() - t0
        return self.model

    def run(self, t_end: float | None = None, dt: float = DEFAULT_DT, progress: bool | Callable = False,
            output_every: int = 1, save_to: str | Path | None = None, spectral_radius: float = 0.5,
            newton_tolerance: tuple[float, float] = (1e-3, 1e-1), newton_options: dict | None = None):
        """Integrate to ``t_end`` [s] with step ``dt`` [s]; return :class:`flexrv.post.Results`.

        ``progress``: True for a rich progress bar, or a callable ``f(t, t_end)``.
        Default ``t_end``: load ramp end + 0.2 s (steady window after the ramps).
        """
        import exudyn as exu

        op = self.reducer.operating
        if t_end is None:
            t_end = max(op.load_ramp_end_s, op.speed_ramp_time_s) + 0.2
        if not (math.isfinite(t_end) and t_end > 0):
            raise InputError(f"t_end = {t_end!r} s is not allowed: must be > 0")
        if not (math.isfinite(dt) and 0 < dt <= t_end):
            raise InputError(f"dt = {dt!r} s is not allowed: must lie in (0, t_end = {t_end:g}]")
        if dt > 5e-4:
            raise InputError(f"dt = {dt:g} s is not allowed: must be <= 5e-4 s to resolve the pin-mesh period")
        model = self.model if self.model is not None else self.build()
        from flexrv.model.kernel_cache import announce_compile

        announce_compile()  # one line on stderr if the numba kernels compile now (first run)
        mbs = model.mbs
        n_steps = int(round(t_end / dt))
        n_out = n_steps // output_every + 2
        ts = np.empty(n_out)
        qs = np.empty((n_out, model.n))
        vs = np.empty((n_out, model.n))
        state = {"k": 0, "step": 0, "fail": None, "stop": False}
        report = _progress_callback(progress, t_end)
        sd = mbs.systemData

        start_of_step = exu.ConfigurationType.StartOfStep

        def prestep(mbs_, t_target):
            # Exudyn calls this with the step's END time; the state is the start-of-step state
            t = sd.GetTime(start_of_step)
            q = np.asarray(sd.GetODE2Coordinates())
            k = state["k"]
            while k > 0 and ts[k - 1] >= t - 1e-12 * dt:  # a step was repeated (adaptive step reduction)
                k -= 1
            state["k"] = k
            if (k == 0 or t >= ts[k - 1] + output_every * dt * (1 - 1e-9)) and k < n_out:
                ts[k] = t
                qs[k] = q
                vs[k] = sd.GetODE2Coordinates_t()
                state["k"] = k + 1
            state["step"] += 1
            if not np.all(np.isfinite(q)):
                state["fail"] = (t, "the state became NaN/inf")
                return False
            for g in model.groups:
                g.new_step()
                msg = g.check()
                if msg:
                    state["fail"] = (t, msg)
                    return False
            if state["stop"]:
                return False
            if report is not None and state["step"] % 200 == 0:
                report(t)
            return True

        mbs.SetPreStepUserFunction(prestep)
        ss = exu.SimulationSettings()
        ti = ss.timeIntegration
        ti.numberOfSteps = n_steps
        ti.endTime = t_end
        ti.verboseMode = 0
        ti.newton.useModifiedNewton = True
        ti.newton.relativeTolerance, ti.newton.absoluteTolerance = newton_tolerance
        ti.generalizedAlpha.spectralRadius = spectral_radius
        for key, value in (newton_options or {}).items():
            setattr(ti.newton, key, value)
        # massless (quasi-static) coordinates make M singular: start from rest with
        # zero accelerations instead (every run starts at rest in equilibrium)
        massless = any(not np.any(np.diag(m.mass_matrix)) for m in model.members.values())
        ti.generalizedAlpha.computeInitialAccelerations = not massless
        ti.adaptiveStep = True
        ti.minimumStepSize = dt * 1e-3
        ss.solution.file.write = False
        # dense LU for the small rigid models; sparse for the ball/ring models, whose
        # dense path costs 2-4x more in Exudyn (rv40e flexible: 10.2 -> 4.1 s per 10 ms)
        ss.linearSolver.solverType = (exu.LinearSolverType.EXUdense if model.n <= SPARSE_ABOVE
                                      else exu.LinearSolverType.EigenSparse)

        def on_sigint(signum, frame):
            state["stop"] = True

        old = None
        try:
            old = signal.signal(signal.SIGINT, on_sigint)
        except ValueError:  # not in the main thread
            old = None
        for g in model.groups:
            g.stats[0] = g.stats[1] = 0
            g.reset()
        solver = exu.MainSolverImplicitSecondOrder()
        t0 = _time.perf_counter()
        error = None
        try:
            ok = solver.SolveSystem(mbs, ss)
        except Exception as exc:  # exudyn raises on Newton failure / user-function errors
            ok, error = False, exc
        finally:
            if old is not None:
                signal.signal(signal.SIGINT, old)
        wall = _time.perf_counter() - t0
        if report is not None:
            report(None)
        k = state["k"]
        # final state
        t_fin = float(mbs.systemData.GetTime())
        if k < n_out and state["fail"] is None and not state["stop"] and ok and (k == 0 or t_fin > ts[k - 1]):
            ts[k] = t_fin
            qs[k] = mbs.systemData.GetODE2Coordinates()
            vs[k] = mbs.systemData.GetODE2Coordinates_t()
            k += 1
        self.timing.update(solve_s=wall, steps=state["step"], simulated_s=float(ts[k - 1]) if k else 0.0,
                           newton_iterations=int(solver.it.newtonStepsCount),
                           jacobians=int(solver.it.newtonJacobiCount),
                           force_calls={g.name: g.stats[0] for g in model.groups},
                           jacobian_calls={g.name: g.stats[1] for g in model.groups})
        status = "completed"
        if state["fail"] is not None or (not ok and not state["stop"]):
            status = "failed"
        elif state["stop"]:
            status = "interrupted"
        from flexrv.post.results import results_from_states

        res = results_from_states(model, ts[:k], qs[:k], vs[:k], dt=dt, status=status, timing=self.timing)
        if status == "failed":
            t_fail, cause = state["fail"] if state["fail"] is not None else (t_fin, f"Newton iteration failed ({error})")
            res.attrs["failure"] = f"t = {t_fail:.6g} s: {cause}"
            path = None
            if save_to is not None and k > 1:
                path = res.save(save_to)
            msg = (f"simulation failed at t = {t_fail:.6g} s: {cause}. Suggestion: reduce the step (dt = {dt:g} s -> "
                   f"{dt / 2:g} s) or increase contact damping (contact.pin_max_damping_Ns_per_m)"
                   + (f"; partial results saved to {path}" if path else "; partial results in exc.results"))
            err = SimulationError(msg)
            err.results = res
            raise err
        if status == "interrupted" and save_to is not None and k > 1:
            res.save(save_to)
        return res


def _progress_callback(progress, t_end):
    """Turn ``progress`` into a callable report(t) (t None = finished) or None."""
    if not progress:
        return None
    if callable(progress):
        def rep(t):
            if t is not None:
                progress(t, t_end)
        return rep
    from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

    bar = Progress(TextColumn("simulating"), BarColumn(), TextColumn("{task.completed:.3f}/{task.total:.3f} s"),
                   TimeRemainingColumn(), transient=True)
    task = bar.add_task("sim", total=t_end)
    bar.start()

    def rep(t):
        if t is None:
            bar.stop()
        else:
            bar.update(task, completed=t)

    return rep


def stiffness_test(preset_or_config, model: str = "rigid", quarter_time: float = 0.02, settle: float = 0.005,
                   dt: float = DEFAULT_DT, torque: float | None = None, progress: bool | Callable = False,
                   save_to: str | Path | None = None, model_options: dict | None = None):
    """Virtual torsional-stiffness test bench (seed 004): input locked, output
    torque ramped 0 -> +T -> -T -> 0 (T = rated torque unless given), each
    quarter of the loop over ``quarter_time`` [s] (quasi-static: far longer than
    the output's torsional period, ~1 ms for both presets).

    Returns (:class:`flexrv.post.stiffness.StiffnessTest`, Results); the Results'
    dataset carries the figures as scalar variables with units (rigidity, lost motion,
    hysteresis, ...) and the loop (``loop_torque``, ``loop_angle``). Written to
    ``save_to`` if given: ``results.nc`` (that dataset), ``stiffness.json``,
    ``config.toml``, the test's own ``summary.md`` and ``hysteresis.png`` (loop with the
    rigidity fit range, lost motion and hysteresis marked).
    """
    from flexrv.model.loads import piecewise_torque
    from flexrv.post.stiffness import (evaluate_stiffness_test, stiffness_dataset, stiffness_json,
                                       stiffness_summary_markdown)

    reducer = load(preset_or_config)
    t_r = reducer.operating.rated_torque_Nm if torque is None else float(torque)
    if not (math.isfinite(t_r) and t_r > 0):
        raise InputError(f"torque = {torque!r} N m is not allowed: must be > 0")
    if not (math.isfinite(quarter_time) and quarter_time > 20 * dt):
        raise InputError(f"quarter_time = {quarter_time!r} s is not allowed: must be > 20 dt = {20 * dt:g} s")
    times = np.array([0.0, settle, settle + quarter_time, settle + 3 * quarter_time, settle + 4 * quarter_time])
    program = piecewise_torque(times, [0.0, 0.0, t_r, -t_r, 0.0])
    sim = Simulation(reducer, model=model, drive="locked", torque=program, model_options=model_options)
    res = sim.run(t_end=float(times[-1]), dt=dt, progress=progress)
    tq = res["output_torque"].values
    angle = -res["theta_out"].values  # the load torque acts against +theta: positive torque winds the output negative
    figures = evaluate_stiffness_test(res.time, tq, angle, times[1:])
    res.ds = stiffness_dataset(figures, res.time, tq, angle * ARCMIN_PER_RAD, base=res.ds)
    if save_to is not None:
        import json

        from flexrv.cache import atomic_path, atomic_write_text
        from flexrv.design import to_toml
        from flexrv.viz.plots import plot_hysteresis

        d = Path(save_to)
        d.mkdir(parents=True, exist_ok=True)
        with atomic_path(d / "results.nc") as tmp:
            res.ds.to_netcdf(tmp, engine="h5netcdf")
        atomic_write_text(d / "config.toml", to_toml(reducer))
        atomic_write_text(d / "stiffness.json", json.dumps(
            {"preset": reducer.name, "model": model, "quarter_time_s": quarter_time, "dt_s": dt,
             "figures": stiffness_json(figures)}, indent=2))
        plot_hysteresis(angle * ARCMIN_PER_RAD, tq, d / "hysteresis.png", figures=figures,
                        title=f"{reducer.name} stiffness test ({model} model)")
        atomic_write_text(d / "summary.md", stiffness_summary_markdown(figures, reducer.name, model,
                                                                       quarter_time, dt))
    return figures, res
