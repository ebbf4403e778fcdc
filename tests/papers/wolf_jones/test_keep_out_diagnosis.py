"""Test case 2 without a keep-out: the two remedies' MI and gradients, and the close-pass growth each removes."""

from __future__ import annotations

import numpy as np
import pytest

from cislunar.cr3bp.propagation import propagate
from cislunar.papers.wolf_jones import keep_out_diagnosis as K
from cislunar.papers.wolf_jones import scenarios as wj


@pytest.fixture(scope="module")
def case2():
    sc = wj.test_case_2()
    info = sc.information_model()
    x_ws = propagate(sc.system, sc.observer_x0, [0.0, sc.window[0]]).x[-1]
    return sc, info, x_ws


def _gradient_fd4(f, x, h):
    """Fourth-order central differences of the scalar ``f`` at ``x`` (6,), step ``h`` on every component."""
    fd = np.zeros(6)
    for i in range(6):
        e = np.zeros(6)
        e[i] = h
        fd[i] = (8 * (f(x + e) - f(x - e)) - (f(x + 2 * e) - f(x - 2 * e))) / (12 * h)
    return fd


def test_remedy_is_the_paper_mi_far_from_the_targets(case2):
    """rho_c far below every range: the row scale is 1 to ~1e-18, so value and gradient are the paper's."""
    sc, info, x_ws = case2
    tiny = K.RangeNoiseInformation(info, 1e-6)  # 1 mm, against ranges of ~1000 km
    v0, g0 = info(x_ws, 1)
    v1, g1 = tiny(x_ws, 1)
    assert v1 == pytest.approx(v0, rel=1e-9) and np.allclose(g1, g0, rtol=1e-7, atol=1e-9 * np.abs(g0).max())
    big = K.RangeNoiseInformation(info, 141.0)
    assert big(x_ws, 0) < v0  # more noise near the targets: less information


def test_remedy_gradient_matches_finite_differences_near_a_target(case2):
    """At a 50 km pass (well inside rho_c = 141 km, where the scale's derivative dominates), the remedy's gradient
    against fourth-order central differences of its value; the scale's derivative is needed to match."""
    sc, info, x_ws = case2
    remedy = K.RangeNoiseInformation(info, 141.0)
    lin0 = info.linearization(x_ws)
    j, k, _ = K._closest(lin0)
    x = K.passing_state(sc.system, [lin0.t[0], lin0.t[k]], lin0.targets[j, k, :3], 50.0, x_ws)
    _, g = remedy(x, 1)
    fd = _gradient_fd4(remedy, x, 1e-7)
    scale = np.abs(fd).max()
    np.testing.assert_allclose(g, fd, rtol=2e-4, atol=2e-4 * scale)
    # the same pass with the paper's noise: a different gradient (the remedy is not a no-op there)
    assert np.abs(info(x, 1)[1] - g).max() > 0.1 * scale


def test_close_pass_growth_and_its_removal(case2):
    """Below 10 km the whitened range-rate row and the MI gradient grow like 1/rho (log-log slope -1 within 0.2)
    while the range row stays flat; with the range-dependent noise the gradient no longer grows."""
    sc, info, x_ws = case2
    d = np.array([0.3, 1.0, 3.0, 9.0])
    plain = K.pass_scan(sc, info, x_ws, d)
    assert plain.slope("range_rate_row") == pytest.approx(-1.0, abs=0.2)
    assert plain.slope("grad_position") == pytest.approx(-1.0, abs=0.2)
    assert abs(plain.slope("range_row")) < 0.05
    remedy = K.pass_scan(sc, K.RangeNoiseInformation(info, 141.0), x_ws, d)
    assert remedy.slope("grad_position") > -0.2
    assert remedy.grad_position[0] < 0.05 * plain.grad_position[0]


def test_regularised_jacobian_remedy_gradient_matches_finite_differences_near_a_target(case2):
    """At a 50 km pass, the regularised-Jacobian MI's gradient (product rule through the regularising factor)
    against fourth-order central differences of its value; with rho_c far below every range it is the paper's MI."""
    sc, info, x_ws = case2
    remedy = K.RegularisedJacobianInformation(info, 141.0)
    tiny = K.RegularisedJacobianInformation(info, 1e-6)
    v0, g0 = info(x_ws, 1)
    v1, g1 = tiny(x_ws, 1)
    assert v1 == pytest.approx(v0, rel=1e-9) and np.allclose(g1, g0, rtol=1e-7, atol=1e-9 * np.abs(g0).max())
    lin0 = info.linearization(x_ws)
    j, k, _ = K._closest(lin0)
    x = K.passing_state(sc.system, [lin0.t[0], lin0.t[k]], lin0.targets[j, k, :3], 50.0, x_ws)
    _, g = remedy(x, 1)
    fd = _gradient_fd4(remedy, x, 1e-7)
    scale = np.abs(fd).max()
    np.testing.assert_allclose(g, fd, rtol=2e-4, atol=2e-4 * scale)
    # it removes information only (a smaller range-rate row): below the paper's MI, above the range-noise one's
    assert K.RangeNoiseInformation(info, 141.0)(x) < remedy(x) < info(x)


def test_the_regularised_jacobian_bounds_the_reward_but_not_its_gradient(case2):
    """The range-rate row's 1/rho is what makes the reward grow without bound (the paper's MI gains nats below
    ~100 m; with that row regularised the MI stays flat to a micrometre), but not what makes the MI gradient grow:
    that still grows like 1/rho (log-log slope -1 within 0.2 below 10 km), because the line of sight, shared by
    both rows, turns like 1/rho as the observer nears the target.  Only a model that discounts the whole target
    near the observer (the range-dependent noise) bounds the gradient."""
    sc, info, x_ws = case2
    d = np.array([1e-6, 1e-3, 0.3, 1.0, 3.0, 9.0])
    plain = K.pass_scan(sc, info, x_ws, d)
    reg = K.pass_scan(sc, K.RegularisedJacobianInformation(info, 141.0), x_ws, d)
    noise = K.pass_scan(sc, K.RangeNoiseInformation(info, 141.0), x_ws, d)
    assert plain.mi[0] - plain.mi[2] > 5.0  # the paper's reward: +10 nats at a micrometre
    assert abs(reg.mi[0] - reg.mi[2]) < 1e-2  # regularised: flat
    assert reg.slope("grad_position") == pytest.approx(-1.0, abs=0.2)
    assert plain.slope("grad_position") == pytest.approx(-1.0, abs=0.2)
    assert reg.grad_position[1] > 1e3 * noise.grad_position[1]  # at 1 m: still huge, unlike the range noise's


def test_remedy_runs_solve_each_named_remedy(case2, monkeypatch):
    """remedy_runs builds one solver per remedy name, in order, each with its own information model; bad names
    are refused by name (the solves themselves are the notebook's, and are stubbed here)."""
    sc, info, _ = case2
    t, k_ws, _ = sc.node_times(10)
    seen = []

    class Stub:
        def __init__(self, sc_, t_, k_, information=None, keep_out=None, settings=None):
            self.information, self.keep_out = information, keep_out

        def __call__(self, alpha, x, u):
            seen.append((type(self.information).__name__, self.keep_out, alpha))
            raise K.scvx.SCvxError("stub")

    monkeypatch.setattr(K.wj, "ScenarioSolver", Stub)
    x, u = sc.ballistic_guess(t)
    runs = K.remedy_runs(sc, t, k_ws, info, 141.0, [1e-2], x, u, keep_out=True,
                         remedies=("regularised J", "range noise"))
    assert [r.model for r in runs] == ["regularised J", "range noise", "keep-out"]
    assert seen == [("RegularisedJacobianInformation", False, 1e-2), ("RangeNoiseInformation", False, 1e-2),
                    ("WindowInformation", True, 1e-2)]
    assert not any(r.converged for r in runs)
    for bad in ((), ("range noise", "range noise"), ("keep-out",), "range noise"):
        with pytest.raises(ValueError, match="remedies"):
            K.remedy_runs(sc, t, k_ws, info, 141.0, [1e-2], x, u, remedies=bad)


def test_bad_arguments_name_the_argument(case2):
    sc, info, x_ws = case2
    with pytest.raises(ValueError, match="range_scale_km"):
        K.RangeNoiseInformation(info, 0.0)
    with pytest.raises(TypeError, match="inner"):
        K.RangeNoiseInformation(lambda x, o=0: 0.0, 1.0)
    with pytest.raises(ValueError, match="d_km"):
        K.pass_scan(sc, info, x_ws, [1.0, -1.0])


def test_brief_outcome_drops_the_solver_advice_and_keeps_whole_numbers():
    advice = "Try another solver, or solve with verbose=True for more information."
    assert K.brief_outcome(f"convex subproblem failed at iteration 3: Solver 'CLARABEL' failed. {advice}") == (
        "convex subproblem failed at iteration 3: Solver 'CLARABEL' failed.")
    assert K.brief_outcome(f"x failed. {advice} (solver status: failed)") == "x failed. (solver status: failed)"
    kept = "no convergence in 150 iterations (largest defect 2.23e-07)"
    assert K.brief_outcome(kept) == kept
