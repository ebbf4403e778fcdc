"""Mutual information: stacked matrices (Eqs. 19-23), dense Eq. 18 vs structured chain rule, gradient (Eqs. 44-52)."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from cislunar.cr3bp.dynamics import EARTH_MOON
from cislunar.sensing import covariance as C
from cislunar.sensing import information as I
from cislunar.sensing import measurements as M

TARGETS = np.array([[7.78717734e-1, 0, 0, 0, 5.55157488e-1, 0],
                    [7.81554639e-1, 0, 0, 0, 5.51070308e-1, 0]])
OBSERVER = np.array([7.80136159e-1, 0, 0, 0, 5.53104815e-1, 0])
DAY = float(EARTH_MOON.days_to_tu(1.0))


def _spd(rng, n, scale=1.0):
    A = rng.normal(size=(n, n))
    return scale * (A @ A.T / n + 0.2 * np.eye(n))


def random_system(seed, N=5, M=3, n=4, p=3, cond=1.0):
    """Random linear-Gaussian sequence and parameter derivatives of F and H."""
    rng = np.random.default_rng(seed)
    P0 = _spd(rng, n, cond)
    Q = np.stack([_spd(rng, n, 0.05) for _ in range(N - 1)]) if N > 1 else np.zeros((0, n, n))
    R = np.stack([_spd(rng, M, 0.3) for _ in range(N)])
    F = np.eye(n) + 0.3 * rng.normal(size=(N - 1, n, n))
    H = rng.normal(size=(N, M, n))
    dF = 0.2 * rng.normal(size=(N - 1, n, n, p))
    dH = rng.normal(size=(N, M, n, p))
    return P0, F, Q, H, R, dF, dH


def test_regularised_range_rate_jacobian_is_the_model_jacobian_with_rho_replaced_in_the_position_part(window):
    """Independent of the mask bookkeeping: rebuilt from the relative states, the range-rate row's position part
    is (dv - rdot u) / sqrt(rho^2 + rho_c^2) (observer +, target -); every other entry is lin.H's."""
    lin, _ = window
    rc = float(np.median(_window_ranges(lin)))
    H = I.regularised_range_rate_jacobian(lin, rc)
    assert H.shape == lin.H.shape
    for j in range(lin.targets.shape[0]):
        rel = lin.observer - lin.targets[j]  # (N, 6), observer minus target
        rho = np.linalg.norm(rel[:, :3], axis=1)
        u = rel[:, :3] / rho[:, None]
        rdot = np.sum(u * rel[:, 3:], axis=1)
        pos = (rel[:, 3:] - rdot[:, None] * u) / np.sqrt(rho**2 + rc**2)[:, None]
        c = 6 * (j + 1)
        np.testing.assert_allclose(H[:, 2 * j + 1, 0:3], pos, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(H[:, 2 * j + 1, c:c + 3], -pos, rtol=1e-12, atol=1e-15)
        # unregularised, the same rebuild with rho gives the model's row (the reference is right)
        np.testing.assert_allclose(lin.H[:, 2 * j + 1, 0:3], (rel[:, 3:] - rdot[:, None] * u) / rho[:, None],
                                   rtol=1e-12, atol=1e-15)
    changed = H != lin.H
    assert not changed[:, 0::2].any()  # range rows untouched
    assert not changed[:, 1::2, 3:6].any()  # velocity part untouched
    # a scale far below the ranges gives the model's Jacobians (to round-off), so the MI is the paper's
    tiny = I.regularised_range_rate_jacobian(lin, 1e-9 * float(_window_ranges(lin).min()))
    np.testing.assert_allclose(tiny, lin.H, rtol=1e-12, atol=0)


def test_regularised_range_rate_jacobian_derivative_matches_finite_differences(window):
    """dH of the regularised Jacobians against central differences of H (re-linearised), and the MI gradient
    through it against differences of the MI; dropping the factor's derivative is visibly wrong."""
    lin, R = window
    rc = float(np.median(_window_ranges(lin)))
    H, dH = I.regularised_range_rate_jacobian(lin, rc, derivatives=True)
    np.testing.assert_array_equal(H, I.regularised_range_rate_jacobian(lin, rc))
    kernel = I.InformationKernel(lin.P0, lin.Q, lin.R, lin.t.size)

    def lin_at(x):
        return C.linearize_augmented(EARTH_MOON, x, TARGETS, lin.t, M.RANGE_RANGE_RATE, R, lin.P0, Q=lin.Q)

    h = 1e-6
    fd_H = np.zeros_like(dH)
    fd_I = np.zeros(6)
    for j in range(6):
        e = np.zeros(6)
        e[j] = h
        lp, lm = lin_at(OBSERVER + e), lin_at(OBSERVER - e)
        fd_H[..., j] = (I.regularised_range_rate_jacobian(lp, rc)
                        - I.regularised_range_rate_jacobian(lm, rc)) / (2 * h)
        fd_I[j] = (kernel.value(lp.F, I.regularised_range_rate_jacobian(lp, rc))
                   - kernel.value(lm.F, I.regularised_range_rate_jacobian(lm, rc))) / (2 * h)
    np.testing.assert_allclose(dH, fd_H, rtol=1e-5, atol=1e-6 * np.abs(dH).max())
    val, grad = kernel.value_gradient(lin.F, H, lin.dF, dH)
    assert val == pytest.approx(kernel.value(lin.F, H), rel=1e-12)
    scale = np.max(np.abs(fd_I))
    np.testing.assert_allclose(grad, fd_I, rtol=1e-4, atol=1e-5 * scale)
    frozen = np.where(dH != lin.dH, lin.dH * I.range_noise_scale(lin, rc)[..., None, None], lin.dH)
    _, g_frozen = kernel.value_gradient(lin.F, H, lin.dF, frozen)
    assert np.max(np.abs(g_frozen - fd_I)) > 1e-3 * scale
    with pytest.raises(ValueError, match="range_scale"):
        I.regularised_range_rate_jacobian(lin, 0.0)
    with pytest.raises(TypeError, match="lin"):
        I.regularised_range_rate_jacobian(lin.H, rc)


@given(seed=st.integers(0, 2**32 - 1), N=st.integers(1, 7), M=st.integers(1, 4), n=st.integers(1, 6),
       logcond=st.floats(-3, 6))
def test_structured_equals_dense(seed, N, M, n, logcond):
    P0, F, Q, H, R, dF, dH = random_system(seed, N, M, n, 2, 10.0**logcond)
    dense = I.mutual_information_dense(P0, F, Q, H, R)
    total, terms = I.mutual_information(P0, F, Q, H, R, return_terms=True)
    assert total == pytest.approx(dense, rel=1e-10, abs=1e-12)
    assert np.all(terms >= -1e-14) and total == pytest.approx(np.sum(terms))
    i1, g1 = I.mutual_information_gradient(P0, F, Q, H, R, dF, dH)
    i2, g2 = I.mutual_information_gradient_dense(P0, F, Q, H, R, dF, dH)
    assert i1 == pytest.approx(dense, rel=1e-10, abs=1e-12) and i2 == pytest.approx(dense, rel=1e-10, abs=1e-12)
    np.testing.assert_allclose(g1, g2, rtol=1e-7, atol=1e-8 * max(1.0, np.max(np.abs(g2))))


def test_stacked_matrices_structure():
    P0, F, Q, H, R, _, _ = random_system(0, N=4, M=2, n=3)
    Pt, Ht, Rt = I.stacked_matrices(P0, F, Q, H, R)
    assert Pt.shape == (12, 12) and Ht.shape == (8, 12) and Rt.shape == (8, 8)
    np.testing.assert_array_equal(Pt[3:6, 3:6], Q[0])  # Eq. 19
    np.testing.assert_allclose(Ht[6:8, 0:3], H[3] @ F[2] @ F[1] @ F[0])  # Eq. 20, H_3 Phi(t3, t0)
    np.testing.assert_allclose(Ht[6:8, 6:9], H[3] @ F[2])  # H_3 Phi(t3, t2): column of w_2 (noise added at t2)
    np.testing.assert_allclose(Ht[6:8, 9:12], H[3])  # diagonal block H_3
    np.testing.assert_array_equal(Ht[2:4, 6:12], 0.0)  # block lower triangular
    np.testing.assert_array_equal(Rt[4:6, 4:6], R[2])  # Eq. 23


def test_single_measurement_closed_form_and_monotonicity():
    rng = np.random.default_rng(3)
    P0, H, R = _spd(rng, 4), rng.normal(size=(1, 2, 4)), _spd(rng, 2)[None]
    ref = 0.5 * np.log(np.linalg.det(np.eye(2) + np.linalg.solve(R[0], H[0] @ P0 @ H[0].T)))
    assert I.mutual_information(P0, np.zeros((0, 4, 4)), np.zeros((0, 4, 4)), H, R) == pytest.approx(ref, rel=1e-12)
    # noisier measurements carry less information; more measurements carry more
    P0, F, Q, H, R, _, _ = random_system(4, N=6)
    base = I.mutual_information(P0, F, Q, H, R)
    assert I.mutual_information(P0, F, Q, H, 4 * R) < base
    assert I.mutual_information(P0, F[:-1], Q[:-1], H[:-1], R[:-1]) < base


def test_mutual_information_matches_monte_carlo_expected_kl():
    """Eq. 11: I(X;Y) = E_X[KL(p(Y|X) || p(Y))]; sampled estimate within three standard errors (seeded)."""
    P0, F, Q, H, R, _, _ = random_system(11, N=3, M=2, n=3)
    exact = I.mutual_information_dense(P0, F, Q, H, R)
    est, se = I.monte_carlo_mutual_information(P0, F, Q, H, R, 40000, np.random.default_rng(2024))
    assert 0 < se < 0.05 * exact
    assert abs(est - exact) < 3 * se
    # the check has power: a 10 % error in the information would be detected
    assert abs(est - 1.1 * exact) > 3 * se


def test_gaussian_kl():
    assert I.gaussian_kl([0.0], [[1.0]], [0.0], [[1.0]]) == pytest.approx(0.0, abs=1e-15)
    # 1-D closed form: log(s2/s1) + (s1^2 + (m1-m2)^2)/(2 s2^2) - 1/2
    val = I.gaussian_kl([1.0], [[4.0]], [0.0], [[9.0]])
    assert val == pytest.approx(np.log(3 / 2) + (4 + 1) / 18 - 0.5, rel=1e-13)
    means = np.array([[0.0, 0.0], [1.0, 2.0]])
    out = I.gaussian_kl(means, np.eye(2), np.zeros(2), 2 * np.eye(2))
    assert out.shape == (2,) and out[1] > out[0]


@pytest.mark.parametrize("method", ["sqrt", "sqrt-forward"])
@given(seed=st.integers(0, 2**32 - 1))
def test_gradient_matches_central_differences_linear_gaussian(method, seed):
    """Gradient of Eq. 18 for F(xi) = F0 + xi.dF + xi^2 terms, H(xi) likewise, at xi0 != 0."""
    P0, F0, Q, H0, R, dF, dH = random_system(seed, N=5, M=2, n=4, p=3)
    rng = np.random.default_rng(seed + 1)
    d2F = 0.05 * rng.normal(size=dF.shape)
    d2H = 0.2 * rng.normal(size=dH.shape)
    xi0 = 0.1 * rng.normal(size=3)

    def system(xi):
        return F0 + dF @ xi + d2F @ xi**2, H0 + dH @ xi + d2H @ xi**2

    F, H = system(xi0)
    jF = dF + 2 * d2F * xi0
    jH = dH + 2 * d2H * xi0
    _, g = I.mutual_information_gradient(P0, F, Q, H, R, jF, jH, method=method)
    fd = np.zeros(3)
    h = 1e-5
    for i, e in enumerate(np.eye(3)):
        Fp, Hp = system(xi0 + h * e)
        Fm, Hm = system(xi0 - h * e)
        fd[i] = (I.mutual_information(P0, Fp, Q, Hp, R) - I.mutual_information(P0, Fm, Q, Hm, R)) / (2 * h)
    np.testing.assert_allclose(g, fd, rtol=1e-5, atol=1e-5 * np.max(np.abs(fd)))


@pytest.fixture(scope="module")
def window():
    t = np.arange(7) * DAY
    P0 = C.block_diag([C.state_covariance(100.0, 1e-2, EARTH_MOON)] * 3)
    R = M.range_range_rate_noise(0.1, 0.01, EARTH_MOON)
    q = C.psd_to_nondimensional(1e-11, EARTH_MOON)
    lin = C.linearize_augmented(EARTH_MOON, OBSERVER, TARGETS, t, M.RANGE_RANGE_RATE, R, P0, q=q, derivatives=True)
    return lin, R


def test_gradient_wrt_observer_matches_finite_differences(window):
    """Eqs. 44-52 on the CR3BP: d I / d x_S(t_0) by STT vs central differences (re-propagated; Q held fixed)."""
    lin, R = window
    info_s, g_s = I.window_information(lin, gradient=True)
    info_d, g_d = I.window_information(lin, gradient=True, method="dense")
    assert info_s == pytest.approx(info_d, rel=1e-10)
    assert info_s == pytest.approx(I.window_information(lin), rel=1e-12)

    def f(x):
        return I.window_information(C.linearize_augmented(EARTH_MOON, x, TARGETS, lin.t, M.RANGE_RANGE_RATE, R,
                                                          lin.P0, Q=lin.Q))

    # fourth-order central differences, step 1e-6 LU (384 m) and 1e-6 LU/TU (1 mm/s)
    h = 1e-6
    fd = np.zeros(6)
    for j in range(6):
        e = np.zeros(6)
        e[j] = h
        fd[j] = (8 * (f(OBSERVER + e) - f(OBSERVER - e)) - (f(OBSERVER + 2 * e) - f(OBSERVER - 2 * e))) / (12 * h)
    scale = np.max(np.abs(fd))
    np.testing.assert_allclose(g_s, fd, rtol=1e-5, atol=1e-5 * scale)
    np.testing.assert_allclose(g_d, fd, rtol=1e-5, atol=1e-5 * scale)
    assert abs(g_s[2]) < 1e-8 * scale and abs(g_s[5]) < 1e-8 * scale  # planar geometry: no z sensitivity


def test_dense_and_structured_crlb_consistency(window):
    """The sum of per-measurement gains equals sum of 0.5 ln|S_k|/|R_k| from the EKF covariance analysis."""
    lin, _ = window
    _, terms = I.mutual_information(*lin.arrays, return_terms=True)
    hist = C.covariance_analysis(*lin.arrays)
    ref = 0.5 * (C.logdet_spd(hist.innovation) - C.logdet_spd(lin.R))
    np.testing.assert_allclose(terms, ref, rtol=1e-9)


def test_timing_helper_runs(window):
    lin, _ = window
    res = I.time_evaluations(*lin.arrays, lin.dF, lin.dH, repeat=1, min_time=1e-3)
    assert res.dense_value > 0 and res.structured_gradient > 0 and res.ratio_gradient > 0


def test_bad_input_names_argument(window):
    lin, _ = window
    P0, F, Q, H, R, dF, dH = random_system(0)
    with pytest.raises(ValueError, match="P0"):
        I.mutual_information(-P0, F, Q, H, R)
    with pytest.raises(ValueError, match="H"):
        I.mutual_information(P0, F, Q, H[..., :-1], R)
    with pytest.raises(ValueError, match="F"):
        I.mutual_information_dense(P0, F[:-1], Q, H, R)
    with pytest.raises(ValueError, match="R"):
        I.mutual_information(P0, F, Q, H, -R)
    with pytest.raises(ValueError, match="Q"):
        I.mutual_information(P0, F, -Q, H, R)
    with pytest.raises(ValueError, match="dH"):
        I.mutual_information_gradient(P0, F, Q, H, R, dF, dH[..., :2, :])
    with pytest.raises(ValueError, match="dF"):
        I.mutual_information_gradient_dense(P0, F, Q, H, R, dF[..., :2], dH)
    with pytest.raises(ValueError, match="dF"):
        I.mutual_information_gradient(P0, F, Q, H, R, dF[:-1], dH)
    with pytest.raises(ValueError, match="dH"):
        I.mutual_information_gradient(P0, F, Q, H, R, dF, dH[:-1], method="sqrt-forward")
    with pytest.raises(ValueError, match="Q"):
        I.mutual_information_gradient(P0, F, -Q, H, R, dF, dH)
    with pytest.raises(ValueError, match="rng"):
        I.monte_carlo_mutual_information(P0, F, Q, H, R, 10, 42)
    with pytest.raises(ValueError, match="n_samples"):
        I.monte_carlo_mutual_information(P0, F, Q, H, R, 1, np.random.default_rng(0))
    with pytest.raises(ValueError, match="method"):
        I.window_information(lin, method="fast")
    no_deriv = C.linearize_augmented(EARTH_MOON, OBSERVER, TARGETS[:1], lin.t[:3], M.RANGE_RANGE_RATE,
                                     lin.R[0, :2, :2], lin.P0[:12, :12], Q=lin.Q[:2, :12, :12])
    with pytest.raises(ValueError, match="derivatives"):
        I.window_information(no_deriv, gradient=True)


def _static_ill_conditioned(xi=0.0):
    """Static 4-state (F = I, Q = 0) observed through rotated axes; prior-to-noise ratios up to 1e12.

    MI = 1/2 sum_i ln(1 + p_i j_i) with j_i = sum over the measurements of axis i of (h_k + xi a_k)^2 (closed form,
    H_k = (h_k + xi a_k) e_i^T U^T, R = 1); d MI / d xi = 1/2 sum_i p_i j_i' / (1 + p_i j_i).
    """
    rng = np.random.default_rng(7)
    U, _ = np.linalg.qr(rng.normal(size=(4, 4)))
    p = np.array([1e6, 1e-2, 1e4, 1.0])
    P0 = U @ np.diag(p) @ U.T
    P0 = 0.5 * (P0 + P0.T)
    N = 12
    axis = np.arange(N) % 4
    h = 1e3 * (1 + rng.random(N))
    a = rng.normal(size=N)
    H = np.zeros((N, 1, 4))
    dH = np.zeros((N, 1, 4, 1))
    for k in range(N):
        H[k, 0] = (h[k] + xi * a[k]) * U[:, axis[k]]
        dH[k, 0, :, 0] = a[k] * U[:, axis[k]]
    j = np.array([np.sum((h[axis == i] + xi * a[axis == i]) ** 2) for i in range(4)])
    dj = np.array([np.sum(2 * (h[axis == i] + xi * a[axis == i]) * a[axis == i]) for i in range(4)])
    exact = 0.5 * np.sum(np.log1p(p * j))
    dexact = 0.5 * np.sum(p * dj / (1 + p * j))
    F = np.tile(np.eye(4), (N - 1, 1, 1))
    return P0, F, np.zeros((N - 1, 4, 4)), H, np.ones((N, 1, 1)), np.zeros((N - 1, 4, 4, 1)), dH, exact, dexact


def test_square_root_value_and_gradient_accurate_when_measurements_dominate():
    """Prior/noise ratios of 1e12: the square-root recursion keeps the value to ~1e-10 relative, where the
    covariance form (EKF innovations) is off by 2e-8 and the dense Eq. 18 by 2e-7 (test case 2's window is worse:
    1e-5).  Gradients: all three structured methods within 1e-4 of the closed form here (every method is ~1e-5 off
    at this ratio; the test-case-2 gradient check in test_wolf_jones separates them)."""
    P0, F, Q, H, R, dF, dH, exact, dexact = _static_ill_conditioned(0.3)
    assert I.mutual_information(P0, F, Q, H, R) == pytest.approx(exact, rel=1e-9)
    hist = C.covariance_analysis(P0, F, Q, H, R)
    cov_form = 0.5 * float(np.sum(C.logdet_spd(hist.innovation)))
    assert cov_form != pytest.approx(exact, rel=1e-9)  # the test has power: the covariance form fails it
    val, g = I.mutual_information_gradient(P0, F, Q, H, R, dF, dH)
    assert val == pytest.approx(exact, rel=1e-9)
    assert g[0] == pytest.approx(dexact, rel=1e-4)
    for method in ("sqrt-forward", "adjoint"):
        val_m, g_m = I.mutual_information_gradient(P0, F, Q, H, R, dF, dH, method=method)
        assert val_m == pytest.approx(val, rel=1e-14) and g_m[0] == pytest.approx(dexact, rel=1e-4)
    with pytest.raises(ValueError, match="method"):
        I.mutual_information_gradient(P0, F, Q, H, R, dF, dH, method="forward")


# ------------------------------------------------------------------------ square-root gradient: reverse vs forward mode
def _rel(a, b):
    """Relative max-abs difference of two gradients."""
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


def _reference_terms(P0, F, Q, H, R):
    """Per-measurement gains from the reference square-root recursion (the one of 2026-11-22)."""
    P0, F, Q, H, R, LR = C._check_linear_system(P0, F, Q, H, R, chol_R=True)
    return I._sqrt_forward(P0, F, Q, np.linalg.solve(LR, H))


@given(seed=st.integers(0, 2**32 - 1), N=st.integers(1, 7), M=st.integers(1, 4), n=st.integers(1, 6),
       logcond=st.floats(-3, 2))
def test_reverse_mode_equals_forward_mode(seed, N, M, n, logcond):
    """method="sqrt" (reverse mode) and "sqrt-forward" differentiate the same recursion: equal to round-off on
    well-conditioned windows (the two drift apart with the condition number, see the test-case-2 window below); the
    value is bit-for-bit that of mutual_information and of the reference recursion."""
    P0, F, Q, H, R, dF, dH = random_system(seed, N, M, n, 3, 10.0**logcond)
    info_r, g_r = I.mutual_information_gradient(P0, F, Q, H, R, dF, dH)
    info_f, g_f = I.mutual_information_gradient(P0, F, Q, H, R, dF, dH, method="sqrt-forward")
    assert info_r == I.mutual_information(P0, F, Q, H, R) == float(np.sum(_reference_terms(P0, F, Q, H, R)))
    assert info_r == pytest.approx(info_f, rel=1e-14)
    assert _rel(g_r, g_f) <= 1e-10


def test_reverse_mode_on_cr3bp_window(window):
    """The 7-day CR3BP window: reverse and forward mode equal to 1e-10, value bit-for-bit."""
    lin, _ = window
    info_r, g_r = I.mutual_information_gradient(*lin.arrays, lin.dF, lin.dH)
    _, g_f = I.mutual_information_gradient(*lin.arrays, lin.dF, lin.dH, method="sqrt-forward")
    assert info_r == I.mutual_information(*lin.arrays)
    assert _rel(g_r, g_f) <= 1e-10


@pytest.fixture(scope="module")
def case2_sized_window():
    """The benchmark window (benchmarks/bench_information.py): observer and three targets on the Table 4 DROs, 17
    daily range / range-rate epochs over [P_ref, 2 P_ref], 24 states; posterior condition number ~4e9."""
    from cislunar.cr3bp.propagation import find_events, propagate

    targets = np.array([[7.78717734e-1, 0, 0, 0, 5.55157488e-1, 0],
                        [7.79426943e-1, 0, 0, 0, 5.54128887e-1, 0],
                        [7.81554639e-1, 0, 0, 0, 5.51070308e-1, 0]])
    period = float(find_events(EARTH_MOON, OBSERVER, 10.0, ("y_crossing",)).t[1])
    start = propagate(EARTH_MOON, np.vstack([OBSERVER, targets]), np.array([0.0, period])).x[:, -1]
    t = period + np.arange(0.0, period + 1e-12, DAY)
    P0 = C.block_diag([C.state_covariance(C.WOLF_JONES_SIGMA_POS_KM, C.WOLF_JONES_SIGMA_VEL_KM_S, EARTH_MOON)] * 4)
    R = M.range_range_rate_noise(M.WOLF_JONES_RANGE_SIGMA_KM, M.WOLF_JONES_RANGE_RATE_SIGMA_KM_S, EARTH_MOON)
    q = C.psd_to_nondimensional(C.WOLF_JONES_PSD_KM2_S3, EARTH_MOON)
    return C.linearize_augmented(EARTH_MOON, start[0], start[1:], t, M.RANGE_RANGE_RATE, R, P0, q=q,
                                 derivatives=True)


def test_reverse_mode_on_case2_sized_window(case2_sized_window):
    """Test-case-2 size: value bit-for-bit; gradient within the double-precision floor of the forward mode.

    Against a 40-digit evaluation of this window (mpmath; not a test dependency) the forward mode is 1.8e-8 and the
    reverse mode 2.4e-8 off, and an eps-sized perturbation of the posterior factors alone moves the gradient by
    ~1e-7: two square-root implementations agree to ~4e-8 here, not to 1e-10.  A wrong sign or factor anywhere in
    the backward sweep gives O(1e-3..1) differences.  The dense form (5e-4) and the covariance-form adjoint (9e-5)
    are the least accurate of the four."""
    lin = case2_sized_window
    assert lin.H.shape == (17, 6, 24)
    args = (*lin.arrays, lin.dF, lin.dH)
    info_r, g_r = I.mutual_information_gradient(*args)
    _, g_f = I.mutual_information_gradient(*args, method="sqrt-forward")
    _, g_a = I.mutual_information_gradient(*args, method="adjoint")
    info_d, g_d = I.mutual_information_gradient_dense(*args)
    assert info_r == I.mutual_information(*lin.arrays) == float(np.sum(_reference_terms(*lin.arrays)))
    assert _rel(g_r, g_f) <= 2e-7
    assert _rel(g_r, g_a) <= 1e-3 and _rel(g_r, g_d) <= 3e-3
    assert info_d == pytest.approx(info_r, rel=1e-5)
    assert abs(g_r[2]) < 1e-8 * np.max(np.abs(g_r)) and abs(g_r[5]) < 1e-8 * np.max(np.abs(g_r))  # planar


def test_value_bit_for_bit_with_reference_recursion():
    """mutual_information (lean sweep, no sign fixing, cached noise roots) reproduces the reference recursion bit for
    bit, including single-component measurements (matrix-vector products) and zero process noise."""
    cases = [random_system(s, N=N, M=Mm, n=n, cond=c)[:5]
             for s, (N, Mm, n, c) in enumerate([(6, 1, 4, 1.0), (5, 3, 5, 1e4), (1, 2, 3, 1.0), (7, 4, 6, 1e-2)])]
    cases.append(_static_ill_conditioned(0.3)[:5])
    for args in cases:
        ref = _reference_terms(*args)
        total, terms = I.mutual_information(*args, return_terms=True)
        np.testing.assert_array_equal(terms, ref)
        assert total == float(np.sum(ref))


def test_process_noise_roots_cache_follows_values():
    """The cached square roots of Q are keyed on Q's entries: a changed Q (new array or the same array changed in
    place) gives the value of an uncached evaluation."""
    P0, F, Q, H, R, dF, dH = random_system(5, N=5)
    base = I.mutual_information(P0, F, Q, H, R)
    Q3 = Q.copy()
    Q3[1] *= 3.0
    I._ROOT_CACHE.clear()
    fresh = I.mutual_information(P0, F, Q3, H, R)
    assert fresh != base
    I._ROOT_CACHE.clear()
    assert I.mutual_information(P0, F, Q, H, R) == base
    assert I.mutual_information(P0, F, Q3, H, R) == fresh
    Q[1] *= 3.0  # in place: the cache holds a copy
    assert I.mutual_information(P0, F, Q, H, R) == fresh
    assert I.mutual_information_gradient(P0, F, Q, H, R, dF, dH)[0] == fresh
    assert I.mutual_information(P0, F[:2], Q[:2], H[:3], R[:3]) == pytest.approx(
        I.mutual_information_dense(P0, F[:2], Q[:2], H[:3], R[:3]), rel=1e-12)  # other shape: no false hit


@given(seed=st.integers(0, 2**32 - 1), N=st.integers(1, 7), M=st.integers(1, 4), n=st.integers(1, 6),
       logcond=st.floats(-3, 6))
def test_information_kernel_equals_public_functions_bit_for_bit(seed, N, M, n, logcond):
    """InformationKernel (P0, Q, R checked once, Q's roots and R's factors kept) returns exactly the value and the
    gradient of mutual_information / mutual_information_gradient, and agrees with dense Eq. 18 and Eqs. 47-48."""
    P0, F, Q, H, R, dF, dH = random_system(seed, N, M, n, 2, 10.0**logcond)
    K = I.InformationKernel(P0, Q, R, N)
    I._ROOT_CACHE.clear()  # the kernel does not rely on the module's caches
    assert K.value(F, H) == I.mutual_information(P0, F, Q, H, R)
    info_k, g_k = K.value_gradient(F, H, dF, dH)
    info_p, g_p = I.mutual_information_gradient(P0, F, Q, H, R, dF, dH)
    assert info_k == info_p and np.array_equal(g_k, g_p)
    info_d, g_d = I.mutual_information_gradient_dense(P0, F, Q, H, R, dF, dH)
    assert info_k == pytest.approx(info_d, rel=1e-10, abs=1e-12)
    np.testing.assert_allclose(g_k, g_d, rtol=1e-7, atol=1e-8 * max(1.0, np.max(np.abs(g_d))))


def test_information_kernel_on_case2_sized_window(case2_sized_window):
    """Test-case-2 size: the kernel is the public reverse mode bit for bit (whose gradient the finite-difference
    tests above check); a broadcast (M, M) R and (n, n) Q give the numbers of their sequences."""
    lin = case2_sized_window
    P0, F, Q, H, R = lin.arrays
    K = I.InformationKernel(P0, Q, R, H.shape[0])
    info_k, g_k = K.value_gradient(F, H, lin.dF, lin.dH)
    info_p, g_p = I.mutual_information_gradient(*lin.arrays, lin.dF, lin.dH)
    assert info_k == info_p == K.value(F, H) and np.array_equal(g_k, g_p)
    K1 = I.InformationKernel(P0, Q[0], R[0], H.shape[0])
    Qc = np.broadcast_to(Q[0], Q.shape)
    assert K1.value(F, H) == I.mutual_information(P0, F, Qc, H, R[0])


def test_information_kernel_refuses_bad_input_by_name():
    P0, F, Q, H, R, dF, dH = random_system(3, N=4, M=2, n=3)
    with pytest.raises(ValueError, match="P0"):
        I.InformationKernel(-P0, Q, R, 4)
    with pytest.raises(ValueError, match="Q"):
        I.InformationKernel(P0, -Q, R, 4)
    with pytest.raises(ValueError, match="R"):
        I.InformationKernel(P0, Q, R[:2], 4)
    with pytest.raises(ValueError, match="n_times"):
        I.InformationKernel(P0, Q, R, 0)
    K = I.InformationKernel(P0, Q, R, 4)
    with pytest.raises(ValueError, match="F"):
        K.value(F[:2], H)
    with pytest.raises(ValueError, match="H"):
        K.value(F, H[:, :1])
    Hn = H.copy()
    Hn[1, 0, 0] = np.nan
    with pytest.raises(ValueError, match="finite"):
        K.value(F, Hn)
    with pytest.raises(ValueError, match="dF"):
        K.value_gradient(F, H, dF[..., :1], dH)
    with pytest.raises(ValueError, match="dH"):
        K.value_gradient(F, H, dF, dH[:2])
    assert K.value(F, H) == I.mutual_information(P0, F, Q, H, R)  # the checked arrays were not changed


# ---------------------------------------------------------------------------------------------------------------
# range-dependent noise (keyword-only row_scale / range_scale)
# ---------------------------------------------------------------------------------------------------------------
def _window_ranges(lin):
    return np.linalg.norm(lin.observer[None, :, :3] - lin.targets[:, :, :3], axis=-1)  # (N_T, N), LU


def test_range_noise_equals_the_mi_with_range_scaled_noise_covariances(window):
    """Scaling the rows of H by s = rho / sqrt(rho^2 + rho_c^2) is the MI of Eq. 18 with every target's noise block
    scaled by 1/s^2 (independent: the dense stacked formula with the scaled R)."""
    lin, _ = window
    rc = float(np.median(_window_ranges(lin)))
    s = I.range_noise_scale(lin, rc)
    assert s.shape == lin.H.shape[:2] and np.all((s > 0) & (s < 1))
    R_scaled = lin.R / (s[:, :, None] * s[:, None, :])  # block-diagonal per target: same s on a target's rows
    dense = I.mutual_information_dense(lin.P0, lin.F, lin.Q, lin.H, R_scaled)
    assert I.window_information(lin, range_scale=rc) == pytest.approx(dense, rel=1e-10)
    assert I.window_information(lin, range_scale=rc) < I.window_information(lin)  # more noise, less information
    # defaults: bit for bit the plain values
    kernel = I.InformationKernel(lin.P0, lin.Q, lin.R, lin.t.size)
    assert kernel.value(lin.F, lin.H, row_scale=None) == I.window_information(lin)
    g0 = I.window_information(lin, gradient=True)
    g1 = I.window_information(lin, gradient=True, range_scale=None)
    assert g0[0] == g1[0] and np.array_equal(g0[1], g1[1])


def test_range_noise_gradient_matches_finite_differences(window):
    """d I / d x_S(t_0) with the range-dependent noise (product rule through the row scale) against fourth-order
    central differences of the value (re-propagated, Q held fixed); the scale's own derivative matters."""
    lin, R = window
    rc = float(np.median(_window_ranges(lin)))
    val, grad = I.window_information(lin, gradient=True, range_scale=rc)
    assert val == pytest.approx(I.window_information(lin, range_scale=rc), rel=1e-12)

    def f(x):
        return I.window_information(C.linearize_augmented(EARTH_MOON, x, TARGETS, lin.t, M.RANGE_RANGE_RATE, R,
                                                          lin.P0, Q=lin.Q), range_scale=rc)

    h = 1e-6
    fd = np.zeros(6)
    for j in range(6):
        e = np.zeros(6)
        e[j] = h
        fd[j] = (8 * (f(OBSERVER + e) - f(OBSERVER - e)) - (f(OBSERVER + 2 * e) - f(OBSERVER - 2 * e))) / (12 * h)
    scale = np.max(np.abs(fd))
    np.testing.assert_allclose(grad, fd, rtol=1e-5, atol=1e-5 * scale)
    # the scale held fixed (no product-rule term) gives a visibly different gradient: the test would catch its loss
    kernel = I.InformationKernel(lin.P0, lin.Q, lin.R, lin.t.size)
    s, ds = I.range_noise_scale(lin, rc, derivatives=True)
    _, frozen = kernel.value_gradient(lin.F, lin.H, lin.dF, lin.dH, row_scale=s, d_row_scale=np.zeros_like(ds))
    assert np.max(np.abs(frozen - fd)) > 1e-3 * scale
    # d_row_scale itself against central differences of the scale
    for j in range(6):
        e = np.zeros(6)
        e[j] = h
        sp = I.range_noise_scale(C.linearize_augmented(EARTH_MOON, OBSERVER + e, TARGETS, lin.t, M.RANGE_RANGE_RATE,
                                                       R, lin.P0, Q=lin.Q), rc)
        sm = I.range_noise_scale(C.linearize_augmented(EARTH_MOON, OBSERVER - e, TARGETS, lin.t, M.RANGE_RANGE_RATE,
                                                       R, lin.P0, Q=lin.Q), rc)
        np.testing.assert_allclose(ds[..., j], (sp - sm) / (2 * h), rtol=1e-6, atol=1e-9 * np.abs(ds).max())


def test_range_noise_refuses_bad_input_by_name(window):
    lin, _ = window
    kernel = I.InformationKernel(lin.P0, lin.Q, lin.R, lin.t.size)
    s, ds = I.range_noise_scale(lin, 0.01, derivatives=True)
    with pytest.raises(ValueError, match="row_scale"):
        kernel.value(lin.F, lin.H, row_scale=-s)
    with pytest.raises(ValueError, match="row_scale"):
        kernel.value(lin.F, lin.H, row_scale=s[:, :1])
    with pytest.raises(ValueError, match="d_row_scale"):
        kernel.value_gradient(lin.F, lin.H, lin.dF, lin.dH, row_scale=s)
    with pytest.raises(ValueError, match="range_scale"):
        I.range_noise_scale(lin, 0.0)
    with pytest.raises(ValueError, match="range_scale"):
        I.window_information(lin, range_scale=0.01, method="dense")


@given(seed=st.integers(0, 2**32 - 1), N=st.integers(1, 7), M=st.integers(1, 4), n=st.integers(1, 6),
       logcond=st.floats(-3, 6))
def test_one_qr_kernel_agrees_with_dense_and_two_qr(seed, N, M, n, logcond):
    """``one_qr=True`` (time and measurement updates in one QR per time): the value of dense Eq. 18 and the gradient
    of dense Eqs. 47-48 (independent formulas), the two-QR value to round-off; ``value`` unchanged bit for bit."""
    P0, F, Q, H, R, dF, dH = random_system(seed, N, M, n, 2, 10.0**logcond)
    K1 = I.InformationKernel(P0, Q, R, N, one_qr=True)
    K2 = I.InformationKernel(P0, Q, R, N)
    info_1, g_1 = K1.value_gradient(F, H, dF, dH)
    info_2, g_2 = K2.value_gradient(F, H, dF, dH)
    info_d, g_d = I.mutual_information_gradient_dense(P0, F, Q, H, R, dF, dH)
    assert info_1 == pytest.approx(info_2, rel=1e-11, abs=1e-13)
    assert info_1 == pytest.approx(info_d, rel=1e-10, abs=1e-12)
    np.testing.assert_allclose(g_1, g_d, rtol=1e-7, atol=1e-8 * max(1.0, np.max(np.abs(g_d))))
    assert K1.value(F, H) == K2.value(F, H)


def test_one_qr_kernel_on_case2_sized_window(case2_sized_window):
    """Test-case-2 size: the one-QR gradient is within the square-root floor (~4e-8 relative) of the two-QR one and
    of the forward mode, and its value within 1e-13 relative."""
    lin = case2_sized_window
    P0, F, Q, H, R = lin.arrays
    info_1, g_1 = I.InformationKernel(P0, Q, R, H.shape[0], one_qr=True).value_gradient(F, H, lin.dF, lin.dH)
    info_2, g_2 = I.InformationKernel(P0, Q, R, H.shape[0]).value_gradient(F, H, lin.dF, lin.dH)
    g_f = I.mutual_information_gradient(*lin.arrays, lin.dF, lin.dH, method="sqrt-forward")[1]
    assert abs(info_1 - info_2) <= 1e-13 * abs(info_2)
    scale = np.max(np.abs(g_2))
    assert np.max(np.abs(g_1 - g_2)) <= 2e-7 * scale and np.max(np.abs(g_1 - g_f)) <= 2e-7 * scale
    with pytest.raises(ValueError, match="one_qr"):
        I.InformationKernel(P0, Q, R, H.shape[0], one_qr="yes")
