"""Output files of ``flexrv optimize`` (:mod:`flexrv.studies.optimize`): the Pareto set as CSV
and NetCDF, every evaluation as CSV, the Pareto plot, the recommended designs' TOML and
summary.md. Every write is atomic."""

from __future__ import annotations

import csv
import io
import json
import math
from pathlib import Path
from typing import Any

import numpy as np


def write_outputs(out: Path, problem, cfg, cands, front, rec, result: dict, reducer) -> None:
    """Write every output file of a run (module docstring)."""
    from flexrv.cache import atomic_write_text

    fields = [v.path for v in problem.variables]
    names = problem.names
    atomic_write_text(out / "evaluations.csv", _csv(cands, fields, names, with_status=True))
    atomic_write_text(out / "pareto.csv", _csv(front, fields, names))
    if front:
        _netcdf(out / "pareto.nc", front, fields, names, result, problem.quantities)
    result["plots"] = [str(p) for p in [_plot(out, problem, cands, front, rec, result)] if p]
    result["designs"] = _designs(out, problem, rec, result, reducer) if reducer is not None else {}
    atomic_write_text(out / "summary.md", markdown(result))


def _csv(cands, fields: list[str], names: list[str], with_status: bool = False) -> str:
    buf = io.StringIO()
    w = csv.writer(buf)
    head = fields + names + ["feasible"] + (["status", "error"] if with_status else [])
    w.writerow(head)
    for c in cands:
        row = [c.fields[f] for f in fields] + [c.metrics.get(n, "") for n in names] + [int(c.feasible)]
        if with_status:
            row += [c.status, c.error.replace("\n", " ")[:200]]
        w.writerow(row)
    return buf.getvalue()


def _netcdf(path: Path, front, fields: list[str], names: list[str], result: dict, quantities: dict) -> None:
    import xarray as xr

    from flexrv.cache import atomic_path
    from flexrv.studies._opt_expr import STATS, metric_name

    units = {metric_name(q, s, u): u.replace("_per_", "/") for q, u in quantities.items() for s in STATS}

    data = {}
    for f in fields:
        data[f] = ("point", np.array([c.fields[f] for c in front], dtype=float), {"long_name": f"design field {f}"})
    for n in names:
        unit = units.get(n) or "1"
        data[n] = ("point", np.array([c.metrics.get(n, np.nan) for c in front], dtype=float), {"units": unit})
    ds = xr.Dataset(
        data,
        coords={"point": np.arange(len(front))},
        attrs={
            "design": result["design"],
            "objectives": json.dumps(result["objectives"]),
            "constraints": json.dumps(result["constraints"]),
            "samples_per_design": result["samples_per_design"],
            "seed": result["seed"],
            "resolution": json.dumps(result["resolution"]),
            "cheap_error": json.dumps(result["cheap_error"]),
        },
    )
    with atomic_path(path) as tmp:
        ds.to_netcdf(tmp, engine="h5netcdf")


def _plot(out: Path, problem, cands, front, rec, result) -> Path | None:
    """Objective 1 against objective 2 (colour: objective 3 if any): every evaluated
    candidate, the front, the recommended designs and the design itself."""
    from flexrv.viz.plots import _plt, _save

    objs = problem.objectives
    if len(objs) < 1:
        return None
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7.5, 5.5))
    n1 = objs[0].name
    n2 = objs[1].name if len(objs) > 1 else objs[0].name
    ok = [c for c in cands if c.status == "ok"]
    ax.scatter(
        [c.metrics[n1] for c in ok],
        [c.metrics[n2] for c in ok],
        s=12,
        c=["0.55" if c.feasible else "0.85" for c in ok],
        label="evaluated (light: infeasible)",
    )
    if front:
        kw = {}
        if len(objs) > 2:
            kw = {"c": [c.metrics[objs[2].name] for c in front], "cmap": "viridis"}
        sc = ax.scatter([c.metrics[n1] for c in front], [c.metrics[n2] for c in front], s=40, label="Pareto set", **kw)
        if len(objs) > 2:
            fig.colorbar(sc, ax=ax, label=objs[2].name)
    labels: dict[int, list[str]] = {}
    for k, c in rec.items():  # one label per point (several trade-offs may pick the same design)
        labels.setdefault(id(c), []).append(k)
    for c in {id(c): c for c in rec.values()}.values():
        ax.annotate(
            ", ".join(labels[id(c)]),
            (c.metrics[n1], c.metrics[n2]),
            fontsize=7,
            xytext=(4, 4),
            textcoords="offset points",
        )
    pre = result["preset"]
    if pre.get(n1) is not None and pre.get(n2) is not None:
        ax.scatter([pre[n1]], [pre[n2]], marker="*", s=220, color="C3", label=f"{result['design']} as given")
    ax.set_xlabel(n1)
    ax.set_ylabel(n2)
    ax.set_title(f"{result['design']}: Pareto set, {result['samples_per_design']} builds per design (same draws)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return _save(fig, out / "pareto.png")


def _designs(out: Path, problem, rec, result, reducer) -> dict[str, str]:
    """designs/<label>.toml of every recommended design, with its provenance."""
    from flexrv.cache import atomic_write_text
    from flexrv.design import from_dict, to_toml

    note = (
        f"optimised by flexrv optimize, objectives {', '.join(result['objectives'])}"
        + (f"; constraints {', '.join(result['constraints'])}" if result["constraints"] else "")
        + f"; {result['samples_per_design']} tolerance draws (seed {result['seed']}) of "
        f"{reducer.name}'s tolerance set; trade-off"
    )
    paths = {}
    for label, c in rec.items():
        data = problem.design_for(c.x)
        data["name"] = f"{reducer.name}_{label}"[:64]
        data["sources"] = list(data["sources"]) + [f"{note} {label}"]
        prov = dict(data.get("provenance", {}))
        for f, v in c.fields.items():
            prov[f] = f"{note} {label}: {f} = {v:g}"
        data["provenance"] = prov
        path = out / "designs" / f"{label}.toml"
        atomic_write_text(path, to_toml(from_dict(data, source=str(path))))
        paths[label] = str(path)
    return paths


def _f(v: Any) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    return f"{v:.4g}" if isinstance(v, float) else str(v)


def markdown(r: dict[str, Any]) -> str:
    """summary.md of a run, every number from the result dict."""
    objs = [o.split(":")[0] for o in r["objectives"]]
    cons = r["constraints"]
    lines = [
        f"# Profile-modification design: {r['design']}",
        "",
        f"Varied: {', '.join(_range(v) for v in r['variables'])}. "
        f"Objectives: {', '.join(r['objectives'])}. Constraints: {', '.join(cons) if cons else 'none'}.",
        f"{r['samples_per_design']} tolerance draws per design (the same draws for every design, seed {r['seed']}); "
        f"{r['evaluations']} designs evaluated ({r['feasible']} feasible; {r['computed_now']} computed now, "
        f"{r['reused']} read from earlier runs), NSGA-II population {r['population']}, "
        f"wall time {r['wall_time_s']:.0f} s.",
        f"Search resolution {json.dumps(r['resolution'])}; re-evaluated at {json.dumps(r['full_resolution'])}.",
        "",
        "## Recommended designs (search figures / full re-evaluation, same draws)",
        "",
    ]
    keys = [v["field"] for v in r["variables"]] + objs + _names_in(cons, r) + ["no_preload_yield"]
    keys = list(dict.fromkeys(k for k in keys if k))
    lines += ["| design | " + " | ".join(keys) + " |", "|---" * (len(keys) + 1) + "|"]
    rows = [("as given", r["preset"])] + list(r["recommended"].items())
    for label, p in rows:
        full = p.get("full", {})
        cells = []
        for k in keys:
            if k in full:
                cells.append(f"{_f(p.get(k))} / {_f(full.get(k))}")
            else:
                cells.append(_f(p.get(k)))
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    nominal = [k.replace("_p95_", "_nominal_").replace("_median_", "_nominal_") for k in objs]
    nominal = [k for k in nominal if k in r["preset"] and k not in objs]
    if nominal:
        lines += ["", "Nominal builds (no tolerance draw):", "", "| design | " + " | ".join(nominal) + " |"]
        lines += ["|---" * (len(nominal) + 1) + "|"]
        for label, p in rows:
            lines.append(f"| {label} | " + " | ".join(_f(p.get(k)) for k in nominal) + " |")
    lm = r.get("lost_motion_target")
    if lm:
        lines += ["", f"**Lost motion target ({lm['metric']} <= {lm['target']:g}):** {lm['verdict']}."]
    gain = r.get("yield_gain") or {}
    if gain:
        lines += ["", "## Yield against the design as given", ""]
        for k, ys in gain.items():
            txt = ", ".join(f"{y} {_f(v['preset'])} -> {_f(v['design'])}" for y, v in ys.items())
            lines.append(f"- {k}: {txt}")
    lines += [
        "",
        "Cheap-evaluation error bound per build (|cheap - full|, unit of each quantity): "
        f"{json.dumps(r['cheap_error'])}.",
        "",
        f"## Pareto set ({len(r['pareto'])} designs)",
        "",
        "| " + " | ".join([v["field"] for v in r["variables"]] + objs) + " |",
        "|---" * (len(r["variables"]) + len(objs)) + "|",
    ]
    for p in r["pareto"]:
        lines.append("| " + " | ".join(_f(p.get(k)) for k in [v["field"] for v in r["variables"]] + objs) + " |")
    return "\n".join(lines) + "\n"


def _range(v: dict) -> str:
    return f"{v['field']} in [{v['lo']:g}, {v['hi']:g}]"


def _names_in(constraints: list[str], r: dict) -> list[str]:
    import re

    names = []
    for c in constraints:
        names += [n for n in re.findall(r"[A-Za-z_][A-Za-z0-9_]*", c) if n in r["preset"]]
    return names
