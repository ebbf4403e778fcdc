"""Every notebook runs end to end in quick mode through the same runner as ``make reproduce``."""

import pytest

from cislunar import notebooks

SOURCES = notebooks.discover()


@pytest.mark.notebook
@pytest.mark.parametrize("source", SOURCES, ids=[p.stem for p in SOURCES])
def test_notebook_quick(source, tmp_path_factory):
    result = notebooks.run_notebook(source, quick=True, seed=0)
    assert result.report_markdown.count("|") > 10, "closing paper-vs-reproduction table is empty"
    assert "| quantity | paper | reproduced | status |" in result.report_markdown
    rows = [ln for ln in result.report_markdown.splitlines() if ln.startswith("| ") and "quantity" not in ln]
    for row in rows:
        cells = [c.strip().lower() for c in row.strip("|").split(" | ")]
        assert "nan" not in cells[:3], f"{source.stem}: NaN in a table row: {row}"
        assert "failed" not in cells[3], f"{source.stem}: a check failed: {row}"
