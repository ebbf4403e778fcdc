"""How low can a detection run go?  The floor of the filter's cost per trial, against issue 21's 2 ms target.

One detection run of notebook 10 at the benchmark setting of ``bench_detection`` (one 9:2 NRHO period from
periapsis, 2-hour cadence, L2 angles and rates, quiet burn at apoapsis, window tuning f = 0.1, OCBE filter and
smoother, z).  Measured in one process, one thread, CPU seconds:

* ``whole``: :func:`~cislunar.papers.greaves_scheeres_2021.detection.run_detection_monte_carlo` per trial, and the
  same run under cProfile split into heyoka's ``propagate_grid``, numpy's stacked QR and the rest.
* ``integration``: the filter's integration pattern replayed alone (every interval of the track restarted at its
  first epoch, the interval's sub-grid as output, 16 trials per batch integrator, the filter's tolerance) for
  three systems: the OCBE block integrator the filter runs (reference, Phi_xx, Phi_xp: 78 states), the plain STM
  (reference and Phi_xx: 42 states, a lower bound if Phi_xp came for free, e.g. by quadrature), and the reference
  alone (6 states).  At the filter's tolerance 1e-15 and at 1e-12.

The floor of a re-linearised filter is its STM integration plus its triangularisations: if both stay above 2 ms,
no rewrite of the bookkeeping reaches the target without changing what is computed.  Run with
``OMP_NUM_THREADS=1 python -m benchmarks detection_floor``; ratios and splits from one run, no timed assertion.
"""

import cProfile
import pstats
import time

import numpy as np

from cislunar.cr3bp import orbits
from cislunar.cr3bp import propagation as prop
from cislunar.cr3bp.dynamics import EARTH_MOON as em
from cislunar.estimation import ocbe
from cislunar.papers.greaves_scheeres_2021 import detection as det

_LANES = 16  # cislunar.estimation.batched_ocbe._LANES


def _cpu(fn):
    c0 = time.process_time()
    out = fn()
    return time.process_time() - c0, out


def whole(setup, pol, n_trials: int, seed: int, batch: int) -> dict:
    """Per-trial CPU of the Monte Carlo, then its split under cProfile (heyoka, QR, the rest)."""
    c, _ = _cpu(lambda: det.run_detection_monte_carlo(setup, pol, n_trials, seed, batch_size=batch, progress=False))
    prof = cProfile.Profile()
    c_p, _ = _cpu(lambda: prof.runcall(det.run_detection_monte_carlo, setup, pol, n_trials, seed, batch_size=batch,
                                       progress=False))
    stats = pstats.Stats(prof).stats
    heyoka = sum(v[2] for k, v in stats.items() if k[2] == "<built-in method heyoka._core.propagate_grid>"
                 or k[2].endswith("propagate_grid>"))
    qr = sum(v[3] for k, v in stats.items() if k[2] == "qr" and "linalg" in k[0])
    total = sum(v[2] for v in stats.values())
    per = 1e3 / n_trials
    out = {"ms_per_trial": c * per, "profiled_ms_per_trial": c_p * per, "heyoka_ms": heyoka * per, "qr_ms": qr * per,
           "rest_ms": (total - heyoka - qr) * per}
    print(f"whole Monte Carlo, {n_trials} trials: {out['ms_per_trial']:.2f} ms/trial ({out['profiled_ms_per_trial']:.2f}"
          f" profiled: heyoka propagate_grid {out['heyoka_ms']:.2f}, numpy QR {out['qr_ms']:.2f}, the rest "
          f"{out['rest_ms']:.2f} ms)")
    return out


def _replay(sys_, n_pars: int, n_state: int, t, n_sub: int, x_ref, tol: float, repeats: int) -> float:
    """CPU ms per trial of the filter's integration pattern for ``sys_`` (16 lanes, one track)."""
    import heyoka as hy

    ta = hy.taylor_adaptive_batch(sys_, np.zeros((n_state, _LANES)), pars=np.zeros((n_pars, _LANES)), tol=tol,
                                  compact_mode=True)
    ta.pars[0] = em.mu
    if n_pars > 1:
        ta.pars[1] = 1e-10
    start = np.zeros((n_state, _LANES))
    if n_state > 6:
        start[6:42] = np.eye(6).ravel()[:, None]
    spread = 1.0 + 1e-7 * np.arange(_LANES)

    def once():
        for n in range(t.size - 1):
            grid = np.linspace(t[n], t[n + 1], n_sub)
            start[:6] = x_ref[n][:, None] * spread[None, :]
            ta.set_time(np.full(_LANES, grid[0]))
            ta.state[:] = start
            ta.propagate_grid(np.repeat(grid[:, None], _LANES, axis=1))

    once()
    c, _ = _cpu(lambda: [once() for _ in range(repeats)])
    return c / repeats / _LANES * 1e3


def integration(setup, repeats: int = 3) -> dict:
    import heyoka as hy

    sc = setup.scenario
    t = np.asarray(sc.t)
    x_ref = prop.propagate(em, sc.x_start, t).x
    base, _ = prop._cr3bp_system()
    systems = {"OCBE blocks (filter)": (ocbe._block_system(False), 2),
               "STM (reference + Phi_xx)": (hy.var_ode_sys(base, hy.var_args.vars, order=1), 1),
               "reference only": (base, 1)}
    out = {}
    for tol in (setup.tol, 1e-12):
        for name, (s, n_pars) in systems.items():
            n_state = len(s.sys) if hasattr(s, "sys") else len(s)
            ms = _replay(s, n_pars, n_state, t, setup.n_sub, x_ref, tol, repeats)
            out[(name, tol)] = ms
            print(f"integration pattern ({t.size - 1} intervals x {setup.n_sub} sub-grid points), {name}, "
                  f"{n_state} states, tol {tol:.0e}: {ms:.2f} ms/trial")
    return out


def main(n_trials: int = 512, batch: int = 8, seed: int = 3) -> dict:
    pol = det.QUIET_POLICY
    setup = det.make_setup(em, orbits.nrho_9_2(em), 0.1 * det.window_control_weight(pol), 1e-18)
    det.run_detection_monte_carlo(setup, pol, 2 * batch, seed + 1, batch_size=batch, progress=False)  # compile
    result = whole(setup, pol, n_trials, seed, batch)
    ints = integration(setup)
    stm = ints[("STM (reference + Phi_xx)", setup.tol)]
    floor = stm + result["qr_ms"]
    result.update(integration={f"{k[0]} @ {k[1]:.0e}": v for k, v in ints.items()}, floor_ms=floor)
    print(f"floor of a re-linearised filter at today's tolerance: STM integration {stm:.2f} + QR {result['qr_ms']:.2f}"
          f" = {floor:.2f} ms/trial against issue 21's 2 ms (with Phi_xp, bookkeeping and the smoother free)")
    return result


if __name__ == "__main__":
    main()
