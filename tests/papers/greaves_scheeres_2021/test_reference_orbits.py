"""Chapter 01 studies: variational equations against finite differences, the halo family and its stable members,
observer visibility (small sizes; invariants, not snapshots)."""

import numpy as np
import pytest

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.dynamics import SYNODIC_MONTH_DAYS
from cislunar.papers.greaves_scheeres_2021 import reference_orbits as ro
from cislunar.papers.greaves_scheeres_2021.claims.reference_orbits import CLAIMS
from cislunar.sensing import sites


@pytest.fixture(scope="module")
def nrho():
    return orbits.nrho_9_2(em)


@pytest.fixture(scope="module")
def halo():
    return ro.halo_family_study(em, 0.06)


def test_variational_check_follows_the_truncation_branch(nrho):
    fd = ro.variational_check(em, nrho, 3, log10_range=(-6.0, -3.0))
    assert fd.steps == pytest.approx([1e-6, 10**-4.5, 1e-3])
    # central differences: truncation error ~ h^2, so a step 10**1.5 larger costs about 10**3 (round-off aside)
    assert 300 < fd.stm_error[2] / fd.stm_error[1] < 3000
    assert fd.best_stm == fd.stm_error.min() < 1e-8 and fd.best_stt < 1e-6
    with pytest.raises(ValueError, match="n_steps"):
        ro.variational_check(em, nrho, 1)


def test_halo_study_orbits_satisfy_their_defining_conditions(halo):
    # the 9:2 NRHO: period imposed by the resonance
    assert halo.nrho.period_days == pytest.approx(2 / 9 * SYNODIC_MONTH_DAYS, rel=1e-8)
    # the inner band's edge: stability index 1; the outer member: every Broucke index on [-1, 1]
    assert abs(halo.stable.stability_index - 1) < 1e-3
    assert np.all(np.abs(halo.outer.broucke_indices.real) <= 1 + 1e-9)
    band = halo.outer_band
    assert band and all(np.max(np.abs(o.broucke_indices.real)) < 1 for o in band)
    assert all(o.perilune_radius_km > halo.nrho.perilune_radius_km for o in band)
    lo, hi = halo.band_perilune_km
    assert lo <= hi and lo == min(o.perilune_radius_km for o in band)
    # the margin is negative exactly for the stable members
    assert np.array_equal(halo.broucke_margin < 0,
                          [np.max(np.abs(o.broucke_indices.real)) < 1 for o in halo.family])
    assert len(halo.perilune_km) == len(halo.family) == len(halo.stability_index)
    assert "outer stable band" in halo.report()


def test_observer_visibility_l2_never_occulted_and_coverage_ordered(nrho):
    vis = ro.observer_visibility(em, {"9:2": nrho}, 300, 30.0, 600.0)["9:2"]
    assert vis.l2.count == 0 and vis.l2.clear_fraction == 1.0
    # one station <= the best pair of them <= all three together
    assert np.max(vis.single) <= vis.best_pair + 1e-12 <= vis.all3 + 2e-12
    assert set(vis.dro_criteria) == {"limited", "infrequent", "short"}
    assert ro.line_of_sight_samples(1.0, 600.0) == 145  # 0, 600, ..., 86400 s
    with pytest.raises(ValueError, match="samples"):
        ro.observer_visibility(em, {"9:2": nrho}, 1, 30.0, 600.0)


def test_station_sweep_refinement_contains_the_best_pair(nrho):
    sw = ro.station_pair_sweep(em, nrho, (30.0, 60.0), 300)
    assert sw.n_pairs == len(sw.grid_sites) * (len(sw.grid_sites) - 1) // 2
    # the 1-deg refinement includes both sites of the coarse best pair, so it can only do as well or better
    assert sw.fine.best_fraction >= sw.coarse.best_fraction - 1e-12
    assert sw.no_pair_suffices == (sw.coarse.n_full_pairs == 0 and sw.fine.n_full_pairs == 0)


def test_perilune_visibility_rows_are_unions_and_intervals_rebuild_them(nrho):
    pv = ro.perilune_visibility(em, nrho, (0, 1), half_width_h=1.0)
    assert pv.hours.size == 241 and pv.hours[0] == -1.0 and pv.hours[-1] == 1.0
    rows = dict(pv.rows)
    singles = [rows[s.name] for s in sites.DEFAULT_STATIONS]
    assert np.array_equal(rows["all three"], np.any(singles, axis=0))
    assert np.array_equal(next(v for k, v in pv.rows if k.startswith("best pair")), singles[0] | singles[1])
    for _, seen in pv.rows:
        rebuilt = np.zeros_like(seen)
        for a, b in pv.intervals(seen):
            rebuilt |= (pv.hours >= a) & (pv.hours <= b)
        assert np.array_equal(rebuilt, seen)


def test_claims_judge_the_measured_rows():
    assert CLAIMS["nrho_period"].judge(2 / 9 * SYNODIC_MONTH_DAYS).status == "derived"
    assert CLAIMS["nrho_perilune"].judge(3250.0).status == "not in paper"
    assert CLAIMS["nrho_perilune"].judge(3400.0).status == "differs"
    assert CLAIMS["dro_outages_9_2"].judge(True).status == "consistent (tuned)"
    assert CLAIMS["l2_line_of_sight"].judge(0).status == "reproduced"
    assert CLAIMS["l2_line_of_sight"].judge(2).status == "differs"


def test_public_boundary_names_the_bad_argument(nrho):
    """Malformed inputs are refused by name before any propagation (the reliability sweep covers every kind)."""
    with pytest.raises(ValueError, match="grid_deg.*divide 180"):
        ro.station_pair_sweep(em, nrho, (40.0, 80.0), 20)  # 40 deg does not divide 180 deg
    with pytest.raises(ValueError, match="grid_deg"):
        ro.station_pair_sweep(em, nrho, (30.0,), 20)
    with pytest.raises(ValueError, match="best_pair"):
        ro.perilune_visibility(em, nrho, (1, 1))  # the same station twice is not a pair
    with pytest.raises(ValueError, match="best_pair"):
        ro.perilune_visibility(em, nrho, (0, 3))  # three default stations: indices 0..2
    with pytest.raises(TypeError, match="best_pair"):
        ro.perilune_visibility(em, nrho, "01")
    with pytest.raises(ValueError, match="log10_range"):
        ro.variational_check(em, nrho, 2, log10_range=(-6.0,))
    with pytest.raises(TypeError, match="targets"):
        ro.observer_visibility(em, [nrho], 20, 1.0, 600.0)
    with pytest.raises(TypeError, match="visibility"):
        ro.visibility_report({"9:2": nrho}, 1.0, 600.0)
    with pytest.raises(ValueError, match="step_s"):
        ro.line_of_sight_samples(1.0, 0.0)
    dro = orbits.dro_family(em, np.array([0.8]))[0]
    with pytest.raises(ValueError, match="observer_t0"):  # the printed state's span is the observer's period
        ro.figure_dro_family(em, [dro], [dro], [(dro, "target 1")], dro.x0)
    with pytest.raises(TypeError, match=r"groups\[0\]"):
        ro.figure_dro_family(em, [dro], [dro], [dro], dro.x0)
    with pytest.raises(TypeError, match="study"):
        ro.figure_halo_stability(em, nrho)
