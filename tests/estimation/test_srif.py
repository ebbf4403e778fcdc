"""The square-root information filter/smoother equals the covariance-form Kalman filter and RTS smoother (filterpy)."""

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter
from hypothesis import given, settings
from hypothesis import strategies as st

from cislunar.estimation import srif


def _random_system(rng, n=4, m=2, N=12, r=None):
    r = n if r is None else r
    Phis = np.array([np.eye(n) + 0.3 * rng.standard_normal((n, n)) for _ in range(N - 1)])
    Gammas = [rng.standard_normal((n, r)) for _ in range(N - 1)]
    Qs = []
    for _ in range(N - 1):
        B = rng.standard_normal((r, r))
        Qs.append(0.05 * (B @ B.T + r * np.eye(r)))
    Hs = [rng.standard_normal((m, n)) for _ in range(N)]
    Rs = []
    for _ in range(N):
        C = rng.standard_normal((m, m))
        Rs.append(0.1 * (C @ C.T + m * np.eye(m)))
    A = rng.standard_normal((n, n))
    P0 = A @ A.T + np.eye(n)
    x0 = rng.standard_normal(n)
    ys = [rng.standard_normal(m) for _ in range(N)]
    return x0, P0, Phis, Gammas, Qs, Hs, Rs, ys


def _filterpy_reference(x0, P0, Phis, Gammas, Qs, Hs, Rs, ys):
    n = x0.size
    kf = KalmanFilter(dim_x=n, dim_z=Hs[0].shape[0])
    kf.x = x0.copy()
    kf.P = P0.copy()
    xs, Ps, Fs, Qfull = [], [], [], []
    for k in range(len(ys)):
        if k > 0:
            kf.F = Phis[k - 1]
            kf.Q = Gammas[k - 1] @ Qs[k - 1] @ Gammas[k - 1].T
            kf.predict()
        kf.H, kf.R = Hs[k], Rs[k]
        kf.update(ys[k])
        xs.append(kf.x.copy())
        Ps.append(kf.P.copy())
        # filterpy's rts_smoother expects Fs[k], Qs[k] = the model that predicted epoch k from k - 1
        Fs.append(Phis[k - 1] if k > 0 else np.eye(n))
        Qfull.append(Gammas[k - 1] @ Qs[k - 1] @ Gammas[k - 1].T if k > 0 else np.zeros((n, n)))
    xs_s, Ps_s, _, _ = kf.rts_smoother(np.array(xs), np.array(Ps), Fs=np.array(Fs), Qs=np.array(Qfull))
    return np.array(xs), np.array(Ps), xs_s, Ps_s


@settings(max_examples=12)
@given(st.integers(0, 10_000))
def test_sri_filter_and_smoother_equal_filterpy(seed):
    rng = np.random.default_rng(seed)
    x0, P0, Phis, Gammas, Qs, Hs, Rs, ys = _random_system(rng)
    res = srif.filter_smoother(x0, P0, Phis, Hs, ys, Rs, Gammas, Qs)
    xf, Pf, xs, Ps = _filterpy_reference(x0, P0, Phis, Gammas, Qs, Hs, Rs, ys)
    scale = max(1.0, np.max(np.abs(Pf)))
    assert np.max(np.abs(res.x_filt - xf)) < 1e-9 * max(1.0, np.max(np.abs(xf)))
    assert np.max(np.abs(res.P_filt - Pf)) < 1e-9 * scale
    assert np.max(np.abs(res.x_smooth - xs)) < 1e-9 * max(1.0, np.max(np.abs(xs)))
    assert np.max(np.abs(res.P_smooth - Ps)) < 1e-9 * scale
    for P in np.concatenate([res.P_filt, res.P_smooth]):
        assert np.allclose(P, P.T, atol=1e-14 * scale) and np.linalg.eigvalsh(P).min() > 0


def test_rank_deficient_process_noise_through_factor():
    rng = np.random.default_rng(5)
    n = 6
    B = rng.standard_normal((n, 3))
    Q = B @ B.T  # rank 3, like the OCBE's -Phi_xp Phi_xx^T restricted to acceleration inputs
    G = srif.factor_process_noise(Q)
    assert G.shape == (6, 3)
    assert np.allclose(G @ G.T, Q, atol=1e-12)
    R, z = srif.sri_from_covariance(np.zeros(n), np.eye(n))
    Rn, zn, _ = srif.time_update(R, z, np.eye(n), G, np.eye(3))
    assert np.allclose(srif.covariance_from_sri(Rn), np.eye(n) + Q, atol=1e-12)


def test_sri_round_trip_and_errors():
    rng = np.random.default_rng(1)
    A = rng.standard_normal((5, 5))
    P = A @ A.T + np.eye(5)
    x = rng.standard_normal(5)
    R, z = srif.sri_from_covariance(x, P)
    assert np.allclose(np.triu(R), R)
    m, P2 = srif.covariance_from_sri(R, z)
    assert np.allclose(P2, P, rtol=1e-12, atol=1e-12) and np.allclose(m, x, atol=1e-12)
    with pytest.raises(ValueError, match="P must be symmetric positive definite"):
        srif.sri_from_covariance(x, -P)
    with pytest.raises(ValueError, match="H must have 5 columns"):
        srif.measurement_update(R, z, np.ones((2, 4)), np.ones(2), np.eye(2))
    with pytest.raises(ValueError, match="meas_cov"):
        srif.measurement_update(R, z, np.ones((2, 5)), np.ones(2), np.eye(3))
    with pytest.raises(ValueError, match="Q must be positive semi-definite"):
        srif.factor_process_noise(-np.eye(3))


def test_stacked_kernels_equal_one_matrix_at_a_time_and_keep_the_information():
    """The private SRI kernels take leading batch axes: each slice equals the unbatched call, and the algebra holds.

    The batched OCBE (cislunar.estimation.batched_ocbe) and the single-trial filters share these kernels.
    """
    rng = np.random.default_rng(11)
    B, n, m, r = 4, 5, 3, 2

    def spd(k):
        A = rng.standard_normal((B, k, k))
        return A @ np.swapaxes(A, -1, -2) + k * np.eye(k)

    P, Rv, Q = spd(n), spd(m), spd(r)
    R = srif._sri_of_cov(P)
    assert np.allclose(R, np.triu(R)) and np.all(np.diagonal(R, axis1=-2, axis2=-1) > 0)
    assert np.allclose(np.swapaxes(R, -1, -2) @ R, np.linalg.inv(P), rtol=1e-10, atol=1e-12)
    z, H, y = rng.standard_normal((B, n)), rng.standard_normal((B, m, n)), rng.standard_normal((B, m))
    Phi, Gamma = np.eye(n) + 0.2 * rng.standard_normal((B, n, n)), rng.standard_normal((B, n, r))
    Rm, zm, e = srif._measurement_update(R, z, H, y, Rv)
    Rt, zt, terms = srif._time_update(R, z, Phi, Gamma, Q)
    Rs, zs = srif._smoother_step(Rm, zm, Phi, Gamma, terms)
    mean, cov = srif._cov_of_sri(Rm, zm)
    for b in range(B):
        one = srif._measurement_update(R[b], z[b], H[b], y[b], Rv[b])
        assert np.allclose(Rm[b], one[0], rtol=1e-13, atol=1e-13) and np.allclose(zm[b], one[1], rtol=1e-13)
        assert np.isclose(e[b], one[2], rtol=1e-12)
        one = srif._time_update(R[b], z[b], Phi[b], Gamma[b], Q[b])
        assert np.allclose(Rt[b], one[0], rtol=1e-13, atol=1e-13) and np.allclose(zt[b], one[1], rtol=1e-13)
        assert all(np.allclose(a[b], c, rtol=1e-13, atol=1e-13) for a, c in zip(terms, one[2]))
        one = srif._smoother_step(Rm[b], zm[b], Phi[b], Gamma[b], tuple(a[b] for a in terms))
        assert np.allclose(Rs[b], one[0], rtol=1e-13, atol=1e-13) and np.allclose(zs[b], one[1], rtol=1e-12)
        # the algebra: information adds in the measurement update, covariance propagates in the time update
        info = np.linalg.inv(P[b]) + H[b].T @ np.linalg.solve(Rv[b], H[b])
        assert np.allclose(Rm[b].T @ Rm[b], info, rtol=1e-10)
        assert np.allclose(cov[b], np.linalg.inv(info), rtol=1e-10)
        assert np.allclose(mean[b], np.linalg.solve(Rm[b], zm[b]), rtol=1e-10)
        assert np.allclose(srif._solve_upper(Rm, zm)[b], mean[b], rtol=1e-10)
        P_next = Phi[b] @ P[b] @ Phi[b].T + Gamma[b] @ Q[b] @ Gamma[b].T
        assert np.allclose(srif._cov_of_sri(Rt[b]), P_next, rtol=1e-10)
        # the whitened residual norm is the increase of the least-squares cost
        prior_mean = np.linalg.solve(R[b], z[b])
        x_hat = np.linalg.solve(info, np.linalg.solve(P[b], prior_mean) + H[b].T @ np.linalg.solve(Rv[b], y[b]))
        d = R[b] @ x_hat - z[b]
        w = np.linalg.cholesky(np.linalg.inv(Rv[b])).T @ (H[b] @ x_hat - y[b])
        assert np.isclose(e[b] ** 2, d @ d + w @ w, rtol=1e-9)
    # one prior broadcast against a stack of measurements (as the batched OCBE's zero prior deviation)
    Rb = srif._measurement_update(R, np.zeros(n), H, y, Rv[0])[0]
    one = srif._measurement_update(R[2], np.zeros(n), H[2], y[2], Rv[0])[0]
    assert np.allclose(Rb[2], one, rtol=1e-13, atol=1e-13)
    with pytest.raises(np.linalg.LinAlgError):
        srif._sri_of_cov(-P)


@pytest.mark.parametrize("noise", [True, False])
def test_filter_many_equals_filter_smoother_set_by_set(noise):
    """Several measurement sets as extra information-vector columns: each set's estimate is filter_smoother's."""
    rng = np.random.default_rng(11)
    x0, P0, Phis, Gammas, Qs, Hs, Rs, _ = _random_system(rng, n=4, m=2, N=10)
    Hs[3] = np.zeros((0, 4))  # an epoch without a measurement
    M = 5
    x0s = x0 + rng.standard_normal((M, 4))
    ys = rng.standard_normal((M, 10, 2))
    kw = dict(Gammas=Gammas, Qs=Qs) if noise else {}
    xf, Pf, Rf = srif.filter_many(x0s, P0, Phis, Hs, ys, Rs, **kw)
    for j in range(M):
        ref = srif.filter_smoother(x0s[j], P0, Phis, Hs, list(ys[j]), Rs, smooth=False, **kw)
        assert np.allclose(xf[j], ref.x_filt, rtol=1e-10, atol=1e-10)
        assert np.allclose(Pf, ref.P_filt, rtol=1e-10, atol=1e-12)
        assert np.allclose(Rf, ref.R_filt, rtol=1e-10, atol=1e-10)


def test_filter_many_refuses_mismatched_measurements():
    rng = np.random.default_rng(12)
    x0, P0, Phis, Gammas, Qs, Hs, Rs, _ = _random_system(rng, n=4, m=2, N=6)
    with pytest.raises(ValueError, match="ys"):
        srif.filter_many(np.zeros((3, 4)), P0, Phis, Hs, np.zeros((2, 6, 2)), Rs, Gammas, Qs)
    with pytest.raises(ValueError, match="P0"):
        srif.filter_many(np.zeros((3, 4)), np.eye(3), Phis, Hs, np.zeros((3, 6, 2)), Rs, Gammas, Qs)
