"""Chapter 09, Section 5d (custody over many periods, SRI against covariance form, run time against cadence): small
sizes, identities against an independent library (filterpy), and cases built so that a wrong implementation fails."""

import pickle

import numpy as np
import pytest

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.papers.greaves_scheeres_2021 import custody as cu
from cislunar.papers.greaves_scheeres_2021 import detection as det
from cislunar.papers.greaves_scheeres_2021.claims.operations import CLAIMS


@pytest.fixture(scope="module")
def nrho():
    return orbits.nrho_9_2(em)


@pytest.fixture(scope="module")
def small_problem(nrho):
    """A short, well-conditioned linear problem: 12-h cadence over half a period from apoapsis."""
    return cu.linear_problem(em, nrho, cadence_hours=12.0, periods=0.5)


def test_pointing_error_is_the_angle_between_lines_of_sight():
    obs = np.zeros(6)
    truth = np.r_[2.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    for a in (1e-9, 1e-4, 0.3, 2.0):
        est = np.r_[3.0 * np.cos(a), 3.0 * np.sin(a), 0.0, 1.0, 1.0, 1.0]  # range and velocity do not matter
        assert cu.pointing_error(obs, est, truth) == pytest.approx(a, rel=1e-12)
    # a moved observer: the angle is measured from it, not from the origin
    o2 = np.r_[1.0, -1.0, 0.0, 0, 0, 0]
    assert cu.pointing_error(o2, np.r_[1.0, 1.0, 0, 0, 0, 0], np.r_[3.0, -1.0, 0, 0, 0, 0]) == pytest.approx(np.pi / 2)


def test_covariance_forms_equal_the_sri_form_on_a_well_conditioned_case(small_problem):
    truth, ys, x0 = small_problem.simulate(np.random.default_rng(3), 4)
    xs, Ps, Rs = cu.sri_filter(small_problem, ys, x0)
    for form in ("joseph", "conventional"):
        xf, Pf = cu.covariance_filter(small_problem, ys, x0, form=form)
        scale = np.max(np.abs(Ps), axis=(-2, -1))[:, None, None]
        assert np.max(np.abs(Pf - Ps) / scale) < 1e-8, form
        assert np.allclose(xf, xs, rtol=0, atol=1e-8 * np.max(np.abs(xs)))
    # the SRI factor is a square root of the information: R^T R P = I
    assert np.allclose(np.swapaxes(Rs, -1, -2) @ Rs @ Ps, np.eye(6), atol=1e-6)


def test_joseph_form_equals_filterpy(small_problem):
    """The covariance form against an independent implementation (filterpy's KalmanFilter, Joseph update)."""
    from filterpy.kalman import KalmanFilter

    pb = small_problem
    truth, ys, x0 = pb.simulate(np.random.default_rng(4), 1)
    xf, Pf = cu.covariance_filter(pb, ys, x0, form="joseph")
    kf = KalmanFilter(dim_x=6, dim_z=pb.meas_cov.shape[0])
    kf.x, kf.P, kf.R = x0[0].copy(), pb.P0.copy(), pb.meas_cov.copy()
    for k in range(pb.t.size):
        if k:
            kf.F, kf.Q = pb.Phis[k - 1], pb.Qs[k - 1]
            kf.predict()
        kf.H = pb.Hs[k]
        kf.update(ys[0, k])
        assert np.allclose(kf.P, Pf[k], rtol=1e-9, atol=1e-12 * np.max(np.abs(Pf[k])))
        assert np.allclose(kf.x, xf[0, k], rtol=1e-9, atol=1e-9 * np.max(np.abs(xf[0, k])))


def test_sri_form_survives_where_the_covariance_form_breaks(nrho):
    """Wide prior (x 1e4), a 3-day gap, then dense 10-nrad updates with tiny process noise: the conventional form
    loses symmetry, positive definiteness and consistency; the SRI form loses nothing."""
    pb = cu.linear_problem(em, nrho, prior_scale=1e4, sigma_angle_rad=1e-8, gap_hours=72.0, q_km2_s3=1e-26)
    case = cu.conditioning_case(pb, 30, np.random.default_rng(1), label="ill-conditioned")
    assert np.nanmax(case.cond_info) > 1e15
    assert case.lost("conventional") == {"symmetry": True, "positive definiteness": True, "consistency": True}
    assert not any(case.lost("SRI").values())
    assert case.lost("Joseph")["symmetry"]


def test_consistency_flag_sees_an_overconfident_filter(small_problem):
    """Shrinking the prior the filter assumes (not the one the truth is drawn from) must show as lost consistency."""
    truth, ys, x0 = small_problem.simulate(np.random.default_rng(5), 30)
    narrow = cu.LinearProblem(small_problem.t, small_problem.Phis, small_problem.Hs, small_problem.measured,
                              small_problem.meas_cov, small_problem.Qs, small_problem.P0 * 1e-4)
    xf, Pf = cu.covariance_filter(narrow, ys, x0)
    d = xf[:, 0] - truth[:, 0]
    assert np.mean(np.einsum("mi,mi->m", d, np.linalg.solve(Pf[0], d.T).T)) > 20  # way above 6


def test_custody_runs_see_the_burns_and_the_bound(nrho):
    """Two periods at 6 h: with the paper's window weight every run keeps custody and stays consistent; without
    the raised window (base weight everywhere), 1-m/s burns make the runs inconsistent after the first apoapsis
    (the burns are in the truth and the NEES sees them); a bound below the hand-off error loses custody at once."""
    kw = dict(periods=2, cadence_hours=6.0, n_runs=3, seed=2)
    ok = cu.custody_study(em, nrho, policy=det.ACTIVE_POLICY, **kw)
    assert ok.custody.shape == (3, 2) and ok.kept_throughout and ok.worst_inconsistent_fraction == 0.0
    assert np.all((ok.burn_m_s >= 0.1) & (ok.burn_m_s <= 1.9))
    blind = cu.custody_study(em, nrho, policy=det.ACTIVE_POLICY, q_window_km2_s3=1e-18, **kw)
    assert not blind.inconsistent[:, 0].all() or blind.inconsistent[:, 1].all()
    assert blind.inconsistent[:, 1].all()
    tight = cu.custody_study(em, nrho, policy=det.QUIET_POLICY, half_angle_rad=1e-9, **kw)
    assert not tight.custody.any()
    assert "custody" in ok.report() and len(ok.report().splitlines()) == 2 + 2


def test_custody_is_cumulative_and_seeded(nrho):
    a = cu.custody_study(em, nrho, periods=2, cadence_hours=12.0, n_runs=2, seed=7, half_angle_rad=2e-5)
    b = cu.custody_study(em, nrho, periods=2, cadence_hours=12.0, n_runs=2, seed=7, half_angle_rad=2e-5)
    assert np.array_equal(a.burn_m_s, b.burn_m_s) and np.array_equal(a.nees_mean, b.nees_mean)
    assert np.all(a.custody[:, 1] <= a.custody[:, 0])  # once lost, never regained
    held = a.max_pointing_rad <= 2e-5
    assert np.array_equal(a.custody, np.cumprod(held, axis=1).astype(bool))


def _cost(sig, sec):
    c = np.array([12.0, 6.0, 2.0, 1.0])
    return cu.CadenceCost(c, np.array([13, 26, 78, 157]), np.array(sec), np.array(sig), np.ones(4), np.ones(4) * 6)


def test_elasticity_knee_of_the_cadence_cost():
    """The first definition (kept for comparison): steps with elasticity >= 1 from 12 h on."""
    # accuracy x 1/4 for cost x 2 (elasticity 2), then x 1/2 for x 1.5 (1.7), then x 0.9 for x 3 (0.1): knee 2 h
    c = _cost([8.0, 2.0, 1.0, 0.9], [1.0, 2.0, 3.0, 9.0])
    assert np.allclose(c.elasticity, [2.0, np.log(2) / np.log(1.5), -np.log(0.9) / np.log(3)])
    assert c.elasticity_knee_h == 2.0
    assert _cost([8.0, 7.0, 1.0, 0.9], [1.0, 2.0, 3.0, 9.0]).elasticity_knee_h == 12.0  # first step already too dear
    assert _cost([8.0, 4.0, 2.0, 1.0], [1.0, 1.5, 2.0, 2.5]).elasticity_knee_h == 1.0  # every step pays
    assert _cost([8.0, 4.0, 2.0, 1.0], [1.0, 1.0, 2.0, 2.5]).elasticity_knee_h == 1.0  # accuracy for free pays
    assert _cost([8.0, 4.0, 2.0, 1.0], [1.0, 0.9, 1.5, 1.8]).elasticity_knee_h == 1.0  # cheaper and better too
    assert _cost([8.0, 8.0, 2.0, 1.0], [1.0, 1.0, 2.0, 2.5]).elasticity_knee_h == 12.0  # no gain, no cost: no gain
    assert np.allclose(c.cost_ratio(), [1 / 3, 2 / 3, 1.0, 3.0])


def test_chord_knee_of_the_cadence_cost():
    """The row's knee: the cadence deepest below the chord of log(3-sigma) against log(run time)."""
    # log C = 0, 1, 2, 3 and log A = 0, -1, -2.2, -2.5: chord log A = -2.5/3 log C, depths 0, 1/6, 2.2 - 5/3, 0
    e = np.exp
    c = _cost(e([0.0, -1.0, -2.2, -2.5]), e([0.0, 1.0, 2.0, 3.0]))
    assert np.allclose(c.chord_depth, [0.0, 1 - 2.5 / 3, 2.2 - 5 / 3, 0.0])
    assert c.has_knee and c.knee_h == 2.0  # a sweet spot at 2 h
    # the same run times with most of the gain in the first step: the bend moves to 6 h (outside the 1-4 h band)
    b = _cost(e([0.0, -1.5, -2.0, -2.5]), e([0.0, 1.0, 2.0, 3.0]))
    assert np.allclose(b.chord_depth, [0.0, 1.5 - 2.5 / 3, 2.0 - 5 / 3, 0.0]) and b.knee_h == 6.0
    # gains accelerating at the dense end (the curve above its chord): no knee, reported at the sparsest cadence
    u = _cost(e([0.0, -0.2, -0.5, -2.5]), e([0.0, 1.0, 2.0, 3.0]))
    assert np.all(u.chord_depth <= 0) and not u.has_knee and u.knee_h == 12.0
    # a knee is a property of the curve, not of its units: scaling the seconds or the kilometres does not move it
    assert _cost(7 * e([0.0, -1.0, -2.2, -2.5]), 0.01 * e([0.0, 1.0, 2.0, 3.0])).knee_h == 2.0
    two = cu.CadenceCost(np.array([12.0, 6.0]), np.array([13, 26]), np.array([1.0, 2.0]), np.array([2.0, 1.5]),
                         np.ones(2), np.ones(2) * 6)
    assert not two.has_knee and two.knee_h == 12.0  # two cadences have no interior point


def test_cadence_cost_study_small(nrho):
    c = cu.cadence_cost_study(em, nrho, [6.0, 12.0], 1e-20, repeats=1)
    assert list(c.cadences_h) == [12.0, 6.0]
    assert list(c.updates) == [13, 26]
    assert np.all(c.seconds > 0) and c.sigma3_km[1] < c.sigma3_km[0]
    assert np.all(np.abs(c.nees_mean - 6) < 6)
    assert "knee" in c.report()


@pytest.mark.parametrize("call, exc", [
    (lambda pb: cu.covariance_filter(pb, np.zeros((1, pb.t.size, 4)), np.zeros((1, 6)), form="info"), ValueError),
    (lambda pb: cu.covariance_filter("pb", np.zeros((1, 2, 4)), np.zeros((1, 6))), TypeError),
    (lambda pb: cu.custody_study(em, orbits.nrho_9_2(em), periods=0), ValueError),
    (lambda pb: cu.custody_study(em, orbits.nrho_9_2(em), policy="quiet"), TypeError),
    (lambda pb: cu.cadence_cost_study(em, orbits.nrho_9_2(em), [2.0], 1e-20), ValueError),
    (lambda pb: cu.linear_problem(em, orbits.nrho_9_2(em), gap_hours=-1.0), ValueError),
])
def test_refusals_name_the_argument_and_pickle(small_problem, call, exc):
    with pytest.raises(exc) as info:
        call(small_problem)
    assert type(pickle.loads(pickle.dumps(info.value))) is type(info.value)


def test_claims_declared():
    assert set(CLAIMS) == {"custody_indefinite", "custody_consistent", "sri_stable", "relinearization_needed",
                           "cadence_sweet_spot"}
    assert CLAIMS["custody_consistent"].criterion.holds(0.10) and not CLAIMS["custody_consistent"].criterion.holds(0.11)
