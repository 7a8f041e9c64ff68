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
