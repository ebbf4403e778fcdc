"""Wolf & Jones scenarios: data from the tables, the window-information model (value/gradient/Hessian consistency
against finite differences on the test-case windows), the keep-out, the CRLB helpers, the unit readings."""

import numpy as np
import pytest

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.propagation import propagate
from cislunar.papers.wolf_jones import scenarios as W
from cislunar.sensing import covariance as C
from cislunar.sensing import information as I


@pytest.fixture(scope="module")
def case1():
    return W.test_case_1()


@pytest.fixture(scope="module")
def case2():
    return W.test_case_2()


def _window_start(sc):
    return propagate(sc.system, sc.observer_x0, [0.0, sc.window[0]]).x[-1]


# ------------------------------------------------------------------------------------------------ scenario data
def test_scenarios_follow_the_tables(case1, case2):
    for sc, n_t, n_per, frac, a_km in ((case1, 1, 2, (0.75, 1.5), 1e-6), (case2, 3, 3, (1.0, 2.0), 5e-7)):
        assert sc.n_targets == n_t and sc.n_periods == n_per and sc.window_fraction == frac
        # the corrected observer DRO is periodic with the printed x0; the printed vy0 is not (Table 2 slip)
        end = propagate(sc.system, sc.observer_x0, sc.period).x[-1]
        assert np.linalg.norm(end - sc.observer_x0) < 1e-8
        assert sc.observer_x0[0] == sc.observer_x0_printed[0] == 7.78185828e-1
        assert abs(sc.observer_x0[4] - sc.observer_x0_printed[4]) > 0.02
        assert sc.a_max * em.acceleration_unit_km_s2 == pytest.approx(a_km, rel=1e-12)
        assert sc.system.tu_to_days(sc.period) == pytest.approx(16.17, abs=0.01)
        # daily measurements spanning the window
        tm = sc.measurement_times
        assert tm[0] == sc.window[0] and tm[-1] <= sc.window[1] and sc.window[1] - tm[-1] < em.days_to_tu(1.0)
        np.testing.assert_allclose(np.diff(tm), em.days_to_tu(1.0), rtol=1e-12)
        P0 = sc.prior_covariance
        assert P0.shape == (6 * (n_t + 1),) * 2
        assert np.sqrt(P0[6, 6]) * em.length_unit_km == pytest.approx(100.0)
        assert np.sqrt(P0[9, 9]) * em.velocity_unit_km_s == pytest.approx(1e-2)
    assert case1.model.name == "relative_position" and case2.model.name == "range_range_rate"
    assert np.sqrt(case2.noise[1, 1]) * em.velocity_unit_km_s == pytest.approx(1e-2)  # 10 m/s
    assert np.sqrt(case2.noise[0, 0]) * em.length_unit_km == pytest.approx(0.1)  # 100 m
    # windows in days: the paper's text says 12-23 d (case 1) and roughly 17-32 d (case 2)
    np.testing.assert_allclose(em.tu_to_days(np.array(case1.window)), [12.13, 24.26], atol=0.01)
    np.testing.assert_allclose(em.tu_to_days(np.array(case2.window)), [16.17, 32.35], atol=0.01)


def test_process_noise_readings_and_constants():
    r = W.PROCESS_NOISE_READINGS_KM2_S3
    nd = r["1e-11 LU^2/TU^3 (normalised units, adopted)"]
    assert C.psd_to_nondimensional(nd, em) == pytest.approx(W.PROCESS_NOISE_PSD_ND, rel=1e-12)
    assert nd == pytest.approx(2.80e-17, rel=0.01)
    assert C.WOLF_JONES_PSD_KM2_S3 == pytest.approx(nd, rel=1e-12)
    assert W.A_MAX_READINGS_CASE2_KM_S2["literal 5^-7"] == pytest.approx(1.28e-5)
    assert W.keep_out_radius_km() == pytest.approx(300 * np.sqrt(2))


def test_node_times_window_and_bounds(case2):
    t, ks, ke = case2.node_times(30)
    assert t[ks] == case2.window[0] and t[ke] == case2.window[1] and np.all(np.diff(t) > 0)
    assert t[0] == 0 and t[-1] == pytest.approx(case2.duration)
    u = case2.control_bounds(t)
    assert np.all(u[ks:ke + 1] == 0) and np.all(u[:ks] == case2.a_max) and np.all(u[ke + 1:] == case2.a_max)
    with pytest.raises(ValueError, match="window"):
        W.node_times_with_window(np.linspace(0, 1, 5), (0.5, 1.5))
    with pytest.raises(ValueError, match="n_nodes"):
        W.node_times_with_window(np.linspace(0, 1, 3), (0.4, 0.6))


def test_impulse_trapezoid():
    t = np.array([0.0, 1.0, 3.0])
    u = np.array([[3.0, 4.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 0.0]])
    assert W.impulse(t, u) == pytest.approx(1.0 * (5 + 1) / 2 + 2.0 * (1 + 0) / 2)


# ------------------------------------------------------------------------------------------------ information model
@pytest.mark.parametrize("which", [1, 2])
def test_information_value_and_gradient_are_one_function(which, case1, case2):
    """d I / d x_S(window start) against 4th-order central differences of the value on the test-case window."""
    sc = case1 if which == 1 else case2
    model = sc.information_model()
    x = _window_start(sc)
    v0 = model(x, 0)
    v1, g = model(x, 1)
    assert v1 == pytest.approx(v0, rel=1e-11)  # the same function, not two that differ by 0.5 %
    h = 2e-7
    fd = np.empty(6)
    for j, e in enumerate(np.eye(6)):
        fd[j] = (8 * (model(x + h * e) - model(x - h * e)) - (model(x + 2 * h * e) - model(x - 2 * h * e))) / (12 * h)
    scale = np.max(np.abs(fd))
    np.testing.assert_allclose(g, fd, rtol=2e-6, atol=2e-6 * scale)
    assert abs(g[2]) < 1e-9 * scale and abs(g[5]) < 1e-9 * scale  # planar: the z-gradient vanishes (saddle)


def test_fixed_process_noise_is_held_and_differs_from_recomputed(case1):
    """The planning model holds Q along its reference; the CRLB evaluation recomputes it: equal at the reference,
    different (slightly) away from it."""
    model = case1.information_model()
    x = _window_start(case1)
    assert W.evaluate_crlb(case1, x).mutual_information == pytest.approx(model(x), rel=1e-9)
    dx = np.r_[em.km_to_lu(2000.0), 0, 0, 0, 0, 0]
    recomputed = W.evaluate_crlb(case1, x + dx).mutual_information
    held = model(x + dx)
    assert held != pytest.approx(recomputed, rel=1e-8)
    assert held == pytest.approx(recomputed, rel=0.05)
    np.testing.assert_array_equal(model.linearization(x + dx).Q, model.Q)


def test_hessian_matches_second_differences_of_value(case1):
    model = case1.information_model()
    central = W.WindowInformation(case1.system, model.t, model.targets_x0, model.model, model.noise, model.P0,
                                  q=model.q, x_reference=model.x_reference, hessian_scheme="central")
    x = _window_start(case1)
    H = central.hessian(x)
    np.testing.assert_allclose(H, H.T)
    h = 2e-6
    v0 = model(x)
    for i in (0, 1, 2, 4):  # diagonal second differences of the value (independent of the gradient code)
        e = h * np.eye(6)[i]
        d2 = (model(x + e) - 2 * v0 + model(x - e)) / h**2
        assert H[i, i] == pytest.approx(d2, rel=1e-3)
    # forward differences agree to O(h) and the concave model is negative semi-definite
    Hf = model.hessian(x)
    assert np.max(np.abs(Hf - H)) < 5e-3 * np.max(np.abs(H))
    value, grad, Hneg = model.concave_model(x)
    assert value == pytest.approx(model(x)) and np.all(np.linalg.eigvalsh(Hneg) <= 1e-6 * np.max(np.abs(H)))
    w = np.linalg.eigvalsh(Hf)
    assert np.linalg.eigvalsh(Hneg)[0] == pytest.approx(min(w[0], 0.0), rel=1e-9)


def test_case2_planar_guess_is_a_saddle_in_z(case2):
    """Positive curvature of the MI along z at the planar guess: out-of-plane motion in either sign gains."""
    model = case2.information_model()
    x = _window_start(case2)
    dz = np.zeros(6)
    dz[5] = 1e-4  # 0.1 m/s-ish out-of-plane velocity
    up, down, mid = model(x + dz), model(x - dz), model(x)
    assert up > mid and down > mid
    assert up == pytest.approx(down, rel=1e-9)  # z-mirror symmetry of the CR3BP and of the measurement


# ------------------------------------------------------------------------------------------------ keep-out
def test_keep_out_values_and_jacobian(case2):
    t, ks, _ = case2.node_times(30)
    ko = case2.keep_out(ks)
    x = _window_start(case2)
    c, Cj = ko(x)
    assert c.shape == (ko.size,) and Cj.shape == (ko.size, 6) and ko.size == 3 * case2.measurement_times.size
    np.testing.assert_allclose(c, ko.d_min - ko.ranges(x).reshape(-1), rtol=1e-12)
    assert ko.d_min * em.length_unit_km == pytest.approx(W.keep_out_radius_km())
    # the ballistic reference respects it with a wide margin
    assert np.max(c) * em.length_unit_km < -1000.0
    h = 1e-7
    fd = np.stack([(ko(x + h * e)[0] - ko(x - h * e)[0]) / (2 * h) for e in np.eye(6)], axis=1)
    np.testing.assert_allclose(Cj, fd, rtol=1e-6, atol=1e-6 * np.max(np.abs(fd)))
    # first-order model: the error of c + C dx shrinks quadratically with the step
    dx = 1e-4 * np.array([1.0, -2.0, 0.5, 0.3, 0.1, -0.2])
    err1 = np.max(np.abs(ko(x + dx)[0] - (c + Cj @ dx)))
    err2 = np.max(np.abs(ko(x + dx / 2)[0] - (c + Cj @ dx / 2)))
    assert 3.0 < err1 / err2 < 5.0
    # in position space the linearised keep-out is the tangent half-space: conservative for the sphere
    r = np.array([0.3, -0.2, 0.1])
    n = r / np.linalg.norm(r)
    for dr in np.random.default_rng(0).normal(scale=0.2, size=(20, 3)):
        assert ko.d_min - np.linalg.norm(r + dr) <= ko.d_min - np.linalg.norm(r) - n @ dr + 1e-15


# ------------------------------------------------------------------------------------------------ CRLB
def test_crlb_result_consistent_with_covariance_analysis(case2):
    x = _window_start(case2)
    res = W.evaluate_crlb(case2, x)
    n = res.t.size
    assert res.sigma_axes_km.shape == (4, n, 3) and res.rms_km.shape == (4, n)
    np.testing.assert_allclose(res.rms_km, np.sqrt(np.sum(res.sigma_axes_km**2, axis=-1)))
    targets = case2.targets_at([res.t[0]])[:, 0]
    lin = C.linearize_augmented(em, x, targets, res.t, case2.model, case2.noise, case2.prior_covariance, q=case2.q)
    hist = C.covariance_analysis(*lin.arrays)
    for i in range(4):
        np.testing.assert_allclose(res.rms_km[i], C.position_sigma_km(hist.posterior, i, em), rtol=1e-10)
    assert res.mutual_information == pytest.approx(I.mutual_information(*lin.arrays), rel=1e-12)
    # the first measurement cannot increase the prior 3-D RMS of 173 km
    assert np.all(res.rms_km[:, 0] <= np.sqrt(3) * 100.0 + 1e-9)


def test_process_noise_reading_decides_boundedness(case1):
    """The evidence for the adopted unit: the literal km^2/s^3 reading lets the alpha_h = 0 CRLB grow past 10^4 km,
    the adopted normalised reading keeps it within a few prior sigmas."""
    x = _window_start(case1)
    big = W.evaluate_crlb(case1, x, q=C.psd_to_nondimensional(1e-11, em))
    adopted = W.evaluate_crlb(case1, x)
    assert big.terminal_rms_km[0] > 1e4
    assert adopted.terminal_rms_km[0] < 500.0
    assert adopted.terminal_rms_km[0] < 0.5 * np.max(adopted.rms_km[0])  # bounded after the initial transient


def test_bad_input(case1):
    with pytest.raises(ValueError, match="scenario"):
        W.evaluate_crlb("case", np.zeros(6))
    model = case1.information_model()
    with pytest.raises(ValueError, match="order"):
        model(np.zeros(6) + 0.8, 2)
    with pytest.raises(ValueError, match="hessian_scheme"):
        W.WindowInformation(case1.system, model.t, model.targets_x0, model.model, model.noise, model.P0, q=1e-11,
                            x_reference=model.x_reference, hessian_scheme="exact")
    with pytest.raises(ValueError, match="q"):
        W.test_case_1(q=-1.0)


# ------------------------------------------------------------------------------------------------ re-flight, solutions
def test_fly_reproduces_first_order_hold(case1):
    """Interpolating the FOH control onto a refined grid must not change the flight (FOH is linear in time)."""
    from cislunar.guidance.discretization import propagate_foh

    t = np.linspace(0.0, case1.window[0], 6)
    u = 0.3 * case1.a_max * np.random.default_rng(3).normal(size=(6, 3))
    tf, xf = W.fly(case1, t, u, refine=5)
    assert tf.size == 5 * 5 + 1 and np.all(np.isin(t, tf))
    coarse = propagate_foh(em, case1.observer_x0, t, u)
    np.testing.assert_allclose(xf[np.isin(tf, t)], coarse, rtol=0, atol=1e-11)
    # zero control is the ballistic DRO
    _, x0 = W.fly(case1, t, np.zeros((6, 3)), refine=2)
    np.testing.assert_allclose(x0[-1], propagate(em, case1.observer_x0, [0.0, t[-1]]).x[-1], atol=1e-11)


@pytest.fixture(scope="module")
def case2_sweep(case2):
    """One warm-started homotopy chain alpha_h = 0 -> 1e-3 on case 2 (two SCvx solves shared by the module; the
    up/down merge of sweep_both_ways is tested with a stand-in solver below)."""
    t, ks, ke = case2.node_times(16)
    solver = W.ScenarioSolver(case2, t, ks, keep_out=True)
    x, u = case2.ballistic_guess(t)
    r0 = solver(0.0, x, u)
    r1 = solver(1e-3, r0.x, r0.u)
    from cislunar.guidance.scvx import SweepResult

    return t, ks, ke, solver, SweepResult(np.array([0.0, 1e-3]), [r0, r1], ["up", "up"], [])


def test_case2_solutions_are_feasible_and_monotone(case2, case2_sweep):
    """Converged test-case-2 solutions: defects, single-shooting miss, Eq. 41 bounds, zero thrust in the window,
    keep-out, and MI/impulse non-decreasing along the (small) homotopy grid; alpha_h > 0 leaves the plane."""
    t, ks, ke, solver, best = case2_sweep
    assert all(r is not None for r in best.best)
    for r in best.best:
        assert r.max_defect <= 1e-9
        assert W.terminal_miss_km(case2, t, r.u) <= 1.0
        u = np.linalg.norm(r.u, axis=1)
        assert np.all(u <= solver.u_max * (1 + 1e-6) + 1e-12)
        assert np.all(u[ks:ke + 1] <= 1e-12)
        c, _ = solver.constraints[0](r.x[ks])
        assert np.max(c) <= 1e-9
        assert r.information == pytest.approx(solver.information(r.x[ks]), rel=1e-9)
    imp = best.column("impulse")
    mi = best.column("information")
    assert imp[1] >= imp[0] and mi[1] >= mi[0]
    assert np.max(np.abs(best.best[1].x[:, 2])) * em.length_unit_km > 10.0  # out of plane
    # the information trajectory is far better determined than the minimum-impulse one
    rms = [W.evaluate_crlb(case2, r.x[ks]).terminal_rms_km[0] for r in best.best]
    assert rms[1] < 0.5 * rms[0]


# ------------------------------------------------------------------------------------------------ sweeps, budgets
class _Res:
    def __init__(self, alpha, cost, x, u, impulse=0.0):
        self.alpha, self.cost, self.x, self.u, self.impulse, self.iterations = alpha, cost, x, u, impulse, 1


class _ToySolver:
    """Picklable stand-in with two basins: a warm start from a large control (u > 0.5) lands in a basin 0.01
    worse; the upward chain's warm start at alpha = 0.2 fails (forcing the cold retry) and its warm start at
    alpha >= 0.5 is 0.02 worse than the downward chain's cold start there."""

    def __call__(self, alpha, x, u):
        from cislunar.guidance.scvx import SCvxError

        warm = bool(np.any(u))
        basin = float(u[0, 0]) if warm else 0.0
        if warm and basin <= 0.5 and alpha == 0.2:
            raise SCvxError("toy failure", [{"iteration": 0}])
        cost = -alpha + (0.01 if basin > 0.5 else 0.0) + (0.02 if warm and basin <= 0.5 and alpha >= 0.5 else 0.0)
        return _Res(alpha, cost, x, np.full_like(u, 1.0 if alpha >= 0.5 or basin > 0.5 else 0.1))


def test_sweep_both_ways_merges_retries_and_is_executor_independent():
    from concurrent.futures import ThreadPoolExecutor

    x, u = np.zeros((4, 6)), np.zeros((4, 3))
    alphas = [0.0, 0.2, 0.6]
    serial = W.sweep_both_ways(_ToySolver(), alphas, x, u)
    with ThreadPoolExecutor(2) as ex:
        threaded = W.sweep_both_ways(_ToySolver(), alphas, x, u, executor=ex)
    for sw in (serial, threaded):
        assert sw.source == ["up", "up", "down"]  # the lower cost of the two chains per alpha
        np.testing.assert_allclose([r.cost for r in sw.best], [0.0, -0.2, -0.6])
        assert [(a["alpha"], a["direction"], a["start"], a["converged"]) for a in sw.attempts] == [
            (0.0, "up", "cold", True), (0.2, "up", "warm", False), (0.2, "up", "cold", True),
            (0.6, "up", "warm", True), (0.6, "down", "cold", True), (0.2, "down", "warm", True),
            (0.0, "down", "warm", True)]
        np.testing.assert_allclose([a["cost"] for a in sw.attempts],
                                   [0.0, np.nan, -0.2, -0.58, -0.6, -0.19, 0.01], equal_nan=True)
    with pytest.raises(ValueError, match="alphas"):
        W.sweep_both_ways(_ToySolver(), [0.2, 0.1], x, u)
    with pytest.raises(ValueError, match="executor"):
        W.sweep_both_ways(_ToySolver(), alphas, x, u, executor=object())


def test_sweep_one_way_is_that_chain_of_the_two_way_sweep():
    """``directions`` runs only the named chains: each one-way sweep returns exactly that chain's plans and
    attempts (same costs, same retries), and the two-way sweep is the per-alpha best of the two."""
    x, u = np.zeros((4, 6)), np.zeros((4, 3))
    alphas = [0.0, 0.2, 0.6]
    both = W.sweep_both_ways(_ToySolver(), alphas, x, u)
    up = W.sweep_both_ways(_ToySolver(), alphas, x, u, directions=["up"])
    down = W.sweep_both_ways(_ToySolver(), alphas, x, u, directions=("down",))
    assert up.source == ["up"] * 3 and down.source == ["down"] * 3
    np.testing.assert_allclose([r.cost for r in up.best], [0.0, -0.2, -0.58])  # warm start at 0.6: 0.02 worse
    np.testing.assert_allclose([r.cost for r in down.best], [0.01, -0.19, -0.6])  # the downward basin
    for one, d in ((up, "up"), (down, "down")):  # the same attempts as that chain of the two-way sweep
        chain = [a for a in both.attempts if a["direction"] == d]
        assert [(a["alpha"], a["start"], a["converged"]) for a in one.attempts] == [
            (a["alpha"], a["start"], a["converged"]) for a in chain]
        np.testing.assert_allclose([a["cost"] for a in one.attempts], [a["cost"] for a in chain], equal_nan=True)
    assert [a["start"] for a in up.attempts] == ["cold", "warm", "cold", "warm"]
    assert [a["direction"] for a in down.attempts] == ["down"] * 3
    np.testing.assert_allclose([r.cost for r in both.best],
                               np.minimum([r.cost for r in up.best], [r.cost for r in down.best]))
    reversed_order = W.sweep_both_ways(_ToySolver(), alphas, x, u, directions=("down", "up"))
    assert reversed_order.source == both.source  # chains always merged in the order up, down
    for bad in ([], ["up", "up"], ["sideways"]):
        with pytest.raises(ValueError, match="directions"):
            W.sweep_both_ways(_ToySolver(), alphas, x, u, directions=bad)
    with pytest.raises(TypeError, match="directions"):
        W.sweep_both_ways(_ToySolver(), alphas, x, u, directions="up")

class _FrontSolver:
    """impulse(alpha) along a toy front; counts solves; a jump makes a budget unreachable."""

    def __init__(self, f):
        self.f, self.calls = f, []

    def __call__(self, alpha, x, u):
        self.calls.append(alpha)
        return _Res(alpha, -alpha, x, u, impulse=self.f(alpha))


def test_solve_for_impulse_hits_the_budget_and_reports_a_jump():
    import pickle

    x, u = np.zeros((3, 6)), np.zeros((3, 3))
    f = lambda a: 0.4 + 3e3 * a**2 + 50.0 * a  # noqa: E731 - convex, monotone impulse(alpha)
    sol = _FrontSolver(f)
    lo, hi = (0.0, sol(0.0, x, u)), (0.02, sol(0.02, x, u))
    out = W.solve_for_impulse(sol, 1.5, lo, hi, rtol=1e-6, max_solves=30)
    assert abs(out.result.impulse - 1.5) <= 1.5e-6
    a_true = (-50.0 + np.sqrt(50.0**2 + 4 * 3e3 * 1.1)) / (2 * 3e3)
    assert out.alpha == pytest.approx(a_true, rel=1e-5)
    assert len(out.solves) <= 12  # Illinois: superlinear, not bisection-slow
    assert [s[0] for s in out.solves] == sol.calls[2:]
    # a budget on a bracket end is returned without a solve
    assert W.solve_for_impulse(sol, f(0.02), lo, hi).alpha == 0.02
    # the budget outside the bracket is refused by name
    with pytest.raises(ValueError, match="bracket"):
        W.solve_for_impulse(sol, 100.0, lo, hi)
    # a front that jumps across the budget: no alpha_h spends it; the error carries every try and pickles
    jump = _FrontSolver(lambda a: 0.4 if a < 0.01 else 20.0)
    with pytest.raises(W.ImpulseBudgetError) as err:
        W.solve_for_impulse(jump, 5.0, (0.0, jump(0.0, x, u)), (0.02, jump(0.02, x, u)), max_solves=6)
    assert len(err.value.solves) == 6 and err.value.budget == 5.0
    back = pickle.loads(pickle.dumps(err.value))
    assert back.solves == err.value.solves and back.reason == err.value.reason


# ------------------------------------------------------------------------------------------------ control-term normalisation
def test_control_scale_against_hand_values(case1):
    """c of each reading of Eq. 42's control term, against numbers computed by hand from the Earth-Moon units
    (L = 384,400 km, T = 375,190.25852 s: 1 LU/TU = 1.02454686 km/s; 2 periods of 16.1713 d = 32.3426 d)."""
    t, _, _ = case1.node_times(12)
    vu = 384400.0 / 375190.25852  # km/s per LU/TU, by hand
    days = 2 * case1.period * 375190.25852 / 86400.0
    assert days == pytest.approx(32.34, abs=0.01)
    assert W.control_scale(case1, t) == 1.0  # the adopted reading: exactly today's cost
    assert W.control_scale(case1, t, unit="km/s") == pytest.approx(vu, rel=1e-12)
    assert W.control_scale(case1, t, unit="m/s") == pytest.approx(1024.5468566, rel=1e-9)
    assert W.control_scale(case1, t, average="node") == pytest.approx(1.0 / 12, rel=1e-15)  # N nodes, not N-1
    assert W.control_scale(case1, t, unit="m/s", average="node") == pytest.approx(1e3 * vu / 12, rel=1e-12)
    assert W.control_scale(case1, t, unit="m/s", average="day") == pytest.approx(1e3 * vu / days, rel=1e-12)
    with pytest.raises(ValueError, match="unit"):
        W.control_scale(case1, t, unit="ft/s")
    with pytest.raises(ValueError, match="control_average"):
        W.ScenarioSolver(case1, t, case1.node_times(12)[1], control_average="mean")


def test_normalised_cost_scales_only_the_control_term(case1):
    """Identity: J_c - J_1 = (1 - alpha)(c - 1) impulse, for any nodes; and the m/s total against a hand sum."""
    t, k, _ = case1.node_times(10)
    x, _ = case1.ballistic_guess(t)
    rng = np.random.default_rng(7)
    u = case1.control_bounds(t)[:, None] * rng.uniform(-0.5, 0.5, size=(t.size, 3))
    info = case1.information_model()
    default = W.ScenarioSolver(case1, t, k, information=info)
    mi = info(x[k], 0)
    imp = W.impulse(t, u)
    for unit, average in (("m/s", "total"), ("LU/TU", "node"), ("m/s", "day")):
        s = W.ScenarioSolver(case1, t, k, information=info, control_unit=unit, control_average=average)
        c = s.control_scale
        for alpha in (0.0, 5e-3, 2e-2, 1.0):
            lhs = s.cost(x, u, alpha) - default.cost(x, u, alpha)
            assert lhs == pytest.approx((1 - alpha) * (c - 1) * imp, rel=1e-12, abs=1e-15)
            # the control part alone is c times the default's
            assert s.cost(x, u, alpha) + alpha * mi * (alpha > 0) == pytest.approx(
                c * (default.cost(x, u, alpha) + alpha * mi * (alpha > 0)), rel=1e-12, abs=1e-18)
    # hand computation of the m/s total: trapezoid of |u| in km/s^2 over seconds, times 1000
    s = W.ScenarioSolver(case1, t, k, information=info, control_unit="m/s")
    a_kms2 = np.linalg.norm(u, axis=1) * em.acceleration_unit_km_s2
    dt_s = np.diff(t) * em.time_unit_s
    hand_mps = 1e3 * float(np.sum(dt_s * (a_kms2[:-1] + a_kms2[1:]) / 2))
    assert s.cost(x, u, 2e-2) == pytest.approx(0.98 * hand_mps - 2e-2 * mi, rel=1e-10)
    # the default cost is what SCvx itself reports (same formula, same bits)
    assert default.cost(x, u, 5e-3) == (1.0 - 5e-3) * imp - 5e-3 * mi


def test_normalised_solve_is_the_default_solve_at_the_equivalent_weight(case1):
    """(1-a) c I_u - a I has the minimisers of (1-a') I_u - a' I with a'/(1-a') = a/((1-a) c): the solver with
    normalisation c at a must land where the default solver lands at a' (same start, same local optimum); the
    default options give the unscaled solve bit for bit."""
    from cislunar.guidance.scvx import solve_scvx

    t, k, _ = case1.node_times(10)
    xb, ub = case1.ballistic_guess(t)
    info = case1.information_model()
    alpha = 2e-2
    s = W.ScenarioSolver(case1, t, k, information=info, control_unit="m/s", control_average="day")
    c = s.control_scale
    a_eq = alpha / (alpha + (1 - alpha) * c)
    default = W.ScenarioSolver(case1, t, k, information=info)
    r_c, r_1 = s(alpha, xb, ub), default(a_eq, xb, ub)
    assert r_c.alpha == alpha and r_1.alpha == a_eq
    # the same optimum: equal J_c to the solver's tolerance (the front is flat there: impulse and MI agree only to
    # 1e-3 and 1e-4); a wrong scale (c instead of 1/c on the information) lands orders of magnitude away
    assert s.cost(r_1.x, r_1.u, alpha) == pytest.approx(r_c.cost, rel=1e-7)
    assert r_c.impulse == pytest.approx(r_1.impulse, rel=1e-3)
    assert r_c.information == pytest.approx(r_1.information, rel=1e-4)
    # the reported cost is J_c in its own units, the information in nats
    assert r_c.cost == s.cost(r_c.x, r_c.u, alpha)
    assert r_c.information == info(r_c.x[k], 0)
    # the default options are the unscaled solve, bit for bit
    direct = solve_scvx(case1.system, t, xb, ub, default.u_max, x_final=case1.observer_xf, info=info, info_node=k,
                        alpha=a_eq)
    assert r_1.cost == direct.cost and np.array_equal(r_1.u, direct.u) and np.array_equal(r_1.x, direct.x)
