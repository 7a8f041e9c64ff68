"""Lubrication of the main bearing and TE (:cite:`seed000,seed001`).

:cite:`seed000,seed001` vary the "oil film thickness at the maximum-load contact" over
0.01-0.18 mm with peak pressures 0.98-1.25 GPa and report a non-monotonic TE range
(about -40 .. +43 arcsec). flexrv varies what sets an EHL film and a contact
pressure in a real bearing, over physically meaningful ranges:

* **film**: the lubricant's viscosity eta0 = 0.01-1.5 Pa s (about ISO VG 10 to
  VG 1000 at the operating temperature), EHL law ``hamrock_dowson``, plus the dry
  Hertz reference — central films of ~0.01-0.5 um at the carrier's slow
  entrainment speed;
* **pressure**: the external radial load on the output flange, 0-30 kN (:cite:`seed001`'s
  range), which sets the maximum Hertz pressure.

Each case runs the reducer with the flexible main bearing (``model="flexible"``)
and records the minimum central film over the loaded balls, the maximum contact
pressure and the TE statistics of the loaded steady state.

Run: ``python -m flexrv.workflows.lubrication`` or ``flexrv workflow lubrication``.
"""

from __future__ import annotations

import numpy as np

from flexrv.workflows._common import WorkflowResult, new_figure

NAME = "lubrication"
PRESET = "rv221"
VISCOSITIES = (0.01, 0.05, 0.15, 0.5, 1.5)  #: eta0 [Pa s]
RADIAL_LOADS = (0.0, 10e3, 20e3, 30e3)  #: external radial force [N]
#: :cite:`seed001`'s lubrication table: minimum film [mm], peak pressure [GPa], TE range [arcsec]
SEED_TABLE = ((0.01, 0.98, (-40.5, 42.3)), (0.07, 1.13, (-38.1, 39.8)), (0.18, 1.25, (-41.7, 43.5)))
SMOKE = {"t_end": 0.01, "viscosities": (0.05, 1.5), "radial_loads": (0.0,), "model": "balls"}


def _case(red, model: str, t_end: float, label: str, value: float) -> dict:
    from flexrv.simulation import Simulation

    res = Simulation(red, model=model).run(t_end=t_end)
    t0 = t_end - min(0.05, 0.5 * t_end)
    sel = res.ds.sel(time=slice(t0, None))
    load = sel["ball_load_inner"].values
    film = sel["ball_film_thickness"].values
    loaded = load > 0.05 * load.max() if load.max() > 0 else load > 0
    te = sel["te"].values
    return {
        label: value,
        "ehl": red.contact.ehl,
        "min central film [um]": 1e6 * float(film[loaded].min()) if loaded.any() else 0.0,
        "film at max load [um]": 1e6 * float(film.reshape(-1)[np.argmax(load)]),
        "max contact pressure [GPa]": 1e-9 * float(sel["ball_max_pressure"].values.max()),
        "max ball load [N]": float(load.max()),
        "TE min [arcsec]": float(te.min()),
        "TE max [arcsec]": float(te.max()),
        "TE mean [arcsec]": float(te.mean()),
        "TE p-p [arcsec]": float(te.max() - te.min()),
    }


def run(
    out_dir=None, smoke: bool = False, preset: str = PRESET, t_end: float | None = None, model: str | None = None
) -> WorkflowResult:
    """Lubrication study on ``preset``; saves to ``results/lubrication``."""
    import xarray as xr

    from flexrv.design import load, override

    base = load(preset)
    op = base.operating
    if t_end is None:
        t_end = SMOKE["t_end"] if smoke else max(op.load_ramp_end_s, op.speed_ramp_time_s) + 0.1
    model = model or (SMOKE["model"] if smoke else "flexible")
    viscosities = SMOKE["viscosities"] if smoke else VISCOSITIES
    radial = SMOKE["radial_loads"] if smoke else RADIAL_LOADS
    r = WorkflowResult(
        NAME,
        f"Main-bearing lubrication and TE ({base.name}, model {model})",
        ["000 (rigid vs flexible TE)", "001 (lubrication table)"],
        smoke=smoke,
    )
    film_rows = [_case(override(base, {"contact.ehl": "dry"}), model, t_end, "viscosity [Pa s]", 0.0)]
    for eta in viscosities:
        red = override(base, {"contact.ehl": "hamrock_dowson", "lubricant.viscosity_Pa_s": eta})
        film_rows.append(_case(red, model, t_end, "viscosity [Pa s]", eta))
    pressure_rows = []
    for fr in radial:
        red = override(base, {"contact.ehl": "hamrock_dowson", "operating.external_radial_force_N": fr})
        pressure_rows.append(_case(red, model, t_end, "radial load [kN]", fr / 1e3))
    r.tables["film: lubricant viscosity (first row: dry Hertz)"] = film_rows
    r.tables["pressure: external radial load"] = pressure_rows
    for (h_mm, p_gpa, (lo, hi)), row in zip(SEED_TABLE, film_rows[1:] + [None] * 3):
        r.compare(
            f"film thickness (seed case {h_mm} mm)",
            "um",
            1e3 * h_mm,
            None if row is None else row["film at max load [um]"],
            "seed's mm-scale 'film' is not an EHL film (EHL: 0.01-1 um); flexrv: Hamrock-Dowson h_c "
            "at the most-loaded ball for the viscosity of this row",
        )
        r.compare(
            f"TE range (seed case {h_mm} mm)",
            "arcsec",
            f"{lo} .. {hi}",
            None if row is None else f"{row['TE min [arcsec]']:.2f} .. {row['TE max [arcsec]']:.2f}",
            f"seed peak pressure {p_gpa} GPa",
        )
    te_span = [row["TE mean [arcsec]"] for row in film_rows]
    h_span = [row["min central film [um]"] for row in film_rows[1:]]
    p_span = [row["max contact pressure [GPa]"] for row in pressure_rows]
    r.numbers = {
        "film": film_rows,
        "pressure": pressure_rows,
        "te_mean_spread_over_films_arcsec": float(np.ptp(te_span)),
    }
    r.text.append(
        "seed000/seed001 set 'minimum film thickness' to 0.01-0.18 mm. An elastohydrodynamic film in a "
        "ball-raceway contact at GPa pressures is 0.01-1 um thick (Hamrock-Dowson; the numerical EHL solver of "
        "flexrv agrees within 6-11 %); a 0.1 mm film would separate the surfaces hydrodynamically and carry no "
        "GPa pressure. The seed's film values are therefore not used as films; flexrv varies the viscosity, "
        f"giving central films of {min(h_span):.3g}-{max(h_span):.3g} um here (at the carrier's entrainment "
        "speed of only a few mm/s)."
    )
    r.text.append(
        f"Effect on TE: the film adds h_c to every contact's approach in series with Hertz (a slightly larger "
        f"effective preload); the TE mean changes by {np.ptp(te_span):.3g} arcsec over dry..thickest film — "
        "negligible against the cycloid stage's wind-up. The seed's non-monotonic TE-vs-film trend (a few "
        "arcsec) is not reproduced; flexrv finds no mechanism for it in the main bearing. Maximum contact "
        f"pressure over the radial-load cases: {min(p_span):.3g}-{max(p_span):.3g} GPa (seed: 0.98-1.25 GPa)."
    )
    if len(pressure_rows) > 1:
        r.text.append(
            "TE vs pressure: the maximum contact pressure rises with the external radial load, and so does the "
            f"TE level (mean {pressure_rows[0]['TE mean [arcsec]']:.2f} -> {pressure_rows[-1]['TE mean [arcsec]']:.2f}"
            " arcsec) — not because of the pressure or the film, but because the radial load shifts the carrier "
            "(and with it cranks and discs) against the pin ring by tens of um (see the ring_deformation "
            "workflow). At zero external load the balls carry only the preload: "
            f"{film_rows[0]['max ball load [N]']:.0f} N dry (seed001: steady main-bearing contact force ~93.7 N)."
        )
    keys = [k for k in film_rows[0] if k != "ehl"]
    r.datasets["lubrication_film"] = xr.Dataset({k: ("case", [row[k] for row in film_rows]) for k in keys})
    keys = [k for k in pressure_rows[0] if k != "ehl"]
    r.datasets["lubrication_pressure"] = xr.Dataset({k: ("case", [row[k] for row in pressure_rows]) for k in keys})
    fig, ax = new_figure(1, 2, figsize=(11, 4))
    films = [row["min central film [um]"] for row in film_rows[1:]]
    ax[0].errorbar(
        films,
        [row["TE mean [arcsec]"] for row in film_rows[1:]],
        yerr=[
            [row["TE mean [arcsec]"] - row["TE min [arcsec]"] for row in film_rows[1:]],
            [row["TE max [arcsec]"] - row["TE mean [arcsec]"] for row in film_rows[1:]],
        ],
        fmt="o-",
        label="flexrv (TE mean, min..max)",
    )
    ax[0].axhline(film_rows[0]["TE mean [arcsec]"], color="k", ls=":", label="dry Hertz")
    ax[0].set_xscale("log")
    ax[0].set_xlabel("minimum central film h_c [µm]")
    ax[0].set_ylabel("TE [arcsec]")
    ax[0].legend(fontsize=8)
    ax[1].errorbar(
        [row["max contact pressure [GPa]"] for row in pressure_rows],
        [row["TE mean [arcsec]"] for row in pressure_rows],
        yerr=[
            [row["TE mean [arcsec]"] - row["TE min [arcsec]"] for row in pressure_rows],
            [row["TE max [arcsec]"] - row["TE mean [arcsec]"] for row in pressure_rows],
        ],
        fmt="s-",
    )
    ax[1].set_xlabel("maximum contact pressure [GPa]")
    ax[1].set_ylabel("TE [arcsec]")
    fig.tight_layout()
    r.figures["lubrication"] = fig
    r.save(out_dir)
    return r


if __name__ == "__main__":
    print(run().out_dir)
