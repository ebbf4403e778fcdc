"""The rounding bound of a printed DRO row (reference.rounding_bound), against independent computations."""

from __future__ import annotations

import numpy as np
import pytest

from cislunar.cr3bp.dynamics import EARTH_MOON
from cislunar.cr3bp.orbits import correct_symmetric
from cislunar.cr3bp.propagation import propagate
from cislunar.papers.wolf_jones import reference


@pytest.fixture(scope="module")
def target_row():
    row = next(r for r in reference.load_wolf_jones_table() if r.table == 4 and r.label == "target2_t0")
    check = reference.verify_table_row(EARTH_MOON, row)
    return check, reference.rounding_bound(EARTH_MOON, check)


def test_family_slope_matches_two_corrected_neighbours(target_row):
    """The implicit-function slope dvy0*/dx0 equals the central difference of two corrected family members."""
    check, bound = target_row
    orb, h = check.corrected, 1e-6
    vy = []
    for s in (1.0, -1.0):
        guess = orb.x0.copy()
        guess[0] += s * h
        vy.append(correct_symmetric(EARTH_MOON, guess, orb.period / 2, fix="x0").x0[4])
    fd = (vy[0] - vy[1]) / (2 * h)
    assert bound.family_slope == pytest.approx(fd, rel=1e-5)
    assert bound.family_slope < -1.0  # DROs: a wider orbit (smaller x0 on the Earth side) is faster


def test_closure_gain_is_the_first_order_closure(target_row):
    """A periodic state pushed by d in vy0 closes after one period at gain * d (first order, checked at two d)."""
    check, bound = target_row
    orb = check.corrected
    for d in (1e-9, -3e-9):
        x = orb.x0.copy()
        x[4] += d
        closure = np.linalg.norm(propagate(EARTH_MOON, x, orb.period).x[-1] - x)
        assert closure == pytest.approx(bound.closure_gain * abs(d), rel=0.02)


def test_bound_composition_and_scaling(target_row):
    """closure = gain x half_unit x (1 + |slope|), linear in half_unit; the periodic rows close inside it and a
    row off by ten half-units in vy0 falls outside."""
    check, bound = target_row
    assert bound.velocity_error == pytest.approx(5e-10 * (1 + abs(bound.family_slope)), rel=1e-12)
    assert bound.closure == pytest.approx(bound.closure_gain * bound.velocity_error, rel=1e-12)
    double = reference.rounding_bound(EARTH_MOON, check, half_unit=1e-9)
    assert double.closure == pytest.approx(2 * bound.closure, rel=1e-12)
    assert check.raw_closure <= bound.closure
    off = reference.TableRow(check.table, check.label, check.x0, check.corrected.x0[4] + 10 * 5e-10)
    off_check = reference.verify_table_row(EARTH_MOON, off)
    assert off_check.raw_closure > bound.closure


def test_refuses_bad_arguments(target_row):
    check, _ = target_row
    with pytest.raises(ValueError, match="half_unit"):
        reference.rounding_bound(EARTH_MOON, check, half_unit=0.0)
    with pytest.raises(TypeError, match="check"):
        reference.rounding_bound(EARTH_MOON, "row")
