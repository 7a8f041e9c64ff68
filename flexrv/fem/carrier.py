"""Carrier compliance by FE condensation (gmsh Tet10 mesh, scikit-fem P2).

The carrier (input end plate, pillars, output-flange plate; part ``carrier`` of
:mod:`flexrv.meshing.parts`) takes the crank forces at its crank bores (one
support bearing per crank in each plate) and passes the torque to the output
flange. :func:`carrier_compliance` condenses the FE carrier onto these interfaces:

* the output flange (outer face of the output plate, bolted to the driven part)
  is **held** (all its nodes clamped: a rigid, fixed flange);
* each crank bore is an **RBE3** (averaging) interface: a force F on the bore
  centre is spread over the bore surface as the traction F a_j / A (a_j the nodal
  area of bore node j, A the bore area), and the bore centre's displacement is the
  work-conjugate area-weighted mean of the bore nodes' displacements (MSC Nastran
  RBE3 with uniform weights). The bearing's outer ring does not stiffen the bore.

The condensed flexibility is C = W^T K_ff^-1 W (W: the 3N x 2B matrix of the
unit bore loads in x and y, K_ff the stiffness with the flange clamped): the
(2B x 2B) compliance [m/N] of the bore centres (x, y per bore, input plate's
bores first, crank k at angle 2 pi k / N) relative to the flange. Its inverse is
the static (Guyan) condensation of the carrier onto the bore-centre DOFs; both are
exact for loads applied through the bores (Guyan 1965, AIAA J. 3(2)), so C times
any bore-force vector equals the bore-centre displacements of the full FE solve.

Torsional compliance (the carrier's share of the output twist): under the output
torque T the N cranks load the bores tangentially, F = T / (N a_w) per crank
(a_w the crank circle radius), split s_in : (1 - s_in) on the input / output
plate; the output rotation is the work-conjugate
theta = sum_bores (s_p t_k / (N a_w)) . u_bore = T g^T C g, g the load vector per
unit torque, so c_carrier = g^T C g [rad/(N m)].

A stiff bound is given too: the same with rigid (RBE2) bores,
:func:`flexrv.fem.reduction.interface_stiffness` (the bearing ring as a rigid
spider); the true value lies between the two.

Verification (tests/test_fem_carrier.py): the condensed matrix reproduces an
independent full FE solve (Lagrange multipliers / direct clamped solve) to 1e-8;
pillars between rigid plates against the built-in (sway) frame
k = N_p (12 E I / L^3 with Timoshenko shear, 1 / (L^3/(12 E I) + L/(kappa G A)))
R^2 + N_p G J / L; mesh convergence with the observed rate.

Discretisation error of the default mesh (stated, not hidden): the sharp re-entrant
edges where the pillars meet the plates limit P2 to an energy convergence order of
about 1.1 (h^(2 lambda), lambda = 0.545 for a 270-degree edge): rv40e 8 / 5.66 / 4 mm
gives 1.607 / 1.645 / 1.672e-7 rad/(N m), order 1.08, Richardson value 1.729e-7, so the
default mesh (6.67 mm, pillars 5.5 mm: 1.6250e-7, 24.7k nodes; its build cost in
docs/benchmarks.md) reads 6 % stiff, i.e. about 0.7 % of the rv40e's total torsional compliance (the carrier's
share is 11 %). Graded refinement at the pillar roots (``edge_size``, off by default)
converges at the same order: 2 / 1 / 0.5 mm give 1.6607 / 1.6840 / 1.6948e-7 at 31k /
48k / 83k nodes, so 1-2 % would cost several times the present build; a real
carrier's root fillets (not in the geometry) would remove the singularity
(tests/test_convergence.py::TestConvergenceCarrierTorsion).

Cached as JSON under :func:`flexrv.cache.cache_dir` keyed by the mesh key, the
material, the load split and the library versions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from flexrv.cache import cache_dir, cached_dataclass, content_hash, entry_problem, library_versions
from flexrv.errors import InputError
from flexrv.units import RAD_PER_ARCMIN

FORMAT_VERSION = 1


# ------------------------------------------------------------------ generic condensation helpers
def rbe3_loads(nodes: np.ndarray, faces: list[np.ndarray], components=(0, 1)) -> sp.csc_matrix:
    """(3N, len(faces) * len(components)) unit RBE3 load vectors: column
    (i, c) spreads a unit force along axis c over the surface ``faces[i]`` (Tri6
    faces) in proportion to the nodal areas (resultant exactly 1, no moment about
    the area centroid for a uniform traction). Its transpose maps displacements to
    the RBE3 (area-weighted mean) displacement of each surface."""
    from flexrv.fem.reduction import nodal_areas

    rows, cols, vals = [], [], []
    col = 0
    for f in faces:
        a = nodal_areas(nodes, np.asarray(f))
        idx = np.flatnonzero(a)
        w = a[idx] / a[idx].sum()
        for c in components:
            rows.append(3 * idx + c)
            cols.append(np.full(idx.size, col))
            vals.append(w)
            col += 1
    n = 3 * nodes.shape[0]
    return sp.csc_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, col))


def clamped_flexibility(K, fixed_nodes: np.ndarray, loads) -> tuple[np.ndarray, np.ndarray]:
    """Flexibility of a clamped FE model for the load vectors ``loads`` (3N, m):
    returns (C = L^T K_ff^-1 L (m, m), displacements (3N, m))."""
    from flexrv.fem.modal import factorize, free_dofs

    n = K.shape[0]
    if len(fixed_nodes) == 0:
        raise InputError("no clamped nodes: the flexibility of a free body is singular")
    idofs = free_dofs(n, np.asarray(fixed_nodes))
    L = sp.csc_matrix(loads)
    U = np.zeros((n, L.shape[1]))
    U[idofs] = factorize(sp.csr_matrix(K)[idofs][:, idofs])(L[idofs].toarray())
    C = np.asarray(L.T @ U)
    return 0.5 * (C + C.T), U


def rigid_master_transform(n_dof: int, nodes: np.ndarray, masters, fixed_nodes=()) -> tuple[sp.csc_matrix, list]:
    """Master-slave elimination of RBE2 (rigid) interfaces and clamped nodes:
    u = Z x, with x = (free nodal DOFs, the free components of each master).

    ``masters`` is a list of (node set, free components): the node set moves
    rigidly with 6 master DOFs (x, y, z, rx, ry, rz about its centroid,
    :func:`flexrv.fem.reduction.rbe2_mapping`), of which only ``free components``
    (indices 0..5) are kept (the others held at 0). Returns Z (n_dof, m) and the
    column index of each master's first kept component."""
    from flexrv.fem.reduction import rbe2_mapping

    slave = np.zeros(n_dof, dtype=bool)
    fixed = np.zeros(n_dof, dtype=bool)
    for s, _ in masters:
        s = np.asarray(s, dtype=np.int64)
        d = (3 * s[:, None] + np.arange(3)).ravel()
        if np.any(slave[d]):
            raise InputError("rigid interfaces overlap; every node may belong to one interface only")
        slave[d] = True
    fn = np.asarray(fixed_nodes, dtype=np.int64)
    fixed[(3 * fn[:, None] + np.arange(3)).ravel()] = True
    fixed &= ~slave
    free = np.flatnonzero(~slave & ~fixed)
    rows, cols, vals = [free], [np.arange(free.size)], [np.ones(free.size)]
    col = free.size
    starts = []
    for s, comps in masters:
        s = np.asarray(s, dtype=np.int64)
        T = rbe2_mapping(nodes, s)[:, list(comps)]
        d = (3 * s[:, None] + np.arange(3)).ravel()
        r, c = np.nonzero(T)
        rows.append(d[r])
        cols.append(col + c)
        vals.append(T[r, c])
        starts.append(col)
        col += len(comps)
    Z = sp.csc_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n_dof, col))
    return Z, starts


def rigid_master_solve(K, nodes: np.ndarray, masters, loads, fixed_nodes=()) -> tuple[np.ndarray, np.ndarray]:
    """Static solve with RBE2 masters (see :func:`rigid_master_transform`):
    ``loads`` (3N, m) nodal loads plus master loads already mapped (Z^T f).
    Returns (u (3N, m), x (n_x, m))."""
    from flexrv.fem.modal import factorize

    Z, _ = rigid_master_transform(K.shape[0], nodes, masters, fixed_nodes)
    Kr = sp.csc_matrix(Z.T @ (sp.csr_matrix(K) @ Z))
    Kr = 0.5 * (Kr + Kr.T)
    rhs = np.asarray(Z.T @ np.asarray(loads, dtype=float).reshape(K.shape[0], -1))
    x = factorize(Kr)(rhs)
    return np.asarray(Z @ x), x


# ------------------------------------------------------------------ carrier
@dataclass(frozen=True)
class CarrierCompliance:
    """Condensed carrier (SI). ``matrix`` (2B x 2B) [m/N] bore-centre compliance
    relative to the held flange, order ``labels`` (bore_in_1 x, bore_in_1 y, ...,
    bore_out_N y); ``torsional`` [rad/(N m)] with RBE3 bores, ``torsional_rbe2``
    the stiff bound with rigid bores; ``split_input`` the share of each crank force
    on the input plate."""

    matrix: list
    labels: list
    torsional: float
    torsional_rbe2: float | None
    split_input: float
    crank_circle_radius: float
    n_cranks: int
    n_nodes: int
    size: float
    mesh_key: str

    @property
    def torsional_stiffness_Nm_per_arcmin(self) -> float:
        return RAD_PER_ARCMIN / self.torsional


def bore_groups(n_cranks: int) -> list[str]:
    """Bore group names, input plate first."""
    return [f"bore_{p}_{k + 1}" for p in ("in", "out") for k in range(n_cranks)]


def torque_load_vector(n_cranks: int, crank_circle_radius: float, split_input: float) -> np.ndarray:
    """(2 * 2N,) bore forces [N] per unit output torque: crank k (angle 2 pi k/N)
    pushes its bores along the tangent (-sin, cos) with T / (N a_w), shared
    ``split_input`` / (1 - split_input) by the input / output plate."""
    if not 0.0 <= split_input <= 1.0:
        raise InputError(f"split_input = {split_input!r} must lie in [0, 1]")
    psi = 2.0 * np.pi * np.arange(n_cranks) / n_cranks
    t = np.stack([-np.sin(psi), np.cos(psi)], axis=1) / (n_cranks * crank_circle_radius)
    return np.concatenate([split_input * t.ravel(), (1.0 - split_input) * t.ravel()])


def carrier_material(reducer) -> dict:
    mat = reducer.material("carrier")
    return {"E": mat.youngs_modulus, "nu": mat.poisson_ratio, "rho": mat.density_kg_m3}


def carrier_compliance(
    reducer,
    size: float | None = None,
    split_input: float = 0.5,
    local_size: float | None = None,
    rigid_bound: bool = True,
    cache: bool = True,
    edge_size: float | None = None,
) -> CarrierCompliance:
    """Condensed bore compliance and torsional compliance of a design's carrier
    (module doc). ``size``: global mesh size [m] (part default if None), ``local_size``
    the pillar mesh size [m] (part default if None); ``rigid_bound`` also
    computes the RBE2 (rigid-bore) bound (a second factorisation; None if False; with
    ``rigid_bound`` False a cached result that has the bound is returned as it is)."""
    from flexrv.fem.body import _assemble
    from flexrv.meshing import build_mesh

    mres = build_mesh(reducer, "carrier", size, local_size=local_size, edge_size=edge_size, cache=cache)
    mat = carrier_material(reducer)

    def keyed(bound: bool):
        k = content_hash(
            mres.key,
            mat,
            float(split_input),
            bool(bound),
            FORMAT_VERSION,
            library_versions("scikit-fem", "scipy", "numpy"),
        )
        return k, cache_dir() / f"carrier-{k}.compliance.json"

    key, path = keyed(rigid_bound)
    if cache and not rigid_bound:  # an entry with the bound holds the same matrix: reuse it
        key_b, path_b = keyed(True)
        if entry_problem([path_b], key_b) is None:
            key, path, rigid_bound = key_b, path_b, True

    def _build() -> CarrierCompliance:
        d = mres.data
        n = reducer.first_stage.n_planets
        a_w = reducer.first_stage.center_distance
        names = bore_groups(n)
        fe = _assemble(d, mat, mass=False)
        flange = d.node_set("flange")
        W = rbe3_loads(d.nodes, [d.faces(g) for g in names])
        C, _ = clamped_flexibility(fe.K, flange, W)
        g = torque_load_vector(n, a_w, split_input)
        c_t = float(g @ C @ g)
        c_rbe2 = float(g @ rbe2_bore_compliance(fe.K, d, names) @ g) if rigid_bound else None
        labels = [f"{b} {c}" for b in names for c in ("x", "y")]
        out = CarrierCompliance(
            matrix=C.tolist(),
            labels=labels,
            torsional=c_t,
            torsional_rbe2=c_rbe2,
            split_input=float(split_input),
            crank_circle_radius=float(a_w),
            n_cranks=int(n),
            n_nodes=int(d.n_nodes),
            size=float(d.size),
            mesh_key=mres.key,
        )
        return out

    return cached_dataclass(path, key, CarrierCompliance, _build, enabled=cache)


def rbe2_bore_compliance(K, mesh, names: list[str]) -> np.ndarray:
    """(2B, 2B) x/y compliance of rigid (RBE2) bores relative to the held flange:
    Guyan condensation onto [flange, bores] (:func:`flexrv.fem.reduction.interface_stiffness`),
    flange DOFs removed (clamped), inverted, x/y rows and columns kept (the other
    bore DOFs unloaded)."""
    from flexrv.fem.crankshaft import _disjoint
    from flexrv.fem.reduction import interface_stiffness

    sets = _disjoint(mesh.node_set("flange"), *[mesh.node_set(g) for g in names])
    kc = interface_stiffness(K, mesh.nodes, sets)[6:, 6:]
    c6 = np.linalg.inv(kc)
    keep = np.array([6 * b + c for b in range(len(names)) for c in (0, 1)])
    return c6[np.ix_(keep, keep)]


def pillar_frame_stiffness(
    n_pillars: int,
    pillar_circle_radius: float,
    pillar_radius: float,
    length: float,
    youngs_modulus: float,
    poisson_ratio: float,
) -> float:
    """Torsional stiffness [N m/rad] of round pillars built in between two rigid
    plates (closed form): each pillar sways as a fixed-fixed (guided) Timoshenko
    beam, delta = F L^3 / (12 E I) + F L / (kappa G A) (Timoshenko & Gere,
    Mechanics of Materials; kappa = 6 (1 + nu) / (7 + 6 nu) for a solid circle,
    Cowper 1966, J. Appl. Mech. 33), at the lever arm R, and twists about its own
    axis, G J / L: k = N_p (R^2 / (L^3/(12 E I) + L/(kappa G A)) + G J / L)."""
    E, nu = youngs_modulus, poisson_ratio
    G = E / (2.0 * (1.0 + nu))
    A = np.pi * pillar_radius**2
    I = 0.25 * np.pi * pillar_radius**4
    J = 2.0 * I
    kappa = 6.0 * (1.0 + nu) / (7.0 + 6.0 * nu)
    k_sway = 1.0 / (length**3 / (12.0 * E * I) + length / (kappa * G * A))
    return float(n_pillars * (k_sway * pillar_circle_radius**2 + G * J / length))


def rigid_plate_frame_stiffness(K, mesh, spec) -> float:
    """Torsional stiffness [N m/rad] of the FE carrier with both plates made rigid
    (every node of the input plate, z <= t_in, moves with one RBE2 master; every
    node of the output plate, z >= t_in + L, clamped): the pillars' share, to be
    compared with :func:`pillar_frame_stiffness`."""
    z = mesh.nodes[:, 2]
    tol = 1e-9 + 1e-6 * spec.length
    plate_in = np.flatnonzero(z <= spec.input_thickness + tol)
    plate_out = np.flatnonzero(z >= spec.input_thickness + spec.gap - tol)
    Z, starts = rigid_master_transform(K.shape[0], mesh.nodes, [(plate_in, range(6))], plate_out)
    from flexrv.fem.modal import factorize

    Kr = sp.csc_matrix(Z.T @ (sp.csr_matrix(K) @ Z))
    rhs = np.zeros(Kr.shape[0])
    rhs[starts[0] + 5] = 1.0  # unit moment about z on the rigid input plate
    x = factorize(0.5 * (Kr + Kr.T))(rhs)
    return float(1.0 / x[starts[0] + 5])


def crank_support_compliance(reducer, size: float | None = None, cache: bool = True) -> np.ndarray:
    """(2N x 2N) compliance [m/N] of the cranks' support points in the carrier frame
    (x, y per crank, crank k at 2 pi k / N), relative to the held flange: each crank's
    support force f_k reaches its two bores split s_in : (1 - s_in) (input / output
    plate, :attr:`CarrierCompliance.split_input`), i.e. the bore forces are S f with
    S = [s_in I; (1 - s_in) I] (4N x 2N), and the crank's support point moves by the
    split-weighted mean of its bores' displacements, S^T u (work-conjugate), so
    C_eff = S^T C S with C the bore compliance of :func:`carrier_compliance`.

    With the torque load vector g_c per unit output torque (tangential T / (N a_w)
    per crank), g_c^T C_eff g_c equals the FE torsional compliance
    :attr:`CarrierCompliance.torsional` (identity, tests/test_bodies.py). The
    rigid-bore bound (a second factorisation, used by no model) is not computed here."""
    c = carrier_compliance(reducer, size=size, rigid_bound=False, cache=cache)
    n = c.n_cranks
    s = c.split_input
    S = np.vstack([s * np.eye(2 * n), (1.0 - s) * np.eye(2 * n)])
    C = np.asarray(c.matrix, dtype=float)
    out = S.T @ C @ S
    return 0.5 * (out + out.T)
