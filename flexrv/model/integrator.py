"""The compiled generalized-alpha integrator of a model whose forces all live in
compiled kernels (the rigid model; :func:`compiled_eligible`).

:class:`CompiledIntegrator` drives the generated ``fused_integrate`` of the model's
fused element (:mod:`flexrv.model.core.registry`, the algorithm in
:mod:`flexrv.model.numerics.gen_alpha`): the steps of a segment run in compiled code,
the fused kernel called at one site; the drive and the loads (Python callables of
time) enter as tables of the elements' time inputs at the step ends, evaluated
vectorised once per call (:meth:`~flexrv.model.base.KernelGroup.time_inputs_many`).
The compiled loop returns to Python every ``check_every`` steps, where the groups'
per-step checks run on the last accepted state (a skipped pin, a penetration beyond
the physical limit) as in the Exudyn path's pre-step hook.

A step whose Newton iteration fails is repeated from its start in two halves (each
half again halved on failure, down to 1e-3 of the step): Exudyn's adaptive step
reduction, except that the nominal step is taken again right after the failed
interval (Exudyn keeps the reduced step for ten steps), so every output stays on the
grid j dt.
"""

from __future__ import annotations

import numpy as np

from flexrv.errors import InputError
from flexrv.model.numerics import gen_alpha

#: Exudyn Newton settings the compiled integrator honours (name -> keyword of gen_alpha.new_state)
NEWTON_OPTIONS = {
    "modifiedNewtonContractivity": "contractivity",
    "maxIterations": "max_iterations",
    "maxModifiedNewtonIterations": "max_modified",
    "adaptInitialResidual": "adapt_initial_residual",
}

#: smallest sub-step of a failed step, as a fraction of the step (Exudyn's minimumStepSize = 1e-3 dt)
MIN_SUBSTEP = 1e-3

#: status codes of fused_integrate -> failure text
_STATUS = {
    1: "Newton iteration failed (step reduced to its minimum)",
    3: "the state became NaN/inf",
}


def compiled_eligible(model) -> str | None:
    """None if ``model`` can run on the compiled integrator, else the reason: a group
    outside the fused kernel (a Python group: balls, flexible rings, flexible crank), a
    coordinate outside it, or a group with a per-step hook."""
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


def compiled_newton_options(options: dict | None) -> dict:
    """The gen_alpha keywords of Exudyn-named Newton ``options``; an option the compiled
    integrator does not honour is an InputError naming it and the allowed ones."""
    out = {}
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
        self.state = gen_alpha.new_state(
            mass, stiff, damp, spectral_radius=spectral_radius, tolerance=tuple(tolerance), **(newton or {})
        )
        self.massless = any(not np.any(np.diag(m.mass_matrix)) for m in model.members.values())
        self.timed = [(i, g) for i, (g, _) in enumerate(fused.slots) if g.time_field]
        ctrs = [c for _, c in fused.counters]
        self.ctrs = tuple(ctrs) if ctrs else (np.zeros(1, np.int64),)
        #: the compiled entry point of fused_integrate for this model's argument types (skips numba's
        #: typing of the ~60 arguments, ~100 us per call; valid while the types stay: every array passed
        #: is float64/int64/bool C-contiguous, checked in :meth:`_call`'s callers)
        self._entry = None

    # ------------------------------------------------------------------ state
    def start(self, t: float, q, v, a=None) -> None:
        """Start (or restart at a segment boundary) from (q, v, a); a None: the initial
        accelerations M^-1 f(t, q, v) (zero for a model with massless coordinates)."""
        if a is None:
            a = np.zeros(self.model.n)
            if not self.massless:
                f, _, _ = self.fused.full(
                    float(t), np.ascontiguousarray(q, float), np.ascontiguousarray(v, float), False
                )
                a = np.linalg.solve(self.state.mass, f - self.state.stiff @ q - self.state.damp @ v)
        gen_alpha.set_state(self.state, q, v, a)
        for g in self.model.groups:
            g.reset()

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
            "calls": int(ip[gen_alpha.I_CALLS]),
            "jacobian_calls": int(ip[gen_alpha.I_JACCALLS]),
        }

    # ------------------------------------------------------------------ stepping
    def advance(self, times: np.ndarray, t_prev: float, rows: np.ndarray, out, tables=None) -> tuple[int, int]:
        """Integrate over the steps ending at ``times`` from the current state at
        ``t_prev``; ``rows``: output row per step (-1: none), ``out``: (ts, qs, vs, src,
        dst, valid) (:meth:`outputs`), ``tables``: :meth:`tables` of ``times`` (computed if
        None). Returns (steps done, status) as ``fused_integrate``, after repeating failed
        steps in halves (module docstring)."""
        if tables is None:
            tables = self.tables(times)
        done = 0
        while done < len(times):
            n, status = self._call(
                times[done:],
                t_prev if done == 0 else times[done - 1],
                rows[done:],
                out,
                [tb[done:] for tb in tables],
            )
            done += n
            if status != 1:
                return done, status
            t0 = t_prev if done == 0 else times[done - 1]
            if not self._substeps(t0, times[done], rows[done], out, 2):
                return done, 1
            done += 1
        return done, 0

    def tables(self, times: np.ndarray) -> list:
        """The time inputs of the timed elements at ``times`` (one row per time)."""
        out = []
        for i, g in self.timed:
            size = getattr(self.fused.packs[i], g.time_field).size
            out.append(np.ascontiguousarray(np.broadcast_to(g.time_inputs_many(times), (len(times), size))))
        return out

    def _substeps(self, t0: float, t1: float, row: int, out, parts: int) -> bool:
        """The failed step (t0, t1] in ``parts`` equal sub-steps from its start state
        (each failing one halved again); the end state into output ``row``."""
        if (t1 - t0) / parts < MIN_SUBSTEP * self.nominal:
            return False
        self._restore()
        sub = t0 + (t1 - t0) * np.arange(1, parts + 1) / parts
        sub[-1] = t1
        rows = np.full(parts, -1, np.int64)
        rows[-1] = row
        done = 0
        while done < parts:
            n, status = self._call(
                sub[done:], t0 if done == 0 else sub[done - 1], rows[done:], out, self.tables(sub[done:])
            )
            done += n
            if status == 0:
                return True
            if status != 1:
                return False
            start = t0 if done == 0 else sub[done - 1]
            if not self._substeps(start, sub[done], rows[done], out, 2):
                return False
            done += 1
        return True

    def _restore(self) -> None:
        st = self.state
        st.q[:], st.v[:], st.a[:], st.aa[:] = st.q0, st.v0, st.a0, st.aa0

    def _call(self, times, t_prev, rows, out, tables) -> tuple[int, int]:
        fused = self.fused
        ts, qs, vs, src, dst, valid = out
        args = (
            self.state,
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
            rows,
            ts,
            qs,
            vs,
            valid,
        )
        if self._entry is None:  # the compiled function for these types, called directly from then on
            n, status = fused.integrate_kernel(*args)
            from flexrv.model.kernels import _entry_point

            self._entry = _entry_point(fused.integrate_kernel, args)
        else:
            n, status = self._entry(*args)
        for _, g in self.timed:
            g._time_last = None  # the live time inputs now hold the tables' rows
        fused.memo, fused._jac_ready = None, False
        return int(n), int(status)

    #: nominal step of the run (for the smallest sub-step), set by the caller
    nominal: float = 1.0

    def outputs(self, ts, qs, vs, recorder) -> tuple:
        """The output buffers of :meth:`advance`: the run's (ts, qs, vs) and the fused
        element's record buffers in ``recorder`` (:class:`flexrv.model.kernels.HistoryRecorder`,
        or None: dummies)."""
        if recorder is not None:
            for i, (element, _, _, src, dst) in enumerate(recorder.sources):
                if element is self.fused:
                    return ts, qs, vs, src, dst, recorder.valid[i]
        return ts, qs, vs, (np.zeros(0),), (np.zeros((len(ts), 0)),), np.zeros(len(ts), bool)

    def failure(self, status: int) -> str:
        """The failure text of a status of :meth:`advance`."""
        if status == 2:
            for g, c in self.fused.counters:
                return g.failure_message
        return _STATUS.get(status, f"compiled integrator status {status}")
