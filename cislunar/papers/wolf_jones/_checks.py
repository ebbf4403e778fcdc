"""Argument checks shared by the Wolf & Jones studies, exercises and figures (private).

Thin compositions of :mod:`cislunar.utils.validation` for the argument shapes that recur at the public boundary of
this paper's package: sequences (of integers, of objects), vectors of equal length, an optional executor and an
SCvx plan (an object carrying node states ``x`` (N, 6) and node controls ``u`` (N, 3)).  Every refusal names the
caller's argument.
"""

from __future__ import annotations

import numpy as np

from cislunar.utils import validation


def sequence(value, name: str, *, allow_empty: bool = False) -> list:
    """A list from an iterable that is not a str, bytes or dict (non-empty unless ``allow_empty``)."""
    if value is None or isinstance(value, (str, bytes, dict)):
        raise validation.ArgumentTypeError(f"{name} must be a sequence; got {type(value).__name__} {value!r:.60}")
    try:
        items = list(value)
    except TypeError:
        raise validation.ArgumentTypeError(f"{name} must be a sequence; got {type(value).__name__}") from None
    if not items and not allow_empty:
        raise ValueError(f"{name} must hold at least one item")
    return items


def integers(value, name: str, *, minimum: int | None = None) -> tuple:
    """A non-empty sequence of integers (each at least ``minimum``), as a tuple of int."""
    return tuple(validation.integer(v, f"{name}[{i}]", minimum=minimum)
                 for i, v in enumerate(sequence(value, name)))


def vector(value, name: str, *, n: int | None = None, min_size: int = 1) -> np.ndarray:
    """A finite 1-D float array of at least ``min_size`` entries (exactly ``n`` if given)."""
    v = validation.as_array(value, name, ndim=(1,), min_size=min_size)
    if n is not None and v.size != n:
        raise ValueError(f"{name} must hold {n} values; got {v.size}")
    return v


def executor(value, name: str = "executor"):
    """``None`` or an object with a ``submit(fn, *args)`` method (a concurrent.futures executor, a Dask client)."""
    if value is not None and not callable(getattr(value, "submit", None)):
        raise validation.ArgumentTypeError(f"{name} must be None or have a submit(fn, *args) method (an executor); "
                                           f"got {type(value).__name__}")
    return value


def plan(value, name: str, *, controls: bool = True, n: int | None = None):
    """An SCvx plan: an object whose ``x`` is (N, 6) node states and (if ``controls``) ``u`` (N, 3) node controls,
    finite; ``N`` equal to ``n`` if given.  Returns the object."""
    if value is None or isinstance(value, (str, bytes, int, float, np.ndarray)) or not hasattr(value, "x") or (
            controls and not hasattr(value, "u")):
        raise validation.ArgumentTypeError(
            f"{name} must be an SCvx plan (node states x{' and controls u' if controls else ''}, e.g. an "
            f"SCvxResult); got {type(value).__name__}")
    x = validation.as_array(value.x, f"{name}.x", ndim=(2,), last=6)
    if n is not None and x.shape[0] != n:
        raise ValueError(f"{name}.x must hold {n} node states; got {x.shape[0]}")
    if controls:
        validation.as_array(value.u, f"{name}.u", shape=(x.shape[0], 3))
    return value


def directions(value, name: str) -> tuple:
    """Homotopy chains to run: a non-empty subset of ("up", "down") without repeats, returned in that order."""
    given = sequence(value, name)
    if any(d not in ("up", "down") for d in given) or len(set(given)) != len(given):
        raise ValueError(f"{name} must be a non-empty subset of ('up', 'down') without repeats; got {given!r}")
    return tuple(d for d in ("up", "down") if d in given)
