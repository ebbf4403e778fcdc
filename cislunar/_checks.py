"""Argument checks shared by the package.

Every public function validates its inputs with these helpers so that bad input fails early with a
``ValueError`` that names the argument and states what was expected.
"""

from __future__ import annotations

import numpy as np


def as_array(value, name: str, *, shape: tuple | None = None, ndim: tuple[int, ...] | None = None,
             last: int | None = None, finite: bool = True, dtype=float) -> np.ndarray:
    """Convert ``value`` to a float array and check it.

    Parameters
    ----------
    value : array_like
        Input to convert.
    name : str
        Argument name used in error messages.
    shape : tuple, optional
        Exact expected shape; ``None`` entries are wildcards.
    ndim : tuple of int, optional
        Allowed numbers of dimensions.
    last : int, optional
        Required length of the last axis.
    finite : bool
        Reject NaN and infinite entries.
    dtype : numpy dtype
        Target dtype.

    Returns
    -------
    numpy.ndarray
    """
    try:
        arr = np.asarray(value, dtype=dtype)
    except (TypeError, ValueError) as exc:  # pragma: no cover - message clarity only
        raise ValueError(f"{name} must be numeric array-like; got {type(value).__name__}") from exc
    if shape is not None:
        ok = arr.ndim == len(shape) and all(s is None or s == a for s, a in zip(shape, arr.shape))
        if not ok:
            want = "(" + ", ".join("n" if s is None else str(s) for s in shape) + ")"
            raise ValueError(f"{name} must have shape {want}; got {arr.shape}")
    if ndim is not None and arr.ndim not in ndim:
        raise ValueError(f"{name} must have {' or '.join(map(str, ndim))} dimensions; got shape {arr.shape}")
    if last is not None and (arr.ndim == 0 or arr.shape[-1] != last):
        raise ValueError(f"{name} must have last axis of length {last}; got shape {arr.shape}")
    if finite and not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return arr


def as_state(value, name: str = "state", *, batch: bool = True) -> np.ndarray:
    """Check a CR3BP state (or a stack of states) of length 6 on the last axis."""
    return as_array(value, name, ndim=(1, 2) if batch else (1,), last=6)


def positive(value, name: str, *, allow_zero: bool = False) -> float:
    """Check a positive finite scalar and return it as float."""
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a real number; got {value!r}") from exc
    if not np.isfinite(v) or v < 0 or (v == 0 and not allow_zero):
        raise ValueError(f"{name} must be {'non-negative' if allow_zero else 'positive'} and finite; got {value!r}")
    return v


def in_range(value, name: str, lo: float, hi: float, *, closed: bool = True) -> float:
    """Check a finite scalar inside ``[lo, hi]`` (or ``(lo, hi)``)."""
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a real number; got {value!r}") from exc
    ok = np.isfinite(v) and ((lo <= v <= hi) if closed else (lo < v < hi))
    if not ok:
        br = "[]" if closed else "()"
        raise ValueError(f"{name} must lie in {br[0]}{lo}, {hi}{br[1]}; got {value!r}")
    return v


def time_grid(value, name: str = "t", *, increasing: bool = False) -> np.ndarray:
    """Check a strictly monotonic 1-D time grid with at least two entries (strictly increasing if asked)."""
    t = as_array(value, name, ndim=(1,))
    if t.size < 2:
        raise ValueError(f"{name} must hold at least two times (start and end); got {t.size}")
    d = np.diff(t)
    if increasing and not np.all(d > 0):
        raise ValueError(f"{name} must be strictly increasing")
    if not (np.all(d > 0) or np.all(d < 0)):
        raise ValueError(f"{name} must be strictly increasing or strictly decreasing")
    return t
