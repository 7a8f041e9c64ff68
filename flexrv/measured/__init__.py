"""Bench measurements in, the same figures out: the measured-data CSV format
(:mod:`flexrv.measured.format`), its writers (:mod:`flexrv.measured.writer`) and the figures
of a measurement by the functions that give a prediction's (:mod:`flexrv.measured.figures`).
``example_loop.csv`` is a stiffness loop simulated by flexrv (its ``origin`` says so), the
format's example."""

from __future__ import annotations

from flexrv.measured.format import MeasuredFileError, Measurement, read_measured  # noqa: F401


def example_path(name: str = "example_loop.csv"):
    """Path of an example file shipped with the package."""
    from importlib import resources
    from pathlib import Path

    return Path(str(resources.files("flexrv.measured") / name))
