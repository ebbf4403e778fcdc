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
