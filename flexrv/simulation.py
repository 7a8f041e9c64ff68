"""Run a reducer model in time and return named results.

>>> from flexrv.simulation import Simulation             # doctest: +SKIP
>>> res = Simulation("rv40e").run(t_end=0.3, dt=1e-4)     # doctest: +SKIP
>>> res["TE [arcsec]"]                                    # doctest: +SKIP

Integration: the implicit generalized-alpha (spectral radius 0.5 to damp the stiff
contact modes numerically) with modified Newton, a fresh analytic Jacobian at every step
for the small dense systems, and adaptive step reduction on Newton failure, run by one of
two integrators (``Simulation.run(integrator=...)``, docs/integrator.md): ``"compiled"``
(:mod:`flexrv.model.integrator`: the step loop compiled around the fused force kernel,
the default for models whose forces are all compiled kernels, e.g. the rigid model) or
``"exudyn"`` (Exudyn's solver with the forces as Python user functions: the reference,
and the default for models with Python force groups). Both take the same steps with the
same Newton iterations (tests/test_integrator.py). A run is integrated in
segments of :data:`SEGMENT_STEPS` steps, the integrator restarted at every
boundary from the reached state with every group's history reset, so a
checkpoint (always at a boundary) resumes bit-identically (:meth:`Simulation.run`;
cost within the timing noise: rv40e 0.72 s CPU segmented vs 0.72-1.07 s not, TE
mean unchanged to 1e-5 arcsec, p-p to 0.01 %). States are recorded every
``output_every`` steps (with the per-contact results of the integrator's last call
at that state: the compiled force groups' and the bearing rows',
:class:`flexrv.model.kernels.HistoryRecorder`),
so a run that fails (Newton failure, NaN, penetration
beyond the physical limit, a disc that skipped a pin) or is interrupted (Ctrl-C,
SIGTERM) still returns the results up to that time:
:class:`flexrv.errors.SimulationError` carries them as ``exc.results`` (and saves
them if ``save_to`` was given); an interrupted run returns results with
``status = "interrupted"``.

Default step and Newton tolerances (:data:`DEFAULT_DT`, :data:`DEFAULT_NEWTON_TOLERANCE`):
verified in tests/test_time_step.py against a 4x finer step with a 100x tighter
tolerance (rv40e: TE mean within 1e-4 arcsec, lines up to the cycloid mesh within
1.6 %; rv221: mean within 0.04 arcsec and its dominant line within 0.7 %, while
its 200-300 Hz lines depend on the start-up history at the Newton-tolerance level
-- two steady responses, see that module), the ball model too (with its Newton
setting :data:`MODEL_NEWTON`). Cost per step and real-time factors: benchmarks/bench_rigid.py
(figures on the documentation's benchmark page).
"""

from __future__ import annotations

import math
import signal
import time as _time
from pathlib import Path
from typing import Callable

import numpy as np

from flexrv.design import load
from flexrv.errors import ConvergenceError, InputError, SimulationError, check_options
from flexrv.units import ARCMIN_PER_RAD
from flexrv.viz.plots import PlottedResults as Results  # re-exported: flexrv.Results (saves its PNGs)

#: systems with more coordinates than this use Exudyn's sparse linear solver
SPARSE_ABOVE = 100

#: default step [s]: ~25 steps per pin-mesh period of both presets at rated speed;
#: TE mean and lines converged to the issue-15 criterion on rv40e (tests/test_time_step.py)
DEFAULT_DT = 1e-4

#: Exudyn Newton settings per model (under the user's newton_options). The ball model's Jacobian,
#: reused across steps, goes stale within a step as lightly loaded balls enter and leave contact: a
#: new one when the residual contracts worse than 0.25 per iteration (Exudyn's default 0.5) took
#: rv221 from 5.0 to 2.9 Newton iterations per step (benchmarks/bench_balls.py); it makes the
#: flexible rings slower (rv221 14.2 -> 15.7 s per simulated s) and is not used there. It applies
#: to balls with inertia (model option ball_inertia = true) only: the default quasi-static balls
#: leave a 6-coordinate element on the carrier, whose Jacobian is fresh every step (the small
#: dense system, as the rigid model), and run faster with Exudyn's 0.5 (benchmarks/bench_balls.py)
MODEL_NEWTON = {"balls": {"modifiedNewtonContractivity": 0.25}}

#: the compiled integrator's own settings where the iteration matrix is kept across steps (above
#: SPARSE_ABOVE coordinates) and partial Jacobians act (flexrv.model.integrator.partial_jacobians: the
#: flexible rings). With them (the elements outside the balls' blocks fresh every step,
#: flexrv.model.numerics.gen_alpha) Exudyn's predictor needed fewer full Jacobians than the extrapolated one
#: (rv40e 0.10 / 0.16 per step, rv221 0.20 / 0.25) and less CPU (rv40e 9.5 / 11.1, rv221 6.5 / 7.4 s per
#: simulated s; benchmarks/bench_integrator.py --model flexible)
KEPT_MATRIX_COMPILED = {"extrapolatedPredictor": False}


#: largest number of time steps of one run (~1.5 h of wall time for the rigid model
#: at ~2.5 ms per step); more is refused before any work with a step-count estimate
MAX_STEPS = 2_000_000

#: largest memory of the recorded states (time, coordinates, velocities) [bytes];
#: the derived result arrays need a few times more
MAX_RECORD_BYTES = 2 * 1024**3

#: default Newton tolerances (relative, absolute [N per coordinate]) of Exudyn's solver
DEFAULT_NEWTON_TOLERANCE = (1e-3, 1e-1)
#: duration [s] of each quarter of the stiffness test's torque loop. Quasi-static means the
#: loop's branches do not depend on it: on rv221 (rated 3000 N m, heavy output side) 0.02 s left
#: the branches 2043 / 1767 N m/arcmin apart (output ringing after the clearance crossing),
#: 0.08 s gives 2147 / 2132 against the quasi-static 2113 catalog slope; rv40e moves by < 1 %
#: (tests/test_stiffness_budget.py::test_default_loop_is_quasi_static)
DEFAULT_QUARTER_TIME = 0.08

#: default wall-time interval between two checkpoints of a run saved to a directory [s]
CHECKPOINT_INTERVAL_S = 10.0

#: steps per integrator segment: the integrator restarts from the reached state at
#: every multiple of this step index, so a checkpoint (always at such a boundary)
#: resumes bit-identically (:meth:`Simulation.run`). 1000 (0.1 s at the default
#: step; ~0.1 s of CPU for the rigid model, ~12 s for the flexible rings): a restart
#: is a small perturbation (see run), so fewer are better; a kill loses at most one
#: checkpoint interval plus one segment
SEGMENT_STEPS = 1000

#: signal numbers that stop a run gracefully (partial results kept): Ctrl-C, kill
STOP_SIGNALS = ("SIGINT", "SIGTERM")

#: steps of the compiled integrator between two returns to Python where a group's per-step check
#: runs in Python (no compiled ``step_check``; the signals and the progress report run there too):
#: those checks see every CHECK_EVERY-th accepted state. 25: one pin-mesh period of the presets at
#: the default step; a return costs ~50 us (the checks, the progress, the compiled call's argument
#: unboxing ~13 us; the drive and load tables are made once per segment)
CHECK_EVERY = 25
#: steps between two returns where every check is compiled (run after every accepted step in the
#: loop): the signals and the progress report only, ~15 ms apart on the rigid model
RETURN_EVERY = 250


def check_time_options(reducer, t_end: float | None, dt: float = DEFAULT_DT) -> float:
    """The end time of a run (default: load ramp end + 0.2 s) after checking ``t_end``
    and ``dt`` (finite, 0 < dt <= t_end, dt <= 5e-4 s); InputError naming the value."""
    op = reducer.operating
    if t_end is None:
        t_end = max(op.load_ramp_end_s, op.speed_ramp_time_s) + 0.2
    if isinstance(t_end, bool) or not isinstance(t_end, (int, float)) or not (math.isfinite(t_end) and t_end > 0):
        raise InputError(f"t_end = {t_end!r} s is not allowed: must be > 0")
    if isinstance(dt, bool) or not isinstance(dt, (int, float)) or not (math.isfinite(dt) and 0 < dt <= t_end):
        raise InputError(f"dt = {dt!r} s is not allowed: must lie in (0, t_end = {t_end:g}]")
    if dt > 5e-4:
        raise InputError(f"dt = {dt:g} s is not allowed: must be <= 5e-4 s to resolve the pin-mesh period")
    return t_end


def check_step_count(
    t_end: float, dt: float, output_every: int = 1, n_coordinates: int | None = None, t_start: float = 0.0
) -> int:
    """Number of steps of a run; InputError (naming --dt/--t-end and the estimate)
    if it exceeds :data:`MAX_STEPS` or the recorded states would exceed
    :data:`MAX_RECORD_BYTES` (checked again with the real coordinate count after
    the model is built)."""
    n_steps = int(round((t_end - t_start) / dt))
    if n_steps > MAX_STEPS:
        raise InputError(
            f"t_end = {t_end:g} s with dt = {dt:g} s needs {n_steps:.3g} time steps: at most "
            f"{MAX_STEPS:.3g} are allowed (~{n_steps * 2.5e-3 / 3600:.3g} h of wall time at ~2.5 ms "
            f"per step); increase dt or reduce t_end"
        )
    if n_coordinates is not None:
        n_out = n_steps // max(int(output_every), 1) + 2
        nbytes = 8.0 * n_out * (2 * n_coordinates + 1)
        if nbytes > MAX_RECORD_BYTES:
            raise InputError(
                f"t_end = {t_end:g} s with dt = {dt:g} s records {n_out:.3g} states of {n_coordinates} "
                f"coordinates: ~{nbytes / 1024**3:.3g} GiB, at most {MAX_RECORD_BYTES / 1024**3:g} GiB "
                "allowed; increase dt or output_every, or reduce t_end"
            )
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

    def __init__(
        self,
        preset_or_config,
        model: str = "rigid",
        drive: str = "ramp",
        torque: Callable | None = None,
        model_options: dict | None = None,
    ):
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
        self.model = build_model(
            self.reducer, self.model_name, drive=self.drive, torque=self.torque, **self.model_options
        )
        self.timing["build_s"] = _time.perf_counter() - t0
        return self.model

    def run(
        self,
        t_end: float | None = None,
        dt: float = DEFAULT_DT,
        progress: bool | Callable = False,
        output_every: int = 1,
        save_to: str | Path | None = None,
        spectral_radius: float = 0.5,
        newton_tolerance: tuple[float, float] = DEFAULT_NEWTON_TOLERANCE,
        newton_options: dict | None = None,
        checkpoint_s: float | None = CHECKPOINT_INTERVAL_S,
        segment_steps: int = SEGMENT_STEPS,
        restart: dict | None = None,
        record_outputs: bool = True,
        integrator: str | None = None,
    ):
        """Integrate to ``t_end`` [s] with step ``dt`` [s]; return :class:`flexrv.post.Results`.

        ``progress``: True for a rich progress bar, or a callable ``f(t, t_end)``.
        Default ``t_end``: load ramp end + 0.2 s (steady window after the ramps).

        ``integrator``: ``"compiled"`` (the compiled generalized-alpha around the fused
        kernel, :mod:`flexrv.model.integrator`; the default for models whose forces all
        live in compiled kernels, e.g. the rigid model), ``"exudyn"`` (Exudyn's solver, the
        reference; the default for models with Python groups: balls, flexible rings,
        flexible crank) or None (that default). Both run the same algorithm and Newton
        control (docs/integrator.md); the choice is recorded as ``attrs["integrator"]``.

        Segments: the run is integrated in segments of ``segment_steps`` steps (step
        index j = 0, S, 2S, ... at t = j dt); at every boundary the integrator is
        restarted from the state it reached (coordinates, velocities and the
        accelerations as the generalized-alpha's initial accelerations, nominal step
        ``dt``, a fresh Newton Jacobian) and every group forgets its history
        (:meth:`~flexrv.model.base.ForceGroup.reset`: warm starts, caches). The state
        at a boundary is therefore everything the rest of the run depends on, and a
        run resumed from a boundary (:meth:`resume`) repeats exactly, bit for bit,
        what the uninterrupted run did. The restart's one approximation: the
        generalized-alpha's algorithmic accelerations restart from the given
        accelerations (Exudyn has no setter for them), i.e. a_alg := a at the boundary;
        with spectral radius 0.5 (alpha_m = 0, alpha_f = 1/3, gamma = 5/6) that
        changes the first step's velocity by (1 - gamma) h (a_alg - a) =
        h (a_n-1 - a_n) / 18, of the order of the scheme's own local error (rv40e:
        TE mean unchanged to 1e-5 arcsec, lines to 0.1 %; in a start-up with
        backlash impacts, and on rv221's two steady responses, any perturbation
        of this size -- a Newton tolerance as well -- grows, tests/test_time_step.py).

        With ``save_to``, a checkpoint is written at the first segment boundary after
        every ``checkpoint_s`` seconds of wall time (``checkpoint.npz``: the records
        and the boundary state; a partial ``results.nc`` with status "running"; both
        atomic), so a killed run loses at most the last interval. SIGINT (Ctrl-C) and
        SIGTERM stop the run after the current step (the compiled integrator: after
        the current check interval): the results up to then are
        returned with status "interrupted" (and saved with ``save_to``, where the
        checkpoint is the last segment boundary reached); ``results.attrs["signal"]``
        names the signal.

        ``restart``: a checkpoint's content (:meth:`resume`): records ``t``, ``q``,
        ``v`` before the boundary, the boundary state ``q_b``, ``v_b``, ``a_b`` and
        its step index ``step`` (and the recording elements' ``records``).

        ``record_outputs`` (default True): the compiled force groups' and the bearing
        rows' outputs (contact forces, ball loads, ...) are those the integrator computed at each recorded state
        (:class:`flexrv.model.kernels.HistoryRecorder`; the same numbers as evaluating
        them again, to the solvers' tolerances, except that ``pin_gap`` of a pin the
        solver proved open is a positive lower bound of its gap); False: every output
        evaluated again from the recorded states, every pin gap exact (rv40e: +0.2-0.3
        s CPU per simulated s).
        """
        plan = _RunPlan.of(self.reducer, t_end, dt, output_every, segment_steps, restart)
        import exudyn as exu

        newton_options = check_options("newton_options", newton_options, _newton_options_allowed(exu))
        if integrator is not None and integrator not in INTEGRATORS:
            raise InputError(f"integrator = {integrator!r} is not allowed: choose from {', '.join(INTEGRATORS)}")
        model = self.model if self.model is not None else self.build()
        plan.check_size(model.n)
        kind = choose_integrator(model, integrator)
        _announce_compile(model, kind)
        if kind == "compiled":
            segments = _CompiledSegments(model, spectral_radius, newton_tolerance, newton_options, plan)
        else:
            segments = _ExudynSegments(model, self.model_name, spectral_radius, newton_tolerance, newton_options)
        records = _Records(model, plan, restart, record_outputs)
        checkpoint = None
        if save_to is not None and checkpoint_s is not None and checkpoint_s > 0:
            checkpoint = _Checkpointer(self, Path(save_to), plan.t_end, dt, output_every, plan.seg, float(checkpoint_s))
            checkpoint.meta.update(
                newton_tolerance=list(newton_tolerance),
                spectral_radius=spectral_radius,
                newton_options=newton_options,
                integrator=kind,
            )
            checkpoint.recorder = records.recorder
        report = _progress_callback(progress, plan.t_end)
        for g in model.groups:
            g.stats[0] = g.stats[1] = 0
        t0, c0 = _time.perf_counter(), _time.process_time()
        with _StopSignals() as stop:
            outcome = _segment_loop(plan, segments, records, checkpoint, stop, report)
        wall, cpu = _time.perf_counter() - t0, _time.process_time() - c0
        if report is not None:
            report(None)
        self.timing.update(solve_s=wall, solve_cpu_s=cpu, integrator=kind)
        return self._finish(model, plan, segments, records, checkpoint, stop, outcome, save_to)

    def _finish(self, model, plan, segments, records, checkpoint, stop, outcome, save_to):
        """Timing, status and results of a run (raising SimulationError with the partial
        results if it failed)."""
        k = records.k
        counts = segments.counts()
        self.timing.update(
            steps=outcome.steps,
            simulated_s=float(records.ts[k - 1]) if k else 0.0,
            newton_iterations=counts["newton"],
            jacobians=counts["jacobians"],
            partial_jacobians=counts.get("partial_jacobians", 0),
            segments=counts["segments"],
            checkpoint_s=checkpoint.spent if checkpoint is not None else 0.0,
            force_calls={g.name: g.stats[0] for g in model.groups},
            jacobian_calls={g.name: g.stats[1] for g in model.groups},
        )
        status = "completed"
        if outcome.fail is not None or (not outcome.ok and not stop.stop):
            status = "failed"
        elif stop.stop:
            status = "interrupted"
        from flexrv.post.results import results_from_states

        res = results_from_states(
            model,
            records.ts[:k],
            records.qs[:k],
            records.vs[:k],
            dt=plan.dt,
            status=status,
            timing=self.timing,
            cls=Results,
            records=records.recorder.records(k) if records.recorder is not None else None,
        )
        res.attrs["integrator"] = self.timing["integrator"]
        if stop.signal is not None:
            res.attrs["signal"] = stop.signal
        if checkpoint is not None:  # the last boundary (the complete run: a resume of it is refused as complete)
            checkpoint.write_states(records.ts, records.qs, records.vs, outcome.boundary)
        if status == "failed":
            raise _failure(res, plan, outcome, segments, save_to, k)
        if status == "interrupted" and save_to is not None and k > 1:
            res.save(save_to)
        return res

    @classmethod
    def resume(
        cls,
        directory: str | Path,
        progress: bool | Callable = False,
        checkpoint_s: float | None = CHECKPOINT_INTERVAL_S,
        **run_options,
    ):
        """Continue a run that was killed (or interrupted) from the last checkpoint in
        ``directory`` (written by :meth:`run` with ``save_to``): same design, model,
        options, step, segment length and end time; the drive and load are functions
        of absolute time. Returns (Simulation, Results); the results cover the whole
        run and are saved to ``directory``.

        Bit-identical to the uninterrupted run: a checkpoint is a segment boundary,
        where the uninterrupted run itself restarts its integrator from the stored
        state (coordinates, velocities, accelerations) with every group's history
        reset (:meth:`run`); tests/test_faults.py compares every variable with
        ``np.array_equal``."""
        from flexrv.post.io import load_checkpoint

        ck = load_checkpoint(directory)
        meta = ck["meta"]
        if "step" not in meta or ck.get("a") is None:
            raise InputError(
                f"--resume {directory}: the checkpoint was written by an older flexrv (no segment "
                "boundary state); rerun the simulation"
            )
        if int(meta["step"]) >= max(int(round(meta["t_end"] / meta["dt"])), 1):
            raise InputError(f"--resume {directory}: the run is already complete (t_end = {meta['t_end']:g} s)")
        options = dict(meta.get("model_options") or {})
        if "parts" in options:
            options["parts"] = tuple(options["parts"])
        sim = cls(ck["reducer"], model=meta["model"], model_options=options)
        run_options.setdefault("newton_tolerance", tuple(meta.get("newton_tolerance", DEFAULT_NEWTON_TOLERANCE)))
        run_options.setdefault("spectral_radius", meta.get("spectral_radius", 0.5))
        run_options.setdefault("newton_options", meta.get("newton_options") or None)
        run_options.setdefault("integrator", meta.get("integrator"))  # (older checkpoints: the model's default)
        t, q, v = ck["t"], ck["q"], ck["v"]
        restart = {
            "t": t[:-1],
            "q": q[:-1],
            "v": v[:-1],
            "q_b": q[-1],
            "v_b": v[-1],
            "a_b": ck["a"],
            "step": int(meta["step"]),
            "records": ck.get("records"),
        }
        res = sim.run(
            t_end=meta["t_end"],
            dt=meta["dt"],
            progress=progress,
            output_every=meta["output_every"],
            save_to=directory,
            checkpoint_s=checkpoint_s,
            segment_steps=int(meta["segment_steps"]),
            restart=restart,
            **run_options,
        )
        return sim, res


class _Checkpointer:
    """Checkpoints of a running simulation into its output directory, at segment
    boundaries: the records and the boundary state (``checkpoint.npz``, for
    :meth:`Simulation.resume`; the boundary state is its last row, its
    accelerations ``a``) and the partial results (``results.nc`` + ``config.toml``,
    status "running"), at the first boundary after every ``interval`` s of wall time
    and at least 5x the time the last checkpoint took
    (so a long run never spends more than ~1/6 of its time saving)."""

    def __init__(
        self,
        sim: "Simulation",
        directory: Path,
        t_end: float,
        dt: float,
        output_every: int,
        segment_steps: int,
        interval: float,
    ):
        self.sim, self.directory, self.interval = sim, directory, interval
        self.meta = {
            "model": sim.model_name,
            "model_options": sim.model_options,
            "drive": sim.drive,
            "t_end": t_end,
            "dt": dt,
            "output_every": output_every,
            "segment_steps": segment_steps,
        }
        self.custom = sim.drive != "ramp" or sim.torque is not None  # not resumable from files
        self.next_at = _time.perf_counter() + interval
        #: the run's HistoryRecorder (its records before a boundary go into the checkpoint), or None
        self.recorder = None
        self.count = 0
        self.spent = 0.0

    def maybe_write(self, model, ts, qs, vs, boundary) -> None:
        now = _time.perf_counter()
        k = boundary[1]
        if now < self.next_at or k < 2:
            return
        try:
            self.write_states(ts, qs, vs, boundary)
            from flexrv.post.io import save_partial
            from flexrv.post.results import results_from_states

            res = results_from_states(
                model,
                ts[:k],
                qs[:k],
                vs[:k],
                dt=self.meta["dt"],
                status="running",
                timing=self.sim.timing,
                records=self.recorder.records(k) if self.recorder is not None else None,
            )
            save_partial(res, self.directory)
        except Exception as exc:  # a full disk (or any save error) must not kill the run; the next one retries
            import sys

            if not getattr(self, "failed", 0):  # one line, at the first failure
                where = getattr(exc, "filename", None) or self.directory
                reason = getattr(exc, "strerror", None) or exc
                print(
                    f"flexrv: warning: checkpoint not written ({reason}: {where}); the run goes on, "
                    "the last checkpoint is kept",
                    file=sys.stderr,
                    flush=True,
                )
            self.failed = getattr(self, "failed", 0) + 1
        took = _time.perf_counter() - now
        self.spent += took
        self.count += 1
        self.next_at = _time.perf_counter() + max(self.interval, 5.0 * took)

    def write_states(self, ts, qs, vs, boundary) -> None:
        """checkpoint.npz at ``boundary`` = (step, records before it, q, v, a): the
        records, then the boundary state as the last row."""
        from flexrv.post.io import save_checkpoint

        j, k, q_b, v_b, a_b = boundary
        if j == 0:  # nothing integrated yet: nothing to resume
            return
        t0 = _time.perf_counter()
        meta = dict(self.meta, resumable=not self.custom, step=int(j))
        t_b = (
            self.meta["t_end"] if j >= max(int(round(self.meta["t_end"] / self.meta["dt"])), 1) else j * self.meta["dt"]
        )
        save_checkpoint(
            self.directory,
            np.append(ts[:k], t_b),
            np.vstack([qs[:k], q_b[None]]),
            np.vstack([vs[:k], v_b[None]]),
            meta,
            self.sim.reducer,
            a_b,
            records=self.recorder.arrays(k) if self.recorder is not None else None,
        )
        self.spent += _time.perf_counter() - t0


#: the integrators of :meth:`Simulation.run` (``integrator``)
INTEGRATORS = ("compiled", "exudyn")


def choose_integrator(model, integrator: str | None) -> str:
    """The integrator of a run: ``integrator`` checked (InputError naming the value and the
    allowed ones; "compiled" for a model with Python groups: InputError with the reason), or
    the default: "compiled" where :func:`flexrv.model.integrator.compiled_eligible`, else "exudyn"."""
    from flexrv.model.integrator import compiled_eligible

    if integrator is not None and integrator not in INTEGRATORS:
        raise InputError(f"integrator = {integrator!r} is not allowed: choose from {', '.join(INTEGRATORS)}")
    reason = compiled_eligible(model)
    if integrator == "compiled" and reason is not None:
        raise InputError(
            f"integrator = 'compiled' is not allowed for the {model.name} model: {reason}; use --integrator exudyn"
        )
    if integrator is None:
        return "compiled" if reason is None else "exudyn"
    return integrator


def _announce_compile(model, integrator: str) -> None:
    """One line on stderr if the model's numba kernels compile now (first run) on ``integrator``."""
    from flexrv.model.kernel_cache import announce_compile

    kinds = ["integrate" if integrator == "compiled" else "fused"] if model.fused is not None else []
    announce_compile(kinds=kinds)


class _RunPlan:
    """The time grid of a run: step j ends at t = j dt (the last at t_end), segments of
    ``seg`` steps, the first step index ``j0`` (a restart's boundary)."""

    def __init__(self, t_end, dt, output_every, seg, j0):
        self.t_end, self.dt, self.output_every, self.seg, self.j0 = float(t_end), dt, int(output_every), seg, j0
        self.n_total = max(int(round(t_end / dt)), 1)  # step j ends at t = j dt, the last one at t_end
        self.t_start = self.t_of(j0)

    @classmethod
    def of(cls, reducer, t_end, dt, output_every, segment_steps, restart) -> "_RunPlan":
        """Checked options (InputError naming the value)."""
        t_end = check_time_options(reducer, t_end, dt)
        seg = int(segment_steps)
        if seg < 1:
            raise InputError(f"segment_steps = {segment_steps!r} is not allowed: must be an integer >= 1")
        j0 = 0 if restart is None else int(restart["step"])
        plan = cls(t_end, dt, output_every, seg, j0)
        if restart is not None and not j0 < plan.n_total:
            raise InputError(f"t_end = {t_end:g} s is not allowed: must be > the checkpoint time {plan.t_start:g} s")
        check_step_count(t_end, dt, output_every, t_start=plan.t_start)
        return plan

    def t_of(self, j: int) -> float:
        return self.t_end if j >= self.n_total else j * self.dt

    def check_size(self, n: int) -> int:
        self.n_steps = check_step_count(self.t_end, self.dt, self.output_every, n, t_start=self.t_start)
        return self.n_steps


class _Records:
    """The recorded states (t, q, v) of a run, the row count ``k`` and the per-contact
    records (:class:`flexrv.model.kernels.HistoryRecorder`, or None); the boundary state
    to start from (a restart's, or the model's initial state)."""

    def __init__(self, model, plan: _RunPlan, restart: dict | None, record_outputs: bool):
        k0 = 0 if restart is None else len(restart["t"])
        self.n_out = n_out = k0 + plan.n_steps // plan.output_every + 2
        self.ts, self.qs, self.vs = np.empty(n_out), np.empty((n_out, model.n)), np.empty((n_out, model.n))
        self.k = k0
        if restart is None:
            self.q_b, self.v_b, self.a_b = model.q0.copy(), np.concatenate([m.v0 for m in model.members.values()]), None
        else:
            self.ts[:k0], self.qs[:k0], self.vs[:k0] = (
                np.asarray(restart[key], dtype=float) for key in ("t", "q", "v")
            )
            self.q_b, self.v_b, self.a_b = (np.array(restart[key], dtype=float) for key in ("q_b", "v_b", "a_b"))
        self.recorder = None
        if record_outputs:
            from flexrv.model.kernels import HistoryRecorder

            recorder = HistoryRecorder(model, n_out)
            if recorder.sources:
                self.recorder = recorder
                if restart is not None and restart.get("records") is not None:
                    recorder.fill(k0, *restart["records"])

    def due(self, j: int, plan: _RunPlan) -> bool:
        """Whether the state at the end of step j is recorded (every output_every steps, and the end)."""
        return (self.k == 0 or j % plan.output_every == 0 or j >= plan.n_total) and self.k < self.n_out

    def append(self, t: float, q, v) -> None:
        """Record a state whose per-contact records are left to the outputs' history pass."""
        k = self.k
        self.ts[k], self.qs[k], self.vs[k] = t, q, v
        self.k = k + 1


class _StopSignals:
    """SIGINT/SIGTERM stop a run gracefully while inside: ``stop`` set, ``signal`` named;
    before the first step (numba may compile for minutes) the process exits at once
    (130 / 143, :func:`flexrv.model.kernel_cache.stop_now`)."""

    def __init__(self):
        self.stop, self.signal, self.step, self._old = False, None, 0, {}

    def _on_stop(self, signum, frame):
        from flexrv.model.kernel_cache import stop_now

        self.stop = True
        self.signal = signal.Signals(signum).name
        if self.step == 0:  # nothing integrated yet: nothing to keep
            stop_now(signum)

    def __enter__(self):
        for name in STOP_SIGNALS:
            try:
                sig = getattr(signal, name)
                self._old[sig] = signal.signal(sig, self._on_stop)
            except ValueError:  # not in the main thread
                break
        return self

    def __exit__(self, *exc):
        for sig, handler in self._old.items():
            signal.signal(sig, handler)
        return False


class _Outcome:
    """How a segment loop ended: ``ok``, the failure (t, cause) or error, the steps taken
    and the last boundary reached: (step index, records before it, q, v, a)."""

    def __init__(self, boundary):
        self.ok, self.fail, self.error, self.steps, self.boundary = True, None, None, 0, boundary


def _segment_loop(plan: _RunPlan, segments, records: _Records, checkpoint, stop: _StopSignals, report) -> _Outcome:
    """Integrate segment by segment (:meth:`Simulation.run`) with ``segments`` (Exudyn's or
    the compiled integrator): restart at every boundary, checkpoint there, stop on a
    failure or a signal."""
    from flexrv.model.kernels import single_thread_blas

    out = _Outcome((plan.j0, records.k, records.q_b, records.v_b, records.a_b))
    j = plan.j0
    q_b, v_b, a_b = records.q_b, records.v_b, records.a_b
    with single_thread_blas():  # one BLAS thread unless FLEXRV_BLAS_THREADS is set
        while j < plan.n_total:
            j_next = min((j // plan.seg + 1) * plan.seg, plan.n_total)
            ok = segments.segment(j, j_next, q_b, v_b, a_b, plan, records, stop, report, out)
            if not ok or out.fail is not None or stop.stop:
                out.ok = False
                break
            q_b, v_b, a_b = segments.boundary_state()
            j = j_next
            out.boundary = (j, records.k, q_b, v_b, a_b)
            if checkpoint is not None and j < plan.n_total:
                checkpoint.maybe_write(segments.model, records.ts, records.qs, records.vs, out.boundary)
    records.q_b, records.v_b = q_b, v_b
    if out.ok and j >= plan.n_total:
        segments.final(plan, records)
    return out


def _failure(res, plan: _RunPlan, outcome: _Outcome, segments, save_to, k: int) -> SimulationError:
    """The SimulationError of a failed run (its partial results attached, saved with ``save_to``)."""
    error = outcome.error
    detail = " ".join(str(error).split())[:200] if error is not None else ""
    t_fail, cause = (
        outcome.fail if outcome.fail is not None else (segments.time_reached(), f"Newton iteration failed ({detail})")
    )
    res.attrs["failure"] = f"t = {t_fail:.6g} s: {cause}"
    path = None
    if save_to is not None and k > 1:
        path = res.save(save_to)
    dt = plan.dt
    if t_fail <= plan.t_start + 2 * dt:  # at the very start: the assembled design, not the step
        advice = (
            "the design cannot start from rest: check the profile modifications and clearances "
            "(second_stage.modification_*, needle_bearing.radial_clearance_um, first_stage.backlash_um) "
            "for interference at assembly"
        )
    else:
        advice = (
            f"reduce the step (dt = {dt:g} s -> {dt / 2:g} s) or increase contact damping "
            "(contact.pin_max_damping_Ns_per_m)"
        )
    msg = f"simulation failed at t = {t_fail:.6g} s: {cause}. Suggestion: {advice}" + (
        f"; partial results saved to {path}" if path else "; partial results in exc.results"
    )
    err = SimulationError(msg)
    err.results = res
    return err


class _ExudynSegments:
    """Segments on Exudyn's implicit generalized-alpha (modified Newton, adaptive step);
    a pre-step hook records the states, runs the groups' per-step checks and stops on a signal."""

    def __init__(self, model, model_name: str, spectral_radius, newton_tolerance, newton_options):
        import exudyn as exu

        self.exu, self.model = exu, model
        newton_options = check_options("newton_options", newton_options, _newton_options_allowed(exu))
        from flexrv.model.integrator import COMPILED_ONLY_OPTIONS

        own = sorted(set(newton_options) & set(COMPILED_ONLY_OPTIONS))
        if own:
            raise InputError(
                f"newton_options {', '.join(map(repr, own))}: an option of the compiled integrator only "
                "(integrator = 'compiled')"
            )
        if model.info.get("ball_inertia", True):  # (quasi-static balls: Exudyn's defaults, see MODEL_NEWTON)
            newton_options = MODEL_NEWTON.get(model_name, {}) | newton_options  # the user's settings win
        self.ss = ss = exu.SimulationSettings()
        ti = self.ti = ss.timeIntegration
        ti.verboseMode = 0
        ti.newton.useModifiedNewton = True
        # small dense systems (the rigid model): a fresh Jacobian at the start of every step. The
        # contact stiffness changes from step to step, so a reused Jacobian needed 3.7-4.6 Newton
        # iterations per step (rv40e / rv221), a fresh one 1.3-1.9: fewer residual calls, whose Python
        # round trip is most of a step (benchmarks/bench_rigid.py, tests/test_time_step.py)
        ti.newton.modifiedNewtonJacUpdatePerStep = model.n <= SPARSE_ABOVE
        ti.newton.relativeTolerance, ti.newton.absoluteTolerance = newton_tolerance
        ti.generalizedAlpha.spectralRadius = spectral_radius
        for key, value in newton_options.items():
            setattr(ti.newton, key, value)
        if model.fused is not None:  # its Jacobians then come with the step's first residual
            model.fused.jacobian_each_step = bool(
                ti.newton.useModifiedNewton and ti.newton.modifiedNewtonJacUpdatePerStep
            )
        # massless (quasi-static) coordinates make M singular: start from rest with
        # zero accelerations instead (every run starts at rest in equilibrium)
        self.massless = any(not np.any(np.diag(m.mass_matrix)) for m in model.members.values())
        ti.adaptiveStep = True
        ss.solution.file.write = False
        # dense LU for the small rigid models; sparse for the ball/ring models, whose
        # dense path costs 2-4x more in Exudyn (rv40e flexible: 10.2 -> 4.1 s per 10 ms)
        ss.linearSolver.solverType = (
            exu.LinearSolverType.EXUdense if model.n <= SPARSE_ABOVE else exu.LinearSolverType.EigenSparse
        )
        self._counts = {"newton": 0, "jacobians": 0, "segments": 0}
        self._hooked = False

    def _install_prestep(self, plan, records, stop, report, out) -> None:
        """The pre-step hook (once per run): record, check, stop."""
        from flexrv.model.base import ForceGroup, exudyn_vector

        model, exu = self.model, self.exu
        sd = model.mbs.systemData
        start_of_step = exu.ConfigurationType.StartOfStep
        # only the groups that override the per-step hooks (the others' are no-ops), in group order
        steppers = [g for g in model.groups if type(g).new_step is not ForceGroup.new_step]
        checkers = [g for g in model.groups if type(g).check is not ForceGroup.check]
        ts, qs, vs, recorder = records.ts, records.qs, records.vs, records.recorder
        dt, output_every, n_out = plan.dt, plan.output_every, records.n_out

        def prestep(mbs_, t_target):
            # Exudyn calls this with the step's END time; the state is the start-of-step state
            t = sd.GetTime(start_of_step)
            values = sd.GetODE2Coordinates()
            k = records.k
            while k > 0 and ts[k - 1] >= t - 1e-12 * dt:  # a step was repeated (adaptive step reduction)
                k -= 1
            records.k = k
            # before recording: a failed run's results hold finite states only (the sum of the Python
            # floats: 0.3 us, numpy's 2.5 us per step)
            if not math.isfinite(sum(values)):
                out.fail = (t, "the state became NaN/inf")
                return False
            q = exudyn_vector(values)
            if (k == 0 or t >= ts[k - 1] + output_every * dt * (1 - 1e-9)) and k < n_out:
                ts[k] = t
                qs[k] = q
                vs[k] = exudyn_vector(sd.GetODE2Coordinates_t())
                if recorder is not None:
                    recorder.store(k, t, q, vs[k])
                records.k = k + 1
            out.steps += 1
            stop.step = out.steps
            for g in steppers:
                g.new_step()
            for g in checkers:
                msg = g.check()
                if msg:
                    out.fail = (t, msg)
                    return False
            if stop.stop:
                return False
            if report is not None and out.steps % 200 == 0:
                report(t)
            return True

        model.mbs.SetPreStepUserFunction(prestep)
        self._hooked = True

    def segment(self, j, j_next, q_b, v_b, a_b, plan, records, stop, report, out) -> bool:
        """Integrate steps j .. j_next from the boundary state; False on failure."""
        if not self._hooked:
            self._install_prestep(plan, records, stop, report, out)
        exu, model, ti = self.exu, self.model, self.ti
        sd = model.mbs.systemData
        ic = exu.ConfigurationType.Initial
        ti.minimumStepSize = plan.dt * 1e-3
        sd.SetODE2Coordinates(q_b.tolist(), configuration=ic)
        sd.SetODE2Coordinates_t(v_b.tolist(), configuration=ic)
        sd.SetODE2Coordinates_tt([0.0] * model.n if a_b is None else a_b.tolist(), configuration=ic)
        ti.generalizedAlpha.computeInitialAccelerations = a_b is None and not self.massless
        ti.startTime, ti.endTime, ti.numberOfSteps = plan.t_of(j), plan.t_of(j_next), j_next - j
        for g in model.groups:
            g.reset()
        if records.recorder is not None:  # the groups' records were reset: not those of the last call
            records.recorder.forget()
        solver = exu.MainSolverImplicitSecondOrder()
        ok = True
        try:
            ok = solver.SolveSystem(model.mbs, self.ss)
        except Exception as exc:  # exudyn raises on Newton failure / user-function errors
            ok, out.error = False, exc
        self._counts["newton"] += int(solver.it.newtonStepsCount)
        self._counts["jacobians"] += int(solver.it.newtonJacobiCount)
        self._counts["segments"] += 1
        return bool(ok)

    def boundary_state(self):
        sd = self.model.mbs.systemData
        return (
            np.array(sd.GetODE2Coordinates()),
            np.array(sd.GetODE2Coordinates_t()),
            np.array(sd.GetODE2Coordinates_tt()),
        )

    def final(self, plan: _RunPlan, records: _Records) -> None:
        """The end state (the pre-step hook records start-of-step states only)."""
        k = records.k
        if k < records.n_out and (k == 0 or plan.t_end > records.ts[k - 1]):
            records.ts[k], records.qs[k], records.vs[k] = plan.t_end, records.q_b, records.v_b
            if records.recorder is not None:
                records.recorder.store(k, plan.t_end, records.q_b, records.v_b)
            records.k = k + 1

    def time_reached(self) -> float:
        return float(self.model.mbs.systemData.GetTime())

    def counts(self) -> dict:
        return dict(self._counts)


class _CompiledSegments:
    """Segments on the compiled generalized-alpha (:mod:`flexrv.model.integrator`): the
    steps of a segment in compiled code, the elements' compiled per-step checks after every
    accepted step there; back in Python every :data:`CHECK_EVERY` steps for the groups'
    Python checks (every :data:`RETURN_EVERY` steps without any), the signals and the
    progress report."""

    def __init__(self, model, spectral_radius, newton_tolerance, newton_options, plan: _RunPlan):
        from flexrv.model.base import ForceGroup
        from flexrv.model.integrator import CompiledIntegrator, compiled_newton_options, partial_jacobians

        self.model = model
        # the Exudyn path's per-model settings (_ExudynSegments): a Jacobian every step for the small dense
        # systems, kept across steps above SPARSE_ABOVE coordinates; MODEL_NEWTON for balls with inertia
        options = {"modifiedNewtonJacUpdatePerStep": model.n <= SPARSE_ABOVE}
        if model.n > SPARSE_ABOVE and partial_jacobians(model):
            options |= KEPT_MATRIX_COMPILED
        if model.info.get("ball_inertia", True):
            options |= MODEL_NEWTON.get(model.name, {})
        options |= dict(newton_options or {})
        tolerance = (
            options.pop("relativeTolerance", newton_tolerance[0]),
            options.pop("absoluteTolerance", newton_tolerance[1]),
        )
        self.integ = CompiledIntegrator(model, spectral_radius, tolerance, compiled_newton_options(options))
        self.checkers = [
            g for g in model.groups if type(g).check is not ForceGroup.check and g not in self.integ.checked
        ]
        self.integ.check_every = CHECK_EVERY if self.checkers else RETURN_EVERY
        self._segments = 0
        self._t = plan.t_start

    def segment(self, j, j_next, q_b, v_b, a_b, plan, records, stop, report, out) -> bool:
        """Integrate steps j .. j_next from the boundary state; False on failure."""
        integ = self.integ
        t0, t1 = plan.t_of(j), plan.t_of(j_next)
        if not (np.all(np.isfinite(q_b)) and np.all(np.isfinite(v_b))):  # (a restart's state; steps check their own)
            out.fail = (t0, "the state became NaN/inf")
            return False
        integ.start(t0, q_b, v_b, a_b)
        self._segments += 1
        self._t = t0
        interval = plan.output_every * plan.dt * (1 - 1e-9)
        k = records.k
        if k < records.n_out and (k == 0 or t0 >= records.ts[k - 1] + interval):  # as the pre-step hook at t0
            records.append(t0, q_b, v_b)  # its per-contact records are left to the history pass
        buffers = integ.outputs(records.ts, records.qs, records.vs, records.recorder, interval)
        if records.k:
            buffers[-1][0] = records.ts[records.k - 1]
        # the segment's end is recorded as the next segment's start, unless it is the run's end
        rec = np.array([records.k, records.n_out, int(j_next < plan.n_total)], np.int64)

        def after_call(t, steps):
            records.k = int(rec[0])
            reported = out.steps // 200
            out.steps = stop.step = out.steps + steps
            self._t = t
            for g in self.checkers:
                msg = g.check()
                if msg:
                    out.fail = (t, msg)
                    return True
            if report is not None and out.steps // 200 > reported:
                report(t)
            return stop.stop

        status, self._t = integ.segment(t0, t1, plan.dt, rec, buffers, after_call)
        records.k = int(rec[0])
        self._sync_stats()
        if status > 0:
            out.fail = (self._t, integ.failure(status))
        return status == 0

    def _sync_stats(self) -> None:
        c = self.integ.counts()
        self.integ.fused.stats[0], self.integ.fused.stats[1] = c["calls"], c["jacobian_calls"]

    def boundary_state(self):
        i = self.integ
        return i.q.copy(), i.v.copy(), i.a.copy()

    def final(self, plan: _RunPlan, records: _Records) -> None:
        """The end state if the compiled loop's output interval skipped it (as the Exudyn
        path's), with the per-contact records of its last call (the converged end state)."""
        k = records.k
        if k < records.n_out and (k == 0 or plan.t_end > records.ts[k - 1]):
            records.append(plan.t_end, self.integ.q, self.integ.v)
            if records.recorder is not None:
                for i, (element, _, _, src, dst) in enumerate(records.recorder.sources):
                    if element is self.integ.fused:
                        for a, d in zip(src, dst):
                            d[k] = a
                        records.recorder.valid[i, k] = True

    def time_reached(self) -> float:
        return self._t

    def counts(self) -> dict:
        self._sync_stats()
        c = self.integ.counts()
        return {
            "newton": c["newton"],
            "jacobians": c["jacobians"],
            "partial_jacobians": c["partial_jacobians"],
            "segments": self._segments,
        }


def _newton_options_allowed(exu) -> dict[str, object]:
    """The names ``newton_options`` may set: Exudyn's Newton settings and the compiled
    integrator's own options (:data:`flexrv.model.integrator.COMPILED_ONLY_OPTIONS`)."""
    from flexrv.model.integrator import COMPILED_ONLY_OPTIONS

    return _newton_settings(exu) | COMPILED_ONLY_OPTIONS


def _newton_settings(exu) -> dict[str, object]:
    """Exudyn's Newton settings by name with their default values (the options
    ``newton_options`` may set, :func:`flexrv.errors.check_options`)."""
    import warnings

    ns = exu.SimulationSettings().timeIntegration.newton
    out = {}
    for k in dir(ns):
        if k.startswith("_"):
            continue
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # deprecated names (Exudyn warns on access) are not offered
            try:
                value = getattr(ns, k)
            except Warning:
                continue
        if isinstance(value, (bool, int, float, str)):
            out[k] = value
    return out


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

    bar = Progress(
        TextColumn("simulating"),
        BarColumn(),
        TextColumn("{task.completed:.3f}/{task.total:.3f} s"),
        TimeRemainingColumn(),
        transient=True,
    )
    task = bar.add_task("sim", total=t_end)
    bar.start()

    def rep(t):
        if t is None:
            bar.stop()
        else:
            bar.update(task, completed=t)

    return rep


def stiffness_test_budget(reducer, torque: float, theta_in: float = 0.0, reference: dict | None = None):
    """Stiffness budget of the stiffness test (:class:`flexrv.analysis.budget.Budget`): the
    quasi-static model's strain-energy budget (:meth:`flexrv.model.quasi_static.StaticModel.
    compliance_budget`, the same force groups and laws as the dynamic rigid model) at the
    test's pose, the input locked at ``theta_in`` and the output at +``torque`` (static
    equilibrium reached by torque continuation from the kinematic pose), through
    :func:`flexrv.analysis.budget.stiffness_budget` (every element in the model);
    ``reference``: named rigidities [N m/rad] stored with it (the loop's)."""
    from flexrv.analysis.budget import ModelShares, stiffness_budget
    from flexrv.model.outputs import model_outputs
    from flexrv.model.quasi_static import StaticModel, ramp_to

    sm = StaticModel(reducer)
    sm.torque = 0.0
    q = ramp_to(sm, theta_in, sm.kinematic_pose(theta_in), torque, steps=8)
    k_t = sm.tangent_rigidity(theta_in, q)
    outs = model_outputs(sm.model, np.array([theta_in]), q[None], np.zeros((1, sm.n)))
    bend = outs.get("crank_bending_fraction")
    model = ModelShares(
        shares=sm.compliance_budget(theta_in, q),
        tangent_compliance=1.0 / k_t,
        bending_fraction=float(np.nanmean(np.asarray(bend.values, dtype=float))) if bend is not None else 0.0,
    )
    ref = {"model_tangent_rigidity": float(k_t), **(reference or {})}
    return stiffness_budget(reducer, torque, model=model, reference=ref, route="stiffness_test")


def stiffness_test(
    preset_or_config,
    model: str = "rigid",
    quarter_time: float = DEFAULT_QUARTER_TIME,
    settle: float = 0.005,
    dt: float = DEFAULT_DT,
    torque: float | None = None,
    progress: bool | Callable = False,
    save_to: str | Path | None = None,
    model_options: dict | None = None,
):
    """Virtual torsional-stiffness test bench (:cite:`seed004`): input locked, output
    torque ramped 0 -> +T -> -T -> 0 (T = rated torque unless given), each
    quarter of the loop over ``quarter_time`` [s] (default :data:`DEFAULT_QUARTER_TIME`; quasi-static: far longer than
    the output's torsional period and its ringing after the clearance crossing).

    Returns (:class:`flexrv.post.stiffness.StiffnessTest`, Results); the Results'
    dataset carries the figures as scalar variables with units (rigidity, lost motion,
    hysteresis, ...; :mod:`flexrv.post.definitions`), the loop (``loop_torque``,
    ``loop_angle``) and the budget of :func:`stiffness_test_budget` at +T with the loop's
    rigidities beside it (``budget_*`` over ``budget_element``,
    :meth:`flexrv.analysis.budget.Budget.to_dataset`). Written to
    ``save_to`` if given: ``results.nc`` (that dataset), ``stiffness.json``,
    ``config.toml``, the test's own ``summary.md`` and ``hysteresis.png`` (loop with the
    rigidity fit range, lost motion and hysteresis marked).
    """
    import dataclasses
    import json

    from flexrv.model.loads import piecewise_torque
    from flexrv.post.stiffness import (
        evaluate_stiffness_test,
        stiffness_dataset,
        stiffness_json,
        stiffness_summary_markdown,
    )

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
    figures = evaluate_stiffness_test(
        res.time,
        tq,
        angle,
        times[1:],
        friction_power=(res["friction_power"].values if "friction_power" in res.ds else None),
    )
    res.ds = stiffness_dataset(figures, res.time, tq, angle * ARCMIN_PER_RAD, base=res.ds)
    loop = {
        "loop_" + k[: -len("_Nm_per_arcmin")]: v * ARCMIN_PER_RAD
        for k, v in figures.named().items()
        if k.startswith("rigidity_")
    }
    try:
        budget = stiffness_test_budget(reducer, t_r, reference=loop)
        if model != "rigid":
            note = f"budget of the rigid quasi-static model at the test's pose (the loop ran the {model} model)"
            budget = dataclasses.replace(budget, notes=budget.notes + (note,))
        res.ds = budget.merged_into(res.ds)
    except ConvergenceError as exc:  # the figures stand without it
        budget = None
        res.ds.attrs["budget_notes"] = (
            f"stiffness budget not available: the quasi-static equilibrium at +{t_r:g} N m did not converge ({exc})"
        )
    if save_to is not None:
        from flexrv.cache import atomic_path, atomic_write_text
        from flexrv.design import to_toml
        from flexrv.viz.plots import plot_hysteresis

        d = Path(save_to)
        d.mkdir(parents=True, exist_ok=True)
        with atomic_path(d / "results.nc") as tmp:
            res.ds.to_netcdf(tmp, engine="h5netcdf")
        atomic_write_text(d / "config.toml", to_toml(reducer))
        atomic_write_text(
            d / "stiffness.json",
            json.dumps(
                {
                    "preset": reducer.name,
                    "model": model,
                    "quarter_time_s": quarter_time,
                    "dt_s": dt,
                    "figures": stiffness_json(figures),
                    "stiffness_budget": budget.to_dict() if budget is not None else None,
                },
                indent=2,
            ),
        )
        plot_hysteresis(
            angle * ARCMIN_PER_RAD,
            tq,
            d / "hysteresis.png",
            figures=figures,
            title=f"{reducer.name} stiffness test ({model} model)",
        )
        atomic_write_text(
            d / "summary.md",
            stiffness_summary_markdown(
                figures, reducer.name, model, quarter_time, dt, budget=budget.to_dict() if budget is not None else None
            ),
        )
    return figures, res
