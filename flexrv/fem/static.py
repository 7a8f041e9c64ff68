"""Linear static FE solutions of a meshed part (full model, not reduced).

Used for stress checks under contact loads taken from a dynamic run (:cite:`seed003`'s
crankshaft under the needle-roller forces): spread each roller's force over the
raceway nodes of its angular sector, clamp the supports, solve K u = f with the
sparse LU of the free DOFs, and recover nodal von Mises stress.
"""

from __future__ import annotations

import numpy as np

from flexrv.errors import InputError


def solve_static(K, fixed_nodes: np.ndarray, forces: np.ndarray) -> np.ndarray:
    """Linear static displacements of a clamped FE model, K u = f (Zienkiewicz &
    Taylor, The Finite Element Method, vol. 1, ch. 2).

    Parameters
    ----------
    K : sparse (3N, 3N) stiffness matrix [N/m] (e.g. ``flexrv.fem.assembly.assemble(...).K``).
    fixed_nodes : indices of clamped nodes (all three DOFs zero).
    forces : (N, 3) nodal forces [N]; those on clamped nodes go straight to the support.

    Returns
    -------
    (N, 3) displacements [m].

    Raises
    ------
    InputError : wrong force size, or no clamped node (a free body is singular).
    """
    from flexrv.fem.modal import factorize, free_dofs

    f = np.asarray(forces, dtype=float).reshape(-1)
    n_dof = K.shape[0]
    if f.size != n_dof:
        raise InputError(f"forces have {f.size} DOFs, the stiffness matrix {n_dof}")
    if len(fixed_nodes) == 0:
        raise InputError("no clamped nodes: the static problem of a free body is singular")
    idofs = free_dofs(n_dof, np.asarray(fixed_nodes))
    u = np.zeros(n_dof)
    u[idofs] = factorize(K[idofs][:, idofs])(f[idofs])
    return u.reshape(-1, 3)


def sector_loads(
    nodes: np.ndarray, surface_nodes: np.ndarray, center_xy, angles, forces, half_width: float
) -> np.ndarray:
    """Nodal forces (N, 3) [N] that spread each load ``forces[i]`` (3,) [N] equally
    over the ``surface_nodes`` whose polar angle about the axis through
    ``center_xy`` lies within +/- ``half_width`` [rad] of ``angles[i]`` — a roller's
    line load along a cylindrical raceway. The resultant of every load is exact."""
    nodes = np.asarray(nodes, dtype=float)
    surface_nodes = np.asarray(surface_nodes)
    angles = np.atleast_1d(np.asarray(angles, dtype=float))
    forces = np.atleast_2d(np.asarray(forces, dtype=float))
    if forces.shape != (angles.size, 3):
        raise InputError(f"forces have shape {forces.shape}, expected ({angles.size}, 3) for {angles.size} angles")
    if not 0.0 < half_width <= np.pi:
        raise InputError(f"half_width = {half_width!r} rad must be in (0, pi]")
    p = nodes[surface_nodes, :2] - np.asarray(center_xy, dtype=float)
    theta = np.arctan2(p[:, 1], p[:, 0])
    sel = np.abs(np.angle(np.exp(1j * (theta[None, :] - angles[:, None])))) <= half_width  # (loads, surface)
    count = sel.sum(axis=1)
    if np.any(count == 0):
        a = angles[np.argmin(count)]
        raise InputError(f"no surface node within {np.degrees(half_width):.3g} deg of {np.degrees(a):.4g} deg")
    out = np.zeros_like(nodes)
    np.add.at(out, surface_nodes, (sel / count[:, None]).T @ forces)
    return out


def von_mises_field(
    nodes: np.ndarray, tets: np.ndarray, displacement: np.ndarray, youngs_modulus: float, poisson_ratio: float
) -> np.ndarray:
    """Nodal (averaged) von Mises stress [Pa] of a displacement field (N, 3)."""
    from flexrv.fem.stress import nodal_stress, von_mises

    s = nodal_stress(nodes, tets, np.asarray(displacement, dtype=float).reshape(-1, 1), youngs_modulus, poisson_ratio)
    return von_mises(s)
