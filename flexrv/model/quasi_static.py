"""Quasi-static loaded transmission error: static equilibrium of the reducer at a
sequence of input positions.

For every input angle theta_in the coordinates q of the carrier, the cranks
(with their planets) and the discs are found such that every generalized force
of the model's force groups sums to zero,

    R(q; theta_in, T) = sum_groups Q_g(q, v = 0; theta_in) = 0,

with the output torque T on the carrier (the ``loads`` group) and the sun's
angle prescribed. The groups are the SAME objects as in the dynamic model
(:func:`flexrv.model.factory.build_rigid` with ``exudyn=False`` and the
``position`` drive, in which the model's "time" argument is the input angle): the
same pin gaps, Hertz/Palmgren laws, needle bearings, crank supports, gear meshes
and main bearing, each with its own parameters built from the design (the element's
``parameters``; the shared ones: :func:`flexrv.model.drive.drive_parameters`). At zero velocity the
damping terms vanish, so this is the dynamic model's equilibrium manifold.

Solver: Newton's method on R with the groups' analytic Jacobians
(:meth:`flexrv.model.assembled.AssembledModel.generalized_forces`, one compiled
call; complete for the pins and gear meshes, and within 1e-6 of (extrapolated)
central differences for the whole rigid model at its equilibria, so no
finite-difference Jacobian is needed: tests/test_quasi_static.py), globalised by
pseudo-transient continuation (Kelley & Keyes 1998 :cite:`kelley1998ptc`): each
step solves (s M - J) dq = R with the members' mass matrix M as the metric, so a
step through a clearance, where J is singular, becomes an over-damped motion
towards contact, and near the solution the iteration is Newton's (details and
the fallbacks for contacts at their onset in :meth:`StaticModel.solve`). Successive positions are warm-started from the
kinematic pose plus the deviation from it extrapolated from the two previous solutions
(:func:`equilibrium_path`: 1.7 Newton iterations per position on rv40e, 1.1 on rv221); the
solver's per-iteration arithmetic is compiled (:mod:`flexrv.model.numerics.static_step`). The
no-load curve starts each position from its image one crank revolution earlier and, for a design
without manufacturing errors, evaluates only a sample of those starts (:func:`equilibrium_path`,
``check_every``).

Transmission error TE = theta_out - theta_in / i. Definitions used for the
catalog quantities (Nabtesco-style catalogs define lost motion at +-3 % of the
rated torque):

* no-load (kinematic) TE: the TE curve at a small torque T0 =
  ``no_load_fraction`` (default 1e-2) of the rated torque, where the contacts
  are just closed. It contains the elastic part at T0, which falls like T0^0.9
  (Palmgren line contact): a single pin moved tangentially by t raises the
  kinematic TE by t / R_p (1 - 1/i) while it is the first contact, and the
  no-load curve shows 65 % and 96.7 % of that at fractions 1e-2 and 1e-3
  (tests/test_quasi_static.py; 76 %, 97.5 % and 99.7 % at 1e-2, 1e-3 and 1e-4
  with the stiffer pin law without the pin seats). Smaller fractions are more exact but
  converge poorly (many contacts sit at the onset kink of their laws, and the
  cranks' load sharing inside their clearances becomes indeterminate: an
  extrapolation to T -> 0 from two such paths amplified that indeterminacy into
  spurious spikes, so it is not used). The same indeterminacy makes the no-load
  path itself path-dependent where several cranks could carry the small torque:
  rv221 over one crank revolution at 8 points per mesh follows, for positions
  18-23, a neighbouring equilibrium 3-5 arcsec away (converged, residual within
  tolerance), so its no-load p-p reads 6.1 arcsec against 2.0 over a whole output
  revolution; the loaded curve is unique;
* backlash: output rotation between +T0 and -T0 at T0 = ``no_load_fraction`` of
  the rated torque, input locked;
* lost motion: output rotation between +3 % and -3 % of rated torque, input locked;
* torsional rigidity at the operating torque: the tangent dT/dtheta_out from the
  condensed Jacobian, mean over the positions; catalog-style secant slope between
  50 % and 100 % rated torque at the lost-motion positions, and the low-torque
  secant between 3 % and 50 % rated (the stiffness test's low-torque range,
  :mod:`flexrv.post.stiffness`);
* compliance budget: each force group's share of the torsional compliance at the
  operating torque (strain-energy fractions, :meth:`StaticModel.compliance_budget`).
"""

from __future__ import annotations

import math
import time as _time
from dataclasses import dataclass, field

import numpy as np

from flexrv.errors import ConvergenceError, InputError
from flexrv.model.numerics.static_step import (
    largest_stiffness_per_mass,
    scaled_norms,
    shifted_newton_step,
    turned_deviation,
    work_arrays,
)
from flexrv.units import ARCMIN_PER_RAD, ARCSEC_PER_RAD


@dataclass(frozen=True)
class StaticOptions:
    """Options of the static equilibrium iteration (unknown keys are rejected by
    :meth:`from_dict`).

    force_tol : residual tolerance [N] on force coordinates, relative to the
        characteristic force T_ref / a_w (T_ref: rated torque, a_w: crank circle).
    step_tol : coordinate-step tolerance [m, rad].
    max_iter : iterations per position before giving up.
    """

    force_tol: float = 1e-6
    step_tol: float = 1e-12
    max_iter: int = 100

    @classmethod
    def from_dict(cls, options: dict | None) -> "StaticOptions":
        options = dict(options or {})
        known = set(cls.__dataclass_fields__)
        unknown = sorted(set(options) - known)
        if unknown:
            raise InputError(f"unknown static-solver option(s) {unknown}: allowed {sorted(known)}")
        out = cls(**options)
        if not (0 < out.force_tol < 1e-2 and 0 < out.step_tol < 1e-6 and 1 <= out.max_iter <= 1000):
            raise InputError(
                f"static-solver options {out} out of range: 0 < force_tol < 1e-2, "
                "0 < step_tol < 1e-6, 1 <= max_iter <= 1000"
            )
        return out


class StaticModel:
    """The reducer's force groups without inertia, for static equilibria.

    ``torque`` [N m] is the load torque on the output (positive against the
    input's direction of rotation, as in the dynamic model)."""

    def __init__(self, reducer, options: StaticOptions | dict | None = None):
        from flexrv.model.factory import build_model

        self.reducer = reducer
        self.options = options if isinstance(options, StaticOptions) else StaticOptions.from_dict(options)
        self._torque = [0.0]
        self.model = build_model(
            reducer, "rigid", drive="position", exudyn=False, torque=lambda t: np.full(np.shape(t), self._torque[0])
        )
        m = self.model
        self.p = m.params
        self.n = m.n
        self.mass = np.concatenate([np.diag(mem.mass_matrix) for mem in m.members.values()])
        cs = m.slice("carrier")
        self.i_theta = cs.start + 2  # the carrier's rotation = output angle
        self.t_ref = max(abs(reducer.operating.rated_torque_Nm), 1.0)
        self.f_ref = self.t_ref / self.p.center_distance
        # residual scale per coordinate: forces [N] and moments [N m] -> comparable numbers
        lengths = np.ones(self.n)
        for mem in m.members.values():
            sl = m.slice(mem.name)
            for k, lab in enumerate(mem.labels):
                if lab in ("theta", "phi", "psi", "rx", "ry"):
                    lengths[sl.start + k] = self.p.center_distance
        self.arm = lengths  # moment = force * arm
        #: largest coordinate step per iteration [m on the crank circle]
        self.max_step = 50e-6
        #: an exact Newton step below this [m on the crank circle] ends the iteration (3e-9 rad
        #: of output rotation on rv40e, 6e-4 arcsec)
        self.position_tol = 1e-10
        self.calls = 0
        #: (input angle, q) of the last residual call (a reference: the solver never changes its arrays)
        self.last = None
        #: work arrays of the compiled Newton step
        self._work = work_arrays(self.n)
        self._zero = np.zeros(self.n)
        #: finite-difference Jacobian in the solver's exact phase (the analytic one is exact; kept
        #: for checks: 20x the residual calls)
        self.fd_fallback = False

    @property
    def torque(self) -> float:
        return self._torque[0]

    @torque.setter
    def torque(self, value: float) -> None:
        self._torque[0] = float(value)
        for g in self.model.groups:  # the loads group caches its force per 'time' (= input angle here)
            if g.name == "loads":
                g.reset()

    def residual(self, theta_in: float, q: np.ndarray, jacobian: bool = True):
        """Generalized force sum R(q) and dR/dq at input angle ``theta_in``."""
        self.calls += 1
        fused = self.model.fused
        if fused is not None and fused.is_full and not fused.others:
            # the fused element holds every force (the rigid model): its call directly, without the
            # velocity Jacobian a static solver never reads
            f, dq, _ = fused.full(theta_in, np.ascontiguousarray(q, dtype=float), self._zero, jacobian, velocity=False)
        else:
            f, dq, _ = self.model.generalized_forces(theta_in, q, self._zero, jacobian=jacobian)
        self.last = (theta_in, q)  # the state the force groups' records belong to (_CurveRecords)
        return f, dq

    def kinematic_pose(self, theta_in) -> np.ndarray:
        """Nominal (conjugate, unloaded) coordinates at input angle(s) [rad], shape
        (..., n): carrier at theta_in / i, each crank carried by the carrier and
        turned by the first stage's relative ratio, discs in the conjugate pose of
        their eccentrics (:func:`flexrv.geometry.cycloid.nominal_disc_pose`:
        centre a (sin chi, cos chi), rotation psi_0 + (chi - chi_0) / z_c)."""
        from flexrv.geometry.kinematics import member_speeds

        p, m = self.p, self.model
        th = np.asarray(theta_in, dtype=float)
        s = member_speeds(1.0, p.z_s, p.z_p, p.z_c, p.z_rp)
        q = np.broadcast_to(m.q0, th.shape + (self.n,)).copy()
        th_c = th * float(s.carrier)
        phi = th_c + th * float(s.crank_relative)  # absolute crank angle
        c, s_ = np.cos(th_c), np.sin(th_c)
        q[..., m.slice("carrier").start + 2] = th_c
        for j in range(p.n_cranks):
            o = m.slice(f"crank{j}").start
            x0, y0 = m.members[f"crank{j}"].q0[:2]
            q[..., o], q[..., o + 1], q[..., o + 2] = c * x0 - s_ * y0, s_ * x0 + c * y0, phi
        for k in range(p.n_discs):
            o = m.slice(f"disc{k}").start
            chi = p.chi0[k] - phi
            q[..., o], q[..., o + 1] = p.eccentricity * np.sin(chi), p.eccentricity * np.cos(chi)
            q[..., o + 2] = p.disc_rot0[k] + (chi - p.chi0[k]) / p.z_c
        return q

    def solve(self, theta_in: float, q_start: np.ndarray) -> tuple[np.ndarray, int]:
        """Static equilibrium at ``theta_in`` from ``q_start``; returns (q, iterations).

        Each iteration solves (s M - J) dq = R (M the members' masses, J = dR/dq):
        Newton's step for s -> 0, an over-damped pseudo-time step for larger s.

        * Acceptance: a step must lower the scaled residual norm |R_i / l_i|_2
          (l_i = 1 for forces, the crank-circle radius a_w for moments); rejected,
          s rises x10 and the step is retried; accepted, s falls x0.1 down to a floor
          of 1e-8 of its start value (which changes steps, never the solution: a
          coordinate whose contacts are all open, e.g. a crank inside its clearances
          at a vanishing torque, keeps a finite step and, its force being zero, stays).
        * Steps are limited to ``max_step`` (50 um on the crank circle), so a contact
          set cannot jump across a clearance in one step.
        * After 12 iterations, two rejections in a row, or a stall (s beyond 1e6 of
          its start: 20 accepted over-damped steps are then taken), the iteration
          continues with exact Newton steps (s at its floor; the analytic Jacobian,
          which is exact, or with ``fd_fallback`` the finite-difference one of
          :meth:`fd_jacobian`, as before the pins' and meshes' Jacobians were
          completed: 20x the residual calls), which may raise the norm below twice
          its largest of the last four values (non-monotone,
          :cite:`grippo1986nonmonotone`), halved after such a rise so that a 2-cycle
          across a contact's onset kink contracts.
        * Convergence: max |R_i / l_i| below ``force_tol`` times T_rated / a_w; or an
          exact Newton step below ``position_tol`` (0.1 nm on the crank circle); or, at
          such a kink, a residual that stagnates, or a best iterate, below 10x the
          tolerance (0.11 N on rv40e: an output-angle error of about 0.11 N x a_w /
          k_t = 4e-9 rad = 0.0008 arcsec with k_t ~ 1e6 N m/rad).

        * The pin gaps' closest points are warm-started; the pins kernel re-finds one
          from cold starts wherever the warm result lies beyond the curve's reach
          (:func:`flexrv.model.pins._curve_reach`). Before that check a warm start could
          track a wrong local minimum after a long excursion (a neighbouring flank, gap
          ~2 mm instead of ~10 um: rv40e with the grade-5 error set at -3 % torque,
          residual 5.5 kN on a cold evaluation of the "converged" state).

        Raises :class:`flexrv.errors.ConvergenceError` otherwise.
        """
        o = self.options
        q = q_start.copy()
        tol = o.force_tol * self.f_ref
        f, jac = self.residual(theta_in, q)
        r, merit = scaled_norms(f, self.arm)
        s0 = self._initial_shift(jac)
        stalls = 0
        shift = 1e-8 * s0  # floor: keeps the step finite for a coordinate whose contacts are all open
        a, piv = self._work
        dq = np.empty(self.n)
        exact = False
        best = (r, q)
        rose = False
        rejected = 0
        history = [merit]
        for it in range(1, o.max_iter + 1):
            if r < tol:
                return q, it - 1
            if exact and len(history) > 8 and r < 10.0 * tol and min(history[-8:]) > 0.99 * history[-9]:
                # stagnated within 10x the tolerance: a contact sits exactly at the onset kink
                # of its law, where Newton cycles across the kink (residual <= 0.01 N)
                return q, it - 1
            if not exact and (it > 12 or stalls or rejected >= 2):
                # slow or stalled: continue with exact Newton steps and non-monotone acceptance
                exact = True
                shift = 1e-8 * s0
                history = [merit]
            if exact and self.fd_fallback:
                jac = self.fd_jacobian(theta_in, q)
            # the step (s M - J)^-1 R, limited to max_step and, if the last step raised the norm,
            # halved (a Newton 2-cycle across a contact's onset kink then contracts onto the kink)
            ok, size, raw = shifted_newton_step(jac, f, shift, self.mass, self.arm, self.max_step, rose, a, piv, dq)
            if ok:
                q_new = q + dq
                f_new, jac_new = self.residual(theta_in, q_new)
                r_new, merit_new = scaled_norms(f_new, self.arm)
                if exact and shift <= 1e-8 * s0 and size < self.position_tol:
                    # the exact Newton step locates the equilibrium to 0.1 nm: at a kink of the
                    # contact laws (a contact at its onset) the residual norm need not fall further
                    return q, it
                # monotone, except for exact Newton steps (no pseudo-time term), which may raise
                # the residual norm for a step or two while the contact set settles (non-monotone
                # acceptance, Grippo, Lampariello & Lucidi 1986 :cite:`grippo1986nonmonotone`):
                # below twice the largest of the last four
                newton = exact and shift <= 1e-8 * s0
                if math.isfinite(merit_new) and (merit_new < merit or newton and merit_new < 2.0 * max(history[-4:])):
                    rose = merit_new > merit
                    q, f, jac, merit, r = q_new, f_new, jac_new, merit_new, r_new
                    history.append(merit)
                    rejected = 0
                    if r < best[0]:
                        best = (r, q)
                    shift = max(0.1 * shift, 1e-8 * s0)
                    if raw < o.step_tol and r < 1e3 * tol:
                        return q, it
                    continue
            rejected += 1
            shift = max(10.0 * shift, s0)
            if shift > 1e6 * s0:
                # stalled at a non-zero local minimum of the residual norm (e.g. a planet inside
                # its backlash, whose free rotation first raises the residual elsewhere):
                # relax along the over-damped motion (s M - J) dq = R, accepting every step
                stalls += 1
                if stalls > 5:
                    break
                for _ in range(20):
                    dq = np.linalg.solve(s0 * np.diag(self.mass) - jac, f)
                    big = np.max(np.abs(dq) * self.arm) / self.max_step
                    q = q + (dq / big if big > 1.0 else dq)
                    f, jac = self.residual(theta_in, q)
                r, merit = scaled_norms(f, self.arm)
                dq = np.empty(self.n)
                history.append(merit)
                shift = 1e-8 * s0
        if best[0] < 10.0 * tol:
            # cycling across a contact's onset kink within 10x the force tolerance: the best
            # iterate locates the equilibrium (see the docstring for the output-angle error)
            return best[1], o.max_iter
        raise ConvergenceError(
            f"static equilibrium at input angle {theta_in:.6g} rad not found in {o.max_iter} "
            f"iterations (residual {min(r, best[0]):.3g} N, tolerance {tol:.3g} N)"
        )

    def fd_jacobian(self, theta_in: float, q: np.ndarray, step: float = 1e-10) -> np.ndarray:
        """dR/dq by central differences (steps ``step`` [m] on the crank circle), for
        checks of the analytic Jacobian and the solver's optional fallback. Its error
        is O(step^2 / delta^2) of a contact's slope where the contact is compressed by
        only delta (the Hertz laws' slope ~ delta^(1/9) bends sharply at the onset)."""
        jac = np.empty((self.n, self.n))
        for i in range(self.n):
            h = step / self.arm[i] if self.arm[i] != 1.0 else step
            e = np.zeros(self.n)
            e[i] = h
            fp, _ = self.residual(theta_in, q + e, jacobian=False)
            fm, _ = self.residual(theta_in, q - e, jacobian=False)
            jac[:, i] = (fp - fm) / (2.0 * h)
        return jac

    def _initial_shift(self, jac) -> float:
        """Pseudo-time weight whose mass term is 1e-3 of the largest stiffness per mass."""
        return 1e-3 * max(largest_stiffness_per_mass(jac, self.mass), 1e6)

    def tangent_rigidity(self, theta_in: float, q: np.ndarray) -> float:
        """Torsional rigidity dT/d(theta_out) [N m/rad] at an equilibrium, input
        locked: the carrier-rotation entry of the inverse (negated) Jacobian."""
        _, jac = self.residual(theta_in, q)
        e = np.zeros(self.n)
        e[self.i_theta] = 1.0
        compliance = np.linalg.solve(-jac, e)[self.i_theta]
        return 1.0 / compliance

    def compliance_budget(self, theta_in: float, q: np.ndarray) -> dict[str, float]:
        """Share of each force group in the torsional compliance at an equilibrium
        (input locked): with the tangent stiffness K = -dR/dq = sum_g K_g and the
        displacement u = K^-1 e_theta under a unit output torque, the compliance is
        C = e_theta . u = u . K u and group g's share is its strain energy
        u . K_g u / C. The shares sum to 1; for elements in series each share is the
        element's part of the total compliance (Castigliano). An elastic carrier or
        disc body condensed into the crank supports or the pins gets its
        own share ``carrier`` / ``cycloid_disc``: df . C df / C with df the group's
        force increment on the body's interface (the support points, the rim) and C
        the body's compliance; the group keeps the rest. The elastic housing condensed
        into the pins (``housing``): c_h dM_h^2 / C, dM_h the pins' torque increment on
        the housing about the axis (1/2 c_h M_h^2 its strain energy)."""
        from flexrv.model.assembled import group_index

        m = self.model
        k_total = np.zeros((self.n, self.n))
        parts = {}
        zero = np.zeros(self.n)
        for g in m.groups:
            idx = np.arange(self.n)[
                group_index([m.members[x].offset for x in g.members], [m.members[x].n for x in g.members])
            ]
            g.new_step()
            jq, _ = g.jacobian(theta_in, q[idx], zero[idx])
            k = np.zeros((self.n, self.n))
            k[np.ix_(idx, idx)] = -jq
            parts[g.name] = k
            k_total += k
        e = np.zeros(self.n)
        e[self.i_theta] = 1.0
        u = np.linalg.solve(k_total, e)
        c = float(u[self.i_theta])
        out = {name: float(u @ k @ u) / c for name, k in parts.items()}
        # elastic bodies condensed into a group: their strain energy split out of it. With the
        # group's condensed force increment df = -K_g u on the body's interface, the body stores df.C.df
        # (series element: its part of u.K_g.u), the contact/bearing the rest.
        for g in m.groups:
            if g.name == "crank_supports" and getattr(g, "elastic_carrier", False):
                df = np.concatenate([-(parts[g.name] @ u)[m.slice(f"crank{j}")][:2] for j in range(g.n)])
                th = float(q[self.i_theta])
                c_, s_ = np.cos(th), np.sin(th)
                rot = np.kron(np.eye(g.n), np.array([[c_, -s_], [s_, c_]]))
                e_body = float(df @ (rot @ g.carrier_c @ rot.T) @ df) / c
                out["carrier"] = e_body
                out[g.name] -= e_body
                for part, cm in g.params.carrier_parts.items():  # rings, joints: their own shares of it
                    out[part] = float(df @ (rot @ cm @ rot.T) @ df) / c
                    out["carrier"] -= out[part]
            if g.name == "pins" and getattr(g, "elastic_discs", False):
                e_body = 0.0
                for k in range(g.nd):
                    dq = -(parts[g.name] @ u)[m.slice(f"disc{k}")]
                    e_body += float(dq @ g.disc_c[k] @ dq) / c
                out["cycloid_disc"] = e_body
                out[g.name] -= e_body
            if g.name == "pins" and getattr(g, "elastic_housing", False):
                # the housing (flexrv.model.pins, "Housing"): the rim compliance's c_h A A^T part stores
                # c_h dM_h^2, dM_h = -sum_k a_k . dQ_k the pins' torque increment on the housing
                dm_h = 0.0
                for k in range(g.nd):
                    qk = q[m.slice(f"disc{k}")]
                    dq = -(parts[g.name] @ u)[m.slice(f"disc{k}")]
                    dm_h -= float(-qk[1] * dq[0] + qk[0] * dq[1] + dq[2])
                e_h = float(g.hstate[0]) * dm_h**2 / c
                out["housing"] = e_h
                out[g.name] -= e_h
        return out


@dataclass
class LoadedTE:
    """Result of :func:`loaded_te` (SI; outputs declared with units in ``outputs``)."""

    input_angle: np.ndarray  #: (P,) [rad]
    output_angle: np.ndarray  #: (P,) [rad]
    te: np.ndarray  #: (P,) loaded TE [rad]
    te_no_load: np.ndarray  #: (P,) [rad]
    torque: float
    ratio: float
    outputs: dict  #: name -> flexrv.model.base.Output over the positions (dims start with "position")
    catalog: dict  #: lost motion, backlash, rigidities (SI)
    iterations: np.ndarray
    solve_time_s: float
    orders: dict = field(default_factory=dict)  #: characteristic orders per output revolution
    no_load_torque: float = 0.0  #: torque of the no-load curve and the backlash [N m]
    #: process CPU [s] of each phase: model, load_ramp, loaded_curve, no_load_curve, outputs, catalog
    timing: dict = field(default_factory=dict)

    def summary(self) -> dict:
        """Headline numbers in engineering units (keys name their unit)."""
        te = self.te * ARCSEC_PER_RAD
        nl = self.te_no_load * ARCSEC_PER_RAD
        c = self.catalog
        return {
            "te_pp_arcsec": float(np.nanmax(te) - np.nanmin(te)) if te.size else float("nan"),
            "te_mean_arcsec": float(np.nanmean(te)) if te.size else float("nan"),
            "no_load_te_pp_arcsec": float(np.nanmax(nl) - np.nanmin(nl)) if nl.size else float("nan"),
            "unconverged_positions": int(np.sum(~np.isfinite(te)) + np.sum(~np.isfinite(nl))),
            "lost_motion_arcmin": c["lost_motion_rad"] * ARCMIN_PER_RAD,
            "backlash_arcmin": c["backlash_rad"] * ARCMIN_PER_RAD,
            "torsional_rigidity_Nm_per_arcmin": c["rigidity_tangent_Nm_per_rad"] / ARCMIN_PER_RAD,
            "catalog_rigidity_Nm_per_arcmin": c["rigidity_secant_Nm_per_rad"] / ARCMIN_PER_RAD,
            "low_torque_rigidity_Nm_per_arcmin": c.get("rigidity_low_Nm_per_rad", float("nan")) / ARCMIN_PER_RAD,
            "compliance_budget_percent": {g: 100.0 * v for g, v in c["compliance_budget"].items() if v > 1e-6},
            "torque_Nm": self.torque,
            "no_load_torque_Nm": self.no_load_torque,
            "positions": int(self.te.size),
            "solve_time_s": self.solve_time_s,
            "mean_iterations": float(np.mean(self.iterations[self.iterations >= 0])) if self.iterations.size else 0.0,
        }


def characteristic_orders(reducer) -> dict[str, float]:
    """Orders (cycles per output revolution) of the reducer's characteristic
    frequencies (:func:`flexrv.geometry.kinematics.characteristic_frequencies`
    divided by the output frequency)."""
    from flexrv.geometry.kinematics import characteristic_frequencies

    fs, ss = reducer.first_stage, reducer.second_stage
    f = characteristic_frequencies(1.0, fs.sun_teeth, fs.planet_teeth, ss.disc_teeth, ss.pin_count)
    out = float(f.carrier)
    return {
        "crank rotation": float(f.crank_rotation) / out,
        "crank, absolute": float(f.crank_absolute) / out,
        "cycloid mesh": float(f.cycloid_mesh) / out,
        "first-stage mesh": float(f.first_stage_mesh) / out,
        "input rotation": float(f.input) / out,
    }


def positions_for(
    reducer, output_revolutions: float | None = None, crank_revolutions: float | None = None, points_per_mesh: int = 8
) -> np.ndarray:
    """Input angles [rad] covering the requested range with ``points_per_mesh``
    points per cycloid-mesh period (the pin-mesh period of the TE ripple).
    ``crank_revolutions`` counts crank revolutions relative to the carrier."""
    if points_per_mesh < 2 or points_per_mesh > 1000:
        raise InputError(f"points_per_mesh = {points_per_mesh} is not allowed: must lie in [2, 1000]")
    orders = characteristic_orders(reducer)
    if (output_revolutions is None) == (crank_revolutions is None):
        if output_revolutions is None:
            output_revolutions = 1.0
        else:
            raise InputError("give either output_revolutions or crank_revolutions, not both")
    if crank_revolutions is not None:
        if not (math.isfinite(crank_revolutions) and 0 < crank_revolutions <= 1e4):
            raise InputError(f"crank_revolutions = {crank_revolutions!r} is not allowed: must lie in (0, 1e4]")
        output_revolutions = crank_revolutions / orders["crank rotation"]
    if not (math.isfinite(output_revolutions) and 0 < output_revolutions <= 100):
        raise InputError(f"output_revolutions = {output_revolutions!r} is not allowed: must lie in (0, 100]")
    n = int(round(output_revolutions * orders["cycloid mesh"] * points_per_mesh))
    n = max(n, 2)
    ratio = orders["input rotation"]
    span = output_revolutions * 2.0 * math.pi * ratio
    return np.arange(n) * (span / n)


#: imaged starts in a row that need Newton iterations before the periodic route ends
IMAGE_MISSES = 3
#: the no-load curve of a design without manufacturing errors evaluates every this many imaged
#: starts from its third crank revolution on (``check_every`` of :func:`equilibrium_path`)
NO_LOAD_CHECK_EVERY = 8


def equilibrium_path(
    sm: StaticModel,
    angles: np.ndarray,
    q_start: np.ndarray,
    max_failed_fraction: float = 0.01,
    periodic: bool = False,
    progress=None,
    record=None,
    check_every: int = 1,
):
    """Solve every position; each is warm-started from the previous solutions (:func:`_warm_start`:
    the deviation from the kinematic pose extrapolated linearly from the two previous positions).
    ``periodic``: from the second crank revolution on, a position starts from the image of
    the solution one crank revolution earlier (:func:`_periodic_image`) while such starts are
    equilibria already (zero iterations: one residual call per position); :data:`IMAGE_MISSES`
    imaged starts in a row that are not end them (as-built errors that break the symmetry; a
    single miss is an equilibrium found at the edge of the tolerance, whose image lies just
    outside). Every position is solved to the same tolerance, except with ``check_every`` > 1:
    from the third crank revolution on, only every ``check_every``-th imaged start is evaluated and
    the others are taken as they are (zero iterations, no residual call). That is for a design whose
    as-built geometry has the symmetry by construction (no manufacturing errors), where the image
    of an equilibrium is one to the solver's tolerance; a checked start that is not an equilibrium
    ends the sampling, and the unchecked positions since the last good check are solved then
    (not allowed with ``record``, which needs a residual call at every position).
    ``progress(done, total)`` is called every 256 positions and at the end; ``record(k, theta, q)``
    after each converged position (:class:`_CurveRecords`).
    A position that neither its warm start nor a restart from the kinematic pose
    (:func:`_restart`) converges is returned as NaN with iterations -1; more than
    ``max_failed_fraction`` of such positions raise ConvergenceError.
    Returns (Q (P, n), iterations (P,))."""
    if check_every < 1 or (check_every > 1 and record is not None):
        raise ValueError(f"check_every = {check_every} must be >= 1, and 1 with a record")
    qs = np.empty((len(angles), sm.n))
    its = np.empty(len(angles), dtype=int)
    kin = sm.kinematic_pose(angles)
    image = _periodic_image(sm, angles) if periodic else None
    last = None
    misses = 0
    unchecked: list[int] = []
    for k, th in enumerate(angles):
        imaged = image is not None and k >= image.period and its[k - image.period] >= 0
        if imaged:  # (the image replaces the extrapolated start)
            guess = image(qs[k - image.period], kin[k - image.period], kin[k])
            if check_every > 1 and k >= 2 * image.period and k % check_every:
                qs[k], its[k], last = guess, 0, k
                unchecked.append(k)
                _report(progress, k, len(angles))
                continue
        else:
            guess = _warm_start(qs, its, kin, k, last) if k else q_start
        qs[k], its[k] = _solve_or_restart(sm, th, guess, kin[k])
        if its[k] < 0:
            continue
        if record is not None:
            record(k, th, qs[k])
        if imaged and its[k] > 0 and unchecked:  # sampling ends: solve the positions taken unchecked
            for j in unchecked:
                qs[j], its[j] = _solve_or_restart(sm, angles[j], qs[j], kin[j])
            check_every = 1
        if imaged:
            unchecked.clear()
        misses = (misses + 1 if its[k] > 0 else 0) if imaged else misses
        if misses >= IMAGE_MISSES:
            image = None
        last = k
        _report(progress, k, len(angles))
    failed = int(np.sum(its < 0))
    if failed > max_failed_fraction * len(angles):
        raise ConvergenceError(
            f"static equilibrium not found at {failed} of {len(angles)} positions "
            f"(torque {sm.torque:.6g} N m): more than {100 * max_failed_fraction:g} %"
        )
    return qs, its


def _warm_start(qs: np.ndarray, its: np.ndarray, kin: np.ndarray, k: int, last: int | None) -> np.ndarray:
    """Start of position k: the kinematic pose plus the deviation q - q_kin of the two previous
    positions extrapolated linearly, or of the last converged one if the one before failed (measured
    over 4 crank revolutions at the rated torque: 1.70 Newton iterations per position on rv40e and
    1.12 on rv221, against 2.06 and 2.00 with the last deviation kept, and 8 against 2 from the
    kinematic pose at a vanishing torque, where the contact set changes between positions)."""
    if last is None:
        return kin[k].copy()
    if last == k - 1 and k >= 2 and its[k - 2] >= 0:
        return kin[k] + 2.0 * (qs[k - 1] - kin[k - 1]) - (qs[k - 2] - kin[k - 2])
    return qs[last] + (kin[k] - kin[last])


def _solve_or_restart(sm: StaticModel, th: float, guess: np.ndarray, q_kin: np.ndarray) -> tuple[np.ndarray, int]:
    """sm.solve from ``guess``, else from a restart (:func:`_restart`; iterations ``max_iter``),
    else (NaN, -1)."""
    try:
        return sm.solve(th, guess)
    except ConvergenceError:
        try:
            return _restart(sm, th, q_kin), sm.options.max_iter
        except ConvergenceError:
            return np.full(sm.n, np.nan), -1  # reported: the caller counts the unconverged positions


def _report(progress, k: int, total: int) -> None:
    if progress is not None and (k % 256 == 255 or k == total - 1):
        progress(k + 1, total)


def _periodic_image(sm: StaticModel, angles: np.ndarray):
    """The map of a solution onto the positions one crank revolution (relative to the carrier)
    later, or None where the positions do not repeat after a whole number of steps.

    After one crank revolution the carrier has turned by dtheta_c (one pin pitch, 2 pi / z_rp),
    every crank and disc is back in its place relative to the carrier and the pins are
    relabelled: a design whose as-built geometry has that symmetry has the same equilibrium
    there, turned by dtheta_c. The image keeps the deviation q - q_kin from the kinematic pose
    with its in-plane vectors (x, y and tilts rx, ry) turned by dtheta_c. Returns a callable
    ``image(q_earlier, kin_earlier, kin_now)`` with attribute ``period`` (positions)."""
    from flexrv.geometry.kinematics import member_speeds

    p = sm.p
    if len(angles) < 2:
        return None
    step = float(angles[1] - angles[0])
    s = member_speeds(1.0, p.z_s, p.z_p, p.z_c, p.z_rp)
    rev = 2.0 * math.pi / abs(float(s.crank_relative))  # input angle of one crank revolution
    period = int(round(rev / step))
    dth = rev * float(s.carrier)
    if period < 1 or abs(period * step - rev) > 1e-9 * rev or period >= len(angles):
        return None
    if abs(dth * p.z_rp / (2.0 * math.pi) - round(dth * p.z_rp / (2.0 * math.pi))) > 1e-9:
        return None  # the pins do not repeat
    ia, ib = [], []
    for mem in sm.model.members.values():
        lab = list(mem.labels)
        for a, b in (("x", "y"), ("rx", "ry")):
            if a in lab and b in lab:
                ia.append(mem.offset + lab.index(a))
                ib.append(mem.offset + lab.index(b))
    ia, ib = np.array(ia, dtype=np.int64), np.array(ib, dtype=np.int64)
    c, sn = math.cos(dth), math.sin(dth)

    def image(q_earlier, kin_earlier, kin_now):
        return turned_deviation(q_earlier, kin_earlier, kin_now, ia, ib, c, sn)

    image.period = period
    return image


def _restart(sm: StaticModel, theta_in: float, q_kin: np.ndarray) -> np.ndarray:
    """Fallback of :func:`equilibrium_path` where the warm start fails (a small
    torque whose contact set changed between positions): reach the torque again
    from the kinematic pose, by continuation from the rated torque downwards
    (each step then starts from a well-loaded, well-conditioned state)."""
    target = sm.torque
    rated = sm.t_ref if target >= 0 else -sm.t_ref
    sm.torque = 0.0
    q = ramp_to(sm, theta_in, q_kin, rated)
    if abs(target) < abs(rated):
        q = ramp_to(sm, theta_in, q, target)
    sm.torque = target
    return q


def ramp_to(sm: StaticModel, theta_in: float, q: np.ndarray, torque: float, steps: int = 4) -> np.ndarray:
    """Equilibrium at ``torque`` reached by continuation from the current torque:
    ``steps`` equal steps, or, between torques of one sign that differ by more
    than 4x, equal ratios (the contact laws' stiffness changes with the load's
    magnitude, so a drop from 412 to 0.4 N m goes 412 -> 41 -> 4 -> 0.4)."""
    t0 = sm.torque
    if t0 * torque > 0 and max(abs(t0 / torque), abs(torque / t0)) > 4.0:
        n = max(steps, int(np.ceil(abs(np.log10(abs(torque / t0))))))
        levels = t0 * (torque / t0) ** (np.arange(1, n + 1) / n)
    else:
        levels = t0 + (torque - t0) * np.arange(1, steps + 1) / steps
    for level in levels:
        sm.torque = float(level)
        q, _ = sm.solve(theta_in, q)
    return q


class _PhaseClock:
    """Process CPU [s] between successive :meth:`lap` calls, by phase name (``laps``)."""

    def __init__(self):
        self.laps: dict[str, float] = {}
        self._t = _time.process_time()

    def lap(self, name: str) -> None:
        t = _time.process_time()
        self.laps[name] = self.laps.get(name, 0.0) + t - self._t
        self._t = t


class _CurveRecords:
    """The force groups' outputs over a curve from the solver's own evaluations.

    Called after each converged position (``record`` of :func:`equilibrium_path`), it copies
    the per-contact records of the fused compiled element
    (:meth:`flexrv.model.kernels.FusedForces.record_entries`) left by the residual call at
    exactly that state (one more call, without the Jacobian, where the solver's last call was
    elsewhere: a best iterate, an exact Newton step below the position tolerance). The same
    numbers as evaluating the groups again at the converged states, to the solvers' own
    tolerances (warm-started closest points and crank-support solves), except ``pin_gap`` of a
    pin the solver proved open: a positive lower bound of its gap, as in a simulation's records
    (:class:`flexrv.model.kernels.HistoryRecorder`). Groups outside the fused element are
    evaluated by :func:`flexrv.model.outputs.group_outputs` at the converged states."""

    def __init__(self, sm: StaticModel, n: int):
        self.sm = sm
        if sm.model.fused is None:
            sm.residual(0.0, sm.model.q0, jacobian=False)  # builds the fused element
        self.entries = sm.model.fused.record_entries()
        self.buffers = [np.empty((n,) + a.shape) for _, _, a in self.entries]
        self.pairs = [(a, b) for (_, _, a), b in zip(self.entries, self.buffers)]
        self.valid = np.zeros(n, dtype=bool)

    def __call__(self, k: int, theta: float, q: np.ndarray) -> None:
        last = self.sm.last
        if last is None or last[0] != theta or not (last[1] == q).all():
            self.sm.residual(theta, q, jacobian=False)
        for live, buffer in self.pairs:
            buffer[k] = live
        self.valid[k] = True

    def outputs(self, angles: np.ndarray, qs: np.ndarray) -> dict:
        """Every group's declared outputs over the positions (dims start with ``position``;
        NaN at the positions that did not converge). Where every position converged (the
        usual case), the record buffers are used as they are, without masked copies (on rv40e's
        12,480 positions the copies were most of this call)."""
        from flexrv.model.base import Output
        from flexrv.model.outputs import group_outputs

        ok = self.valid & np.isfinite(qs).all(axis=1)
        every = bool(ok.all())
        sel = slice(None) if every else ok
        data: dict = {}
        for (group, key, _), buffer in zip(self.entries, self.buffers):
            data.setdefault(group, {})[key] = buffer[sel]
        records = {"data": data, "valid": {g: np.ones(int(ok.sum()), dtype=bool) for g in data}}
        z = np.zeros_like(qs[sel])
        outs = {}
        for name, val in group_outputs(self.sm.model, angles[sel], qs[sel], z, records=records).items():
            v = np.asarray(val.values, dtype=float)
            if every:
                full = v
            else:
                full = np.full((len(angles),) + v.shape[1:], np.nan)
                full[ok] = v
            outs[name] = Output(full, ("position",) + tuple(val.dims[1:]), val.units, val.long_name)
        return outs


def _catalog_levels(
    sm: StaticModel, th: float, q: np.ndarray, torque: float, rated: float, t_small: float, play=()
) -> dict[str, float]:
    """Output angles at rated, half, +3 %, +T0, -3 % and -T0 torque, and at +-f rated for each
    fraction f of ``play`` (keys ("plus", f) / ("minus", f)), at one input
    angle (input locked). The reversed load starts from the mirror image of the
    +3 % pose about the kinematic pose (symmetric clearances give nearly that)
    instead of creeping through the clearances; where that fails (errors make the
    clearances asymmetric), from a restart at the reversed rated torque."""
    levels = {}
    sm.torque = torque
    q_plus3 = None
    for name, level in (("rated", rated), ("half", 0.5 * rated), ("plus3", 0.03 * rated), ("plus0", t_small)):
        q = ramp_to(sm, th, q, level, steps=2)
        levels[name] = q[sm.i_theta]
        if name == "plus3":
            q_plus3 = q
    for f in sorted(play, reverse=True):
        q = ramp_to(sm, th, q, f * rated, steps=1)
        levels["plus", f] = q[sm.i_theta]
    q_kin = sm.kinematic_pose(th)
    sm.torque = -0.03 * rated
    try:
        q, _ = sm.solve(th, 2.0 * q_kin - q_plus3)
    except ConvergenceError:
        q = _restart(sm, th, q_kin)
    levels["minus3"] = q[sm.i_theta]
    q = ramp_to(sm, th, q, -t_small, steps=2)
    levels["minus0"] = q[sm.i_theta]
    for f in sorted(play, reverse=True):
        q = ramp_to(sm, th, q, -f * rated, steps=1)
        levels["minus", f] = q[sm.i_theta]
    return levels


def loaded_te(
    reducer,
    torque: float | None = None,
    output_revolutions: float | None = None,
    crank_revolutions: float | None = None,
    points_per_mesh: int = 8,
    no_load_fraction: float = 1e-2,
    catalog_positions: int = 6,
    options: dict | None = None,
    play_fractions: tuple = (),
    progress=None,
) -> LoadedTE:
    """Loaded and no-load TE over the requested input range, catalog lost motion,
    backlash and rigidity (see module docstring).

    ``play_fractions``: fractions of the rated torque at which the play between -f and +f
    is read too (catalog ``play_positions_rad``; the geometric backlash's extrapolation,
    :mod:`flexrv.post.definitions`). ``torque`` [N m] defaults to the design's rated torque; it must be positive and
    at most 3x the rated torque (beyond that the Hertz laws leave their range).
    ``progress(stage, done, total)``: called while the curves are solved (stage "loaded curve" /
    "no-load curve", positions done of total).
    """
    op = reducer.operating
    rated = op.rated_torque_Nm
    if torque is None:
        torque = rated
    if not (0 < no_load_fraction <= 0.03):
        raise InputError(f"no_load_fraction = {no_load_fraction!r} is not allowed: must lie in (0, 0.03]")
    t_min = no_load_fraction * rated
    if not (math.isfinite(torque) and t_min <= torque <= 3.0 * rated):
        raise InputError(
            f"torque = {torque!r} N m is not allowed: must lie in [{t_min:g}, {3 * rated:g}] N m: at least the "
            f"no-load torque ({no_load_fraction:g} x rated), against which the loaded TE is measured, and at most "
            "3 x rated, beyond which the Hertz laws leave their range"
        )
    angles = positions_for(reducer, output_revolutions, crank_revolutions, points_per_mesh)
    clock = _PhaseClock()
    sm = StaticModel(reducer, options)
    clock.lap("model")
    t_start = _time.perf_counter()
    q0 = sm.kinematic_pose(angles[0])
    # first position: torque continuation from the kinematic pose
    sm.torque = 0.0
    try:  # assembly first: errors that make parts interfere preload them at zero torque
        q0, _ = sm.solve(angles[0], q0)
    except ConvergenceError:
        pass  # nothing touches (clearances everywhere): the load ramp closes them
    q_load = ramp_to(sm, angles[0], q0, torque, steps=8)
    stage = (lambda name: lambda done, total: progress(name, done, total)) if progress is not None else None
    records = _CurveRecords(sm, len(angles))
    clock.lap("load_ramp")
    qs, its = equilibrium_path(sm, angles, q_load, progress=stage and stage("loaded curve"), record=records)
    clock.lap("loaded_curve")
    # no-load curve
    t_small = no_load_fraction * rated
    sm.torque = torque
    q_small = ramp_to(sm, angles[0], qs[0], t_small)
    check = NO_LOAD_CHECK_EVERY if reducer.errors.is_zero() else 1
    qs_nl, its_nl = equilibrium_path(
        sm, angles, q_small, periodic=True, progress=stage and stage("no-load curve"), check_every=check
    )
    clock.lap("no_load_curve")
    ratio = sm.p.ratio
    th_out = qs[:, sm.i_theta]
    te = th_out - angles / ratio
    te_nl = qs_nl[:, sm.i_theta] - angles / ratio
    # outputs declared by the groups, over the positions (at the loaded curve's torque)
    outs = records.outputs(angles, qs)
    ok = np.isfinite(qs).all(axis=1)
    clock.lap("outputs")
    # catalog quantities at a few converged positions spread over the range
    good = np.flatnonzero(ok)
    cat_idx = good[np.unique(np.linspace(0, len(good) - 1, max(1, min(catalog_positions, len(good)))).astype(int))]
    lm, bl, k_sec, k_tan, budgets, k_low, plays = [], [], [], [], [], [], []
    for i in cat_idx:
        try:
            levels = _catalog_levels(sm, angles[i], qs[i], torque, rated, t_small, play_fractions)
        except ConvergenceError:
            continue  # reported through the number of catalog positions used
        # output angle under positive load is smaller (the load acts against +theta)
        lm.append(levels["minus3"] - levels["plus3"])
        bl.append(levels["minus0"] - levels["plus0"])
        plays.append([levels["minus", f] - levels["plus", f] for f in play_fractions])
        k_sec.append(0.5 * rated / (levels["half"] - levels["rated"]))
        k_low.append(0.47 * rated / (levels["plus3"] - levels["half"]))  # secant 3 % -> 50 % rated
        sm.torque = torque
        k_tan.append(sm.tangent_rigidity(angles[i], qs[i]))
        budgets.append(sm.compliance_budget(angles[i], qs[i]))
    if not lm:
        raise ConvergenceError("no catalog position (lost motion, backlash, rigidity) converged")
    wall = _time.perf_counter() - t_start
    clock.lap("catalog")
    catalog = {
        "lost_motion_rad": float(np.max(lm)),
        "backlash_rad": float(np.max(bl)),
        "lost_motion_positions_rad": np.asarray(lm),
        "backlash_positions_rad": np.asarray(bl),
        "play_positions_rad": np.asarray(plays).reshape(len(plays), len(play_fractions)),  #: at +-play_fractions
        "play_fractions": np.asarray(play_fractions, dtype=float),
        "rigidity_secant_Nm_per_rad": float(np.mean(k_sec)),
        "rigidity_low_Nm_per_rad": float(np.mean(k_low)),
        "rigidity_tangent_Nm_per_rad": float(np.mean(k_tan)),
        "catalog_input_angles": angles[cat_idx],
        "compliance_budget": {g: float(np.mean([b_[g] for b_ in budgets])) for g in budgets[0]},
        "catalog_positions_used": len(lm),
    }
    return LoadedTE(
        input_angle=angles,
        output_angle=th_out,
        te=te,
        te_no_load=te_nl,
        torque=float(torque),
        ratio=ratio,
        outputs=outs,
        catalog=catalog,
        iterations=np.r_[its, its_nl],
        solve_time_s=wall,
        orders=characteristic_orders(reducer),
        no_load_torque=t_small,
        timing=clock.laps,
    )
