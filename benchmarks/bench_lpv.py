"""LMI solve time of the H2 precision problem (Theorem 1) against the number of polytope vertices 2^k.

The scheduling parameters of the 2:1 resonant-orbit box are released one at a time (the others held at the box
centre), k = 0..6, and the same problem is solved with Clarabel (interior point) and SCS (first-order, eps 1e-7).
Reported: build (cvxpy canonicalisation) and solve wall-clock seconds, status, and the optimal ||beta||_1.
"""

from __future__ import annotations

import time
import warnings


def main(max_k: int = 6, gamma: float = 0.0013) -> dict:
    """Run the benchmark and print a table; returns ``{(solver, n_vertices): {...}}`` as a dict of dicts."""
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
