"""Main-bearing ring deformation and TE vs external load (:cite:`seed001`).

:cite:`seed001` loads the RV reducer's output flange with axial/radial forces of 15/20,
20/25 and 25/30 kN and reports the "elastic deformation" of the bearing rings
(0.35/0.50/0.65 um) and a TE that grows with it. flexrv runs, per case, the
reducer with flexible main-bearing rings (``model="flexible"``) and, as the
reference, with rigid rings (``model="balls"``, balls with inertia as in the flexible
model) on identical inputs, and
reports the raceway deflection at the most-loaded contact (along the contact
normal, ring clamped at its fit) of the outer and inner rings, the ball loads and
the TE range of both.

Run: ``python -m flexrv.workflows.ring_deformation`` or ``flexrv workflow ring_deformation``.
"""

from __future__ import annotations

import numpy as np

from flexrv.workflows._common import WorkflowResult, new_figure

NAME = "ring_deformation"
PRESET = "rv221"
#: :cite:`seed001`'s load cases: (axial, radial) [N] and its ring deformation [um]
CASES = ((15e3, 20e3), (20e3, 25e3), (25e3, 30e3))
SEED_DEFORMATION_UM = (0.35, 0.50, 0.65)
#: smoke: one case, 10 ms, coarse ring meshes
SMOKE = {"t_end": 0.01, "cases": CASES[:1], "ring_options": {"size": 0.015}}


def run(
    out_dir=None, smoke: bool = False, preset: str = PRESET, t_end: float | None = None, cases=None
) -> WorkflowResult:
    """:cite:`seed001` load cases on ``preset``; saves to ``results/ring_deformation``."""
    import xarray as xr

    from flexrv.design import load, override
    from flexrv.simulation import Simulation

    base = load(preset)
    cases = tuple(cases or (SMOKE["cases"] if smoke else ((0.0, 0.0),) + CASES))  # (0, 0): no-load reference
    op = base.operating
    if t_end is None:
        t_end = SMOKE["t_end"] if smoke else max(op.load_ramp_end_s, op.speed_ramp_time_s) + 0.1
    ring_options = SMOKE["ring_options"] if smoke else {}
    r = WorkflowResult(
        NAME,
        f"Main-bearing ring deformation vs external load ({base.name})",
        ["001 (flexible main bearing, load cases 15/20, 20/25, 25/30 kN)"],
        smoke=smoke,
    )
    rows, te_series = [], {}
    for k, (fa, fr) in enumerate(cases):
        red = override(base, {"operating.external_axial_force_N": fa, "operating.external_radial_force_N": fr})
        runs = {}
        # the rigid-ring reference with balls of inertia, as the flexible model's (the ball
        # model's default quasi-static balls would add a second, if negligible, difference)
        for model, options in (("balls", {"ball_inertia": True}), ("flexible", {"ring_options": ring_options})):
            res = Simulation(red, model=model, model_options=options).run(t_end=t_end)
            runs[model] = res
        flex, rigid = runs["flexible"], runs["balls"]
        t0 = t_end - min(0.05, 0.5 * t_end)
        sel_f = flex.ds.sel(time=slice(t0, None))
        sel_r = rigid.ds.sel(time=slice(t0, None))
        te_f, te_r = sel_f["te"].values, sel_r["te"].values
        row = {
            "axial [kN]": fa / 1e3,
            "radial [kN]": fr / 1e3,
            "seed deformation [um]": SEED_DEFORMATION_UM[CASES.index((fa, fr))] if (fa, fr) in CASES else None,
            "outer ring deflection [um]": 1e6 * float(sel_f["ring_deformation_outer"].values.max()),
            "inner ring deflection [um]": 1e6 * float(sel_f["ring_deformation_inner"].values.max()),
            "max ball load [N]": float(sel_f["ball_load_inner"].values.max()),
            "max ball load, rigid rings [N]": float(sel_r["ball_load_inner"].values.max()),
            "TE min, flexible [arcsec]": float(te_f.min()),
            "TE max, flexible [arcsec]": float(te_f.max()),
            "TE min, rigid rings [arcsec]": float(te_r.min()),
            "TE max, rigid rings [arcsec]": float(te_r.max()),
            "carrier radial shift, flexible [um]": 1e6
            * float(np.hypot(sel_f["carrier_x"].values, sel_f["carrier_y"].values).max()),
            "carrier radial shift, rigid rings [um]": 1e6
            * float(np.hypot(sel_r["carrier_x"].values, sel_r["carrier_y"].values).max()),
        }
        rows.append(row)
        te_series[k] = (flex["te"], rigid["te"])
    r.tables["load cases (last 50 ms of the run)"] = rows
    reference = [row for row in rows if row["axial [kN]"] == 0 and row["radial [kN]"] == 0]
    rows_seed = [row for row in rows if row["seed deformation [um]"] is not None]
    for row in rows_seed:
        case = f"{row['axial [kN]']:.0f}/{row['radial [kN]']:.0f} kN"
        r.compare(
            f"ring elastic deformation, {case}",
            "um",
            row["seed deformation [um]"],
            row["outer ring deflection [um]"],
            "flexrv: outer-raceway deflection at the most-loaded ball along the contact normal (ring "
            "clamped at its fit in a rigid housing; FE-verified to 1 % in tests)",
        )
        r.compare(
            f"TE range, {case}",
            "arcsec",
            None,
            f"{row['TE min, flexible [arcsec]']:.2f} .. {row['TE max, flexible [arcsec]']:.2f}",
            f"rigid rings: {row['TE min, rigid rings [arcsec]']:.2f} .. {row['TE max, rigid rings [arcsec]']:.2f}",
        )
    growth = [row["outer ring deflection [um]"] for row in rows_seed]
    loads = [row["max ball load [N]"] for row in rows_seed]
    d_te = max(
        max(
            abs(row["TE min, flexible [arcsec]"] - row["TE min, rigid rings [arcsec]"]),
            abs(row["TE max, flexible [arcsec]"] - row["TE max, rigid rings [arcsec]"]),
        )
        for row in rows_seed
    )
    d_shift = [
        row["carrier radial shift, flexible [um]"] - row["carrier radial shift, rigid rings [um]"] for row in rows_seed
    ]
    text = (
        "The seed does not define its 'elastic deformation'; flexrv reports the raceway deflection under the "
        "most-loaded ball along its contact normal (the ring clamped at its fit), which is what changes the "
        "contact geometry. "
    )
    if len(rows_seed) > 1:
        text += (
            f"It grows from {growth[0]:.2f} to {growth[-1]:.2f} um (x{growth[-1] / growth[0]:.2f}), exactly "
            f"as the maximum ball load does (x{loads[-1] / loads[0]:.2f}): the ring is linear-elastic, so its "
            "deflection is proportional to the ball load. The seed's 0.35 -> 0.65 um (x1.86) grows faster than "
            "its loads (x1.5 radial, x1.67 axial) would allow for a linear-elastic ring — a sign that its "
            "numbers are not from the same kind of quantity; flexrv's are ~2x larger in magnitude. "
        )
    text += (
        f"TE: flexible and rigid rings differ by at most {d_te:.2f} arcsec in the TE range; the ring "
        f"compliance adds {min(d_shift):.2f}-{max(d_shift):.2f} um to the carrier's radial shift (of "
        f"{rows_seed[0]['carrier radial shift, rigid rings [um]']:.1f}-"
        f"{rows_seed[-1]['carrier radial shift, rigid rings [um]']:.1f}"
        " um from the balls' Hertz compliance). With the rings clamped at their fits, their deformation is "
        "local (lowest fit-clamped ring mode ~47 kHz for rv221) and small next to the Hertz approach, so the "
        "seed's doubling of the TE range with flexible rings is not reproduced; it would need a compliant "
        "housing or carrier, or clearance, which the seed does not describe. What does move TE is the "
        "carrier's radial shift under the external load itself (tens of um against a 165 mm pin circle), "
        "present with rigid rings too"
    )
    if reference:
        ref = reference[0]
        text += (
            f": without external load the TE range is {ref['TE min, flexible [arcsec]']:.2f} .. "
            f"{ref['TE max, flexible [arcsec]']:.2f} arcsec, with seed001's loads it moves to "
            f"{rows_seed[0]['TE min, flexible [arcsec]']:.2f} .. {rows_seed[-1]['TE max, flexible [arcsec]']:.2f}"
            " arcsec."
        )
    else:
        text += "."
    r.text.append(text)
    r.numbers = {"cases": rows}
    ds = xr.Dataset(
        {key: ("case", [row[key] for row in rows]) for key in rows[0]}, coords={"case": np.arange(len(rows))}
    )
    r.datasets["ring_deformation"] = ds
    fig, ax = new_figure(1, 2, figsize=(11, 4))
    x = np.arange(len(rows))
    ax[0].bar(x - 0.2, [row["outer ring deflection [um]"] for row in rows], 0.4, label="flexrv outer ring")
    ax[0].bar(x + 0.2, [row["seed deformation [um]"] or 0.0 for row in rows], 0.4, label="seed001")
    ax[0].set_xticks(x, [f"{row['axial [kN]']:.0f}/{row['radial [kN]']:.0f}" for row in rows])
    ax[0].set_xlabel("axial/radial load [kN]")
    ax[0].set_ylabel("ring deformation [µm]")
    ax[0].legend()
    for k, (te_f, te_r) in te_series.items():
        ax[1].plot(te_f["time"], te_f, label=f"flexible, case {k + 1}")
        ax[1].plot(te_r["time"], te_r, "--", label=f"rigid rings, case {k + 1}")
    ax[1].set_xlabel("time [s]")
    ax[1].set_ylabel("TE [arcsec]")
    ax[1].legend(fontsize=7)
    fig.tight_layout()
    r.figures["ring_deformation"] = fig
    r.save(out_dir)
    return r


if __name__ == "__main__":
    print(run().out_dir)
