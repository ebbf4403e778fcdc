"""Wolf & Jones' DRO tables (chapter 01): rows grouped into orbits, how tightly the printed rows pin mu, and the
window arithmetic of the two readings of the time unit (invariants, not snapshots)."""

import dataclasses

import numpy as np
import pytest

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.dynamics import SYNODIC_MONTH_DAYS
from cislunar.papers.wolf_jones import reference
from cislunar.papers.wolf_jones import reference_tables as wjt
from cislunar.papers.wolf_jones.claims.reference_orbits import CLAIMS


@pytest.fixture(scope="module")
def tables():
    return wjt.dro_table_study(em, 8)


def test_row_labels_mark_the_inferred_ones():
    assert wjt.row_label(2, "target1_t0") == "Table 2: target1_t0"
    assert wjt.row_label(4, "target3_t0") == "Table 4: target3_t0"  # the one label Table 4 keeps
    assert wjt.row_label(4, "target1_t0").endswith("(label inferred)")
    # every declared closure claim is one row of the tables
    assert {f"closure_table{t}_{label}" for t, label in wjt.TABLE_ROWS} <= set(CLAIMS)


def test_rows_group_into_distinct_orbits(tables):
    checks, groups = tables.checks, tables.groups
    assert len(checks) == len(wjt.TABLE_ROWS) == 8
    # Tables 2 and 4 print the same observer start: eight rows, seven orbits, every row in exactly one group
    assert len(groups) == 7
    assert sorted(id(c) for g in groups for c in g.checks) == sorted(id(c) for c in checks)
    shared = [g for g in groups if len(g.checks) > 1]
    assert len(shared) == 1 and {c.table for c in shared[0].checks} == {2, 4}
    assert all(c.label == "observer_t0" for c in shared[0].checks) and " = " in shared[0].label
    for g in groups:  # one printed state per group
        assert len({(c.x0, c.vy0) for c in g.checks}) == 1
    # sorted by crossing; the crossing is the printed x0 measured from the Moon, km (Earth side: negative)
    cross = np.array([g.crossing_km for g in groups])
    assert np.all(np.diff(cross) > 0) and np.all(cross < 0)
    for g in groups:
        assert g.crossing_km == pytest.approx((g.checks[0].x0 - (1 - em.mu)) * em.length_unit_km, rel=1e-12)
    # the figure gets one periodic orbit per group, through the printed x0
    assert [o.x0[0] for o, _ in tables.figure_groups] == pytest.approx([g.checks[0].x0 for g in groups], abs=1e-12)
    assert all(o.closure < reference.CLOSURE_TOL for o, _ in tables.figure_groups)


def test_observer_row_is_the_one_off_the_family(tables):
    obs = tables.observer
    assert obs.label == "observer_t0" and not obs.periodic_as_printed
    assert sum(not c.periodic_as_printed for c in tables.checks) == 2  # the same row, printed twice
    rng = tables.jacobi_ranges()
    lo, hi = rng["others"]
    # corrected, the observer lies among the other orbits' Jacobi constants' neighbourhood; printed, it does not
    printed = em.jacobi(np.array([obs.x0, 0, 0, 0, obs.vy0, 0]))
    assert abs(obs.corrected.jacobi - (lo + hi) / 2) < 10 * (hi - lo)
    assert abs(printed - (lo + hi) / 2) > 10 * (hi - lo)
    assert rng["targets"][0] >= lo and rng["targets"][1] <= hi
    assert "printed observer state" in tables.observer_report() and "7 distinct orbits" in tables.groups_report()
    assert len(tables.rows_report().splitlines()) == 1 + len(tables.checks)


def test_zoom_family_spans_the_printed_crossings(tables):
    x_moon = 1 - em.mu
    zoom = np.array([(o.x0[0] - x_moon) * em.length_unit_km for o in tables.zoom_family])
    cross = [g.crossing_km for g in tables.groups]
    assert zoom.max() == pytest.approx(max(cross) + 1500.0, abs=1e-6)
    assert zoom.min() == pytest.approx(min(cross) - 1500.0, abs=1e-6)
    assert len(tables.zoom_family) == 12 and len(tables.family) == 8
    # along the DRO family the period grows with the distance of the crossing from the Moon
    order = np.argsort(zoom)
    assert np.all(np.diff([tables.zoom_family[k].period_days for k in order]) < 0)
    with pytest.raises(ValueError, match="n_members"):
        wjt.dro_table_study(em, 1)


def test_mu_closure_pins_the_adopted_value():
    study = wjt.mu_closure_study(em, [em.mu + 1e-9, em.mu - 3e-9])
    assert study.mus[0] == em.mu  # the adopted value is always tried, first
    assert study.adopted_closure < reference.CLOSURE_TOL <= min(study.closures[1:])
    assert study.pinned
    # away from the ~1e-8 floor of nine printed digits, the closure grows linearly with |d mu|
    ratio = study.closure[em.mu - 3e-9] / study.closure[em.mu + 1e-9]
    assert 2.0 < ratio < 4.5
    assert "+1.0e-09 ->" in study.trials_text() and "closes" in study.report() and "fails" in study.report()
    assert wjt.mu_trials(em, 2e-9)[:3] == (em.mu, em.mu + 2e-9, em.mu - 2e-9)
    assert wjt.mu_trials(em)[3:] == wjt.PUBLISHED_MU


def test_pinned_rule():
    mk = lambda closures: wjt.MuClosureStudy(0.5, (0.5, 0.5 + 1e-9, 0.5 + 1e-10), closures, 1e-7)  # noqa: E731
    assert mk((1e-8, 2e-7, 3e-8)).pinned  # a trial closer than 0.9e-9 may close
    assert not mk((1e-8, 5e-8, 3e-8)).pinned  # a trial 1e-9 away that closes: not pinned
    assert not mk((2e-7, 5e-7, 3e-7)).pinned  # the adopted value itself does not close


def test_window_arithmetic():
    w = wjt.window_study(em, 3.725)
    (a1, b1), (a2, b2) = w.windows["standard"]
    P = 3.725 * em.time_unit_days
    assert (a1, b1, a2, b2) == pytest.approx((0.75 * P, 1.5 * P, P, 2 * P))
    for reading in w.windows:  # [3P/4, 3P/2] and [P, 2P] have end ratio 2 whatever the time unit
        (c1, d1), (c2, d2) = w.windows[reading]
        assert d1 / c1 == pytest.approx(2) and d2 / c2 == pytest.approx(2)
    assert w.units_days["P_synodic/2pi"] == pytest.approx(SYNODIC_MONTH_DAYS / (2 * np.pi))
    assert w.miss("standard") == pytest.approx(max(abs(a1 - 12), abs(b1 - 23), abs(a2 - 17), abs(b2 - 32)))
    assert w.case1_misses == pytest.approx((abs(a1 - 12), abs(b1 - 23)))
    # the literal reading is the longer unit: every window lies later, and here fits the day counts worse
    assert w.units_days["P_synodic/2pi"] > w.units_days["standard"] and w.standard_fits_better
    # periods inside the fitting range meet both 12 and 23 days within the tolerance; just outside, one end fails
    lo, hi = w.fitting_periods
    assert lo < hi
    for P_days, fits in ((lo + 1e-6, True), (hi - 1e-6, True), (lo - 1e-3, False), (hi + 1e-3, False)):
        ends = (0.75 * P_days, 1.5 * P_days)
        assert (abs(ends[0] - 12) <= w.tolerance_days and abs(ends[1] - 23) <= w.tolerance_days) is fits
    assert "ratio of the window ends" in w.report()
    # a looser tolerance widens the range of fitting periods
    lo2, hi2 = dataclasses.replace(w, tolerance_days=2.0).fitting_periods
    assert lo2 < lo and hi2 > hi
    with pytest.raises(ValueError, match="period_tu"):
        wjt.window_study(em, -1.0)
    assert CLAIMS["window_case1"].criterion.limit == wjt.WINDOW_TOL_DAYS
