"""Notebook 03's studies: the transfer problem, one SCvx solve on few nodes, the reading of an iteration history and
the single-shooting check."""

from types import SimpleNamespace

import numpy as np
import pytest

from cislunar.guidance import scvx
from cislunar.papers.wolf_jones import scenarios as wj
from cislunar.papers.wolf_jones import scvx_study as S


@pytest.fixture(scope="module")
def problem():
    return S.transfer_problem(16, 1.0)


def test_problem_has_a_thrust_free_window(problem):
    k0, k1 = problem.k_window
    assert 0 < k0 < k1 < problem.t.size - 1
    assert np.all(problem.u_max[k0:k1 + 1] == 0) and np.all(problem.u_max[:k0] == problem.scenario.a_max)
    assert np.all(problem.in_window == (problem.u_max == 0))
    assert np.allclose(problem.x_guess[0], problem.x0) and problem.ballistic_miss > 1e-4  # a transfer is needed
    with pytest.raises(ValueError):
        S.transfer_problem(2)


def test_zero_control_single_shooting_is_the_ballistic_arc(problem):
    shot = S.single_shooting(problem, np.zeros((problem.t.size, 3)))
    assert np.allclose(shot.x, problem.x_guess, atol=1e-9)
    em = problem.system
    miss = problem.x_guess[-1] - problem.x_final
    assert shot.miss_km == pytest.approx(np.linalg.norm(miss[:3]) * em.length_unit_km, rel=1e-6)


def test_solve_converges_and_flies(problem):
    res = S.solve(problem)
    assert res.max_defect < 1e-9 and res.impulse > 0
    assert np.max(np.linalg.norm(res.u[problem.in_window], axis=1)) == 0
    assert S.single_shooting(problem, res.u).miss_km < 1.0
    summary = S.iteration_summary(res, scvx.SCvxSettings())
    assert summary.n_steps == len(res.history) and summary.defect_ratio.size == summary.n_steps - 1


def test_iteration_summary_applies_the_noise_rule():
    settings = scvx.SCvxSettings()
    base = {"accepted": True, "multiplier_update": False, "eta": 0.05}
    hist = [dict(base, iteration=0, cost=1.0, predicted=0.5, rho=0.9, max_defect=1e-2),
            dict(base, iteration=1, cost=0.5, predicted=-1e-12, rho=1.0, max_defect=1e-3, multiplier_update=True),
            dict(base, iteration=2, cost=0.6, predicted=0.1, rho=0.8, max_defect=1e-3, accepted=False, eta=0.1)]
    s = S.iteration_summary(SimpleNamespace(history=hist), settings)
    assert s.forced == (1,) and s.forced_negative == 1 and s.n_real == 2 and s.rho_range == (0.8, 0.9)
    assert s.n_accepted == 2 and s.updates == (1,) and (s.eta_start, s.eta_end) == (0.05, 0.1)
    assert np.allclose(s.defect_ratio, [0.1, 1.0])
    with pytest.raises(ValueError):
        S.iteration_summary(SimpleNamespace(history=[]), settings)


def _summary(defects, accepted=None):
    base = {"multiplier_update": False, "eta": 0.05, "cost": 1.0, "predicted": 0.1, "rho": 0.9}
    accepted = [True] * len(defects) if accepted is None else accepted
    hist = [dict(base, iteration=i, max_defect=d, accepted=a) for i, (d, a) in enumerate(zip(defects, accepted))]
    return S.iteration_summary(SimpleNamespace(history=hist), scvx.SCvxSettings())


def test_superlinear_rate_is_judged_above_the_round_off_floor():
    """Ratios tending to zero pass; a linear rate fails; a step with an end below the floor (defect_tol, 5e-10) is
    left out; rejected steps do not count; fewer than three ratios above the floor cannot show a rate."""
    fast = _summary([1e-2, 1e-3, 1e-5, 1e-9])  # ratios 0.1, 0.01, 1e-4
    assert fast.rate_floor == scvx.SCvxSettings().defect_tol and np.allclose(fast.rate_ratios, [0.1, 0.01, 1e-4])
    assert fast.superlinear(3, 0.5)
    assert not _summary([1e-2, 1e-3, 1e-4, 1e-5]).superlinear(3, 0.5)  # linear: every ratio 0.1
    assert not _summary([1e-2, 1e-3, 1e-4, 4e-5]).superlinear(3, 0.5)  # the last ratio grows
    # a round-off step (1e-11 -> 3e-10, ratio 30, both ends below the floor) and one that ends below it are left out
    noisy = _summary([1e-2, 1e-3, 1e-5, 1e-9, 1e-11, 3e-10])
    assert np.allclose(noisy.rate_ratios, [0.1, 0.01, 1e-4]) and noisy.superlinear(3, 0.5)
    assert noisy.defect_ratio.max() == pytest.approx(30.0)  # the raw ratios keep it
    # a rejected step (its defect is the trial's, not an iterate's) is not part of the sequence
    rejected = _summary([1e-2, 1e-3, 5e-2, 1e-5, 1e-9], accepted=[True, True, False, True, True])
    assert np.allclose(rejected.rate_ratios, [0.1, 0.01, 1e-4]) and rejected.superlinear(3, 0.5)
    assert not _summary([1e-2, 1e-4, 1e-12]).superlinear(3, 0.5)  # one ratio above the floor: no rate shown


def test_guess_study_draws_first_and_matches_through_an_executor(problem):
    from concurrent.futures import ThreadPoolExecutor

    guess = S.blended_guess(problem)
    assert np.allclose(guess[0], problem.x0) and np.allclose(guess[-1], problem.x_final)  # ends of the blend
    ref = S.solve(problem).impulse
    serial = S.guess_study(problem, 2, np.random.default_rng(5), ref, max_iter=60)
    with ThreadPoolExecutor(2) as pool:
        pooled = S.guess_study(problem, 2, np.random.default_rng(5), ref, max_iter=60, executor=pool)
    assert np.array_equal(serial.impulses, pooled.impulses) and serial.iterations == pooled.iterations
    assert serial.spread == pytest.approx((serial.impulses.max() - serial.impulses.min()) / ref)
    assert serial.spread < 1e-6  # the same optimum from both guesses
    assert serial.plans.shape == (2, problem.t.size, 6) and np.array_equal(serial.plans, pooled.plans)
    assert np.allclose(serial.plans[:, 0], problem.x0) and np.allclose(serial.plans[:, -1], problem.x_final)


def test_a_tighter_thrust_bound_reaches_the_problem(problem):
    tight = S.transfer_problem(16, 1.0, a_max_km_s2=1e-8)
    assert tight.scenario.a_max == pytest.approx(0.01 * problem.scenario.a_max)
    assert np.allclose(tight.u_max, 0.01 * problem.u_max) and np.array_equal(tight.t, problem.t)


def test_printed_method_study_costs_are_the_objective_of_independent_runs():
    """The reference row is the package's default run (re-solved here independently: the same cost to round-off);
    each row's cost is (1 - alpha) impulse - alpha MI of its last accepted step, and gaps are cost differences."""
    study = S.printed_method_study(10, alpha=5e-3, max_iter=60, labels=["L1 + linear, practical"])
    assert list(study.runs) == ["AL + quadratic, strict", "L1 + linear, practical"]
    ref = study.runs["AL + quadratic, strict"]
    assert ref.converged and ref.stopped_by == "strict"
    sc = wj.test_case_1()
    t, k_ws, _ = sc.node_times(10, 1.0)
    x0, u0 = sc.ballistic_guess(t)
    info = sc.information_model()
    res = scvx.solve_scvx(sc.system, t, x0, u0, sc.control_bounds(t), x_final=sc.observer_xf, info=info,
                          info_node=k_ws, alpha=5e-3)
    assert ref.cost == pytest.approx(res.cost, rel=1e-12, abs=1e-14)
    assert res.cost == pytest.approx((1 - 5e-3) * res.impulse - 5e-3 * info(res.x[k_ws], 0), rel=1e-12)
    pen = study.runs["L1 + linear, practical"]
    assert pen.method == "penalty" and pen.information_model == "linear" and pen.practical
    last = [h for h in pen.history if h["accepted"]][-1]
    assert pen.cost == pytest.approx((1 - 5e-3) * last["impulse"] - 5e-3 * last["information"], rel=1e-14)
    assert study.gap(pen.label) == pytest.approx(pen.cost - ref.cost, rel=1e-14)
    if not pen.converged:  # a run that does not stop says why, and never claims a practical stop
        assert pen.stopped_by == "" and pen.outcome
    assert "L1 + linear, practical" in study.summary()
    with pytest.raises(ValueError, match="labels"):
        S.printed_method_study(10, labels=["L2 + cubic"])
    with pytest.raises(ValueError, match="alpha"):
        S.printed_method_study(10, alpha=0.0)


def test_printed_method_runs_at_other_penalty_weights():
    """A gamma run at the package's weight (1e3) is the printed-method variant itself; another weight changes it."""
    study = S.printed_method_study(6, alpha=5e-3, max_iter=3, labels=["L1 + linear, practical"], gammas=[1e3, 1e1])
    same, other, pen = study.gamma_runs[1e3], study.gamma_runs[1e1], study.runs["L1 + linear, practical"]
    assert list(study.gamma_runs) == [1e3, 1e1] and same.method == "penalty" and same.information_model == "linear"
    assert same.practical and [h["cost"] for h in same.history] == [h["cost"] for h in pen.history]
    assert [h["cost"] for h in other.history] != [h["cost"] for h in pen.history]
    assert "gamma 1e+01" in study.summary()
    for bad in ([0.0], 5.0):
        with pytest.raises(ValueError, match="gammas"):
            S.printed_method_study(6, max_iter=1, labels=[], gammas=bad)


def test_node_defects_are_measured_independently(problem):
    """A plan flown by heyoka under a first-order-hold control has DOP853 defects at the integrators' round-off; the
    same nodes with the control shifted by one node, or with one node moved by 1e-9, show the defect."""
    from cislunar.guidance import discretization as D
    from cislunar.papers.wolf_jones.claims.scvx import DEFECT_TOL, INTEGRATOR_ALLOWANCE

    em, t = problem.system, problem.t
    u = 0.3 * problem.u_max[:, None] * np.sin(np.arange(t.size)[:, None] + np.arange(3)[None, :])  # FOH, zero in window
    x = D.propagate_foh(em, problem.x0, t, u)
    d = S.NodeDefects.of(em, t, x, u)
    assert d.defects.shape == (t.size - 1,) and d.largest < 1e-11  # passes the row's tolerance by far
    assert d.largest <= DEFECT_TOL + INTEGRATOR_ALLOWANCE and np.all(d.integrator_spread < 1e-10)
    shifted = S.NodeDefects.of(em, t, x, np.roll(u, 1, axis=0))  # the solver flying another control than it returns
    assert shifted.largest > 1e3 * (DEFECT_TOL + INTEGRATOR_ALLOWANCE)
    moved = x.copy()
    moved[5, 0] += 1e-9  # one node off by 1e-9 LU: the interval ending there shows it, the next about as much
    dm = S.NodeDefects.of(em, t, moved, u)
    assert dm.defects[4] == pytest.approx(1e-9, rel=1e-2) and dm.largest > DEFECT_TOL + INTEGRATOR_ALLOWANCE
    assert np.all(np.delete(dm.defects, [4, 5]) < 1e-11)
    with pytest.raises(ValueError):
        S.NodeDefects.of(em, t, x[:-1], u)


def test_same_optimum_needs_both_the_cost_and_the_plan():
    """Impulse within cost_tol (1 + |J|) and every node within the distance: a cost off by 1e-7 or a node 2 km away
    fails."""
    from cislunar.cr3bp.dynamics import EARTH_MOON as em

    ref_x = np.zeros((5, 6))
    ref_x[:, 0] = np.linspace(0.8, 0.9, 5)
    plans = np.stack([ref_x, ref_x + 1e-9])
    g = S.GuessStudy(np.array([1e-3, 1e-3 + 1e-9]), (3, 4), 1e-6, plans)
    one_km = em.km_to_lu(1.0)
    assert g.impulse_gap(1e-3) == pytest.approx(1e-9 / (1 + 1e-3))
    assert g.plan_distance(ref_x) == pytest.approx(np.sqrt(3) * 1e-9)
    assert g.same_optimum(1e-3, ref_x, cost_tol=1e-8, distance=one_km)
    far = S.GuessStudy(np.array([1e-3, 1e-3 + 1e-7]), (3, 4), 1e-4, plans)  # impulse 1e-7 away
    assert not far.same_optimum(1e-3, ref_x, cost_tol=1e-8, distance=one_km)
    moved = plans.copy()
    moved[1, 2, 1] += em.km_to_lu(2.0)  # one node of one plan 2 km away
    other = S.GuessStudy(g.impulses, (3, 4), 1e-6, moved)
    assert not other.same_optimum(1e-3, ref_x, cost_tol=1e-8, distance=one_km)
    assert em.lu_to_km(other.plan_distance(ref_x)) == pytest.approx(2.0, rel=1e-3)
    with pytest.raises(ValueError):
        g.same_optimum(1e-3, ref_x, cost_tol=0.0, distance=one_km)
