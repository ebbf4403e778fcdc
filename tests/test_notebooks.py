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
