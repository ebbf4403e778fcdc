"""The status rule: criteria just inside and just outside their tolerance, the rule's table, and every claim the
paper packages declare probed at its own edges."""

from __future__ import annotations

import importlib
import pickle
import pkgutil

import numpy as np
import pytest

import cislunar.papers
from cislunar.publish import claims as C
from cislunar.publish.report import ComparisonTable


@pytest.mark.parametrize("criterion", [
    C.Within(1.2, 0.05), C.Within(1.2, 0.05, relative=True), C.Within(-3.0, 0.0), C.Within(1e-11, 5e-12),
    C.Within(1e-20, 0.0), C.Within(6.5e5, 1e-9), C.Within(10.0, 0.1, n_sigma=2),
    C.AtMost(0.1), C.AtMost(-2.0, n_sigma=1), C.AtLeast(0.9), C.AtLeast(0.0), C.Between(0.2, 0.4),
    C.Holds("the bound is met"), C.Holds("diverges", expected=False), C.Equals(3), C.Equals("reading B"),
])
@pytest.mark.parametrize("se", [0.0, 0.01])
def test_every_criterion_accepts_just_inside_and_refuses_just_outside(criterion, se):
    inside, outside = criterion.probes(se)
    assert criterion.holds(inside, se)
    assert not criterion.holds(outside, se)


def test_within_is_absolute_or_relative_and_widens_with_the_standard_error():
    assert C.Within(1.2, 0.05).holds(1.25) and not C.Within(1.2, 0.05).holds(1.2501)
    assert C.Within(100.0, 0.1, relative=True).holds(90.0) and not C.Within(100.0, 0.1, relative=True).holds(89.9)
    w = C.Within(0.5, 0.01, n_sigma=2)
    assert not w.holds(0.53) and w.holds(0.53, standard_error=0.01)
    # a factor of two in the half width would be noticed
    assert w.half_width(0.01) == pytest.approx(0.03)


def test_printed_tolerance_is_half_the_last_digit():
    assert C.printed_tolerance("1.2") == pytest.approx(0.05)
    assert C.printed_tolerance("3e-4") == pytest.approx(5e-5)
    assert C.printed_tolerance("120") == pytest.approx(0.5)
    assert C.printed_tolerance("0.130") == pytest.approx(5e-4)
    with pytest.raises(ValueError, match="printed"):
        C.printed_tolerance("about 1")


@pytest.mark.parametrize("kind, holds, tuned, expected", [
    ("comparison", True, False, "reproduced"),
    ("comparison", True, True, "consistent (tuned)"),
    ("comparison", False, False, "differs"),
    ("comparison", False, True, "differs"),
    ("derived", None, False, "derived"),
    ("not in paper", None, False, "not in paper"),
    ("beyond paper", None, False, "beyond paper"),
    ("beyond paper", True, False, "beyond paper"),
    ("beyond paper", False, False, "differs"),
])
def test_the_status_rule(kind, holds, tuned, expected):
    assert C.status_of(kind, holds, tuned) == expected


def test_a_claim_is_judged_not_typed():
    claim = C.Claim("period [d]", 6.5624, C.Within(6.5624, C.printed_tolerance("6.5624")), source="Table 2")
    v = claim.judge(6.56238)
    assert v.status == "reproduced" and "within 5.00e-05 of 6.5624" in v.note and "Table 2" in v.note
    with pytest.raises(ValueError, match="no reason"):
        claim.judge(6.57)
    assert claim.judge(6.57, reason="the printed mu differs").status == "differs"
    tuned = C.Claim("z_lim [m/s]", 0.1, C.Within(0.1, 0.25, relative=True), tuned="window weight chosen to match")
    v = tuned.judge(0.11)
    assert v.status == "consistent (tuned)" and "window weight" in v.note
    table = ComparisonTable("t").add(v, claim.judge(6.5624))
    assert [r.status for r in table.rows] == ["consistent (tuned)", "reproduced"]
    with pytest.raises(TypeError, match="verdict must be a Verdict"):
        ComparisonTable("t").add("x", 1, 2, "reproduced")


def test_claims_refuse_what_cannot_be_judged():
    with pytest.raises(ValueError, match="criterion"):
        C.Claim("x", 1.0)
    with pytest.raises(ValueError, match="tuned"):
        C.Claim("x", kind="derived", tuned="because")
    with pytest.raises(ValueError, match="kind"):
        C.Claim("x", kind="reproduced")
    with pytest.raises(ValueError, match="measured"):
        C.Claim("x", 1.0, C.AtMost(2.0)).judge(float("nan"))
    with pytest.raises(TypeError, match="measured"):
        C.Claim("x", "yes", C.Holds("it holds")).judge(1.0)
    with pytest.raises(ValueError, match="reason or a note"):
        C.Claim("x", kind="not in paper").judge(3.0)
    assert C.Claim("x", kind="not in paper", reason="our choice").judge(3.0).status == "not in paper"


def test_claims_and_verdicts_pickle():
    claim = C.Claim("x", 1.0, C.Within(1.0, 0.1))
    v = claim.judge(1.05)
    assert pickle.loads(pickle.dumps(v)) == v and pickle.loads(pickle.dumps(claim)) == claim


def declared_claims():
    """Every Claim declared at module level in a paper package (``cislunar.papers.<paper>.*``)."""
    found = []
    for info in pkgutil.walk_packages(cislunar.papers.__path__, "cislunar.papers."):
        mod = importlib.import_module(info.name)
        for name, obj in vars(mod).items():
            items = obj.values() if isinstance(obj, dict) else obj if isinstance(obj, (list, tuple)) else [obj]
            for item in items:
                if isinstance(item, C.Claim):
                    found.append((f"{info.name}.{name}", item))
    return found


DECLARED = declared_claims()


@pytest.mark.parametrize("name, claim", DECLARED, ids=[f"{n}:{c.quantity[:40]}" for n, c in DECLARED])
def test_every_declared_claim_flips_at_its_tolerance(name, claim):
    """Each paper claim's criterion, probed just inside and just outside its own tolerance."""
    if claim.criterion is None:
        assert claim.kind != "comparison"
        return
    inside, outside = claim.criterion.probes()
    assert claim.judge(inside).status in ("reproduced", "consistent (tuned)", claim.kind)
    assert claim.judge(outside, reason="probe").status == "differs"
    if claim.kind == "comparison":
        assert claim.judge(inside).status == ("consistent (tuned)" if claim.tuned else "reproduced")


def test_equals_on_arrays_and_numbers():
    assert C.Equals(np.int64(3)).holds(3) and not C.Equals(3).holds(4)
