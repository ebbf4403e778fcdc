"""Tests of cislunar.cr3bp.torus: invariant circles of the stroboscopic map about the 9:2 NRHO.

Every test checks a mathematical property that a wrong implementation would break: the invariance equation off the
grid, the linear limit (rotation number -> argument of the centre eigenvalue, quadratic dependence on size),
agreement between circle resolutions, the Jacobian against finite differences, long-time stay on the torus.
"""

from __future__ import annotations

import pickle
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from cislunar import EARTH_MOON
from cislunar.cr3bp import torus as tm
from cislunar.cr3bp.orbits import ConvergenceError, nrho_9_2
from cislunar.cr3bp.propagation import propagate, propagate_scipy


@pytest.fixture(scope="module")
def orbit():
    return nrho_9_2(EARTH_MOON)


@pytest.fixture(scope="module")
def big(orbit):
    """A 200-km torus with N = 11 (its Fourier modes fall below 1e-13 by k = 5)."""
    return tm.torus_from_orbit(orbit, 11, 200.0)


@pytest.fixture(scope="module")
def small_family(orbit):
    """Tori of 10, 20 and 40 km (N = 7) for the linear-limit tests."""
    t10 = tm.torus_from_orbit(orbit, 7, 10.0)
    return [t10] + tm.continue_tori(t10, [20.0, 40.0], progress=False)


def _grid_residual(torus):
    x = propagate(torus.system, torus.circle, torus.period).x[:, -1]
    return np.max(np.linalg.norm(x - torus.circle_at(torus.thetas + torus.rho), axis=1))


# ------------------------------------------------------------------------------------------ invariance
def test_invariance_at_grid_and_midpoints(big):
    grid = _grid_residual(big)
    mid = big.invariance_error()
    print(f"N=11, 200 km: invariance residual grid {grid:.2e}, midpoints {mid:.2e}")
    assert grid <= 1e-9
    assert mid <= 1e-9
    # a random set of angles as well
    assert big.invariance_error(np.random.default_rng(1).uniform(0, 2 * np.pi, 9)) <= 1e-9


def test_invariance_with_an_independent_integrator(big):
    """scipy DOP853 (not heyoka) maps a midpoint of the circle onto the rotated circle."""
    th = big.thetas[3] + np.pi / big.N
    x = propagate_scipy(big.system, big.circle_at([th])[0], [0.0, big.period], rtol=1e-13, atol=1e-13).x[-1]
    assert np.linalg.norm(x - big.circle_at([th + big.rho])[0]) < 1e-9


@given(n=st.sampled_from([5, 7, 11]), seed=st.integers(0, 2**31), theta=st.floats(-10.0, 10.0))
def test_fourier_interpolation_is_exact_for_trigonometric_polynomials(n, seed, theta):
    rng = np.random.default_rng(seed)
    m = (n - 1) // 2
    a, b = rng.standard_normal(m + 1), rng.standard_normal(m + 1)
    k = np.arange(m + 1)

    def f(x):
        return np.cos(np.outer(x, k)) @ a + np.sin(np.outer(x, k)) @ b

    def df(x):
        return -np.sin(np.outer(x, k)) @ (a * k) + np.cos(np.outer(x, k)) @ (b * k)

    grid = 2 * np.pi * np.arange(n) / n
    assert np.allclose(tm.fourier_weights([theta], n) @ f(grid), f([theta]), atol=1e-12)
    assert np.allclose(tm.fourier_weights([theta], n, derivative=True) @ f(grid), df([theta]), atol=1e-11)


def test_midpoint_check_bites_when_circle_is_under_resolved(orbit, big):
    """N = 5 keeps only modes |k| <= 2; the 200-km circle has a 3rd mode of ~3e-9, which the midpoint test sees."""
    with pytest.warns(tm.UnderResolvedWarning, match="increase N"):
        coarse = tm.solve_torus(replace(big, circle=big.circle_at(2 * np.pi * np.arange(5) / 5)),
                                fix={"size_km": 200.0})
    assert _grid_residual(coarse) <= 1e-9  # solved at its own grid ...
    assert coarse.invariance_error() > 1e-9  # ... but not invariant in between


def test_torus_pickles(big):
    again = pickle.loads(pickle.dumps(big))
    assert np.array_equal(again.circle, big.circle) and again.rho == big.rho and again.period == big.period


def test_quadratic_convergence_and_constant_jacobi(big):
    r = np.array(big.residuals)
    assert r[-1] < 1e-11
    assert len(r) <= 5
    assert big.jacobi_spread < 1e-12


def test_jacobian_matches_finite_differences(big):
    fixes = tm._parse_fix({"jacobi": big.jacobi}, False, big.system)
    prob = tm._Problem(big.orbit, big.N, fixes, False, big.phase_component, 1e-15, big.period)
    x = prob.pack(big.circle, big.rho, big.period)
    f0, jac = prob.evaluate(x)
    rng = np.random.default_rng(3)
    for _ in range(3):
        d = rng.standard_normal(x.size)
        d /= np.linalg.norm(d)
        h = 1e-6
        fd = (prob.evaluate(x + h * d, jac=False)[0] - prob.evaluate(x - h * d, jac=False)[0]) / (2 * h)
        assert np.allclose(jac @ d, fd, atol=1e-7 * max(1.0, np.abs(fd).max()))
    # free period column
    probt = tm._Problem(big.orbit, big.N, tm._parse_fix({"size": big.size, "period": big.period}, True,
                                                        big.system), True, big.phase_component, 1e-15, big.period)
    xt = probt.pack(big.circle, big.rho, big.period)
    _, jt = probt.evaluate(xt)
    e = np.zeros(xt.size)
    e[-1] = 1.0
    fd = (probt.evaluate(xt + 1e-7 * e, jac=False)[0] - probt.evaluate(xt - 1e-7 * e, jac=False)[0]) / 2e-7
    assert np.allclose(jt[:, -1], fd, atol=1e-6)


def test_jacobian_null_space_and_rank(big):
    """The invariance block annihilates the two phase directions (d/dtheta and the flow) and has a 3-D null space
    (phases + family); the phase and member constraints restore full column rank."""
    fixes = tm._parse_fix({"size_km": big.size_km}, False, big.system)
    prob = tm._Problem(big.orbit, big.N, fixes, False, big.phase_component, 1e-15, big.period)
    _, jac = prob.evaluate(prob.pack(big.circle, big.rho, big.period))
    n = big.N
    inv = jac[: 6 * n]
    du = tm.fourier_weights(big.thetas, n, derivative=True) @ big.circle
    flow = big.system.eom(big.circle)
    for v in (du, flow):
        vec = np.append(v.ravel(), 0.0)
        assert np.linalg.norm(inv @ vec) < 1e-9 * np.linalg.norm(vec)
    sv = np.linalg.svd(inv, compute_uv=False)  # 6N values for 6N+1 columns
    assert np.sum(sv < 1e-10 * sv[0]) == 2  # rank 6N - 2: null space of dimension 3
    sv_full = np.linalg.svd(jac, compute_uv=False)
    assert sv_full[-1] > 1e-4 * sv_full[0]  # full column rank with the constraints


# ------------------------------------------------------------------------------------------ linear limit
def test_collapse_to_periodic_orbit(orbit, small_family):
    lam, _ = tm.centre_eigenpair(orbit)
    alpha = np.angle(lam)
    tiny = tm.torus_from_orbit(orbit, 7, 0.5)
    assert abs(tiny.rho - alpha) < 1e-9
    # the ring shrinks onto x0: its points are within ~size of x0, its centroid within ~size^2
    for t in [tiny] + small_family:
        off = np.linalg.norm(t.circle[:, :3] - orbit.x0[:3], axis=1).max() * EARTH_MOON.length_unit_km
        assert off < 1.5 * t.size_km
    # the tiny ring is the eigen-ellipse: semi-axes consistent with the RMS size, a flat (planar) ring
    a = tiny.semi_axes_km
    assert abs(np.sqrt(np.sum(a**2) / 2) - tiny.size_km) < 1e-9
    assert a[2] < 1e-6 * a[0]
    cen = [np.linalg.norm(t.circle.mean(axis=0) - orbit.x0) for t in small_family]
    assert 3.5 < cen[2] / cen[1] < 4.5
    assert abs(tiny.jacobi - orbit.jacobi) < 1e-10


def test_stability_multipliers_inherit_the_orbit_hyperbolic_pair(orbit, small_family, big):
    lam_max = np.abs(orbit.eigenvalues[0])
    for t in (small_family[0], big):
        m = t.stability_multipliers()
        # N copies lambda e^{ik rho} of the unstable multiplier (same modulus), then the rest
        assert np.allclose(np.abs(m[: t.N]), lam_max, rtol=1e-4)
        assert np.abs(m[t.N]) < 1.01
        assert abs(np.abs(m[0]) - lam_max) < 1e-6 * (t.size_km / 10.0) ** 2 + 1e-8
    m = small_family[0].stability_multipliers()[: small_family[0].N]
    assert np.min(np.abs(m - orbit.eigenvalues[0])) < 1e-5  # the k = 0 member is the orbit's multiplier
    # the others are rotated by multiples of rho
    rot = m / orbit.eigenvalues[0]
    k = np.arange(-(small_family[0].N // 2), small_family[0].N // 2 + 1)
    for kk in k:
        assert np.min(np.abs(rot - np.exp(1j * kk * small_family[0].rho))) < 1e-5


def test_rotation_number_and_jacobi_quadratic_in_size(orbit, small_family):
    alpha = np.angle(tm.centre_eigenpair(orbit)[0])
    d_rho = np.array([t.rho - alpha for t in small_family])
    d_c = np.array([t.jacobi - orbit.jacobi for t in small_family])
    sizes = np.array([t.size_km for t in small_family])
    assert np.allclose(sizes, [10, 20, 40], rtol=1e-8)
    for d in (d_rho, d_c):
        assert np.all(d != 0) and np.all(np.sign(d) == np.sign(d[0]))
        # doubling the size multiplies the change by 4 (not 2, not 8)
        assert 3.8 < d[1] / d[0] < 4.2
        assert 3.8 < d[2] / d[1] < 4.2


# ------------------------------------------------------------------------------------------ long time on torus
def test_ring_point_stays_on_torus_for_ten_periods(big):
    theta0 = 1.234
    x0 = big.circle_at([theta0])[0]
    x10 = propagate(big.system, x0, 10 * big.period).x[-1]
    dist = big.distance_to_ring(x10)[0]
    to_point = np.linalg.norm(x10 - big.circle_at([theta0 + 10 * big.rho])[0])
    km = EARTH_MOON.length_unit_km
    print(f"10 periods: distance to the circle {dist:.2e} ({dist * km * 1e3:.3f} m); to u(theta0 + 10 rho) "
          f"{to_point:.2e}")
    assert dist < 1e-8
    assert to_point < 1e-8
    # a point displaced off the circle by 1e-9 along the unstable eigendirection leaves it (so the test can fail)
    lam, vec = np.linalg.eig(big.orbit.monodromy)
    vu = np.real(vec[:, np.argmax(np.abs(lam))])
    y10 = propagate(big.system, x0 + 1e-7 * vu / np.linalg.norm(vu), 10 * big.period).x[-1]
    assert big.distance_to_ring(y10)[0] > 1e-5


def test_states_are_on_torus_and_consistent_with_flow(big):
    th = np.array([0.3, 2.0])
    T = big.period
    a = big.states(th, [0.0, 0.4 * T, 1.4 * T, 2.0 * T])
    assert np.allclose(a[:, 0], big.circle_at(th), atol=1e-15)
    assert np.allclose(a[:, 2], big.states(th + big.rho, [0.4 * T])[:, 0], atol=1e-12)
    assert np.allclose(a[:, 3], big.circle_at(th + 2 * big.rho), atol=1e-12)
    # times just below / at a whole period, negative times
    b = big.states(th, [np.nextafter(T, 0.0), -0.5 * T])
    assert np.allclose(b[:, 0], big.circle_at(th + big.rho), atol=1e-12)
    assert np.allclose(b[:, 1], big.states(th - big.rho, [0.5 * T])[:, 0], atol=1e-15)
    direct = propagate(big.system, big.circle_at(th), [0.0, 0.4 * T, 1.4 * T]).x
    assert np.allclose(a[:, :3], direct, atol=1e-10)
    # ring at a given time: flowing the circle for t equals the ring function
    ring = big.ring(0.4 * T)
    assert np.allclose(ring, propagate(big.system, big.circle, [0.0, 0.4 * T]).x[:, -1], atol=1e-12)


# ------------------------------------------------------------------------------------------ resolution
def test_two_values_of_n_agree(big):
    other = tm.solve_torus(replace(big, circle=big.circle_at(2 * np.pi * np.arange(15) / 15)), fix={"size_km": 200.0})
    assert other.N == 15
    assert abs(other.rho - big.rho) < 1e-11
    th = np.linspace(0, 2 * np.pi, 17)
    assert np.max(np.abs(other.circle_at(th) - big.circle_at(th))) < 1e-11
    assert abs(other.jacobi - big.jacobi) < 1e-12
    assert abs(other.max_offset_km - big.max_offset_km) < 1e-5
    assert abs(other.max_velocity_offset_mps - big.max_velocity_offset_mps) < 1e-6
    assert abs(other.velocity_size_mps - big.velocity_size_mps) < 1e-8


def test_member_constraints_select_the_same_torus(big):
    by_c = tm.solve_torus(replace(big, circle=big.circle * (1 + 1e-6)), fix={"jacobi": big.jacobi})
    by_rho = tm.solve_torus(replace(big, circle=big.circle * (1 + 1e-6)), fix={"rho": big.rho})
    free = tm.solve_torus(replace(big, period=big.period * (1 + 1e-7)), free_period=True,
                          fix={"size_km": big.size_km, "period": big.orbit.period})
    # Jacobi constant and rotation number vary only with size^2 (dC/ds ~ 1e-8 per km here), so a 1e-11 residual
    # pins the size to ~1e-3 km through them; the size itself is pinned to ~1e-7 km.
    for t, size_tol in ((by_c, 1e-3), (by_rho, 1e-3), (free, 1e-6)):
        assert abs(t.size_km - big.size_km) < size_tol
        assert abs(t.rho - big.rho) < 1e-10
        assert np.max(np.abs(t.circle - big.circle)) < 2 * size_tol / EARTH_MOON.length_unit_km
    assert abs(free.period - big.orbit.period) < 1e-13


def test_free_period_changes_the_frequency_ratio(big):
    """With T free and the Jacobi constant fixed, a 1e-4 shorter period is a different torus (2-parameter family)."""
    t2 = tm.solve_torus(replace(big, period=big.period * (1 - 1e-4)), free_period=True,
                        fix={"size_km": big.size_km, "period": big.period * (1 - 1e-4)})
    assert t2.invariance_error() < 1e-9
    assert abs(t2.jacobi - big.jacobi) > 1e-6


def test_continuation_at_fixed_jacobi_with_free_period(big):
    """Along the branch of constant Jacobi constant the period changes, and each member is invariant."""
    fam = tm.continue_tori(big, [190.0, 180.0], free_period=True, hold={"jacobi": big.jacobi}, progress=False)
    for t in fam:
        assert abs(t.jacobi - big.jacobi) < 1e-11
        assert t.invariance_error() < 1e-9
    d1, d2 = (fam[0].period - big.period), (fam[1].period - big.period)
    assert d1 != 0 and 1.5 < d2 / d1 < 2.5  # smooth branch: twice the step, about twice the change
    with pytest.raises(ValueError, match="hold"):
        tm.continue_tori(big, [190.0], hold={"size_km": 1.0}, progress=False)


# ------------------------------------------------------------------------------------------ mean range
def test_mean_range_definition(big):
    s1 = tm.mean_range(big, n_theta=24, n_t=401)
    s2 = tm.mean_range(big, n_theta=24, n_t=401, periods=2)
    fine = tm.mean_range(big, n_theta=48, n_t=1601)
    assert abs(s1.mean_km - s2.mean_km) < 1e-3 * s1.mean_km  # independent of the whole number of periods
    assert abs(s1.mean_km - fine.mean_km) < 1e-3 * fine.mean_km  # quadrature converged
    assert fine.min_km <= s1.range_km.min() + 1e-9 and fine.max_km >= s1.range_km.max() - 1e-9
    assert fine.min_km < fine.mean_km < fine.max_km
    assert abs(fine.per_theta_mean_km.mean() - fine.mean_km) < 1e-9
    assert fine.per_theta_mean_km.min() < fine.mean_km < fine.per_theta_mean_km.max()
    # brute force at the refined minimum
    th, t = fine.min_at
    agent = big.states([th], [t])[0, 0]
    target = propagate(big.system, big.orbit.x0, t).x[-1]
    assert abs(np.linalg.norm(agent[:3] - target[:3]) * EARTH_MOON.length_unit_km - fine.min_km) < 1e-6
    # long-time average along one trajectory tends to the torus average
    tt = np.linspace(0, 30 * big.period, 30 * 400 + 1)
    one = big.states([0.7], tt)[0]
    tgt = big.orbit.period
    target_one = propagate(big.system, big.orbit.x0, np.linspace(0, tgt, 401)).x
    target_rep = np.vstack([target_one[:-1]] * 30 + [target_one[-1:]])
    r = np.linalg.norm(one[:, :3] - target_rep[:, :3], axis=1) * EARTH_MOON.length_unit_km
    assert abs(np.trapezoid(r, tt) / tt[-1] - fine.mean_km) < 0.03 * fine.mean_km


def test_closest_approach_to_the_moon(orbit, big):
    d, (th, t) = big.closest_approach()
    # brute force on a fine grid near the reported point and over the whole torus on a coarse grid
    km = EARTH_MOON.length_unit_km
    x = big.states(np.linspace(0, 2 * np.pi, 64, endpoint=False), np.linspace(0, big.period, 801))
    coarse = np.linalg.norm(x[..., :3] - EARTH_MOON.secondary_position, axis=-1).min() * km
    assert d <= coarse + 1e-9 and d > coarse - 5.0
    y = big.states([th], [t])[0, 0]
    assert abs(np.linalg.norm(y[:3] - EARTH_MOON.secondary_position) * km - d) < 1e-6
    assert abs(t - orbit.period / 2) < 0.01  # at perilune
    assert d < orbit.perilune_radius_km  # the torus dips below the NRHO's perilune
    with pytest.raises(ValueError, match="body"):
        big.closest_approach("Sun")


def test_member_with_215_km_mean_range(orbit):
    torus, stats = tm.qpo_for_mean_range(orbit, 215.0, N=11, n_theta=24, n_t=601)
    assert abs(stats.mean_km - 215.0) < 215.0 * 1e-5
    assert torus.invariance_error() < 1e-9
    assert 100.0 < torus.size_km < 215.0
    assert stats.min_km < 215.0 < stats.max_km
    # the extrema are refined for the accepted member only: its statistics are those of mean_range, bit for bit
    again = tm.mean_range(torus, n_theta=24, n_t=601)
    for name in ("mean_km", "min_km", "max_km", "rms_km", "ring_mean_km", "min_at", "max_at", "range_km"):
        assert np.array_equal(getattr(stats, name), getattr(again, name)), name
    # matching the mean over the apolune ring instead selects a larger member (the ring is smallest near apolune)
    ring, ring_stats = tm.qpo_for_mean_range(orbit, 215.0, N=11, n_theta=24, n_t=601, statistic="ring_mean_km")
    assert abs(ring_stats.ring_mean_km - 215.0) < 215.0 * 1e-5
    assert ring.size_km > torus.size_km
    with pytest.raises(ValueError, match="statistic"):
        tm.qpo_for_mean_range(orbit, 215.0, N=11, statistic="median")


# ------------------------------------------------------------------------------------------ failures
def _failing_solve():
    orbit = nrho_9_2(EARTH_MOON)
    tm.solve_torus(tm.torus_seed(orbit, 7, 3000.0), fix={"size_km": 3000.0}, max_iter=1)


def test_non_convergence_raises_with_history_through_a_process_pool():
    with pytest.raises(tm.TorusConvergenceError) as info:
        _failing_solve()
    err = info.value
    assert isinstance(err, ConvergenceError)
    assert err.reason in ("max_iter", "diverged")
    assert len(err.residuals) >= 2 and err.residuals[-1] > 1e-11
    again = pickle.loads(pickle.dumps(err))
    assert again.residuals == err.residuals and str(again) == str(err)
    with ProcessPoolExecutor(max_workers=1) as pool:
        fut = pool.submit(_failing_solve)
        with pytest.raises(tm.TorusConvergenceError) as remote:
            fut.result()
    assert remote.value.residuals == err.residuals and remote.value.reason == err.reason
    assert "residual history" in str(remote.value)


def test_iterate_through_the_moon_is_an_impact_failure(orbit):
    """A 20000-km seed ring sends trajectories into the Moon: the solve refuses instead of integrating through it."""
    with pytest.raises(tm.TorusConvergenceError, match="Moon") as info:
        tm.solve_torus(tm.torus_seed(orbit, 7, 20000.0), fix={"size_km": 20000.0})
    assert info.value.reason == "impact"


@pytest.mark.parametrize("n", [4, 3, 2.5, True, "9"])
def test_bad_n(orbit, n):
    with pytest.raises((ValueError, TypeError), match="N"):
        tm.torus_seed(orbit, n, 1.0)


def test_bad_inputs(orbit, big):
    with pytest.raises(ValueError, match="size_km"):
        tm.torus_seed(orbit, 7, -1.0)
    with pytest.raises(ValueError, match="size_km"):
        tm.torus_from_orbit(orbit, 7, float("nan"))
    with pytest.raises(ValueError, match="fix"):
        tm.solve_torus(big, fix={"amplitude": 1.0})
    with pytest.raises(ValueError, match="fix"):
        tm.solve_torus(big, fix={"size_km": 1.0, "rho": 0.8})
    with pytest.raises(ValueError, match="period"):
        tm.solve_torus(big, fix={"period": 1.5})
    with pytest.raises(TypeError, match="guess"):
        tm.solve_torus(big.circle, fix={"size_km": 1.0})
    with pytest.raises(ValueError, match="t "):
        big.states([0.0], [np.nan])
    with pytest.raises(ValueError, match="theta0"):
        big.states([[0.0]], [1.0])
    with pytest.raises(ValueError, match="period"):
        replace(big, period=-1.0)
    with pytest.raises(ValueError, match="circle"):
        replace(big, circle=big.circle[:, :5])
    with pytest.raises(ValueError, match="N"):
        replace(big, circle=big.circle[:10])
    with pytest.raises(ValueError, match="n_t"):
        tm.mean_range(big, n_t=3)
    with pytest.raises(ValueError, match="values"):
        tm.continue_tori(big, [10.0, -5.0], progress=False)
    with pytest.raises(ValueError, match="parameter"):
        tm.continue_tori(big, [10.0], parameter="energy", progress=False)
    hyperbolic = replace(orbit, monodromy=np.diag([3.0, 1 / 3.0, 1.0, 1.0, 2.0, 0.5]))
    with pytest.raises(ValueError, match="centre eigenvalue"):
        tm.torus_seed(hyperbolic, 7, 1.0)
