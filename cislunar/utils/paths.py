"""Locations of the repository and of generated output, resolved from the package, never the working directory.

Three kinds of output folder, each with one purpose:

* ``build/``: only ever a complete full run (``make reproduce``), put in place by the notebook runner;
* ``build-quick/``: quick runs from the command line (``make test`` uses a temporary folder instead);
* ``build-scratch/``: anything run by hand (a notebook opened in JupyterLab, ``save_figure`` without a folder).

Nothing here creates a folder; the code that writes into one creates it.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

__all__ = ["repo_root", "build_dir", "quick_build_dir", "scratch_dir", "figures_dir"]


def repo_root() -> Path:
    """Repository root: ``CISLUNAR_ROOT`` if set, else the nearest ancestor of this package with ``pyproject.toml``.

    Raises
    ------
    FileNotFoundError
        When the package is not inside a checkout and ``CISLUNAR_ROOT`` is unset.
    """
    env = os.environ.get("CISLUNAR_ROOT")
    if env:
        return Path(env).resolve()
    here = Path(__file__).resolve().parent
    for candidate in (here, *here.parents):
        if (candidate / "pyproject.toml").is_file() and (candidate / "cislunar").is_dir():
            return candidate
    raise FileNotFoundError("cannot locate the repository root from the installed package; set CISLUNAR_ROOT")


def _in_checkout() -> Path | None:
    try:
        return repo_root()
    except FileNotFoundError:
        return None


def build_dir(output_dir: str | os.PathLike | None = None) -> Path:
    """Output directory: ``output_dir`` if given (relative paths are taken from the repository root), else ``build/``."""
    if output_dir is None or str(output_dir) == "":
        return repo_root() / "build"
    path = Path(output_dir)
    if not path.is_absolute():
        path = repo_root() / path
    return path


def quick_build_dir() -> Path:
    """``build-quick/`` under the repository root: the default home of quick runs from the command line.

    Quick runs never write into ``build/``, which only ever holds a full run (``make reproduce``).
    """
    return repo_root() / "build-quick"


def scratch_dir() -> Path:
    """Where hand runs write: ``build-scratch/`` in a checkout, else ``<temp>/cislunar-scratch`` (an installed
    package has no repository to write into)."""
    root = _in_checkout()
    return (root / "build-scratch") if root is not None else Path(tempfile.gettempdir()) / "cislunar-scratch"


def figures_dir(output_dir: str | os.PathLike | None = None) -> Path:
    """``<output_dir>/figures``, or ``<scratch>/figures`` when no folder is given (a hand run), created if missing."""
    base = scratch_dir() if output_dir is None or str(output_dir) == "" else build_dir(output_dir)
    path = base / "figures"
    path.mkdir(parents=True, exist_ok=True)
    return path
