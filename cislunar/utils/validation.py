"""Argument checks shared by the package.

Every public function validates its inputs with these helpers so that bad input fails early with an error that
names the caller's argument and states what was expected:

* a value of the wrong *kind* (a string where a number is expected, ``None`` where an array is expected, an object
  that is not a :class:`~cislunar.cr3bp.dynamics.CR3BP`, a non-callable where a callable is expected) raises
  :class:`ArgumentTypeError`, which is both a ``TypeError`` and a ``ValueError`` (so callers and tests written
  against either keep working);
* a value of the right kind but the wrong shape, range or structure (NaN, negative, not symmetric positive
  definite, not upper triangular, ...) raises ``ValueError``.

Every message starts with the argument name as the caller spelled it.
"""

from __future__ import annotations

import numbers

import numpy as np

__all__ = ["ArgumentTypeError", "dict_of", "as_array", "as_state", "positive", "in_range", "time_grid", "real", "integer",
           "boolean", "choice", "callable_", "rng", "spd", "psd", "upper_triangular", "square",
           "instance", "seed_entropy", "work_size"]


class ArgumentTypeError(TypeError, ValueError):
    """A caller's argument has the wrong type (also a ``ValueError`` for backward compatibility)."""


def _type_name(value) -> str:
    return type(value).__name__


def _reject_non_numeric(value, name: str, what: str):
    """Strings, bytes, None, dicts and sets are never numbers (``float("3")`` would silently accept a string)."""
    if value is None or isinstance(value, (str, bytes, dict, set, frozenset)):
        raise ArgumentTypeError(f"{name} must be {what}; got {_type_name(value)} {value!r:.60}")


def as_array(value, name: str, *, shape: tuple | None = None, ndim: tuple[int, ...] | None = None,
             last: int | None = None, finite: bool = True, dtype=float, min_size: int | None = None) -> np.ndarray:
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
    min_size : int, optional
        Smallest number of elements (e.g. 1 to refuse empty arrays).

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    ArgumentTypeError
        ``value`` is not numeric (None, a string, an object, a ragged nested sequence, complex numbers, strings
        inside any container, such as a list of numeric strings ``["1.0", "0"]``).
    ValueError
        Wrong shape or non-finite entries.
    """
    _reject_non_numeric(value, name, "numeric array-like")
    if isinstance(value, np.ndarray) and value.dtype.kind in "OUSV":
        raise ArgumentTypeError(f"{name} must be numeric array-like; got an array of dtype {value.dtype}")
    try:
        raw = value if isinstance(value, np.ndarray) else np.asarray(value)
    except (TypeError, ValueError) as exc:  # ragged nested sequences
        raise ArgumentTypeError(f"{name} must be numeric array-like (a regular, non-ragged array); got "
                                f"{_type_name(value)}") from exc
    if raw.dtype.kind in "USV" or (raw.dtype.kind == "O" and any(isinstance(v, (str, bytes)) for v in raw.flat)):
        # a list of numeric strings (["1.0", "0"]) converts silently: refused like an array of strings
        raise ArgumentTypeError(f"{name} must be numeric array-like; got text inside a {_type_name(value)} "
                                f"{value!r:.60}")
    kind = np.dtype(dtype).kind
    if raw.dtype.kind == "c" and kind != "c":
        raise ArgumentTypeError(f"{name} must be real; got complex values")
    if raw.dtype.kind == "b" and kind in "fc":
        raise ArgumentTypeError(f"{name} must be numeric; got booleans {value!r:.60}")
    try:
        arr = np.asarray(raw, dtype=dtype)
    except (TypeError, ValueError) as exc:
        raise ArgumentTypeError(f"{name} must be numeric array-like; got {_type_name(value)}") from exc
    if shape is not None:
        ok = arr.ndim == len(shape) and all(s is None or s == a for s, a in zip(shape, arr.shape))
        if not ok:
            want = "(" + ", ".join("n" if s is None else str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"
            raise ValueError(f"{name} must have shape {want}; got {arr.shape}")
    if ndim is not None and arr.ndim not in ndim:
        raise ValueError(f"{name} must have {' or '.join(map(str, ndim))} dimensions; got shape {arr.shape}")
    if last is not None and (arr.ndim == 0 or arr.shape[-1] != last):
        raise ValueError(f"{name} must have last axis of length {last}; got shape {arr.shape}")
    if min_size is not None and arr.size < min_size:
        raise ValueError(f"{name} must hold at least {min_size} value(s); got shape {arr.shape}")
    if finite and not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return arr


def as_state(value, name: str = "state", *, batch: bool = True) -> np.ndarray:
    """Check a CR3BP state (or a stack of states) of length 6 on the last axis."""
    return as_array(value, name, ndim=(1, 2) if batch else (1,), last=6)


def real(value, name: str, *, finite: bool = True) -> float:
    """A real scalar (int, float or 0-d/size-1 numeric array; never a string, bool or None) as float."""
    _reject_non_numeric(value, name, "a real number")
    if isinstance(value, (bool, np.bool_)):
        raise ArgumentTypeError(f"{name} must be a real number; got bool {value!r}")
    if isinstance(value, (complex, np.complexfloating)):
        raise ArgumentTypeError(f"{name} must be a real number; got complex {value!r}")
    if isinstance(value, np.ndarray):
        if value.size != 1 or value.dtype.kind not in "iuf":
            raise ArgumentTypeError(f"{name} must be a real number; got an array of shape {value.shape} "
                                    f"and dtype {value.dtype}")
        value = value.reshape(())[()]
    elif not isinstance(value, numbers.Real):
        raise ArgumentTypeError(f"{name} must be a real number; got {_type_name(value)}")
    v = float(value)
    if finite and not np.isfinite(v):
        raise ValueError(f"{name} must be finite; got {value!r}")
    return v


def positive(value, name: str, *, allow_zero: bool = False) -> float:
    """Check a positive finite scalar and return it as float."""
    v = real(value, name, finite=False)
    if not np.isfinite(v) or v < 0 or (v == 0 and not allow_zero):
        raise ValueError(f"{name} must be {'non-negative' if allow_zero else 'positive'} and finite; got {value!r}")
    return v


def in_range(value, name: str, lo: float, hi: float, *, closed: bool = True) -> float:
    """Check a finite scalar inside ``[lo, hi]`` (or ``(lo, hi)``)."""
    v = real(value, name, finite=False)
    ok = np.isfinite(v) and ((lo <= v <= hi) if closed else (lo < v < hi))
    if not ok:
        br = "[]" if closed else "()"
        raise ValueError(f"{name} must lie in {br[0]}{lo}, {hi}{br[1]}; got {value!r}")
    return v


def integer(value, name: str, *, minimum: int | None = None, maximum: int | None = None) -> int:
    """An integer (Python or numpy integer, or an integral float such as 3.0) in range.

    A non-integral float (2.9), a bool, a string or None raises :class:`ArgumentTypeError`: silently truncating
    would change the caller's request.
    """
    if isinstance(value, (bool, np.bool_)):
        raise ArgumentTypeError(f"{name} must be an integer; got bool {value!r}")
    if isinstance(value, (numbers.Integral, np.integer)):
        v = int(value)
    elif isinstance(value, (float, np.floating)) and np.isfinite(value) and float(value).is_integer():
        v = int(value)
    else:
        raise ArgumentTypeError(f"{name} must be an integer; got {_type_name(value)} {value!r:.60}")
    if minimum is not None and v < minimum:
        raise ValueError(f"{name} must be >= {minimum}; got {v}")
    if maximum is not None and v > maximum:
        raise ValueError(f"{name} must be <= {maximum}; got {v}")
    return v


def boolean(value, name: str) -> bool:
    """A bool (Python or numpy)."""
    if not isinstance(value, (bool, np.bool_)):
        raise ArgumentTypeError(f"{name} must be True or False; got {_type_name(value)} {value!r:.60}")
    return bool(value)


def choice(value, name: str, options) -> str:
    """One of a fixed set of options (compared by equality; the options are listed in the message)."""
    options = tuple(options)
    try:
        ok = isinstance(value, (str, type(None), int)) and value in options
    except TypeError:  # pragma: no cover - unhashable
        ok = False
    if not ok:
        if not isinstance(value, (str, type(None), int)):
            raise ArgumentTypeError(f"{name} must be one of {options}; got {_type_name(value)} {value!r:.60}")
        raise ValueError(f"{name} must be one of {options}; got {value!r}")
    return value


def callable_(value, name: str):
    """A callable."""
    if not callable(value):
        raise ArgumentTypeError(f"{name} must be callable; got {_type_name(value)} {value!r:.60}")
    return value


def instance(value, name: str, cls, what: str | None = None):
    """An instance of ``cls`` (a class or a tuple of classes)."""
    if not isinstance(value, cls):
        if what is None:
            names = cls if isinstance(cls, tuple) else (cls,)
            what = " or ".join(f"a {c.__module__}.{c.__qualname__}" for c in names)
        raise ArgumentTypeError(f"{name} must be {what}; got {_type_name(value)}")
    return value


def rng(value, name: str = "rng") -> np.random.Generator:
    """A ``numpy.random.Generator`` (pass ``numpy.random.default_rng(seed)``; there is no global state)."""
    return instance(value, name, np.random.Generator, "a numpy.random.Generator (numpy.random.default_rng(seed))")


def seed_entropy(value, name: str = "seed"):
    """A reproducible root seed: a non-negative int, a sequence of them, or a ``numpy.random.SeedSequence``.

    ``None`` is refused: it would draw fresh OS entropy and make every run different.
    """
    if isinstance(value, np.random.SeedSequence):
        return value
    if value is None:
        raise ArgumentTypeError(f"{name} must be a non-negative integer, a sequence of them or a SeedSequence; got "
                                "None (which would give a different result on every call)")
    vals = value if isinstance(value, (list, tuple, np.ndarray)) else [value]
    if isinstance(value, np.ndarray) and value.ndim > 1:
        raise ValueError(f"{name} must be an integer or a flat sequence of integers; got shape {value.shape}")
    if len(vals) == 0:
        raise ValueError(f"{name} must not be empty")
    for v in vals:
        integer(v, name, minimum=0)
    return value


def int_seed_list(value, name: str = "seed", *, why: str = "an index is appended per set") -> list:
    """A root seed given as a non-negative int or a flat sequence of them, as a list (``SeedSequence`` refused).

    For callers that derive sub-seeds by appending an index (``base + [k]``); ``why`` says so in the refusal.
    """
    seed_entropy(value, name)
    if isinstance(value, np.random.SeedSequence):
        raise ArgumentTypeError(f"{name} must be an int or a list of ints here ({why}); got a SeedSequence")
    return [int(v) for v in np.atleast_1d(value)]


def sequence_of(value, name: str, cls, what: str) -> list:
    """A non-empty sequence whose items are all ``cls`` instances, as a list (``what`` names the class, no article).

    A single instance, a str/bytes/dict or a non-iterable is refused with an ``ArgumentTypeError`` naming ``name``;
    a wrong item is named by its index (``name[i]``).
    """
    if isinstance(value, (cls, str, bytes, dict)):
        raise ArgumentTypeError(f"{name} must be a sequence of {what}; got a single {_type_name(value)}")
    try:
        items = list(value)
    except TypeError:
        raise ArgumentTypeError(f"{name} must be a sequence of {what}; got {_type_name(value)}") from None
    if not items:
        raise ValueError(f"{name} must hold at least one {what}")
    for i, item in enumerate(items):
        instance(item, f"{name}[{i}]", cls, f"a {what}")
    return items


def one_or_many(value, name: str, single, what: str) -> tuple:
    """A non-empty tuple from one item of type ``single`` or an iterable of them.

    ``what`` names the expected items in the messages (e.g. ``"str"``, ``"SurfaceStation"``).  The items themselves
    are not checked beyond that (callers check each with :func:`choice`, :func:`instance`, ...).
    """
    if isinstance(value, single):
        return (value,)
    try:
        items = tuple(value)
    except TypeError:
        raise ArgumentTypeError(f"{name} must be a {what} or a sequence of {what}; got {_type_name(value)}") from None
    if not items:
        raise ValueError(f"{name} must hold at least one {what}")
    return items


def square(value, name: str, *, n: int | None = None, batch: bool = False) -> np.ndarray:
    """A finite square matrix (or a stack ``(..., n, n)`` when ``batch``)."""
    A = as_array(value, name, ndim=None if batch else (2,))
    if A.ndim < 2 or A.shape[-1] != A.shape[-2]:
        raise ValueError(f"{name} must be a square matrix{' (or a stack of them)' if batch else ''}; got shape "
                         f"{A.shape}")
    if n is not None and A.shape[-1] != n:
        raise ValueError(f"{name} must be {n}x{n}; got shape {A.shape}")
    return A


def _symmetric(A, name, rtol):
    scale = max(float(np.max(np.abs(A))) if A.size else 0.0, 1e-300)
    asym = float(np.max(np.abs(A - np.swapaxes(A, -1, -2)))) if A.size else 0.0
    if asym > rtol * scale:
        raise ValueError(f"{name} must be symmetric; largest asymmetry {asym:.3e} (relative {asym / scale:.1e})")


#: Smallest accepted ratio of the extreme eigenvalues of a covariance's correlation matrix (see :func:`spd`).
SPD_RCOND = 1e-13


def spd(value, name: str, *, n: int | None = None, batch: bool = False, rtol: float = 1e-8,
        rcond: float = SPD_RCOND) -> np.ndarray:
    """A symmetric positive-definite matrix (a covariance), numerically non-singular.

    Checked on the correlation matrix :math:`C = D^{-1/2} A D^{-1/2}` (:math:`D` the diagonal of ``A``, so the
    test does not depend on units or scaling): the diagonal must be positive, a Cholesky factorisation of ``A``
    must succeed and the smallest eigenvalue of :math:`C` must exceed ``rcond`` (default 1e-13) times its
    largest.  A rank-deficient positive semi-definite matrix rotated out of diagonal form passes a plain
    Cholesky with round-off pivots (its eigenvalues come out at about 1e-16 of the largest) and is refused here;
    the package's covariances sit above 1e-8 (measured on the test suites).  ``rtol`` bounds the relative
    asymmetry.
    """
    A = square(value, name, n=n, batch=batch)
    _symmetric(A, name, rtol)
    S = 0.5 * (A + np.swapaxes(A, -1, -2))
    try:
        np.linalg.cholesky(S)
    except np.linalg.LinAlgError:
        lam = np.linalg.eigvalsh(S)
        raise ValueError(f"{name} must be symmetric positive definite; smallest eigenvalue {np.min(lam):.3e}") from None
    if S.size:
        d = np.sqrt(np.diagonal(S, axis1=-2, axis2=-1))  # > 0 after a successful Cholesky
        lam = np.linalg.eigvalsh(S / (d[..., :, None] * d[..., None, :]))
        ratio = lam[..., 0] / lam[..., -1]
        if np.any(~(ratio > rcond)):
            raise ValueError(f"{name} is numerically singular: smallest/largest eigenvalue of its correlation matrix "
                             f"{float(np.min(ratio)):.1e}, at most rcond = {rcond:g}")
    return A


def psd(value, name: str, *, n: int | None = None, batch: bool = False, rtol: float = 1e-8) -> np.ndarray:
    """A symmetric positive semi-definite matrix (eigenvalues >= -rtol * largest)."""
    A = square(value, name, n=n, batch=batch)
    _symmetric(A, name, rtol)
    lam = np.linalg.eigvalsh(0.5 * (A + np.swapaxes(A, -1, -2)))
    top = max(float(np.max(np.abs(lam))) if lam.size else 0.0, 1e-300)
    if lam.size and np.min(lam) < -rtol * top:
        raise ValueError(f"{name} must be positive semi-definite; smallest eigenvalue {np.min(lam):.3e}")
    return A


def upper_triangular(value, name: str, *, n: int | None = None, nonsingular: bool = True,
                     rtol: float = 0.0) -> np.ndarray:
    """An upper-triangular square matrix (a square-root information factor), non-singular unless told otherwise."""
    R = square(value, name, n=n)
    low = np.tril(R, -1)
    scale = max(float(np.max(np.abs(R))) if R.size else 0.0, 1e-300)
    if np.any(np.abs(low) > rtol * scale):
        raise ValueError(f"{name} must be upper triangular; largest entry below the diagonal {np.max(np.abs(low)):.3e}")
    if nonsingular and np.any(np.diag(R) == 0):
        raise ValueError(f"{name} is singular (zero on its diagonal): the information matrix is not invertible")
    return R


def work_size(count, name: str, limit: float, what: str) -> int:
    """Refuse up front a request whose size would hang or exhaust memory.

    ``count`` is the number of ``what`` (steps, samples, grid points) that argument ``name`` implies; above
    ``limit`` a ``ValueError`` names the argument, the count and the limit.  Returns ``count`` as an int.
    """
    c = float(count)
    if not np.isfinite(c) or c > limit:
        raise ValueError(f"{name} gives {c:.3g} {what}, more than the limit of {limit:.3g} (a size this large would "
                         "hang or exhaust memory)")
    return int(c)


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


def dict_of(value, name: str, cls, what: str) -> dict:
    """A non-empty dict whose values are all ``cls`` instances (``what`` names the class in messages)."""
    instance(value, name, dict, f"a dict of {what}")
    if not value:
        raise ValueError(f"{name} must hold at least one {what}")
    for key, v in value.items():
        instance(v, f"{name}[{key!r}]", cls, f"a {what}")
    return value
