"""Studies of notebook 08 (informed station keeping) on small sizes: each statistic against its definition."""

from __future__ import annotations

import numpy as np
import pytest

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.orbits import nrho_9_2
from cislunar.cr3bp.torus import torus_from_orbit
from cislunar.papers.greaves_scheeres_2023 import station_keeping as sk
from cislunar.papers.greaves_scheeres_2023 import station_keeping_study as study

HR = 3600.0 / em.time_unit_s


@pytest.fixture(scope="module")
def torus():
    return torus_from_orbit(nrho_9_2(em), N=15, size_km=100.0)


@pytest.fixture(scope="module")
def surface(torus):
    theta = 2 * np.pi * np.arange(6) / 6
    return sk.station_keeping_surface(em, torus, theta, np.array([-6.0, 0.5, 7.0]) * HR, -18 * HR, 12 * HR,
                                      progress=False)


def test_slice_statistics_against_their_definitions(surface):
    st = study.slice_statistics(surface)
    S = surface
    for j in range(S.t_arrival.size):
        sig, fuel = S.range_sigma_km[j], S.fuel_m_s[j]
        i = S.informed[j]
        assert st.percentile[j] == pytest.approx(100 * np.mean(sig < sig[i]))
        assert st.fuel_percentile[j] == pytest.approx(100 * np.mean(fuel > fuel[i]))
        # the best maneuver using no more fuel than u* is at least as good as u*
        assert st.cheaper_best_km[j] <= sig[i]
        assert st.cheaper_best_km[j] == pytest.approx(sig[fuel <= fuel[i] + 1e-12].min())
    assert st.below_median_fuel == pytest.approx(np.mean(S.informed_fuel_m_s <= np.median(S.fuel_m_s, axis=1)))
    assert -1 <= st.rank_correlation <= 1
    assert st.median_percentile == pytest.approx(np.median(st.percentile))
    assert len(st.format(S).splitlines()) == S.t_arrival.size + 1


def test_grid_resolution_study_rows(torus, surface):
    t_grid = np.array([-6.0, 7.0]) * HR
    g = study.grid_resolution_study(em, torus, (4, 6), t_grid, -18 * HR, 12 * HR, agent_phases=(0.0,))
    assert len(g.rows) == 4 and g.n_grid == (4, 6)
    assert g.series(0.0, "angle", "percentile").shape == (2,)
    # the 6-angle row is the same computation as a surface on those angles
    s6 = sk.station_keeping_surface(em, torus, surface.theta, t_grid, -18 * HR, 12 * HR, progress=False)
    p = s6.reselect("projection")
    assert g.series(0.0, "projection", "percentile")[1] == pytest.approx(np.median(p.informed_percentile))
    assert g.series(0.0, "projection", "sigma_m")[1] == pytest.approx(np.median(p.informed_range_sigma_km) * 1e3)
    assert len(g.format().splitlines()) == 5


def test_scenario_sweep_one_setting_is_the_surface(torus, surface):
    t_arr = surface.t_arrival
    rows = study.scenario_sweep(em, torus, surface.theta, t_arr, -6.0, 12 * HR, pre_arcs_h=(0.0,), leads_h=(12.0,),
                                agent_thetas=(0.0,))
    (r,) = rows
    assert (r.pre_h, r.lead_h, r.agent_phase) == (0.0, 12.0, 0.0)
    assert r.pct_tf == pytest.approx(np.median(surface.informed_percentile))
    assert r.pct_proj == pytest.approx(np.median(surface.reselect("projection").informed_percentile))
    assert 0 <= r.q_tf <= 100 and 0 <= r.pct_arr <= 100
    assert len(study.format_sweep(rows).splitlines()) == 3


def test_zero_offset_is_the_baseline(torus, surface):
    out = study.offset_study(em, torus, surface.theta, surface.t_arrival, -18 * HR, 12 * HR,
                             np.random.default_rng(0), distances_km=(0.0,), n_directions=1)
    assert out == {0.0: [pytest.approx(np.median(surface.informed_percentile))]}


def test_execution_levels():
    lv = study.execution_levels(1e-3, 0.01)
    assert lv["perfect"] == (0.0, 0.0) and lv["exec"] == (1e-3, 0.01)
    assert lv["small"] == pytest.approx((1e-4, 1e-3))


def test_filter_monte_carlo_structure(surface):
    mcs = study.filter_monte_carlo(em, surface, surface.reselect("projection"), nrho_9_2(em).x0, n_trials=1, seed=0)
    inf, infp, uni, none = study.POLICIES
    assert set(mcs.summary) == {(p, t) for p in (inf, infp, uni) for t in ("perfect", "small", "exec")} | {
        (none, "perfect")}
    j, zero = mcs.slice_index, mcs.no_maneuver_index
    assert surface.fuel_m_s[j, zero] < 1e-6 and zero == 0  # the agent's own ring angle: no maneuver
    assert mcs.summary[(inf, "perfect")]["ca"] == pytest.approx(surface.informed_range_sigma_km[j] * 1e3)
    lo, hi = mcs.band
    assert lo < 12 < hi  # the mean NEES of a 12-dimensional state is 12 on average
    assert mcs.prior_range_m == pytest.approx(20e3 * np.sqrt(2), rel=1e-9)
    assert mcs.ratio(uni) == pytest.approx(1.0)
    assert "filter runs" in mcs.format()


def test_sweeps_on_an_executor_match_the_serial_run(torus, surface):
    from concurrent.futures import ThreadPoolExecutor

    t_arr = surface.t_arrival
    sweep_kw = {"pre_arcs_h": (0.0,), "leads_h": (12.0, 18.0), "agent_thetas": (0.0, np.pi)}
    grid_args = (em, torus, (4, 6), np.array([-6.0, 7.0]) * HR, -18 * HR, 12 * HR)
    off_args = (em, torus, surface.theta, t_arr, -18 * HR, 12 * HR)
    serial = (study.scenario_sweep(em, torus, surface.theta, t_arr, -6.0, 12 * HR, **sweep_kw),
              study.grid_resolution_study(*grid_args, agent_phases=(0.0, 0.5)),
              study.offset_study(*off_args, np.random.default_rng(4), distances_km=(0.0, 5.0), n_directions=2))
    with ThreadPoolExecutor(2) as ex:
        par = (study.scenario_sweep(em, torus, surface.theta, t_arr, -6.0, 12 * HR, executor=ex, **sweep_kw),
               study.grid_resolution_study(*grid_args, agent_phases=(0.0, 0.5), executor=ex),
               study.offset_study(*off_args, np.random.default_rng(4), distances_km=(0.0, 5.0), n_directions=2,
                                  executor=ex))
    assert serial == par
    rows = par[0]
    assert [(r.lead_h, r.agent_phase) for r in rows] == [(12.0, 0.0), (12.0, 0.5), (18.0, 0.0), (18.0, 0.5)]
    assert [(g.agent_phase, g.n, g.reading) for g in par[1].rows][:3] == [(0.0, 4, "angle"), (0.0, 4, "projection"),
                                                                          (0.0, 6, "angle")]
    assert list(par[2]) == [0.0, 5.0] and all(len(v) == 2 for v in par[2].values())
    # zero offset: both directions give the baseline surface
    assert par[2][0.0] == [pytest.approx(np.median(surface.informed_percentile))] * 2


def test_studies_refuse_bad_arguments_by_name(torus, surface):
    g = study.grid_resolution_study(em, torus, (4, 6), np.array([-6.0, 7.0]) * HR, -18 * HR, 12 * HR,
                                    agent_phases=(0.0,))
    with pytest.raises(ValueError, match="agent_phase"):
        g.series(0.5, "angle", "sigma_m")  # a phase the study did not run
    with pytest.raises(ValueError, match="key"):
        g.series(0.0, "angle", "sigma")
    with pytest.raises(TypeError, match="torus"):
        study.scenario_sweep(em, "torus", surface.theta, surface.t_arrival, -6.0, 12 * HR)
    with pytest.raises(ValueError, match="pre_arcs_h"):
        study.scenario_sweep(em, torus, surface.theta, surface.t_arrival, -6.0, 12 * HR, pre_arcs_h=(-1.0,))
    with pytest.raises(TypeError, match="executor"):
        study.offset_study(em, torus, surface.theta, surface.t_arrival, -18 * HR, 12 * HR, np.random.default_rng(0),
                           executor=object())
    with pytest.raises(ValueError, match="statistics"):
        study.member_study(em, nrho_9_2(em), surface.theta, surface.t_arrival, -18 * HR, 12 * HR,
                           statistics=("median_km",))
    with pytest.raises(ValueError, match="exec_rel"):
        study.execution_levels(1e-3, -0.01)
    with pytest.raises(TypeError, match="rows"):
        study.format_sweep("rows")
