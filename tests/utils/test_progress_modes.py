"""The progress mode: plain text by default (hand runs, papermill, the runner alike), a widget only when asked."""

import pytest

from cislunar.utils import progress as pg


def test_plain_text_is_the_default_and_auto_reads_as_plain(monkeypatch):
    monkeypatch.delenv("CISLUNAR_PROGRESS", raising=False)
    assert pg.progress_mode() == "plain"
    bar = pg.progress(range(3))
    assert type(bar).__module__ == "tqdm.std"
    bar.close()
    monkeypatch.setenv("CISLUNAR_PROGRESS", "auto")
    assert pg.progress_mode() == "plain"


def test_widget_only_when_asked_and_bad_modes_are_refused(monkeypatch):
    monkeypatch.setenv("CISLUNAR_PROGRESS", "widget")
    assert pg.progress_mode() == "widget"
    monkeypatch.setenv("CISLUNAR_PROGRESS", "fancy")
    with pytest.raises(ValueError, match="CISLUNAR_PROGRESS"):
        pg.progress_mode()
