"""Evaluation of the virtual torsional-stiffness test (:cite:`seed004` test bench):
input locked, output torque 0 -> +T_r -> -T_r -> 0 quasi-statically.

The figures are the named definitions of :mod:`flexrv.post.definitions` (rigidities by
their reading: 50-100 % slope, tangent at rated, low-torque slope, loop secant; lost motion
at +-3 % and +-1 %; the geometric backlash; hysteresis width and loss), read from the loop by
:func:`flexrv.post.definitions.loop_figures`, the same function that reads a measured loop.
This module adds the test program's bookkeeping (which samples are the loop, the friction
energy over the program) and the files of a test run.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from flexrv.post import definitions as defs

#: names of older readers -> the named figure they are
_ALIASES = {
    "rigidity_Nm_per_arcmin": "rigidity_slope_50_100_Nm_per_arcmin",
    "rigidity_positive_Nm_per_arcmin": "rigidity_slope_50_100_positive_Nm_per_arcmin",
    "rigidity_negative_Nm_per_arcmin": "rigidity_slope_50_100_negative_Nm_per_arcmin",
    "rigidity_low_Nm_per_arcmin": "rigidity_low_torque_Nm_per_arcmin",
    "rated_torque": "rated_torque_Nm",
    "lost_motion_negative_arcmin": "lost_motion_negative_angle_arcmin",
    "lost_motion_positive_arcmin": "lost_motion_positive_angle_arcmin",
    "hysteresis_returning_arcmin": "hysteresis_ascending_angle_arcmin",
    "hysteresis_descending_arcmin": "hysteresis_descending_angle_arcmin",
}


@dataclass(frozen=True)
class StiffnessTest:
    """Figures of a stiffness test: ``figures`` the named values of
    :func:`flexrv.post.definitions.loop_figures` (read as attributes too, e.g.
    ``t.lost_motion_arcmin``), ``friction_energy_J`` the friction dissipation over the
    program (0 without friction)."""

    figures: dict = field(default_factory=dict)
    friction_energy_J: float = 0.0

    def __getattr__(self, name):
        figures = self.__dict__.get("figures", {})
        key = _ALIASES.get(name, name)
        if key in figures:
            return figures[key]
        raise AttributeError(name)

    def named(self) -> dict:
        """The named figures of :data:`flexrv.post.definitions.DEFINITIONS` and the friction energy."""
        out = {k: float(self.figures[k]) for k in defs.DEFINITIONS}
        out["friction_energy_J"] = float(self.friction_energy_J)
        return out

    def reading(self) -> dict:
        """How the named figures were read, the numbers summary.md states beside them (rated
        torque, fit range, lost-motion band and angles, the branches' slopes, the hysteresis
        angles at T = 0): every saved figure of :data:`_FIGURES` that :meth:`named` leaves out."""
        named = self.named()
        return {name: float(getattr(self, name)) for name, _, _ in _FIGURES if name not in named}


def loop_energy(torque_down, angle_down, torque_back, angle_back, rated: float, samples: int = 2001) -> float:
    """The loop's area from its descending and returning branches
    (:func:`flexrv.post.definitions.loop_energy`) [J]."""
    return defs.loop_energy(
        [(np.asarray(torque_down, float), np.asarray(angle_down, float))],
        [(np.asarray(torque_back, float), np.asarray(angle_back, float))],
        rated,
        samples,
    )


def evaluate_stiffness_test(time, torque, angle, times, friction_power=None) -> StiffnessTest:
    """Evaluate a loop. ``times`` = (t_start, t_pos, t_neg, t_end): the program
    ramps 0 -> +T_r on [t_start, t_pos], +T_r -> -T_r on [t_pos, t_neg] and
    -T_r -> 0 on [t_neg, t_end]; ``angle`` is the output rotation [rad]. The rated torque
    is the smaller of the loop's two peaks (a recorded step may miss the program's peak).
    ``friction_power`` [W] over ``time`` (the run's output ``friction_power``, if it has
    friction): its integral over [t_start, t_end] is the friction energy of the program
    [J], the friction part of the dissipation measured directly (trapezoid rule)."""
    time, torque, angle = (np.asarray(a, dtype=float) for a in (time, torque, angle))
    t0, _, _, te = times
    prog = (time >= t0) & (time <= te)
    rated = float(min(np.max(torque[prog]), -np.min(torque[prog])))
    figures = defs.loop_figures(torque[prog], angle[prog], rated)
    e_fric = 0.0
    if friction_power is not None:
        e_fric = float(np.trapezoid(np.asarray(friction_power, dtype=float)[prog], time[prog]))
    return StiffnessTest(figures=figures, friction_energy_J=e_fric)


#: (name, units, long name) of the saved figures: the named definitions and the read points
_FIGURES = tuple((name, *defs.DEFINITIONS[name][:2]) for name in defs.DEFINITIONS) + (
    (
        "friction_energy_J",
        "J",
        "energy dissipated by friction over the test program (0 -> +T_r -> -T_r -> 0), integral of "
        "friction_power; 0 without friction",
    ),
    ("rated_torque_Nm", "N m", "rated (peak) torque of the loop"),
    ("rigidity_slope_50_100_positive_Nm_per_arcmin", "N m/arcmin", "slope of the +T_r loading branch, 50-100 %"),
    ("rigidity_slope_50_100_negative_Nm_per_arcmin", "N m/arcmin", "slope of the -T_r loading branch, 50-100 %"),
    ("angle_at_rated_arcmin", "arcmin", "output rotation at +T_r (loading)"),
    ("fit_range_low_Nm", "N m", "lower end of the 50-100 % rigidity fit range, abs(T)"),
    ("lost_motion_torque_Nm", "N m", "torque band of the lost motion, 3 % T_r"),
    ("lost_motion_negative_angle_arcmin", "arcmin", "mid-curve angle at -3 % T_r"),
    ("lost_motion_positive_angle_arcmin", "arcmin", "mid-curve angle at +3 % T_r"),
    ("hysteresis_ascending_angle_arcmin", "arcmin", "ascending branch at T = 0"),
    ("hysteresis_descending_angle_arcmin", "arcmin", "descending branch at T = 0"),
)


def stiffness_dataset(figures: StiffnessTest, time, torque, angle_arcmin, base=None):
    """The test's numbers as an :class:`xarray.Dataset`: every figure a scalar variable
    with ``units`` and ``long_name`` (rigidity, lost motion, hysteresis, ...), and the loop
    ``loop_torque`` [N m] / ``loop_angle`` [arcmin] over ``time`` [s]; merged into ``base``
    (the run's dataset) if given."""
    import xarray as xr

    data = {
        name: xr.Variable((), float(getattr(figures, name)), {"units": units, "long_name": long})
        for name, units, long in _FIGURES
    }
    data["loop_torque"] = xr.Variable(
        ("time",), np.asarray(torque, dtype=float), {"units": "N m", "long_name": "output torque of the test loop"}
    )
    data["loop_angle"] = xr.Variable(
        ("time",),
        np.asarray(angle_arcmin, dtype=float),
        {"units": "arcmin", "long_name": "output rotation of the test loop"},
    )
    ds = xr.Dataset(data, coords={"time": ("time", np.asarray(time, dtype=float), {"units": "s"})})
    if base is not None:
        ds = base.assign(**{k: ds[k] for k in ds.data_vars})
        ds.attrs = {k: v for k, v in base.attrs.items() if k != "stiffness_test"}
    ds.attrs["kind"] = "stiffness_test"
    return ds


def stiffness_json(figures: StiffnessTest) -> dict:
    """JSON-ready figures: ``{name: {"value", "units", "description"}}``."""
    return {
        name: {"value": float(getattr(figures, name)), "units": units, "description": long}
        for name, units, long in _FIGURES
    }


def stiffness_summary_markdown(
    figures: StiffnessTest,
    preset: str,
    model: str,
    quarter_time: float,
    dt: float,
    plot: str | None = "hysteresis.png",
    budget: dict | None = None,
) -> str:
    """summary.md of a stiffness test (not the time-simulation template): the program,
    the figures with units and how each is read, the loop plot, References."""
    f = figures
    lines = [
        f"# Stiffness test {preset} ({model} model)",
        "",
        f"Input locked; output torque 0 -> +{f.rated_torque:.4g} -> -{f.rated_torque:.4g} -> 0 N m, each "
        f"quarter over {quarter_time:.4g} s (quasi-static), dt = {dt:.3g} s. Each figure is named by its "
        "definition (flexrv.post.definitions; docs/definitions.md).",
        "",
        "| quantity | value | unit | how it is read |",
        "|---|---|---|---|",
    ]
    for name, units, long in _FIGURES[: len(defs.DEFINITIONS) + 1]:
        lines.append(f"| {name} | {getattr(f, name):.4g} | {units} | {long} |")
    lines += [
        "",
        f"Rigidity fit range: abs(T) = {f.fit_range_low_Nm:.4g} .. {f.rated_torque:.4g} N m; lost motion read "
        f"at T = +-{f.lost_motion_torque_Nm:.3g} N m ({f.lost_motion_negative_arcmin:.4g} .. "
        f"{f.lost_motion_positive_arcmin:.4g} arcmin); hysteresis at T = 0 ({f.hysteresis_returning_arcmin:.4g}"
        f" .. {f.hysteresis_descending_arcmin:.4g} arcmin).",
        "",
    ]
    if plot:
        lines += [f"![torque vs output rotation loop]({plot})", ""]
    if budget:
        lines += [
            f"## Stiffness budget at {budget['torque_Nm']:.4g} N m",
            "",
            "Strain-energy budget of the quasi-static model at the test's pose (flexrv.simulation."
            "stiffness_test_budget, flexrv.analysis.budget), the same elements as `flexrv te` and `flexrv design`, "
            "every one in the model.",
            "",
            "| element | compliance [arcsec/(N m)] | share [%] |",
            "|---|---|---|",
        ]
        for name, e in sorted(budget["elements"].items(), key=lambda kv: -kv[1]["share_percent"]):
            lines.append(f"| {name} | {e['compliance_arcsec_per_Nm']:.4g} | {e['share_percent']:.3g} |")
        lines += [f"| total | {budget['total_compliance_arcsec_per_Nm']:.4g} | 100 |", ""]
        lines += [f"- {k}: {v:.4g} N m/arcmin" for k, v in budget.items() if k.endswith("_Nm_per_arcmin")]
        lines += [""] + [f"Note: {n}" for n in budget.get("notes", [])] + [""]
    lines += [
        "Files: results.nc (the run plus the figures as variables with units, and the loop), "
        "stiffness.json, config.toml.",
        "",
        "## References",
        "",
        "seed004 (RV-40E torsional stiffness): key `seed004` of `docs/references.md` in the flexrv repository.",
        "",
    ]
    return "\n".join(lines)
