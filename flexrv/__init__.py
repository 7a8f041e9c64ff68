"""flexrv — transmission error, stiffness and contact loads of RV reducers.

Pipeline: design (validated presets) -> geometry -> meshing -> fem/cms -> contact/ehl
-> model -> simulation -> post/viz. See README.md.
"""

from __future__ import annotations

__version__ = "0.1.0"

from flexrv.design import list_presets, load  # noqa: F401


def __getattr__(name: str):
    """Lazy access to heavy entry points (Exudyn is imported only when needed)."""
    if name in ("Simulation", "Results"):
        from flexrv import simulation

        return getattr(simulation, name)
    raise AttributeError(f"module 'flexrv' has no attribute {name!r}")
