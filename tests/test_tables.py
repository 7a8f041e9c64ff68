"""Tables never cut what a user must copy: long names and paths wrap (fold) instead of
ending in an ellipsis, at any terminal width."""

from __future__ import annotations

import io

from rich.console import Console

from flexrv.cli import _common


def _cells(text: str, column: int) -> str:
    """The text of one column of a rendered rich table, its folded lines joined."""
    parts = []
    for line in text.splitlines():
        if line.startswith("│"):
            parts.append(line.split("│")[column + 1].strip())
    return "".join(parts)


def test_kv_table_folds_long_paths_and_names():
    """A 70-character result path and a 58-character quantity name in a 40-column terminal
    come out whole (folded over several lines, joined back exactly), with no ellipsis."""
    path = "results/rv40e_te_20990101-000000_a_long_output_directory_name/run"
    name = "a_very_long_quantity_name_that_a_user_must_copy_exactly_x"
    buf = io.StringIO()
    Console(file=buf, width=40, markup=False).print(_common.kv_table("t", [(name, path, "")]))
    text = buf.getvalue()
    assert "…" not in text
    assert _cells(text, 0) == name
    assert _cells(text, 1) == path


def test_show_prints_every_field_name_whole(monkeypatch):
    """`flexrv show rv40e` in a 70-column terminal: no cell is cut (no ellipsis) and every
    field name of every section is in the field column, whole once the folded lines are
    joined."""
    from typer.testing import CliRunner

    from flexrv.cli import app
    from flexrv.design import load

    buf = io.StringIO()
    monkeypatch.setattr(_common, "console", Console(file=buf, width=70, markup=False))
    import flexrv.cli.design as design_cli

    monkeypatch.setattr(design_cli, "console", _common.console)
    result = CliRunner().invoke(app, ["show", "rv40e"])
    assert result.exit_code == 0, result.output
    text = buf.getvalue()
    assert "…" not in text
    fields = _cells(text, 0)
    for section, values in load("rv40e").model_dump().items():
        if isinstance(values, dict) and section not in ("provenance", "errors"):
            for key in values:
                assert key in fields, (section, key)
