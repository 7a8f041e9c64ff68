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
from flexrv.viz.plots import PlottedResults as Results  # re-exported: flexrv.Results (saves its PNGs)
from flexrv.units import ARCMIN_PER_RAD

#: systems with more coordinates than this use Exudyn's sparse linear solver
SPARSE_ABOVE = 100

#: default step [s]: ~25 steps per pin-mesh period of both presets at rated speed
DEFAULT_DT = 1e-4

#: largest number of time steps of one run (~1.5 h of wall time for the rigid model
#: at ~2.5 ms per step); more is refused before any work with a step-count estimate
MAX_STEPS = 2_000_000

#: largest memory of the recorded states (time, coordinates, velocities) [bytes];
#: the derived result arrays need a few times more
MAX_RECORD_BYTES = 2 * 1024**3

#: default wall-time interval between two checkpoints of a run saved to a directory [s]
CHECKPOINT_INTERVAL_S = 10.0

#: signal numbers that stop a run gracefully (partial results kept): Ctrl-C, kill
STOP_SIGNALS = ("SIGINT", "SIGTERM")


def check_step_count(t_end: float, dt: float, output_every: int = 1, n_coordinates: int | None = None,
                     t_start: float = 0.0) -> int:
    """Number of steps of a run; InputError (naming --dt/--t-end and the estimate)
    if it exceeds :data:`MAX_STEPS` or the recorded states would exceed
    :data:`MAX_RECORD_BYTES` (checked again with the real coordinate count after
    the model is built)."""
    n_steps = int(round((t_end - t_start) / dt))
    if n_steps > MAX_STEPS:
        raise InputError(f"t_end = {t_end:g} s with dt = {dt:g} s needs {n_steps:.3g} time steps: at most "
                         f"{MAX_STEPS:.3g} are allowed (~{n_steps * 2.5e-3 / 3600:.3g} h of wall time at ~2.5 ms "
                         f"per step); increase dt or reduce t_end")
    if n_coordinates is not None:
        n_out = n_steps // max(int(output_every), 1) + 2
        nbytes = 8.0 * n_out * (2 * n_coordinates + 1)
        if nbytes > MAX_RECORD_BYTES:
            raise InputError(f"t_end = {t_end:g} s with dt = {dt:g} s records {n_out:.3g} states of {n_coordinates} "
                             f"coordinates: ~{nbytes / 1024**3:.3g} GiB, at most {MAX_RECORD_BYTES / 1024**3:g} GiB "
                             "allowed; increase dt or output_every, or reduce t_end")
    return n_steps


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
            newton_tolerance: tuple[float, float] = (1e-3, 1e-1), newton_options: dict | None = None,
            checkpoint_s: float | None = CHECKPOINT_INTERVAL_S, initial_records: tuple | None = None,
            initial_accelerations=None):
        """Integrate to ``t_end`` [s] with step ``dt`` [s]; return :class:`flexrv.post.Results`.

        ``progress``: True for a rich progress bar, or a callable ``f(t, t_end)``.
        Default ``t_end``: load ramp end + 0.2 s (steady window after the ramps).

        With ``save_to``, the recorded states are checkpointed into that directory
        every ``checkpoint_s`` seconds of wall time (``checkpoint.npz`` and a partial
        ``results.nc`` with status "running", both written atomically), so a killed
        run loses at most the last interval; :meth:`resume` continues it. SIGINT
        (Ctrl-C) and SIGTERM stop the run after the current step: the results up to
        then are returned with status "interrupted" (and saved with ``save_to``);
        ``results.attrs["signal"]`` names the signal.

        ``initial_records``: (t, q, v) arrays of an earlier part of this run (a
        checkpoint); the run continues from their last state at its time.
        """

        op = self.reducer.operating
        if t_end is None:
            t_end = max(op.load_ramp_end_s, op.speed_ramp_time_s) + 0.2
        if not (math.isfinite(t_end) and t_end > 0):
            raise InputError(f"t_end = {t_end!r} s is not allowed: must be > 0")
        if not (math.isfinite(dt) and 0 < dt <= t_end):
            raise InputError(f"dt = {dt!r} s is not allowed: must lie in (0, t_end = {t_end:g}]")
        if dt > 5e-4:
            raise InputError(f"dt = {dt:g} s is not allowed: must be <= 5e-4 s to resolve the pin-mesh period")
        t_start = 0.0
        if initial_records is not None:
            t_start = float(initial_records[0][-1])
            if not t_start < t_end:
                raise InputError(f"t_end = {t_end:g} s is not allowed: must be > the checkpoint time {t_start:g} s")
        check_step_count(t_end, dt, output_every, t_start=t_start)
        import exudyn as exu

        model = self.model if self.model is not None else self.build()
        from flexrv.model.kernel_cache import announce_compile

        announce_compile()  # one line on stderr if the numba kernels compile now (first run)
        mbs = model.mbs
        n_steps = check_step_count(t_end, dt, output_every, model.n, t_start=t_start)
        k0 = 0 if initial_records is None else len(initial_records[0])
        n_out = k0 + n_steps // output_every + 2
        ts = np.empty(n_out)
        qs = np.empty((n_out, model.n))
        vs = np.empty((n_out, model.n))
        state = {"k": 0, "step": 0, "fail": None, "stop": False, "signal": None}
        if initial_records is not None:
            t0_, q0_, v0_ = (np.asarray(a, dtype=float) for a in initial_records)
            ts[:k0], qs[:k0], vs[:k0] = t0_, q0_, v0_
            state["k"] = k0
        checkpoint = None
        if save_to is not None and checkpoint_s is not None and checkpoint_s > 0:
            checkpoint = _Checkpointer(self, Path(save_to), t_end, dt, output_every, float(checkpoint_s))
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
                state["a_last"] = sd.GetODE2Coordinates_tt(start_of_step)
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
            if checkpoint is not None and state["step"] % 20 == 0:
                checkpoint.maybe_write(model, ts, qs, vs, state["k"], state.get("a_last"))
            return True

        mbs.SetPreStepUserFunction(prestep)
        ss = exu.SimulationSettings()
        ti = ss.timeIntegration
        ti.numberOfSteps = n_steps
        ti.startTime = t_start
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

        def on_stop(signum, frame):
            state["stop"] = True
            state["signal"] = signal.Signals(signum).name

        old = {}
        for name in STOP_SIGNALS:
            try:
                sig = getattr(signal, name)
                old[sig] = signal.signal(sig, on_stop)
            except ValueError:  # not in the main thread
                break
        for g in model.groups:
            g.stats[0] = g.stats[1] = 0
            g.reset()
        if initial_records is not None:  # continue from the checkpointed state at its (absolute) time
            ic = exu.ConfigurationType.Initial
            mbs.systemData.SetODE2Coordinates(list(qs[k0 - 1]), configuration=ic)
            mbs.systemData.SetODE2Coordinates_t(list(vs[k0 - 1]), configuration=ic)
            if initial_accelerations is not None:
                mbs.systemData.SetODE2Coordinates_tt(list(initial_accelerations), configuration=ic)
                ti.generalizedAlpha.computeInitialAccelerations = False
        solver = exu.MainSolverImplicitSecondOrder()
        t0 = _time.perf_counter()
        error = None
        from flexrv.model.kernels import single_thread_blas

        try:
            with single_thread_blas():  # one BLAS thread unless FLEXRV_BLAS_THREADS is set (issue 15)
                ok = solver.SolveSystem(mbs, ss)
        except Exception as exc:  # exudyn raises on Newton failure / user-function errors
            ok, error = False, exc
        finally:
            for sig, handler in old.items():
                signal.signal(sig, handler)
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
            state["a_last"] = mbs.systemData.GetODE2Coordinates_tt()
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

        res = results_from_states(model, ts[:k], qs[:k], vs[:k], dt=dt, status=status, timing=self.timing,
                                  cls=Results)
        if state["signal"] is not None:
            res.attrs["signal"] = state["signal"]
        if checkpoint is not None and k > 1:  # the complete record, so a resume of a finished run is a no-op
            checkpoint.write_states(ts[:k], qs[:k], vs[:k], state.get("a_last"))
        if status == "failed":
            detail = " ".join(str(error).split())[:200] if error is not None else ""
            t_fail, cause = state["fail"] if state["fail"] is not None else (t_fin, f"Newton iteration failed ({detail})")
            res.attrs["failure"] = f"t = {t_fail:.6g} s: {cause}"
            path = None
            if save_to is not None and k > 1:
                path = res.save(save_to)
            if t_fail <= t_start + 2 * dt:  # at the very start: the assembled design, not the step
                advice = ("the design cannot start from rest: check the profile modifications and clearances "
                          "(second_stage.modification_*, needle_bearing.radial_clearance_um, first_stage.backlash_um) "
                          "for interference at assembly")
            else:
                advice = (f"reduce the step (dt = {dt:g} s -> {dt / 2:g} s) or increase contact damping "
                          "(contact.pin_max_damping_Ns_per_m)")
            msg = (f"simulation failed at t = {t_fail:.6g} s: {cause}. Suggestion: {advice}"
                   + (f"; partial results saved to {path}" if path else "; partial results in exc.results"))
            err = SimulationError(msg)
            err.results = res
            raise err
        if status == "interrupted" and save_to is not None and k > 1:
            res.save(save_to)
        return res

    @classmethod
    def resume(cls, directory: str | Path, progress: bool | Callable = False,
               checkpoint_s: float | None = CHECKPOINT_INTERVAL_S, **run_options):
        """Continue a run that was killed (or interrupted) from the last checkpoint in
        ``directory`` (written by :meth:`run` with ``save_to``): same design, model,
        options, step and end time; the drive and load are functions of absolute
        time, the state (coordinates, velocities) is the checkpointed one. Returns
        (Simulation, Results); the results cover the whole run and are saved to
        ``directory``.

        Not bit-identical: the integrator restarts at the checkpoint with the
        recorded accelerations as its algorithmic accelerations and a fresh Newton
        Jacobian, where the uninterrupted run carries both from earlier steps (Exudyn
        offers no setter for them). The difference is at the Newton-tolerance level;
        the backlash impacts of the start-up amplify it (rv40e rigid, checkpoint at
        0.03 s: up to 1.3 arcsec at t <= 0.05 s), and it decays with the transient:
        over the steady window of a 0.3 s run the resumed TE equals the
        uninterrupted one within 1e-6 arcsec (tests/test_faults.py)."""
        from flexrv.post.io import load_checkpoint

        ck = load_checkpoint(directory)
        meta = ck["meta"]
        if float(ck["t"][-1]) >= meta["t_end"] - 0.5 * meta["dt"]:
            raise InputError(f"--resume {directory}: the run is already complete (t_end = {meta['t_end']:g} s)")
        options = dict(meta.get("model_options") or {})
        if "parts" in options:
            options["parts"] = tuple(options["parts"])
        sim = cls(ck["reducer"], model=meta["model"], model_options=options)
        res = sim.run(t_end=meta["t_end"], dt=meta["dt"], progress=progress, output_every=meta["output_every"],
                      save_to=directory, checkpoint_s=checkpoint_s, initial_records=(ck["t"], ck["q"], ck["v"]),
                      initial_accelerations=ck.get("a"),
                      **run_options)
        return sim, res


class _Checkpointer:
    """Periodic, atomic checkpoints of a running simulation into its output
    directory: raw states (``checkpoint.npz``, for :meth:`Simulation.resume`) and
    the partial results (``results.nc`` + ``config.toml``, status "running"),
    every ``interval`` s of wall time, and at least 5x the time the last
    checkpoint took (so a long run never spends more than ~1/6 of its time saving)."""

    def __init__(self, sim: "Simulation", directory: Path, t_end: float, dt: float, output_every: int,
                 interval: float):
        self.sim, self.directory, self.interval = sim, directory, interval
        self.meta = {"model": sim.model_name, "model_options": sim.model_options, "drive": sim.drive,
                     "t_end": t_end, "dt": dt, "output_every": output_every}
        self.custom = sim.drive != "ramp" or sim.torque is not None  # not resumable from files
        self.next_at = _time.perf_counter() + interval
        self.count = 0

    def maybe_write(self, model, ts, qs, vs, k: int, a_last=None) -> None:
        now = _time.perf_counter()
        if now < self.next_at or k < 2:
            return
        try:
            self.write_states(ts[:k], qs[:k], vs[:k], a_last)
            from flexrv.post.io import save_partial
            from flexrv.post.results import results_from_states

            res = results_from_states(model, ts[:k], qs[:k], vs[:k], dt=self.meta["dt"], status="running",
                                      timing=self.sim.timing)
            save_partial(res, self.directory)
        except Exception as exc:  # a full disk (or any save error) must not kill the run; the next one retries
            import warnings

            warnings.warn(f"checkpoint to {self.directory} failed: {exc}", RuntimeWarning, stacklevel=2)
        took = _time.perf_counter() - now
        self.count += 1
        self.next_at = _time.perf_counter() + max(self.interval, 5.0 * took)

    def write_states(self, t, q, v, a_last=None) -> None:
        from flexrv.post.io import save_checkpoint

        meta = dict(self.meta, resumable=not self.custom)
        save_checkpoint(self.directory, t, q, v, meta, self.sim.reducer, a_last)


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
