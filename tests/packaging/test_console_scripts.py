"""The console scripts away from the repository: one line saying what is missing and how to get it (exit 2).

The installed-wheel version of the same check, with real console scripts, is in ``test_wheel.py``; these run in
process by pointing ``CISLUNAR_ROOT`` at a folder that is not a checkout.
"""

from __future__ import annotations

import email.message
import importlib.metadata

import pytest

from cislunar.publish import book, notebooks


def _metadata(*urls):
    msg = email.message.Message()
    for url in urls:
        msg["Project-URL"] = url
    return lambda name: msg


def test_in_the_checkout_nothing_is_missing(monkeypatch):
    monkeypatch.delenv("CISLUNAR_ROOT", raising=False)
    assert notebooks._missing_checkout("notebooks", "cislunar-notebooks") is None
    assert notebooks._missing_checkout("book", "cislunar-book") is None


@pytest.mark.parametrize("main, args, folder, script", [
    (notebooks.main, ["--quick", "01"], "notebooks", "cislunar-notebooks"),
    (book.main, [], "book", "cislunar-book"),
])
def test_outside_a_checkout_the_scripts_exit_2_with_one_line(main, args, folder, script, tmp_path, monkeypatch,
                                                              capsys):
    monkeypatch.setenv("CISLUNAR_ROOT", str(tmp_path))
    assert main(args) == 2
    out, err = capsys.readouterr()
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"error: {script} needs the repository's {folder}/ folder")
    assert f"{tmp_path.resolve()} has no {folder}/ folder" in lines[0]
    assert not (tmp_path / "build").exists() and not (tmp_path / "build-quick").exists()  # nothing written


def test_the_message_names_the_repository_url_when_the_metadata_declares_one(tmp_path, monkeypatch):
    monkeypatch.setenv("CISLUNAR_ROOT", str(tmp_path))
    monkeypatch.setattr(importlib.metadata, "metadata", _metadata(
        "Wolf & Jones (arXiv 2408.17435), https://arxiv.org/abs/2408.17435",
        "Repository, https://example.org/cislunar.git"))
    message = notebooks._missing_checkout("notebooks", "cislunar-notebooks")
    assert "git clone https://example.org/cislunar.git and run it from that checkout" in message
    assert "arxiv" not in message  # a paper's URL is not where the code lives

    monkeypatch.setattr(importlib.metadata, "metadata", _metadata(
        "Wolf & Jones (arXiv 2408.17435), https://arxiv.org/abs/2408.17435"))
    message = notebooks._missing_checkout("notebooks", "cislunar-notebooks")
    assert "clone the cislunar repository and run it from that checkout" in message


def test_without_a_checkout_or_cislunar_root_the_message_says_so(monkeypatch):
    def no_root():
        raise FileNotFoundError("cannot locate the repository root")

    monkeypatch.setattr(notebooks.paths, "repo_root", no_root)
    message = notebooks._missing_checkout("notebooks", "cislunar-notebooks")
    assert "not inside a checkout of the repository and CISLUNAR_ROOT is not set" in message
