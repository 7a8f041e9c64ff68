"""Hurty–Craig–Bampton reduction with Fourier raceway-load modes, and the raceway
interpolation used by moving ball contacts.

Basis (all vectors vanish on the first interface, which defines the floating
frame of an Exudyn ``ObjectFFRFreducedOrder``; Craig & Bampton 1968, AIAA J. 6(7)):

1. RBE2 rigid-interface static modes of the other interfaces (6 each; the
   crankshaft's second support journal), -Kii^-1 Kib T (as Exudyn's
   ``FEMinterface.ComputeHurtyCraigBamptonModes`` with ``HCBstaticModeSelection.RBE2``);
2. ``n_eig`` fixed-interface eigenmodes (Kii, Mii);
3. raceway-load modes: static responses Kii^-1 F_k to raceway loads in Fourier
   form, F_k^c / F_k^s = sum_j a_j g_j {cos, sin}(k theta_j) n_j, k = 0..K, with
   a_j the nodal area of raceway node j, g_j = exp(-(m_j/b)^2) its weight by the
   meridian distance m_j from the nominal contact point and n_j the contact
   direction (contact angle) at the node's own azimuth theta_j.

Why Fourier modes: a ball load at azimuth theta is modelled as the contact
direction times a smooth patch w_j(theta) = a_j g_j exp(-(R_c wrap(theta_j - theta)/b)^2)
(normalised to unit sum); its circumferential factor has the Fourier series
sum_k c_k cos k(theta_j - theta), so f(theta) = sum_k c_k [cos k theta F_k^c + sin k theta F_k^s]
EXACTLY, for every azimuth, and the only error of the basis is the harmonic
truncation (c_k ~ exp(-(k b / 2 R_c)^2)). Static modes at discrete load points
(the prototype of exudyn-facts.md) instead have an error that depends on where the
ball is between load points. The patch width b (default D/4, of the order of the
Hertz contact ellipse) is the length below which the ring deformation is left to
the Hertz law; harmonics above K carry load coefficients c_K/c_0 < ``harmonic_tol``
(default 0.2: on the rv221 outer ring, K = 57 and 115 raceway modes give < 0.5 %
error of the deflection under the load at any azimuth; K = 40: -4 %, K = 20: -24 %).

Finally the basis is replaced by its Ritz vectors (generalized eigenvectors of the
projected K, M; near-dependent directions dropped), so the reduced mass is the
identity and the reduced stiffness diagonal (omega^2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from flexrv.errors import InputError
from flexrv.fem.modal import factorize


@dataclass(frozen=True)
class RacewaySpec:
    """Where ball loads act: nominal contact circle (radius ``r``, axial ``z``),
    unit contact direction (``n_r``, ``n_z``) into the ring, patch width ``b``
    [m], harmonic count ``n_harmonics`` (K)."""

    r: float
    z: float
    n_r: float
    n_z: float
    b: float
    n_harmonics: int


def default_harmonics(r: float, b: float, harmonic_tol: float = 0.2) -> int:
    """K such that the patch's Fourier coefficient c_K / c_0 = exp(-(K b/2R)^2)
    just falls below ``harmonic_tol``: K = ceil(2 R / b sqrt(ln(1/tol)))."""
    return int(math.ceil(2.0 * r / b * math.sqrt(math.log(1.0 / harmonic_tol))))


def nodal_areas(nodes: np.ndarray, tris6: np.ndarray) -> np.ndarray:
    """Area [m^2] lumped to the nodes of Tri6 faces (1/6 of the flat corner
    triangle's area to each of its six nodes). Returns (N,) for all nodes."""
    p = nodes[tris6[:, :3]]
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    return np.bincount(tris6.ravel(), weights=np.repeat(area / 6.0, 6), minlength=nodes.shape[0])


def rbe2_mapping(nodes: np.ndarray, node_set: np.ndarray) -> np.ndarray:
    """(3 n, 6) rigid-body mapping of an interface node set about its centroid:
    columns = unit translations x, y, z and small rotations about x, y, z."""
    p = nodes[node_set] - nodes[node_set].mean(axis=0)
    n = len(node_set)
    T = np.zeros((n, 3, 6))
    T[:, :, :3] = np.eye(3)
    # u = theta x p  ->  columns of -skew(p)
    T[:, 0, 4], T[:, 0, 5] = p[:, 2], -p[:, 1]
    T[:, 1, 3], T[:, 1, 5] = -p[:, 2], p[:, 0]
    T[:, 2, 3], T[:, 2, 4] = p[:, 1], -p[:, 0]
    return T.reshape(3 * n, 6)


def interface_dofs(n_dof: int, interfaces: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(boundary DOFs in interface order, interior DOFs) of disjoint interface node sets."""
    bnodes = np.concatenate([np.asarray(s, dtype=np.int64) for s in interfaces])
    if np.unique(bnodes).size != bnodes.size:
        raise InputError("interface node sets overlap; every interface node may belong to one interface only")
    bdofs = (3 * bnodes[:, None] + np.arange(3)).ravel()
    mask = np.ones(n_dof, dtype=bool)
    mask[bdofs] = False
    return bdofs, np.flatnonzero(mask)


def rbe2_block(nodes: np.ndarray, interfaces: list[np.ndarray]) -> np.ndarray:
    """(boundary DOFs, 6 n_if) block-diagonal RBE2 mapping of all interfaces
    (rows in the order of :func:`interface_dofs`)."""
    rows = 3 * sum(len(s) for s in interfaces)
    T = np.zeros((rows, 6 * len(interfaces)))
    start = 0
    for k, s in enumerate(interfaces):
        t = rbe2_mapping(nodes, np.asarray(s))
        T[start : start + t.shape[0], 6 * k : 6 * k + 6] = t
        start += t.shape[0]
    return T


def raceway_weights(
    nodes: np.ndarray,
    race_nodes: np.ndarray,
    areas: np.ndarray,
    spec: RacewaySpec,
    azimuths: np.ndarray,
    cutoff: float = 4.0,
) -> sp.csr_matrix:
    """Sparse (n_az, n_race) patch weights w_j(theta) (rows sum to 1); see module doc."""
    x = nodes[race_nodes]
    rj = np.hypot(x[:, 0], x[:, 1])
    tj = np.arctan2(x[:, 1], x[:, 0])
    g = areas[race_nodes] * np.exp(-(((rj - spec.r) ** 2 + (x[:, 2] - spec.z) ** 2) / spec.b**2))
    keep = g > g.max() * math.exp(-(cutoff**2))
    idx = np.flatnonzero(keep)
    az = np.asarray(azimuths, dtype=float).ravel()
    d = np.remainder(tj[idx][None, :] - az[:, None] + np.pi, 2.0 * np.pi) - np.pi
    s = spec.r * d / spec.b
    mask = np.abs(s) < cutoff
    rows, cols = np.nonzero(mask)
    vals = g[idx][cols] * np.exp(-(s[rows, cols] ** 2))
    W = sp.csr_matrix((vals, (rows, idx[cols])), shape=(az.size, race_nodes.size))
    sums = np.asarray(W.sum(axis=1)).ravel()
    if np.any(sums <= 0):
        raise InputError(
            f"raceway patch width b = {spec.b * 1e3:.3g} mm finds no raceway nodes at some azimuths; "
            "refine the mesh or widen the patch"
        )
    return sp.diags(1.0 / sums) @ W


def fourier_loads(nodes: np.ndarray, race_nodes: np.ndarray, areas: np.ndarray, spec: RacewaySpec) -> np.ndarray:
    """(3N, 2K+1) raceway load vectors F_0, F_1^c, F_1^s, ... (module doc)."""
    x = nodes[race_nodes]
    rj = np.hypot(x[:, 0], x[:, 1])
    tj = np.arctan2(x[:, 1], x[:, 0])
    g = areas[race_nodes] * np.exp(-(((rj - spec.r) ** 2 + (x[:, 2] - spec.z) ** 2) / spec.b**2))
    direction = np.stack([spec.n_r * np.cos(tj), spec.n_r * np.sin(tj), np.full_like(tj, spec.n_z)], axis=1)
    k = np.arange(spec.n_harmonics + 1)
    harm = [np.cos(0 * tj)[:, None]]
    harm.append(np.cos(np.outer(tj, k[1:])))
    harm.append(np.sin(np.outer(tj, k[1:])))
    H = np.concatenate(harm, axis=1)  # (n_race, 2K+1)
    F = np.zeros((3 * nodes.shape[0], H.shape[1]))
    for c in range(3):
        F[3 * race_nodes + c] = (g * direction[:, c])[:, None] * H
    F /= g.sum()
    # order columns as 0, 1c, 1s, 2c, 2s, ...
    K = spec.n_harmonics
    order = [0] + [v for kk in range(1, K + 1) for v in (kk, K + kk)]
    return F[:, order]


@dataclass
class HCBResult:
    """Ritz basis and diagonal reduced matrices."""

    modes: np.ndarray  # (3N, m) M-orthonormal
    omega2: np.ndarray  # (m,) [rad^2/s^2]
    n_interface: int
    n_eig: int
    n_raceway: int
    fixed_interface_hz: np.ndarray


def hcb_basis(
    K: sp.csr_matrix,
    M: sp.csr_matrix,
    nodes: np.ndarray,
    interfaces: list[np.ndarray],
    n_eig: int,
    raceway_loads: np.ndarray | None = None,
) -> HCBResult:
    """Hurty–Craig–Bampton basis (RBE2 interfaces) + raceway static modes, as Ritz vectors.

    Parameters
    ----------
    K, M : full matrices (Exudyn DOF order); nodes : (N, 3);
    interfaces : node sets; the first is the frame interface (its rigid motion is
        the body's floating frame and is excluded); each further one adds 6 RBE2
        static modes.
    n_eig : fixed-interface eigenmodes.
    raceway_loads : (3N, r) load vectors whose static responses (interfaces fixed)
        are added (attachment modes).
    """
    from flexrv.fem.modal import eigenmodes

    n = K.shape[0]
    bdofs, idofs = interface_dofs(n, interfaces)
    bnodes = bdofs[::3] // 3
    Kii = K[idofs][:, idofs]
    solve = factorize(Kii)
    cols = []
    # 1. RBE2 interface static modes (interfaces 2..; the first is the body frame)
    if len(interfaces) > 1:
        Tall = rbe2_block(nodes, interfaces)[:, 6:]
        Kib = K[idofs][:, bdofs]
        S = np.zeros((n, Tall.shape[1]))
        S[bdofs] = Tall
        S[idofs] = -solve(np.asarray(Kib @ Tall))
        cols.append(S)
    n_if = 6 * (len(interfaces) - 1)
    # 2. fixed-interface eigenmodes
    fi_hz = np.array([])
    if n_eig > 0:
        fi_hz, E = eigenmodes(K, M, n_eig, fixed_nodes=bnodes, solve0=solve)
        cols.append(E)
    # 3. raceway attachment modes
    n_r = 0
    if raceway_loads is not None and raceway_loads.shape[1]:
        R = np.zeros((n, raceway_loads.shape[1]))
        R[idofs] = solve(raceway_loads[idofs])
        cols.append(R)
        n_r = raceway_loads.shape[1]
    if not cols:
        raise InputError("the reduced basis is empty: ask for eigenmodes or raceway modes")
    Psi = np.concatenate(cols, axis=1)
    Psi /= np.linalg.norm(Psi, axis=0)
    Mr = Psi.T @ (M @ Psi)
    Kr = Psi.T @ (K @ Psi)
    # drop near-dependent directions, then Ritz vectors
    dm, V = np.linalg.eigh(Mr)
    keep = dm > dm.max() * 1e-12
    T = V[:, keep] / np.sqrt(dm[keep])
    w2, Q = sla.eigh(T.T @ Kr @ T)
    modes = Psi @ (T @ Q)
    return HCBResult(modes, np.clip(w2, 0.0, None), n_if, n_eig, n_r, fi_hz)


def interface_stiffness(K: sp.csr_matrix, nodes: np.ndarray, interfaces: list[np.ndarray]) -> np.ndarray:
    """Static (Guyan) condensation of a body onto the rigid-body motions of its
    RBE2 interfaces: K_c = S^T K S with the interface static modes S (each
    interface's nodes move rigidly, the interior relaxes: S_i = -K_ii^-1 K_ib T).

    Returns the (6 n_if, 6 n_if) stiffness [N/m, N, N m/rad] in the order
    (x, y, z, rx, ry, rz) per interface, each about its node set's centroid
    (:func:`rbe2_mapping`). Exact for static loads applied through the interfaces
    (Guyan 1965); a free body gives a singular K_c with the 6 rigid-body modes.
    """
    from flexrv.fem.modal import factorize

    bdofs, idofs = interface_dofs(K.shape[0], interfaces)
    T = rbe2_block(nodes, interfaces)
    K = sp.csr_matrix(K)
    kib_t = np.asarray(K[idofs][:, bdofs] @ T)
    s_i = -factorize(K[idofs][:, idofs])(kib_t)
    kc = T.T @ np.asarray(K[bdofs][:, bdofs] @ T) + T.T @ np.asarray(K[bdofs][:, idofs] @ s_i)
    return 0.5 * (kc + kc.T)


def periodic_cubic(table: np.ndarray, azimuth: np.ndarray) -> np.ndarray:
    """Catmull–Rom periodic cubic interpolation of ``table`` (n_grid, ...) given on
    the uniform grid 2 pi i / n_grid at ``azimuth`` (...); returns (..., *table.shape[1:])."""
    ng = table.shape[0]
    u = np.remainder(np.asarray(azimuth, dtype=float), 2.0 * np.pi) * (ng / (2.0 * np.pi))
    i = np.floor(u).astype(np.int64)
    t = u - i
    t2, t3 = t * t, t * t * t
    w = (0.5 * (-t3 + 2 * t2 - t), 0.5 * (3 * t3 - 5 * t2 + 2), 0.5 * (-3 * t3 + 4 * t2 + t), 0.5 * (t3 - t2))
    extra = (None,) * (table.ndim - 1)
    out = 0.0
    for off, wk in zip((-1, 0, 1, 2), w):
        out = out + wk[(...,) + extra] * table[(i + off) % ng]
    return out
