"""What ``flexrv simulate`` and ``flexrv te`` compile, done in a background process on a first
run (:class:`flexrv.model.kernel_cache.BackgroundCompile`) while the command builds the FE
bodies of its design.

Each job calls the command's own code path (no copy of its argument building) on the
design with rigid bodies: the kernels' argument types are those of the real model (a
rigid body is an empty array of the same dimension), so the compiled kernels are the
ones the command then loads from numba's cache. ``simulate``: a run of two time steps
(the compiled integrator, which also evaluates the elements for the initial accelerations
and the outputs' history pass: one entry point); ``te``: the loaded TE over the first
positions (the fused kernel and the kernels of its outputs pass). Models with flexible
rings or crankshafts build FE bodies of their own; they are not compiled in the background.
"""

from __future__ import annotations

#: models whose background job is cheap to build (no FE body of their own once the bodies are rigid)
BACKGROUND_MODELS = ("rigid", "balls")
#: positions per pin-mesh period and crank revolutions of the te job (the first few positions)
TE_JOB_POINTS = 2
TE_JOB_CRANK_REVOLUTIONS = 0.05
#: modules of the element kernels compiled by a second helper process beside the job (the largest:
#: the pins with the disc bodies, ~11 s CPU of the ~40 s (simulate) / ~30 s (te) of the whole
#: compilation, benchmarks/bench_compile.py), which the job waits for
SPLIT_MODULES = ("flexrv.model.pins",)


def _simulation(reducer, model: str, model_options: dict):
    """The Simulation of ``simulate`` with every elastic body rigid."""
    from flexrv.simulation import Simulation

    return Simulation(reducer, model=model, model_options={**model_options, "bodies": ()})


def _static_model(reducer):
    """The quasi-static model of ``te`` with every elastic body rigid."""
    from flexrv.model.bodies import with_bodies
    from flexrv.model.quasi_static import StaticModel

    return StaticModel(with_bodies(reducer, ()))


def simulate_job(reducer, model: str, model_options: dict, dt: float, integrator: str | None) -> None:
    """Two time steps of ``model`` on ``reducer`` with rigid bodies (the kernels of ``simulate``),
    the pins' kernel compiled meanwhile by a helper process (:func:`elements_job`)."""
    from flexrv.model.kernel_cache import start_background

    start_background(elements_job, ("simulate", reducer, model, model_options), modules=SPLIT_MODULES)
    sim = _simulation(reducer, model, model_options)
    sim.run(t_end=2.0 * dt, dt=dt, integrator=integrator, checkpoint_s=None)


def te_job(reducer) -> None:
    """The loaded TE of ``reducer`` with rigid bodies over its first positions (the kernels of ``te``),
    the pins' kernel compiled meanwhile by a helper process (:func:`elements_job`)."""
    from flexrv.model.bodies import with_bodies
    from flexrv.model.kernel_cache import start_background
    from flexrv.model.quasi_static import loaded_te
    from flexrv.post.definitions import PLAY_FRACTIONS

    start_background(elements_job, ("te", reducer), modules=SPLIT_MODULES)
    loaded_te(
        with_bodies(reducer, ()),
        crank_revolutions=TE_JOB_CRANK_REVOLUTIONS,
        points_per_mesh=TE_JOB_POINTS,
        catalog_positions=1,
        play_fractions=PLAY_FRACTIONS,
    )


def elements_job(command: str, reducer, model: str = "rigid", model_options: dict | None = None) -> None:
    """Call the element kernels of :data:`SPLIT_MODULES` of the command's stand-in model once, as its
    fused kernel calls them (the model's initial state, Jacobians on: the same argument types), so
    that their compilation runs beside the rest of the fused kernel's."""
    import numpy as np

    from flexrv.model.core.registry import spec_of
    from flexrv.model.kernels import FusedForces

    if command == "simulate":
        built = _simulation(reducer, model, model_options or {}).build()
    else:
        built = _static_model(reducer).model
    fused = built.fused if built.fused is not None else FusedForces(built)
    q = np.ascontiguousarray(built.q0[fused.index], dtype=float)
    v = np.zeros_like(q)
    for (group, _), pack in zip(fused.slots, fused.packs):
        kernel = spec_of(group).kernel
        if kernel.py_func.__module__.startswith(SPLIT_MODULES):
            kernel(q, v, fused.f, fused.jq, fused.jv, True, pack)


def start_simulate(sim, dt: float, integrator: str | None):
    """Start the background compilation of a ``simulate`` run of ``sim`` (a
    :class:`flexrv.simulation.Simulation` not built yet) on a first run; None if not started."""
    from flexrv.model.kernel_cache import start_background

    if sim.model_name not in BACKGROUND_MODELS or "parts" in sim.model_options:
        return None
    args = (sim.reducer, sim.model_name, dict(sim.model_options), float(dt), integrator)
    return start_background(simulate_job, args, entries=("fused_integrate",))


def start_te(reducer):
    """Start the background compilation of ``te`` on ``reducer`` on a first run; None if not started."""
    from flexrv.model.kernel_cache import start_background

    return start_background(te_job, (reducer,), entries=("fused_kernel",))
