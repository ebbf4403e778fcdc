"""LPV precision LMIs (Nychka & Bhattacharya): speed of the old against the new path, measured side by side in one
process and reported as RATIOS (old CPU time / new CPU time; the machine is shared, absolute times are noise), and
the LMI solve time against the number of polytope vertices.

``main()`` runs the ratios (about 40 s of CPU):

* ``hinf_norm``: the Hamiltonian level-set H-infinity norm with the frequency grid evaluated one frequency at a time
  (the old :func:`_hinf_norm_loop`, kept here) against the batched :func:`cislunar.estimation.lpv._hinf_norm`, on the
  frozen error systems notebook 11 verifies; the values must be bit-identical.
* ``verify``: :func:`cislunar.papers.nychka_bhattacharya.sensing_precision.verify_designs` with either kernel.
* ``objective``: the objective-norm study solving the p = 2 H-infinity problem first at its default scaling (old:
  it ends optimal_inaccurate and the retry list re-solves at the first retry scaling) against starting there (new);
  the designs must be bit-identical.
* ``backend``: notebook 11's eight 64-vertex and theta1-only problems (H2 and H-infinity; six sensors under
  p = 1, 2, inf and theta1 only under p = 1), each built and solved through cvxpy's canonicalisation (old,
  ``backend="cvxpy"``) against Clarabel's data built directly in numpy (new, the default).  Not bit-identical: the
  two reach the optimum along different paths, so the table reports the largest relative change of the used
  precisions and whether every status agrees.

``vertex_scaling(max_k)`` is the older benchmark (H2 LMI build and solve time against 2^k vertices, Clarabel and SCS;
about 8.5 min, almost all SCS) and is not run by ``main``.
"""

from __future__ import annotations

import time
import warnings

import numpy as np


def _hinf_norm_loop(A, B, C, rtol: float = 1e-9, max_iter: int = 50) -> float:
    """The H-infinity kernel before the batched frequency grid (one ``_sigma_max`` call per frequency)."""
    from cislunar.estimation.lpv import _sigma_max

    eig = np.linalg.eigvals(A)
    if np.max(eig.real) >= 0:
        return np.inf
    scale = max(np.max(np.abs(eig)), 1e-12)
    freqs = np.concatenate([[0.0], np.abs(eig.imag), scale * np.logspace(-4, 2, 60)])
    lb = max(_sigma_max(A, B, C, w) for w in freqs)
    if lb == 0:
        return 0.0
    BB, CC = B @ B.T, C.T @ C
    for _ in range(max_iter):
        g = lb * (1.0 + 2.0 * rtol)
        H = np.block([[A, BB / g**2], [-CC, -A.T]])
        ev = np.linalg.eigvals(H)
        tol_im = 1e-8 * max(np.max(np.abs(ev)), 1.0)
        w = np.sort(np.abs(ev[np.abs(ev.real) < tol_im].imag))
        w = np.unique(np.round(w / tol_im) * tol_im)
        if w.size == 0:
            return float(lb)
        cand = [w[0]] if w.size == 1 else 0.5 * (w[:-1] + w[1:])
        new = max(_sigma_max(A, B, C, x) for x in cand)
        if new <= lb * (1.0 + rtol):
            return float(lb)
        lb = new
    return float(lb)


def _objective_old(scenario, designs):
    """The objective-norm study's four solves as before (p = 2 H-infinity from its default scaling)."""
    from cislunar.estimation import lpv
    from cislunar.papers.nychka_bhattacharya import sensing_precision as sp

    V = scenario.box.vertices()
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        for obj in ("l2", "linf"):
            for n in sp.NORMS:
                kw = {"pole_radius": designs.pole_radius} if n == "hinf" else {}
                out[(obj, n)] = lpv.PrecisionLMI.for_cr3bp(scenario.model, V, n, objective=obj, **kw).solve(
                    designs.gamma, retry=not (obj == "linf" and n == "hinf"))
    return out


def _backend_set(scenario, backend):
    """Notebook 11's problems (build + solve) through ``backend``; returns the designs by case."""
    from cislunar.estimation import lpv
    from cislunar.papers.nychka_bhattacharya.scenarios import GAMMA, POLE_RADIUS, THETA1_SENSORS

    V = scenario.box.vertices()
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        for norm in ("h2", "hinf"):
            kw = {"pole_radius": POLE_RADIUS} if norm == "hinf" else {}
            for obj in ("l1", "l2", "linf"):
                lmi = lpv.PrecisionLMI.for_cr3bp(scenario.model, V, norm, objective=obj, backend=backend, **kw)
                if norm == "hinf" and obj in ("l1", "l2"):
                    lmi = lmi.rescaled(lpv.RETRY_SCALINGS[0][0], lmi.balanced_state_scale)
                out[(norm, obj, 6)] = lmi.solve(GAMMA, retry=not (norm == "hinf" and obj == "linf"))
            out[(norm, "l1", 2)] = lpv.PrecisionLMI.for_cr3bp(scenario.model, V, norm, sensors=THETA1_SENSORS,
                                                              backend=backend, **kw).solve(GAMMA)
    return out


def _same_design(a, b) -> bool:
    return all(np.array_equal(getattr(a, k), getattr(b, k)) for k in ("L", "X", "beta", "kappa", "used")) and \
        a.status == b.status and a.objective == b.objective


def _cpu(f, *args):
    t0 = time.process_time()
    out = f(*args)
    return out, time.process_time() - t0


def main(n_verify: int = 20) -> dict:
    """Old/new CPU-time ratios on notebook 11's quick set-up; prints a table and returns ``{name: {...}}``."""
    from cislunar.estimation import lpv
    from cislunar.papers.nychka_bhattacharya import sensing_precision as sp
    from cislunar.papers.nychka_bhattacharya.scenarios import GAMMA, POLE_RADIUS, paper_scenario

    sc = paper_scenario(n_samples=600)
    D = sp.paper_designs(sc, GAMMA, POLE_RADIUS)
    results = {}
    # H-infinity kernel on the frozen error systems of the four designs at the vertices and random points
    pts = np.vstack([sc.box.vertices(), sc.box.sample(n_verify, np.random.default_rng(0))])
    systems = [lpv._error_system(sc.model, d, r, d.L) for d in (*D.theta1.values(), *D.all.values()) for r in pts]
    old, t_old = _cpu(lambda: [_hinf_norm_loop(*s) for s in systems])
    new, t_new = _cpu(lambda: [lpv._hinf_norm(*s) for s in systems])
    results["hinf_norm"] = {"old_s": t_old, "new_s": t_new, "ratio": t_old / t_new, "n": len(systems),
                            "identical": old == new}
    # the verification of the four designs, old kernel swapped in for the duration of the call
    kernel = lpv._hinf_norm
    try:
        lpv._hinf_norm = _hinf_norm_loop
        v_old, t_old = _cpu(sp.verify_designs, sc, D, n_verify, np.random.default_rng(0))
    finally:
        lpv._hinf_norm = kernel
    v_new, t_new = _cpu(sp.verify_designs, sc, D, n_verify, np.random.default_rng(0))
    results["verify"] = {"old_s": t_old, "new_s": t_new, "ratio": t_old / t_new, "n": 4,
                         "identical": all(np.array_equal(getattr(v_old[k], f), getattr(v_new[k], f))
                                          for k in v_old for f in ("max_real_eig", "worst_h2", "worst_hinf",
                                                                   "worst_rho_h2", "worst_rho_hinf"))}
    # the objective-norm study
    o_old, t_old = _cpu(_objective_old, sc, D)
    o_new, t_new = _cpu(lambda: sp.objective_norm_study(sc, D).designs)
    results["objective"] = {"old_s": t_old, "new_s": t_new, "ratio": t_old / t_new, "n": 4,
                            "identical": all(_same_design(o_old[k], o_new[k]) for k in o_old)}
    # cvxpy canonicalisation against the directly built Clarabel data (the same eight problems, built and solved)
    b_old, t_old = _cpu(_backend_set, sc, "cvxpy")
    b_new, t_new = _cpu(_backend_set, sc, "direct")
    change = max(float(np.max(np.abs(b_new[k].kappa[b_old[k].used] / b_old[k].kappa[b_old[k].used] - 1)))
                 for k in b_old)
    results["backend"] = {"old_s": t_old, "new_s": t_new, "ratio": t_old / t_new, "n": len(b_old),
                          "identical": all(_same_design(b_old[k], b_new[k]) for k in b_old),
                          "statuses_equal": all(b_old[k].status == b_new[k].status for k in b_old),
                          "max_rel_kappa_change": change}
    print(f"{'case':12s} {'n':>6s} {'old CPU s':>10s} {'new CPU s':>10s} {'old/new':>8s} {'identical':>10s}")
    for k, r in results.items():
        print(f"{k:12s} {r['n']:6d} {r['old_s']:10.2f} {r['new_s']:10.2f} {r['ratio']:8.2f} {str(r['identical']):>10s}")
    r = results["backend"]
    print(f"backend: statuses equal {r['statuses_equal']}, largest relative change of a used precision "
          f"{r['max_rel_kappa_change']:.1e}")
    return results


def vertex_scaling(max_k: int = 6, gamma: float = 0.0013) -> dict:
    """H2 precision problem (Theorem 1) against the number of polytope vertices 2^k.

    The scheduling parameters of the 2:1 resonant-orbit box are released one at a time (the others held at the box
    centre), k = 0..6, and the same problem is solved with Clarabel (interior point) and SCS (first-order, eps
    1e-7).  Reported: build (cvxpy canonicalisation) and solve wall-clock seconds, status, and the optimal
    ||beta||_1; returns ``{"SOLVER_nvertices": {...}}``.
    """
    from cislunar.estimation import lpv
    from cislunar.papers.nychka_bhattacharya.scenarios import paper_scenario

    sc = paper_scenario(n_samples=1000)
    order = [0, 2, 4, 5, 1, 3]  # 1/r13^3, 1/r13, x, y, 1/r23^3, 1/r23
    results = {}
    print(f"{'solver':9s} {'vertices':>8s} {'build s':>8s} {'solve s':>8s} {'status':>20s} {'||beta||_1':>12s}")
    for k in range(max_k + 1):
        V = sc.box.vertices(free=order[:k])
        for solver, opts in (("CLARABEL", {}), ("SCS", {"eps_abs": 1e-7, "eps_rel": 1e-7})):
            t0 = time.perf_counter()
            lmi = lpv.PrecisionLMI.for_cr3bp(sc.model, V, "h2")
            build = time.perf_counter() - t0
            t0 = time.perf_counter()
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    d = lmi.solve(gamma, solver=solver, retry=False, **opts)
                status, obj = d.status, d.objective
            except lpv.InfeasibleLMIError as exc:
                status, obj = exc.status, float("nan")
            solve = time.perf_counter() - t0
            results[f"{solver}_{V.shape[0]}"] = {"solver": solver, "vertices": V.shape[0], "build_s": build,
                                                 "solve_s": solve, "status": status, "beta_l1": obj}
            print(f"{solver:9s} {V.shape[0]:8d} {build:8.2f} {solve:8.2f} {status:>20s} {obj:12.5g}", flush=True)
    return results


if __name__ == "__main__":
    main()
