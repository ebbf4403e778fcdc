"""One progress bar for every long loop of the package.

Long loops (continuation, Monte Carlo, SCvx iterations, sweeps) call :func:`progress`.  What it draws depends on the
environment variable ``CISLUNAR_PROGRESS``:

``plain`` (default)
    plain-text ``tqdm`` on standard error, updated at most every 10 s: readable in a terminal, a live notebook, a
    papermill run by hand and the notebook runner's logs alike, and no widget state in an executed notebook.
``widget``
    ``tqdm.auto``: a widget in a live Jupyter front end (text elsewhere), for readers who prefer it.
``off``
    no bar at all.

The bar is also off when the caller passes ``enabled=False``.
"""

from __future__ import annotations

import os
import sys

__all__ = ["progress", "progress_mode", "MODES"]

MODES = ("plain", "widget", "off")


def progress_mode() -> str:
    """The active mode from ``CISLUNAR_PROGRESS`` (``plain`` when unset; ``auto``, the old default, reads as
    ``plain``).

    Raises
    ------
    ValueError
        If the variable holds anything but ``plain``, ``widget`` or ``off``.
    """
    mode = os.environ.get("CISLUNAR_PROGRESS", "plain").strip().lower() or "plain"
    mode = "plain" if mode == "auto" else mode
    if mode not in MODES:
        raise ValueError(f"CISLUNAR_PROGRESS must be one of {MODES}, got {mode!r}")
    return mode


def progress(iterable=None, *, total: int | None = None, desc: str | None = None, enabled: bool = True):
    """Wrap ``iterable`` in a progress bar (or return it unchanged when bars are off).

    Parameters
    ----------
    iterable : iterable or None
        What to iterate over.  ``None`` with ``total`` gives a manually updated bar (``.update(n)``, ``.close()``).
    total : int, optional
        Number of items, when ``len(iterable)`` is not available.
    desc : str, optional
        Label printed before the bar.
    enabled : bool
        ``False`` switches the bar off whatever the mode.

    Returns
    -------
    iterable or tqdm
        ``iterable`` itself when off; a ``tqdm`` object otherwise.
    """
    mode = progress_mode()
    if not enabled or mode == "off":
        if iterable is None:
            return _NullBar()
        return iterable
    if mode == "plain":
        from tqdm.std import tqdm

        return tqdm(iterable, total=total, desc=desc, file=sys.stderr, ascii=True, mininterval=10.0,
                    dynamic_ncols=False, ncols=80)
    from tqdm.auto import tqdm

    return tqdm(iterable, total=total, desc=desc)


class _NullBar:
    """Stand-in for a manual bar when bars are off."""

    def update(self, n: int = 1) -> None:  # noqa: D102
        pass

    def close(self) -> None:  # noqa: D102
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False
