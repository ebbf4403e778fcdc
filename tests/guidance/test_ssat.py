"""SSAT state, covariance analysis and MMD guidance (Greaves & Scheeres AMOS 2023, Eqs. 1-7, 13-24)."""

from __future__ import annotations

import numpy as np
import pytest

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.orbits import nrho_9_2
from cislunar.cr3bp.propagation import propagate, propagate_stm
from cislunar.guidance import ssat
from cislunar.sensing.measurements import AZIMUTH_ELEVATION

HR = 3600.0 / em.time_unit_s


@pytest.fixture(scope="module")
def pair():
    """Target at the 9:2 NRHO apolune, agent trailing 0.6 h on the same orbit (about 229 km)."""
    o = nrho_9_2(em)
    xt0 = o.x0.copy()
    xa0 = propagate(em, o.x0, np.array([0.0, -0.6 * HR])).x[-1]
    return xa0, xt0


def _random_spd(rng, n):
    A = rng.standard_normal((n, n))
    return A @ A.T + n * np.eye(n)


# ---------------------------------------------------------------------------------------------------------------
# Eqs. 1-7 and 13-14: identities
# ---------------------------------------------------------------------------------------------------------------
def test_transform_matches_eq6_and_inverts():
    rng = np.random.default_rng(1)
    x = rng.standard_normal((5, 12))
    T = ssat.transform_matrix()
    assert np.allclose(T[:6, :6], 0.5 * np.eye(6)) and np.allclose(T[6:, :6], -np.eye(6))
    xr = ssat.to_relative(x)
    assert np.allclose(xr, x @ T.T, atol=1e-15)
    assert np.allclose(xr[:, :6], 0.5 * (x[:, :6] + x[:, 6:]))  # Eq. 3
    assert np.allclose(xr[:, 6:], x[:, 6:] - x[:, :6])  # Eq. 4: target minus agent
    assert np.allclose(ssat.from_relative(xr), x, atol=1e-14)
    xb = ssat.to_agent_based(x)
    assert np.allclose(xb, x @ ssat.agent_transform_matrix().T)
    assert np.allclose(ssat.from_agent_based(xb), x, atol=1e-14)


def test_covariance_maps_and_equivalence_of_relative_partitions():
    rng = np.random.default_rng(2)
    P = _random_spd(rng, 12)
    T = ssat.transform_matrix()
    Pr = ssat.relative_covariance(P)
    assert np.allclose(Pr, T @ P @ T.T)  # Eq. 7
    assert np.allclose(ssat.inertial_covariance(Pr), P, atol=1e-12)
    # sample covariance of transformed samples equals T P T^T (independent check of Eq. 7)
    L = np.linalg.cholesky(P)
    s = (L @ rng.standard_normal((12, 200000))).T
    emp = np.cov(ssat.to_relative(s).T)
    assert np.allclose(emp, Pr, atol=0.05 * np.max(np.abs(Pr)))
    # agent-based and mean-based states share the relative block
    Pa = ssat.agent_based_covariance(P)
    assert np.allclose(Pa[6:, 6:], Pr[6:, 6:])
    assert not np.allclose(Pa[:6, :6], Pr[:6, :6])
    x = rng.standard_normal(12)
    J = [ssat.range_variance(C, x, c) for C, c in ((P, "inertial"), (Pr, "relative"), (Pa, "agent"))]
    assert np.allclose(J, J[0])


def test_angles_see_only_the_relative_partition(pair):
    xa, xt = pair
    _, Ha, Ht = AZIMUTH_ELEVATION.evaluate(xa, xt)
    H = np.hstack([Ha, Ht])
    for C in (ssat.transform_matrix(), ssat.agent_transform_matrix()):
        Hc = H @ np.linalg.inv(C)
        assert np.max(np.abs(Hc[:, :6])) < 1e-12 * np.max(np.abs(H))
        assert np.allclose(Hc[:, 6:], Ht)


def test_control_on_agent_only():
    B = ssat.control_matrix()
    assert B.shape == (12, 3) and np.allclose(B[3:6], np.eye(3)) and np.count_nonzero(B) == 3
    rng = np.random.default_rng(3)
    x, u = rng.standard_normal(12), rng.standard_normal(3)
    xp = ssat.apply_impulse(x, u)
    assert np.allclose(xp - x, B @ u)  # Eq. 13
    # in relative coordinates: the mean velocity moves by u/2, the relative velocity by -u
    dr = ssat.to_relative(xp) - ssat.to_relative(x)
    assert np.allclose(dr, ssat.control_matrix("relative") @ u)
    assert np.allclose(dr[3:6], 0.5 * u) and np.allclose(dr[9:12], -u)
    with pytest.raises(ValueError, match="coordinates"):
        ssat.control_matrix("polar")


def test_range_projection_is_line_of_sight():
    x = np.zeros(12)
    x[6:9] = [3.0, 4.0, 0.0]
    M = ssat.range_projection(x)
    assert np.allclose(M[0:3], [-0.6, -0.8, 0]) and np.allclose(M[6:9], [0.6, 0.8, 0])
    assert np.allclose(ssat.range_projection(x, "relative")[6:9], [0.6, 0.8, 0])
    with pytest.raises(ValueError, match="coincident"):
        ssat.range_projection(np.zeros(12))


# ---------------------------------------------------------------------------------------------------------------
# trajectories with impulses
# ---------------------------------------------------------------------------------------------------------------
def test_impulses_between_grid_points_and_stm(pair):
    xa, _ = pair
    t = np.linspace(0, 10 * HR, 11)
    dv1, dv2 = np.array([1e-4, -2e-4, 5e-5]), np.array([-3e-4, 1e-4, 2e-4])
    tb = 4.5 * HR
    tr = ssat.propagate_with_impulses(em, xa, t, [(t[0], dv1), (tb, dv2)])
    # manual reference
    x = xa.copy()
    x[3:6] += dv1
    seg1 = propagate(em, x, np.array([0.0, 4 * HR, tb])).x
    y = seg1[-1].copy()
    y[3:6] += dv2
    seg2 = propagate(em, y, np.array([tb, 5 * HR, 10 * HR])).x
    assert np.allclose(tr.x[0, 4], seg1[1], atol=1e-13)
    assert np.allclose(tr.x[0, 5], seg2[1], atol=1e-13)
    assert np.allclose(tr.x[0, -1], seg2[-1], atol=1e-13)
    # STM w.r.t. the post-impulse initial state, checked by central differences through both impulses
    h = 1e-7
    E = h * np.eye(6)
    xp = ssat.propagate_with_impulses(em, np.vstack([x + E, x - E]) - np.r_[0, 0, 0, dv1], t, [(t[0], dv1), (tb, dv2)])
    fd = (xp.x[:6, -1] - xp.x[6:, -1]).T / (2 * h)
    assert np.allclose(tr.stm[0, -1], fd, rtol=1e-5, atol=1e-5 * np.max(np.abs(fd)))
    assert np.allclose(tr.stm[0, 0], np.eye(6))


def test_impulses_on_grid_times_are_post_impulse(pair):
    xa, _ = pair
    t = np.linspace(0, 4 * HR, 5)
    dv = np.array([1e-4, 0, 0])
    for k in (2, 4):
        tr = ssat.propagate_with_impulses(em, xa, t, [(t[k], dv)])
        plain = ssat.propagate_with_impulses(em, xa, t)
        assert np.allclose(tr.x[0, :k], plain.x[0, :k], atol=1e-15)
        assert np.allclose(tr.x[0, k, 3:6] - plain.x[0, k, 3:6], dv, atol=1e-14)
        assert np.allclose(tr.x[0, k, :3], plain.x[0, k, :3], atol=1e-15)
        assert np.allclose(tr.stm[0, k], plain.stm[0, k], atol=1e-12)


def test_impulse_validation(pair):
    xa, _ = pair
    t = np.linspace(0, 1, 3)
    with pytest.raises(ValueError, match=r"impulses\[0\] time"):
        ssat.propagate_with_impulses(em, xa, t, [(2.0, np.zeros(3))])
    with pytest.raises(ValueError, match=r"impulses\[0\] dv"):
        ssat.propagate_with_impulses(em, xa, t, [(0.5, np.zeros(4))])
    with pytest.raises(ValueError, match="x0"):
        ssat.propagate_with_impulses(em, np.zeros(5), t)
    with pytest.raises(ValueError, match="t must be strictly increasing"):
        ssat.propagate_with_impulses(em, xa, t[::-1])


# ---------------------------------------------------------------------------------------------------------------
# covariance analysis (Eqs. 15-22)
# ---------------------------------------------------------------------------------------------------------------
def test_initial_covariance_numbers():
    P0 = ssat.initial_covariance(em)
    assert np.isclose(np.sqrt(P0[0, 0]) * em.length_unit_km, 20.0)
    assert np.isclose(np.sqrt(P0[9, 9]) * em.velocity_unit_km_s * 1e5, 20.0)  # 20 cm/s
    assert np.allclose(P0[:6, 6:], 0)
    with pytest.raises(ValueError, match="sigma3_pos_km"):
        ssat.initial_covariance(em, -1.0)


def test_sri_covariance_equals_ekf_recursion_in_all_coordinates(pair):
    xa, xt = pair
    t = np.arange(0, 25) * HR
    P0 = ssat.initial_covariance(em)
    ag = ssat.propagate_with_impulses(em, xa, t, [(t[0], np.array([2e-4, 0, -1e-4])), (7.3 * HR, np.array([0, 3e-4, 0]))])
    tg = ssat.propagate_with_impulses(em, xt, t)
    res = ssat.ssat_covariance(em, ag, tg, P0)
    # no information yet along the line of sight at t0: J = 2 sigma^2 (both vehicles), sqrt = 28.28 km
    assert np.isclose(res.range_sigma_km[0, 0], np.sqrt(2) * 20.0, rtol=1e-9)
    assert np.all(res.range_sigma_km[0, 1:] < res.range_sigma_km[0, 0])
    for coords in ("inertial", "relative", "agent"):
        post, J = ssat.ssat_covariance_ekf(em, ag, tg, P0, coordinates=coords)
        assert np.allclose(J, res.J_rho[0], rtol=1e-5)
    post, _ = ssat.ssat_covariance_ekf(em, ag, tg, P0)
    assert np.allclose(res.P_final[0], post[-1], rtol=1e-4, atol=1e-6 * np.max(np.abs(post[-1])))
    # the relative-coordinate recursion is T P T^T of the inertial one
    postr, _ = ssat.ssat_covariance_ekf(em, ag, tg, P0, coordinates="relative")
    assert np.allclose(postr[-1], ssat.relative_covariance(post[-1]), rtol=1e-4,
                       atol=1e-6 * np.max(np.abs(postr[-1])))


def test_covariance_noise_model_and_batching(pair):
    xa, xt = pair
    t = np.arange(0, 13) * HR
    P0 = ssat.initial_covariance(em)
    tg = ssat.propagate_with_impulses(em, xt, t)
    dvs = np.array([[0, 0, 0], [3e-4, 0, 0], [0, 0, -3e-4]])
    ag = ssat.propagate_with_impulses(em, np.tile(xa, (3, 1)), t, [(t[0], dvs)])
    batch = ssat.ssat_covariance(em, ag, tg, P0)
    for i in range(3):
        one = ssat.ssat_covariance(em, ssat.ImpulsiveTrajectory(t, ag.x[i:i + 1], ag.stm[i:i + 1]), tg, P0)
        assert np.allclose(one.J_rho[0], batch.J_rho[i], rtol=1e-10)
    # Eq. 20 at the true range
    sig = np.sqrt((10e-6) ** 2 + (4e-3 / batch.range_km) ** 2)
    assert np.allclose(batch.sigma_theta_rad, sig)
    # a noisier sensor cannot know the range better
    noisy = ssat.ssat_covariance(em, ag, tg, P0, sigma_min_rad=100e-6)
    assert np.all(noisy.J_rho[:, 1:] > batch.J_rho[:, 1:])
    with pytest.raises(ValueError, match="P0"):
        ssat.ssat_covariance(em, ag, tg, -P0)
    with pytest.raises(ValueError, match="target"):
        ssat.ssat_covariance(em, ag, ssat.propagate_with_impulses(em, np.tile(xt, (2, 1)), t), P0)


# ---------------------------------------------------------------------------------------------------------------
# MMD (Eqs. 23-24)
# ---------------------------------------------------------------------------------------------------------------
def test_mmd_matrix_equals_full_state_formula(pair):
    xa, xt = pair
    tf = 6 * HR
    Sa = propagate_stm(em, xa, tf).stm[-1]
    St = propagate_stm(em, xt, tf).stm[-1]
    xf = propagate(em, np.vstack([xa, xt]), tf).x[:, -1]
    _, Ha, Ht = AZIMUTH_ELEVATION.evaluate(xf[0], xf[1])
    Phi = np.zeros((12, 12))
    Phi[:6, :6], Phi[6:, 6:] = Sa, St
    H = np.hstack([Ha, Ht])
    B = ssat.control_matrix()
    Qfull = B.T @ Phi.T @ H.T @ H @ Phi @ B
    assert np.allclose(ssat.mmd_matrix(Sa, Ha), Qfull, rtol=1e-12, atol=1e-12 * np.max(np.abs(Qfull)))
    assert np.linalg.matrix_rank(Qfull, tol=1e-9 * np.max(np.abs(Qfull))) == 2


def test_mmd_is_brute_force_maximiser_of_nonlinear_measurement_deviation(pair):
    """The eigenvector maximises the (small-burn) measurement deviation over a dense sphere of directions."""
    xa, xt = pair
    tf = 6 * HR
    St = propagate(em, np.vstack([xa, xt]), tf).x[:, -1]
    y0 = AZIMUTH_ELEVATION(St[0], St[1])
    Sa = propagate_stm(em, xa, tf).stm[-1]
    _, Ha, _ = AZIMUTH_ELEVATION.evaluate(St[0], St[1])
    e = ssat.mmd_direction(ssat.mmd_matrix(Sa, Ha))
    D = ssat.fibonacci_sphere(4000)
    v = 1e-7  # small impulse: the linear surrogate regime
    x = np.tile(xa, (D.shape[0], 1))
    x[:, 3:6] += v * D
    xf = propagate(em, x, tf).x[:, -1]
    dev = np.linalg.norm(AZIMUTH_ELEVATION.residual(AZIMUTH_ELEVATION(xf, St[1]), y0), axis=-1)
    best = D[np.argmax(dev)]
    spacing = np.sqrt(4 * np.pi / D.shape[0])
    assert np.arccos(min(1.0, abs(best @ e))) < 1.5 * spacing
    # and the surrogate value: the eigenvalue equals the max of u^T Q u on the sphere
    Q = ssat.mmd_matrix(Sa, Ha)
    quad = np.einsum("ni,ij,nj->n", D, Q, D)
    lam = np.linalg.eigvalsh(Q)[-1]
    assert quad.max() <= lam * (1 + 1e-12) and quad.max() > lam * (1 - spacing**2)
    assert np.isclose(e @ Q @ e, lam)


def test_mmd_policy_sign_and_optimiser(pair):
    xa, xt = pair
    t = np.arange(0, 7) * HR
    P0 = ssat.initial_covariance(em)
    v = 1e-3 / em.velocity_unit_km_s
    u, Q, Jpm = ssat.mmd_policy(em, xa, xt, t, v, P0)
    e = ssat.mmd_direction(Q)
    assert np.isclose(np.linalg.norm(u), v)
    assert np.allclose(u, (v if Jpm[0] <= Jpm[1] else -v) * e)
    assert Jpm[0] != Jpm[1]
    tg = ssat.propagate_with_impulses(em, xt, t)
    d, Jmin = ssat.minimize_range_sigma(em, xa, None, t, v, P0, n_grid=400, target=tg)
    assert np.isclose(np.linalg.norm(d), 1.0)
    grid = ssat.range_sigma_over_directions(em, xa, None, t, v, ssat.fibonacci_sphere(400), P0, target=tg)
    assert Jmin <= grid.J_rho[:, -1].min() and Jmin <= Jpm.min()
    check = ssat.range_sigma_over_directions(em, xa, None, t, v, d[None], P0, target=tg)
    assert np.isclose(check.J_rho[0, -1], Jmin, rtol=1e-10)


def test_direction_helpers():
    D = ssat.fibonacci_sphere(500)
    assert np.allclose(np.linalg.norm(D, axis=1), 1)
    assert np.allclose(D.mean(axis=0), 0, atol=5e-3)
    los = np.array([0.3, -1.0, 0.2])
    P = ssat.perpendicular_directions(los, 36)
    assert np.allclose(P @ los, 0, atol=1e-14) and np.allclose(np.linalg.norm(P, axis=1), 1)
    with pytest.raises(ValueError, match="n must be"):
        ssat.fibonacci_sphere(1)
    with pytest.raises(ValueError, match="line_of_sight"):
        ssat.perpendicular_directions(np.zeros(3), 4)
    with pytest.raises(ValueError, match="dv_magnitude"):
        ssat.mmd_policy(em, np.ones(6), np.ones(6), [0, 1], -1.0, np.eye(12))


def test_burn_after_a_tracking_arc(pair):
    """burn_index: MMD uses Phi(tau_f, tau_b) (same Q as starting at the burn) and a mid-arc burn is informative."""
    xa, xt = pair
    t = np.arange(0, 13) * HR
    b = 6
    P0 = ssat.initial_covariance(em)
    v = 1e-3 / em.velocity_unit_km_s
    _, Q_b, _ = ssat.mmd_policy(em, xa, xt, t, v, P0, burn_index=b)
    xb = propagate(em, np.vstack([xa, xt]), t[:b + 1]).x[:, -1]
    _, Q_0, _ = ssat.mmd_policy(em, xb[0], xb[1], t[b:], v, P0)
    assert np.allclose(Q_b, Q_0, rtol=1e-7, atol=1e-9 * np.max(np.abs(Q_0)))
    # a known burn in the middle of a tracking arc breaks the angles-only scaling symmetry: large information gain
    D = ssat.fibonacci_sphere(50)
    tg = ssat.propagate_with_impulses(em, xt, t)
    mid = ssat.range_sigma_over_directions(em, xa, None, t, v, D, P0, burn_index=b, target=tg)
    none = ssat.ssat_covariance(em, ssat.propagate_with_impulses(em, xa, t), tg, P0)
    assert np.median(mid.J_rho[:, -1]) < 0.1 * none.J_rho[0, -1]
    with pytest.raises(ValueError, match="burn_index"):
        ssat.mmd_policy(em, xa, xt, t, v, P0, burn_index=12)
    with pytest.raises(ValueError, match="coast_indices"):
        ssat.compare_burn_policies(em, xa, xt, t, [3], v, P0, burn_index=b, n_grid=10, n_perp=4)


# ---------------------------------------------------------------------------------------------------------------
# independent checks added by the referee: equations as printed, and the covariance analysis from scratch
# ---------------------------------------------------------------------------------------------------------------
def test_eqs_15_to_18_as_printed(pair):
    """Azimuth/elevation (Eqs. 15-17) and their Jacobian w.r.t. rho (Eq. 18) typed in from the paper."""
    xa, xt = pair
    val, Ha, Ht = AZIMUTH_ELEVATION.evaluate(xa, xt)
    rx, ry, rz = xt[:3] - xa[:3]  # Eq. 22 below: rho = r_t - r_a
    r = np.sqrt(rx**2 + ry**2 + rz**2)
    rxy2 = rx**2 + ry**2
    assert np.isclose(np.cos(val[0]), rx / np.sqrt(rxy2)) and np.isclose(np.sin(val[0]), ry / np.sqrt(rxy2))
    assert np.isclose(val[1], np.arcsin(rz / r))
    H18 = np.array([[-ry / rxy2, rx / rxy2, 0, 0, 0, 0],
                    [-rx * rz / (r**2 * np.sqrt(rxy2)), -ry * rz / (r**2 * np.sqrt(rxy2)), np.sqrt(rxy2) / r**2, 0, 0, 0]])
    assert np.allclose(Ht, H18, rtol=1e-12, atol=1e-12 * np.abs(H18).max())
    assert np.allclose(Ha, -H18, rtol=1e-12, atol=1e-12 * np.abs(H18).max())


def test_eqs_11_12_cr3bp_acceleration_as_printed():
    """Eq. 11 with Eq. 12 (non-dimensional: G(m1+m2) = r12 = 1, so |omega| = 1) equals the package's equations of motion."""
    rng = np.random.default_rng(11)
    mu = em.mu
    w = np.array([0.0, 0.0, 1.0])
    for _ in range(5):
        s = np.r_[rng.uniform(-1.2, 1.2, 3), rng.uniform(-0.5, 0.5, 3)]
        r, v = s[:3], s[3:]
        rho1 = r - np.array([-mu, 0, 0])  # from the Earth
        rho2 = r - np.array([1 - mu, 0, 0])  # from the Moon
        a = (-2 * np.cross(w, v) - np.cross(w, np.cross(w, r)) - (1 - mu) * rho1 / np.linalg.norm(rho1) ** 3
             - mu * rho2 / np.linalg.norm(rho2) ** 3)
        f = np.asarray(em.eom(s))
        assert np.allclose(f[:3], v) and np.allclose(f[3:], a, rtol=1e-12, atol=1e-12)


def test_covariance_analysis_against_finite_difference_batch(pair):
    """J_rho and P_f from scratch: finite-difference measurement Jacobians of the propagated pair, Eq. 20 typed in.

    Independent of the STMs, the whitened rows and the QR recursion of ``ssat_covariance``; a factor two in the noise
    or in the projection, or a wrong STM across the impulse, fails it.
    """
    xa, xt = pair
    t = np.arange(0, 6) * HR
    tb, dv = 2.5 * HR, np.array([3e-4, -2e-4, 1e-4])
    P0 = ssat.initial_covariance(em)
    res = ssat.ssat_covariance(em, ssat.propagate_with_impulses(em, xa, t, [(tb, dv)]),
                               ssat.propagate_with_impulses(em, xt, t), P0)

    def states(X0):
        """(m, 12) initial SSAT states -> (m, N, 12) states on the grid (agent burns dv at tb)."""
        a1 = propagate(em, X0[:, :6], np.array([0.0, 1 * HR, 2 * HR, tb])).x
        a2s = a1[:, -1].copy()
        a2s[:, 3:6] += dv
        a2 = propagate(em, a2s, np.array([tb, 3 * HR, 4 * HR, 5 * HR])).x
        ag = np.concatenate([a1[:, :3], a2[:, 1:]], axis=1)
        tg = propagate(em, X0[:, 6:], t).x
        return np.concatenate([ag, tg], axis=-1)

    x0 = np.r_[xa, xt]
    h = 1e-7
    X = states(np.vstack([x0 + h * np.eye(12), x0 - h * np.eye(12), x0[None]]))
    nom = X[-1]

    def angles(S):
        return AZIMUTH_ELEVATION(S[..., :6], S[..., 6:])

    y0 = angles(nom)
    dy = AZIMUTH_ELEVATION.residual(angles(X[:12]), y0[None]) - AZIMUTH_ELEVATION.residual(angles(X[12:24]), y0[None])
    Hk = np.moveaxis(dy / (2 * h), 0, -1)  # (N, 2, 12): d y_k / d x0
    Phi_f = ((X[:12, -1] - X[12:24, -1]) / (2 * h)).T  # d x_f / d x0
    rho_km = np.linalg.norm(nom[:, 6:9] - nom[:, :3], axis=-1) * em.length_unit_km
    sig = np.sqrt((10e-6) ** 2 + (4e-3 / rho_km) ** 2)  # Eq. 20, typed in
    Lam = np.linalg.inv(P0) + np.einsum("kai,kaj->ij", Hk / sig[:, None, None], Hk / sig[:, None, None])
    Pf = Phi_f @ np.linalg.inv(Lam) @ Phi_f.T
    u = (nom[-1, 6:9] - nom[-1, :3]) / np.linalg.norm(nom[-1, 6:9] - nom[-1, :3])
    M = np.r_[-u, 0, 0, 0, u, 0, 0, 0]  # T^T M_rho, Eq. 22 in inertial coordinates
    J = M @ Pf @ M
    assert np.isclose(res.J_rho[0, -1], J, rtol=2e-4)
    d = np.sqrt(np.diag(Pf))
    assert np.allclose(res.P_final[0] / np.outer(d, d), Pf / np.outer(d, d), atol=2e-4)


def test_compare_burn_policies_bookkeeping(pair):
    """Every number of the policy comparison re-derived from the primitives (a factor or a swapped field fails)."""
    xa, xt = pair
    t = np.arange(0, 5) * HR
    P0 = ssat.initial_covariance(em)
    v = 1e-3 / em.velocity_unit_km_s
    L = em.length_unit_km
    r = ssat.compare_burn_policies(em, xa, xt, t, [2, 4], v, P0, n_grid=150, n_perp=12)
    assert np.allclose(r.coast_hours, [2.0, 4.0])
    tg = ssat.propagate_with_impulses(em, xt, t)
    none = ssat.ssat_covariance(em, ssat.propagate_with_impulses(em, xa, t), tg, P0)
    grid = ssat.range_sigma_over_directions(em, xa, None, t, v, ssat.fibonacci_sphere(150), P0, target=tg)
    for i, k in enumerate((2, 4)):
        assert np.isclose(r.none[i], np.sqrt(none.J_rho[0, k]) * L)
        _, _, Jpm = ssat.mmd_policy(em, xa, xt, t[:k + 1], v, P0)
        assert np.isclose(r.mmd[i], np.sqrt(Jpm.min()) * L) and np.isclose(r.mmd_other[i], np.sqrt(Jpm.max()) * L)
        Jg = grid.J_rho[:, k]
        assert np.isclose(r.grid_median[i], np.sqrt(np.median(Jg)) * L)
        assert np.isclose(r.mmd_percentile[i], 100 * np.mean(Jg < Jpm.min()))
        assert r.optimum[i] <= np.sqrt(Jg.min()) * L * (1 + 1e-12) and r.optimum[i] <= r.mmd[i]
        assert r.optimum[i] <= r.perp_best[i] * (1 + 1e-12) <= r.perp_worst[i] * (1 + 1e-12)
        check = ssat.range_sigma_over_directions(em, xa, None, t[:k + 1], v, r.optimum_direction[i][None], P0,
                                                 target=ssat.ImpulsiveTrajectory(t[:k + 1], tg.x[:, :k + 1],
                                                                                 tg.stm[:, :k + 1]))
        assert np.isclose(check.final_range_sigma_km[0], r.optimum[i], rtol=1e-9)
        los = (xt[:3] - xa[:3]) / np.linalg.norm(xt[:3] - xa[:3])
        assert np.isclose(r.optimum_perp_angle_deg[i], np.degrees(np.arcsin(abs(r.optimum_direction[i] @ los))))
    assert np.allclose(r.mmd_excess_percent, 100 * (r.mmd / r.optimum - 1))
