"""The progress-bar switch: off returns the iterable itself, plain is text tqdm, bad modes are named."""

import pytest

from cislunar.utils import progress as pg


def test_off_returns_iterable(monkeypatch):
    monkeypatch.setenv("CISLUNAR_PROGRESS", "off")
    items = [1, 2, 3]
    assert pg.progress(items) is items
    bar = pg.progress(total=3)
    bar.update(1)
    bar.close()


def test_disabled_overrides_mode(monkeypatch):
    monkeypatch.setenv("CISLUNAR_PROGRESS", "plain")
    items = (4, 5)
    assert pg.progress(items, enabled=False) is items


def test_plain_is_text_tqdm(monkeypatch, capsys):
    monkeypatch.setenv("CISLUNAR_PROGRESS", "plain")
    from tqdm.std import tqdm as std_tqdm

    bar = pg.progress(range(4), desc="work")
    assert type(bar) is std_tqdm
    assert list(bar) == [0, 1, 2, 3]
    err = capsys.readouterr().err
    assert "work" in err and "4/4" in err


def test_bad_mode_is_named(monkeypatch):
    monkeypatch.setenv("CISLUNAR_PROGRESS", "widgets")
    with pytest.raises(ValueError, match="CISLUNAR_PROGRESS"):
        pg.progress([1])
