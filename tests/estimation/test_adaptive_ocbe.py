"""Adaptive OCBE: the metric's three-term identity and chi-square law, the detection rule, the reset, batch = single."""

import pickle
from types import SimpleNamespace

import numpy as np
import pytest
from scipy import stats
from scipy.integrate import simpson

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.estimation import adaptive_ocbe as ad
from cislunar.estimation import consistency, ocbe, srif
from cislunar.papers.greaves_scheeres_2021 import detection as det
from cislunar.papers.greaves_scheeres_2021 import panels, tracking
from cislunar.sensing import measurements


def _random_spd(rng, n, scale=1.0):
    A = rng.standard_normal((n, n))
    return scale * (A @ A.T + n * np.eye(n))


# ---------------------------------------------------------------------------------------------------------------
# The metric: identity and law
# ---------------------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("m", [2, 4, 7])
def test_metric_terms_sum_to_the_whitened_innovation(m):
    rng = np.random.default_rng(m)
    for _ in range(20):
        P, Q, R = _random_spd(rng, 6), _random_spd(rng, 6, 0.1), _random_spd(rng, m, 0.01)
        Phi = np.eye(6) + 0.3 * rng.standard_normal((6, 6))
        H = rng.standard_normal((m, 6))
        dy = rng.standard_normal(m) * 3
        S = srif.sri_from_covariance(np.zeros(6), P)[0]
        mt = ad.metric_terms(S, Phi, Q, H, dy, R)
        C = H @ (Phi @ P @ Phi.T + Q) @ H.T + R
        nis = dy @ np.linalg.solve(C, dy)
        assert mt.total == pytest.approx(nis, rel=1e-9)
        assert mt.innovation == pytest.approx(nis, rel=1e-9)
        assert min(mt.prior, mt.control, mt.measurement) >= 0
        # the minimiser: delta and w are the joint least-squares solution (gradient of the cost vanishes)
        Pinv, Qinv, Rinv = np.linalg.inv(P), np.linalg.inv(Q), np.linalg.inv(R)
        r = dy - H @ (Phi @ mt.delta + mt.w)
        assert np.allclose(Pinv @ mt.delta - Phi.T @ H.T @ Rinv @ r, 0, atol=1e-8 * np.abs(Pinv @ mt.delta).max())
        assert np.allclose(Qinv @ mt.w - H.T @ Rinv @ r, 0, atol=1e-8 * np.abs(Qinv @ mt.w).max())


def test_control_term_is_the_control_energy_of_the_ocbe():
    """w^T Q^{-1} w = int u^T Qt^{-1} u dt for u = -q B^T Phi_pp p, p = Phi_xp^{-1} w (Eq. 32), on the 9:2 NRHO."""
    o = orbits.nrho_9_2(em)
    q = 1e-6
    grid = np.linspace(0.3, 0.3 + 2 * 3600 / em.time_unit_s, 201)
    x0 = tracking.simulate_truth(em, o.x0, [0.0, 0.3])[-1]
    tr = ocbe.ocbe_transition(em, x0, grid, q)
    Q = ocbe.ocbe_process_noise(tr.phi[-1])
    rng = np.random.default_rng(3)
    for _ in range(3):
        w = np.linalg.cholesky(Q) @ rng.standard_normal(6)
        p = np.linalg.solve(tr.phi_xp[-1], w)
        u = ocbe.estimated_control(q, tr.phi_pp, p)
        energy = simpson(np.sum(u**2, axis=-1) / q, x=grid)
        assert energy == pytest.approx(w @ np.linalg.solve(Q, w), rel=1e-7)


def _linear_run(rng, N=600, n=6, m=4):
    """A linear time-varying system with Gaussian noise of exactly the assumed covariances, SRI-filtered."""
    P0 = np.diag([1.0, 1, 1, 0.1, 0.1, 0.1])
    Phis, Qs, Hs, Rs, ys = [], [], [], [], []
    x = rng.multivariate_normal(np.zeros(n), P0)
    x0_est = np.zeros(n)
    for k in range(N):
        if k:
            dt = 0.1 + 0.05 * np.sin(k)
            Phi = np.eye(n)
            Phi[:3, 3:] = dt * np.eye(3)
            Phi[3:, :3] = -0.2 * dt * np.eye(3)
            Q = np.diag([dt**3 / 3] * 3 + [dt] * 3) * 1e-2
            Q[:3, 3:] = Q[3:, :3] = np.eye(3) * dt**2 / 2 * 1e-2
            x = Phi @ x + rng.multivariate_normal(np.zeros(n), Q)
            Phis.append(Phi)
            Qs.append(Q)
        H = rng.standard_normal((m, n))
        R = np.diag(rng.uniform(0.01, 0.1, m))
        ys.append(H @ x + rng.multivariate_normal(np.zeros(m), R))
        Hs.append(H)
        Rs.append(R)
    res = srif.filter_smoother(x0_est, P0, np.array(Phis), Hs, ys, Rs, [np.eye(n)] * (N - 1), Qs, smooth=False)
    return res, Phis, Qs, Hs, Rs, ys


def test_metric_law_is_chi_square_m_kolmogorov_smirnov():
    m = 4
    res, Phis, Qs, Hs, Rs, ys = _linear_run(np.random.default_rng(20261122), m=m)
    # the package's metric of the run (forward_metric reads the whitened innovation norms; the model only sets m)
    metric, dof = ad.forward_metric(SimpleNamespace(residual_norms=res.residuals), measurements.ANGLES_AND_RATES)
    assert np.all(dof == m) and np.array_equal(metric, res.residuals**2)
    # the three-term form gives the same numbers (checked at a sample of epochs)
    for k in range(1, 600, 97):
        S = srif.sri_from_covariance(np.zeros(6), res.P_filt[k - 1])[0]
        dy = ys[k] - Hs[k] @ res.x_pred[k]
        assert ad.metric_terms(S, Phis[k - 1], Qs[k - 1], Hs[k], dy, Rs[k]).total == pytest.approx(metric[k],
                                                                                                     rel=1e-7)
    assert stats.kstest(metric, ad.metric_law(m).cdf).pvalue > 0.01
    # the test has power against the nearby wrong laws (one dof more or less, a factor of two)
    assert stats.kstest(metric, stats.chi2(m + 1).cdf).pvalue < 1e-3
    assert stats.kstest(metric, stats.chi2(m - 1).cdf).pvalue < 1e-3
    assert stats.kstest(metric / 2, ad.metric_law(m).cdf).pvalue < 1e-3
    # the 99 % limit is exceeded about 1 % of the time (binomial, 4 sigma)
    frac = np.mean(metric > ad.metric_limit(m))
    assert abs(frac - 0.01) < 4 * np.sqrt(0.01 * 0.99 / metric.size)


def test_metric_limit_values():
    assert ad.metric_limit(4) == pytest.approx(13.2767, abs=1e-4)
    assert ad.metric_limit(2) == pytest.approx(9.2103, abs=1e-4)
    lim = ad.metric_limit(np.array([4, 0, 2]))
    assert np.isnan(lim[1]) and lim[0] == pytest.approx(13.2767, abs=1e-4)
    with pytest.raises(ValueError, match="probability"):
        ad.metric_limit(4, 1.0)
    with pytest.raises(ValueError, match="dof"):
        ad.metric_limit(-1)


# ---------------------------------------------------------------------------------------------------------------
# The detection rule
# ---------------------------------------------------------------------------------------------------------------
def test_three_consecutive_epochs_dated_to_the_first():
    L = 10.0
    m = np.array([1, 20, 20, 1, 20, 20, 20, 20, 1.0])
    assert ad.first_detection(m, L) == 4
    assert ad.first_detection(m, L, start=5) == 5
    assert ad.first_detection(m, L, start=6) is None  # 20, 20 then 1: only two
    assert ad.first_detection(m, L, consecutive=2) == 1
    assert ad.first_detection(np.array([1, 20, np.nan, 20, 20]), L) is None  # NaN breaks a run
    assert ad.first_detection(np.array([20, 20, 20, 1.0]), L, start=0) == 0
    assert ad.first_detection(np.array([20, 20, 20, 1.0]), L, start=1) is None  # epoch 0 excluded by default
    assert ad.first_detection(np.array([1, 1, 20, 20.0]), L) is None  # an open run at the end is no detection
    assert ad.first_detection(np.array([1, 10, 20, 20, 20.0]), L) == 2  # strictly above the limit


# ---------------------------------------------------------------------------------------------------------------
# The adaptive filter on the paper's scenario (9:2 NRHO, start at periapsis, L2 observer, 2 h)
# ---------------------------------------------------------------------------------------------------------------
Q_BASE_KM2_S3 = 1e-18


@pytest.fixture(scope="module")
def setup():
    return det.make_setup(em, orbits.nrho_9_2(em), Q_BASE_KM2_S3, Q_BASE_KM2_S3)


def _adaptive(setup, inputs, **kw):
    sc = setup.scenario
    return ad.adaptive_ocbe(em, sc.t, inputs.y, setup.observer_states, sc.model, sc.meas_cov, inputs.x0, inputs.P0,
                            setup.control_weight, **kw)


def test_no_maneuver_never_resets(setup):
    """Three fixed seeds: no reset, and the metric behaves like chi2(4) (mean, exceedance rate).

    Deterministic (fixed seeds).  Under the derived law a false reset has probability < 1e-4 per track, single
    exceedances 1 %; a mis-scaled metric (e.g. twice the cost, or a wrong dof) fails the mean or the rate check.
    """
    pooled = []
    for seed in (1, 2, 3):
        inp = det.draw_trial(np.random.default_rng(seed), setup, None)
        a = _adaptive(setup, inp, smooth=False)
        assert a.detections == () and a.passes == 1
        assert np.array_equal(a.control_weight, setup.control_weight)
        assert np.all(a.dof == 4)
        pooled.append(a.metric)
    pooled = np.concatenate(pooled)
    assert abs(pooled.mean() - 4.0) < 4 * np.sqrt(8.0 / pooled.size)
    assert np.mean(pooled > ad.metric_limit(4)) < 0.04
    assert stats.kstest(pooled, ad.metric_law(4).cdf).pvalue > 1e-3


@pytest.fixture(scope="module")
def big_burn(setup):
    inp = det.draw_trial(np.random.default_rng(1), setup, magnitude_m_s=3.0)
    return inp, _adaptive(setup, inp)


def test_large_maneuver_detected_within_three_epochs(setup, big_burn):
    inp, a = big_burn
    k_burn = int(np.searchsorted(setup.scenario.t, setup.t_maneuver, side="right"))  # first epoch after the burn
    assert len(a.detections) >= 1
    d = a.detections[0]
    assert k_burn <= d.epoch <= k_burn + 2
    assert d.declared_epoch == d.epoch + 2
    assert d.metric_before > ad.metric_limit(4)
    assert d.metric_after == pytest.approx(4.0, rel=1e-6)  # the reset sets the metric to its mean
    assert a.metric[d.epoch] == pytest.approx(4.0, rel=1e-6)
    assert d.factor > 1e4  # a 3 m/s burn against a ~0.1 mm/s ballistic tuning
    assert a.control_weight[d.epoch - 1] == pytest.approx(setup.control_weight[d.epoch - 1] * d.factor)
    assert a.passes == len(a.detections) + 1
    assert np.array_equal(a.metric[:d.epoch], a.metric_first_pass[:d.epoch])  # the past is untouched


def test_reset_restores_nees_consistency(setup, big_burn):
    from scipy.stats import chi2

    inp, a = big_burn
    k = a.detections[0].epoch
    lim = chi2.ppf(consistency.NEES_PROBABILITY, 6)
    after = slice(k, None)
    n_f = consistency.nees(a.result.x_filt, a.result.P_filt, inp.truth)
    n_s = consistency.nees(a.result.x_smooth, a.result.P_smooth, inp.truth)
    assert np.mean(n_f[after] > lim) <= tracking.DIVERGED_FRACTION
    assert np.mean(n_s > lim) <= tracking.DIVERGED_FRACTION
    # the same data through the non-adaptive filter: inconsistent after the burn (so this test can fail)
    sc = setup.scenario
    plain = ocbe.ocbe_filter_smoother(em, sc.t, inp.y, setup.observer_states, sc.model, sc.meas_cov, inp.x0, inp.P0,
                                      setup.control_weight, smooth=False)
    assert np.mean(consistency.nees(plain.x_filt, plain.P_filt, inp.truth)[after] > lim) > 0.5


def test_batched_adaptive_equals_single_trial(setup):
    sc = setup.scenario
    inputs = [det.draw_trial(np.random.default_rng(7), setup, magnitude_m_s=3.0),
              det.draw_trial(np.random.default_rng(8), setup, None)]
    res, q, metric, dets = ad.adaptive_ocbe_batch(em, sc.t, np.array([i.y for i in inputs]), setup.observer_states,
                                                  sc.model, sc.meas_cov, np.array([i.x0 for i in inputs]),
                                                  inputs[0].P0, setup.control_weight)
    assert len(dets[0]) >= 1 and dets[1] == ()
    for b, inp in enumerate(inputs):
        one = _adaptive(setup, inp)
        assert [d.epoch for d in dets[b]] == [d.epoch for d in one.detections]
        for d1, d2 in zip(dets[b], one.detections):
            assert d1.factor == pytest.approx(d2.factor, rel=1e-7)
        assert np.allclose(q[b], one.control_weight, rtol=1e-7, atol=0)
        assert np.allclose(metric[b], one.metric, rtol=1e-6, atol=1e-9)
        assert np.max(np.abs(res.x_filt[b] - one.result.x_filt)) < 1e-9 * np.max(np.abs(one.result.x_filt))
        assert np.max(np.abs(res.x_smooth[b] - one.result.x_smooth)) < 1e-9 * np.max(np.abs(one.result.x_smooth))


def _two_burns(setup, seed, magnitudes=(3.0, 30.0)):
    """Burns at apoapsis and in the next interval (random pointing): truth, measurements, hand-off."""
    sc = setup.scenario
    rng = np.random.default_rng(seed)
    k = int(np.searchsorted(sc.t, setup.t_maneuver, side="right"))
    dv = [det.pointing_vector(*det.StationKeepingPolicy.sample_pointing(rng)) * m * 1e-3 / em.velocity_unit_km_s
          for m in magnitudes]
    truth = tracking.simulate_truth(em, sc.x_start, sc.t, [(setup.t_maneuver, dv[0]),
                                                          (0.5 * (sc.t[k] + sc.t[k + 1]), dv[1])])
    y = tracking.simulate_measurements(sc, truth, rng)[:, 0]
    x0, P0 = tracking.initial_estimate(em, truth[0], rng)
    return k, y, x0, P0


@pytest.mark.parametrize("reset", ad.RESET_RULES)
def test_burns_in_consecutive_intervals_are_dated_to_consecutive_epochs(setup, reset):
    """After a reset at epoch k the search resumes at k + 1: a second, larger burn in the next interval is dated
    to k + 1 (not k + 2), by the single-trial and the batched adaptive filter alike."""
    sc = setup.scenario
    runs = [_two_burns(setup, seed) for seed in (0, 2)]
    for k, y, x0, P0 in runs:
        a = ad.adaptive_ocbe(em, sc.t, y, setup.observer_states, sc.model, sc.meas_cov, x0, P0,
                             setup.control_weight, reset=reset, smooth=False)
        assert [d.epoch for d in a.detections] == [k, k + 1]
        assert a.control_weight[k - 1] > 1e4 * setup.control_weight[k - 1]
        assert a.control_weight[k] > 1e4 * setup.control_weight[k]
    _, _, _, dets = ad.adaptive_ocbe_batch(em, sc.t, np.array([r[1] for r in runs]), setup.observer_states, sc.model,
                                           sc.meas_cov, np.array([r[2] for r in runs]), runs[0][3],
                                           setup.control_weight, reset=reset)
    assert [[d.epoch for d in dd] for dd in dets] == [[r[0], r[0] + 1] for r in runs]


def test_first_pass_detections_match_the_adaptive_filter(setup):
    """The batched first-pass detection epoch is the adaptive filter's first detection, whatever the reset rule."""
    sc = setup.scenario
    inputs = [det.draw_trial(np.random.default_rng(s), setup, magnitude_m_s=m)
              for s, m in ((11, 3.0), (12, None), (13, 0.3), (14, 0.05))]
    epochs = ad.first_pass_detections(em, sc.t, np.array([i.y for i in inputs]), setup.observer_states, sc.model,
                                      sc.meas_cov, np.array([i.x0 for i in inputs]), inputs[0].P0,
                                      setup.control_weight)
    assert epochs.dtype.kind == "i" and epochs.shape == (4,)
    assert epochs[1] == -1 and epochs[0] > 0  # no burn: none; 3 m/s: detected
    for e, inp in zip(epochs, inputs):
        for reset in ad.RESET_RULES:
            a = _adaptive(setup, inp, reset=reset, smooth=False)
            assert e == (a.detections[0].epoch if a.detections else -1)
    # a stricter rule (more consecutive epochs) never detects earlier
    later = ad.first_pass_detections(em, sc.t, np.array([i.y for i in inputs]), setup.observer_states, sc.model,
                                     sc.meas_cov, np.array([i.x0 for i in inputs]), inputs[0].P0,
                                     setup.control_weight, consecutive=5)
    assert all(lt == -1 or (e != -1 and lt >= e) for e, lt in zip(epochs, later))


def test_reset_factor_consistency_and_errors(setup, big_burn):
    inp, a = big_burn
    sc = setup.scenario
    d = a.detections[0]
    first = ocbe.ocbe_filter_smoother(em, sc.t, inp.y, setup.observer_states, sc.model, sc.meas_cov, inp.x0,
                                      inp.P0, setup.control_weight, smooth=False)
    k = d.epoch
    factor, m1 = ad.reset_factor(em, sc.t, k, first.x_filt[k - 1], first.P_filt[k - 1], inp.y[k],
                                 setup.observer_states[k], sc.model, sc.meas_cov, setup.control_weight[k - 1])
    assert m1 == pytest.approx(first.residual_norms[k] ** 2, rel=1e-6)  # the run's metric, recomputed
    assert factor == pytest.approx(d.factor, rel=1e-9)
    with pytest.raises(ad.ResetError) as err:
        ad.reset_factor(em, sc.t, k, first.x_filt[k - 1], first.P_filt[k - 1], inp.y[k], setup.observer_states[k],
                        sc.model, sc.meas_cov, setup.control_weight[k - 1], max_factor=10.0)
    e2 = pickle.loads(pickle.dumps(err.value))
    assert (e2.epoch, e2.reason) == (err.value.epoch, err.value.reason)
    with pytest.raises(ValueError, match="k"):
        ad.reset_factor(em, sc.t, 0, first.x_filt[0], first.P_filt[0], inp.y[1], setup.observer_states[1],
                        sc.model, sc.meas_cov, 1.0)


def test_likelihood_reset_is_stationary_and_avoids_the_mean_rule_blow_up():
    """1 m/s burn whose angle-rate noise alone exceeds the mean: the mean rule needs alpha ~ 1e14, ML ~ 1e7-1e8."""
    s = det.make_setup(em, orbits.nrho_9_2(em), Q_BASE_KM2_S3, Q_BASE_KM2_S3, periods=1.5)
    sc = s.scenario
    inp = det.draw_trial(np.random.default_rng(100), s, magnitude_m_s=1.0)
    run = ocbe.ocbe_filter_smoother(em, sc.t, inp.y, s.observer_states, sc.model, sc.meas_cov, inp.x0, inp.P0,
                                    s.control_weight, smooth=False)
    metric, dof = ad.forward_metric(run, sc.model)
    k = ad.first_detection(metric, ad.metric_limit(dof))
    assert k == 40
    args = (em, sc.t, k, run.x_filt[k - 1], run.P_filt[k - 1], inp.y[k], s.observer_states[k], sc.model,
            sc.meas_cov, s.control_weight[k - 1])
    f_mean, _ = ad.reset_factor(*args, rule="mean")
    f_ml, _ = ad.reset_factor(*args, rule="likelihood")
    assert f_mean > 1e4 * f_ml and 1e6 < f_ml < 1e9
    # stationarity of the innovation likelihood at f_ml (covariance form, independent of the SRI code)
    grid = np.linspace(sc.t[k - 1], sc.t[k], 9)
    tr = ocbe.ocbe_transition(em, run.x_filt[k - 1], grid, s.control_weight[k - 1])
    Phi, Q = tr.phi[-1, :6, :6], ocbe.ocbe_process_noise(tr.phi[-1])
    val, _, Ht = sc.model.evaluate(s.observer_states[k][None], tr.x[-1])
    dy = sc.model.residual(inp.y[k][None], val).reshape(-1)
    H = Ht.reshape(-1, 6)

    def nll(a):
        C = H @ (Phi @ run.P_filt[k - 1] @ Phi.T + a * Q) @ H.T + sc.meas_cov
        return np.linalg.slogdet(C)[1] + dy @ np.linalg.solve(C, dy)

    for a in (f_ml * 0.7, f_ml * 1.4):
        assert nll(a) > nll(f_ml)
    with pytest.raises(ValueError, match="rule"):
        ad.reset_factor(*args, rule="median")


def test_smoothed_costs_sum_to_the_forward_metrics():
    """Batch least-squares minimum = sum of squared innovations: linear system exactly, the OCBE on the NRHO closely."""
    rng = np.random.default_rng(4)
    res, Phis, Qs, Hs, Rs, ys = _linear_run(rng, N=60)
    sm = srif.filter_smoother(np.zeros(6), np.diag([1.0, 1, 1, 0.1, 0.1, 0.1]), np.array(Phis), Hs, ys, Rs,
                              [np.eye(6)] * 59, Qs, smooth=True)
    x = sm.x_smooth
    total = float(x[0] @ np.linalg.solve(np.diag([1.0, 1, 1, 0.1, 0.1, 0.1]), x[0]))
    for k in range(60):
        r = ys[k] - Hs[k] @ x[k]
        total += r @ np.linalg.solve(Rs[k], r)
        if k:
            w = x[k] - Phis[k - 1] @ x[k - 1]
            total += w @ np.linalg.solve(Qs[k - 1], w)
    assert total == pytest.approx(np.sum(sm.residuals**2), rel=1e-8)


def test_smoothed_metric_on_the_ocbe(setup):
    sc = setup.scenario
    inp = det.draw_trial(np.random.default_rng(5), setup, None)
    a = _adaptive(setup, inp)
    assert a.smoothed_metric.shape == a.metric.shape and np.all(a.smoothed_metric >= 0)
    # the smoothed costs redistribute the forward ones: equal sums up to linearisation and quadrature
    assert np.sum(a.smoothed_metric) == pytest.approx(np.sum(a.metric), rel=0.02)
    with pytest.raises(ValueError, match="smooth=True"):
        plain = ocbe.ocbe_filter_smoother(em, sc.t[:5], inp.y[:5], setup.observer_states[:5], sc.model,
                                          sc.meas_cov, inp.x0, inp.P0, 1e-6, smooth=False)
        ad.smoothed_metric(plain, inp.y[:5], setup.observer_states[:5], sc.model, sc.meas_cov, 1e-6)


def test_bad_arguments_are_named(setup):
    sc = setup.scenario
    inp = det.draw_trial(np.random.default_rng(9), setup, None)
    args = (em, sc.t, inp.y, setup.observer_states, sc.model, sc.meas_cov, inp.x0, inp.P0, setup.control_weight)
    with pytest.raises(ValueError, match="reset"):
        ad.adaptive_ocbe(*args, reset="median")
    with pytest.raises(ValueError, match="consecutive"):
        ad.adaptive_ocbe(*args, consecutive=0)
    with pytest.raises(ValueError, match="available"):
        ad.adaptive_ocbe(*args, available=np.ones((3, 1), bool))
    with pytest.raises(ValueError, match="control_weight"):
        ad.adaptive_ocbe(*args[:-1], -1.0)


# ---------------------------------------------------------------------------------------------------------------
# The figure panels (Figs. 6-13)
# ---------------------------------------------------------------------------------------------------------------
def test_panel_series_matches_the_run(setup, big_burn):
    """Every panel is the run's quantity in display units: errors, 3-sigma, NEES, control, both metrics."""
    inp, a = big_burn
    sc = setup.scenario
    p = panels.panel_series(em, a.result, inp.truth, a.control_weight, inp.y, setup.observer_states, sc.model,
                        sc.meas_cov)
    r = a.result
    L, V = em.length_unit_km, em.velocity_unit_km_s * 1e3
    assert np.allclose(p.t_days * 86400, r.t * em.time_unit_s)
    assert np.allclose(p.position_error_km[1], np.linalg.norm(r.x_smooth[:, :3] - inp.truth[:, :3], axis=1) * L)
    assert np.allclose(p.velocity_error_m_s[0], np.linalg.norm(r.x_filt[:, 3:] - inp.truth[:, 3:], axis=1) * V)
    # 3-sigma of the norm bound: 3 sqrt(trace P) (position block of the filter at the last epoch)
    assert p.position_3sigma_km[0, -1] == pytest.approx(3 * np.sqrt(np.trace(r.P_filt[-1, :3, :3])) * L)
    assert np.allclose(p.nees[0], consistency.nees(r.x_filt, r.P_filt, inp.truth))
    acc = em.length_unit_km * 1e3 / em.time_unit_s**2
    assert np.allclose(p.control_norm_m_s2[1], np.linalg.norm(r.control_smooth, axis=-1) * acc)
    assert np.allclose(p.metric[0], a.metric, equal_nan=True)
    assert np.allclose(p.metric[1], a.smoothed_metric)
    assert np.allclose(p.normalized_metric[0] * p.limit, a.metric)
    assert np.allclose(p.mean_line, 4 / stats.chi2.ppf(0.99, 4))
    # the 3 m/s burn stands out in both passes' control at the burn (Fig. 7)
    c = p.spike_contrast(setup.t_maneuver * em.time_unit_days)
    assert np.all(c > 10)


def test_spike_contrast_of_a_known_spike():
    """Mean norm near the burn over the mean elsewhere: values 1, 1, 4 elsewhere (mean 2, median 1, max 4)."""
    t_sub = np.arange(150.0).reshape(30, 5) * 0.1
    u = np.zeros((2,) + t_sub.shape)
    u[:] = np.array([1.0, 1.0, 4.0] * 50).reshape(30, 5)
    near = (t_sub >= 7.0) & (t_sub <= 8.0)  # 11 points
    u[1][near] = 50.0
    u[0][near] = 2.0 * u[0][near] / u[0][near].mean()  # forward: mean 2 near, as elsewhere
    z = np.zeros((2, 30))
    p = panels.PanelSeries(t_sub[:, 0], t_sub, z, z, z, z, u, z, np.ones(30), np.full(30, 4), z)
    elsewhere_mean = (1.0 * 2 + 4.0) / 3
    assert np.isclose(u[1][~near].mean(), elsewhere_mean, rtol=0.02)
    c = p.spike_contrast(7.5, 0.5)
    assert c[1] == pytest.approx(50.0 / u[1][~near].mean())
    assert c[0] == pytest.approx(1.0, rel=0.02)
    with pytest.raises(ValueError, match="t_days"):
        p.spike_contrast(100.0, 0.5)


def test_panel_figures_have_units_on_every_axis(setup, big_burn):
    from cislunar.publish.plotting import axis_label_problems

    inp, a = big_burn
    sc = setup.scenario
    p = panels.panel_series(em, a.result, inp.truth, a.control_weight, inp.y, setup.observer_states, sc.model,
                        sc.meas_cov)
    for fig in (panels.figure_errors(p, "t", burn_days=3.3, velocity_unit="mm/s"),
                panels.figure_control_metric(p, "t", detection_days=[3.3], first_pass_metric=a.metric_first_pass,
                                         first_pass_until=a.detections[0].declared_epoch)):
        assert axis_label_problems(fig) == []
        assert len(fig.axes) == 4


@pytest.mark.parametrize("max_resets", [1, 5])
def test_batched_adaptive_flagged_filter_only_equals_single_trial(setup, max_resets):
    """The batched adaptive filter in the mode of the reset-rule study (forward only, a reset rule per trial, failures
    flagged per trial, re-runs of only the trials with a new detection) equals the single-trial filter trial by
    trial: detections, factors, weights, metric and estimates; a trial whose reset fails (more than max_resets) is
    flagged at the epoch at which the single-trial filter raises, while the others go on."""
    sc = setup.scenario
    k2, y2, x02, P02 = _two_burns(setup, 0)  # two detections (k2, k2 + 1): fails with max_resets = 1
    burn = det.draw_trial(np.random.default_rng(7), setup, magnitude_m_s=3.0)
    quiet = det.draw_trial(np.random.default_rng(8), setup, None)
    cases = [(burn.y, burn.x0, burn.P0, "mean"), (burn.y, burn.x0, burn.P0, "likelihood"),
             (y2, x02, P02, "mean"), (quiet.y, quiet.x0, quiet.P0, "likelihood"), (y2, x02, P02, "likelihood")]
    res, q, metric, dets = ad.adaptive_ocbe_batch(
        em, sc.t, np.array([c[0] for c in cases]), setup.observer_states, sc.model, sc.meas_cov,
        np.array([c[1] for c in cases]), np.array([c[2] for c in cases]), setup.control_weight,
        reset=[c[3] for c in cases], max_resets=max_resets, smooth=False, on_failure="flag")
    assert res.x_smooth is None
    assert [len(d) for d in dets] == ([1, 1, 1, 0, 1] if max_resets == 1 else [1, 1, 2, 0, 2])
    assert list(res.failed) == [False, False, max_resets == 1, False, max_resets == 1]
    assert dets[0][0].factor != pytest.approx(dets[1][0].factor, rel=1e-3)  # the two rules differ on the same data
    for b, (yb, x0b, P0b, rule) in enumerate(cases):
        args = (em, sc.t, yb, setup.observer_states, sc.model, sc.meas_cov, x0b, P0b, setup.control_weight)
        kw = dict(reset=rule, max_resets=max_resets, smooth=False)
        if res.failed[b]:
            with pytest.raises(ad.ResetError) as err:
                ad.adaptive_ocbe(*args, **kw)
            assert err.value.epoch == k2 + 1 and res.failure_epoch[b] == k2 + 1 and "max_resets" in res.failure[b]
            assert [d.epoch for d in dets[b]] == [k2]
            assert np.all(np.isnan(res.x_filt[b])) and np.all(np.isnan(metric[b]))
            continue
        one = ad.adaptive_ocbe(*args, **kw)
        assert res.failure_epoch[b] == -1 and res.failure[b] == ""
        assert [d.epoch for d in dets[b]] == [d.epoch for d in one.detections]
        for d1, d2 in zip(dets[b], one.detections):
            assert d1.factor == pytest.approx(d2.factor, rel=1e-7)
            assert d1.metric_after == pytest.approx(d2.metric_after, rel=1e-6)
        assert np.allclose(q[b], one.control_weight, rtol=1e-7, atol=0)
        assert np.allclose(metric[b], one.metric, rtol=1e-6, atol=1e-9)
        assert np.max(np.abs(res.x_filt[b] - one.result.x_filt)) < 1e-9 * np.max(np.abs(one.result.x_filt))
        assert np.allclose(res.P_filt[b], one.result.P_filt, rtol=1e-6, atol=0)
    if max_resets == 1:  # on_failure="raise" stops the batch at the failing trial
        with pytest.raises(ad.ResetError, match="max_resets"):
            ad.adaptive_ocbe_batch(em, sc.t, np.array([c[0] for c in cases[:3]]), setup.observer_states, sc.model,
                                   sc.meas_cov, np.array([c[1] for c in cases[:3]]), P02, setup.control_weight,
                                   max_resets=1, smooth=False)
        with pytest.raises(ValueError, match="reset"):
            ad.adaptive_ocbe_batch(em, sc.t, np.array([c[0] for c in cases]), setup.observer_states, sc.model,
                                   sc.meas_cov, np.array([c[1] for c in cases]), P02, setup.control_weight,
                                   reset=["mean"] * 4)


# ---------------------------------------------------------------------------------------------------------------
# The state-covariance (inflation) reset
# ---------------------------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def informative_rates(setup):
    """The detection setup with rates differenced over 1 TU (informative rates) and a 3 m/s burn drawn with it."""
    import dataclasses

    sc = setup.scenario
    R = tracking.angles_rates_covariance(em, tracking.DEFAULT_SIGMA_ANGLE_RAD, rate_dt_s=em.time_unit_s)
    s1 = dataclasses.replace(setup, scenario=dataclasses.replace(sc, meas_cov=R))
    return s1, det.draw_trial(np.random.default_rng(1), s1, magnitude_m_s=3.0)


def test_inflation_reset_solves_for_the_state_covariance_and_restores_consistency(informative_rates):
    """A 3 m/s burn seen with informative rates: the filter without a reset is inconsistent after the burn; the
    inflation reset multiplies the predicted covariance by the beta that solves
    dy^T (beta H P^- H^T + R)^-1 dy = m (checked against that formula, independently of the SRI code), leaves the
    control weights and the past untouched, and the filter is then consistent (at most DIVERGED_FRACTION of the
    epochs from the reset on above the NEES 99.9 % quantile, final NEES inside its chi-square bounds).  Removing
    the inflation (beta = 1) fails the consistency checks; mis-scaling it (beta x 10 or / 10) fails the metric one."""
    s1, inp = informative_rates
    sc = s1.scenario
    a = _adaptive(s1, inp, reset="inflate", smooth=False)
    plain = ocbe.ocbe_filter_smoother(em, sc.t, inp.y, s1.observer_states, sc.model, sc.meas_cov, inp.x0, inp.P0,
                                      s1.control_weight, smooth=False)
    lo, hi = stats.chi2.ppf([0.0005, consistency.NEES_PROBABILITY], 6)
    d = a.detections[0]
    k = d.epoch
    n_plain = consistency.nees(plain.x_filt, plain.P_filt, inp.truth)
    assert np.mean(n_plain[k:] > hi) > 0.5  # no reset: inconsistent (so the checks below can fail)
    # beta from the innovation covariance of the first pass (an independent formula)
    tr = ocbe.ocbe_transition(em, plain.x_filt[k - 1], np.linspace(sc.t[k - 1], sc.t[k], 9), s1.control_weight[k - 1])
    Phi, Q = tr.phi[-1, :6, :6], ocbe.ocbe_process_noise(tr.phi[-1])
    P_pred = Phi @ plain.P_filt[k - 1] @ Phi.T + Q
    val, _, H = sc.model.evaluate(s1.observer_states[k], tr.x[-1])
    dy = sc.model.residual(inp.y[k], val)
    metric_at = lambda beta: float(dy @ np.linalg.solve(beta * H @ P_pred @ H.T + sc.meas_cov, dy))  # noqa: E731
    assert d.factor > 10 and metric_at(1.0) == pytest.approx(d.metric_before, rel=1e-6)
    assert metric_at(d.factor) == pytest.approx(4.0, rel=1e-6)
    assert d.metric_after == pytest.approx(4.0, rel=1e-6) and a.metric[k] == pytest.approx(4.0, rel=1e-6)
    assert np.allclose(a.result.P_pred[k], d.factor * P_pred, rtol=1e-6)
    assert np.array_equal(a.control_weight, s1.control_weight)  # the control weights are not touched
    assert np.array_equal(a.result.x_filt[:k], plain.x_filt[:k])  # nor the past
    n_f = consistency.nees(a.result.x_filt, a.result.P_filt, inp.truth)
    assert np.mean(n_f[k:] > hi) <= tracking.DIVERGED_FRACTION
    assert lo < n_f[-1] < hi


def test_inflation_reset_batched_equals_single_trial_and_smoother_segments(setup, informative_rates):
    """The batched filter with reset="inflate" (restarts grouped by epoch) equals the single-trial one trial by
    trial, chains of inflations included; with smooth=True the smoothed estimates after the last restart are those of
    an OCBE run started there from the inflated prior."""
    s1, inp = informative_rates
    sc = setup.scenario
    burns = [det.draw_trial(np.random.default_rng(s), setup, magnitude_m_s=m) for s, m in ((1, 3.0), (9, 1.0))]
    quiet = det.draw_trial(np.random.default_rng(8), setup, None)
    failing = det.draw_trial(np.random.default_rng(7), setup, magnitude_m_s=3.0)  # its covariance turns singular
    cases = burns + [quiet, failing]
    res, q, metric, dets = ad.adaptive_ocbe_batch(em, sc.t, np.array([c.y for c in cases]), setup.observer_states,
                                                  sc.model, sc.meas_cov, np.array([c.x0 for c in cases]),
                                                  cases[0].P0, setup.control_weight, reset="inflate", smooth=False,
                                                  on_failure="flag")
    assert len(dets[0]) > 1 and dets[2] == ()  # a chain of inflations (1-s rates) and no false reset
    assert list(res.failed) == [False, False, False, True]
    with pytest.raises(ad.ResetError, match="singular") as err:
        _adaptive(setup, failing, reset="inflate", smooth=False)
    assert res.failure_epoch[3] == err.value.epoch and np.all(np.isnan(metric[3]))
    pickle.loads(pickle.dumps(err.value))
    for b, c in enumerate(cases[:3]):
        one = _adaptive(setup, c, reset="inflate", smooth=False)
        assert [d.epoch for d in dets[b]] == [d.epoch for d in one.detections]
        for d1, d2 in zip(dets[b], one.detections):
            assert d1.factor == pytest.approx(d2.factor, rel=1e-7)
        assert np.array_equal(q[b], one.control_weight)
        assert np.allclose(metric[b], one.metric, rtol=1e-6, atol=1e-9)
        assert np.max(np.abs(res.x_filt[b] - one.result.x_filt)) < 1e-9 * np.max(np.abs(one.result.x_filt))
    a = _adaptive(s1, inp, reset="inflate", smooth=True)
    k = a.detections[-1].epoch
    tail = ocbe.ocbe_filter_smoother(em, s1.scenario.t[k:], inp.y[k:], s1.observer_states[k:], s1.scenario.model,
                                     s1.scenario.meas_cov, a.result.x_pred[k], a.result.P_pred[k],
                                     s1.control_weight[k:], smooth=True)
    assert np.allclose(a.result.x_smooth[k:], tail.x_smooth, rtol=0, atol=1e-12)
    assert a.result.z_smooth == pytest.approx(float(ocbe._control_integral(a.result.t_sub, a.result.control_smooth)))
    with pytest.raises(ValueError, match="reset"):
        _adaptive(setup, quiet, reset="inflated")
