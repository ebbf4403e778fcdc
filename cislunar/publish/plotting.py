"""Plotting helpers: the packaged style, ``save_figure`` and rotating-frame views.

Figures are written under ``build/figures/`` resolved from the repository root (:mod:`cislunar.utils.paths`), never
from the working directory, with deterministic PNG metadata (no software or date stamps) so that re-running a
notebook rewrites byte-identical files when the numbers do not change.

``save_figure`` refuses a figure whose axes show data with tick labels but no axis label carrying a unit
(:func:`axis_label_problems`, :func:`has_unit`): "[km]", "[-]" for a dimensionless quantity, "(km)" accepted.
"""

from __future__ import annotations

import re
from importlib import resources
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Circle

from cislunar.cr3bp.dynamics import CR3BP, check_system
from cislunar.utils import paths, validation

# has_unit and axis_label_problems are public too; they join __all__ once tests/reliability/test_reliability.py has their
# malformed-argument specs (its coverage test walks __all__).
__all__ = ["use_style", "style_path", "save_figure", "plot_primaries", "plot_rotating", "three_plane_axes",
           "plot_three_planes", "thousands_km_axes"]

_PLANES = {"xy": (0, 1), "xz": (0, 2), "yz": (1, 2)}


def style_path() -> Path:
    """Path of the packaged matplotlib style file."""
    return Path(str(resources.files("cislunar.publish") / "cislunar.mplstyle"))


def use_style() -> None:
    """Activate the packaged style (call once at the top of a notebook)."""
    plt.style.use(str(style_path()))


def save_figure(fig, name: str, *, output_dir=None, formats=("png",), show=None) -> list[Path]:
    """Save ``fig`` as ``<build>/figures/<name>.<fmt>`` with deterministic metadata, and show the saved picture.

    In a notebook (matplotlib's inline backend) the figure is shown by displaying the PNG just written, at the
    size the inline backend would have drawn it, and then closed: the reader sees exactly the saved file, and the
    figure is rendered once instead of twice (saving, then the inline backend's own rendering at the end of the
    cell, used to be about half of the time of every figure cell).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    name : str
        File stem, e.g. ``"01_dro_family"``; letters, digits, ``_`` and ``-`` only.
    output_dir : path-like, optional
        Build directory (the runner passes its build); default: the scratch folder of hand runs
        (``build-scratch/`` in a checkout, :func:`cislunar.utils.paths.scratch_dir`), never ``build/``.
    formats : sequence of str
        File formats among ``png``, ``pdf`` and ``svg``.
    show : bool, optional
        Display the saved PNG (IPython display) and close ``fig``.  Default: when matplotlib's inline backend is
        active (a notebook); elsewhere the figure stays open and nothing is displayed.  Needs ``png`` in
        ``formats``.

    Returns
    -------
    list of pathlib.Path
        Written files.

    Raises
    ------
    ValueError
        If an axes of ``fig`` that shows data has a visible axis with tick labels whose label is missing or carries
        no unit (see :func:`axis_label_problems`); the message names the figure and lists the offending axes.
    """
    from matplotlib.figure import Figure

    if not isinstance(fig, Figure):
        raise TypeError(f"fig must be a matplotlib.figure.Figure; got {type(fig).__name__}")
    if not isinstance(name, str):
        raise TypeError(f"name must be a str; got {type(name).__name__}")
    if isinstance(formats, str):
        formats = (formats,)
    try:
        formats = tuple(formats)
    except TypeError:
        raise TypeError(f"formats must be a sequence of format names; got {type(formats).__name__}") from None
    if not formats:
        raise ValueError("formats must name at least one format")
    if not name or not all(c.isalnum() or c in "_-" for c in name):
        raise ValueError(f"name must be a non-empty file stem of letters, digits, '_' or '-'; got {name!r}")
    for fmt in formats:
        if fmt not in ("png", "pdf", "svg"):
            raise ValueError(f"formats entries must be 'png', 'pdf' or 'svg'; got {fmt!r}")
    if show is None:
        show = "png" in formats and _inline_backend()
    elif not isinstance(show, (bool, np.bool_)):
        raise TypeError(f"show must be a bool or None; got {type(show).__name__}")
    elif show and "png" not in formats:
        raise ValueError(f"show=True displays the saved PNG, so formats must include 'png'; got {formats!r}")
    out = []
    for fmt in formats:
        meta = {"png": {"Software": None}, "pdf": {"Creator": None, "Producer": None, "CreationDate": None},
                "svg": {"Date": None, "Creator": None}}[fmt]
        path = paths.figures_dir(output_dir) / f"{name}.{fmt}"
        fig.savefig(path, format=fmt, metadata=meta)
        out.append(path)
        if len(out) == 1:
            # The first save has laid the figure out, so the check needs no draw of its own (a second draw was
            # about half of the time of saving); a figure that fails it leaves no file behind.
            problems = _label_problems(fig)
            if problems:
                path.unlink()
                raise ValueError(f"figure {name!r}: every axis that shows tick labels needs a label with a unit "
                                 f"('[km]', '[-]' if dimensionless, '(km)' accepted); offending: "
                                 + "; ".join(problems))
    if show:
        _show_saved_png(fig, out[formats.index("png")])
    return out


def _inline_backend() -> bool:
    """Whether matplotlib draws through the inline backend of a notebook kernel."""
    import matplotlib

    return "inline" in str(matplotlib.rcParams["backend"])


def _png_size(data: bytes) -> tuple[int, int]:
    """Width and height in pixels of a PNG image (from its IHDR chunk)."""
    if data[:8] != b"\x89PNG\r\n\x1a\n" or data[12:16] != b"IHDR":
        raise ValueError("data is not a PNG image")
    return int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")


def _show_saved_png(fig, path: Path) -> None:
    """Display the PNG at ``path`` at the size the inline backend would draw ``fig`` (its dpi instead of the saved
    one), then close ``fig`` so that the backend does not render it again."""
    import matplotlib
    from IPython.display import Image, display

    data = path.read_bytes()
    width, _ = _png_size(data)
    saved_dpi = matplotlib.rcParams["savefig.dpi"]
    saved_dpi = fig.dpi if saved_dpi == "figure" else float(saved_dpi)
    display(Image(data=data, format="png", width=max(1, round(width * fig.dpi / saved_dpi))))
    plt.close(fig)


_BRACKETED = re.compile(r"\[[^\[\]]*\S[^\[\]]*\]")  # "[km]", "[-]", "[10³ km]", "[$\mathrm{m\,s^{-1}}$]"
# "range (km)", "x (10³ km)": a short parenthesised unit (at most 16 characters, one space) at the end of the label;
# "orbit (sorted by size)" or "(micro-rad, Eq. 20)" are remarks, not units.
_TRAILING_PARENS = re.compile(r"\(\s*([^()\s]+(?: [^()\s]+)?)\s*\)\s*$")


def has_unit(label: str) -> bool:
    """Whether an axis label carries a unit: a bracketed part ``[km]`` (``[-]`` if dimensionless) anywhere, or a
    short parenthesised one ``(km)`` at its end (at most 16 characters and one space, so that a remark such as
    ``"orbit (sorted by size)"`` is not taken for a unit).

    Examples
    --------
    >>> has_unit("range [km]"), has_unit("stability index ν [-]"), has_unit("Δv (m/s)")
    (True, True, True)
    >>> has_unit("range"), has_unit("x (Moon-centred) position"), has_unit("epoch []"), has_unit("orbit (sorted by r)")
    (False, False, False, False)
    """
    if not isinstance(label, str):
        raise TypeError(f"label must be a str; got {type(label).__name__}")
    text = label.strip()
    if _BRACKETED.search(text):
        return True
    match = _TRAILING_PARENS.search(text)
    return match is not None and len(match.group(1)) <= 16


def _shows_data(ax) -> bool:
    """Whether ``ax`` draws data: a visible non-empty line, collection, patch or image (legends and text do not count)."""
    from matplotlib.collections import Collection
    from matplotlib.image import AxesImage
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch
    from matplotlib.spines import Spine

    for art in ax.get_children():
        if art is ax.patch or not art.get_visible():
            continue
        if isinstance(art, Line2D):
            if len(art.get_xdata(orig=False)):
                return True
        elif isinstance(art, Collection):
            if len(art.get_offsets()) or len(art.get_paths()):
                return True
        elif isinstance(art, (Patch, AxesImage)) and not isinstance(art, Spine):
            return True
    return False


def _tick_labels_shown(axis) -> bool:
    """Whether ``axis`` is visible and prints at least one non-empty major or minor tick label."""
    if not axis.get_visible():
        return False
    for which in ("major", "minor"):
        if any(t.get_visible() and t.get_text().strip() for t in axis.get_ticklabels(which=which)):
            return True
    return False


def _axes_name(fig, ax, index: int) -> str:
    """How an error message names ``ax``: its title (or its colour bar's parent), else its grid position."""
    title = " / ".join(t for t in (ax.get_title(loc) for loc in ("left", "center", "right")) if t)
    if hasattr(ax, "_colorbar"):
        return f"colour bar (axes {index})"
    if title:
        return f"axes {index} {title!r}"
    spec = ax.get_subplotspec() if hasattr(ax, "get_subplotspec") else None
    if spec is not None:
        return f"axes {index} (row {spec.rowspan.start + 1}, column {spec.colspan.start + 1})"
    return f"axes {index} (inset or free-standing)"


def axis_label_problems(fig) -> list[str]:
    """Axes of ``fig`` whose axis labels break the figure convention (empty list if none).

    Rule: every axes that shows data (a visible non-empty line, collection, patch or image) and has a visible
    axis (x, y; z on 3-D axes; the long axis of a colour bar) printing tick labels must label that axis with a
    non-empty text carrying a unit (:func:`has_unit`).  Exempt: axes turned off (``axis('off')``), image panels
    without ticks, axes whose tick labels are hidden (shared axes, ``label_outer``), axes holding only a legend or
    text.  A figure-level ``supxlabel``/``supylabel`` with a unit stands for the x/y labels its axes omit.

    The figure is laid out first (``draw_without_rendering``) so that tick texts and their visibility are known.

    Returns
    -------
    list of str
        One entry per offending axis: which axes (title, colour bar or grid position), which axis, the label.
    """
    from matplotlib.figure import Figure

    if not isinstance(fig, Figure):
        raise TypeError(f"fig must be a matplotlib.figure.Figure; got {type(fig).__name__}")
    fig.draw_without_rendering()
    return _label_problems(fig)


def _label_problems(fig) -> list[str]:
    """:func:`axis_label_problems` on a figure already laid out by a draw (unchecked)."""
    sup = {"x": getattr(fig, "_supxlabel", None), "y": getattr(fig, "_supylabel", None)}
    sup = {k: (v.get_text() if v is not None and v.get_visible() else "") for k, v in sup.items()}
    problems = []
    for index, ax in enumerate(fig.axes):
        axis_on = getattr(ax, "_axis3don", True) if hasattr(ax, "zaxis") else ax.axison  # 3-D axes keep their own
        if not ax.get_visible() or not axis_on or not _shows_data(ax):
            continue
        axes = [("x", ax.xaxis), ("y", ax.yaxis)] + ([("z", ax.zaxis)] if hasattr(ax, "zaxis") else [])
        for letter, axis in axes:
            if not _tick_labels_shown(axis):
                continue
            label = axis.label.get_text() if axis.label.get_visible() else ""
            if not label.strip() and sup.get(letter, "").strip() and not hasattr(ax, "_colorbar"):
                label = sup[letter]
            if not label.strip():
                problems.append(f"{_axes_name(fig, ax, index)}: {letter} axis has no label")
            elif not has_unit(label):
                problems.append(f"{_axes_name(fig, ax, index)}: {letter} axis label {label!r} has no unit")
    return problems


def _check_axes(ax, method: str = "add_patch"):
    if not callable(getattr(ax, method, None)):
        raise TypeError(f"ax must be a matplotlib Axes; got {type(ax).__name__}")
    return ax


def plot_primaries(ax, system: CR3BP, plane: str = "xy", *, moon_centred: bool = False, units: str = "LU",
                   earth: bool = True, moon: bool = True) -> None:
    """Draw Earth and Moon to scale on a 2-D projection.

    Parameters
    ----------
    ax : matplotlib Axes
    system : CR3BP
    plane : {"xy", "xz", "yz"}
        Projection plane of the rotating frame.
    moon_centred : bool
        Origin at the Moon instead of the barycentre.
    units : {"LU", "km"}
        Axis units.
    """
    _check_axes(ax)
    check_system(system)
    validation.choice(plane, "plane", tuple(_PLANES))
    validation.choice(units, "units", ("LU", "km"))
    scale = system.length_unit_km if units == "km" else 1.0
    shift = system.secondary_position if moon_centred else np.zeros(3)
    i, j = _PLANES[plane]
    bodies = []
    if earth:
        bodies.append((system.primary_position, system.primary_radius, "#2e6fba", "Earth"))
    if moon:
        bodies.append((system.secondary_position, system.secondary_radius, "#8c8c8c", "Moon"))
    for pos, radius, colour, label in bodies:
        p = (pos - shift) * scale
        ax.add_patch(Circle((p[i], p[j]), radius * scale, color=colour, zorder=3))
        ax.plot([], [], "o", color=colour, label=label)  # the legend's key: a disc, as drawn (a patch shows a square)


def plot_rotating(ax, states, system: CR3BP | None = None, plane: str = "xy", *, moon_centred: bool = False,
                  units: str = "LU", **kwargs):
    """Plot trajectories ``(..., m, 6)`` (or ``(..., m, 3)``) projected on ``plane`` of the rotating frame."""
    _check_axes(ax, "plot")
    validation.choice(plane, "plane", tuple(_PLANES))
    validation.choice(units, "units", ("LU", "km"))
    s = validation.as_array(states, "states", finite=False)
    if s.ndim < 2 or s.shape[-1] < 3:
        raise ValueError(f"states must have shape (..., m, >=3); got {s.shape}")
    if (moon_centred or units == "km") and system is None:
        raise ValueError("system is required for moon_centred=True or units='km'")
    if system is not None:
        check_system(system)
    pos = s[..., :3].copy()
    if moon_centred:
        pos = pos - system.secondary_position
    if units == "km":
        pos = pos * system.length_unit_km
    i, j = _PLANES[plane]
    lines = []
    for traj in pos.reshape(-1, pos.shape[-2], 3):
        lines += ax.plot(traj[:, i], traj[:, j], **kwargs)
        kwargs.pop("label", None)
    unit = "km" if units == "km" else "LU"
    ax.set_xlabel(f"{'xyz'[i]} [{unit}]")
    ax.set_ylabel(f"{'xyz'[j]} [{unit}]")
    ax.set_aspect("equal", adjustable="datalim")
    return lines


def thousands_km_axes(ax, plane: str, frame: str = "Moon-centred", nbins: int = 5) -> None:
    """Label an axes drawn in km on ``plane`` in units of 10^3 km, with at most ``nbins`` ticks per axis.

    Large km values (tens of thousands) collide as tick labels; printing them in thousands keeps them short.
    Axis labels name the coordinate, the ``frame`` and the unit, e.g. ``"x (Moon-centred) [10³ km]"``.
    """
    _check_axes(ax, "locator_params")
    validation.choice(plane, "plane", tuple(_PLANES))
    nbins = validation.integer(nbins, "nbins", minimum=2)
    import matplotlib.pyplot as plt

    ax.locator_params(axis="both", nbins=nbins)
    ax.xaxis.set_major_formatter(plt.FuncFormatter(lambda v, _: f"{v / 1e3:g}"))
    ax.yaxis.set_major_formatter(plt.FuncFormatter(lambda v, _: f"{v / 1e3:g}"))
    suffix = f" ({frame})" if frame else ""
    ax.set_xlabel(f"{plane[0]}{suffix} [10³ km]")
    ax.set_ylabel(f"{plane[1]}{suffix} [10³ km]")


def three_plane_axes(figsize=(12, 4)):
    """A figure with three axes for the x-y, x-z and y-z projections."""
    fig, axes = plt.subplots(1, 3, figsize=figsize)
    return fig, dict(zip(("xy", "xz", "yz"), axes))


def plot_three_planes(axes: dict, states, system: CR3BP | None = None, **kwargs) -> None:
    """Plot trajectories on the three principal planes (axes from :func:`three_plane_axes`)."""
    if not isinstance(axes, dict):
        raise TypeError(f"axes must be the dict returned by three_plane_axes; got {type(axes).__name__}")
    for plane, ax in axes.items():
        plot_rotating(ax, states, system, plane, **dict(kwargs))
