"""SCvx on Wolf & Jones test cases 1 and 2: where an iteration's time goes, re-solve vs rebuild, a full alpha_h
sweep per case.

Scenario: :func:`cislunar.papers.wolf_jones.scenarios.test_case_1` (observer and one target on DROs, relative position 100 m, two
periods, zero thrust in [3P/4, 3P/2]) on 40 Sundman nodes, the information model with fixed process noise.

1. **Per iteration**: the nonlinear evaluation splits into the first-order-hold discretisation
   (:func:`cislunar.guidance.discretization.foh_discretize`), the information model (value, gradient, Hessian) and the
   convex solve (cvxpy + Clarabel); measured both in isolation at the ballistic reference and averaged over an
   SCvx run at alpha_h = 5e-3 (the Hessian is refreshed only when the window-start state moved, see
   ``SCvxSettings.hessian_refresh``).
2. **Re-solve vs rebuild**: the subproblem built once with ``cvxpy.Parameter`` objects (DPP, canonicalised once)
   and re-solved with new values, against building and solving a fresh problem each time.
3. **Sweep**: the alpha_h grid of notebook 05 (9 values) swept upward and downward, best kept.
4. **Test case 2 sweep**: observer and three targets, range and range-rate, the minimum-range keep-out, 30 Sundman
   nodes and the 8-value alpha_h grid of notebook 06, both directions serially (the notebook runs them in two
   processes).

``python -m benchmarks scvx`` prints the numbers; ``main()`` returns them.  Ratios are within one run.
"""

from __future__ import annotations

import time

import numpy as np

from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.guidance import discretization as D
from cislunar.guidance import scvx
from cislunar.papers.wolf_jones import scenarios as wolf_jones

N_NODES = 40
ALPHAS = [0.0, 1e-3, 2e-3, 3e-3, 5e-3, 7e-3, 1e-2, 1.5e-2, 2e-2]
N_NODES_CASE_2 = 30
ALPHAS_CASE_2 = [0.0, 5e-4, 1e-3, 2e-3, 5e-3, 7e-3, 1e-2, 2e-2]


def sweep_case_2() -> dict:
    """Test case 2: the notebook-06 alpha_h grid swept up and down (serial), with the keep-out."""
    sc = wolf_jones.test_case_2()
    t, k_ws, _ = sc.node_times(N_NODES_CASE_2, 1.0)
    x0, u0 = sc.ballistic_guess(t)
    solver = wolf_jones.ScenarioSolver(sc, t, k_ws, information=sc.information_model(), keep_out=True,
                                       settings=scvx.SCvxSettings(max_iter=150))
    t0 = time.perf_counter()
    sweep = wolf_jones.sweep_both_ways(solver, ALPHAS_CASE_2, x0, u0)
    seconds = time.perf_counter() - t0
    n_it = int(sum(a["iterations"] for a in sweep.attempts))
    return dict(case2_nodes=N_NODES_CASE_2, case2_alphas=len(ALPHAS_CASE_2), case2_runs=len(sweep.attempts),
                case2_converged=int(sum(a["converged"] for a in sweep.attempts)), case2_iterations=n_it,
                case2_sweep_s=seconds, case2_per_iteration_s=seconds / max(n_it, 1))


def _best_time(fn, repeat=5):
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def _setup():
    sc = wolf_jones.test_case_1()
    t, k_ws, _ = sc.node_times(N_NODES)
    x0, u0 = sc.ballistic_guess(t)
    return sc, t, k_ws, x0, u0, sc.control_bounds(t), sc.information_model()


def _load(sub, model, x, u, eta, alpha, grad, L):
    n = x.shape[0]
    for k in range(n - 1):
        sub.A[k].value, sub.Bm[k].value, sub.Bp[k].value = model.A[k], model.Bm[k], model.Bp[k]
    sub.r.value = model.r
    sub.xbar.value, sub.ubar.value, sub.eta.value = x, u, eta
    sub.lam.value = np.zeros((n - 1, 6))
    sub.half_w.value = 500.0
    sub.gamma_dt.value = np.zeros(n - 1)
    sub.g.value = alpha * grad
    sub.L.value = np.sqrt(alpha) * L


def resolve_vs_rebuild(t, k_ws, x0, u0, u_max, x_final, info, repeat=3):
    """Seconds per solve: parameterised re-solve, first solve (includes canonicalisation), rebuild + solve."""
    model = D.foh_discretize(em, t, x0, u0)
    _, grad = info(x0[k_ws], 1)
    L = scvx.concave_part(info.hessian(x0[k_ws]))
    n = t.size
    dt = np.diff(t)
    w_u = np.zeros(n)
    w_u[:-1] += dt / 2
    w_u[1:] += dt / 2
    opts = dict(tol_gap_abs=1e-10, tol_gap_rel=1e-10, tol_feas=1e-10)

    def build():
        sub = scvx._Subproblem(n, True, k_ws, [], coast=u_max == 0)
        sub.x_ic.value, sub.x_tc.value, sub.umax.value = x0[0], x_final, u_max
        sub.w_u.value = 0.995 * w_u
        return sub

    t0 = time.perf_counter()
    sub = build()
    _load(sub, model, x0, u0, 0.05, 5e-3, grad, L)
    sub.problem.solve(solver="CLARABEL", **opts)
    first = time.perf_counter() - t0
    etas = iter(np.geomspace(0.05, 0.01, 100))

    def resolve():
        _load(sub, model, x0, u0, next(etas), 5e-3, grad, L)
        sub.problem.solve(solver="CLARABEL", **opts)

    def rebuild():
        s2 = build()
        _load(s2, model, x0, u0, next(etas), 5e-3, grad, L)
        s2.problem.solve(solver="CLARABEL", **opts)

    return _best_time(resolve, repeat), first, _best_time(rebuild, repeat)


def main() -> dict:
    sc, t, k_ws, x0, u0, u_max, info = _setup()
    xw = x0[k_ws]
    D.foh_discretize(em, t, x0, u0)  # compile / warm the integrators
    info(xw, 1)
    rng = np.random.default_rng(0)

    def fresh():  # a new point each call: the information model caches its last linearisations
        return xw + 1e-9 * rng.standard_normal(6)

    pieces = {
        "discretize_s": _best_time(lambda: D.foh_discretize(em, t, x0, u0)),
        "mi_value_s": _best_time(lambda: info(fresh(), 0)),
        "mi_gradient_s": _best_time(lambda: info(fresh(), 1)),
        "mi_hessian_s": _best_time(lambda: info.hessian(fresh()), 3),
    }
    resolve, first, rebuild = resolve_vs_rebuild(t, k_ws, x0, u0, u_max, sc.observer_xf, info)

    t0 = time.perf_counter()
    res = scvx.solve_scvx(em, t, x0, u0, u_max, x_final=sc.observer_xf, info=info, info_node=k_ws, alpha=5e-3)
    run_s = time.perf_counter() - t0
    H = res.history
    per_iter = {k: float(np.mean([h[k] for h in H])) for k in ("t_discretize", "t_info", "t_hessian", "t_solve")}

    def solve(a, x, u):
        return scvx.solve_scvx(em, t, x, u, u_max, x_final=sc.observer_xf, info=info, info_node=k_ws, alpha=a)

    t0 = time.perf_counter()
    sweep = scvx.homotopy_sweep(solve, ALPHAS, x0, u0)
    sweep_s = time.perf_counter() - t0
    n_it = sum(a["iterations"] for a in sweep.attempts)
    out = dict(
        n_nodes=N_NODES,
        **pieces,
        subproblem_resolve_s=resolve,
        subproblem_first_solve_s=first,
        subproblem_rebuild_s=rebuild,
        rebuild_over_resolve=rebuild / resolve,
        run_alpha_5e_3_iterations=res.iterations,
        run_alpha_5e_3_s=run_s,
        run_per_iteration_s=run_s / res.iterations,
        **{f"run_mean_{k}_s": v for k, v in per_iter.items()},
        run_hessian_refreshes=int(sum(h["t_hessian"] > 0 for h in H)),
        sweep_alphas=len(ALPHAS),
        sweep_runs=len(sweep.attempts),
        sweep_converged=int(sum(a["converged"] for a in sweep.attempts)),
        sweep_iterations=int(n_it),
        sweep_s=sweep_s,
        sweep_per_iteration_s=sweep_s / max(n_it, 1),
    )
    print(f"test case 1, {N_NODES} nodes")
    print(f"  in isolation: FOH discretisation {1e3 * pieces['discretize_s']:.1f} ms, MI value "
          f"{1e3 * pieces['mi_value_s']:.1f} ms, MI gradient {1e3 * pieces['mi_gradient_s']:.1f} ms, MI Hessian "
          f"{1e3 * pieces['mi_hessian_s']:.1f} ms")
    print(f"  convex subproblem: re-solve {1e3 * resolve:.1f} ms, first solve (canonicalisation) {1e3 * first:.0f} ms, "
          f"rebuild + solve {1e3 * rebuild:.0f} ms ({rebuild / resolve:.1f} x re-solve)")
    print(f"  SCvx alpha_h = 5e-3 from the ballistic DRO: {res.iterations} iterations, {run_s:.2f} s "
          f"({run_s / res.iterations:.3f} s/iteration: discretisation {per_iter['t_discretize']:.3f}, MI value + "
          f"gradient {per_iter['t_info']:.3f}, Hessian {per_iter['t_hessian']:.3f} "
          f"({out['run_hessian_refreshes']} refreshes), solve {per_iter['t_solve']:.3f})")
    print(f"  alpha_h sweep up and down over {len(ALPHAS)} values: {out['sweep_converged']}/{out['sweep_runs']} "
          f"converged, {n_it} iterations, {sweep_s:.1f} s ({out['sweep_per_iteration_s']:.3f} s/iteration)")
    c2 = sweep_case_2()
    out.update(c2)
    print(f"test case 2, {c2['case2_nodes']} nodes, keep-out: alpha_h sweep up and down over {c2['case2_alphas']} "
          f"values: {c2['case2_converged']}/{c2['case2_runs']} converged, {c2['case2_iterations']} iterations, "
          f"{c2['case2_sweep_s']:.1f} s ({c2['case2_per_iteration_s']:.3f} s/iteration)")
    return out


if __name__ == "__main__":
    main()
