"""CLI: ``flexrv mesh PRESET --part PART`` and ``flexrv modes PRESET --part PART``."""

from __future__ import annotations

import enum
import math
from pathlib import Path
from typing import Optional

import typer
from rich.table import Table

from flexrv.cli._common import JSON_HELP, PRESET_HELP, console, emit, fmt, kv_table
from flexrv.units import M_PER_MM


class Part(str, enum.Enum):
    outer_ring = "outer_ring"
    inner_ring = "inner_ring"
    crankshaft = "crankshaft"
    cycloid_disc = "cycloid_disc"
    carrier = "carrier"


PART_OPT = typer.Option(..., "--part", help="Part to mesh.", case_sensitive=True)
SIZE_OPT = typer.Option(None, "--size", help="Global mesh size [mm] (default: part-specific).")


def _size_m(size_mm: Optional[float]) -> Optional[float]:
    return None if size_mm is None else size_mm * M_PER_MM


COMPLIANCE_HELP = (
    "carrier / cycloid_disc: also condense the part (FE) and print its torsional compliance at the "
    "output (carrier: flange held, crank bores loaded by the torque path; disc: crank holes held, pin "
    "loads at the rated torque, mean over 6 crank angles of one crank-hole period)."
)


def mesh(
    preset: str = typer.Argument(..., help=PRESET_HELP),
    part: Part = PART_OPT,
    size: Optional[float] = SIZE_OPT,
    json: bool = typer.Option(False, "--json", help=JSON_HELP),
    compliance: bool = typer.Option(False, "--compliance", help=COMPLIANCE_HELP),
) -> None:
    """Mesh a part with second-order tetrahedra (cached in the user cache directory,
    $FLEXRV_CACHE_DIR to override): files and counts."""
    from flexrv.design import load
    from flexrv.errors import InputError
    from flexrv.meshing import build_mesh

    if compliance and part.value not in ("carrier", "cycloid_disc"):
        raise InputError(f"--compliance: only for --part carrier or cycloid_disc, not {part.value}")
    reducer = load(preset)
    res = build_mesh(reducer, part.value, _size_m(size))
    d = res.data
    data = {
        "part": part.value,
        "msh": str(res.msh_path),
        "vtu": str(res.vtu_path),
        "cached": res.cached,
        "nodes": d.n_nodes,
        "elements": d.n_elements,
        "element_type": "tetra10",
        "size_mm": d.size * 1e3,
        "local_size_mm": d.info.get("local_size", d.size) * 1e3,
        "groups": {g: int(len(d.node_set(g))) for g in d.group_names},
    }
    if "profile_deviation_m" in d.info:
        data["profile_deviation_um"] = d.info["profile_deviation_m"] * 1e6
    if compliance:
        from flexrv.units import RAD_PER_ARCMIN

        if part.value == "carrier":
            from flexrv.fem.carrier import carrier_compliance

            c = carrier_compliance(reducer, size=_size_m(size))
            data["torsional_compliance_rad_per_Nm"] = c.torsional
            data["torsional_stiffness_Nm_per_arcmin"] = c.torsional_stiffness_Nm_per_arcmin
            data["rigid_bore_stiffness_Nm_per_arcmin"] = RAD_PER_ARCMIN / c.torsional_rbe2
        else:
            from flexrv.fem.disc import disc_compliance_sweep

            c = disc_compliance_sweep(reducer, size=_size_m(size))
            data["crank_angles_deg"] = [round(math.degrees(a), 6) for a in c.angles]
            data["one_disc_compliance_rad_per_Nm"] = c.torsional
            data["torsional_compliance_rad_per_Nm"] = c.output_share
            data["torsional_stiffness_Nm_per_arcmin"] = c.output_stiffness_Nm_per_arcmin

    def render(x):
        rows = [(k, v, "") for k, v in x.items() if k != "groups"]
        rows += [(f"nodes on {g}", n, "") for g, n in x["groups"].items()]
        console.print(kv_table(f"mesh {preset} {part.value}", rows))

    emit(data, json, render)


def modes(
    preset: str = typer.Argument(..., help=PRESET_HELP),
    part: Part = PART_OPT,
    n: int = typer.Option(10, "--n", help="Number of elastic modes."),
    size: Optional[float] = SIZE_OPT,
    json: bool = typer.Option(False, "--json", help=JSON_HELP),
    png: Optional[Path] = typer.Option(
        None, "--png", help="Render each free-free and constrained mode to PNGs in this folder."
    ),
    show: bool = typer.Option(False, "--show", help="Open an interactive window (needs a display)."),
    vtu: Optional[Path] = typer.Option(None, "--vtu", help="Write the modes as VTU for ParaView to this folder."),
) -> None:
    """Free-free and constrained (interfaces clamped) eigenfrequencies [Hz] of a part."""
    from flexrv.cli._common import check_output_dir
    from flexrv.design import load
    from flexrv.errors import InputError
    from flexrv.fem.body import part_modes

    if n < 1:
        raise InputError(f"--n {n}: must be >= 1")
    for opt, folder in (("--png", png), ("--vtu", vtu)):
        if folder is not None:
            check_output_dir(folder, opt, allow_existing=True)
    pm = part_modes(load(preset), part.value, n=n, size=_size_m(size))
    m = pm.mesh
    files = []
    if png is not None:
        from flexrv.viz.modes import render_part_modes

        files += [str(p) for p in render_part_modes(png, part.value, pm)]
    if vtu is not None:
        from flexrv.viz.modes import export_modes_vtu

        vtu.mkdir(parents=True, exist_ok=True)
        files.append(
            str(export_modes_vtu(vtu / f"{part.value}_free_modes.vtu", m.nodes, m.tets, pm.free_modes, pm.free_hz))
        )
        if pm.constrained_hz.size:
            files.append(
                str(
                    export_modes_vtu(
                        vtu / f"{part.value}_constrained_modes.vtu",
                        m.nodes,
                        m.tets,
                        pm.constrained_modes,
                        pm.constrained_hz,
                        prefix="cmode",
                    )
                )
            )
    shown = False
    if show:
        from flexrv.viz.modes import show_mode

        shown = show_mode(m.nodes, m.tris, pm.free_modes[:, 0].reshape(-1, 3), f"{pm.free_hz[0]:.1f} Hz")
    data = {
        "part": part.value,
        "nodes": m.n_nodes,
        "dof": 3 * m.n_nodes,
        "constrained_at": pm.interfaces,
        "free_hz": pm.free_hz,
        "constrained_hz": pm.constrained_hz,
        "files": files,
    }

    def render(x):
        table = Table(
            title=f"modes {preset} {part.value} ({x['dof']} DOF; constrained: "
            f"{', '.join(x['constrained_at'])} clamped)",
            title_justify="left",
        )
        for col in ("mode", "free-free [Hz]", "constrained [Hz]"):
            table.add_column(col, justify="right")
        for k in range(max(len(x["free_hz"]), len(x["constrained_hz"]))):
            fr = fmt(x["free_hz"][k]) if k < len(x["free_hz"]) else ""
            cr = fmt(x["constrained_hz"][k]) if k < len(x["constrained_hz"]) else ""
            table.add_row(str(k + 1), fr, cr)
        console.print(table)
        for f in x["files"]:
            console.print(f"wrote {f}")
        if show and not shown:
            console.print("no display: --show ignored (use --png)")

    emit(data, json, render)


def register(app: typer.Typer) -> None:
    """Add the ``mesh`` and ``modes`` commands."""
    app.command("mesh")(mesh)
    app.command("modes")(modes)
