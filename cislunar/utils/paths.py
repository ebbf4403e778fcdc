"""Locations of the repository and of generated output, resolved from the package, never the working directory."""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["repo_root", "build_dir", "quick_build_dir", "figures_dir"]


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


def build_dir(output_dir: str | os.PathLike | None = None) -> Path:
    """Output directory: ``output_dir`` if given (relative paths are taken from the repository root), else ``build/``."""
    if output_dir is None or str(output_dir) == "":
        path = repo_root() / "build"
    else:
        path = Path(output_dir)
        if not path.is_absolute():
            path = repo_root() / path
    path.mkdir(parents=True, exist_ok=True)
    return path


def quick_build_dir() -> Path:
    """``build-quick/`` under the repository root, created if missing: the default home of quick runs.

    Quick runs never write into ``build/``, which only ever holds a full run (``make reproduce``).
    """
    path = repo_root() / "build-quick"
    path.mkdir(parents=True, exist_ok=True)
    return path


def figures_dir(output_dir: str | os.PathLike | None = None) -> Path:
    """``<build>/figures``, created if missing."""
    path = build_dir(output_dir) / "figures"
    path.mkdir(parents=True, exist_ok=True)
    return path
