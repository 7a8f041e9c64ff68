"""Benchmark: the main-bearing subsystem (2 rows x Z balls) in a dynamic Exudyn run.

A rigid carrier frame (NodeRigidBodyRxyz) turns at the preset's output speed and
carries :cite:`seed001`'s first external load case (axial 15 kN, radial 20 kN), ramped
in smoothly (a sudden 35 kN step costs ~8 Newton iterations per step); the rings
are rigid or reduced flexible outer rings (:func:`flexrv.fem.body.reduce_part`),
condensed into the row elements (default) or with their modal coordinates as
system coordinates (``--uncondensed``). Prints wall and CPU time per step and the
share of time spent in the contact user functions (force and Jacobian).

    python benchmarks/bench_flexible_bearing.py [--preset rv221] [--flexible] [--uncondensed] [--t-end 0.01]
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def build(
    preset: str,
    flexible: bool,
    size: float | None,
    axial: float,
    radial: float,
    ramp_time: float = 0.0,
    condense: bool = True,
):
    import exudyn as exu
    from exudyn.itemInterface import LoadForceVector, MarkerNodeRigid, NodeRigidBodyRxyz, ObjectRigidBody
    from exudyn.utilities import RigidBodyInertia

    from flexrv.design import load
    from flexrv.geometry.kinematics import reducer_kinematics
    from flexrv.model.flexible_bearing import ModalRing, add_main_bearing, rows_from_design

    reducer = load(preset)
    outer = None
    t_reduce = 0.0
    if flexible:
        from flexrv.fem.body import reduce_part

        t0 = time.perf_counter()
        body = reduce_part(reducer, "outer_ring", size=size)
        t_reduce = time.perf_counter() - t0
        zeta = reducer.main_bearing.ring_damping_ratio
        outer = [
            ModalRing(body, damping_ratio=zeta, condense=condense),
            ModalRing(body, damping_ratio=zeta, mirror=True, condense=condense),
        ]
    rows = rows_from_design(reducer, outer=outer)
    omega_c = float(reducer_kinematics(reducer).speeds.carrier)
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    frame = mbs.AddNode(NodeRigidBodyRxyz(referenceCoordinates=[0.0] * 6, initialVelocities=[0, 0, 0, 0, 0, omega_c]))
    inertia = RigidBodyInertia(
        mass=reducer.inertia.carrier_mass_kg,
        inertiaTensor=np.diag([0.5, 0.5, 1.0]) * reducer.inertia.carrier_inertia_kg_m2,
    )
    mbs.AddObject(
        ObjectRigidBody(mass=reducer.inertia.carrier_mass_kg, inertia=inertia.GetInertia6D(), nodeNumber=frame)
    )
    handle = add_main_bearing(mbs, rows, frame)
    marker = mbs.AddMarker(MarkerNodeRigid(nodeNumber=frame))
    load_vec = np.array([radial, 0.0, axial])

    def ramp(mbs_, t, load_vector):
        """Load ramped smoothly (Adams STEP) over ``ramp_time``, as the seeds' load steps."""
        from flexrv.contact.laws import adams_step

        factor = 1.0 if ramp_time <= 0 else float(adams_step(t, 0.0, 0.0, ramp_time, 1.0))
        return list(factor * load_vec)

    mbs.AddLoad(LoadForceVector(markerNumber=marker, loadVector=list(load_vec), loadVectorUserFunction=ramp))
    mbs.Assemble()
    return mbs, sc, handle, rows, t_reduce


def main() -> None:
    import exudyn as exu

    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--preset", default="rv221")
    parser.add_argument("--flexible", action="store_true", help="reduced flexible outer rings")
    parser.add_argument("--uncondensed", action="store_true", help="ring modes as system coordinates")
    parser.add_argument("--size", type=float, default=None, help="ring mesh size [m] (default: the part's)")
    parser.add_argument("--t-end", type=float, default=0.01)
    parser.add_argument("--dt", type=float, default=1e-4)
    parser.add_argument(
        "--ramp", type=float, default=None, help="external-load ramp time [s] (default: half of --t-end; 0 = step load)"
    )
    args = parser.parse_args()
    ramp_time = 0.5 * args.t_end if args.ramp is None else args.ramp
    mbs, sc, handle, rows, t_reduce = build(
        args.preset, args.flexible, args.size, 15e3, 20e3, ramp_time, condense=not args.uncondensed
    )
    import flexrv.model.flexible_bearing as fb

    calls = {"n": 0, "t": 0.0}

    def timed(fn):  # the contact user functions call fb.row_force / fb.row_jacobian
        def wrapper(*a, **k):
            t0 = time.process_time()
            out = fn(*a, **k)
            calls["t"] += time.process_time() - t0
            calls["n"] += 1
            return out

        return wrapper

    fb.row_force = timed(fb.row_force)
    fb.row_jacobian = timed(fb.row_jacobian)
    settings = exu.SimulationSettings()
    settings.timeIntegration.numberOfSteps = int(round(args.t_end / args.dt))
    settings.timeIntegration.endTime = args.t_end
    settings.timeIntegration.verboseMode = 0
    settings.timeIntegration.generalizedAlpha.spectralRadius = 0.5
    settings.timeIntegration.newton.useModifiedNewton = True
    settings.timeIntegration.newton.relativeTolerance = 1e-3
    settings.timeIntegration.newton.absoluteTolerance = 1e-1
    settings.solution.file.write = False
    t0 = time.perf_counter()
    c0 = time.process_time()
    exu.SolveDynamic(mbs, settings, solverType=exu.DynamicSolverType.GeneralizedAlpha)
    wall = time.perf_counter() - t0
    cpu = time.process_time() - c0
    steps = settings.timeIntegration.numberOfSteps
    modes = rows[0].outer.n_modes if args.flexible else 0
    kind = ("condensed" if not args.uncondensed else "uncondensed") + f" flexible outer rings ({modes} modes each)"
    print(
        f"{args.preset}: {kind if args.flexible else 'rigid rings'}, "
        f"{rows[0].ball_count} balls x 2 rows, dt = {args.dt:g} s, {steps} steps, "
        f"15/20 kN axial/radial ramped over {ramp_time:g} s"
    )
    if args.flexible:
        print(f"  reduce outer ring (cached after first run): {t_reduce:.2f} s")
    print(
        f"  wall {wall:.2f} s -> {1e3 * wall / steps:.2f} ms/step, {wall / args.t_end:.0f} s per simulated s; "
        f"CPU {cpu:.2f} s -> {cpu / args.t_end:.0f} s per simulated s"
    )
    print(f"  user-function calls {calls['n']} ({calls['n'] / steps:.1f}/step), share of CPU {calls['t'] / cpu:.0%}")


if __name__ == "__main__":
    main()
