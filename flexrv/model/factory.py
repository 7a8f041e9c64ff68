"""Model factory: assemble a reducer model by name from member groups.

``build_model(reducer, "rigid")`` creates the members (carrier, cranks with
their planets, discs) and the force-element groups

====================  =========================================  ==========================
group                 members                                    module
====================  =========================================  ==========================
``gear_stage``        carrier, cranks (sun angle prescribed)     :mod:`.gear_stage`
``crank_supports``    carrier, cranks                            :mod:`.cranks_discs`
``needle_bearings``   cranks, discs                              :mod:`.cranks_discs`
``pins``              discs                                      :mod:`.pins`
``main_bearing``      carrier                                    :mod:`.main_bearing_rigid`
``loads``             carrier                                    :mod:`.loads`
====================  =========================================  ==========================

A flexible variant registers a different builder in :data:`MODELS` that swaps
single groups/members (e.g. ``main_bearing`` -> the ball-resolved flexible
bearing) while keeping the others and their output names.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from flexrv.errors import ConfigError, check_options, signature_options
from flexrv.model.assembled import AssembledModel
from flexrv.model.base import Member
from flexrv.model.bodies import BODY_PARTS, with_bodies


def _members(p) -> dict[str, Member]:
    """The members from the drive's parameters ``p`` (:class:`flexrv.model.drive.DriveParameters`)."""
    mem: dict[str, Member] = {}
    mc = np.diag(
        [
            p.carrier_mass,
            p.carrier_mass,
            p.carrier_inertia,
            p.carrier_mass,
            0.5 * p.carrier_inertia,
            0.5 * p.carrier_inertia,
        ]
    )
    mem["carrier"] = Member("carrier", mc, np.zeros(6), np.zeros(6), ("x", "y", "theta", "z", "rx", "ry"))
    for j in range(p.n_cranks):
        b = p.crank_angles[j]
        q0 = np.array([p.center_distance * np.cos(b), p.center_distance * np.sin(b), 0.0])
        mem[f"crank{j}"] = Member(
            f"crank{j}", np.diag([p.crank_mass, p.crank_mass, p.crank_inertia]), q0, np.zeros(3), ("x", "y", "phi")
        )
    for k in range(p.n_discs):
        q0 = np.array([p.eccentricity * np.sin(p.chi0[k]), p.eccentricity * np.cos(p.chi0[k]), p.disc_rot0[k]])
        mem[f"disc{k}"] = Member(
            f"disc{k}", np.diag([p.disc_mass, p.disc_mass, p.disc_inertia]), q0, np.zeros(3), ("x", "y", "psi")
        )
    return mem


def _drive(p, drive: str):
    """The input's angle and speed functions of a drive: ``ramp`` (to the design's speed),
    ``locked`` or ``position`` (quasi-static: the 'time' argument is the input angle itself)."""
    from flexrv.model.loads import locked_drive, position_drive, ramp_drive

    if drive == "ramp":
        return ramp_drive(p.input_speed, p.speed_ramp_time)
    if drive == "locked":
        return locked_drive()
    if drive == "position":
        return position_drive()
    raise ConfigError(f"drive = {drive!r} is not allowed: choose 'ramp', 'locked' or 'position'")


def _add_main_bearing(reducer, p, main_bearing, ring_options, ball_inertia, members, groups, info) -> None:
    """Insert the main bearing's group (and the balls' members) before the loads: the
    rigid 5-DOF element, or the ball-resolved bearing with rigid (``balls``) or reduced
    flexible rings (``flexible``; see :func:`build_rigid`)."""
    if main_bearing == "rigid":
        from flexrv.model.main_bearing_rigid import RigidMainBearing

        if ball_inertia is not None:
            raise ConfigError(
                f"ball_inertia = {ball_inertia!r} is not allowed with the rigid main bearing: it "
                f"applies to the ball-resolved bearing (model 'balls' or 'flexible')"
            )
        groups.insert(4, RigidMainBearing.from_design(reducer, p))
    elif main_bearing in ("balls", "flexible"):
        from flexrv.model.flexible_bearing import BallBearingGroup, rows_from_design

        rings = {}
        if main_bearing == "flexible":
            from flexrv.model.flexible_bearing import flexible_rings

            rings = flexible_rings(
                reducer, **check_options("ring_options", ring_options, signature_options(flexible_rings, skip=1))
            )
            info["flexible_bodies"] = rings["bodies"]
            info["ring_lowest_mode_hz"] = rings["lowest_mode_hz"]
        if ball_inertia is None:  # quasi-static balls unless a condensed ring couples them (see the docstring)
            ball_inertia = any(
                r is not None and r.condensed for side in ("inner", "outer") for r in rings.get(side) or []
            )
        group = BallBearingGroup(
            rows_from_design(
                reducer, inner=rings.get("inner"), outer=rings.get("outer"), ball_inertia=bool(ball_inertia)
            )
        )
        info["ball_inertia"] = bool(ball_inertia)
        members.update(group.new_members())
        groups.insert(4, group)
    else:
        raise ConfigError(f"main_bearing = {main_bearing!r} is not allowed: choose 'rigid', 'balls' or 'flexible'")


def build_rigid(
    reducer,
    drive: str = "ramp",
    torque: Callable | None = None,
    main_bearing: str = "rigid",
    crankshaft: str = "rigid",
    ring_options: dict | None = None,
    crank_options: dict | None = None,
    model_name: str = "rigid",
    exudyn: bool = True,
    bodies=None,
    ball_inertia: bool | None = None,
) -> AssembledModel:
    """Rigid-body model with compliant contacts (see module docstring).

    ``main_bearing``: ``"rigid"`` (linear 5-DOF element), ``"balls"`` (the
    ball-resolved bearing of :mod:`flexrv.model.flexible_bearing`: every ball a
    point mass between rigid rings, Hertz/EHL contacts per the design) or
    ``"flexible"`` (the same with reduced flexible rings, ``ring_options``);
    ``crankshaft``: ``"rigid"`` or ``"flexible"`` (:mod:`flexrv.model.flexible_crank`,
    options ``crank_options``). ``ball_inertia`` (ball-resolved bearings): False
    makes the balls quasi-static (no ball coordinates, solved inside the row
    elements), True point masses; None (default) takes quasi-static balls unless a
    ring is condensed (the flexible model's default rings), where each ball keeps
    its inertia (:mod:`flexrv.model.flexible_bearing`). ``model_name`` labels the results of a non-rigid
    variant. ``exudyn=False`` returns the members and force groups without an Exudyn
    system (the quasi-static solver evaluates the same groups directly).

    ``bodies``: the elastic bodies of the run among :data:`BODY_PARTS` (``carrier``:
    the FE carrier condensed into the crank supports; ``cycloid_disc``: the FE disc
    body around the pins, :mod:`flexrv.model.cranks_discs`, :mod:`flexrv.model.pins`);
    None takes the design's switches (``carrier.body_model``,
    ``second_stage.disc_body_model``), a list sets them (named: ``condensed_fe``,
    others ``rigid``; :func:`flexrv.model.bodies.with_bodies`). ``params`` of the model: the
    drive's shared parameters (:class:`flexrv.model.drive.DriveParameters`); each element keeps
    its own (``group.params``)."""
    from flexrv.model.cranks_discs import CrankSupports, NeedleBearings
    from flexrv.model.drive import drive_parameters
    from flexrv.model.gear_stage import GearMeshes
    from flexrv.model.loads import OutputLoads, step_torque
    from flexrv.model.pins import PinContacts

    if bodies is not None:
        bad = [b for b in bodies if b not in BODY_PARTS]
        if bad:
            raise ConfigError(f"bodies = {','.join(bad)} is not allowed: choose from {', '.join(BODY_PARTS)}")
        reducer = with_bodies(reducer, bodies)
    p = drive_parameters(reducer)
    theta, omega = _drive(p, drive)
    if torque is None:
        torque = step_torque(p.load_torque, *p.load_ramp)
    # each element builds its own parameters from the design (only what it needs)
    pins = PinContacts.from_design(reducer, p)
    groups = [
        GearMeshes.from_design(reducer, p, theta, omega),
        CrankSupports.from_design(reducer, p),
        NeedleBearings.from_design(reducer, p),
        pins,
        OutputLoads.from_design(reducer, p, torque, ramp=None if drive == "position" else p.load_ramp),
    ]
    members = _members(p)
    info: dict = {}
    _add_main_bearing(reducer, p, main_bearing, ring_options, ball_inertia, members, groups, info)
    if crankshaft == "flexible":
        from flexrv.model.flexible_crank import add_flexible_cranks

        info.update(
            add_flexible_cranks(
                reducer,
                p,
                members,
                groups,
                **check_options("crank_options", crank_options, signature_options(add_flexible_cranks, skip=4)),
            )
        )
    elif crankshaft != "rigid":
        raise ConfigError(f"crankshaft = {crankshaft!r} is not allowed: choose 'rigid' or 'flexible'")
    info.update(
        main_bearing=main_bearing,
        crankshaft=crankshaft,
        elastic_bodies=[
            b
            for b, on in (
                ("carrier", reducer.carrier is not None and reducer.carrier.body_model == "condensed_fe"),
                ("cycloid_disc", pins.elastic_discs),
            )
            if on
        ],
    )
    name = "rigid" if (main_bearing, crankshaft) == ("rigid", "rigid") else model_name
    model = AssembledModel(
        name=name,
        reducer=reducer,
        params=p,
        members=members,
        groups=groups,
        input_angle=theta,
        input_speed=omega,
        load_torque=torque,
        info=info,
    )
    if not exudyn:
        offset = 0
        for m in members.values():
            m.offset = offset
            offset += m.n
        model.n = offset
        return model
    return assemble(model)


def _member_jacobian(m, exu):
    """Jacobian user function of a member's own object (mass, constant stiffness and
    damping): it returns zero and Exudyn adds the object's constant matrices. Without
    one, Exudyn differentiates the object numerically at every Jacobian (2n + 1
    evaluations of a force that is zero or linear; measured 55-75 us per Jacobian
    for a 114-coordinate ball member). Sparse (no entries) for a pure
    mass, dense when the member has stiffness or damping matrices (Exudyn requires
    the format of those)."""
    if m.stiffness_matrix is None and m.damping_matrix is None:
        zero = exu.MatrixContainer()
        zero.SetWithSparseMatrix(np.zeros((0, 3)), numberOfRows=m.n, numberOfColumns=m.n, useDenseMatrix=False)
    else:
        zero = np.zeros((m.n, m.n))

    def jacobian(mbs_, t, item, q, q_t, f_q, f_v):
        return zero

    return jacobian


def assemble(model: AssembledModel) -> AssembledModel:
    """Create the Exudyn system: one NodeGenericODE2 + mass object per member and
    the force elements. The compiled kernel groups (:class:`flexrv.model.base.KernelGroup`:
    gear stage, crank supports, needle bearings, pins, rigid main bearing, loads)
    share ONE ObjectGenericODE2 (:class:`flexrv.model.kernels.FusedForces`, one
    compiled call per residual); every other group (ball bearing rows, flexible
    cranks) adds its own element(s) through :meth:`~flexrv.model.base.ForceGroup.add_to`."""
    import exudyn as exu
    from exudyn.itemInterface import NodeGenericODE2, ObjectGenericODE2

    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    offset = 0
    for m in model.members.values():
        m.node = mbs.AddNode(
            NodeGenericODE2(
                referenceCoordinates=[0.0] * m.n,
                initialCoordinates=list(m.q0),
                initialCoordinates_t=list(m.v0),
                numberOfODE2Coordinates=m.n,
            )
        )
        extra = {}
        if m.stiffness_matrix is not None:
            extra["stiffnessMatrix"] = m.stiffness_matrix
        if m.damping_matrix is not None:
            extra["dampingMatrix"] = m.damping_matrix
        mbs.AddObject(
            ObjectGenericODE2(
                nodeNumbers=[m.node], massMatrix=m.mass_matrix, jacobianUserFunction=_member_jacobian(m, exu), **extra
            )
        )
        m.offset = offset
        offset += m.n
    from flexrv.model.base import KernelGroup
    from flexrv.model.kernels import FusedForces

    kernel_groups = [g for g in model.groups if isinstance(g, KernelGroup)]
    if kernel_groups:  # ONE element for every compiled group
        model.fused = FusedForces(model, kernel_groups)
        for g in kernel_groups:
            g._stats = model.fused.stats  # the groups report the fused element's call counts
        model.fused.add_to(mbs, [model.members[name].node for name in model.fused.member_names])
    for g in model.groups:
        if not isinstance(g, KernelGroup):
            g.add_to(
                mbs, [model.members[name].node for name in g.members], [model.members[name].n for name in g.members]
            )
    mbs.Assemble()
    model.mbs, model.sc, model.n = mbs, sc, offset
    q = np.asarray(mbs.systemData.GetODE2Coordinates())
    if q.shape != (offset,) or not np.allclose(q, model.q0):
        raise RuntimeError("unexpected Exudyn coordinate ordering")
    return model


def build_balls(reducer, **kwargs) -> AssembledModel:
    """Rigid model with the ball-resolved main bearing (rigid rings): the carrier
    is carried only by the balls of both rows (radial, axial and tilt compliance of
    the Hertz/EHL contacts). The flexible-ring model builds on this."""
    return build_rigid(reducer, main_bearing="balls", model_name="balls", **kwargs)


#: parts that :func:`build_flexible` can make flexible (the last two: :data:`BODY_PARTS`)
FLEXIBLE_PARTS = ("main_bearing", "crankshaft") + BODY_PARTS
DEFAULT_FLEXIBLE_PARTS = ("main_bearing",)


def parts_options(model: str, parts) -> dict:
    """Builder options from a ``--parts`` list (CLI semantics): ``--parts`` names the
    elastic parts of the run, the others are rigid. ``carrier`` and ``cycloid_disc``
    work with every model (option ``bodies``); ``main_bearing`` and ``crankshaft``
    need ``--model flexible``. None (no ``--parts``): {} (the design's switches for
    the bodies; ``flexible``: main_bearing flexible)."""
    if parts is None:
        return {}
    parts = parse_parts(parts)
    if model == "flexible":
        return {"parts": parts}
    own = [x for x in parts if x not in BODY_PARTS]
    if own:
        raise ConfigError(
            f"parts = {','.join(own)} needs --model flexible (got --model {model}); with --model "
            f"{model} --parts names elastic bodies only: {', '.join(BODY_PARTS)}"
        )
    return {"bodies": parts}


def parse_parts(parts) -> tuple[str, ...]:
    """Validate a list (or comma-separated string) of flexible part names; ``none``
    alone: no elastic part (every body rigid)."""
    if isinstance(parts, str):
        parts = [p.strip() for p in parts.split(",")] if parts.strip() else []
    parts = tuple(parts)
    if parts == ("none",):
        return ()
    if "" in parts:
        raise ConfigError(f"parts = {','.join(parts)!r} is not allowed: an empty part name (stray comma)")
    twice = sorted({p for p in parts if parts.count(p) > 1})
    if twice:
        raise ConfigError(f"parts = {','.join(parts)} is not allowed: {', '.join(twice)} given twice")
    bad = [p for p in parts if p not in FLEXIBLE_PARTS]
    if bad or not parts:
        raise ConfigError(
            f"parts = {','.join(parts) or '(empty)'} is not allowed: choose one or more of {', '.join(FLEXIBLE_PARTS)}"
        )
    return parts


def build_flexible(
    reducer, parts=None, ring_options: dict | None = None, crank_options: dict | None = None, **kwargs
) -> AssembledModel:
    """Rigid model with the named parts flexible (:data:`FLEXIBLE_PARTS`; None: the
    main bearing, with the design's elastic bodies; a list: exactly the named parts,
    ``carrier`` / ``cycloid_disc`` included or rigid):

    * ``main_bearing`` — ball-resolved bearing with reduced flexible inner and
      outer rings of both rows (:func:`flexrv.model.flexible_bearing.flexible_rings`,
      options ``ring_options``: harmonics, n_eig (default None: no fixed-interface
      eigenmodes for the quasi-static rings, 12 for dynamic ones), size, damping_ratio,
      stiffness_scale, quasi_static, condense (default True: the quasi-static rings'
      modal coordinates condensed into the bearing element; False keeps them as
      coordinates, for verification), rings; unknown options are refused);
    * ``crankshaft`` — flexible crankshafts (:mod:`flexrv.model.flexible_crank`,
      options ``crank_options``: size, stiffness_scale, damping_ratio).
    """
    bodies = None
    if parts is None:
        parts = DEFAULT_FLEXIBLE_PARTS
    else:
        parts = parse_parts(parts)
        bodies = tuple(x for x in parts if x in BODY_PARTS)
    return build_rigid(
        reducer,
        main_bearing="flexible" if "main_bearing" in parts else "rigid",
        crankshaft="flexible" if "crankshaft" in parts else "rigid",
        ring_options=ring_options,
        crank_options=crank_options,
        model_name="flexible",
        bodies=bodies,
        **kwargs,
    )


#: model name -> builder(reducer, drive=..., torque=..., **options) -> AssembledModel
MODELS: dict[str, Callable[..., AssembledModel]] = {
    "rigid": build_rigid,
    "balls": build_balls,
    "flexible": build_flexible,
}


def build_model(reducer, model: str = "rigid", **kwargs) -> AssembledModel:
    """Build the named model for a design (see :data:`MODELS`)."""
    if model not in MODELS:
        raise ConfigError(f"model = {model!r} is not allowed: choose one of {sorted(MODELS)}")
    builder = MODELS[model]
    allowed = signature_options(builder, skip=1, exclude=("model_name",))
    if builder is not build_rigid:  # build_balls / build_flexible pass the rest on to build_rigid
        set_here = ("main_bearing", "crankshaft", "bodies") if builder is build_flexible else ("main_bearing",)
        allowed = {**signature_options(build_rigid, skip=1, exclude=("model_name",) + set_here), **allowed}
        allowed.pop("kwargs", None)
    opts = check_options(
        f"model options of {model!r}", {k: v for k, v in kwargs.items() if k not in ("drive", "torque")}, allowed
    )
    return builder(reducer, **{**kwargs, **opts})
