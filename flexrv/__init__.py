"""flexrv — transmission error, stiffness and contact loads of RV reducers.

Pipeline: design (validated presets; geometry checks) -> geometry -> meshing -> fem/cms -> contact/ehl
-> model -> simulation -> post/viz. See README.md.
"""

from __future__ import annotations

from flexrv._version import __version__  # noqa: F401
from flexrv.cache import configure_numba_cache

configure_numba_cache()  # numba's kernel cache beside flexrv's other caches, damaged entries healed

#: Layer order of the package, lowest first: a module may import from its own layer and the
#: layers below it, never from a layer above (tests/test_layers.py checks every import,
#: including those inside functions, and that modules import no cycle). Each entry names the
#: top-level modules or subpackages of ``flexrv`` in that layer; the package root
#: (``flexrv/__init__.py``, a facade) and ``flexrv/__main__.py`` (-> cli) are outside the order.
LAYERS: tuple[tuple[str, ...], ...] = (
    ("units", "errors", "cache", "references", "_version"),  # base utilities, no flexrv imports
    ("geometry",),  # kinematics, involute, cycloid, bearing and as-built geometry (of numbers / a design)
    ("design",),  # validated design model and presets (its validation uses geometry)
    ("contact",),  # contact laws (Hertz, EHL-corrected laws)
    ("ehl",),  # closed-form films, numerical EHL solver, solver maps
    ("analysis",),  # analytic design calculations (pin loads, stiffness, life, report)
    ("meshing",),  # gmsh part meshes
    ("fem",),  # FE assembly, modes, reduction
    ("model",),  # Exudyn multibody model: members and force groups
    ("post",),  # results, statistics, spectra, I/O
    ("measured",),  # bench files in (loops, TE records), their figures by post's definitions
    ("viz",),  # plots and 3-D views
    ("simulation",),  # Simulation: build, run, save
    ("sweep", "studies", "workflows"),  # orchestration of many runs
    ("cli",),  # command line
)

from flexrv.design import list_presets, load  # noqa: E402, F401  (after the numba cache is configured)


def __getattr__(name: str):
    """Lazy access to heavy entry points (Exudyn is imported only when needed)."""
    if name in ("Simulation", "Results"):
        from flexrv import simulation

        return getattr(simulation, name)
    raise AttributeError(f"module 'flexrv' has no attribute {name!r}")
