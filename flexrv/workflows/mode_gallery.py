"""Mode gallery: free-free eigenfrequencies and off-screen pyvista
renderings of the first modes of every flexible part of both presets.

Uses :func:`flexrv.fem.body.part_modes` and :func:`flexrv.viz.modes.render_mode_png`
exactly as ``flexrv modes PRESET --part PART --png DIR`` does.

Run: ``python -m flexrv.workflows.mode_gallery`` or ``flexrv workflow mode_gallery``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from flexrv.workflows._common import WorkflowResult, default_out, new_figure

NAME = "mode_gallery"
PARTS = ("outer_ring", "inner_ring", "crankshaft", "cycloid_disc")
PRESETS = ("rv221", "rv40e")
N_MODES = 4
#: smoke: rv40e crankshaft, coarse 6 mm mesh, 2 modes, no constrained modes
SMOKE = {"presets": ("rv40e",), "parts": ("crankshaft",), "n_modes": 2, "size": 6e-3}


def run(out_dir=None, smoke: bool = False, presets=None, parts=None, n_modes=None, size=None) -> WorkflowResult:
    """Render the first ``n_modes`` free-free modes of ``parts`` of ``presets`` to PNGs
    (``size``: mesh size [m], default: each part's default) and tabulate the frequencies [Hz]."""
    import xarray as xr

    from flexrv.design import load
    from flexrv.fem.body import part_modes
    from flexrv.viz.modes import render_mode_png

    if smoke:
        presets, parts = presets or SMOKE["presets"], parts or SMOKE["parts"]
        n_modes, size = n_modes or SMOKE["n_modes"], size or SMOKE["size"]
    presets, parts, n_modes = tuple(presets or PRESETS), tuple(parts or PARTS), int(n_modes or N_MODES)
    out = Path(out_dir) if out_dir else default_out(NAME, smoke)
    out.mkdir(parents=True, exist_ok=True)
    r = WorkflowResult(NAME, "Mode gallery: free-free modes of the flexible parts", [], smoke=smoke)
    rows, gallery, freq = [], [], {}
    for p in presets:
        red = load(p)
        for part in parts:
            pm = part_modes(red, part, n=n_modes, size=size, constrained=not smoke)
            m = pm.mesh
            freq[f"{p}/{part}"] = [float(f) for f in pm.free_hz[:n_modes]]
            for k, f in enumerate(pm.free_hz[:n_modes]):
                name = f"{p}_{part}_mode{k + 1:02d}.png"
                render_mode_png(
                    out / name,
                    m.nodes,
                    m.tris,
                    pm.free_modes[:, k].reshape(-1, 3),
                    title=f"{p} {part} free mode {k + 1}: {f:.1f} Hz",
                )
                gallery.append(f"![{p} {part} mode {k + 1}]({name})")
                cf = float(pm.constrained_hz[k]) if k < len(pm.constrained_hz) else None
                rows.append(
                    {
                        "preset": p,
                        "part": part,
                        "mode": k + 1,
                        "free-free [Hz]": float(f),
                        "constrained [Hz]": cf,
                        "nodes": int(m.n_nodes),
                        "png": name,
                    }
                )
    r.tables["eigenfrequencies"] = rows
    r.numbers["frequencies_hz"] = freq
    r.numbers["pngs"] = [row["png"] for row in rows]
    r.text.append(
        "Free-free modes (6 rigid-body modes dropped) of the second-order tetrahedral FE models "
        "(flexrv.fem.body.part_modes); constrained: the part's interfaces clamped. "
        f"Mesh size: {'%.1f mm' % (size * 1e3) if size else 'each part default'}."
    )
    r.text.append("## Gallery\n\n" + "\n".join(gallery))
    r.datasets["frequencies"] = xr.Dataset(
        {"free_hz": (("case", "mode"), np.array([freq[c] for c in freq]), {"units": "Hz"})},
        coords={"case": list(freq), "mode": np.arange(1, n_modes + 1)},
    )
    fig, ax = new_figure(figsize=(8, 3.5))
    for j, c in enumerate(freq):
        ax.plot(np.arange(1, n_modes + 1), freq[c], "o-", label=c)
    from matplotlib.ticker import LogLocator, ScalarFormatter

    ax.set_xlabel("mode number"), ax.set_ylabel("free-free frequency [Hz]"), ax.set_yscale("log"), ax.legend(fontsize=7)
    ax.yaxis.set_major_formatter(ScalarFormatter())  # plain numbers in Hz, not 2.1 x 10^4
    ax.yaxis.set_minor_formatter(ScalarFormatter())
    ax.yaxis.set_minor_locator(LogLocator(subs=(2.0, 5.0)))
    ax.set_xticks(np.arange(1, n_modes + 1))  # whole mode numbers only
    fig.tight_layout()
    r.figures["frequencies"] = fig
    r.save(out)
    return r


if __name__ == "__main__":
    run()
