"""Stress recovery for Tet10 meshes: nodal-averaged stress (post-processing) modes.

Exudyn's ``FEMinterface.ComputePostProcessingModes`` handles Tet4 only (pure
Python per element), so the equivalent is computed here, vectorised: for every
element the displacement gradient of the isoparametric quadratic tetrahedron is
evaluated at its 10 nodes, sigma = lambda tr(eps) I + 2 mu eps, and nodal values
are averaged over the elements sharing the node. Columns follow Exudyn's
``postProcessingModes`` layout: 6 per mode (xx, yy, zz, yz, xz, xy), so the stress
of modal coordinates q is ``S[:, c::6] @ q`` for component c.
"""

from __future__ import annotations

import numpy as np

from flexrv.fem.assembly import lame

# reference coordinates of the 10 nodes (VTK tetra10 order)
_REF = np.array(
    [
        [0, 0, 0],
        [1, 0, 0],
        [0, 1, 0],
        [0, 0, 1],
        [0.5, 0, 0],
        [0.5, 0.5, 0],
        [0, 0.5, 0],
        [0, 0, 0.5],
        [0.5, 0, 0.5],
        [0, 0.5, 0.5],
    ],
    dtype=float,
)
_EDGES = ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))


def shape_gradients(xi: np.ndarray) -> np.ndarray:
    """dN_a/dxi_k of the quadratic tetrahedron at points xi (P, 3) -> (P, 10, 3)."""
    L = np.stack([1.0 - xi.sum(axis=1), xi[:, 0], xi[:, 1], xi[:, 2]], axis=1)
    dL = np.array([[-1, -1, -1], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    g = np.empty((xi.shape[0], 10, 3))
    for a in range(4):
        g[:, a] = (4.0 * L[:, a] - 1.0)[:, None] * dL[a]
    for e, (a, b) in enumerate(_EDGES):
        g[:, 4 + e] = 4.0 * (L[:, a, None] * dL[b] + L[:, b, None] * dL[a])
    return g


def nodal_stress(
    nodes: np.ndarray, tets: np.ndarray, modes: np.ndarray, youngs_modulus: float, poisson_ratio: float, chunk: int = 8
) -> np.ndarray:
    """Nodal-averaged stress modes (N, 6 m) [Pa per unit modal coordinate]."""
    lam, mu = lame(youngs_modulus, poisson_ratio)
    dN = shape_gradients(_REF)  # (10 pts, 10 fns, 3)
    X = nodes[tets]  # (E, 10, 3)
    J = np.einsum("eai,pak->epik", X, dN)  # dx_i/dxi_k
    G = np.einsum("epki,pak->epai", np.linalg.inv(J), dN)  # dN_a/dx_i at node p
    n_nodes, m = nodes.shape[0], modes.shape[1]
    count = np.bincount(tets.ravel(), minlength=n_nodes).astype(float)
    out = np.zeros((n_nodes, 6 * m))
    U = modes.reshape(n_nodes, 3, m)
    flat = tets.ravel()
    for s in range(0, m, chunk):
        ue = U[tets, :, s : s + chunk]  # (E, 10, 3, c)
        grad = np.einsum("epaj,eaic->epijc", G, ue)  # du_i/dx_j
        eps = 0.5 * (grad + grad.transpose(0, 1, 3, 2, 4))
        tr = eps[:, :, 0, 0] + eps[:, :, 1, 1] + eps[:, :, 2, 2]
        comps = [
            lam * tr + 2 * mu * eps[:, :, 0, 0],
            lam * tr + 2 * mu * eps[:, :, 1, 1],
            lam * tr + 2 * mu * eps[:, :, 2, 2],
            2 * mu * eps[:, :, 1, 2],
            2 * mu * eps[:, :, 0, 2],
            2 * mu * eps[:, :, 0, 1],
        ]
        for c, val in enumerate(comps):  # val (E, 10, chunk)
            v = val.reshape(-1, val.shape[-1])
            for j in range(v.shape[1]):
                out[:, 6 * (s + j) + c] = np.bincount(flat, weights=v[:, j], minlength=n_nodes) / count
    return out


def von_mises(stress6: np.ndarray) -> np.ndarray:
    """von Mises stress [Pa] of (..., 6) stress components (xx, yy, zz, yz, xz, xy)."""
    s = np.asarray(stress6)
    xx, yy, zz, yz, xz, xy = (s[..., i] for i in range(6))
    return np.sqrt(0.5 * ((xx - yy) ** 2 + (yy - zz) ** 2 + (zz - xx) ** 2) + 3.0 * (yz**2 + xz**2 + xy**2))
