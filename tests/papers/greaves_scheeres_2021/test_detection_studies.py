"""Notebook 10's closing-table helpers and claims: the Monte Carlo tolerances they compute, and the claims judged at
the edges of those tolerances."""

from __future__ import annotations

import numpy as np
import pytest

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.papers.greaves_scheeres_2021 import detection as det
from cislunar.papers.greaves_scheeres_2021 import detection_studies as ds
from cislunar.papers.greaves_scheeres_2021.claims.maneuver_detection import (
    CLAIMS,
    PAPER_ACCURACY,
    PAPER_ZLIM,
)


def _binom_tol(paper, n):
    """The Table 7 tolerance as it was fixed before the comparison (notebook 10)."""
    return max(0.02, 2 * np.sqrt(paper * (1 - paper) / n) + 1 / (2 * n))


@pytest.mark.parametrize("paper", [1.0, 0.97, 0.5])
@pytest.mark.parametrize("n", [8, 16, 100, 200, 1000])
def test_two_accuracy_standard_errors_are_the_fixed_tolerance(paper, n):
    assert 2 * ds.accuracy_standard_error(paper, n) == pytest.approx(_binom_tol(paper, n), rel=1e-12)


def test_accuracy_claims_flip_at_the_binomial_tolerance():
    for p, paper in PAPER_ACCURACY.items():
        n = 200
        se = ds.accuracy_standard_error(paper, n)
        tol = _binom_tol(paper, n)
        for key in (f"accuracy f=0.1, {p}", f"accuracy f_c, {p}"):
            claim = CLAIMS[key]
            assert claim.judge(paper - 0.999 * tol, standard_error=se).status != "differs"
            assert claim.judge(paper - 1.001 * tol, standard_error=se, reason="probe").status == "differs"
        assert CLAIMS[f"accuracy f=0.1, {p}"].judge(paper, standard_error=se).status == "consistent (tuned)"
        assert CLAIMS[f"accuracy f_c, {p}"].judge(paper, standard_error=se).status == "reproduced"
    with pytest.raises(ValueError, match="rate"):
        ds.accuracy_standard_error(1.5, 10)


def test_thresholds_tuned_within_25_percent_and_predicted_within_two_bootstrap_errors():
    for p, z in PAPER_ZLIM.items():
        assert CLAIMS[f"z_lim f=0.1, {p}"].judge(1.24 * z).status == "consistent (tuned)"
        assert CLAIMS[f"z_lim f=0.1, {p}"].judge(1.26 * z, reason="probe").status == "differs"
        se = 0.01 * z
        assert CLAIMS[f"z_lim f_c, {p}"].judge(z + 1.99 * se, standard_error=se).status == "reproduced"
        assert CLAIMS[f"z_lim f_c, {p}"].judge(z + 2.01 * se, standard_error=se, reason="probe").status == "differs"


def test_improvement_in_standard_errors():
    assert ds.improvement_in_standard_errors(0.1, 0.2, 0.03, 0.04) == pytest.approx(2.0)
    assert ds.improvement_in_standard_errors(0.3, 0.2, 0.03, 0.04) == pytest.approx(-2.0)
    assert ds.improvement_in_standard_errors(0.2, 0.2, 0.0, 0.0) == 0.0
    assert ds.improvement_in_standard_errors(0.1, 0.2, 0.0, 0.0) > 1e6
    claim = CLAIMS["stable better, stable NRHO, quiet"]
    assert claim.judge(ds.improvement_in_standard_errors(0.1, 0.2, 0.03, 0.04)).status == "reproduced"
    assert claim.judge(ds.improvement_in_standard_errors(0.15, 0.2, 0.03, 0.04), reason="probe").status == "differs"


def test_finite_or_and_the_pm_j_fallback_counts_as_no_preference():
    assert ds.finite_or(1.3, 1.0) == 1.3 and ds.finite_or(np.nan, 1.0) == 1.0
    assert CLAIMS["+-j"].judge(ds.finite_or(np.nan, 1.0), reason="probe").status == "differs"


def test_health_claims_use_the_single_run_spread_and_the_printed_digit():
    sd = 0.02
    assert CLAIMS["health z, f_c"].judge(0.4761 + 1.9 * sd, standard_error=sd).status == "reproduced"
    assert CLAIMS["health z, f = 0.1"].judge(0.4761 - 1.9 * sd, standard_error=sd).status == "consistent (tuned)"
    assert CLAIMS["health z, f_c"].judge(0.4761 + 2.1 * sd, standard_error=sd, reason="probe").status == "differs"
    assert CLAIMS["health sigma, f_c"].judge(29.0).status == "reproduced"
    assert CLAIMS["health sigma, f_c"].judge(36.0).status == "differs"


def test_kinds_of_the_rows_without_a_paper_number():
    assert CLAIMS["sizes"].judge("500 / 3000 / 100").status == "derived"
    assert CLAIMS["sizes"].judge("8 / 8 / 4").status == "differs"  # quick mode: says so, with the declared reason
    assert CLAIMS["control first, f = 0.1, 100 urad"].judge(True).status == "beyond paper"
    assert CLAIMS["control first, f = 0.1, 10 urad"].judge(True).status == "consistent (tuned)"
    assert CLAIMS["control first, f_c, 10 urad"].judge(True).status == "reproduced"
    for key in ("noise", "tuning", "FP/MD, 9:2 NRHO, quiet", "z_lim, stable NRHO, active"):
        assert CLAIMS[key].judge("x").status == "not in paper"


def _map(h1_by_f, zlim_by_f):
    """A synthetic map: H1 forward inconsistency and z_lim per factor, the same on every orbit and policy."""
    orbits, policies, variants = ("9:2 NRHO", "stable NRHO"), ("active", "quiet"), ("base", "other")
    f_grid, f_side = (0.1, 0.3, 1.0), (0.1, 0.3)
    cells = {}
    for v in variants:
        for o in (orbits if v == "base" else orbits[:1]):
            for p in policies:
                for f in (f_grid if v == "base" else f_side):
                    cells[o, p, f, v] = {"z_lim": zlim_by_f[f] * (1 if p == "active" else 0.1), "err": 0.05,
                                         "h0": (0.0, 0.0), "h1": (h1_by_f[f], 0.02), "n": (4, 4), "slope": 1.0}
    return ds.TuningMap(cells, orbits, policies, variants, f_grid, f_side, {"active": 0.2, "quiet": 0.02})


def test_tuning_map_readings():
    m = _map({0.1: 0.5, 0.3: 0.08, 1.0: 0.0}, {0.1: 0.1, 0.3: 0.4, 1.0: 0.8})
    assert m.worst("9:2 NRHO", "quiet", 0.1) == 0.5
    assert m.consistent_factors == [0.3, 1.0] and m.f_c == 0.3
    # log-log interpolation between f = 0.1 (z 0.1) and 0.3 (z 0.4): z = 0.2 at f = 0.1 * 3**(log 2 / log 4)
    assert m.f_match("active") == pytest.approx(0.1 * 3 ** 0.5)
    assert m.f_match("quiet") == pytest.approx(0.1 * 3 ** 0.5)
    assert m.edge("other") == 0.3
    text = m.report(0.1)
    assert "f_c = 0.3" in text and "settings consistent at f = 0.1: none" in text
    none = _map({0.1: 0.5, 0.3: 0.5, 1.0: 0.5}, {0.1: 0.3, 0.3: 0.4, 1.0: 0.8})
    assert none.consistent_factors == [] and none.f_c == 1.0 and np.isnan(none.f_match("active"))
    assert none.edge("other") is None


def _spike_cells(inc_h1_smooth, sig_const, contrast_h1, contrast_h0):
    cell = {"after_burn": 0.5}
    return {("constant", "H0"): {**cell, "inc": (0.0, 0.0), "sig_km": sig_const, "contrast": np.array(contrast_h0)},
            ("constant", "H1"): {**cell, "inc": (0.05, inc_h1_smooth), "sig_km": sig_const,
                                 "contrast": np.array(contrast_h1)},
            ("apoapsis window", "H0"): {**cell, "inc": (0.0, 0.0), "sig_km": 5.0, "contrast": np.array(contrast_h0)},
            ("apoapsis window", "H1"): {**cell, "inc": (0.5, 0.1), "sig_km": 5.0, "contrast": np.array(contrast_h1)}}


def test_spike_study_criteria_of_figs_10_and_11():
    h1 = [[1.0, 3.0], [1.0, 2.5], [3.0, 2.5], [1.0, 1.5]]  # smoothed >= 2 and above forward in 2 of 4
    h0 = [[1.0, 1.0], [1.0, 1.5], [1.0, 2.0], [1.0, 1.2]]  # smoothed below 2 in 3 of 4
    s = ds.SpikeStudy(_spike_cells(0.1, 12.0, h1, h0), 4)
    assert s.fig10_ok and s.fig11_h1 == 0.5 and s.fig11_h0 == 0.75
    assert not ds.SpikeStudy(_spike_cells(0.11, 12.0, h1, h0), 4).fig10_ok  # above 10 % inconsistent
    assert not ds.SpikeStudy(_spike_cells(0.1, 4.0, h1, h0), 4).fig10_ok  # bound not larger than the window's
    assert "4 quiet-policy runs" in s.report()


def test_pm_j_search_picks_the_largest_contrast_at_apoapsis():
    z = np.ones(6)
    cells = {(0.1, 10.0, 0.0): (z, 1.05), (0.1, 10.0, 3.0): (z, 1.5), (0.1, 300.0, 0.0): (z, 1.3),
             (0.1, 300.0, 3.0): (z, 1.25)}
    s = ds.PmJSearch(cells, (0.1,), (0.0, 3.0), np.array([1.0, 0.0, 0.0]), 8e4)
    assert s.best == ((0.1, 300.0, 0.0), 1.3)  # the 1.5 is off apoapsis
    assert s.contrasts_at(10.0) == [1.05, 1.5]
    assert s.burn_time_effect() == pytest.approx(0.05)
    assert "contrast 1.30" in s.report()


def test_burn_z_sigma_level():
    s = ds.BurnZStudy({0.1: np.array([0.4, 0.5, 0.6])}, 0.5)
    h1 = np.array([0.04, 0.05, 0.06])
    assert s.sigma_level(0.1, h1) == pytest.approx((0.5 - 0.05) / h1.std())
    assert "f = 0.10: z of a 0.5 m/s burn 0.5000" in s.report()


def test_a_small_spike_study_runs_and_is_bounded():
    o = orbits.nrho_9_2(em)
    qw = 0.1 * det.window_control_weight(det.QUIET_POLICY, 8.0)
    window = det.make_setup(em, o, qw, 1e-18)
    s = ds.run_spike_study(det.make_setup(em, o, qw, qw), window, 2, [0, 41])
    assert set(s.cells) == {(t, h) for t in ("constant", "apoapsis window") for h in ("H0", "H1")}
    for v in s.cells.values():
        assert all(0.0 <= x <= 1.0 for x in v["inc"]) and v["contrast"].shape == (2, 2) and v["sig_km"] > 0
    # the constant tuning admits more control everywhere: its forward bound is the larger one
    assert s.cells["constant", "H1"]["sig_km"] > s.cells["apoapsis window", "H1"]["sig_km"]
