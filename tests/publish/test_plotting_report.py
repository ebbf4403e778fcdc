"""save_figure paths and determinism; report tables; the notebook runner's failure reporting."""

import os
import re

import matplotlib.pyplot as plt
import numpy as np
import pytest

from cislunar.publish import notebooks, plotting
from cislunar.publish.claims import AtMost, Claim, Within, printed_tolerance
from cislunar.publish.report import ComparisonTable
from cislunar.utils import paths


def test_save_figure_resolves_from_repo_root_and_is_deterministic(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the working directory must not matter
    plotting.use_style()
    fig, ax = plt.subplots()
    ax.plot(np.arange(5), np.arange(5) ** 2)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("distance [m]")
    (p1,) = plotting.save_figure(fig, "test_determinism", output_dir=tmp_path / "b")
    first = p1.read_bytes()
    (p2,) = plotting.save_figure(fig, "test_determinism", output_dir=tmp_path / "b")
    assert p1 == p2 and p2.read_bytes() == first
    assert p1.parent == tmp_path / "b" / "figures"
    assert (paths.repo_root() / "pyproject.toml").is_file()
    monkeypatch.setenv("CISLUNAR_ROOT", str(tmp_path / "repo"))  # a hand run: the scratch folder, never build/
    (p3,) = plotting.save_figure(fig, "test_determinism")
    assert p3 == tmp_path / "repo" / "build-scratch" / "figures" / "test_determinism.png"
    assert p3.read_bytes() == first
    plt.close(fig)


def test_save_figure_rejects_bad_names_and_formats(tmp_path):
    fig = plt.figure()
    with pytest.raises(ValueError, match="name"):
        plotting.save_figure(fig, "../escape", output_dir=tmp_path)
    with pytest.raises(ValueError, match="formats"):
        plotting.save_figure(fig, "ok", output_dir=tmp_path, formats=("bmp",))
    plt.close(fig)


def _labelled_figure():
    plotting.use_style()
    fig, ax = plt.subplots(figsize=(4.0, 3.0))
    ax.plot(np.arange(5), np.arange(5) ** 2)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("distance [m]")
    return fig


def test_save_figure_show_displays_the_saved_png_at_the_inline_size_and_closes(tmp_path, monkeypatch):
    import IPython.display
    import matplotlib.image

    shown = []
    monkeypatch.setattr(IPython.display, "display", lambda obj: shown.append(obj))
    fig = _labelled_figure()
    (p,) = plotting.save_figure(fig, "shown", output_dir=tmp_path, show=True)
    assert len(shown) == 1 and shown[0].data == p.read_bytes()  # exactly the saved file
    height, width = matplotlib.image.imread(p).shape[:2]  # an independent reader of the PNG
    assert plotting._png_size(p.read_bytes()) == (width, height)
    # displayed at the inline backend's size: pixels at figure.dpi (110) instead of savefig.dpi (150)
    assert shown[0].width == round(width * 110 / 150) and shown[0].width < width
    assert not plt.fignum_exists(fig.number)  # closed: the inline backend does not draw it again

    fig = _labelled_figure()  # Agg (tests): the default neither displays nor closes
    plotting.save_figure(fig, "kept", output_dir=tmp_path)
    assert len(shown) == 1 and plt.fignum_exists(fig.number)
    monkeypatch.setattr(plotting, "_inline_backend", lambda: True)  # a notebook: the default shows
    plotting.save_figure(fig, "inline", output_dir=tmp_path)
    assert len(shown) == 2 and not plt.fignum_exists(fig.number)
    fig = _labelled_figure()
    plotting.save_figure(fig, "vector_only", output_dir=tmp_path, formats=("svg",))  # no PNG: nothing to show
    assert len(shown) == 2 and plt.fignum_exists(fig.number)
    plt.close(fig)


def test_save_figure_show_rejects_bad_values(tmp_path):
    fig = _labelled_figure()
    with pytest.raises(TypeError, match="show"):
        plotting.save_figure(fig, "x", output_dir=tmp_path, show="yes")
    with pytest.raises(ValueError, match="show=True.*png"):
        plotting.save_figure(fig, "x", output_dir=tmp_path, formats=("pdf",), show=True)
    with pytest.raises(ValueError, match="PNG"):
        plotting._png_size(b"GIF89a" + bytes(30))
    plt.close(fig)


def test_comparison_table_rows_come_from_judged_claims():
    t = ComparisonTable("demo")
    period = Claim("period [d]", 6.5624, Within(6.5624, printed_tolerance("6.5624")), source="Table 2")
    t.add(period.judge(6.56235))
    with pytest.raises(TypeError, match="verdict"):
        t.add("x", 1, 2, "reproduced")  # a typed status word is not a row
    t.add(Claim("y", 1.0, Within(1.0, 0.1), reason="printed value not periodic").judge(2.0))
    md = t.to_markdown()
    assert md.count("\n|") == 4 and "6.5624" in md and "| differs |" in md and "printed value not periodic" in md


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
    from cislunar.publish.report import STATUSES, ComparisonTable

    assert STATUSES == ("reproduced", "consistent (tuned)", "differs", "derived", "not in paper", "beyond paper")
    tuned = Claim("z_lim", 0.1, Within(0.1, 0.25, relative=True), tuned="window weight chosen to match")
    t = ComparisonTable("t").add(tuned.judge(0.11))
    assert "consistent (tuned)" in t.to_markdown() and "window weight chosen to match" in t.to_markdown()
    with pytest.raises(ValueError, match="kind"):
        Claim("x", 1.0, kind="agrees")


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


# --- the axis-label check of save_figure (issue 12: every axis with tick labels carries a label with a unit) -------

def _labelled(ax, x="time [d]", y="range [km]"):
    ax.set_xlabel(x)
    ax.set_ylabel(y)
    return ax


@pytest.mark.parametrize("label, ok", [
    ("range [km]", True), ("stability index ν [-]", True), ("x (Moon-centred) [10³ km]", True),
    (r"$\Delta v$ [$\mathrm{m\,s^{-1}}$]", True), ("Δv (m/s)", True), (r"$\sqrt{J_\rho}$ after 12 h (km)", True),
    ("range", False), ("", False), ("x (Moon-centred) position", False), ("epoch []", False), ("epoch [ ]", False),
    ("(km) range", False), ("x (1000 km)", True), (r"$\log_{10}\sqrt{J_\rho}$ (m)", True),
    (r"orbit (sorted by $\max r_{13}$)", False), ("sigma (micro-rad, Eq. 20)", False), ("phase (normalised by 2 pi)", False),
])
def test_has_unit(label, ok):
    assert plotting.has_unit(label) is ok


def test_save_figure_accepts_labelled_axes_and_writes(tmp_path):
    fig, ax = plt.subplots()
    _labelled(ax).plot([0, 1], [2, 3])
    (p,) = plotting.save_figure(fig, "ok_labels", output_dir=tmp_path)
    assert p.is_file()
    plt.close(fig)


@pytest.mark.parametrize("xlabel, ylabel, bad", [
    ("", "range [km]", "x axis has no label"),
    ("time [d]", "", "y axis has no label"),
    ("time [d]", "range", "y axis label 'range' has no unit"),
    ("time", "range [km]", "x axis label 'time' has no unit"),
])
def test_save_figure_refuses_missing_label_or_unit_and_names_figure_and_axes(tmp_path, xlabel, ylabel, bad):
    fig, axes = plt.subplots(1, 2)
    _labelled(axes[0]).plot([0, 1], [2, 3])
    _labelled(axes[1], xlabel, ylabel).plot([0, 1], [2, 3])
    axes[1].set_title("residuals")
    with pytest.raises(ValueError, match=r"figure 'fig_bad'") as info:
        plotting.save_figure(fig, "fig_bad", output_dir=tmp_path)
    msg = str(info.value)
    assert bad in msg and "axes 1 'residuals'" in msg and "axes 0" not in msg
    assert not (tmp_path / "figures" / "fig_bad.png").exists()  # nothing written
    axes[1].set_title("")
    with pytest.raises(ValueError, match=r"axes 1 \(row 1, column 2\)"):  # untitled: named by its position
        plotting.save_figure(fig, "fig_bad", output_dir=tmp_path)
    plt.close(fig)


def test_shared_axes_with_hidden_tick_labels_pass_and_visible_ones_do_not(tmp_path):
    fig, axes = plt.subplots(2, 2, sharex=True, sharey=True)
    for ax in axes.flat:
        ax.plot([0, 1], [2, 3])
    for ax in axes[1, :]:
        ax.set_xlabel("time [d]")  # only the bottom row prints x tick labels
    for ax in axes[:, 0]:
        ax.set_ylabel("range [km]")  # only the left column prints y tick labels
    assert plotting.axis_label_problems(fig) == []
    plotting.save_figure(fig, "shared_ok", output_dir=tmp_path)
    axes[0, 1].tick_params(labelleft=True)  # now the upper-right panel prints y tick labels without a label
    problems = plotting.axis_label_problems(fig)
    assert len(problems) == 1 and "row 1, column 2" in problems[0] and "y axis has no label" in problems[0]
    plt.close(fig)


def test_figure_level_labels_cover_shared_axes(tmp_path):
    fig, axes = plt.subplots(1, 2, sharey=True)
    for ax in axes:
        ax.plot([0, 1], [2, 3])
        ax.set_xlabel("time [d]")
    assert len(plotting.axis_label_problems(fig)) == 1  # the left y axis
    fig.supylabel("range")
    assert "has no unit" in plotting.axis_label_problems(fig)[0]
    fig.supylabel("range [km]")
    assert plotting.axis_label_problems(fig) == []
    plt.close(fig)


def test_3d_axes_need_a_z_label(tmp_path):
    fig = plt.figure()
    ax = fig.add_subplot(projection="3d")
    ax.plot([0, 1], [0, 1], [0, 1])
    ax.set_xlabel("x [km]")
    ax.set_ylabel("y [km]")
    problems = plotting.axis_label_problems(fig)
    assert len(problems) == 1 and "z axis has no label" in problems[0]
    ax.set_zlabel("z")
    assert "z axis label 'z' has no unit" in plotting.axis_label_problems(fig)[0]
    ax.set_zlabel("z [km]")
    plotting.save_figure(fig, "three_d_ok", output_dir=tmp_path)
    ax.set_xlabel("")
    assert "x axis has no label" in plotting.axis_label_problems(fig)[0]
    ax.set_axis_off()  # a 3-D axes turned off is exempt
    assert plotting.axis_label_problems(fig) == []
    plt.close(fig)


def test_colour_bar_needs_a_label_with_unit(tmp_path):
    fig, ax = plt.subplots()
    mesh = _labelled(ax, "x [km]", "y [km]").pcolormesh(np.arange(12.0).reshape(3, 4))
    cbar = fig.colorbar(mesh, ax=ax)
    problems = plotting.axis_label_problems(fig)
    assert len(problems) == 1 and "colour bar" in problems[0] and "y axis has no label" in problems[0]
    cbar.set_label("cost")
    assert "'cost' has no unit" in plotting.axis_label_problems(fig)[0]
    cbar.set_label("cost [m/s]")
    plotting.save_figure(fig, "cbar_ok", output_dir=tmp_path)
    fig2, ax2 = plt.subplots()  # horizontal colour bar: its x axis carries the ticks
    mesh2 = _labelled(ax2, "x [km]", "y [km]").pcolormesh(np.arange(12.0).reshape(3, 4))
    fig2.colorbar(mesh2, ax=ax2, orientation="horizontal", label="density")
    assert any("colour bar" in p and "x axis label 'density'" in p for p in plotting.axis_label_problems(fig2))
    plt.close(fig)
    plt.close(fig2)


def test_exempt_axes_off_images_without_ticks_legend_and_text_only(tmp_path):
    fig, axes = plt.subplots(1, 4)
    axes[0].plot([0, 1], [2, 3])
    axes[0].axis("off")  # off: exempt
    axes[1].imshow(np.eye(3))
    axes[1].set_xticks([])
    axes[1].set_yticks([])  # image panel without ticks: exempt
    axes[2].plot([], [], label="proxy")
    axes[2].legend()  # legend only: exempt
    axes[3].text(0.5, 0.5, "note")  # text only: exempt
    assert plotting.axis_label_problems(fig) == []
    plotting.save_figure(fig, "exempt_ok", output_dir=tmp_path)
    axes[1].set_xticks([0, 1, 2])  # the image now prints tick labels: it needs an x label
    problems = plotting.axis_label_problems(fig)
    assert len(problems) == 1 and "axes 1" in problems[0] and "x axis has no label" in problems[0]
    plt.close(fig)


def test_twin_axes_and_hidden_axis(tmp_path):
    fig, ax = plt.subplots()
    _labelled(ax).plot([0, 1], [2, 3])
    twin = ax.twinx()
    twin.plot([0, 1], [5, 4])
    problems = plotting.axis_label_problems(fig)  # the twin's own x axis is hidden; its y axis is not
    assert len(problems) == 1 and "axes 1" in problems[0] and "y axis has no label" in problems[0]
    twin.set_ylabel("rate [km/s]")
    assert plotting.axis_label_problems(fig) == []
    ax.yaxis.set_visible(False)
    ax.set_ylabel("")
    assert plotting.axis_label_problems(fig) == []  # an invisible axis prints no tick labels
    plt.close(fig)


def test_axis_label_problems_rejects_non_figures():
    with pytest.raises(TypeError, match="fig"):
        plotting.axis_label_problems("not a figure")
    with pytest.raises(TypeError, match="label"):
        plotting.has_unit(3)


def test_the_legend_defines_exactly_the_status_words_a_table_uses():
    from cislunar.publish.report import STATUS_MEANINGS, STATUSES

    assert set(STATUS_MEANINGS) == set(STATUSES)
    t = ComparisonTable("t").add(Claim("a", 1.0, Within(1.0, 0.01, relative=True)).judge(1.0))
    t.add(Claim("b", 2.0, AtMost(2.5), reason="too large").judge(3.0)).add(Claim("c", kind="derived").judge(4.0))
    lines = t.legend().splitlines()
    assert [ln.split("**")[1] for ln in lines] == ["reproduced", "differs", "derived"]
    assert "fixed before comparing" in lines[0]
    assert ComparisonTable("empty").legend() == ""


def test_primaries_are_drawn_to_scale_and_keyed_as_discs():
    """One circle per body, of the body's radius at its position (km here), and a legend key that is a disc marker
    (a patch's key is a square, which a reader takes for another object)."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Circle

    from cislunar.cr3bp.dynamics import EARTH_MOON as em

    fig, ax = plt.subplots()
    plotting.plot_primaries(ax, em, units="km")
    circles = [p for p in ax.patches if isinstance(p, Circle)]
    assert [c.get_radius() for c in circles] == pytest.approx(
        [em.primary_radius * em.length_unit_km, em.secondary_radius * em.length_unit_km])
    assert circles[1].center == pytest.approx((em.secondary_position[0] * em.length_unit_km, 0.0))
    handles, labels = ax.get_legend_handles_labels()
    assert labels == ["Earth", "Moon"]
    assert all(isinstance(h, Line2D) and h.get_marker() == "o" for h in handles)
    plt.close(fig)
