"""SCvx with first-order hold: feasibility of converged solutions, the homotopy front, failure modes, arguments."""

import pickle

import numpy as np
import pytest

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.propagation import ImpactError, propagate
from cislunar.guidance import discretization as D
from cislunar.guidance import scvx
from cislunar.papers.wolf_jones import scenarios as wolf_jones

A_MAX = 1e-6 / em.acceleration_unit_km_s2  # 1e-6 km/s^2 (Wolf & Jones Table 3)
N_NODES = 24  # coarse, but the same problem as notebook 05
# Up to 1e-2 (notebook 05 goes further): the cold start at the top then converges in ~28 iterations instead of ~80
# at 2e-2, and the front still spans a factor > 100 in impulse and > 20 nats in information.
ALPHAS = (0.0, 1e-3, 3e-3, 1e-2)


@pytest.fixture(scope="module")
def case1():
    """Wolf & Jones test case 1 on a coarse Sundman grid, window ends on nodes, zero thrust in the window."""
    sc = wolf_jones.test_case_1()
    t, k_ws, k_we = sc.node_times(N_NODES)
    x0, u0 = sc.ballistic_guess(t)
    return dict(sc=sc, t=t, k_ws=k_ws, k_we=k_we, x0=x0, u0=u0, u_max=sc.control_bounds(t),
                info=sc.information_model())


def _solve(case, alpha, x, u, **kw):
    return scvx.solve_scvx(em, case["t"], x, u, case["u_max"], x_final=case["sc"].observer_xf, info=case["info"],
                           info_node=case["k_ws"], alpha=alpha, **kw)


@pytest.fixture(scope="module")
def sweep1(case1):
    return scvx.homotopy_sweep(lambda a, x, u: _solve(case1, a, x, u), ALPHAS, case1["x0"], case1["u0"])


def test_every_sweep_run_converges(sweep1):
    assert all(a["converged"] for a in sweep1.attempts), sweep1.attempts
    assert {a["direction"] for a in sweep1.attempts} == {"up", "down"}
    assert all(b is not None for b in sweep1.best)


def test_converged_solutions_are_dynamically_feasible_and_within_bounds(case1, sweep1):
    t, sc = case1["t"], case1["sc"]
    window = (t >= sc.window[0] - 1e-12) & (t <= sc.window[1] + 1e-12)
    assert window.sum() >= 3 and np.all(case1["u_max"][window] == 0)
    for res in sweep1.best:
        # defects recomputed independently of the solver's bookkeeping
        model = D.foh_discretize(em, t, res.x, res.u)
        assert np.max(np.linalg.norm(model.defects, axis=1)) <= 1e-9
        assert res.max_defect <= 1e-9
        # single shooting: the FOH control alone, from the initial state, reaches the terminal state
        xs = D.propagate_foh(em, sc.observer_x0, t, res.u)
        assert np.linalg.norm(xs[-1, :3] - sc.observer_xf[:3]) * em.length_unit_km <= 1.0
        # thrust within the per-node bounds (Eq. 41, acceleration reading) and zero inside the window
        unorm = np.linalg.norm(res.u, axis=1)
        assert np.all(unorm <= case1["u_max"] * (1 + 1e-7) + 1e-12 * A_MAX)
        assert np.all(unorm[window] <= 1e-9 * A_MAX)
        assert np.allclose(res.x[0], sc.observer_x0, atol=1e-12) and np.allclose(res.x[-1], sc.observer_xf, atol=1e-9)
        # the reported information is the model's at the window-start state
        assert res.information == pytest.approx(case1["info"](res.x[case1["k_ws"]], 0), rel=1e-12)


def test_front_is_monotone_in_alpha(sweep1):
    imp, mi = sweep1.column("impulse"), sweep1.column("information")
    assert np.all(np.diff(imp) >= -1e-6 * imp.max()), imp
    assert np.all(np.diff(mi) >= -1e-6), mi
    assert imp[-1] > 10 * imp[0] and mi[-1] > mi[0] + 5.0  # the reward really buys information
    # each best solution is at least as good as every other converged run at its own alpha
    for i, a in enumerate(sweep1.alphas):
        costs = [r["cost"] for r in sweep1.attempts if r["alpha"] == a and r["converged"]]
        assert sweep1.best[i].cost <= min(costs) + 1e-12


def test_cold_start_at_the_largest_alpha_reaches_the_swept_optimum(case1, sweep1):
    res = _solve(case1, ALPHAS[-1], case1["x0"], case1["u0"])
    assert res.max_defect <= 1e-9
    assert res.cost == pytest.approx(sweep1.best[-1].cost, abs=1e-6 * (1 + abs(res.cost)))
    # the log holds what the issue asks for
    keys = {"predicted", "model_error_defect", "model_error_info", "rho", "eta", "tr_active"}
    assert keys <= set(res.history[0])
    last = res.history[-1]
    assert last["accepted"] and not last["tr_active"]


def test_exact_penalty_variant_converges_without_information(free_transfer):
    dro, xf, t = _transfer()
    kw = dict(x_final=xf)
    r_al = free_transfer
    r_pen = scvx.solve_scvx(em, t, propagate(em, dro.x0, t).x, np.zeros((t.size, 3)), np.full(t.size, A_MAX),
                            settings=scvx.SCvxSettings(method="penalty"), **kw)
    assert r_al.max_defect < 1e-9 and r_pen.max_defect < 1e-9
    assert r_pen.impulse == pytest.approx(r_al.impulse, rel=1e-5)


def _transfer():
    sc = wolf_jones.test_case_1()

    class Orbit:
        x0 = sc.observer_x0

    return Orbit, sc.observer_xf, np.linspace(0.0, 2 * sc.period, 30)


@pytest.fixture(scope="module")
def free_transfer():
    """The minimum-impulse transfer (no information, no keep-out), solved once for the tests that start from it."""
    dro, xf, t = _transfer()
    return scvx.solve_scvx(em, t, propagate(em, dro.x0, t).x, np.zeros((t.size, 3)), np.full(t.size, A_MAX),
                           x_final=xf)


def test_minimum_impulse_transfer_is_feasible_and_guess_independent(free_transfer):
    dro, xf, t = _transfer()
    res = free_transfer
    assert res.max_defect < 1e-9
    assert np.all(np.linalg.norm(res.u, axis=1) <= A_MAX * (1 + 1e-7))
    xs = D.propagate_foh(em, dro.x0, t, res.u)
    assert np.max(np.abs(xs[-1] - xf)) < 1e-8
    rng = np.random.default_rng(1)
    back = propagate(em, xf, t[::-1]).x[::-1]
    s = (t / t[-1])[:, None]
    guess = (1 - s) * propagate(em, dro.x0, t).x + s * back
    res2 = scvx.solve_scvx(em, t, guess, 0.1 * A_MAX * rng.standard_normal((t.size, 3)), np.full(t.size, A_MAX),
                           x_final=xf)
    assert abs(res2.impulse - res.impulse) < 1e-5 * res.impulse
    assert np.max(np.abs(res2.u - res.u)) < 1e-3 * A_MAX


def test_no_terminal_constraint_and_no_information_means_no_thrust():
    dro, _, t = _transfer()
    res = scvx.solve_scvx(em, t, propagate(em, dro.x0, t).x, np.zeros((t.size, 3)), np.full(t.size, A_MAX))
    assert res.impulse < 1e-10


def test_linear_reward_trades_impulse_for_reward():
    dro, xf, t = _transfer()
    direction = np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0])  # a linear "information" rewarding +x at node 10

    def info(x, order=0):
        return 5.0 * direction @ x if order == 0 else (5.0 * direction @ x, 5.0 * direction)

    out = []
    for alpha in (0.0, 0.01, 0.05):
        res = scvx.solve_scvx(em, t, propagate(em, dro.x0, t).x, np.zeros((t.size, 3)), np.full(t.size, A_MAX),
                              x_final=xf, info=info, info_node=10, alpha=alpha)
        out.append((res.impulse, res.information))
        assert res.max_defect < 1e-9
    impulses, infos = zip(*out)
    assert impulses[0] < impulses[1] < impulses[2]
    assert infos[0] < infos[1] < infos[2]


class _Sphere:
    """Keep-out sphere around a point, at one node: c = d - |r - centre| <= 0 (constraints protocol)."""

    def __init__(self, node, centre, d):
        self.node, self.size, self.centre, self.d = node, 1, np.asarray(centre), d

    def __call__(self, x):
        rel = x[:3] - self.centre
        rng_ = np.linalg.norm(rel)
        C = np.zeros((1, 6))
        C[0, :3] = -rel / rng_
        return np.array([self.d - rng_]), C


def test_nonconvex_keep_out_constraint_is_met(free_transfer):
    dro, xf, t = _transfer()
    x_ball = propagate(em, dro.x0, t).x
    node = 12
    free = free_transfer
    d = em.km_to_lu(2000.0)
    centre = free.x[node, :3] + 0.3 * d * np.array([0.0, 1.0, 0.0])  # the free optimum sits inside the sphere
    res = scvx.solve_scvx(em, t, x_ball, np.zeros((t.size, 3)), np.full(t.size, A_MAX), x_final=xf,
                          constraints=[_Sphere(node, centre, d)])
    # met to the feasibility tolerance (defect_tol, 5e-10 LU = 0.2 m), far below the 2000 km radius
    assert np.linalg.norm(res.x[node, :3] - centre) >= d - scvx.SCvxSettings().defect_tol
    assert _Sphere(node, centre, d)(free.x[node])[0][0] > 0.5 * d  # ... which the free optimum violates
    assert res.impulse > free.impulse  # the constraint is active and costs impulse
    assert res.max_defect < 1e-9


def test_trust_region_collapse_raises_with_history_and_pickles():
    dro, xf, t = _transfer()

    def lying_info(x, order=0):  # the gradient points the wrong way: every predicted gain is a real loss
        v = -100.0 * x[0]
        return v if order == 0 else (v, np.array([100.0, 0, 0, 0, 0, 0]))

    lying_info.hessian = lambda x: np.zeros((6, 6))
    st = scvx.SCvxSettings(eta0=1e-3, eta_min=1e-7, max_iter=200)
    with pytest.raises(scvx.SCvxError, match="collapsed") as err:
        scvx.solve_scvx(em, t, propagate(em, dro.x0, t).x, np.zeros((t.size, 3)), np.full(t.size, A_MAX),
                        info=lying_info, info_node=10, alpha=0.5, settings=st)
    exc = err.value
    assert exc.history and not any(h["accepted"] for h in exc.history)
    assert exc.history[-1]["eta"] < 2 * st.eta_min
    # the same run with a stall limit stops earlier, also with an error
    with pytest.raises(scvx.SCvxError, match="stalled") as err2:
        scvx.solve_scvx(em, t, propagate(em, dro.x0, t).x, np.zeros((t.size, 3)), np.full(t.size, A_MAX),
                        info=lying_info, info_node=10, alpha=0.5,
                        settings=scvx.SCvxSettings(eta0=1e-3, eta_min=1e-12, stall_iter=5))
    assert len(err2.value.history) == 6
    back = pickle.loads(pickle.dumps(exc))
    assert isinstance(back, scvx.SCvxError) and back.reason == exc.reason and str(back) == str(exc)
    assert len(back.history) == len(exc.history) and back.history[-1]["rho"] == exc.history[-1]["rho"]


def test_concave_part_and_finite_difference_hessian():
    rng = np.random.default_rng(3)
    V, _ = np.linalg.qr(rng.standard_normal((6, 6)))
    lam = np.array([-5.0, -1.0, 0.0, 0.5, 2.0, 7.0])
    H = (V * lam) @ V.T
    L = scvx.concave_part(H)
    assert np.allclose(-L @ L.T, (V * np.minimum(lam, 0)) @ V.T, atol=1e-12)
    L = scvx.concave_part(H, floor=0.1)  # every eigenvalue at most -0.1 * 7
    assert np.allclose(-L @ L.T, (V * np.minimum(lam, -0.7)) @ V.T, atol=1e-12)
    grad = lambda x: H @ x + np.sin(x[0]) * np.eye(6)[0]  # noqa: E731
    x = rng.standard_normal(6)
    exact = H.copy()
    exact[0, 0] += np.cos(x[0])
    assert np.allclose(scvx.finite_difference_hessian(grad, x, 1e-5), exact, atol=1e-8)
    assert np.allclose(scvx.finite_difference_hessian(grad, x, 1e-7, g0=grad(x)), exact, atol=1e-5)


@pytest.mark.parametrize("field, value, exc", [
    ("rho1", "0.1", TypeError), ("rho2", 1.5, ValueError), ("beta_shrink", 1.0, ValueError),
    ("eta0", -1.0, ValueError), ("eta_max", 1e-9, ValueError), ("max_iter", 0, ValueError),
    ("max_iter", 2.5, ValueError), ("tol", None, TypeError), ("defect_tol", 0.0, ValueError),
    ("method", "exact", ValueError), ("information_model", "cubic", ValueError), ("penalty_growth", 0.5, ValueError),
    ("multiplier_threshold_decay", 0.0, ValueError), ("active_tol", 1.0, ValueError), ("noise_tol", -1.0, ValueError),
    ("hessian_refresh", float("nan"), ValueError), ("penalty_weight_max", 1.0, ValueError),
    ("hessian_error_ratio", 0.0, ValueError), ("curvature_floor", -1.0, ValueError), ("stall_iter", -1, ValueError)])
def test_settings_validate_every_field(field, value, exc):
    with pytest.raises(exc, match=field):
        scvx.SCvxSettings(**{field: value})


def test_bad_arguments_name_the_argument():
    dro, xf, t = _transfer()
    x = propagate(em, dro.x0, t).x
    u, um = np.zeros((t.size, 3)), np.full(t.size, A_MAX)
    with pytest.raises(ValueError, match="alpha"):
        scvx.solve_scvx(em, t, x, u, um, alpha=1.5)
    with pytest.raises(ValueError, match="u_max"):
        scvx.solve_scvx(em, t, x, u, -np.ones(t.size))
    with pytest.raises(TypeError, match="info"):
        scvx.solve_scvx(em, t, x, u, um, info=3.0, info_node=2)
    with pytest.raises(ValueError, match="info_node"):
        scvx.solve_scvx(em, t, x, u, um, info=lambda x, order=0: 0.0)
    with pytest.raises(ValueError, match="info_node"):
        scvx.solve_scvx(em, t, x, u, um, info=lambda x, order=0: 0.0, info_node=t.size)
    with pytest.raises(TypeError, match="settings"):
        scvx.solve_scvx(em, t, x, u, um, settings={"max_iter": 3})
    with pytest.raises(TypeError, match="system"):
        scvx.solve_scvx("earth-moon", t, x, u, um)
    with pytest.raises(ValueError, match="x_guess"):
        scvx.solve_scvx(em, t, x[:-1], u, um)
    with pytest.raises(ValueError, match="solver"):
        scvx.solve_scvx(em, t, x, u, um, solver="NO_SUCH_SOLVER")
    with pytest.raises(TypeError, match=r"constraints\[0\]"):
        scvx.solve_scvx(em, t, x, u, um, constraints=[object()])
    with pytest.raises(scvx.SCvxError, match="infeasible|collapsed|no convergence"):
        # a terminal state out of reach with no thrust at all
        scvx.solve_scvx(em, t, x, u, np.zeros(t.size), x_final=xf, settings=scvx.SCvxSettings(max_iter=5))


def test_homotopy_sweep_arguments():
    with pytest.raises(ValueError, match="alphas"):
        scvx.homotopy_sweep(lambda a, x, u: None, [0.0, 0.0], None, None)
    with pytest.raises(TypeError, match="solve"):
        scvx.homotopy_sweep(None, [0.0], None, None)



def _fast_run(periods, alpha, x_final):
    """16 nodes of test case 1's observer orbit, linear reward on +x at node 5 (< 1 s once cvxpy is loaded)."""
    sc = wolf_jones.test_case_1()
    t = np.linspace(0.0, periods * sc.period, 16)
    g = 5.0 * np.eye(6)[0]

    def info(x, order=0):
        return g @ x if order == 0 else (g @ x, g)

    st = scvx.SCvxSettings()
    x0 = propagate(em, sc.observer_x0, t).x
    res = scvx.solve_scvx(em, t, x0, np.zeros((t.size, 3)), np.full(t.size, A_MAX), x_final=x_final,
                          info=info if alpha > 0 else None, info_node=5 if alpha > 0 else None, alpha=alpha,
                          settings=st)
    obj0 = -alpha * info(x0[5], 0)  # objective of the guess (zero thrust)
    return dict(res=res, st=st, obj0=obj0, alpha=alpha)


@pytest.fixture(scope="module")
def reward_run():
    """One period, reward only: the history visits every trust-region branch."""
    return _fast_run(1, 0.05, None)


@pytest.fixture(scope="module")
def transfer_run():
    """Two periods to test case 1's terminal state, no reward: feasible steps still changing the cost by 1e-7."""
    return _fast_run(2, 0.0, wolf_jones.test_case_1().observer_xf)


def test_trust_region_follows_the_ratio_test(reward_run):
    """Table 1: shrink on rho < rho1, keep on rho1 <= rho < rho2, grow (capped) on rho >= rho2, at every step."""
    st, hist = reward_run["st"], reward_run["res"].history
    middle = 0
    for rec, nxt in zip(hist[:-1], hist[1:]):
        rho, eta = rec["rho"], rec["eta"]
        if rho < st.rho1:
            expected = eta / st.beta_shrink
        elif rho >= st.rho2:
            expected = min(eta * st.beta_grow, st.eta_max)
        else:
            expected = eta
            middle += eta < st.eta_max  # a step where growing would have shown
        assert nxt["eta"] == pytest.approx(expected, rel=1e-15), (rec["iteration"], rho, eta, nxt["eta"])
    # the run exercises the three branches (else the test would not test them)
    rhos = np.array([h["rho"] for h in hist])
    assert middle >= 1 and np.any(rhos < st.rho1) and np.any(rhos >= st.rho2)


@pytest.mark.parametrize("run", ["reward_run", "transfer_run"])
def test_stops_on_the_first_step_meeting_all_three_convergence_tests(run, request):
    """Convergence: an accepted step with objective change <= tol (1 + |J|), defects <= defect_tol and an
    inactive trust region; the run stops on the first such step, not earlier (a looser tolerance) nor later."""
    case = request.getfixturevalue(run)
    res, st, alpha = case["res"], case["st"], case["alpha"]
    obj_ref = case["obj0"]
    meets = []
    near = 0  # accepted, feasible, inactive steps whose change lies between tol and 1e3 tol
    for rec in res.history:
        if not rec["accepted"]:
            continue
        obj_new = (1.0 - alpha) * rec["impulse"] - (alpha * rec["information"] if alpha > 0 else 0.0)
        change = abs(obj_new - obj_ref) / (1.0 + abs(rec["cost"]))
        feasible = rec["max_defect"] <= st.defect_tol and rec["max_violation"] <= st.defect_tol
        meets.append(change <= st.tol and feasible and not rec["tr_active"])
        near += bool(st.tol < change <= 1e3 * st.tol and feasible and not rec["tr_active"])
        obj_ref = obj_new
    assert res.history[-1]["accepted"]
    assert meets[-1] and not any(meets[:-1]), meets
    # the default tolerance the notebooks rely on, and (transfer) a step where a 1e3 looser one would have stopped
    assert st.tol <= 1e-8
    if run == "transfer_run":
        assert near >= 1


def _run_or_error(**kw):
    """A solve's (x, u, cost, history costs), or its error's history costs (a run that does not converge)."""
    try:
        res = scvx.solve_scvx(**kw)
    except scvx.SCvxError as exc:
        return None, [h["new_cost"] for h in exc.history]
    return res, [h["new_cost"] for h in res.history]


def test_runs_reusing_one_workspace_equal_runs_on_fresh_problems():
    """A sweep that passes one SCvxWorkspace to all its runs (one canonicalisation) gives, run by run, the solutions
    and iterates of runs that build their own subproblem: bit for bit, across warm starts, homotopy weights and
    both defect methods (every Parameter is reassigned; the first solve of a run starts a new Clarabel solver)."""
    sc = wolf_jones.test_case_1()
    t = np.linspace(0.0, sc.period, 16)
    g = 5.0 * np.eye(6)[0]

    def info(x, order=0):
        return g @ x if order == 0 else (g @ x, g)

    x0 = propagate(em, sc.observer_x0, t).x
    ws = scvx.SCvxWorkspace()
    guess = (x0, np.zeros((t.size, 3)))
    runs = [(0.02, "penalty", 12), (0.05, "augmented_lagrangian", 150), (0.1, "augmented_lagrangian", 150)]
    converged = solves = 0
    for alpha, method, max_iter in runs:
        kw = dict(system=em, t_nodes=t, x_guess=guess[0], u_guess=guess[1], u_max=np.full(t.size, A_MAX),
                  info=info, info_node=5, alpha=alpha, settings=scvx.SCvxSettings(method=method, max_iter=max_iter))
        fresh, costs_fresh = _run_or_error(**kw)
        reused, costs_reused = _run_or_error(**kw, workspace=ws)
        assert costs_fresh == costs_reused, (alpha, method)
        solves += len(costs_fresh)
        if fresh is not None:
            converged += 1
            assert reused is not None and reused.iterations == fresh.iterations
            assert np.array_equal(reused.x, fresh.x) and np.array_equal(reused.u, fresh.u)
            assert reused.cost == fresh.cost
            guess = (fresh.x, fresh.u)
    assert converged >= 2 and solves >= 10
    assert ws.builds == 1  # one structure: canonicalised once for the three runs
    # pickling drops the built problems (a process builds its own); the workspace stays usable
    clone = pickle.loads(pickle.dumps(ws))
    assert clone.builds == 0 and clone._problems == {} and clone.max_problems == ws.max_problems


def test_workspace_keeps_one_problem_per_structure_and_thread():
    import threading

    ws = scvx.SCvxWorkspace(max_problems=2)
    coast = np.zeros(5, bool)
    a = ws._subproblem(5, True, None, [], coast)
    assert ws._subproblem(5, True, None, [], coast) is a and ws.builds == 1
    b = ws._subproblem(5, False, None, [], coast)  # another structure: another problem
    assert b is not a and ws.builds == 2
    other = []
    th = threading.Thread(target=lambda: other.append(ws._subproblem(5, True, None, [], coast)))
    th.start()
    th.join()
    assert other[0] is not a  # never shared between threads
    assert len(ws._problems) == 2  # least recently used dropped beyond max_problems
    with pytest.raises(ValueError, match="max_problems"):
        scvx.SCvxWorkspace(max_problems=0)
    with pytest.raises(TypeError, match="workspace"):
        scvx.solve_scvx(em, np.linspace(0, 1, 3), propagate(em, wolf_jones.test_case_1().observer_x0,
                                                           np.linspace(0, 1, 3)).x, np.zeros((3, 3)),
                        np.full(3, A_MAX), workspace=object())


def test_no_gradient_or_hessian_on_the_converged_step():
    """The gradient and Hessian at a new reference are computed only when the iteration goes on: never at the
    converged solution (nothing would use them), and once per accepted step before it."""
    sc = wolf_jones.test_case_1()
    t = np.linspace(0.0, sc.period, 16)
    g = 5.0 * np.eye(6)[0]
    calls = []

    class Info:
        def __call__(self, x, order=0):
            if order == 1:
                calls.append(("gradient", np.array(x)))
            return g @ x if order == 0 else (g @ x, g)

        def hessian(self, x):
            calls.append(("hessian", np.array(x)))
            return np.zeros((6, 6))

    x0 = propagate(em, sc.observer_x0, t).x
    res = scvx.solve_scvx(em, t, x0, np.zeros((t.size, 3)), np.full(t.size, A_MAX), info=Info(), info_node=5,
                          alpha=0.05, settings=scvx.SCvxSettings(hessian_refresh=0.0))
    grads = [x for kind, x in calls if kind == "gradient"]
    hessians = [x for kind, x in calls if kind == "hessian"]
    accepted = sum(h["accepted"] for h in res.history)
    assert accepted >= 3
    assert len(grads) == accepted  # the initial reference and every accepted step but the last
    assert len(hessians) >= accepted  # hessian_refresh = 0: at every reference (and after poor-model rejections)
    assert not any(np.array_equal(x, res.x[5]) for x in grads + hessians)


# ---------------------------------------------------------------------------------------------------------------
# the practical stopping rule (solve_scvx(..., practical_stop=PracticalStop(...)))
# ---------------------------------------------------------------------------------------------------------------
def _practical_meets(res, ps, alpha):
    """Per accepted step: does it meet the practical rule (defects and violation <= defect_tol, merit and
    objective change <= cost_tol (1 + |J|))?  Recomputed from the history, independently of the solver."""
    out, obj_ref = [], None
    for rec in res.history:
        if not rec["accepted"]:
            continue
        obj_new = (1.0 - alpha) * rec["impulse"] - alpha * rec["information"]
        scale = 1.0 + abs(rec["cost"])
        change = max(abs(rec["actual"]), abs(obj_new - obj_ref) if obj_ref is not None else np.inf)
        out.append(change <= ps.cost_tol * scale and rec["max_defect"] <= ps.defect_tol
                   and rec["max_violation"] <= ps.defect_tol)
        obj_ref = obj_new
    return out


def test_practical_rule_stops_the_linear_model_where_the_strict_test_cannot(case1):
    """The paper's linear MI model (Eq. 44) with the augmented Lagrangian on test case 1: every step ends on the
    trust-region boundary, so the strict test (inactive trust region) cannot stop it; the practical rule stops it on
    the first run of `window` qualifying accepted steps, with closed defects, at the optimum of the default
    (concave-quadratic) model.  On this coarse grid the run ends in a four-step cycle whose accepted steps leave
    defects of 1.1e-8 (second order in eta ~ 1e-4), so the defect tolerance here is 1e-7 (notebook 03 uses 1e-8 on
    its finer grid)."""
    alpha = ALPHAS[-1]
    ps = scvx.PracticalStop(window=5, defect_tol=1e-7, cost_tol=1e-8)
    res = _solve(case1, alpha, case1["x0"], case1["u0"], settings=scvx.SCvxSettings(information_model="linear"),
                 practical_stop=ps)
    assert res.stopped_by == "practical"
    assert res.history[-1]["accepted"] and res.history[-1]["tr_active"]  # the strict test could not have stopped here
    assert res.max_defect <= ps.defect_tol
    model = D.foh_discretize(em, case1["t"], res.x, res.u)  # defects recomputed independently
    assert np.max(np.linalg.norm(model.defects, axis=1)) <= ps.defect_tol
    meets = _practical_meets(res, ps, alpha)
    run = 0
    for i, m in enumerate(meets):  # the stop is on the first accepted step that completes a run of `window`
        run = run + 1 if m else 0
        assert (run >= ps.window) == (i == len(meets) - 1), (i, meets)
    ref = _solve(case1, alpha, case1["x0"], case1["u0"])  # default: augmented Lagrangian, quadratic model, strict
    assert ref.stopped_by == "strict"
    assert abs(res.cost - ref.cost) <= 1e-6


def test_practical_rule_never_stops_with_open_defects():
    """A terminal state out of reach (thrust bound 1e-6 a_max): the defects cannot close, so even a rule that
    accepts any cost change and a single step must not stop; the run ends in SCvxError."""
    sc = wolf_jones.test_case_1()
    t = np.linspace(0.0, 2 * sc.period, 12)
    st = scvx.SCvxSettings(max_iter=8, stall_iter=0)
    with pytest.raises(scvx.SCvxError) as err:
        scvx.solve_scvx(em, t, propagate(em, sc.observer_x0, t).x, np.zeros((t.size, 3)),
                        np.full(t.size, 1e-6 * A_MAX), x_final=sc.observer_xf, settings=st,
                        practical_stop=scvx.PracticalStop(window=1, cost_tol=1e3, defect_tol=1e-8))
    hist = err.value.history
    assert len(hist) == 8 and sum(h["accepted"] for h in hist) >= 1
    assert min(h["max_defect"] for h in hist if h["accepted"]) > 1e-8  # the defects really stayed open


def test_practical_rule_off_or_unmet_leaves_the_run_unchanged(transfer_run):
    """Default settings stop on the strict test; a practical rule that can never be met changes no iterate."""
    base = transfer_run["res"]
    assert base.stopped_by == "strict"
    sc = wolf_jones.test_case_1()
    t = np.linspace(0.0, 2 * sc.period, 16)
    res = scvx.solve_scvx(em, t, propagate(em, sc.observer_x0, t).x, np.zeros((t.size, 3)), np.full(t.size, A_MAX),
                          x_final=sc.observer_xf, settings=scvx.SCvxSettings(),
                          practical_stop=scvx.PracticalStop(window=3, defect_tol=1e-300, cost_tol=1e-300))
    assert res.stopped_by == "strict"
    assert np.array_equal(res.x, base.x) and np.array_equal(res.u, base.u) and res.cost == base.cost
    assert [h["cost"] for h in res.history] == [h["cost"] for h in base.history]


@pytest.mark.parametrize("field, value, exc", [("window", 0, ValueError), ("window", 1.5, ValueError),
                                               ("defect_tol", 0.0, ValueError), ("cost_tol", -1e-8, ValueError),
                                               ("cost_tol", "1e-8", TypeError)])
def test_practical_stop_validates_every_field(field, value, exc):
    with pytest.raises(exc, match=field):
        scvx.PracticalStop(**{field: value})
    dro, xf, t = _transfer()
    with pytest.raises(TypeError, match="practical_stop"):
        scvx.solve_scvx(em, t, propagate(em, dro.x0, t).x, np.zeros((t.size, 3)), np.full(t.size, A_MAX),
                        x_final=xf, practical_stop=dict(window=5))



def test_a_trial_step_through_a_primary_is_rejected_not_raised(monkeypatch):
    """A trial step whose arcs hit a primary (ImpactError from the discretisation) is a rejected step: the run
    records it, shrinks the trust region and goes on to the same optimum as a run that never met it."""
    dro, xf, t = _transfer()
    x0, u0 = propagate(em, dro.x0, t).x, np.zeros((t.size, 3))
    ref = scvx.solve_scvx(em, t, x0, u0, np.full(t.size, A_MAX), x_final=xf)
    calls = {"n": 0}
    real = scvx._foh_discretize

    def fails_once(*args):
        calls["n"] += 1
        if calls["n"] == 2:  # the first trial step (call 1 evaluates the initial reference)
            raise ImpactError("Moon", 1.0)
        return real(*args)

    monkeypatch.setattr(scvx, "_foh_discretize", fails_once)
    res = scvx.solve_scvx(em, t, x0, u0, np.full(t.size, A_MAX), x_final=xf)
    first = res.history[0]
    assert not first["accepted"] and first["rho"] == -np.inf and first["status"].startswith("impact")
    assert res.history[1]["eta"] == pytest.approx(first["eta"] / scvx.SCvxSettings().beta_shrink)
    assert res.max_defect < 1e-9
    assert res.impulse == pytest.approx(ref.impulse, rel=1e-6)


def test_a_trial_step_with_a_node_inside_the_moon_is_rejected(monkeypatch):
    """The same when the trial step puts a node inside the Moon (no integration is attempted from there)."""
    dro, xf, t = _transfer()
    x0, u0 = propagate(em, dro.x0, t).x, np.zeros((t.size, 3))
    real = scvx._inside_primaries
    calls = {"n": 0}

    def inside_once(system, positions):
        calls["n"] += 1
        return True if calls["n"] == 1 else real(system, positions)

    monkeypatch.setattr(scvx, "_inside_primaries", inside_once)
    res = scvx.solve_scvx(em, t, x0, u0, np.full(t.size, A_MAX), x_final=xf)
    assert res.history[0]["status"].startswith("impact") and not res.history[0]["accepted"]
    assert res.max_defect < 1e-9


def test_direct_clarabel_resolve_equals_cvxpy_solve():
    """The subproblem's direct Clarabel path (cvxpy's re-solve replayed without Problem.solve's bookkeeping) sets
    every variable to exactly the values cvxpy's ``Problem.solve`` sets, for a new solver and for data updates, with
    a nonneg slack variable and a window node (all variable kinds of the SCvx subproblem)."""
    sc = wolf_jones.test_case_1()
    t = np.linspace(0.0, sc.period, 12)
    n = t.size
    x0 = propagate(em, sc.observer_x0, t).x
    u0 = np.zeros((n, 3))
    model = D.foh_discretize(em, t, x0, u0)
    rng = np.random.default_rng(3)
    opts = dict(tol_gap_abs=1e-10, tol_gap_rel=1e-10, tol_feas=1e-10, tol_ktratio=1e-8, max_iter=500)
    coast = np.zeros(n, dtype=bool)
    coast[6:8] = True
    subs = [scvx._Subproblem(n, True, 5, [(4, 3)], coast=coast) for _ in range(2)]
    subs[1]._clarabel = False  # cvxpy's Problem.solve
    dt = np.diff(t)
    for it, (eta, alpha) in enumerate([(0.05, 0.02), (0.02, 0.05), (0.01, 0.1), (0.03, 0.0)]):
        g = rng.standard_normal(6)
        L = 0.1 * rng.standard_normal((6, 6))
        c = np.array([-1e-3, 2e-4, -5e-4])
        C = rng.standard_normal((3, 6))
        for sub in subs:
            sub.set_model(model)
            sub.xbar.value, sub.ubar.value, sub.eta.value = x0 + 1e-4 * it, u0, eta
            sub.umax.value = np.where(coast, 0.0, A_MAX)
            sub.x_ic.value, sub.x_tc.value = x0[0], x0[-1]
            sub.w_u.value = (1 - alpha) * np.r_[dt / 2, 0.0] + np.r_[0.0, dt / 2] * (1 - alpha)
            sub.lam.value = 1e-3 * it * np.ones((n - 1, 6))
            sub.half_w.value = 500.0
            sub.gamma_dt.value = np.zeros(n - 1)
            sub.g.value, sub.L.value = alpha * g, np.sqrt(alpha) * L
            con = sub.con[0]
            con["c"].value, con["C"].value, con["mu"].value, con["gamma"].value = c, C, np.full(3, 1e-2), 0.0
        statuses = [sub.solve("CLARABEL", it % 2 == 0, opts) for sub in subs]
        assert statuses[0] == statuses[1] == subs[1].problem.status
        assert statuses[0] in ("optimal", "optimal_inaccurate")
        assert isinstance(subs[0]._clarabel, dict)  # the direct path was taken
        for a, b in zip(subs[0].problem.variables(), subs[1].problem.variables()):
            assert a.shape == b.shape and np.array_equal(a.value, b.value), (it, a.name())
        assert np.array_equal(subs[0].step.value, subs[1].step.value)
        assert np.max(subs[0].step.value) <= eta * (1 + 1e-6)
