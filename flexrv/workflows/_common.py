"""Shared pieces of the seed-study workflows.

Every workflow module in :mod:`flexrv.workflows` exposes ``run(..., out_dir=None,
smoke=False) -> WorkflowResult`` and runs with ``python -m flexrv.workflows.NAME`` or
``flexrv workflow NAME``. A :class:`WorkflowResult` collects the numbers beside the
seed's reported values with an explanation of every difference, xarray datasets and
matplotlib figures, and writes them atomically (NetCDF, PNG, summary.md) to
``./results/<workflow>/`` of the current directory, like ``flexrv simulate`` — or to
``./results/<workflow>-smoke/`` for ``--smoke`` runs, whose every summary says so at
the top — unless an output folder is given. The seeds are the studies listed in
``docs/references.md`` (keys seed000 .. seed004).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from flexrv.cache import atomic_path, atomic_write_text
from flexrv.post.format import fmt as _fmt

#: smoke outputs go to ``results/<name><SMOKE_SUFFIX>``
SMOKE_SUFFIX = "-smoke"
#: the banner at the top of every smoke summary
SMOKE_BANNER = (
    "> **SMOKE RUN** (`--smoke`): short runs and coarse meshes to check that the workflow "
    "runs. The numbers below are NOT results: the runs are too short and too coarse "
    "(steady windows and spectra may fall in the ramps). Run without `--smoke` for results."
)
#: the generated report written by :func:`collect_report` (the tracked results/README.md is never touched)
REPORT_NAME = "REPORT.md"
#: the seed studies' bibliography (written in docs/references.md, keys seed000 .. seed004)
REFERENCES = (
    "## References",
    "",
    "Seed studies are cited by the keys of `docs/references.md` in the flexrv repository: "
    "`seed000`, `seed001`, `seed002`, `seed003`, "
    "`seed004` (full citations there).",
    "",
)


#: invisible marker closing every workflow summary: ``flexrv report`` collects only these
#: (not the ``flexrv simulate`` / ``compare`` runs that share ./results)
WORKFLOW_MARK = "<!-- flexrv workflow: {name} -->"


def is_workflow_summary(path: Path) -> bool:
    """True if ``path`` is a summary.md written by :meth:`WorkflowResult.save`."""
    return "<!-- flexrv workflow: " in path.read_text()


def results_root() -> Path:
    """``./results`` of the current directory (the default parent of every output, as for
    ``flexrv simulate``)."""
    return Path.cwd() / "results"


def default_out(name: str, smoke: bool = False) -> Path:
    """The default output folder of workflow ``name``: ``./results/<name>`` or, for a
    smoke run, ``./results/<name>-smoke``."""
    return results_root() / (name + (SMOKE_SUFFIX if smoke else ""))


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
    smoke: bool = False  # a --smoke run: separate folder, banner on the summary

    def compare(self, quantity: str, unit: str, seed: Any, flexrv: Any, note: str = "") -> None:
        """Add a seed-vs-flexrv row (``note`` explains any difference)."""
        self.comparisons.append(Comparison(quantity, unit, seed, flexrv, note))

    # ---------------------------------------------------------------- output
    def summary_markdown(self) -> str:
        """The summary.md text: title, seeds, comparison table, notes, tables, figures."""
        lines = [f"# {self.title}" + (" (SMOKE RUN)" if self.smoke else ""), ""]
        if self.smoke:
            lines += [SMOKE_BANNER, ""]
        if self.seeds:  # a workflow of flexrv's own (e.g. the mode gallery) reproduces no seed
            lines += [f"Seeds: {', '.join(self.seeds)} (see References)", ""]
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
        lines += list(REFERENCES)
        lines += [WORKFLOW_MARK.format(name=self.name), ""]
        return "\n".join(lines)

    def save(self, out_dir: str | Path | None = None) -> Path:
        """Write NetCDF datasets, PNG figures and summary.md atomically; return the folder."""
        out = Path(out_dir) if out_dir else default_out(self.name, self.smoke)
        out.mkdir(parents=True, exist_ok=True)
        for name, ds in self.datasets.items():
            with atomic_path(out / f"{name}.nc") as tmp:
                ds.to_netcdf(tmp, engine="h5netcdf")
        for name, fig in self.figures.items():
            with atomic_path(out / f"{name}.png") as tmp:
                fig.savefig(tmp, dpi=120, format="png")
        atomic_write_text(out / "summary.md", self.summary_markdown())
        if self.smoke:  # nested run folders (e.g. compare's rigid/, flexible/) are smoke too
            for path in out.rglob("summary.md"):
                text = path.read_text()
                if SMOKE_BANNER not in text:
                    atomic_write_text(path, SMOKE_BANNER + "\n\n" + text)
        self.out_dir = out
        return out


def new_figure(*args, **kwargs):
    """A matplotlib figure on the Agg backend (headless)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt.subplots(*args, **kwargs)


def _is_smoke_folder(path: Path) -> bool:
    return path.name.endswith(SMOKE_SUFFIX)


def collect_report(results_root: Path | None = None, smoke: bool = False) -> Path:
    """Collect the workflow summaries under ``results_root`` (default ``./results``) into
    the generated ``REPORT.md`` there (``REPORT-smoke.md`` from the ``-smoke`` folders if
    ``smoke``); the tracked results/README.md is never written.

    Full and smoke runs are never mixed: the full report reads ``results/<name>/``
    only, the smoke report ``results/<name>-smoke/`` only and carries the smoke banner.
    Figures keep working because links are rewritten relative to the results folder.
    """
    root = Path(results_root) if results_root is not None else results_root_default()
    parts = [f"# flexrv results{' (SMOKE RUNS)' if smoke else ''}", ""]
    if smoke:
        parts += [SMOKE_BANNER, ""]
    parts += [
        "Generated by `flexrv report` from the workflow outputs below; every number and every "
        "statement in the Answer is computed from those outputs. Each section below is one "
        "workflow's summary (seed numbers beside flexrv's, with the reason for every difference).",
        "",
    ]
    answer = answer_section(root, smoke=smoke)
    if answer:
        parts += answer
    found = sorted(
        p for p in root.glob("*/summary.md") if _is_smoke_folder(p.parent) == smoke and is_workflow_summary(p)
    )
    for path in found:
        folder = path.parent.name
        text = path.read_text()
        text = text.replace("](", f"]({folder}/").replace(f"]({folder}/http", "](http")
        # drop each summary's own References section: the report has one at its end
        text = text.split("\n## References\n")[0].split("<!-- flexrv workflow: ")[0]
        text = "\n".join(("#" + line) if line.startswith("#") else line for line in text.splitlines())
        parts += [text, ""]
    if not found:
        parts.append(f"No workflow results yet: run `flexrv workflow NAME`{' --smoke' if smoke else ''} first.")
        parts.append("")
    parts += list(REFERENCES)
    name = REPORT_NAME.replace(".md", "-smoke.md") if smoke else REPORT_NAME
    return atomic_write_text(root / name, "\n".join(parts) + "\n")


def results_root_default() -> Path:
    """Alias of :func:`results_root` (the report's default folder)."""
    return results_root()


def _change_words(delta: float, scale: float, rel_small: float = 0.05) -> str:
    """``"negligible"`` if ``|delta|`` is below ``rel_small`` of ``scale`` (a reference
    magnitude), else ``"significant"`` — the report's wording computed from the numbers."""
    if scale <= 0 or not math.isfinite(scale):
        return "significant" if delta != 0 else "negligible"
    return "negligible" if abs(delta) < rel_small * scale else "significant"


def _rigid_flexible(path: Path) -> tuple[dict, dict, float, float]:
    """A workflow's compare.json at ``path``: its rigid and flexible summaries and the
    flexible model's TE mean and peak-to-peak less the rigid model's [arcsec]."""
    import json

    n = json.loads(path.read_text())
    r, f = n["rigid"], n["flexible"]
    return r, f, f["te_mean_arcsec"] - r["te_mean_arcsec"], f["te_pp_arcsec"] - r["te_pp_arcsec"]


def answer_section(results_root: Path | None = None, smoke: bool = False) -> list[str]:
    """The report's short answer, computed from the saved workflow outputs that exist
    (rigid_vs_flexible/compare.json, ring_deformation.nc, lubrication_film.nc,
    crankshaft_flexibility/compare.json; the ``-smoke`` folders if ``smoke``); empty if
    none does. Every qualitative word (negligible / significant, larger / smaller,
    reproduced / not) is decided from the numbers: a change is called negligible below
    5 % of the reference magnitude (the rigid model's TE peak-to-peak, or its mean)."""
    import numpy as np
    import xarray as xr

    from flexrv.studies.compare import SEED_TE

    root = Path(results_root) if results_root is not None else results_root_default()
    sfx = SMOKE_SUFFIX if smoke else ""
    lines: list[str] = []
    cmp = root / f"rigid_vs_flexible{sfx}" / "compare.json"
    if cmp.exists():
        r, f, d_mean, d_pp = _rigid_flexible(cmp)
        ratio = f["te_pp_arcsec"] / r["te_pp_arcsec"] if r["te_pp_arcsec"] else float("nan")
        sr, sf = SEED_TE["rigid"], SEED_TE["flexible"]
        seed_ratio = (sf["te_max_arcsec"] - sf["te_min_arcsec"]) / (sr["te_max_arcsec"] - sr["te_min_arcsec"])
        agree = abs(ratio - seed_ratio) < 0.25 * seed_ratio
        lines.append(
            f"* **Main-bearing flexibility** (rv221, seed000/seed001): steady TE "
            f"{r['te_min_arcsec']:.2f} .. {r['te_max_arcsec']:.2f} arcsec with the rigid model, "
            f"{f['te_min_arcsec']:.2f} .. {f['te_max_arcsec']:.2f} arcsec with flexible rings and "
            f"ball-resolved contacts: {d_mean:+.2f} arcsec in the mean "
            f"({_change_words(d_mean, r['te_pp_arcsec'])} against the rigid ripple of "
            f"{r['te_pp_arcsec']:.2f} arcsec) and {d_pp:+.2f} arcsec in the ripple, a ripple ratio "
            f"flexible/rigid of {ratio:.2f} against the seeds' {seed_ratio:.2f} "
            f"({'consistent with' if agree else 'unlike'} the seeds')."
        )
    ring = root / f"ring_deformation{sfx}" / "ring_deformation.nc"
    if ring.exists():
        ds = xr.load_dataset(ring, engine="h5netcdf")
        loaded = ds.where(ds["radial [kN]"] > 0, drop=True)
        if loaded.sizes.get("case", 0):
            d_rings = float(
                np.max(
                    np.abs(
                        np.concatenate(
                            [
                                loaded["TE min, flexible [arcsec]"].values
                                - loaded["TE min, rigid rings [arcsec]"].values,
                                loaded["TE max, flexible [arcsec]"].values
                                - loaded["TE max, rigid rings [arcsec]"].values,
                            ]
                        )
                    )
                )
            )
            pp = float(
                np.max(loaded["TE max, rigid rings [arcsec]"].values - loaded["TE min, rigid rings [arcsec]"].values)
            )
            line = (
                f"* **External load** (seed001's load cases, radial "
                f"{float(loaded['radial [kN]'].min()):.0f} .. {float(loaded['radial [kN]'].max()):.0f} kN): "
                f"outer-ring deflection {float(loaded['outer ring deflection [um]'].min()):.2f} .. "
                f"{float(loaded['outer ring deflection [um]'].max()):.2f} µm (seed 0.35 .. 0.65 µm); TE range "
                f"{float(loaded['TE min, flexible [arcsec]'].min()):.2f} .. "
                f"{float(loaded['TE max, flexible [arcsec]'].max()):.2f} arcsec with flexible rings; flexible "
                f"and rigid rings differ by at most {d_rings:.2f} arcsec "
                f"({_change_words(d_rings, pp)} against the TE peak-to-peak of {pp:.2f} arcsec)"
            )
            if "carrier radial shift, rigid rings [um]" in loaded:
                line += (
                    f"; the carrier's radial shift is "
                    f"{float(loaded['carrier radial shift, rigid rings [um]'].min()):.1f} .. "
                    f"{float(loaded['carrier radial shift, rigid rings [um]'].max()):.1f} µm with rigid rings"
                )
            lines.append(line + ".")
    film = root / f"lubrication{sfx}" / "lubrication_film.nc"
    if film.exists():
        ds = xr.load_dataset(film, engine="h5netcdf")
        te = ds["TE mean [arcsec]"].values
        h = ds["min central film [um]"].values
        h = h[h > 0] if np.any(h > 0) else np.array([0.0])
        spread = float(te.max() - te.min())
        scale = float(np.max(np.abs(te))) if te.size else 0.0
        lines.append(
            f"* **Lubrication**: EHL films of {h.min():.3g} .. {h.max():.3g} µm change the TE mean by "
            f"{spread:.3f} arcsec ({_change_words(spread, scale)} against a TE mean of up to "
            f"{scale:.2f} arcsec in magnitude)."
        )
    crank = root / f"crankshaft_flexibility{sfx}" / "compare.json"
    if crank.exists():
        r, f, d_mean, d_pp = _rigid_flexible(crank)
        lines.append(
            f"* **Crankshaft torsion** (rv40e): shifts the TE mean by {d_mean:+.2f} arcsec and the "
            f"ripple by {d_pp:+.3f} arcsec ({_change_words(d_pp, r['te_pp_arcsec'])} against the "
            f"rigid ripple of {r['te_pp_arcsec']:.2f} arcsec)."
        )
    if not lines:
        return []
    head = ["## Answer", ""]
    if smoke:
        head += ["(from SMOKE runs: not results)", ""]
    return [*head, *lines, ""]
