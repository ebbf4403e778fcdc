"""save_figure paths and determinism; report tables; the notebook runner's failure reporting."""

import os
import re

import matplotlib.pyplot as plt
import numpy as np
import pytest

from cislunar import notebooks, paths, plotting
from cislunar.report import ComparisonTable


def test_save_figure_resolves_from_repo_root_and_is_deterministic(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the working directory must not matter
    plotting.use_style()
    fig, ax = plt.subplots()
    ax.plot(np.arange(5), np.arange(5) ** 2)
    (p1,) = plotting.save_figure(fig, "test_determinism", output_dir=tmp_path / "b")
    first = p1.read_bytes()
    (p2,) = plotting.save_figure(fig, "test_determinism", output_dir=tmp_path / "b")
    assert p1 == p2 and p2.read_bytes() == first
    assert p1.parent == tmp_path / "b" / "figures"
    default = paths.figures_dir()
    assert default == paths.repo_root() / "build" / "figures"
    assert (paths.repo_root() / "pyproject.toml").is_file()
    plt.close(fig)


def test_save_figure_rejects_bad_names_and_formats(tmp_path):
    fig = plt.figure()
    with pytest.raises(ValueError, match="name"):
        plotting.save_figure(fig, "../escape", output_dir=tmp_path)
    with pytest.raises(ValueError, match="formats"):
        plotting.save_figure(fig, "ok", output_dir=tmp_path, formats=("bmp",))
    plt.close(fig)


def test_comparison_table_rules():
    t = ComparisonTable("demo")
    t.add("period [d]", 6.5624, 6.56235, "reproduced")
    with pytest.raises(ValueError, match="needs a note"):
        t.add("x", 1, 2, "differs")
    with pytest.raises(ValueError, match="status"):
        t.add("x", 1, 2, "ok")
    t.add("y", 1, 2, "differs: printed value not periodic")
    md = t.to_markdown()
    assert md.count("\n|") == 4 and "6.5624" in md and "differs: printed" in md


def test_runner_names_the_failing_notebook_and_cell(tmp_path):
    src = tmp_path / "99_failing.py"
    src.write_text(
        '# %% [markdown]\n# A notebook that fails.\n\n# %% tags=["parameters"]\nQUICK = False\nSEED = 0\n'
        'OUTPUT_DIR = ""\n\n# %%\nx = 1\n\n# %%\nraise ValueError("boom in cell")\n'
    )
    with pytest.raises(notebooks.NotebookFailure, match=r"99_failing: cell \d+ .*ValueError: boom in cell"):
        notebooks.run_notebook(src, quick=True, output_dir=tmp_path / "build")


def test_runner_requires_one_parameters_cell(tmp_path):
    src = tmp_path / "98_noparams.py"
    src.write_text("# %%\nx = 1\n")
    with pytest.raises(notebooks.NotebookFailure, match="parameters"):
        notebooks.run_notebook(src, quick=True, output_dir=tmp_path / "build")


def test_every_notebook_source_follows_the_conventions():
    for src in notebooks.discover():
        text = src.read_text()
        assert re.fullmatch(r"\d\d[a-z]?_[a-z0-9_]+", src.stem), f"{src.name}: NN_topic.py or NNx_topic.py"
        assert text.count('tags=["parameters"]') == 1, src
        for name in ("QUICK", "SEED", "OUTPUT_DIR"):
            assert f"\n{name} = " in text, (src, name)
        assert ".display()" in text, f"{src.name} does not display its closing table"
    assert not list((paths.repo_root() / "notebooks").glob("*.ipynb")) or os.environ.get("CI") is None


def test_status_words_follow_the_guide():
    from cislunar.report import STATUSES, ComparisonTable

    assert STATUSES == ("reproduced", "consistent (tuned)", "differs", "derived", "not in paper", "beyond paper")
    t = ComparisonTable("t").add("z_lim", 0.1, 0.11, "consistent (tuned)", "window weight chosen to match")
    assert "consistent (tuned)" in t.to_markdown()
    for bad_status in ("agrees", "consistent"):
        with pytest.raises(ValueError, match="status"):
            ComparisonTable("t").add("x", 1, 2, bad_status)


def test_thousands_km_axes_labels_and_ticks():
    fig, ax = plt.subplots()
    ax.plot([0.0, 40000.0], [-20000.0, 60000.0])
    plotting.thousands_km_axes(ax, "yz", frame="Moon-centred")
    assert ax.get_xlabel() == "y (Moon-centred) [10³ km]" and ax.get_ylabel() == "z (Moon-centred) [10³ km]"
    for axis in (ax.xaxis, ax.yaxis):  # printed in thousands of km
        assert axis.get_major_formatter()(40000.0, 0) == "40"
        assert axis.get_major_formatter()(-2500.0, 0) == "-2.5"
    assert len(ax.get_xticks()) <= 7 and len(ax.get_yticks()) <= 7  # at most nbins + 1 intervals
    with pytest.raises(ValueError, match="plane"):
        plotting.thousands_km_axes(ax, "xq")
    plt.close(fig)
