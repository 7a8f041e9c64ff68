"""Benchmark: the main-bearing subsystem (2 rows x Z balls) in a dynamic Exudyn run.

A rigid carrier frame (NodeRigidBodyRxyz) turns at the preset's output speed and
carries seed 001's first external load case (axial 15 kN, radial 20 kN), ramped
in smoothly (a sudden 35 kN step costs ~8 Newton iterations per step); the rings are rigid or reduced flexible bodies (outer rings as plain
modal coordinates, from :func:`flexrv.fem.body.reduce_part`). Prints wall time per
step, Newton iterations and the share of time spent in the contact user functions.

    python benchmarks/bench_flexible_bearing.py [--preset rv221] [--flexible] [--t-end 0.01]
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def build(preset: str, flexible: bool, size: float | None, axial: float, radial: float, ramp_time: float = 0.0):
    import exudyn as exu
    from exudyn.itemInterface import (LoadForceVector, MarkerNodeRigid, NodeRigidBodyRxyz, ObjectRigidBody)
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
        outer = [ModalRing(body), ModalRing(body, mirror=True)]
    rows = rows_from_design(reducer, outer=outer)
    omega_c = float(reducer_kinematics(reducer).speeds.carrier)
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    frame = mbs.AddNode(NodeRigidBodyRxyz(referenceCoordinates=[0.0] * 6, initialVelocities=[0, 0, 0, 0, 0, omega_c]))
    inertia = RigidBodyInertia(mass=reducer.inertia.carrier_mass_kg,
                               inertiaTensor=np.diag([0.5, 0.5, 1.0]) * reducer.inertia.carrier_inertia_kg_m2)
    mbs.AddObject(ObjectRigidBody(mass=reducer.inertia.carrier_mass_kg, inertia=inertia.GetInertia6D(), nodeNumber=frame))
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
    parser.add_argument("--size", type=float, default=None, help="ring mesh size [m] (default: the part's)")
    parser.add_argument("--t-end", type=float, default=0.01)
    parser.add_argument("--dt", type=float, default=1e-4)
    parser.add_argument("--ramp", type=float, default=None,
                        help="external-load ramp time [s] (default: half of --t-end; 0 = step load)")
    args = parser.parse_args()
    ramp_time = 0.5 * args.t_end if args.ramp is None else args.ramp
    mbs, sc, handle, rows, t_reduce = build(args.preset, args.flexible, args.size, 15e3, 20e3, ramp_time)
    import flexrv.model.flexible_bearing as fb

    calls = {"n": 0, "t": 0.0}
    evaluate = fb.evaluate_row

    def timed(*a, **k):  # the contact user functions call fb.evaluate_row
        t0 = time.perf_counter()
        out = evaluate(*a, **k)
        calls["t"] += time.perf_counter() - t0
        calls["n"] += 1
        return out

    fb.evaluate_row = timed
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
    exu.SolveDynamic(mbs, settings, solverType=exu.DynamicSolverType.GeneralizedAlpha)
    wall = time.perf_counter() - t0
    steps = settings.timeIntegration.numberOfSteps
    modes = [r.m_outer for r in rows]
    print(f"{args.preset}: {'flexible outer rings (' + str(modes[0]) + ' modes each)' if args.flexible else 'rigid rings'}, "
          f"{rows[0].ball_count} balls x 2 rows, dt = {args.dt:g} s, {steps} steps, "
          f"15/20 kN axial/radial ramped over {ramp_time:g} s")
    if args.flexible:
        print(f"  reduce outer ring (cached after first run): {t_reduce:.2f} s")
    print(f"  wall {wall:.2f} s -> {1e3 * wall / steps:.2f} ms/step, {wall / args.t_end:.0f} s per simulated s")
    print(f"  user-function calls {calls['n']} ({calls['n'] / steps:.1f}/step), share of wall {calls['t'] / wall:.0%}")


if __name__ == "__main__":
    main()
