"""The fixed costs of a command's process: what the CLI imports before it knows the command,
and the garbage collector's thresholds while it runs (benchmarks/bench_startup.py measures the
whole processes; docs/benchmarks.md has the figures)."""

from __future__ import annotations

import gc
import json
import subprocess
import sys


def _modules_after(code: str) -> set[str]:
    """The modules a fresh interpreter holds after running ``code``."""
    probe = code + "\nimport json, sys\nprint(json.dumps(sorted(sys.modules)))"
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=300, check=True)
    return set(json.loads(out.stdout.splitlines()[-1]))


def test_cli_import_leaves_the_heavy_libraries_to_the_commands():
    """Importing the CLI (every command registered) imports neither xarray (with pandas ~0.3 s
    CPU), matplotlib, numba, Exudyn nor dask: each command imports what it uses when it runs.
    ``flexrv.post.Results`` is still reachable (imported on first access)."""
    mods = _modules_after("import flexrv.cli\nimport flexrv.post")
    assert "flexrv.cli.te" in mods and "flexrv.cli.simulate" in mods
    heavy = {"xarray", "pandas", "matplotlib", "numba", "exudyn", "dask", "scipy.optimize"}
    assert not mods & heavy, sorted(mods & heavy)
    mods = _modules_after("import flexrv.post\nflexrv.post.Results")
    assert "xarray" in mods and "flexrv.post.results" in mods


def test_plots_never_import_pyplot():
    """A figure of the plots (``flexrv.viz.plots._plt``) is a Figure on an Agg canvas: drawing and
    saving one imports neither pyplot nor a GUI backend."""
    code = (
        "import io\nfrom flexrv.viz.plots import _plt\n"
        "fig, ax = _plt().subplots(figsize=(3, 2))\nax.plot([1, 2, 3], [1e-3, 1e-1, 1.0])\n"
        "fig.savefig(io.BytesIO(), format='png')"
    )
    mods = _modules_after(code)
    assert "matplotlib.backends.backend_agg" in mods
    assert not {m for m in mods if m == "matplotlib.pyplot" or "backend_tk" in m or "backend_qt" in m}


def test_main_sets_the_gc_thresholds_of_a_command():
    """``flexrv.cli.main`` runs a command with :data:`flexrv.cli.GC_THRESHOLDS` (a first generation
    of 50,000 objects instead of 700: ~0.45 -> ~0.1 s of collector CPU in a warm simulate), and
    the command's result is unchanged (``presets --json`` lists every preset)."""
    import io
    from contextlib import redirect_stdout

    from flexrv import cli
    from flexrv.design import list_presets

    before = gc.get_threshold()
    buf = io.StringIO()
    try:
        gc.set_threshold(700, 10, 10)
        with redirect_stdout(buf):
            try:
                cli.main(["presets", "--json"])
            except SystemExit as exc:
                assert exc.code in (0, None)
        during = gc.get_threshold()
    finally:
        gc.set_threshold(*before)
    assert during == cli.GC_THRESHOLDS and cli.GC_THRESHOLDS[0] >= 10_000
    assert [p["name"] for p in json.loads(buf.getvalue())] == list_presets()
