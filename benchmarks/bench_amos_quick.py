"""Notebooks 07/08 speed-ups, old path against new, side by side in one process (ratios; nothing asserted).

* ``ssat kernel``: the measurement loop of ``ssat.ssat_covariance`` as it was (``np.linalg.qr``/``solve`` wrappers
  and one ``einsum`` per epoch, the oracle of ``tests/guidance/test_ssat_kernel.py``) against
  ``ssat._sri_range_variance``, for one trajectory (a Nelder-Mead cost evaluation of the true minimiser) and for a
  600-direction sphere, 49 hourly epochs; the outputs are compared bit for bit.
* ``MMD true minimiser``: ``ssat.minimize_range_sigma`` at the 12-h coast of notebook 07 (600-direction sphere +
  Nelder-Mead), old kernel patched in against the new one; same minimiser required.
* ``215-km QPO member``: ``qpo_for_mean_range`` with the range extrema refined at every secant step (old) against
  only for the accepted member (new); same member and statistics required.

Run with ``python -m benchmarks amos_quick``.
"""

import sys
import time
from pathlib import Path

import numpy as np

from benchmarks.bench_torus import _timed as _best
from cislunar.cr3bp import torus as tm
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.cr3bp.orbits import nrho_9_2
from cislunar.cr3bp.propagation import propagate
from cislunar.guidance import ssat

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "guidance"))
from test_ssat_kernel import _reference_loop as _old_loop  # the test oracle, not part of the package  # noqa: E402

HR = 3600.0 / em.time_unit_s


def _old_qpo(orbit, target_km=215.0, N=25, n_theta=48, n_t=1201, rtol=1e-5, max_iter=12):
    """qpo_for_mean_range as it was: mean_range (with both extrema refined) at every secant step."""
    small = tm.torus_from_orbit(orbit, N, min(5.0, target_km / 10.0))
    stats = tm.mean_range(small, n_theta=n_theta, n_t=n_t)
    sizes, means = [small.size_km], [stats.mean_km]
    guess_km, torus = small.size_km * target_km / means[0], small
    for _ in range(max_iter):
        n_steps = max(1, int(np.ceil(abs(guess_km - torus.size_km) / 25.0)))
        torus = tm.continue_tori(torus, np.linspace(torus.size_km, guess_km, n_steps + 1)[1:], parameter="size_km",
                                 progress=False)[-1]
        stats = tm.mean_range(torus, n_theta=n_theta, n_t=n_t)
        if abs(stats.mean_km - target_km) <= rtol * target_km:
            return torus, stats
        sizes.append(torus.size_km)
        means.append(stats.mean_km)
        guess_km = sizes[-1] + (target_km - means[-1]) / ((means[-1] - means[-2]) / (sizes[-1] - sizes[-2]))
    raise RuntimeError("no member")


def main(repeat: int = 5) -> dict:
    orbit = nrho_9_2(em)
    xa0 = propagate(em, orbit.x0, np.array([0.0, -0.5 * HR])).x[-1]
    t = np.arange(49) * HR
    target = ssat.propagate_with_impulses(em, orbit.x0, t)
    P0 = ssat.initial_covariance(em)
    out = {}
    print("ssat kernel (49 hourly epochs): old wrapper loop vs new kernel")
    for n in (1, 600):
        D = ssat.fibonacci_sphere(max(n, 2))[:n]
        agent = ssat.propagate_with_impulses(em, np.broadcast_to(xa0, (n, 6)), t,
                                             [(t[0], 1e-3 / em.velocity_unit_km_s * D)])
        xt = np.broadcast_to(target.x, (n, t.size, 6))
        st = np.broadcast_to(target.stm, (n, t.size, 6, 6))
        H, _, _ = ssat._measurement_rows(em, agent.x, xt, ssat.AMOS_SIGMA_MIN_RAD, ssat.AMOS_RESOLUTION_KM)
        A = np.concatenate([H[..., :6] @ agent.stm, H[..., 6:] @ st], axis=-1)
        R0 = np.broadcast_to(np.linalg.inv(np.linalg.cholesky(P0)), (n, 12, 12)).copy()
        M = ssat.range_projection(np.concatenate([agent.x, xt], axis=-1), "inertial")
        r = max(1, repeat * (20 if n == 1 else 1))
        t_old, (J_old, _) = _best(lambda: _old_loop(R0, A, agent.stm, st, M), r)
        t_new, (J_new, _) = _best(lambda: ssat._sri_range_variance(R0, A, agent.stm, st, M), r)
        same = bool(np.array_equal(J_old, J_new))
        print(f"  n = {n:4d}: old {t_old * 1e3:8.2f} ms, new {t_new * 1e3:8.2f} ms, old/new {t_old / t_new:5.2f}; "
              f"bit-identical {same}")
        out[f"kernel_n{n}"] = {"old_s": t_old, "new_s": t_new, "ratio": t_old / t_new, "identical": same}

    tb = t[:13]
    tgt = ssat.propagate_with_impulses(em, orbit.x0, tb)
    dv = 1e-3 / em.velocity_unit_km_s

    def minimiser():
        return ssat.minimize_range_sigma(em, xa0, None, tb, dv, P0, n_grid=600, target=tgt)

    minimiser()  # warm-up
    t_new, (d_new, J_new) = _best(minimiser, max(1, repeat // 2))
    kernel = ssat._sri_range_variance
    ssat._sri_range_variance = _old_loop
    try:
        t_old, (d_old, J_old) = _best(minimiser, max(1, repeat // 2))
    finally:
        ssat._sri_range_variance = kernel
    same = bool(np.array_equal(d_old, d_new) and J_old == J_new)
    print(f"MMD true minimiser, 12-h coast, 600 directions + Nelder-Mead: old {t_old:.3f} s, new {t_new:.3f} s, "
          f"old/new {t_old / t_new:.2f}; same minimiser {same}")
    out["minimiser"] = {"old_s": t_old, "new_s": t_new, "ratio": t_old / t_new, "identical": same}

    t0 = time.perf_counter()
    m_old, s_old = _old_qpo(orbit)
    t_old = time.perf_counter() - t0
    t0 = time.perf_counter()
    m_new, s_new = tm.qpo_for_mean_range(orbit, 215.0)
    t_new = time.perf_counter() - t0
    same = bool(np.array_equal(m_old.circle, m_new.circle) and s_old.min_km == s_new.min_km
                and s_old.max_km == s_new.max_km and s_old.mean_km == s_new.mean_km)
    print(f"215-km QPO member (N = 25): old {t_old:.2f} s, new {t_new:.2f} s, old/new {t_old / t_new:.2f}; "
          f"same member and statistics {same}")
    out["qpo_member"] = {"old_s": t_old, "new_s": t_new, "ratio": t_old / t_new, "identical": same}
    return out


if __name__ == "__main__":
    main()
