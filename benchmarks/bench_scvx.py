"""SCvx on Wolf & Jones test cases 1 and 2: the sweeps of notebooks 05 and 06 by the old path and the new, in one
run; where an iteration's time goes; re-solve vs rebuild of the convex subproblem.

Scenario: :func:`cislunar.papers.wolf_jones.scenarios.test_case_1` (observer and one target on DROs, relative
position 100 m, two periods, zero thrust in [3P/4, 3P/2]) on 40 Sundman nodes, the information model with fixed
process noise; :func:`~cislunar.papers.wolf_jones.scenarios.test_case_2` (three targets, range and range rate, the
minimum-range keep-out) on 30 nodes.

1. **Old path vs new, one run** (:func:`compare_sweeps`): the alpha_h grid of notebook 05 (9 values, test case 1)
   and of notebook 06 (8 values, test case 2) swept upward and downward (serially,
   :func:`~cislunar.papers.wolf_jones.scenarios.sweep_both_ways`) by

   * ``old``: the path before 2026-11-26, rebuilt here: a fresh subproblem canonicalised for every run, with one
     cvxpy Parameter per matrix (3 (N-1) for the FOH model, :class:`_PerIntervalSubproblem`), and the information
     model checking P0, Q and R (and the whole window) at every evaluation through the public
     ``assemble_augmented`` and ``mutual_information[_gradient]`` (:class:`_RecheckingInformation`, no Hessian
     cache), and the FOH interval propagation rebuilding its parameter and initial arrays on every call
     (:func:`_old_foh_interval`);
   * ``new``: :class:`~cislunar.papers.wolf_jones.scenarios.ScenarioSolver` as the notebooks call it (one
     :class:`~cislunar.guidance.scvx.SCvxWorkspace`: canonicalised once per sweep, stacked FOH Parameters; the
     window's fixed ingredients checked once; no gradient or Hessian on the converged step; the FOH parameters
     set in place; since 2026-11-26d each re-solve hands cvxpy's canonical data straight to Clarabel
     (``_Subproblem._solve_clarabel``) instead of going through ``Problem.solve``, and the Hessian's second-order
     propagations run with sorted lanes in wide batches, item 4; the old path keeps the old ones).

   Both paths visit the same iterates (the solutions are compared bit for bit and the iteration counts printed);
   one saving is not rebuilt in the old path (the gradient and Hessian it computed on the converged step of every
   run), so the ratio understates the gain by about one Hessian per run.  CPU time (``time.process_time``) and wall
   time are both printed: on a shared machine the CPU ratio is the robust one.
2. **Per iteration** (new path): the FOH discretisation, the information model (value, gradient, Hessian) and the
   convex solve, in isolation and averaged over an SCvx run at alpha_h = 5e-3.
3. **Re-solve vs rebuild**: the subproblem built once with ``cvxpy.Parameter`` objects (DPP, canonicalised once)
   and re-solved with new values (direct Clarabel path; the per-interval old subproblem through
   ``Problem.solve``), against building and solving a fresh problem each time.

4. **The Hessian's second-order propagations** (:func:`compare_lane_order`, since 2026-11-26d): the 12 perturbed
   observers x window intervals handed to heyoka's batch integrator (4 SIMD lanes) in the given, observer-major order
   (``old``: a batch holds 4 consecutive intervals of one observer and steps until its slowest lane has finished)
   or sorted by an estimate of their step counts (``new``, :func:`cislunar.sensing.covariance._lane_order`: a batch
   holds the perturbed copies of one interval, lanes = perturbations; and order-2 batches twice heyoka's SIMD size,
   :func:`cislunar.cr3bp.propagation._batch_plan`); one Hessian refresh and the whole notebook sweeps of both test
   cases by each, bit for bit the same results.

``python -m benchmarks scvx`` prints the numbers; ``main()`` returns them.  Ratios are within one run.
"""

from __future__ import annotations

import time

import numpy as np

from cislunar.cr3bp import propagation
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.guidance import discretization as D
from cislunar.guidance import scvx
from cislunar.papers.wolf_jones import scenarios as wolf_jones
from cislunar.sensing import covariance as cov
from cislunar.sensing import information as info_mod

N_NODES = 40
ALPHAS = [0.0, 1e-3, 2e-3, 3e-3, 5e-3, 7e-3, 1e-2, 1.5e-2, 2e-2]
N_NODES_CASE_2 = 30
ALPHAS_CASE_2 = [0.0, 5e-4, 1e-3, 2e-3, 5e-3, 7e-3, 1e-2, 2e-2]


# ------------------------------------------------------------------------------------------------------------------
# the old path, rebuilt (reference implementations; same numbers, the old costs)
# ------------------------------------------------------------------------------------------------------------------
class _PerIntervalSubproblem(scvx._Subproblem):
    """The subproblem as built before 2026-11-26: one Parameter per A_k, B-_k, B+_k (117 at 40 nodes), solved
    through cvxpy's ``Problem.solve`` (before 2026-11-26d; now a direct Clarabel re-solve)."""

    def __init__(self, n, has_terminal, k_star, con_specs, coast=None):
        import cvxpy as cp

        self._clarabel = False  # cvxpy's Problem.solve at every solve (the old path)
        self.n = n
        self.x = cp.Variable((n, 6))
        self.u = cp.Variable((n, 3))
        self.nu = cp.Variable((n - 1, 6))
        self.A = [cp.Parameter((6, 6)) for _ in range(n - 1)]
        self.Bm = [cp.Parameter((6, 3)) for _ in range(n - 1)]
        self.Bp = [cp.Parameter((6, 3)) for _ in range(n - 1)]
        self.r = cp.Parameter((n - 1, 6))
        self.xbar = cp.Parameter((n, 6))
        self.ubar = cp.Parameter((n, 3))
        self.eta = cp.Parameter(nonneg=True)
        self.umax = cp.Parameter(n, nonneg=True)
        self.x_ic = cp.Parameter(6)
        self.x_tc = cp.Parameter(6)
        self.w_u = cp.Parameter(n, nonneg=True)
        self.lam = cp.Parameter((n - 1, 6))
        self.half_w = cp.Parameter(nonneg=True)
        self.gamma_dt = cp.Parameter(n - 1, nonneg=True)
        cons = [self.x[0] == self.x_ic]
        if has_terminal:
            cons.append(self.x[n - 1] == self.x_tc)
        for k in range(n - 1):
            cons.append(self.x[k + 1] == self.A[k] @ self.x[k] + self.Bm[k] @ self.u[k] + self.Bp[k] @ self.u[k + 1]
                        + self.r[k] + self.nu[k])
        unorm = cp.norm(self.u, 2, axis=1)
        cons.append(unorm <= self.umax)
        if coast is not None and np.any(coast):
            cons.append(self.u[np.flatnonzero(coast)] == 0)
        self.step = cp.norm(self.x - self.xbar, 2, axis=1) + cp.norm(self.u - self.ubar, 2, axis=1)
        cons.append(self.step <= self.eta)
        objective = (self.w_u @ unorm + cp.sum(cp.multiply(self.lam, self.nu)) + self.half_w * cp.sum_squares(self.nu)
                     + self.gamma_dt @ cp.norm(self.nu, 1, axis=1))
        self.k_star = k_star
        if k_star is not None:
            self.g = cp.Parameter(6)
            self.L = cp.Parameter((6, 6))
            self.dxs = cp.Variable(6)
            cons.append(self.dxs == self.x[k_star] - self.xbar[k_star])
            objective = objective - self.g @ self.dxs + 0.5 * cp.sum_squares(self.L.T @ self.dxs)
        self.con = []
        for node, m in con_specs:
            c = cp.Parameter(m)
            C = cp.Parameter((m, 6))
            mu = cp.Parameter(m)
            s = cp.Variable(m, nonneg=True)
            dx = cp.Variable(6)
            cons += [dx == self.x[node] - self.xbar[node], c + C @ dx <= s]
            gam = cp.Parameter(nonneg=True)
            objective = objective + mu @ s + self.half_w * cp.sum_squares(s) + gam * cp.sum(s)
            self.con.append(dict(c=c, C=C, mu=mu, s=s, gamma=gam, node=node))
        self.problem = cp.Problem(cp.Minimize(objective), cons)

    def set_model(self, model):
        for k in range(self.n - 1):
            self.A[k].value, self.Bm[k].value, self.Bp[k].value = model.A[k], model.Bm[k], model.Bp[k]
        self.r.value = model.r


class _FreshWorkspace(scvx.SCvxWorkspace):
    """The old path's subproblem handling: a new (per-interval) problem, canonicalised, for every run."""

    def _subproblem(self, n, has_terminal, k_star, con_specs, coast):
        self.builds += 1
        return _PerIntervalSubproblem(n, has_terminal, k_star, con_specs, coast=coast)


class _RecheckingInformation(wolf_jones.WindowInformation):
    """The information model before 2026-11-26: every evaluation goes through the public, re-checking functions."""

    def linearization(self, x, derivatives: bool = False):
        from cislunar.utils import validation
        x = validation.as_state(x, "x", batch=False)
        key = (x.tobytes(), validation.boolean(derivatives, "derivatives"))
        if key in self._cache:
            return self._cache[key]
        arcs = cov.propagate_arcs(self.system, x, self.t, order=2 if derivatives else 1)
        lin = cov.assemble_augmented(self.model, self.noise, self.P0, arcs, self._targets, Q=self.Q)
        if len(self._cache) >= 8:
            self._cache.pop(next(iter(self._cache)))
        self._cache[key] = lin
        return lin

    def __call__(self, x, order: int = 0):
        if order == 0:
            return info_mod.mutual_information(*self.linearization(x).arrays)
        lin = self.linearization(x, derivatives=True)
        value, grad = info_mod.mutual_information_gradient(*lin.arrays, lin.dF, lin.dH)
        return float(value), grad

    def hessian(self, x):
        from cislunar.utils import validation
        x = validation.as_state(x, "x", batch=False)
        h = self.hessian_step
        X0 = np.concatenate([x + h * np.eye(6), x - h * np.eye(6)], axis=0)
        arcs = cov.propagate_arcs(self.system, X0, self.t, order=2)
        G = np.empty((12, 6))
        for j in range(12):
            lin = cov.assemble_augmented(self.model, self.noise, self.P0, arcs, self._targets, Q=self.Q, index=j)
            G[j] = info_mod.mutual_information_gradient(*lin.arrays, lin.dF, lin.dH)[1]
        Hm = (G[:6] - G[6:]).T / (2.0 * h)
        return 0.5 * (Hm + Hm.T)


def _old_foh_interval(system, x0, uk, uk1, t0, t1, tol):
    """The FOH interval propagation before 2026-11-26 (parameters and variational state built with ``np.r_`` and
    ``np.concatenate`` on every call; same numbers)."""
    ta = D.thread_local_copy(("foh", tol), lambda: D._foh_template(tol)[0])
    _, index = D._foh_template(tol)
    ta.pars[:] = np.r_[system.mu, uk, uk1, np.zeros(6), t0, t1, system.secondary_radius, system.primary_radius]
    ta.time = t0
    ta.state[:6] = x0
    ta.state[6:] = np.concatenate([np.eye(6), np.zeros((6, 12))], axis=1).ravel()
    res = ta.propagate_until(t1)
    D._check_outcome(res[0], t1, ta.time)
    return ta.state[:6].copy(), ta.state[index]


def _old_solver(new: wolf_jones.ScenarioSolver) -> wolf_jones.ScenarioSolver:
    m = new.information
    old_info = _RecheckingInformation(m.system, m.t, m.targets_x0, m.model, m.noise, m.P0, q=m.q,
                                      x_reference=m.x_reference, hessian_step=m.hessian_step)
    old = wolf_jones.ScenarioSolver(new.scenario, new.t, new.k_window, information=old_info,
                                    keep_out=bool(new.constraints), settings=new.settings)
    old.constraints = new.constraints
    old.workspace = _FreshWorkspace()
    return old


def _timed_sweep(solver, alphas, x0, u0, old: bool = False):
    fast = D._foh_interval
    if old:  # the old FOH interval code for this sweep only (module attribute looked up at every call)
        D._foh_interval = _old_foh_interval
    try:
        with _OldSecondOrder() if old else _New():  # and the old second-order propagations (before 2026-11-26d)
            p0, t0 = time.process_time(), time.perf_counter()
            sweep = wolf_jones.sweep_both_ways(solver, alphas, x0, u0)
            return sweep, time.process_time() - p0, time.perf_counter() - t0
    finally:
        D._foh_interval = fast


def compare_sweeps(case: int) -> dict:
    """Old path vs new on the notebook sweep of test case ``case`` (1 or 2); same iterates, times and ratios."""
    if case == 1:
        sc = wolf_jones.test_case_1()
        t, k_ws, _ = sc.node_times(N_NODES)
        alphas, keep_out, settings = ALPHAS, False, None
    else:
        sc = wolf_jones.test_case_2()
        t, k_ws, _ = sc.node_times(N_NODES_CASE_2, 1.0)
        alphas, keep_out, settings = ALPHAS_CASE_2, True, scvx.SCvxSettings(max_iter=150)
    x0, u0 = sc.ballistic_guess(t)
    new = wolf_jones.ScenarioSolver(sc, t, k_ws, information=sc.information_model(), keep_out=keep_out,
                                    settings=settings)
    old = _old_solver(new)
    with _OldSecondOrder():  # warm the integrators of both paths
        old.information(x0[k_ws], 1)
        old.information.hessian(x0[k_ws] + 1e-9)
    new.information(x0[k_ws], 1)
    new.information.hessian(x0[k_ws] + 1e-9)
    s_old, cpu_old, wall_old = _timed_sweep(old, alphas, x0, u0, old=True)
    s_new, cpu_new, wall_new = _timed_sweep(new, alphas, x0, u0)
    same = all((a is None and b is None) or (a is not None and b is not None and np.array_equal(a.x, b.x)
                                             and np.array_equal(a.u, b.u)) for a, b in zip(s_old.best, s_new.best))
    it_old = int(sum(a["iterations"] for a in s_old.attempts))
    it_new = int(sum(a["iterations"] for a in s_new.attempts))
    p = f"case{case}_"
    out = {p + "nodes": int(t.size), p + "alphas": len(alphas), p + "runs": len(s_new.attempts),
           p + "converged": int(sum(a["converged"] for a in s_new.attempts)), p + "iterations_old": it_old,
           p + "iterations_new": it_new, p + "solutions_bit_identical": bool(same),
           p + "canonicalisations_old": old.workspace.builds, p + "canonicalisations_new": new.workspace.builds,
           p + "cpu_old_s": cpu_old, p + "cpu_new_s": cpu_new, p + "wall_old_s": wall_old, p + "wall_new_s": wall_new,
           p + "cpu_ratio_new_over_old": cpu_new / cpu_old, p + "wall_ratio_new_over_old": wall_new / wall_old}
    print(f"test case {case}, {t.size} nodes, {len(alphas)} alpha_h up and down: {out[p + 'converged']}/"
          f"{out[p + 'runs']} converged; iterations old {it_old}, new {it_new}; solutions bit-identical: {same}; "
          f"canonicalisations old {old.workspace.builds}, new {new.workspace.builds}")
    print(f"  CPU old {cpu_old:.1f} s, new {cpu_new:.1f} s: new / old = {cpu_new / cpu_old:.2f} "
          f"({100 * (1 - cpu_new / cpu_old):.0f} % less); wall old {wall_old:.1f} s, new {wall_new:.1f} s: "
          f"{wall_new / wall_old:.2f}")
    return out


# ------------------------------------------------------------------------------------------------------------------
# the Hessian's second-order propagations: batch lanes in the given order (before 2026-11-26d) or sorted
# ------------------------------------------------------------------------------------------------------------------
def _narrow_plan(n, simd, order):
    """``propagation._batch_plan`` before 2026-11-26d: chunks of heyoka's SIMD size at every order."""
    return [(0, 1)] if n == 1 else [(i, simd) for i in range(0, n, simd)]


class _OldSecondOrder:
    """Context: the second-order interval propagations as before 2026-11-26d (lanes in the given order, batches of
    the SIMD size), by swapping the two module attributes for the duration."""

    def __enter__(self):
        self.saved = cov._propagate_arcs, propagation._batch_plan
        cov._propagate_arcs, propagation._batch_plan = _unsorted_arcs, _narrow_plan

    def __exit__(self, *exc):
        cov._propagate_arcs, propagation._batch_plan = self.saved


class _New:
    def __enter__(self):
        pass

    def __exit__(self, *exc):
        pass


def _unsorted_arcs(system, x0, t, qq, order, n_nodes):
    """``covariance._propagate_arcs`` before 2026-11-26d: the batch lanes in the given (observer-major) order."""
    K, N = x0.shape[0], t.size
    X = cov.propagate(system, x0, t).x
    X = X if X.ndim == 3 else X[None]
    F, Qd, Psi = cov._interval_transitions(system, X[:, :-1].reshape(-1, 6), np.tile(np.diff(t), K), qq,
                                           int(n_nodes), order, sort_lanes=False)
    return cov.ObjectArcs(t=t, x=X, F=F.reshape(K, N - 1, 6, 6),
                          Q=None if Qd is None else Qd.reshape(K, N - 1, 6, 6),
                          stt=None if Psi is None else Psi.reshape(K, N - 1, 6, 6, 6))


def _case(case):
    if case == 1:
        sc = wolf_jones.test_case_1()
        t, k_ws, _ = sc.node_times(N_NODES)
        return sc, t, k_ws, ALPHAS, False, None
    sc = wolf_jones.test_case_2()
    t, k_ws, _ = sc.node_times(N_NODES_CASE_2, 1.0)
    return sc, t, k_ws, ALPHAS_CASE_2, True, scvx.SCvxSettings(max_iter=150)


def compare_lane_order(case: int, sweeps: bool = True, repeat: int = 6) -> dict:
    """Hessian refresh and whole sweeps of test case ``case`` with the second-order interval propagations as before
    2026-11-26d (``old``: batch lanes in the given order, batches of heyoka's SIMD size) and now (``new``: lanes
    sorted by step count, :func:`cislunar.sensing.covariance._lane_order`; order-2 batches twice as wide,
    :func:`cislunar.cr3bp.propagation._batch_plan`), side by side in one process.

    Prints the Hessian times (CPU, median of ``repeat`` interleaved pairs at fresh points near the ballistic guess),
    the largest relative difference of the two Hessians, and (``sweeps``) the CPU time of the notebook sweep by each
    path, the iteration counts, the largest relative cost difference of the best plans and the largest state
    difference.
    """
    sc, t, k_ws, alphas, keep_out, settings = _case(case)
    x0, u0 = sc.ballistic_guess(t)
    info = sc.information_model()
    xw = x0[k_ws]
    info(xw, 1)
    with _OldSecondOrder():
        info.hessian(xw + 1e-9)  # compile the narrow order-2 integrator outside the timings
    rng = np.random.default_rng(0)
    t_old, t_new, rel = [], [], 0.0
    for _ in range(repeat):
        x = xw + 1e-9 * rng.standard_normal(6)
        H = {}
        for name, path, sink in (("old", _OldSecondOrder, t_old), ("new", _New, t_new)):
            with path():
                info._hessians.clear()
                p0 = time.process_time()
                H[name] = info.hessian(x)
                sink.append(time.process_time() - p0)
        rel = max(rel, float(np.max(np.abs(H["new"] - H["old"])) / np.max(np.abs(H["old"]))))
    p = f"case{case}_"
    out = {p + "hessian_old_ms": 1e3 * float(np.median(t_old)), p + "hessian_new_ms": 1e3 * float(np.median(t_new)),
           p + "hessian_ratio_new_over_old": float(np.median(np.array(t_new) / np.array(t_old))),
           p + "hessian_max_rel_diff": rel}
    print(f"test case {case}: Hessian refresh old {out[p + 'hessian_old_ms']:.1f} ms, new "
          f"{out[p + 'hessian_new_ms']:.1f} ms (new / old {out[p + 'hessian_ratio_new_over_old']:.2f}); "
          f"max relative difference {rel:.1e}")
    if not sweeps:
        return out
    res = {}
    for name, path in (("old", _OldSecondOrder), ("new", _New)):
        with path():
            solver = wolf_jones.ScenarioSolver(sc, t, k_ws, information=sc.information_model(), keep_out=keep_out,
                                               settings=settings)
            solver.information(xw, 1)
            res[name] = _timed_sweep(solver, alphas, x0, u0)
    so, sn = res["old"][0], res["new"][0]
    it = {k: [(int(a["iterations"]), bool(a["converged"])) for a in res[k][0].attempts] for k in res}
    cost = dx = 0.0
    identical = True
    for a, b in zip(so.attempts, sn.attempts):
        ca, cb = float(a.get("cost", np.nan)), float(b.get("cost", np.nan))
        if np.isfinite(ca) or np.isfinite(cb):
            cost = max(cost, abs(cb - ca) / max(abs(ca), 1e-300))
    for a, b in zip(so.best, sn.best):
        if (a is None) != (b is None):
            identical, dx = False, np.inf
        elif a is not None:
            identical = identical and np.array_equal(a.x, b.x) and np.array_equal(a.u, b.u)
            dx = max(dx, float(np.max(np.abs(a.x - b.x))))
    out.update({p + "sweep_cpu_old_s": res["old"][1], p + "sweep_cpu_new_s": res["new"][1],
                p + "sweep_cpu_ratio_new_over_old": res["new"][1] / res["old"][1],
                p + "sweep_iterations_equal": it["old"] == it["new"],
                p + "sweep_iterations": sum(i for i, _ in it["new"]),
                p + "sweep_max_rel_cost_diff": cost, p + "sweep_max_state_diff_lu": dx,
                p + "sweep_bit_identical": identical})
    print(f"  sweep ({len(alphas)} alpha_h up and down): CPU old {res['old'][1]:.1f} s, new {res['new'][1]:.1f} s "
          f"(new / old {res['new'][1] / res['old'][1]:.2f}); iterations per run equal: {it['old'] == it['new']} "
          f"({sum(i for i, _ in it['new'])}); max relative cost difference {cost:.1e}; max state difference "
          f"{dx:.1e} LU; "
          f"bit-identical: {identical}")
    return out


# ------------------------------------------------------------------------------------------------------------------
# per iteration, re-solve vs rebuild (new path)
# ------------------------------------------------------------------------------------------------------------------
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
    sub.set_model(model)
    sub.xbar.value, sub.ubar.value, sub.eta.value = x, u, eta
    sub.lam.value = np.zeros((n - 1, 6))
    sub.half_w.value = 500.0
    sub.gamma_dt.value = np.zeros(n - 1)
    sub.g.value = alpha * grad
    sub.L.value = np.sqrt(alpha) * L


def resolve_vs_rebuild(t, k_ws, x0, u0, u_max, x_final, info, repeat=3):
    """Seconds per solve: parameterised re-solve (stacked and per-interval Parameters), first solve (includes
    canonicalisation), rebuild + solve."""
    model = D.foh_discretize(em, t, x0, u0)
    _, grad = info(x0[k_ws], 1)
    L = scvx.concave_part(info.hessian(x0[k_ws]))
    n = t.size
    dt = np.diff(t)
    w_u = np.zeros(n)
    w_u[:-1] += dt / 2
    w_u[1:] += dt / 2
    opts = dict(tol_gap_abs=1e-10, tol_gap_rel=1e-10, tol_feas=1e-10, tol_ktratio=1e-8, max_iter=500)  # SCvx's

    def build(cls=scvx._Subproblem):
        sub = cls(n, True, k_ws, [], coast=u_max == 0)
        sub.x_ic.value, sub.x_tc.value, sub.umax.value = x0[0], x_final, u_max
        sub.w_u.value = 0.995 * w_u
        return sub

    t0 = time.perf_counter()
    sub = build()
    _load(sub, model, x0, u0, 0.05, 5e-3, grad, L)
    sub.solve("CLARABEL", True, opts)
    first = time.perf_counter() - t0
    old = build(_PerIntervalSubproblem)
    _load(old, model, x0, u0, 0.05, 5e-3, grad, L)
    old.solve("CLARABEL", True, opts)
    via_cvxpy = build()  # stacked Parameters, solved through Problem.solve
    via_cvxpy._clarabel = False
    _load(via_cvxpy, model, x0, u0, 0.05, 5e-3, grad, L)
    via_cvxpy.solve("CLARABEL", True, opts)
    etas = iter(np.geomspace(0.05, 0.01, 100))

    def resolve(s=sub):
        _load(s, model, x0, u0, next(etas), 5e-3, grad, L)
        s.solve("CLARABEL", False, opts)

    def rebuild():
        s2 = build()
        _load(s2, model, x0, u0, next(etas), 5e-3, grad, L)
        s2.solve("CLARABEL", True, opts)

    set_new = _best_time(lambda: _load(sub, model, x0, u0, 0.05, 5e-3, grad, L), 20)
    set_old = _best_time(lambda: _load(old, model, x0, u0, 0.05, 5e-3, grad, L), 20)
    direct, cvx = np.inf, np.inf  # interleaved: the same problem data through both solve paths
    for _ in range(max(repeat, 5)):
        direct = min(direct, _best_time(resolve, 1))
        cvx = min(cvx, _best_time(lambda: resolve(via_cvxpy), 1))
    return (direct, _best_time(lambda: resolve(old), repeat), first, _best_time(rebuild, repeat),
            set_new, set_old, cvx)


def main() -> dict:
    out = {}
    out.update(compare_sweeps(1))
    out.update(compare_sweeps(2))
    out.update(compare_lane_order(1))
    out.update(compare_lane_order(2))
    sc, t, k_ws, x0, u0, u_max, info = _setup()
    xw = x0[k_ws]
    D.foh_discretize(em, t, x0, u0)  # compile / warm the integrators
    info(xw, 1)
    rng = np.random.default_rng(0)

    def fresh():  # a new point each call: the information model caches its last linearisations and Hessians
        return xw + 1e-9 * rng.standard_normal(6)

    pieces = {
        "discretize_s": _best_time(lambda: D.foh_discretize(em, t, x0, u0)),
        "mi_value_s": _best_time(lambda: info(fresh(), 0)),
        "mi_gradient_s": _best_time(lambda: info(fresh(), 1)),
        "mi_hessian_s": _best_time(lambda: info.hessian(fresh()), 3),
    }
    resolve, resolve_old, first, rebuild, set_new, set_old, resolve_cvxpy = resolve_vs_rebuild(
        t, k_ws, x0, u0, u_max, sc.observer_xf, info)
    t0 = time.perf_counter()
    res = scvx.solve_scvx(em, t, x0, u0, u_max, x_final=sc.observer_xf, info=info, info_node=k_ws, alpha=5e-3)
    run_s = time.perf_counter() - t0
    H = res.history
    per_iter = {k: float(np.mean([h[k] for h in H])) for k in ("t_discretize", "t_info", "t_hessian", "t_solve")}
    out.update(
        n_nodes=N_NODES,
        **pieces,
        subproblem_resolve_s=resolve,
        subproblem_resolve_per_interval_parameters_s=resolve_old,
        subproblem_resolve_problem_solve_s=resolve_cvxpy,
        direct_over_problem_solve=resolve / resolve_cvxpy,
        parameter_setting_stacked_s=set_new,
        parameter_setting_per_interval_s=set_old,
        subproblem_first_solve_s=first,
        subproblem_rebuild_s=rebuild,
        rebuild_over_resolve=rebuild / resolve,
        run_alpha_5e_3_iterations=res.iterations,
        run_alpha_5e_3_s=run_s,
        run_per_iteration_s=run_s / res.iterations,
        **{f"run_mean_{k}_s": v for k, v in per_iter.items()},
        run_hessian_refreshes=int(sum(h["t_hessian"] > 0 for h in H)),
    )
    print(f"test case 1, {N_NODES} nodes (new path)")
    print(f"  in isolation: FOH discretisation {1e3 * pieces['discretize_s']:.1f} ms, MI value "
          f"{1e3 * pieces['mi_value_s']:.1f} ms, MI gradient {1e3 * pieces['mi_gradient_s']:.1f} ms, MI Hessian "
          f"{1e3 * pieces['mi_hessian_s']:.1f} ms")
    print(f"  convex subproblem: re-solve {1e3 * resolve:.1f} ms (through Problem.solve {1e3 * resolve_cvxpy:.1f} ms: "
          f"direct / Problem.solve {resolve / resolve_cvxpy:.2f})")
    print(f"  convex subproblem: re-solve {1e3 * resolve:.1f} ms (per-interval Parameters {1e3 * resolve_old:.1f} ms; "
          f"setting the Parameters {1e3 * set_new:.2f} vs {1e3 * set_old:.2f} ms), first solve (canonicalisation) "
          f"{1e3 * first:.0f} ms, rebuild + solve {1e3 * rebuild:.0f} ms ({rebuild / resolve:.1f} x re-solve)")
    print(f"  SCvx alpha_h = 5e-3 from the ballistic DRO: {res.iterations} iterations, {run_s:.2f} s "
          f"({run_s / res.iterations:.3f} s/iteration: discretisation {per_iter['t_discretize']:.3f}, MI value + "
          f"gradient {per_iter['t_info']:.3f}, Hessian {per_iter['t_hessian']:.3f} "
          f"({out['run_hessian_refreshes']} refreshes), solve {per_iter['t_solve']:.3f})")
    return out


if __name__ == "__main__":
    main()
