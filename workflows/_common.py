"""Shared pieces of the seed-study workflows.

Every workflow module in :mod:`workflows` exposes ``run(..., out_dir=None, smoke=False)
-> WorkflowResult`` and plots behind ``if __name__ == "__main__"``. A
:class:`WorkflowResult` collects the numbers beside the seed's reported values with
an explanation of every difference, xarray datasets and matplotlib figures, and
writes them atomically to ``results/<workflow>/`` (NetCDF, PNG, summary.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from flexrv.cache import atomic_path, atomic_write_text

RESULTS_ROOT = Path(__file__).resolve().parent.parent / "results"


@dataclass
class Comparison:
    """One row of a seed-vs-flexrv table."""

    quantity: str
    unit: str
    seed: Any
    flexrv: Any
    note: str = ""


@dataclass
class WorkflowResult:
    """Outputs of one workflow run."""

    name: str
    title: str
    seeds: list[str]
    comparisons: list[Comparison] = field(default_factory=list)
    text: list[str] = field(default_factory=list)
    tables: dict[str, list[dict[str, Any]]] = field(default_factory=dict)
    datasets: dict[str, Any] = field(default_factory=dict)  # name -> xarray.Dataset
    figures: dict[str, Any] = field(default_factory=dict)  # name -> matplotlib Figure
    numbers: dict[str, Any] = field(default_factory=dict)  # machine-readable key results
    out_dir: Path | None = None

    def compare(self, quantity: str, unit: str, seed: Any, flexrv: Any, note: str = "") -> None:
        """Add a seed-vs-flexrv row (``note`` explains any difference)."""
        self.comparisons.append(Comparison(quantity, unit, seed, flexrv, note))

    # ---------------------------------------------------------------- output
    def summary_markdown(self) -> str:
        """The summary.md text: title, seeds, comparison table, notes, tables, figures."""
        lines = [f"# {self.title}", "", f"Seeds: {', '.join(self.seeds)}", ""]
        if self.comparisons:
            lines += ["| quantity | unit | seed | flexrv | note |", "|---|---|---|---|---|"]
            for c in self.comparisons:
                lines.append(f"| {c.quantity} | {c.unit} | {_fmt(c.seed)} | {_fmt(c.flexrv)} | {c.note} |")
            lines.append("")
        for paragraph in self.text:
            lines += [paragraph, ""]
        for name, rows in self.tables.items():
            if not rows:
                continue
            cols = list(rows[0])
            lines += [f"### {name}", "", "| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
            for row in rows:
                lines.append("| " + " | ".join(_fmt(row.get(c)) for c in cols) + " |")
            lines.append("")
        if self.figures:
            lines += ["## Figures", ""]
            for name in self.figures:
                lines.append(f"![{name}]({name}.png)")
            lines.append("")
        return "\n".join(lines)

    def save(self, out_dir: str | Path | None = None) -> Path:
        """Write NetCDF datasets, PNG figures and summary.md atomically; return the folder."""
        out = Path(out_dir) if out_dir else RESULTS_ROOT / self.name
        out.mkdir(parents=True, exist_ok=True)
        for name, ds in self.datasets.items():
            with atomic_path(out / f"{name}.nc") as tmp:
                ds.to_netcdf(tmp, engine="h5netcdf")
        for name, fig in self.figures.items():
            with atomic_path(out / f"{name}.png") as tmp:
                fig.savefig(tmp, dpi=120, format="png")
        atomic_write_text(out / "summary.md", self.summary_markdown())
        self.out_dir = out
        return out


def _fmt(value: Any) -> str:
    if value is None:
        return "–"
    if isinstance(value, float):
        if not math.isfinite(value):
            return str(value)
        if value != 0 and (abs(value) < 1e-3 or abs(value) >= 1e5):
            return f"{value:.4g}"
        return f"{value:.4g}"
    return str(value)


def new_figure(*args, **kwargs):
    """A matplotlib figure on the Agg backend (headless)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt.subplots(*args, **kwargs)


def collect_report(results_root: Path = RESULTS_ROOT) -> Path:
    """Collect every ``results/<workflow>/summary.md`` into ``results/README.md``.

    Figures keep working because links are rewritten relative to ``results/``.
    """
    parts = ["# flexrv results", "",
             "What do main-bearing flexibility and lubrication do to an RV reducer's transmission error?",
             "Each section below is one workflow's summary (seed numbers beside flexrv's, with the",
             "reason for every difference). Regenerate with `flexrv report`.", ""]
    answer = answer_section(results_root)
    if answer:
        parts += answer
    found = sorted(p for p in results_root.glob("*/summary.md"))
    for path in found:
        folder = path.parent.name
        text = path.read_text()
        text = text.replace("](", f"]({folder}/").replace(f"]({folder}/http", "](http")
        text = "\n".join(("#" + line) if line.startswith("#") else line for line in text.splitlines())
        parts += [text, ""]
    if not found:
        parts.append("No workflow results yet: run `flexrv workflow NAME` (or the workflows' modules) first.")
    return atomic_write_text(results_root / "README.md", "\n".join(parts) + "\n")


def answer_section(results_root: Path = RESULTS_ROOT) -> list[str]:
    """The report's short answer, computed from the saved workflow outputs that
    exist (rigid_vs_flexible/compare.json, ring_deformation.nc, lubrication_*.nc,
    crankshaft_flexibility/compare.json); empty if none does."""
    import json

    import numpy as np
    import xarray as xr

    lines: list[str] = []
    cmp = results_root / "rigid_vs_flexible" / "compare.json"
    if cmp.exists():
        n = json.loads(cmp.read_text())
        r, f = n["rigid"], n["flexible"]
        lines.append(f"* **Main-bearing flexibility** (rv221, seeds 000/001, 20 N m): steady TE "
                     f"{r['te_min_arcsec']:.2f} .. {r['te_max_arcsec']:.2f} arcsec with the rigid model, "
                     f"{f['te_min_arcsec']:.2f} .. {f['te_max_arcsec']:.2f} arcsec with flexible rings and "
                     f"ball-resolved EHL contacts — a change of {f['te_mean_arcsec'] - r['te_mean_arcsec']:+.2f} arcsec "
                     f"in the mean and {f['te_pp_arcsec'] - r['te_pp_arcsec']:+.2f} arcsec in the ripple, not the "
                     "seeds' near-doubling: clamped at their fits the rings deform only locally (~1 um under a "
                     "ball).")
    ring = results_root / "ring_deformation" / "ring_deformation.nc"
    if ring.exists():
        ds = xr.load_dataset(ring, engine="h5netcdf")
        loaded = ds.where(ds["radial [kN]"] > 0, drop=True)
        if loaded.sizes.get("case", 0):
            lines.append(
                f"* **External load** (seed 001's 15/20 .. 25/30 kN): ring deflection "
                f"{float(loaded['outer ring deflection [um]'].min()):.2f} .. "
                f"{float(loaded['outer ring deflection [um]'].max()):.2f} um (seed 0.35 .. 0.65 um); what moves TE is "
                "the carrier's radial shift in the ball bearing (tens of um): the TE range moves to "
                f"{float(loaded['TE min, flexible [arcsec]'].min()):.2f} .. "
                f"{float(loaded['TE max, flexible [arcsec]'].max()):.2f} arcsec, with rigid and flexible rings alike.")
    film = results_root / "lubrication" / "lubrication_film.nc"
    if film.exists():
        ds = xr.load_dataset(film, engine="h5netcdf")
        te = ds["TE mean [arcsec]"].values
        h = ds["min central film [um]"].values
        h = h[h > 0] if np.any(h > 0) else np.array([0.0])
        lines.append(f"* **Lubrication**: EHL films of {h.min():.3g} .. {h.max():.3g} um (viscosity "
                     f"0.01 .. 1.5 Pa s) change the TE mean by {te.max() - te.min():.3f} arcsec: negligible. The "
                     "seeds' mm-scale 'films' are not EHL films.")
    crank = results_root / "crankshaft_flexibility" / "compare.json"
    if crank.exists():
        n = json.loads(crank.read_text())
        lines.append(f"* **Crankshaft torsion** (rv40e, 412 N m): shifts TE by "
                     f"{n['flexible']['te_mean_arcsec'] - n['rigid']['te_mean_arcsec']:+.2f} arcsec (twist / z_c), "
                     "the ripple is unchanged.")
    if not lines:
        return []
    return ["## Answer", "", *lines, ""]