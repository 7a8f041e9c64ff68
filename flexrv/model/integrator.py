"""The compiled generalized-alpha integrator of a model whose forces all live in
compiled kernels (the rigid model, the ball-resolved main bearing with rigid or flexible
rings; :func:`compiled_eligible`). The dense diagonal blocks the elements declare (a
bearing row's balls: :func:`flexrv.model.core.registry.dense_blocks`) are eliminated
first in its Newton systems (:mod:`flexrv.model.numerics.block_lu`).

:class:`CompiledIntegrator` drives the generated ``fused_integrate`` of the model's
fused element (:mod:`flexrv.model.core.registry`, the algorithm in
:mod:`flexrv.model.numerics.gen_alpha`): the steps of a segment run in compiled code,
the elements' kernels called at one site (which also serves the element's evaluations
from Python during the run: :meth:`flexrv.model.kernels.FusedForces.drive_with`); the
drive and the loads (Python callables of time) enter as tables of the elements' time
inputs at the step ends, evaluated vectorised once per call
(:meth:`~flexrv.model.base.KernelGroup.time_inputs_many`).
The elements' compiled per-step checks (``step_check``: a skipped pin, a penetration
beyond the physical limit) run in the loop after every accepted step, as the Exudyn
path's pre-step hook runs the groups' checks; the compiled loop returns to Python every
``check_every`` steps (the caller's remaining checks, signals, progress).

Time stepping as Exudyn's adaptive step (its settings of flexrv.simulation): t += h,
the last step of a segment clipped to its end; a step whose Newton iteration fails is
retried from its start at half the step (down to :data:`MIN_SUBSTEP` of it), and the
step doubles again, up to the nominal one, after :data:`RECOVERY_STEPS` accepted steps
of at most :data:`RECOVERY_ITERATIONS` Newton iterations (Exudyn's defaults); a state is
recorded when its time is at least ``output_every`` dt after the last record, as the
Exudyn path's pre-step hook does. So both integrators take the same steps.
"""

from __future__ import annotations

import numpy as np

from flexrv.errors import InputError
from flexrv.model.core.registry import INTEGRATE, dense_blocks
from flexrv.model.numerics import gen_alpha
from flexrv.model.numerics.block_lu import block_structure

#: Exudyn Newton settings the compiled integrator honours (name -> keyword of gen_alpha.new_state)
NEWTON_OPTIONS = {
    "modifiedNewtonContractivity": "contractivity",
    "maxIterations": "max_iterations",
    "maxModifiedNewtonIterations": "max_modified",
    "adaptInitialResidual": "adapt_initial_residual",
    "modifiedNewtonJacUpdatePerStep": "jacobian_each_step",
    "extrapolatedPredictor": "extrapolate",
    "partialJacobian": "partial_jacobian",
}

#: the compiled integrator's own Newton options (not Exudyn settings) and their defaults.
#: ``extrapolatedPredictor``: a step's predictor moved by the previous step's Newton correction
#: (:mod:`flexrv.model.numerics.gen_alpha`); False: Exudyn's predictor, the same steps and Newton
#: iterations as Exudyn's integrator. ``partialJacobian``: where an element's Jacobian is costly (the
#: bearing rows with condensed rings: the flexible-ring model), it is kept and the other elements'
#: refreshed at every step (gen_alpha's partial Jacobians; :func:`partial_jacobians`); False: every
#: element's Jacobian at every step or, with a kept matrix, when the contraction test asks, as Exudyn's
#: modified Newton
COMPILED_ONLY_OPTIONS = {"extrapolatedPredictor": True, "partialJacobian": True}

#: smallest reduced step, as a fraction of the nominal step (flexrv.simulation sets Exudyn's
#: minimumStepSize to 1e-3 dt)
MIN_SUBSTEP = 1e-3
#: accepted steps before a reduced step doubles, and the most Newton iterations (+1, Exudyn counts
#: its one discontinuous iteration) of the last of them (Exudyn's adaptiveStepRecoverySteps and
#: adaptiveStepRecoveryIterations defaults)
RECOVERY_STEPS = 10
RECOVERY_ITERATIONS = 7

#: status codes of fused_integrate -> failure text
_STATUS = {
    1: "Newton iteration failed at the minimum step",
    3: "the state became NaN/inf",
    4: "a force element's per-step check failed",
}


def compiled_eligible(model) -> str | None:
    """None if ``model`` can run on the compiled integrator, else the reason: a group
    outside the fused kernel (a Python group: the flexible crankshaft), a coordinate
    outside it, or a group with a per-step hook."""
    from flexrv.model.base import ForceGroup

    fused = model.fused
    if fused is None:
        return "the model has no compiled force elements"
    if fused.others:
        names = ", ".join(g.name for g in fused.others)
        return f"its force groups {names} are Python groups (not compiled kernels)"
    if fused.n != model.n or not np.array_equal(fused.index, np.arange(model.n)):
        return "some coordinates are not coupled by the compiled force elements"
    hooked = [g.name for g in model.groups if type(g).new_step is not ForceGroup.new_step]
    if hooked:
        return f"its groups {', '.join(hooked)} need a per-step hook"
    return None


def partial_jacobian_allowed(fused, blocks) -> bool:
    """True if a costly element (``costly_jacobian``) is present and the fused element's cheap
    elements act on no coordinate of the dense ``blocks`` [(start, size), ...]: the condition of
    gen_alpha's partial Jacobians (with a kept matrix only the Schur complement changes)."""
    _, outside = block_structure(fused.n, blocks)
    costly = [getattr(g, "costly_jacobian", False) for g, _ in fused.slots]
    cheap = [fused.index[idx] for (g, idx), c in zip(fused.slots, costly) if not c]
    return any(costly) and all(np.isin(ix, outside).all() for ix in cheap)


def partial_jacobians(model) -> bool:
    """True if the compiled integrator of ``model`` runs with partial Jacobians by default
    (:func:`partial_jacobian_allowed` for its fused element and dense blocks)."""
    return model.fused is not None and partial_jacobian_allowed(model.fused, dense_blocks(model))


def compiled_newton_options(options: dict | None) -> dict:
    """The gen_alpha keywords of Exudyn-named Newton ``options``; an option the compiled
    integrator does not honour is an InputError naming it and the allowed ones."""
    out = {NEWTON_OPTIONS[k]: v for k, v in COMPILED_ONLY_OPTIONS.items()}
    for key, value in (options or {}).items():
        if key not in NEWTON_OPTIONS:
            raise InputError(
                f"newton_options {key!r} is not allowed with the compiled integrator: choose from "
                f"{', '.join(NEWTON_OPTIONS)}, relativeTolerance, absoluteTolerance (or --integrator exudyn)"
            )
        out[NEWTON_OPTIONS[key]] = value
    return out


class CompiledIntegrator:
    """The compiled generalized-alpha of ``model`` (module docstring).

    ``tolerance``: (relative, absolute) Newton tolerance; ``newton``: gen_alpha keywords
    (:func:`compiled_newton_options`)."""

    def __init__(self, model, spectral_radius: float, tolerance, newton: dict | None = None):
        reason = compiled_eligible(model)
        if reason is not None:
            raise InputError(f"integrator = 'compiled' is not allowed for the {model.name} model: {reason}")
        self.model = model
        self.fused = fused = model.fused
        stiff = np.zeros((model.n, model.n))
        damp = np.zeros((model.n, model.n))
        mass = np.zeros((model.n, model.n))
        for m in model.members.values():
            s = slice(m.offset, m.offset + m.n)
            mass[s, s] = m.mass_matrix
            if m.stiffness_matrix is not None:
                stiff[s, s] = m.stiffness_matrix
            if m.damping_matrix is not None:
                damp[s, s] = m.damping_matrix
        newton = dict(newton or {})
        newton["partial_jacobian"] = newton.get("partial_jacobian", False) and partial_jacobians(model)
        self.state = gen_alpha.new_state(
            mass,
            stiff,
            damp,
            spectral_radius=spectral_radius,
            tolerance=tuple(tolerance),
            blocks=dense_blocks(model) or None,
            **newton,
        )
        #: the state's dense blocks, or None without (the block elimination is then not compiled in)
        self.blocks = self.state.blocks if self.state.blocks.shape[0] else None
        fused.drive_with(self.state, self.blocks)  # the element's evaluations from Python: the same entry point
        self.massless = any(not np.any(np.diag(m.mass_matrix)) for m in model.members.values())
        self.timed = [(i, g) for i, (g, _) in enumerate(fused.slots) if g.time_field]
        #: the groups whose per-step check runs in the compiled loop after every accepted step
        self.checked = [g for g, _ in fused.slots if getattr(type(g), "step_check", None) is not None]
        ctrs = [c for _, c in fused.counters]
        self.ctrs = tuple(ctrs) if ctrs else (np.zeros(1, np.int64),)
        #: the compiled entry points of fused_integrate for this model's argument types, by the
        #: record arrays' kinds (skips numba's typing of the ~60 arguments, ~10 ms, on every call;
        #: valid while the types stay: every array :meth:`_call` passes is a fresh or fixed
        #: float64/int64/bool C-contiguous array of fixed dimension), kept on the model's fused
        #: element for the integrators of its later runs
        self._entry = fused.__dict__.setdefault("integrate_entries", {})
        self._src, self._key = None, None
        #: steps of the nominal size per compiled call (the caller's checks run in between)
        self.check_every = 10

    # ------------------------------------------------------------------ state
    def start(self, t: float, q, v, a=None) -> None:
        """Start (or restart at a segment boundary) from (q, v, a); a None: the initial
        accelerations M^-1 f(t, q, v) (zero for a model with massless coordinates)."""
        for g in self.model.groups:
            g.reset()
        if a is None:
            a = np.zeros(self.model.n)
            if not self.massless:
                f, _, _ = self.fused.full(
                    float(t), np.ascontiguousarray(q, float), np.ascontiguousarray(v, float), False
                )
                a = np.linalg.solve(self.state.mass, f - self.state.stiff @ q - self.state.damp @ v)
        gen_alpha.set_state(self.state, q, v, a)

    @property
    def q(self) -> np.ndarray:
        return self.state.q

    @property
    def v(self) -> np.ndarray:
        return self.state.v

    @property
    def a(self) -> np.ndarray:
        return self.state.a

    def counts(self) -> dict:
        ip = self.state.ip
        return {
            "newton": int(ip[gen_alpha.I_NEWTON]),
            "jacobians": int(ip[gen_alpha.I_JACOBIANS]),
            "partial_jacobians": int(ip[gen_alpha.I_PARTIALS]),
            "calls": int(ip[gen_alpha.I_CALLS]),
            "jacobian_calls": int(ip[gen_alpha.I_JACCALLS]),
        }

    # ------------------------------------------------------------------ stepping
    def segment(self, t0: float, t1: float, h: float, rec, out, after_call) -> tuple[int, float]:
        """Integrate from the current state at ``t0`` to ``t1`` with nominal step ``h`` (module
        docstring). Steps of the nominal size run :attr:`check_every` at a time in compiled
        code (their time inputs evaluated once from the start or the return to the nominal
        step), reduced ones up to the next test for doubling the step. ``rec`` (int64: next row, rows, segment end not
        recorded), ``rec_t`` inside ``out``: the recording state of ``fused_integrate``;
        ``after_call(t, steps)`` runs after every compiled call (checks, signals, progress) and
        returns True to stop. Returns (status, time reached): 0 done, -1 stopped by
        ``after_call``, else the failure status of ``fused_integrate``."""
        t, step, since = t0, h, 0
        end_recorded = rec[2]
        grid, at = None, 0  # the nominal steps' end times and time inputs from the last (re)start, the next one
        while t < t1 - 1e-10:
            if step == h:
                if grid is None:
                    grid, at = self._grid(t, t1, h), 0
                stop = min(at + self.check_every, len(grid[0]))
                times, tables = grid[0][at:stop], [tb[at:stop] for tb in grid[1]]
            else:
                grid = None
                times = self._times(t, step, max(RECOVERY_STEPS - since, 1))
                last = np.nonzero(times >= t1 - 1e-10)[0]
                if len(last):
                    times = times[: last[0] + 1]
                    times[-1] = t1  # (clipped, or a sum's round-off off the end)
                tables = self.tables(times)
            rec[2] = end_recorded if times[-1] >= t1 - 1e-10 else 0
            done, status = self._call(times, t, out, rec, tables)
            at += done
            if done:
                t = float(times[done - 1])
                since += done
            if status == 1 and step > MIN_SUBSTEP * h * (1 + 1e-9):  # the failed step again at half the step
                self._restore()
                step, since = max(0.5 * step, MIN_SUBSTEP * h), 0
            elif status != 0:
                return status, t
            elif step < h and since >= RECOVERY_STEPS and self.state.ip[gen_alpha.I_IT] + 1 <= RECOVERY_ITERATIONS:
                step, since = min(2.0 * step, h), 0
            if after_call(t, done):
                return -1, t
        return 0, t

    @staticmethod
    def _times(t: float, step: float, n: int) -> np.ndarray:
        """The end times of ``n`` steps of ``step`` from ``t``, summed one by one (t += step, as
        the steps are taken one at a time)."""
        return np.cumsum(np.concatenate(([t], np.full(n, step))))[1:]

    def _grid(self, t0: float, t1: float, h: float) -> tuple:
        """(end times t0 + h, t0 + 2 h, ... of the nominal steps up to t1, the last clipped to t1,
        their time inputs): one vectorised evaluation per segment (or per return to the nominal
        step) instead of one per compiled call."""
        times = self._times(t0, h, max(int(np.ceil((t1 - t0) / h - 1e-9)), 1))
        times[-1] = t1
        return times, self.tables(times)

    def tables(self, times: np.ndarray) -> list:
        """The time inputs of the timed elements at ``times`` (one row per time)."""
        return self.fused.time_tables(times)

    def _restore(self) -> None:
        """The state at the start of a failed step, for its retry at a smaller step. As
        Exudyn's step reduction: q, v, a restored, the algorithmic accelerations left at the
        failed attempt's predictor value a* (Exudyn restores them in its Newton restart,
        not for a step retry; with alpha_m = 0, a* = alpha_f a_n)."""
        st = self.state
        st.q[:], st.v[:], st.a[:] = st.q0, st.v0, st.a0

    def _call(self, times, t_prev, out, rec, tables) -> tuple[int, int]:
        fused = self.fused
        ts, qs, vs, src, dst, valid, rec_t = out
        args = (
            INTEGRATE,
            self.state,
            self.blocks,
            times,
            float(t_prev),
            *tables,
            fused.f,
            fused.jq,
            fused.jv,
            *fused.packs,
            self.ctrs,
            src,
            dst,
            rec,
            rec_t,
            ts,
            qs,
            vs,
            valid,
        )
        if src is not self._src:  # (the argument types differ only in the record buffers, fixed in a run)
            self._src, self._key = src, tuple((a.dtype.char, a.ndim) for a in (*src, *dst))
        entry = self._entry.get(self._key)
        if entry is None:  # the compiled function for these types, called directly from then on
            n, status = fused.integrate_kernel(*args)
            from flexrv.model.kernels import _entry_point

            self._entry[self._key] = _entry_point(fused.integrate_kernel, args)
        else:
            n, status = entry(*args)
        for _, g in self.timed:
            g._time_last = None  # the live time inputs now hold the tables' rows
        fused.memo, fused._jac_ready = None, False
        return int(n), int(status)

    def outputs(self, ts, qs, vs, recorder, interval: float) -> tuple:
        """The output buffers of :meth:`segment`: the run's (ts, qs, vs), the fused
        element's record buffers in ``recorder`` (:class:`flexrv.model.kernels.HistoryRecorder`,
        or None: dummies) and ``rec_t`` = (time of the last record, recording interval)."""
        rec_t = np.array([-np.inf, interval])
        if recorder is not None:
            for i, (element, _, _, src, dst) in enumerate(recorder.sources):
                if element is self.fused:
                    return ts, qs, vs, src, dst, recorder.valid[i], rec_t
        return ts, qs, vs, (np.zeros(0),), (np.zeros((len(ts), 0)),), np.zeros(len(ts), bool), rec_t

    def failure(self, status: int) -> str:
        """The failure text of a status of :meth:`advance`."""
        if status == 2:
            for g, c in self.fused.counters:
                return g.failure_message
        if status == 4:  # the groups' checks name the failure (the same conditions as their step_check)
            for g in self.checked:
                msg = g.check()
                if msg:
                    return msg
        return _STATUS.get(status, f"compiled integrator status {status}")
