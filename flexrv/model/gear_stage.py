"""First stage: sun–planet involute meshes along the line of action.

Mesh deflection of planet j (lumped-parameter model along the line of action,
Kahraman 1994; Lin & Parker 1999), with the sun centre fixed on the axis and its
angle prescribed by the drive:

    delta_j = r_bs theta_s + r_bp phi_j - (r_bs + r_bp)(beta_j - beta_j0)
              - sin(alpha_w) (a_j - a_w),

beta_j, a_j the polar angle and radius of the crank (= planet) centre, phi_j the
absolute planet angle, r_b base radii, alpha_w the working pressure angle. It is
zero for the ideal rolling motion (r_bs (theta_s - beta) = -r_bp (phi - beta))
and positive when the drive flanks are compressed. The planet's torsion relative to the
crank's eccentrics (crank torsion and planet spline, c_t per crank [rad/(N m)],
:func:`flexrv.analysis.path_compliances.model_compliances`) is in series with the
mesh: the torque F r_bp turns the planet by c_t F r_bp against the crank, the mesh
point by c_t r_bp^2 F along the line of action, so the mesh law's stiffness is

    k(xi) = 1 / (1 / k_m(xi) + s),   s = c_t r_bp^2,

k_m the involute mesh's (s = 0: the mesh law itself; a massless series spring, exact
for the static equilibrium; the planet's own torsional vibration on the crank is the
flexible-crank model's, :mod:`flexrv.model.flexible_crank`, which keeps only the
spline here). delta is then the approach of the crank-side mesh point along the line
of action, the mesh's and the planet's torsion together. With the normal backlash
b_n = j_t cos(alpha_w) the force is

    F = k(xi) delta + c ddelta/dt              for delta > 0   (drive flank, F >= 0)
    F = k(xi) (delta + b_n) + c ddelta/dt      for delta < -b_n (coast flank, F <= 0)
    F = 0                                      otherwise,

with the time-varying stiffness k_m(xi) of :func:`flexrv.analysis.mesh_stiffness.
time_varying_mesh_stiffness` (in series with s) at the mesh phase xi_j = z_s (theta_s - beta_j)/2pi
- z_s beta_j0/2pi (carrier-frame kinematics: one base pitch per sun tooth passing
the planet), and the mesh damping c12 of
:func:`flexrv.analysis.mesh_stiffness.involute_stage`. The generalized forces
are Q = -F d(delta)/dq (exact, the deflection being a function of the
coordinates). Jacobian (complete, g = d delta/dq over the planet's (x, y, phi)):

    dQ/dq = -g (dF/dq)^T - F H,   dQ/dv = -c g g^T,
    dF/dq = k g + delta_e (dk/dxi) dxi/dq + c (H v + A_s sin(theta_s - beta + ph_s) omega_s dbeta/dq),

H = d2 delta/dq2 the deflection's curvature (from beta(x, y) = atan2(y, x), the
radius a(x, y) and the runout terms), delta_e = delta (drive flank) or delta + b_n
(coast flank), xi the mesh phase (dxi/dq = -z_s/2pi dbeta/dq). The stiffness
slope dk/dxi is the central difference (+-1e-6 in phase) of the one stiffness law
(:func:`series_mesh_stiffness` of :func:`~flexrv.analysis.mesh_stiffness.mesh_stiffness_ramped`),
exact for its piecewise-linear ramps except within 1e-6 of their corners. Verified against
central differences in tests/test_kernel.py (1e-6 of the largest entry; measured
7-8e-8).

As-built geometry (:class:`GearStageParameters`, from :func:`flexrv.geometry.as_built.as_built`): sun runout
(A_s, ph_s), planet runout (A_j, ph_j) and planet assembly phase errors err_j
add to the deflection

    delta_j += A_s sin(theta_s - beta_j + ph_s) + A_j sin(phi_j - beta_j + ph_j) + r_bp err_j,

and their derivatives enter g (d/dphi_j = r_bp + A_j cos(.), d/dbeta_j gains
-A_s cos(.) - A_j cos(.)), so Q = -F g stays exact. All zero: the ideal stage.

One compiled kernel (:func:`gear_stage_kernel`, numba) is the only executor: the
group's evaluate/jacobian and the fused element of the model call it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from flexrv.analysis.mesh_stiffness import mesh_stiffness_ramped
from flexrv.model.base import KernelGroup, Output, SummaryRow
from flexrv.model.core.params import empty_pack, law_type, pack_type
from flexrv.model.drive import DriveParameters
from flexrv.units import TWO_PI

#: the meshes' scalar law: base radii of sun and planet, sin of the working pressure angle, centre
#: distance, sun teeth, normal backlash, single-pair stiffness, contact ratio, stiffness ramp
#: fraction, mesh damping, sun runout amplitude and phase, the planet torsion's compliance along
#: the line of action s = c_t r_bp^2 [m/N]
GearLaw = law_type(
    "GearLaw",
    rbs=float,
    rbp=float,
    sin_alpha_w=float,
    a_w=float,
    z_s=float,
    b_n=float,
    k_single=float,
    eps_alpha=float,
    ramp=float,
    c=float,
    A_sun=float,
    ph_sun=float,
    s_t=float,
)
_F, _I = np.float64, np.int64
#: :func:`gear_stage_kernel`'s pack: indices (carrier x, y, theta, then each crank's x, y, phi), law,
#: the drive at t (sun angle, sun speed: the time inputs), crank angles in the carrier, planet
#: (runout amplitude, phase, assembly phase error), per-mesh outputs
GearPack = pack_type(
    "GearPack",
    ("idx", (_I, (6,))),
    ("law", GearLaw),
    ("drive", (_F, (2,))),
    ("beta0", (_F, 1)),
    ("planet", (_F, 2)),
    ("force", (_F, 1)),
    ("deflection", (_F, 1)),
    ("stiffness", (_F, 1)),
)


@njit(cache=True)
def series_mesh_stiffness(xi, k_single, eps_alpha, ramp, s):
    """The mesh law's stiffness [N/m] at the mesh phase ``xi``: the involute mesh's
    (:func:`~flexrv.analysis.mesh_stiffness.mesh_stiffness_ramped`) in series with the
    planet torsion's compliance ``s`` along the line of action [m/N] (module docstring)."""
    k = mesh_stiffness_ramped(xi, k_single, eps_alpha, ramp)
    return k / (1.0 + k * s)


@njit(cache=True)
def gear_stage_kernel(q, v, f, jq, jv, jac, pack):
    """Sun–planet meshes (module docstring) at the sun angle and speed ``pack.drive``:
    adds Q into f[idx] and, if ``jac``, dQ/dq, dQ/dv into jq, jv. Per-mesh force,
    deflection and stiffness go to the pack's output arrays."""
    idx, law, beta0, planet = pack.idx, pack.law, pack.beta0, pack.planet
    ts, ws = pack.drive[0], pack.drive[1]
    out_f, out_d, out_k = pack.force, pack.deflection, pack.stiffness
    rbs, rbp, sw, aw, zs, bn = law.rbs, law.rbp, law.sin_alpha_w, law.a_w, law.z_s, law.b_n
    ks, eps, ramp, c, a_s, ph_s = law.k_single, law.eps_alpha, law.ramp, law.c, law.A_sun, law.ph_sun
    s_t = law.s_t
    r = rbs + rbp
    th_c = q[idx[2]]
    for j in range(beta0.shape[0]):
        ix, iy, ip = idx[6 + 3 * j], idx[7 + 3 * j], idx[8 + 3 * j]
        x, y, phi = q[ix], q[iy], q[ip]
        a2 = x * x + y * y
        a = np.sqrt(a2)
        rel = np.arctan2(y, x) - th_c - beta0[j]
        rel -= TWO_PI * np.rint(rel / TWO_PI)
        beta = th_c + beta0[j] + rel
        a_p, ph_p, err = planet[j, 0], planet[j, 1], planet[j, 2]
        cos_s = a_s * np.cos(ts - beta + ph_s)
        cos_p = a_p * np.cos(phi - beta + ph_p)
        delta = (
            rbs * ts
            + rbp * phi
            - r * (beta - beta0[j])
            - sw * (a - aw)
            + a_s * np.sin(ts - beta + ph_s)
            + a_p * np.sin(phi - beta + ph_p)
            + rbp * err
        )
        rb = r + cos_s + cos_p  # -d delta / d beta
        gx = rb * y / a2 - sw * x / a
        gy = -rb * x / a2 - sw * y / a
        gp = rbp + cos_p
        ddelta = (rbs + cos_s) * ws + gx * v[ix] + gy * v[iy] + gp * v[ip]
        k = series_mesh_stiffness((zs / TWO_PI) * (ts - beta - beta0[j]), ks, eps, ramp, s_t)
        force = 0.0
        active = False
        if delta > 0.0:
            force = max(k * delta + c * ddelta, 0.0)
            active = force > 0.0
        elif delta < -bn:
            force = min(k * (delta + bn) + c * ddelta, 0.0)
            active = force < 0.0
        f[ix] -= force * gx
        f[iy] -= force * gy
        f[ip] -= force * gp
        out_f[j], out_d[j], out_k[j] = force, delta, k
        if jac and active:
            g = (gx, gy, gp)
            ii = (ix, iy, ip)
            # curvature of delta(x, y, phi) (module docstring, "Jacobian")
            ss = a_s * np.sin(ts - beta + ph_s)
            sp = a_p * np.sin(phi - beta + ph_p)
            sb = ss + sp  # d rb / d beta
            a4, a3 = a2 * a2, a2 * a
            hxx = -sb * y * y / a4 - 2.0 * rb * x * y / a4 - sw * y * y / a3
            hxy = sb * x * y / a4 + rb * (x * x - y * y) / a4 + sw * x * y / a3
            hyy = -sb * x * x / a4 + 2.0 * rb * x * y / a4 - sw * x * x / a3
            hxp, hyp, hpp = -sp * y / a2, sp * x / a2, -sp
            hess = ((hxx, hxy, hxp), (hxy, hyy, hyp), (hxp, hyp, hpp))
            # d beta / dq and the stiffness' slope along the mesh phase (central difference of the
            # one stiffness law, exact for its piecewise-linear ramps beyond 1e-6 of their corners)
            bx, by = -y / a2, x / a2
            xi = (zs / TWO_PI) * (ts - beta - beta0[j])
            dk = (
                (
                    series_mesh_stiffness(xi + 1e-6, ks, eps, ramp, s_t)
                    - series_mesh_stiffness(xi - 1e-6, ks, eps, ramp, s_t)
                )
                / 2e-6
                * (-zs / TWO_PI)
            )
            d_eff = delta if delta > 0.0 else delta + bn
            vv = (v[ix], v[iy], v[ip])
            for n in range(3):
                db = bx if n == 0 else (by if n == 1 else 0.0)
                # dF/dq_n: stiffness, its phase change, damping through g(q) and the sun runout's rate
                hv = hess[0][n] * vv[0] + hess[1][n] * vv[1] + hess[2][n] * vv[2]
                dfn = k * g[n] + d_eff * dk * db + c * (hv + ss * ws * db)
                for m in range(3):
                    jq[ii[m], ii[n]] -= g[m] * dfn + force * hess[m][n]
                    jv[ii[m], ii[n]] -= c * g[m] * g[n]


# ---------------------------------------------------------------- the element's parameters from the design
@dataclass(frozen=True)
class GearStageParameters:
    """The first stage's parameters (SI). Built by :func:`gear_stage_parameters`."""

    drive: DriveParameters
    stage: object  #: the involute stage's mesh stiffness (:func:`flexrv.analysis.mesh_stiffness.involute_stage`)
    base_radius_sun: float
    base_radius_planet: float
    working_pressure_angle: float
    normal_backlash: float
    sun_runout: np.ndarray  #: (2,) as-built amplitude [m] along the lines of action, phase [rad]
    planet_runout: np.ndarray  #: (N, 2) as-built amplitude [m], phase [rad]
    planet_phase_errors: np.ndarray  #: (N,) as-built assembly phase error of each planet on its crank [rad]
    #: torsional compliances per crank between planet gear and eccentrics [rad/(N m)], in series with
    #: each mesh: crank torsion, planet spline (:func:`flexrv.analysis.path_compliances.planet_torsion_compliances`)
    crank_torsion_compliance: float
    planet_spline_compliance: float


def gear_stage_parameters(reducer, drive: DriveParameters) -> GearStageParameters:
    """The first stage's parameters: base radii, working pressure angle and normal backlash
    of the involute pair, its mesh stiffness, the as-built runouts and phase errors
    (:func:`flexrv.geometry.as_built.as_built`) and the planets' torsional compliances."""
    from flexrv.analysis.mesh_stiffness import involute_stage
    from flexrv.analysis.path_compliances import planet_torsion_compliances

    fs = reducer.first_stage
    alpha = fs.pressure_angle
    rb_s = 0.5 * fs.module * fs.sun_teeth * math.cos(alpha)
    rb_p = 0.5 * fs.module * fs.planet_teeth * math.cos(alpha)
    alpha_w = math.acos((rb_s + rb_p) / fs.center_distance)
    c_crank, c_spline = planet_torsion_compliances(reducer)
    ab = drive.as_built
    return GearStageParameters(
        drive=drive,
        stage=involute_stage(reducer),
        base_radius_sun=rb_s,
        base_radius_planet=rb_p,
        working_pressure_angle=alpha_w,
        normal_backlash=fs.backlash * math.cos(alpha_w),
        sun_runout=ab.sun_runout,
        planet_runout=ab.planet_runout,
        planet_phase_errors=ab.planet_phase_errors,
        crank_torsion_compliance=c_crank,
        planet_spline_compliance=c_spline,
    )


class GearMeshes(KernelGroup):
    """All sun–planet meshes in one element (members: carrier, crank0..N-1)."""

    name = "gear_stage"
    kind = "gear"
    summary_rows = (SummaryRow("max_mesh_force_N", "N", "largest sun-planet mesh force", "mesh_force", "max"),)
    kernel = staticmethod(gear_stage_kernel)
    time_field = "drive"

    parameters = staticmethod(gear_stage_parameters)

    def __init__(self, params: GearStageParameters, input_angle, input_speed, ramp_fraction: float = 0.2):
        p = self.params = params
        d, stage = p.drive, p.stage
        self.n = d.n_cranks
        self.members = ("carrier",) + tuple(f"crank{j}" for j in range(self.n))
        self.rbs, self.rbp = p.base_radius_sun, p.base_radius_planet
        self.beta0 = np.ascontiguousarray(d.crank_angles, dtype=float)
        self.bn = p.normal_backlash
        self.c = stage.c12
        w1 = stage.eps_alpha - 1.0
        ramp = ramp_fraction * min(w1, 1.0 - w1)
        sun = np.asarray(p.sun_runout, dtype=float)
        self.law = GearLaw.of(
            rbs=p.base_radius_sun,
            rbp=p.base_radius_planet,
            sin_alpha_w=np.sin(p.working_pressure_angle),
            a_w=d.center_distance,
            z_s=d.z_s,
            b_n=p.normal_backlash,
            k_single=stage.k_single,
            eps_alpha=stage.eps_alpha,
            ramp=ramp,
            c=stage.c12,
            A_sun=sun[0],
            ph_sun=sun[1],
            s_t=0.0,
        )
        self.set_planet_torsion(p.crank_torsion_compliance + p.planet_spline_compliance)
        #: (N, 3): planet runout amplitude [m], phase [rad], assembly phase error [rad]
        self.planet = np.ascontiguousarray(
            np.column_stack(
                [
                    np.asarray(p.planet_runout, dtype=float).reshape(-1, 2),
                    np.asarray(p.planet_phase_errors, dtype=float),
                ]
            )
        )
        self.theta_s, self.omega_s = input_angle, input_speed
        self._drive_cache = None
        self.force, self.deflection, self.stiffness = np.zeros(self.n), np.zeros(self.n), np.zeros(self.n)
        #: the drive at the time of the last call: sun angle [rad], sun speed [rad/s]
        self.drive = np.zeros(2)

    def set_planet_torsion(self, c_t: float) -> None:
        """The planet's torsional compliance relative to the crank's eccentrics ``c_t`` per crank
        [rad/(N m)] in series with each mesh (module docstring): s = c_t r_bp^2."""
        if not (np.isfinite(c_t) and c_t >= 0.0):
            raise ValueError(f"planet torsion compliance {c_t!r} must be a finite value >= 0 [rad/(N m)]")
        #: the planet's torsional compliance per crank [rad/(N m)]
        self.planet_torsion = float(c_t)
        self.law = self.law._replace(s_t=float(c_t) * self.rbp**2)

    def pack(self, idx, history=False):
        return GearPack(idx, self.law, self.drive, self.beta0, self.planet, self.force, self.deflection, self.stiffness)

    @staticmethod
    def empty_pack():
        return empty_pack(GearPack)

    def time_inputs(self, t):
        """(sun angle, sun speed) at t; cached (all Newton iterations of a step
        evaluate the same time)."""
        c = self._drive_cache
        if c is None or c[0] != t:
            c = self._drive_cache = (t, float(self.theta_s(t)), float(self.omega_s(t)))
        return c[1], c[2]

    def set_time(self, t, array) -> None:
        """The drive at t into the pack's live ``array`` (two floats: written every call)."""
        array[0], array[1] = self.time_inputs(t)

    def time_inputs_many(self, ts):
        return np.stack(
            [
                np.broadcast_to(np.asarray(self.theta_s(ts), dtype=float), ts.shape),
                np.broadcast_to(np.asarray(self.omega_s(ts), dtype=float), ts.shape),
            ],
            axis=-1,
        )

    def record_sources(self):
        return {"force": self.force, "deflection": self.deflection, "stiffness": self.stiffness}

    def outputs(self, t, rec):
        force = rec["force"]
        return {
            "mesh_force": Output(force, ("time", "planet"), "N", "sun-planet mesh force along the line of action"),
            "mesh_deflection": Output(
                rec["deflection"],
                ("time", "planet"),
                "m",
                "mesh deflection along the line of action, the planet's torsion on its crank included",
            ),
            "mesh_stiffness": Output(
                rec["stiffness"],
                ("time", "planet"),
                "N/m",
                "time-varying mesh stiffness, the planet's torsion on its crank in series",
            ),
            "sun_torque": Output(self.rbs * force.sum(axis=-1), ("time",), "N m", "torque of the meshes on the sun"),
        }

    def reset(self) -> None:
        self._drive_cache = None
        super().reset()
