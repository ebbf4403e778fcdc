"""Plotting helpers: the packaged style, ``save_figure`` and rotating-frame views.

Figures are written under ``build/figures/`` resolved from the repository root (:mod:`cislunar.paths`), never
from the working directory, with deterministic PNG metadata (no software or date stamps) so that re-running a
notebook rewrites byte-identical files when the numbers do not change.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Circle

from . import _checks, paths
from .dynamics import CR3BP

__all__ = ["use_style", "style_path", "save_figure", "plot_primaries", "plot_rotating", "three_plane_axes",
           "plot_three_planes", "thousands_km_axes"]

_PLANES = {"xy": (0, 1), "xz": (0, 2), "yz": (1, 2)}


def style_path() -> Path:
    """Path of the packaged matplotlib style file."""
    return Path(str(resources.files("cislunar") / "cislunar.mplstyle"))


def use_style() -> None:
    """Activate the packaged style (call once at the top of a notebook)."""
    plt.style.use(str(style_path()))


def save_figure(fig, name: str, *, output_dir=None, formats=("png",)) -> list[Path]:
    """Save ``fig`` as ``<build>/figures/<name>.<fmt>`` with deterministic metadata.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    name : str
        File stem, e.g. ``"01_dro_family"``; letters, digits, ``_`` and ``-`` only.
    output_dir : path-like, optional
        Build directory (default ``build/`` under the repository root).
    formats : sequence of str
        File formats among ``png``, ``pdf`` and ``svg``.

    Returns
    -------
    list of pathlib.Path
        Written files.
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
    out = []
    for fmt in formats:
        if fmt not in ("png", "pdf", "svg"):
            raise ValueError(f"formats entries must be 'png', 'pdf' or 'svg'; got {fmt!r}")
        meta = {"png": {"Software": None}, "pdf": {"Creator": None, "Producer": None, "CreationDate": None},
                "svg": {"Date": None, "Creator": None}}[fmt]
        path = paths.figures_dir(output_dir) / f"{name}.{fmt}"
        fig.savefig(path, format=fmt, metadata=meta)
        out.append(path)
    return out


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
    _checks.system(system)
    _checks.choice(plane, "plane", tuple(_PLANES))
    _checks.choice(units, "units", ("LU", "km"))
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
        ax.add_patch(Circle((p[i], p[j]), radius * scale, color=colour, zorder=3, label=label))


def plot_rotating(ax, states, system: CR3BP | None = None, plane: str = "xy", *, moon_centred: bool = False,
                  units: str = "LU", **kwargs):
    """Plot trajectories ``(..., m, 6)`` (or ``(..., m, 3)``) projected on ``plane`` of the rotating frame."""
    _check_axes(ax, "plot")
    _checks.choice(plane, "plane", tuple(_PLANES))
    _checks.choice(units, "units", ("LU", "km"))
    s = _checks.as_array(states, "states", finite=False)
    if s.ndim < 2 or s.shape[-1] < 3:
        raise ValueError(f"states must have shape (..., m, >=3); got {s.shape}")
    if (moon_centred or units == "km") and system is None:
        raise ValueError("system is required for moon_centred=True or units='km'")
    if system is not None:
        _checks.system(system)
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
    _checks.choice(plane, "plane", tuple(_PLANES))
    nbins = _checks.integer(nbins, "nbins", minimum=2)
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
