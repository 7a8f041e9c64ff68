"""Main bearing as a multibody subsystem: rigid balls between (optionally flexible)
rings, one vectorised Exudyn contact element per row.

Members per row of the back-to-back pair:

* the **inner ring** rides on a rigid frame node (``NodeRigidBodyRxyz``: the
  carrier, or a frame rigidly joined to it). Its elastic raceway displacement is
  ``Phi_i(psi) q_i`` in the frame's coordinates. The inertia coupling between the
  ring's slow frame rotation (carrier, ~0.7-1.6 rad/s) and its elastic modes is
  neglected: centrifugal and Coriolis terms scale with omega_c^2 ~ 1 s^-2, eight
  orders below the modal stiffness terms omega_mode^2 > (2 pi 500 Hz)^2 — so no
  FFRF body is needed for the inner rings either;
* the **outer ring** sits in the housing (fixed frame), modal coordinates ``q_o``;
* **balls** are point masses (3 DOF each; why: :mod:`flexrv.contact.ball_raceway`)
  or, with ``ball_inertia=False`` (the ball model's default),
  **quasi-static**: massless, in force equilibrium at every instant, solved inside
  the row kernel (:func:`flexrv.model.bearing_kernel.quasi_static_balls`, a Newton
  per ball warm-started from a prediction; the element then has the frame's and
  modal rings' coordinates only, its Jacobian the balls' Schur complement). Why:
  the balls' inertia does not reach the transmission -- on rv40e the steady TE
  mean moved by < 1e-5 arcsec and its p-p by < 4e-4 arcsec with ball masses
  x0.1 / x1 / x10 (mean -166.3676", p-p 0.3924 / 0.3924 / 0.3927"), and
  quasi-static balls give -166.36764" / 0.39239" against -166.36759" / 0.39236"
  (0.30-0.40 s, benchmarks/bench_balls.py); the centrifugal load of a few-gram
  ball orbiting with the cage at < 1 rad/s is < 1e-4 N against contact loads of
  1-100 N -- while the ball coordinates (6 Z per bearing) and
  their stiff contact dynamics make up most of the system and its Newton
  iterations. Condensed rings couple all balls of a row (a dense 3Z block): there
  the balls keep their inertia (the flexible model's default);
* a kinematic **cage**: a tangential spring-damper pulls every ball towards its
  pocket at theta_cage + 2 pi j / Z, theta_cage = cage_ratio * theta_frame (pure
  rolling on a fixed outer ring). Without friction nothing else drives the balls
  circumferentially; the cage's reaction torque (stiffness x the balls' tiny lag)
  is carried by the kinematic constraint, not by the frame.

Rings given as ``None`` are rigid. A flexible ring (:class:`ModalRing`) is by
default quasi-static AND **condensed**: its massless modal
coordinates are not system coordinates; the row kernel solves the contact
deflections from the ring's compliance at the ball contacts
(:mod:`flexrv.model.bearing_kernel`), and the ring's modal amplitudes are
recovered from the recorded contact loads for the outputs and ``flexrv view``.
``condense=False`` keeps the massless modal coordinates as Exudyn coordinates
(the uncondensed formulation, for verification), ``quasi_static=False`` gives
the ring mass and modal damping (dynamic modes, then always uncondensed).

A row's contact element sees the coordinates [frame, modal rings' modes, balls];
its force and Jacobian are ONE compiled kernel, :func:`flexrv.model.bearing_kernel.row_eval`
(the only implementation of the bearing's physics: :func:`evaluate_row` and the
outputs call it too). In the reducer model the rows are a compiled force element of
the model's fused kernel (:class:`BallBearingGroup`, both integrators); the
stand-alone bearing (:func:`add_main_bearing`) adds one Exudyn element per row
(:class:`RowElement`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Protocol

import numpy as np

from flexrv.contact.ball_raceway import RowContactGeometry, hertz_law
from flexrv.errors import ConfigError
from flexrv.model.base import KernelGroup, Output, SummaryRow, exudyn_vector
from flexrv.model.bearing_kernel import (
    BALL_FORCE_TOL,
    N_RECORD,
    RECORD_FIELDS,
    BearingRowsPack,
    RowGeometry,
    RowPack,
    ball_workspace,
    condense_workspace,
    film_workspace,
    law_parameters,
    ring_modal_amplitudes,
    row_element,
    row_force_kernel,
    row_kernel,
    rows_kernel,
)
from flexrv.model.core.params import check_pack, empty_pack
from flexrv.units import M_PER_MM

_REC = {name: i for i, name in enumerate(RECORD_FIELDS)}


class RingModes(Protocol):
    """What the bearing needs of a reduced flexible ring (one row's ring)."""

    mass: np.ndarray  #: (m, m) reduced mass matrix [kg]
    stiffness: np.ndarray  #: (m, m) reduced stiffness matrix [N/m]
    damping: np.ndarray  #: (m, m) reduced damping matrix [N s/m]
    table: np.ndarray  #: (n_grid, 3, m) cylindrical raceway displacement per modal coordinate
    mirror: bool  #: z -> -z image of the table (second row of the pair)
    condensed: bool  #: True: modal coordinates condensed into the row element

    def groove_basis(self, azimuth: np.ndarray) -> np.ndarray:
        """(N, 3, m): groove-centre displacement (ring frame, Cartesian) per unit
        modal coordinate at the given azimuths [rad]."""


@dataclass
class ModalRing:
    """:class:`RingModes` view of a reduced ring (:class:`flexrv.fem.body.ReducedBody`).

    The meshed ring is the row with outer-contact side s = +1
    (:meth:`flexrv.geometry.bearing.BallBearingGeometry.ring_section`); the other
    row of the back-to-back pair is its mirror image z -> -z (``mirror=True``).
    ``stiffness_scale`` multiplies the ring's stiffness (a stiffened ring for the
    stiff-ring consistency checks; 1 = the real ring).

    ``quasi_static=True`` (default) drops the ring's inertia: K q = Q(contacts)
    holds at every instant. Justification: with the fit clamped (rigid housing /
    carrier) the lowest ring mode is 47-260 kHz (rv221 / rv40e,
    ``frequencies_hz``; :func:`flexible_rings` records it), 2-3 orders above every
    excitation of the bearing (ball pass < 1 kHz, first-stage mesh < 1 kHz), so
    the ring's dynamic amplification (f/f_1)^2 < 1e-4 — while these stiff modes
    (omega dt ~ 100) make the modified Newton iteration of the dynamic version
    take ~5x more iterations and ~100x more Jacobians (measured: rv40e, 5 ms: 278
    vs 88 Newton iterations, 96 vs 1 Jacobians). No dynamic ring mode is
    therefore kept by default: all modes of a quasi-static ring are condensed
    (``condense=True``, see the module docstring). ``quasi_static=False`` keeps
    M = I and modal damping ``damping_ratio`` as system coordinates.
    """

    body: object
    damping_ratio: float = field(
        kw_only=True
    )  #: modal damping of a dynamic ring (design main_bearing.ring_damping_ratio)
    mirror: bool = False
    stiffness_scale: float = 1.0
    quasi_static: bool = True
    condense: bool = True

    @property
    def n_modes(self) -> int:
        return int(self.body.n_modes)

    @property
    def condensed(self) -> bool:
        return bool(self.quasi_static and self.condense)

    @property
    def mass(self) -> np.ndarray:
        return (0.0 if self.quasi_static else 1.0) * np.asarray(self.body.mass_matrix, dtype=float)

    @property
    def stiffness(self) -> np.ndarray:
        return self.stiffness_scale * np.asarray(self.body.stiffness_matrix, dtype=float)

    @property
    def damping(self) -> np.ndarray:
        if self.quasi_static:
            return np.zeros((self.n_modes, self.n_modes))
        omega2 = self.stiffness_scale * np.asarray(self.body.omega2, dtype=float)
        return np.diag(2.0 * self.damping_ratio * np.sqrt(omega2))

    @property
    def table(self) -> np.ndarray:
        return np.ascontiguousarray(self.body.table, dtype=float)

    @property
    def compliance_factors(self) -> np.ndarray:
        """(n_grid, 3, m) raceway table times K^-1/2 of the (scaled) ring: the
        compliance at the contacts is W_j W_k^T
        (:meth:`flexrv.fem.body.ReducedBody.raceway_compliance_factors`)."""
        return self.body.raceway_compliance_factors(self.stiffness_scale)

    @property
    def compliance_diag(self) -> np.ndarray:
        """1 / diag K [m/N] (the reduced stiffness is diagonal, K = diag(omega^2))."""
        return 1.0 / (self.stiffness_scale * np.asarray(self.body.omega2, dtype=float))

    def groove_basis(self, azimuth: np.ndarray) -> np.ndarray:
        basis = np.array(self.body.raceway_matrix(azimuth), dtype=float)
        if self.mirror:
            basis[..., 2, :] *= -1.0
        return basis


def rxyz_matrices(phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotation matrix A = Rx Ry Rz and G (omega_global = G phi_dot) of the
    Tait–Bryan xyz angles of Exudyn's NodeRigidBodyRxyz (Exudyn's own utilities)."""
    from exudyn.rigidBodyUtilities import RotXYZ2G, RotXYZ2RotationMatrix

    return np.asarray(RotXYZ2RotationMatrix(phi)), np.asarray(RotXYZ2G(phi))


def _is_condensed(ring) -> bool:
    return ring is not None and bool(getattr(ring, "condensed", False))


@dataclass
class RowModel:
    """Everything one row's contact element needs (SI).

    ``z`` is the axial position of the row's ball plane in the frame (and housing)
    coordinates; ``row`` holds the groove-centre loci in row coordinates.
    Condensed rings (:class:`ModalRing` with ``condensed``) add no coordinates.
    """

    row: RowContactGeometry
    z: float
    ball_count: int
    ball_mass: float
    law_inner: object  #: NormalLaw, or an EHL law with ``normal_law(speed)``
    law_outer: object
    inner: RingModes | None = None
    outer: RingModes | None = None
    #: tangential spring [N/m] and damper [N s/m] of each ball to its cage pocket, and the
    #: weak radial/axial spring to the pocket [N/m]: the design's main_bearing.cage_* /
    #: pocket_* estimates (presets, with provenance)
    cage_stiffness: float = field(kw_only=True)
    cage_damping: float = field(kw_only=True)
    pocket_stiffness: float = field(kw_only=True)
    #: cage angle / frame (inner ring) angle for pure rolling with a fixed outer
    #: ring: (1 - D cos a / d_m) / 2 (:meth:`flexrv.geometry.bearing.BallBearingGeometry.cage_speed`)
    cage_ratio: float = field(kw_only=True)
    #: entrainment speed per unit frame (inner ring) angular speed [m]:
    #: u = (d_m/4)(1 - gamma^2)|omega| (Hamrock 1994, ch. 24)
    speed_factor: float = 0.0
    #: effective radii (rx, ry) [m] of the inner contact and the effective modulus
    #: E' [Pa] (for the Hertz pressure output; None: not reported)
    inner_radii: tuple | None = None
    e_eff: float = 0.0
    #: True: every ball is a point mass with 3 element coordinates; False: the balls are
    #: quasi-static (massless, in force equilibrium at every instant, solved inside the
    #: row kernel, :func:`flexrv.model.bearing_kernel.quasi_static_balls`; rigid or
    #: uncondensed modal rings only) and the element has the frame and modal coordinates
    ball_inertia: bool = field(default=True, kw_only=True)
    #: reference ball centres (Z, 3) in global coordinates
    ball_reference: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        self._sizes = tuple(
            0 if (r is None or _is_condensed(r)) else r.stiffness.shape[0] for r in (self.inner, self.outer)
        )
        if not self.ball_inertia and (_is_condensed(self.inner) or _is_condensed(self.outer)):
            raise ConfigError(
                "quasi-static balls (ball_inertia = false) need rigid or uncondensed modal rings: "
                "a condensed ring couples every ball of the row"
            )
        psi = 2.0 * np.pi * np.arange(self.ball_count) / self.ball_count
        rb = self.row.ball_radius_pitch
        self.ball_reference = np.stack([rb * np.cos(psi), rb * np.sin(psi), np.full(self.ball_count, self.z)], -1)

    @property
    def m_inner(self) -> int:
        return self._sizes[0]

    @property
    def m_outer(self) -> int:
        return self._sizes[1]

    @property
    def n_ball_coordinates(self) -> int:
        """3 Z with ball inertia, 0 for quasi-static balls (not element coordinates)."""
        return 3 * self.ball_count if self.ball_inertia else 0

    @property
    def n_coordinates(self) -> int:
        return 6 + self.m_inner + self.m_outer + self.n_ball_coordinates

    @property
    def n_kernel(self) -> int:
        """Length of the row kernel's full coordinate vector (frame, modes, 3Z balls)."""
        return 6 + self.m_inner + self.m_outer + 3 * self.ball_count

    def slices(self) -> tuple[slice, slice, slice, slice]:
        """Coordinate slices of frame, inner modes, outer modes, balls in the element."""
        a = 6 + self.m_inner
        b = a + self.m_outer
        return slice(0, 6), slice(6, a), slice(a, b), slice(b, b + self.n_ball_coordinates)

    def ring_nodes(self) -> list[str]:
        """Labels of the rings with modal coordinates in the element ("inner", "outer")."""
        return [label for label, m in (("inner", self.m_inner), ("outer", self.m_outer)) if m > 0]


_NO_TABLE = np.zeros((1, 3, 0))
_NO_COMPLIANCE = np.zeros((0, 3, 0))


def _ring_arrays(ring, ball_count: int) -> tuple:
    """(modal table, z sign, compliance factors, work array) of a ring for the kernel."""
    if ring is None:
        return _NO_TABLE, 1.0, _NO_COMPLIANCE, film_workspace(ball_count)
    zs = -1.0 if getattr(ring, "mirror", False) else 1.0
    table = getattr(ring, "table", None)
    if table is None:
        raise ConfigError(f"ring model {type(ring).__name__} has no raceway table: the bearing kernel needs one")
    table = np.ascontiguousarray(table, dtype=float)
    if _is_condensed(ring):
        factors = np.ascontiguousarray(ring.compliance_factors, dtype=float)
        return _NO_TABLE, zs, factors, condense_workspace(ball_count, factors.shape[2])
    return table, zs, _NO_COMPLIANCE, film_workspace(ball_count)


def kernel_inputs(model: RowModel) -> RowPack:
    """The :data:`~flexrv.model.bearing_kernel.RowPack` of a row, the argument of the row
    kernels (:func:`flexrv.model.bearing_kernel.row_kernel`) after (q, q_t), prepared once
    per row and kept on it (the condensed rings' deflections are the local solve's warm
    start). A law the kernel does not cover is refused."""
    inputs = getattr(model, "_kernel_inputs", None)
    if inputs is not None:
        return inputs
    laws = []
    for side, law in (("inner", model.law_inner), ("outer", model.law_outer)):
        p = law_parameters(law)
        if p is None:
            mode = getattr(law, "mode", type(law).__name__)
            raise ConfigError(
                f"contact law {mode!r} is not supported by the ball-resolved main bearing "
                f"({side} contact): use contact.ehl = 'dry', 'hamrock_dowson' or 'map' "
                f"(one contact geometry per ring: scalar radii)"
            )
        laws.append(p)
    tab_i, zs_i, comp_i, ws_i = _ring_arrays(model.inner, model.ball_count)
    tab_o, zs_o, comp_o, ws_o = _ring_arrays(model.outer, model.ball_count)
    row = model.row
    geometry = RowGeometry.of(
        z=model.z,
        inner_center_radius=row.inner_center_radius,
        inner_center_z=row.inner_center_z,
        outer_center_radius=row.outer_center_radius,
        outer_center_z=row.outer_center_z,
        inner_offset=row.inner_offset,
        outer_offset=row.outer_offset,
        ball_radius_pitch=row.ball_radius_pitch,
        speed_factor=model.speed_factor,
        cage_ratio=model.cage_ratio,
        cage_stiffness=model.cage_stiffness,
        cage_damping=model.cage_damping,
        pocket_stiffness=model.pocket_stiffness,
        quasi_static_balls=not model.ball_inertia,
        ball_force_tol=0.0 if model.ball_inertia else BALL_FORCE_TOL,
    )
    # quasi-static balls: the local solve's work array, its first warm start the preload
    # equilibrium; with ball inertia the balls are element coordinates
    balls = np.zeros(0)
    if not model.ball_inertia:
        balls = ball_workspace(model.ball_count, model.n_coordinates)
        balls[: 3 * model.ball_count] = initial_ball_displacements(model).ravel()
    inputs = RowPack(
        ball_ref=np.ascontiguousarray(model.ball_reference, dtype=float),
        geometry=geometry,
        law_i=laws[0],
        law_o=laws[1],
        tab_i=tab_i,
        tab_o=tab_o,
        comp_i=comp_i,
        comp_o=comp_o,
        ws_i=ws_i,
        ws_o=ws_o,
        zsign=np.array([zs_i, zs_o]),
        balls=balls,
        state=np.zeros(8, np.int64),
    )
    check_pack(inputs)
    model._kernel_inputs = inputs
    model._kernel_initial = (ws_i.copy(), ws_o.copy(), balls.copy())
    return inputs


def fresh_kernel_inputs(model: RowModel) -> RowPack:
    """The row's kernel inputs (:func:`kernel_inputs`) with fresh warm starts: the rings'
    and the quasi-static balls' work arrays as first prepared, zero statistics (a history
    pass that does not depend on the calls before it)."""
    inputs = kernel_inputs(model)
    ws_i, ws_o, balls = model._kernel_initial
    return inputs._replace(ws_i=ws_i.copy(), ws_o=ws_o.copy(), balls=balls.copy(), state=np.zeros(8, np.int64))


def set_ball_force_tolerance(model: RowModel, tol: float) -> None:
    """Set the relative force tolerance of a row's quasi-static balls (:data:`BALL_FORCE_TOL`
    by default) in its prepared kernel inputs: for studies of the local solve's tolerance."""
    inputs = kernel_inputs(model)
    if not inputs.geometry.quasi_static_balls:
        raise ValueError("the row's balls are element coordinates (ball inertia): no local solve")
    model._kernel_inputs = inputs._replace(geometry=inputs.geometry._replace(ball_force_tol=float(tol)))


def row_force(model: RowModel, q: np.ndarray, q_t: np.ndarray) -> np.ndarray:
    """Generalized force of a row element (compiled row kernel)."""
    return row_force_kernel(
        np.ascontiguousarray(q, dtype=float), np.ascontiguousarray(q_t, dtype=float), kernel_inputs(model)
    )


_NO_RECORD = np.zeros((0, N_RECORD))


def row_jacobian(model: RowModel, q: np.ndarray, q_t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(d force/d q, d force/d q_t) of a row element (compiled row kernel)."""
    _, jq, jv = row_kernel(
        np.ascontiguousarray(q, dtype=float),
        np.ascontiguousarray(q_t, dtype=float),
        kernel_inputs(model),
        True,
        _NO_RECORD,
    )
    return jq, jv


@dataclass
class RaceContacts:
    """One ring's contacts with the balls of a row (arrays over the balls, global frame)."""

    load: np.ndarray  #: (Z,) normal load [N]
    normal: np.ndarray  #: (Z, 3) unit normal, groove centre -> ball
    displacement: np.ndarray  #: (Z, 3) raceway displacement of the ring at the contact [m]
    azimuth: np.ndarray  #: (Z,) contact azimuth in the ring's frame [rad]
    ring_load: np.ndarray  #: (Z, 3) contact force on the ring in the ring's own frame [N]

    @property
    def force_ball(self) -> np.ndarray:
        """(Z, 3) force of the ring on each ball [N]."""
        return -self.load[:, None] * self.normal

    @property
    def contact_angle(self) -> np.ndarray:
        """(Z,) angle of the normal to the radial plane [rad]."""
        return np.arctan2(np.abs(self.normal[:, 2]), np.hypot(self.normal[:, 0], self.normal[:, 1]))


@dataclass
class RowEvaluation:
    """Result of :func:`evaluate_row` (arrays over the row's balls)."""

    inner: RaceContacts
    outer: RaceContacts
    force: np.ndarray  # (n,) generalized force vector of the element
    jac_q: np.ndarray | None  # (n, n) d force / d q
    jac_v: np.ndarray | None  # (n, n) d force / d q_t
    ball_pos: np.ndarray
    azimuth: np.ndarray  # (Z,) ball azimuths in the housing [rad]


def _contacts(rec: np.ndarray, label: str) -> RaceContacts:
    s = label[0]
    return RaceContacts(
        load=rec[:, _REC[f"load_{label}"]].copy(),
        normal=rec[:, [_REC[f"n{s}x"], _REC[f"n{s}y"], _REC[f"n{s}z"]]],
        displacement=rec[:, [_REC[f"u{s}x"], _REC[f"u{s}y"], _REC[f"u{s}z"]]],
        azimuth=rec[:, _REC[f"psi_{label}"]].copy(),
        ring_load=rec[:, [_REC[f"g{s}x"], _REC[f"g{s}y"], _REC[f"g{s}z"]]],
    )


def evaluate_row(model: RowModel, q: np.ndarray, q_t: np.ndarray, jacobian: bool = True) -> RowEvaluation:
    """Generalized forces (and Jacobians) of one row's contact element with every
    contact's state — one call of the compiled row kernel.

    Parameters
    ----------
    q, q_t : element coordinates and velocities (displacements from the reference
        configuration), ordered [frame(6), inner modes, outer modes, balls(3Z)].
    """
    rec = np.zeros((model.ball_count, N_RECORD))
    f, jq, jv = row_kernel(
        np.ascontiguousarray(q, dtype=float),
        np.ascontiguousarray(q_t, dtype=float),
        kernel_inputs(model),
        bool(jacobian),
        rec,
    )
    return RowEvaluation(
        inner=_contacts(rec, "inner"),
        outer=_contacts(rec, "outer"),
        force=f,
        jac_q=jq if jacobian else None,
        jac_v=jv if jacobian else None,
        ball_pos=rec[:, [_REC["bx"], _REC["by"], _REC["bz"]]],
        azimuth=rec[:, _REC["psi_outer"]].copy(),
    )


def ring_modal_coordinates(model: RowModel, label: str, q: np.ndarray, ev: RowEvaluation) -> np.ndarray:
    """Modal amplitudes of a row's flexible ring: the element coordinates of a modal
    ring, or q = K^-1 sum_j B_j^T g_j of a condensed one from its contact loads."""
    ring = getattr(model, label)
    if not _is_condensed(ring):
        _, si, so, _ = model.slices()
        return np.asarray(q)[si if label == "inner" else so].copy()
    st = getattr(ev, label)
    zs = -1.0 if ring.mirror else 1.0
    return ring_modal_amplitudes(
        np.ascontiguousarray(st.azimuth)[None],
        np.ascontiguousarray(st.ring_load)[None],
        ring.table,
        zs,
        np.ascontiguousarray(ring.compliance_diag),
    )[0]


# ---------------------------------------------------------------------------- Exudyn
@dataclass
class BearingHandle:
    """Node/object indices of a bearing added to an Exudyn system."""

    rows: list[RowModel]
    frame_node: int
    inner_nodes: list[int | None]
    outer_nodes: list[int | None]
    ball_nodes: list[list[int]]
    contact_objects: list[int]

    def element_coordinates(self, mbs, row_index: int, configuration=None) -> tuple[np.ndarray, np.ndarray]:
        """Current (q, q_t) of a row's contact element read from the system."""
        import exudyn as exu

        cfg = configuration or exu.ConfigurationType.Current
        nodes = [self.frame_node]
        if self.inner_nodes[row_index] is not None:
            nodes.append(self.inner_nodes[row_index])
        if self.outer_nodes[row_index] is not None:
            nodes.append(self.outer_nodes[row_index])
        nodes += self.ball_nodes[row_index]
        q = np.concatenate([np.asarray(mbs.GetNodeOutput(n, exu.OutputVariableType.Coordinates, cfg)) for n in nodes])
        q_t = np.concatenate(
            [np.asarray(mbs.GetNodeOutput(n, exu.OutputVariableType.Coordinates_t, cfg)) for n in nodes]
        )
        return q, q_t


def initial_ball_displacements(model: RowModel) -> np.ndarray:
    """Ball displacements (Z,3) that balance the contact forces with the frame and
    rings in their reference configuration (preload equilibrium), so a static or
    dynamic run starts without an artificial transient."""
    from flexrv.contact.ball_raceway import solve_ball_positions

    psi = 2.0 * np.pi * np.arange(model.ball_count) / model.ball_count
    ci = model.row.groove_centers(psi, "inner")
    co = model.row.groove_centers(psi, "outer")
    ci[:, 2] += model.z
    co[:, 2] += model.z
    law_i = model.law_inner.normal_law(0.0) if hasattr(model.law_inner, "normal_law") else model.law_inner
    law_o = model.law_outer.normal_law(0.0) if hasattr(model.law_outer, "normal_law") else model.law_outer
    pos, st_i, st_o = solve_ball_positions(model.row, ci, co, law_i, law_o, ball_pos0=model.ball_reference)
    return pos - model.ball_reference


def row_work(row: RowModel, record: bool = True) -> tuple:
    """The work arrays of one row's evaluation (:func:`flexrv.model.bearing_kernel.row_part`
    after its idx): qe, ve, f over the kernel's full coordinate vector (quasi-static balls:
    the work vectors also hold the balls); the row Jacobians jq, jv (n, n) with ball
    inertia, zero-allocated (the kernel writes only its nonzero entries); the per-ball
    records (Z, N_RECORD) if ``record`` (else none); for quasi-static balls the balls'
    blocks kbb (3Z, 4) and the condensed Jacobians kx, cx (n, n) instead."""
    m, full = row.n_coordinates, row.n_kernel
    nj, nb, nk = (m, 0, 0) if row.ball_inertia else (0, 3 * row.ball_count, m)
    return (
        np.zeros(full),
        np.zeros(full),
        np.zeros(full),
        np.zeros((nj, nj)),
        np.zeros((nj, nj)),
        np.zeros((row.ball_count if record else 0, N_RECORD)),
        np.zeros((nb, 4)),
        np.zeros((nk, nk)),
        np.zeros((nk, nk)),
    )


class RowElement:
    """The Exudyn glue of bearing rows outside the reducer model (the stand-alone bearing
    of :func:`add_main_bearing`; the reducer model's rows are a compiled element of its
    fused kernel, :class:`BallBearingGroup`): one Exudyn element for one or more rows, one
    compiled call (:func:`flexrv.model.bearing_kernel.row_element`) per force or Jacobian
    evaluation into arrays preallocated here — per row the gather of its element
    coordinates from the nodes' (``idx``: row element coordinate -> nodes'
    coordinate; ``absolute``: the nodes hold absolute ball positions, the reference
    is subtracted), the row kernel, and the sum over the rows in the nodes' order
    (for the Jacobian Exudyn's -(f_q dF/dq + f_v dF/dq_t)). The returned arrays are
    reused by the next call (Exudyn copies them). The compiled entry point is
    called directly after the first call (skips numba's typing of the arguments,
    whose types never change: :meth:`_call`). ``stats`` counts the force and
    Jacobian calls.

    ``record``: every call also fills each row's per-ball records (:attr:`records`,
    (Z, N_RECORD), :data:`flexrv.model.bearing_kernel.RECORD_FIELDS`) and keeps its
    element force (:meth:`frame_force`: the frame's six, element order), and
    :attr:`memo` = (t, q, q_t) of the call they belong to."""

    def __init__(self, rows, idx=None, absolute: bool = False, stats: list | None = None, record: bool = False):
        rows = [rows] if isinstance(rows, RowModel) else list(rows)
        idxs = (
            [idx] if (idx is None or np.ndim(idx) == 1 and len(rows) == 1 and not isinstance(idx, list)) else list(idx)
        )
        if len(idxs) != len(rows):
            raise ValueError("one coordinate map per row")
        self.rows = rows
        self.idx = [
            np.ascontiguousarray(np.arange(r.n_coordinates) if i is None else i, dtype=np.int64)
            for r, i in zip(rows, idxs)
        ]
        n = 1 + max(int(i.max()) for i in self.idx)
        self.absolute = bool(absolute)
        self.stats = [0, 0] if stats is None else stats
        self._work = []
        for r, i in zip(rows, self.idx):
            if i.shape != (r.n_coordinates,):
                raise ValueError(f"coordinate map of shape {i.shape} for a row of {r.n_coordinates} coordinates")
            self._work.append((i, *row_work(r, record)))
        self.out_f, self.out_j = np.zeros(n), np.zeros((n, n))
        self._entry = None
        self._parts = None
        #: (t, q, q_t) of the last call (the nodes' coordinates, copies), None during a call
        self.memo = None

    @property
    def records(self) -> list[np.ndarray]:
        """Per row, the live per-ball records (Z, N_RECORD) of the last call (``record``)."""
        return [w[6] for w in self._work]

    def frame_force(self, k: int) -> np.ndarray:
        """Live view of row k's generalized force on the frame coordinates (element
        order x, y, z, rx, ry, rz) of the last call."""
        return self._work[k][3][:6]

    def _call(self, t, q, q_t, jacobian: bool, f_q: float, f_v: float) -> None:
        self.memo = None  # until the call has filled the records
        parts = self._parts
        if parts is None:  # (the rows' kernel inputs are made once and kept on them)
            parts = self._parts = tuple((*w, kernel_inputs(r)) for w, r in zip(self._work, self.rows))
        qn, vn = exudyn_vector(q), exudyn_vector(q_t)
        args = (qn, vn, self.absolute, jacobian, f_q, f_v, self.out_f, self.out_j, parts)
        if self._entry is not None:
            self._entry(*args)
        else:
            row_element(*args)
            from numba import typeof

            cres = row_element.overloads.get(tuple(typeof(x) for x in args))
            self._entry = None if cres is None else cres.entry_point
        self.memo = (t, qn, vn)

    def force(self, q, q_t, t: float = 0.0) -> np.ndarray:
        """Generalized force in the nodes' coordinate order (q, q_t: the nodes' coordinates)."""
        self.stats[0] += 1
        self._call(t, q, q_t, False, 0.0, 0.0)
        return self.out_f

    def jacobian(self, q, q_t, f_q, f_v, t: float = 0.0) -> np.ndarray:
        """Exudyn's -(f_q dF/dq + f_v dF/dq_t) in the nodes' coordinate order."""
        self.stats[1] += 1
        self._call(t, q, q_t, True, float(f_q), float(f_v))
        return self.out_j

    def add_to(self, mbs, nodes: list[int]) -> int:
        """Add this element to ``mbs`` as ONE ``ObjectGenericODE2`` over ``nodes`` whose
        force and Jacobian user functions call it; returns the object number."""
        from exudyn.itemInterface import ObjectGenericODE2

        def force_fn(mbs_, t, item, q, q_t):
            return self.force(q, q_t, t)

        def jac_fn(mbs_, t, item, q, q_t, f_q, f_v):
            return self.jacobian(q, q_t, f_q, f_v, t)

        return mbs.AddObject(
            ObjectGenericODE2(nodeNumbers=nodes, forceUserFunction=force_fn, jacobianUserFunction=jac_fn)
        )


def add_row_element(mbs, rows, nodes: list[int], idx=None, absolute: bool = False, stats: list | None = None) -> int:
    """Add bearing rows to ``mbs`` as ONE ``ObjectGenericODE2`` over ``nodes`` whose
    force and Jacobian user functions are a :class:`RowElement` (the compiled row
    kernel). ``rows``: a :class:`RowModel` or a list; ``idx``: per row, its element
    coordinates [frame(6), inner modes, outer modes, balls(3Z)] -> the nodes'
    coordinates (default for one row: the same order); ``absolute``: the nodes
    hold absolute ball positions; ``stats`` counts the force and Jacobian calls.
    The stand-alone bearing of :func:`add_main_bearing` (one element per row; the
    reducer model's :class:`BallBearingGroup` adds its recording elements by
    :meth:`RowElement.add_to` itself). Returns the object number."""
    return RowElement(rows, idx, absolute, stats).add_to(mbs, nodes)


def add_main_bearing(mbs, rows: list[RowModel], frame_node: int) -> BearingHandle:
    """Add balls, ring modal bodies and one contact element per row to ``mbs``.

    ``frame_node`` must be a ``NodeRigidBodyRxyz`` at the origin (reference
    position 0, reference rotation 0) carrying the inner rings.
    """
    from exudyn.itemInterface import MassPoint, NodeGenericODE2, NodePoint, ObjectGenericODE2

    inner_nodes, outer_nodes, ball_nodes, objects = [], [], [], []
    for model in rows:
        node_list = [frame_node]
        for ring, store in ((model.inner, inner_nodes), (model.outer, outer_nodes)):
            if ring is None or _is_condensed(ring):
                store.append(None)
                continue
            m = ring.stiffness.shape[0]
            node = mbs.AddNode(
                NodeGenericODE2(
                    referenceCoordinates=[0.0] * m,
                    initialCoordinates=[0.0] * m,
                    initialCoordinates_t=[0.0] * m,
                    numberOfODE2Coordinates=m,
                )
            )
            mbs.AddObject(
                ObjectGenericODE2(
                    nodeNumbers=[node], massMatrix=ring.mass, stiffnessMatrix=ring.stiffness, dampingMatrix=ring.damping
                )
            )
            store.append(node)
            node_list.append(node)
        balls = []
        for ref, init in zip(model.ball_reference, initial_ball_displacements(model) if model.ball_inertia else []):
            nb = mbs.AddNode(NodePoint(referenceCoordinates=list(ref), initialCoordinates=list(init)))
            mbs.AddObject(MassPoint(mass=model.ball_mass, nodeNumber=nb))
            balls.append(nb)
        ball_nodes.append(balls)
        node_list += balls

        objects.append(add_row_element(mbs, model, node_list))
    return BearingHandle(
        rows=rows,
        frame_node=frame_node,
        inner_nodes=inner_nodes,
        outer_nodes=outer_nodes,
        ball_nodes=ball_nodes,
        contact_objects=objects,
    )


def rows_from_design(
    reducer,
    inner=None,
    outer=None,
    ehl: str | None = None,
    c_max: float | None = None,
    depth: float | None = None,
    ball_inertia: bool = True,
) -> list[RowModel]:
    """Row models of a design's main bearing (both rows, back-to-back).

    Parameters
    ----------
    inner, outer : per-row lists of :class:`RingModes` (``None``: rigid rings).
    ehl : ``"dry"``, ``"hamrock_dowson"`` or ``"map"`` (default: ``reducer.contact.ehl``);
        the lubricated laws come from :class:`flexrv.ehl.law.EHLPointLaw`
        and use the entrainment speed of the frame's rotation.
    c_max, depth : contact damping and its ramp depth (default: the design's).
    ball_inertia : False: quasi-static balls (:attr:`RowModel.ball_inertia`).
    """
    from flexrv.contact.hertz import effective_modulus
    from flexrv.ehl.law import EHLPointLaw
    from flexrv.geometry.bearing import BallBearingGeometry

    geom = BallBearingGeometry.from_design(reducer.main_bearing)
    mb = reducer.main_bearing
    ring_mat, ball_mat = reducer.material("bearing_rings"), reducer.material("rolling_elements")
    e_eff = float(
        effective_modulus(
            ring_mat.youngs_modulus, ring_mat.poisson_ratio, ball_mat.youngs_modulus, ball_mat.poisson_ratio
        )
    )
    c_max = reducer.main_bearing.ball_damping_Ns_per_m if c_max is None else c_max
    depth = reducer.contact.impact_damping_depth_mm * M_PER_MM if depth is None else depth
    ehl = reducer.contact.ehl if ehl is None else ehl
    rx_i, ry_i, rx_o, ry_o = geom.contact_radii()
    if ehl == "dry":
        laws = None
    else:
        laws = [
            replace(EHLPointLaw.from_design(reducer, float(rx), float(ry), mode=ehl), c_max=c_max, damping_depth=depth)
            for rx, ry in ((rx_i, ry_i), (rx_o, ry_o))
        ]
    speed_factor = 0.25 * geom.pitch_diameter * (1.0 - geom.gamma**2)
    rows = []
    for k, (z, side) in enumerate(zip(geom.row_positions(), geom.row_sides())):
        row = RowContactGeometry.from_bearing(geom, e_eff, side=float(side), preload=geom.axial_preload)
        if laws is None:
            law_i, law_o = hertz_law(row.k_inner, c_max, depth), hertz_law(row.k_outer, c_max, depth)
        else:
            law_i, law_o = laws
        rows.append(
            RowModel(
                row=row,
                z=float(z),
                ball_count=geom.ball_count,
                cage_ratio=float(geom.cage_speed(1.0, 0.0)),  # cage turns per frame (inner ring) turn
                cage_stiffness=mb.cage_stiffness_N_per_m,
                cage_damping=mb.cage_damping_Ns_per_m,
                pocket_stiffness=mb.pocket_stiffness_N_per_m,
                ball_mass=geom.ball_mass(ball_mat.density_kg_m3),
                law_inner=law_i,
                law_outer=law_o,
                speed_factor=speed_factor,
                inner_radii=(float(rx_i), float(ry_i)),
                e_eff=e_eff,
                inner=None if inner is None else inner[k],
                outer=None if outer is None else outer[k],
                ball_inertia=ball_inertia,
            )
        )
    return rows


#: raceway Fourier harmonics K (None: the reduction's patch-width default,
#: :func:`flexrv.fem.reduction.default_harmonics`) and fixed-interface
#: eigenmodes of the rings: 12 for dynamic rings; none for quasi-static
#: (condensed) rings, whose static compliance at the raceway is exact in the span
#: of the raceway attachment modes alone (see :func:`flexible_rings`)
RING_HARMONICS = None
RING_EIGENMODES = 12
RING_EIGENMODES_QUASI_STATIC = 0


def flexible_rings(
    reducer,
    harmonics: int | None = RING_HARMONICS,
    n_eig: int | None = None,
    size: float | None = None,
    damping_ratio: float | None = None,
    stiffness_scale: float = 1.0,
    quasi_static: bool = True,
    rings: tuple[str, ...] = ("inner", "outer"),
    condense: bool = True,
) -> dict:
    """Reduced flexible rings of a design's main bearing for both rows.

    Returns ``{"inner": [row0, row1], "outer": [row0, row1], "bodies": {...}}`` with
    :class:`ModalRing` views (row 1 mirrored) and, under ``"bodies"``, the
    :func:`flexrv.fem.body.reduce_part` arguments that rebuild each body (cache hit)
    for post-processing (:mod:`flexrv.viz.rings`).

    Basis: HCB with the fit surface clamped (ring pressed into a rigid housing /
    onto a rigid carrier), ``n_eig`` fixed-interface eigenmodes and 2K+1 Fourier
    raceway load modes. K must exceed the ball count Z: Z equal ball loads excite
    the harmonics 0, Z, 2Z, ... of the local dent under each ball, and a basis
    without them misses it. Measured (rv221, Z = 26, :cite:`seed001`'s 20 kN radial +
    15 kN axial, deflection at the loaded balls vs the full FE, see
    tests/test_model_flexible_rings.py): K = 24/40/57/80 -> -42/2.7/0.08/0.04 %.
    The default K is the reduction's patch-width rule (57 for rv221).

    ``condense`` (default True): quasi-static rings are condensed into the row
    elements (no modal system coordinates); False keeps their massless
    modal coordinates (the uncondensed formulation, for verification).

    ``n_eig`` (None: :data:`RING_EIGENMODES` for dynamic rings,
    :data:`RING_EIGENMODES_QUASI_STATIC` = 0 for quasi-static ones). A
    quasi-static ring only needs its static compliance at the raceway, which the
    attachment modes of the raceway loads span exactly; the fixed-interface
    eigenmodes were 45 % of the cold build of the rv221 rings (23 of 54 s CPU)
    and 12 of the 127 modes the condensed kernel carries. The recorded lowest
    mode (``lowest_mode_hz``) is then the Ritz estimate of the attachment basis
    (an upper bound; measured rv221 outer ring: bench_flexible_model).
    """
    from flexrv.fem.body import body_identity, reduce_part

    if n_eig is None:
        n_eig = RING_EIGENMODES_QUASI_STATIC if quasi_static else RING_EIGENMODES
    out: dict = {"bodies": {}}
    for label in rings:
        if label not in ("inner", "outer"):
            raise ConfigError(f"ring = {label!r} is not allowed: choose 'inner' or 'outer'")
        part = f"{label}_ring"
        settings = {"size": size, "n_eig": int(n_eig), "n_harmonics": None if harmonics is None else int(harmonics)}
        body = reduce_part(reducer, part, **settings)
        zeta = reducer.main_bearing.ring_damping_ratio if damping_ratio is None else float(damping_ratio)
        opts = dict(
            damping_ratio=zeta, stiffness_scale=stiffness_scale, quasi_static=quasi_static, condense=bool(condense)
        )
        out[label] = [ModalRing(body, **opts), ModalRing(body, mirror=True, **opts)]
        out["bodies"][part] = {**settings, "identity": body_identity(body)}  # view loads this body, never re-meshes
        out.setdefault("lowest_mode_hz", {})[part] = float(np.sqrt(stiffness_scale) * body.frequencies_hz.min())
    return out


# ------------------------------------------------------------ reducer-model group
#: carrier coordinates of the reducer model (x, y, theta, z, rx, ry) -> the row
#: element's frame coordinates (x, y, z, phi_x, phi_y, phi_z): frame[i] = carrier[_PERM[i]]
_PERM = np.array([0, 1, 3, 4, 5, 2])


@dataclass(frozen=True)
class BearingRowsParameters:
    """The ball-resolved main bearing's rows (:class:`RowModel`, one per row of the
    back-to-back pair), the typed parameters of :class:`BallBearingGroup`."""

    rows: tuple


def bearing_rows_parameters(reducer, drive) -> BearingRowsParameters:
    """The design's rows between rigid rings with quasi-static balls (the ball model's
    default; the factory builds the flexible rings' and the balls' inertia variants with
    :func:`rows_from_design`). ``drive`` is not read: the rows take their entrainment
    speed from the carrier's coordinates."""
    return BearingRowsParameters(tuple(rows_from_design(reducer, ball_inertia=False)))


class BallBearingGroup(KernelGroup):
    """The ball-resolved main bearing as a compiled force element of the reducer model
    (:mod:`flexrv.model.factory`), replacing the rigid model's 5-DOF element.

    Members: ``carrier`` (x, y, theta, z, rx, ry — the tilts are small, so the
    Tait–Bryan frame (rx, ry, theta) of the row elements is the carrier pose) and,
    per row k, ``main_bearing_inner<k>`` / ``main_bearing_outer<k>`` (modal
    coordinates of an uncondensed flexible ring only; the inner ring's modes live
    in the carrier frame, the outer ring's in the housing) and
    ``main_bearing_balls<k>`` (absolute ball-centre positions, 3 Z coordinates, balls
    with inertia only). Each row's contact element (:func:`flexrv.model.bearing_kernel.row_eval`)
    sees the coordinates [frame(6), inner modes, outer modes, balls]; the element's
    kernel (:func:`flexrv.model.bearing_kernel.rows_kernel`) gathers them per row from
    the model's vector and sums the rows' forces and Jacobians, inside the fused kernel
    of the model (both integrators). A row's own members form a dense diagonal block of
    the Newton matrix (:meth:`dense_blocks`: the rows couple only through the carrier).

    Records per row k: ``balls<k>`` (Z, N_RECORD) per-ball results, ``frame<k>`` the row's
    force on the frame (element order x, y, z, rx, ry, rz), ``x<k>`` the row's frame and
    modal-ring coordinates, ``xt<k>`` the frame's velocities: the outputs are built from
    them alone (:func:`bearing_outputs`)."""

    name = "main_bearing"
    kind = "bearing_rows"
    kernel = staticmethod(rows_kernel)
    #: its Jacobian can be costly (the integrator routes it, :class:`~flexrv.model.base.KernelGroup`);
    #: an instance's is where a row has a condensed ring (set in __init__)
    costly_jacobian = True
    parameters = staticmethod(bearing_rows_parameters)
    summary_rows = (
        SummaryRow("max_ball_load_outer_N", "N", "largest ball-outer raceway normal load", "ball_load_outer", "max"),
    )

    def __init__(self, params: BearingRowsParameters):
        if not isinstance(params, BearingRowsParameters):  # a list of rows
            params = BearingRowsParameters(tuple(params))
        self.params = params
        self.rows = rows = list(params.rows)
        members, sizes, index, own = ["carrier"], [6], [], []
        for k, row in enumerate(rows):
            parts, names = [_PERM], []
            for label, m in (("inner", row.m_inner), ("outer", row.m_outer), ("balls", row.n_ball_coordinates)):
                if m == 0:
                    continue
                start = sum(sizes)
                names.append(f"main_bearing_{label}{k}")
                sizes.append(m)
                parts.append(np.arange(start, start + m))
            members += names
            own.append(tuple(names))
            index.append(np.concatenate(parts).astype(np.int64))
        self.members = tuple(members)
        self.sizes = sizes
        #: the condensed rings' dense tangents (~1 ms per Jacobian call on rv40e, about four force calls)
        #: make the Jacobian costly; between rigid rings the quasi-static balls' condensed Jacobian comes
        #: with the ball solve (partial Jacobians there: rv40e 2.96 -> 3.16 s per simulated s, not used)
        self.costly_jacobian = any(_is_condensed(r) for row in rows for r in (row.inner, row.outer))
        self._index = index  # per row: element coordinates in the group's local vector
        self._own = own
        #: per row, the live work arrays of its evaluation (records included; :func:`row_work`)
        self._work = [row_work(row) for row in rows]

    def dense_blocks(self) -> list[tuple[str, ...]]:
        """Per row with own members (modal rings' modes, balls with inertia): their names,
        contiguous in the model's order — a dense diagonal block of the Newton matrix that
        couples to the rest through the carrier only (the block elimination of the compiled
        integrator, :func:`flexrv.model.core.registry.dense_blocks`)."""
        return [names for names in self._own if names]

    def pack(self, idx, history: bool = False):
        """The rows' parts (:func:`flexrv.model.bearing_kernel.row_part`) on the coordinates
        ``idx``; ``history``: fresh warm starts (the rows' initial local-solve states), the
        same live work and record arrays."""
        idx = np.asarray(idx, dtype=np.int64)
        parts = []
        for k, (row, work) in enumerate(zip(self.rows, self._work)):
            p = fresh_kernel_inputs(row) if history else kernel_inputs(row)
            parts.append((np.ascontiguousarray(idx[self._index[k]]), *work, p))
        return BearingRowsPack(tuple(parts))

    @staticmethod
    def empty_pack():
        return empty_pack(BearingRowsPack)

    def record_sources(self) -> dict:
        out = {}
        for k, (row, work) in enumerate(zip(self.rows, self._work)):
            qe, ve, f, rec = work[0], work[1], work[2], work[5]
            out[f"balls{k}"] = rec
            out[f"frame{k}"] = f[:6]
            out[f"x{k}"] = qe[: 6 + row.m_inner + row.m_outer]
            out[f"xt{k}"] = ve[:6]
        return out

    def outputs(self, t, rec) -> dict:
        """The bearing's named outputs from the records (values: :func:`bearing_arrays`): the
        reaction on the carrier (radial, axial, tilting); per ball (dims time, bearing_row,
        ball) the inner and outer normal loads, the loaded inner contact angle, the central
        film and the Hertz pressure at the inner contact; with flexible rings per row the
        raceway deflection at the most-loaded contact and the rings' modal coordinates."""
        frame = np.asarray(rec["frame0"])
        fc = np.zeros(frame.shape)
        for k in range(len(self.rows)):
            fc[..., _PERM] += rec[f"frame{k}"]
        history = [(rec[f"balls{k}"], rec[f"x{k}"]) for k in range(len(self.rows))]
        speed = np.abs(np.asarray(rec["xt0"])[..., 5])  # the frame's phi_z rate: the carrier's
        load_i, load_o, angle, film, p_max, defl, modal = bearing_arrays(self, speed, history)
        dims = ("time", "bearing_row", "ball")
        out = {
            "main_bearing_radial_force": Output(
                np.hypot(fc[:, 0], fc[:, 1]), ("time",), "N", "radial reaction of the main bearing on the carrier"
            ),
            "main_bearing_axial_force": Output(fc[:, 3], ("time",), "N", "axial reaction on the carrier"),
            "main_bearing_tilting_moment": Output(
                np.hypot(fc[:, 4], fc[:, 5]), ("time",), "N m", "tilting reaction moment on the carrier"
            ),
            "ball_load_inner": Output(load_i, dims, "N", "ball-inner raceway normal load"),
            "ball_load_outer": Output(load_o, dims, "N", "ball-outer raceway normal load"),
            "ball_contact_angle": Output(np.degrees(angle), dims, "deg", "loaded inner contact angle"),
            "ball_film_thickness": Output(film, dims, "m", "central EHL film thickness at the inner contact"),
            "ball_max_pressure": Output(p_max, dims, "Pa", "maximum Hertz pressure at the inner contact"),
        }
        for label in ("inner", "outer"):
            if any(m is None for m in modal[label]):
                continue
            out[f"ring_deformation_{label}"] = Output(
                defl[label], ("time", "bearing_row"), "m", f"{label} raceway deflection at the most-loaded contact"
            )
            out[f"ring_modal_{label}"] = Output(
                np.stack(modal[label], 1),
                ("time", "bearing_row", f"mode_{label}"),
                "1",
                f"modal coordinates of the {label} rings",
            )
        return out

    @property
    def flexible(self) -> bool:
        return any(r.inner is not None or r.outer is not None for r in self.rows)

    def check(self) -> str | None:
        """Failure message if a condensed ring's local contact solve or the quasi-static
        balls' equilibrium did not converge in the last evaluation (the accepted state
        of the step on Exudyn's integrator; the state of every CHECK_EVERY-th accepted
        step on the compiled one)."""
        states = [kernel_inputs(r).state for r in self.rows if hasattr(r, "_kernel_inputs")]
        if any(int(s[1]) for s in states):  # (rigid and modal rings: no local solve, never set)
            return "main bearing: the condensed rings' contact deflections did not converge"
        if any(int(s[5]) for s in states):
            return "main bearing: the quasi-static balls' force equilibrium did not converge"
        return None

    def new_members(self) -> dict:
        """The group's own members (balls at the preload equilibrium, modal ring
        coordinates at rest) as :class:`flexrv.model.base.Member` objects, in the
        group's order."""
        from flexrv.model.base import Member

        out = {}
        for k, row in enumerate(self.rows):
            for label in row.ring_nodes():
                ring = getattr(row, label)
                m = ring.stiffness.shape[0]
                out[f"main_bearing_{label}{k}"] = Member(
                    f"main_bearing_{label}{k}",
                    np.asarray(ring.mass, dtype=float),
                    np.zeros(m),
                    np.zeros(m),
                    tuple(f"mode{i}" for i in range(m)),
                    kind="modal",
                    stiffness_matrix=ring.stiffness,
                    damping_matrix=ring.damping,
                )
            if not row.ball_inertia:  # quasi-static balls: no coordinates
                continue
            q0 = (row.ball_reference + initial_ball_displacements(row)).ravel()
            out[f"main_bearing_balls{k}"] = Member(
                f"main_bearing_balls{k}",
                np.eye(q0.size) * row.ball_mass,
                q0,
                np.zeros(q0.size),
                tuple(f"{c}{j}" for j in range(row.ball_count) for c in "xyz"),
                kind="points",
            )
        return out


def _law_film(law, load, speed) -> np.ndarray:
    """Central film h_c [m] of an EHL law at the given loads and speed (0 for dry laws)."""
    if not hasattr(law, "film"):
        return np.zeros_like(load)
    h, _ = law.film(np.maximum(load, law.load_floor), speed)
    return np.where(load > 0, h, 0.0)


def bearing_arrays(group: BallBearingGroup, carrier_speed, history) -> tuple:
    """The values of the bearing's outputs over a time history (:meth:`BallBearingGroup.outputs`):
    (load_i, load_o, angle, film, p_max, defl, modal).

    Per ball (dims time, bearing_row, ball): inner/outer normal loads, loaded inner
    contact angle, central film thickness and maximum Hertz pressure at the inner
    contact (the more heavily stressed: convex–convex, smaller rx); per row: the
    ring's raceway deflection at its most-loaded contact along the contact load
    (positive: the raceway yields away from the ball), and the rings' modal
    coordinates (for :mod:`flexrv.viz.rings`; a condensed ring's from its recorded
    contact loads, :func:`ring_modal_coordinates`). The film is the quasi-static
    EHL h_c(Q, u) of the contact law at the entrainment speed of the carrier's
    rotation; the pressure is the Hertz p_max of the load (the EHL pressure spike
    is not resolved by the law, see :mod:`flexrv.ehl.law`).
    ``carrier_speed``
    (T,): |d theta / dt| of the carrier [rad/s]; ``history[k]``: (per-ball records (T, Z, N_RECORD),
    the row's frame and modal-ring coordinates (T, 6 + modes)) of row k.
    """
    from flexrv.contact.hertz import point_contact

    rows = group.rows
    n_t, n_r, n_b = carrier_speed.shape[0], len(rows), rows[0].ball_count
    shape = (n_t, n_r, n_b)
    load_i, load_o, angle = np.zeros(shape), np.zeros(shape), np.zeros(shape)
    film, p_max = np.zeros(shape), np.zeros(shape)
    defl = {"inner": np.zeros((n_t, n_r)), "outer": np.zeros((n_t, n_r))}
    modal = {
        label: [
            np.zeros((n_t, getattr(row, label).stiffness.shape[0])) if getattr(row, label) is not None else None
            for row in rows
        ]
        for label in ("inner", "outer")
    }
    rt = np.arange(n_t)
    for k, (row, (recs, qe)) in enumerate(zip(rows, history)):
        load_i[:, k], load_o[:, k] = recs[:, :, _REC["load_inner"]], recs[:, :, _REC["load_outer"]]
        angle[:, k] = np.arctan2(
            np.abs(recs[:, :, _REC["niz"]]), np.hypot(recs[:, :, _REC["nix"]], recs[:, :, _REC["niy"]])
        )
        for label in ("inner", "outer"):
            ring = getattr(row, label)
            if ring is None:
                continue
            s = label[0]
            normal = recs[:, :, [_REC[f"n{s}x"], _REC[f"n{s}y"], _REC[f"n{s}z"]]]
            disp = recs[:, :, [_REC[f"u{s}x"], _REC[f"u{s}y"], _REC[f"u{s}z"]]]
            j = np.argmax(recs[:, :, _REC[f"load_{label}"]], axis=1)
            defl[label][:, k] = np.einsum("tc,tc->t", disp[rt, j], normal[rt, j])
            if _is_condensed(ring):
                zs = -1.0 if ring.mirror else 1.0
                g_local = np.ascontiguousarray(recs[:, :, [_REC[f"g{s}x"], _REC[f"g{s}y"], _REC[f"g{s}z"]]])
                modal[label][k][:] = ring_modal_amplitudes(
                    np.ascontiguousarray(recs[:, :, _REC[f"psi_{label}"]]),
                    g_local,
                    ring.table,
                    zs,
                    np.ascontiguousarray(ring.compliance_diag),
                )
            else:
                _, si, so, _ = row.slices()
                modal[label][k][:] = qe[:, si if label == "inner" else so]
    for k, row in enumerate(rows):
        speed = (row.speed_factor * carrier_speed)[:, None]
        film[:, k] = _law_film(row.law_inner, load_i[:, k], speed)
        if row.inner_radii is not None:
            ok = np.isfinite(load_i[:, k]).all(axis=-1)  # (a failed run's last samples may not be)
            p_max[:, k] = np.nan
            p_max[ok, k] = point_contact(load_i[ok, k], *row.inner_radii, row.e_eff).p_max
    return load_i, load_o, angle, film, p_max, defl, modal
