"""Claims: what a paper says, how the reproduction measures it, and the rule that turns the two into a status word.

A closing-table row is never typed by hand.  Each paper package declares its claims in code (``papers/<paper>/
claims.py``), before anything is compared:

* the paper's value or statement, and where it is printed;
* a :class:`Criterion` with its tolerance (from the paper's printed digits, :func:`printed_tolerance`, and, for a
  Monte Carlo figure, a number of standard errors);
* whether the comparison was tuned (a choice made while looking at the paper's number), with its reason;
* or, for rows with nothing to compare, the kind: ``"derived"``, ``"not in paper"`` or ``"beyond paper"``.

At run time a notebook measures the quantity and calls :meth:`Claim.judge`, which returns a :class:`Verdict` whose
status is computed by one rule (:func:`status_of`):

* a comparison whose criterion holds is **reproduced**, or **consistent (tuned)** when the claim is tuned;
* a comparison whose criterion fails **differs** (a reason is then required);
* the other kinds keep their word; a ``"beyond paper"`` check that carries a criterion and fails **differs** too.

Every criterion states itself in words (:meth:`Criterion.describe`, shown in the row) and offers probe values just
inside and just outside its tolerance (:meth:`Criterion.probes`), which the tests use on every declared claim.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from decimal import Decimal, InvalidOperation

import numpy as np

from cislunar.utils import validation

__all__ = ["STATUSES", "STATUS_MEANINGS", "KINDS", "Criterion", "Within", "AtMost", "AtLeast", "Between", "Holds",
           "Equals", "Claim", "Verdict", "status_of", "printed_tolerance", "fmt"]

#: Allowed status words, in the order legends list them.
STATUSES = ("reproduced", "consistent (tuned)", "differs", "derived", "not in paper", "beyond paper")
#: What each status word means; shown under every table for the words it uses and in the report's header.
STATUS_MEANINGS = {
    "reproduced": "an independent prediction that agrees with the paper within a tolerance fixed before comparing "
                  "(stated in the row)",
    "consistent (tuned)": "agrees only after a choice made while looking at the paper's number",
    "differs": "does not agree; the reason follows, and where the paper's claim rests on something unstated, the "
               "search for the regime in which it holds",
    "derived": "no paper number to compare with: computed here from what the paper gives (or an input taken "
               "from it)",
    "not in paper": "an input or value the paper does not state (our choice, or a missing table)",
    "beyond paper": "a check or result the paper does not attempt",
}
#: Kinds of claim: a comparison with the paper, or one of the rows with nothing to compare.
KINDS = ("comparison", "derived", "not in paper", "beyond paper")


def fmt(value, digits: int = 6) -> str:
    """Format a number compactly for a table (strings pass through; ``None`` prints as ``-``)."""
    digits = validation.integer(digits, "digits", minimum=1, maximum=17)
    if value is None:
        return "-"
    if isinstance(value, str):
        return value
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    try:
        v = float(value)
    except (TypeError, ValueError):
        return str(value)
    if v == 0:
        return "0"
    if 1e-3 <= abs(v) < 1e6:
        return f"{v:.{digits}g}"
    return f"{v:.{max(digits - 2, 2)}e}"


def printed_tolerance(printed: str) -> float:
    """Half a unit in the last printed digit of a number as the paper prints it: ``"1.2"`` -> 0.05, ``"3e-4"`` ->
    5e-5, ``"120"`` -> 0.5.  The tolerance a printed value itself implies."""
    validation.instance(printed, "printed", str)
    try:
        d = Decimal(printed.strip())
    except InvalidOperation:
        raise ValueError(f"printed must be a number as printed (e.g. '1.2' or '3e-4'); got {printed!r}") from None
    if not d.is_finite():
        raise ValueError(f"printed must be finite; got {printed!r}")
    return float(Decimal(5).scaleb(d.as_tuple().exponent - 1))


def _number(value, name):
    if isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be a number; got {type(value).__name__}")
    v = validation.real(value, name)
    return float(v)


# ---------------------------------------------------------------------------------------------------------------
# Criteria
# ---------------------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Criterion:
    """How a measured value is judged against the paper.  Subclasses define :meth:`holds`, :meth:`describe` and
    :meth:`probes`."""

    def holds(self, measured, standard_error: float = 0.0) -> bool:  # pragma: no cover - abstract
        raise NotImplementedError

    def describe(self) -> str:  # pragma: no cover - abstract
        raise NotImplementedError

    def probes(self, standard_error: float = 0.0) -> tuple:
        """``(just_inside, just_outside)`` measured values: the first satisfies the criterion, the second does
        not, each within one part in a thousand of the tolerance's edge."""
        raise NotImplementedError  # pragma: no cover - abstract


@dataclass(frozen=True)
class Within(Criterion):
    """``|measured - target| <= tol`` (absolute) or ``<= tol * |target|`` (``relative=True``), widened by
    ``n_sigma`` Monte Carlo standard errors when the verdict is given one.

    Parameters
    ----------
    target : float
        The paper's value, in the units of the measured value.
    tol : float
        Tolerance fixed before comparing (>= 0): absolute, or a fraction of ``|target|``.
    relative : bool
    n_sigma : float
        Standard errors of the measured value added to the tolerance (a Monte Carlo estimate), >= 0.
    """

    target: float
    tol: float
    relative: bool = False
    n_sigma: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "target", _number(self.target, "target"))
        object.__setattr__(self, "tol", validation.positive(self.tol, "tol", allow_zero=True))
        object.__setattr__(self, "n_sigma", validation.positive(self.n_sigma, "n_sigma", allow_zero=True))
        if self.relative and self.target == 0:
            raise ValueError("a relative tolerance needs a non-zero target")

    def half_width(self, standard_error: float = 0.0) -> float:
        base = self.tol * abs(self.target) if self.relative else self.tol
        return base + self.n_sigma * float(standard_error)

    def holds(self, measured, standard_error: float = 0.0) -> bool:
        m = _number(measured, "measured")
        return abs(m - self.target) <= self.half_width(standard_error) * (1 + 1e-12)

    def describe(self) -> str:
        tol = f"{self.tol * 100:g} %" if self.relative else fmt(self.tol, 3)
        se = f" + {self.n_sigma:g} standard errors" if self.n_sigma else ""
        return f"within {tol}{se} of {fmt(self.target)}"

    def probes(self, standard_error: float = 0.0):
        h = self.half_width(standard_error)
        if h > 0:  # a thousandth of the half width, never below the float spacing at the edge
            eps = max(h * 1e-3, 8 * float(np.spacing(abs(self.target) + h)))
            return self.target + h - eps, self.target + h + eps
        return self.target, self.target + max(abs(self.target) * 1e-6, 1e-300)


@dataclass(frozen=True)
class AtMost(Criterion):
    """``measured <= limit`` (plus ``n_sigma`` standard errors)."""

    limit: float
    n_sigma: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "limit", _number(self.limit, "limit"))
        object.__setattr__(self, "n_sigma", validation.positive(self.n_sigma, "n_sigma", allow_zero=True))

    def holds(self, measured, standard_error: float = 0.0) -> bool:
        return _number(measured, "measured") <= self.limit + self.n_sigma * float(standard_error)

    def describe(self) -> str:
        se = f" + {self.n_sigma:g} standard errors" if self.n_sigma else ""
        return f"at most {fmt(self.limit)}{se}"

    def probes(self, standard_error: float = 0.0):
        edge = self.limit + self.n_sigma * float(standard_error)
        eps = max(abs(edge) * 1e-3, 1e-12)
        return edge - eps, edge + eps


@dataclass(frozen=True)
class AtLeast(Criterion):
    """``measured >= limit`` (minus ``n_sigma`` standard errors)."""

    limit: float
    n_sigma: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "limit", _number(self.limit, "limit"))
        object.__setattr__(self, "n_sigma", validation.positive(self.n_sigma, "n_sigma", allow_zero=True))

    def holds(self, measured, standard_error: float = 0.0) -> bool:
        return _number(measured, "measured") >= self.limit - self.n_sigma * float(standard_error)

    def describe(self) -> str:
        se = f" - {self.n_sigma:g} standard errors" if self.n_sigma else ""
        return f"at least {fmt(self.limit)}{se}"

    def probes(self, standard_error: float = 0.0):
        edge = self.limit - self.n_sigma * float(standard_error)
        eps = max(abs(edge) * 1e-3, 1e-12)
        return edge + eps, edge - eps


@dataclass(frozen=True)
class Between(Criterion):
    """``lo <= measured <= hi``."""

    lo: float
    hi: float

    def __post_init__(self):
        object.__setattr__(self, "lo", _number(self.lo, "lo"))
        object.__setattr__(self, "hi", _number(self.hi, "hi"))
        if not self.lo <= self.hi:
            raise ValueError(f"lo must not exceed hi; got lo = {self.lo}, hi = {self.hi}")

    def holds(self, measured, standard_error: float = 0.0) -> bool:
        return self.lo <= _number(measured, "measured") <= self.hi

    def describe(self) -> str:
        return f"between {fmt(self.lo)} and {fmt(self.hi)}"

    def probes(self, standard_error: float = 0.0):
        eps = max((self.hi - self.lo) * 1e-3, abs(self.hi) * 1e-12, 1e-12)
        return self.hi - eps, self.hi + eps


@dataclass(frozen=True)
class Holds(Criterion):
    """A yes/no statement measured as a boolean: holds when the measured value is ``expected``.

    Parameters
    ----------
    test : str
        The test in words, e.g. ``"RMS at the window end <= RMS at the second measurement"``.
    expected : bool
    """

    test: str
    expected: bool = True

    def __post_init__(self):
        validation.instance(self.test, "test", str)
        if not self.test.strip():
            raise ValueError("test must say in words what is checked")
        if not isinstance(self.expected, (bool, np.bool_)):
            raise TypeError(f"expected must be a bool; got {type(self.expected).__name__}")

    def holds(self, measured, standard_error: float = 0.0) -> bool:
        if not isinstance(measured, (bool, np.bool_)):
            raise TypeError(f"measured must be a bool for a yes/no claim; got {type(measured).__name__}")
        return bool(measured) == bool(self.expected)

    def describe(self) -> str:
        return ("" if self.expected else "not: ") + self.test

    def probes(self, standard_error: float = 0.0):
        return bool(self.expected), not bool(self.expected)


@dataclass(frozen=True)
class Equals(Criterion):
    """The measured value equals ``value`` exactly (an integer count, a label, a chosen reading)."""

    value: object

    def holds(self, measured, standard_error: float = 0.0) -> bool:
        if isinstance(self.value, str) or isinstance(measured, str):
            return str(measured) == str(self.value)
        return bool(np.all(np.asarray(measured) == np.asarray(self.value)))

    def describe(self) -> str:
        return f"equals {fmt(self.value)}"

    def probes(self, standard_error: float = 0.0):
        if isinstance(self.value, str):
            return self.value, self.value + " (other)"
        return self.value, (self.value + 1 if isinstance(self.value, (int, np.integer)) else
                            float(self.value) * (1 + 1e-3) + 1e-12)


# ---------------------------------------------------------------------------------------------------------------
# Claims and verdicts
# ---------------------------------------------------------------------------------------------------------------


def status_of(kind: str, criterion_holds: bool | None, tuned: bool) -> str:
    """The one rule from a claim's kind, its criterion's outcome (None: no criterion) and whether it was tuned."""
    validation.choice(kind, "kind", KINDS)
    if kind == "comparison":
        if criterion_holds is None:
            raise ValueError("a comparison needs a criterion")
        if not criterion_holds:
            return "differs"
        return "consistent (tuned)" if tuned else "reproduced"
    if criterion_holds is False:
        return "differs"
    return kind


@dataclass(frozen=True)
class Verdict:
    """One row of a closing table: the judged claim.  Built only by :meth:`Claim.judge`."""

    quantity: str
    paper: str
    reproduced: str
    status: str
    note: str
    claim: "Claim" = field(repr=False, compare=False, default=None)


@dataclass(frozen=True)
class Claim:
    """A row of a closing table declared before comparing.

    Parameters
    ----------
    quantity : str
        What is compared, as the row names it.
    paper : str or float or None
        The paper's value or statement as printed (``None``: the paper gives nothing).
    criterion : Criterion or None
        How the measured value is judged; required for a comparison.
    kind : {"comparison", "derived", "not in paper", "beyond paper"}
    tuned : str
        Empty for an independent prediction; otherwise the choice made while looking at the paper's number and why.
    source : str
        Where the paper prints it (section, table, figure, equation).
    reason : str
        Why the reproduction may differ (shown when the verdict is "differs"; required then, here or at judging).
    """

    quantity: str
    paper: object = None
    criterion: Criterion | None = None
    kind: str = "comparison"
    tuned: str = ""
    source: str = ""
    reason: str = ""

    def __post_init__(self):
        for name in ("quantity", "tuned", "source", "reason"):
            validation.instance(getattr(self, name), name, str)
        if not self.quantity.strip():
            raise ValueError("quantity must be a non-empty str")
        validation.choice(self.kind, "kind", KINDS)
        if self.criterion is not None:
            validation.instance(self.criterion, "criterion", Criterion)
        if self.kind == "comparison" and self.criterion is None:
            raise ValueError(f"a comparison claim needs a criterion (quantity {self.quantity!r})")
        if self.kind != "comparison" and self.tuned:
            raise ValueError("only a comparison can be tuned")
        p = self.paper
        if isinstance(p, (bool, np.bool_)) or (isinstance(p, (int, float, np.number)) and not math.isfinite(p)):
            raise ValueError(f"paper must be a finite number, a str or None; got {p!r}")

    def judge(self, measured, *, shown: str | None = None, note: str = "", standard_error: float = 0.0,
              reason: str = "") -> Verdict:
        """Judge a measured value and return the table row.

        Parameters
        ----------
        measured : float or bool or str
            The reproduction's value, in the criterion's units.
        shown : str, optional
            How the value is printed (default: :func:`fmt` of ``measured``).
        note : str
            Context printed in the row's note.
        standard_error : float
            Monte Carlo standard error of ``measured`` (widens criteria with ``n_sigma``).
        reason : str
            Why it differs, when it does (overrides the declared ``reason``).
        """
        validation.instance(note, "note", str)
        validation.instance(reason, "reason", str)
        standard_error = validation.positive(standard_error, "standard_error", allow_zero=True)
        if isinstance(measured, (int, float, np.floating, np.integer)) and not isinstance(measured, bool):
            if not math.isfinite(float(measured)):
                raise ValueError(f"measured must be finite for {self.quantity!r}; got {measured!r}")
        ok = None if self.criterion is None else self.criterion.holds(measured, standard_error)
        status = status_of(self.kind, ok, bool(self.tuned))
        parts = []
        if self.criterion is not None:
            se = f" (standard error {fmt(standard_error, 2)})" if standard_error else ""
            parts.append(f"criterion: {self.criterion.describe()}{se}")
        if self.tuned and status != "differs":
            parts.append(f"tuned: {self.tuned}")
        why = reason or self.reason
        if status == "differs":
            if not why:
                raise ValueError(f"{self.quantity!r} differs from the paper and no reason is given")
            parts.append(f"differs because {why}" if not why[0].isupper() else why)
        if status == "not in paper" and not (why or note):
            raise ValueError(f"a 'not in paper' row needs a reason or a note (quantity {self.quantity!r})")
        if status == "not in paper" and why:
            parts.append(why)
        if note:
            parts.append(note)
        if self.source:
            parts.append(f"paper: {self.source}")
        text = shown if shown is not None else fmt(measured)
        return Verdict(self.quantity, fmt(self.paper), text, status, "; ".join(parts), self)

    def with_paper(self, paper) -> "Claim":
        """The same claim with the paper's value filled in (for values read from a transcribed table)."""
        return replace(self, paper=paper)
