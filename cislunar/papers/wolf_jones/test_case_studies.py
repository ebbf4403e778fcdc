"""Studies of Wolf & Jones test cases 1 and 2 (notebooks 05 and 06): each returns a frozen result object.

Test case 1 (notebook 05): the Table 2 slip (:func:`table2_slip`), the homotopy sweep both ways
(:func:`sweep_test_case_1`), the printed exact-penalty SCvx (:func:`penalty_study`), the re-flight of every plan
(:func:`reflight`), the mesh check (:func:`mesh_check`), the departures from the DRO (:func:`departures_km`), the
CRLB of every plan under the adopted and the literal process noise (:func:`crlb_study`) and the equal-impulse
comparison (:func:`budget_study`).  Test case 2 (notebook 06) follows below.

Units: impulses in m/s, distances in km, times in TU unless a name says ``days``; states are rotating-frame
barycentric CR3BP states in LU and LU/TU.
"""

from __future__ import annotations

import concurrent.futures
import functools
import time
from dataclasses import dataclass

import numpy as np
from scipy.stats import spearmanr

from cislunar.cr3bp import orbits
from cislunar.cr3bp.dynamics import check_system
from cislunar.cr3bp.propagation import ImpactError, propagate, propagate_stm
from cislunar.guidance import discretization as D
from cislunar.guidance import scvx
from cislunar.papers.wolf_jones import _checks
from cislunar.papers.wolf_jones import scenarios as wj
from cislunar.sensing import covariance as cov
from cislunar.utils import montecarlo, validation

__all__ = ["case1_scenario_summary", "SlipStudy", "table2_slip", "Case1Sweep", "sweep_test_case_1", "PenaltyStudy", "penalty_study",
           "Reflight", "reflight", "MeshCheck", "mesh_check", "departures_km", "CrlbStudy", "crlb_study",
           "BudgetRow", "budget_study", "GradientCheck", "gradient_check", "KeepOutScan",
           "keep_out_scan", "PlanRow", "plan_row", "Case2Sweep", "case2_rows", "departure_km", "GridDepartures",
           "grid_departures", "MirrorPair", "mirror_pair", "mirrored", "relative_rms_km", "NoiseReadings",
           "noise_readings", "Front", "front", "RecordingInformation", "FreeRun", "free_run", "RadiusRow", "radius_row",
           "alt_grid_sweep", "MirrorStudy", "mirror_study", "case2_budget", "radius_summary", "dominated_note",
           "KeepOutStudy", "keep_out_study", "Case2Runs", "case2_runs", "KeepOutJobs",
           "queue_keep_out_runs", "dense_flight"]


def _mps(system) -> float:
    return system.velocity_unit_km_s * 1e3


def _dv(res, system) -> float:
    """Total impulse of an SCvx result in m/s."""
    return res.impulse * system.velocity_unit_km_s * 1e3


def _alphas(value, name: str = "alphas") -> np.ndarray:
    """Homotopy weights: a non-empty, strictly increasing vector inside [0, 1]."""
    a = _checks.vector(value, name)
    if np.any(a < 0) or np.any(a > 1) or np.any(np.diff(a) <= 0):
        raise ValueError(f"{name} must be strictly increasing within [0, 1]; got {a}")
    return a


def _node(value, name: str, n: int) -> int:
    """A node index on a grid of ``n`` nodes."""
    return validation.integer(value, name, minimum=0, maximum=n - 1)


def _rows(value, name: str, width: int, *, allow_empty: bool = True) -> list:
    """A sequence of tuples of ``width`` entries."""
    rows = _checks.sequence(value, name, allow_empty=allow_empty)
    for i, r in enumerate(rows):
        if not isinstance(r, tuple) or len(r) != width:
            raise validation.ArgumentTypeError(f"{name}[{i}] must be a tuple of {width} entries; got "
                                               f"{type(r).__name__} {r!r:.60}")
    return rows


# --------------------------------------------------------------------------------------------------------------
# test case 1, section 1: which number of Table 2's x_S(t0) slipped
# --------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SlipStudy:
    """The printed observer state of Table 2 and the two readings of its slip.

    Attributes
    ----------
    printed_fate : str
        What the printed state does when flown ballistically over the scenario.
    printed_transfer_mps : float
        Minimum-impulse transfer (alpha_h = 0) from the printed state to x_S(t_f), m/s.
    readings : dict
        ``name -> (x0 (6,), period TU)`` for "x0 held (vy0 corrected)" and "vy0 held (x0 corrected)".
    n_other_rows : int
    x0_span, period_span_days : tuple
        Span of x0 (LU) and period (days) over the other (periodic) rows of Tables 2 and 4.
    max_other_closure : float
    adjacent, miss_days, miss23_days : dict
        Per reading: inside the span; largest miss of the text's 12/17/32 days; miss of its 23 days (days).
    windows_days : dict
        Per reading: ``(case 1 window, case 2 window)`` in days.
    """

    printed_fate: str
    printed_transfer_mps: float
    readings: dict
    n_other_rows: int
    x0_span: tuple
    period_span_days: tuple
    max_other_closure: float
    adjacent: dict
    miss_days: dict
    miss23_days: dict
    windows_days: dict

    ADOPTED = "x0 held (vy0 corrected)"
    REJECTED = "vy0 held (x0 corrected)"

    @property
    def x0_wins(self) -> bool:
        """The adopted reading lies inside the span of the other rows and the rejected one does not."""
        return bool(self.adjacent[self.ADOPTED] and not self.adjacent[self.REJECTED])

    def summary(self, system) -> str:
        lines = [f"printed observer state, flown ballistically: {self.printed_fate}",
                 f"minimum-impulse transfer (alpha_h = 0) from the printed state to x_S(t_f): "
                 f"{self.printed_transfer_mps:.2f} m/s",
                 f"the {self.n_other_rows} other rows of Tables 2 and 4: x0 {self.x0_span[0]:.5f}-{self.x0_span[1]:.5f}"
                 f" LU, periods {self.period_span_days[0]:.2f}-{self.period_span_days[1]:.2f} d, closures <= "
                 f"{self.max_other_closure:.1e}"]
        for name, (x0_r, P_r) in self.readings.items():
            w1, w2 = self.windows_days[name]
            lines.append(f"{name:<26}: x0 = {x0_r[0]:.7f}, vy0 = {x0_r[4]:.7f}, P = {system.tu_to_days(P_r):.2f} d "
                         f"(inside the span of the other rows: {self.adjacent[name]}) -> case 1 window "
                         f"{w1[0]:.2f}-{w1[1]:.2f} d, case 2 window {w2[0]:.2f}-{w2[1]:.2f} d")
        lines.append("largest miss of the paper's 12 (case 1), 17 and 32 days (case 2): "
                     + str({k: round(float(v), 2) for k, v in self.miss_days.items()})
                     + " ; miss of its '23 days' (case 1 window end): "
                     + str({k: round(float(v), 2) for k, v in self.miss23_days.items()}))
        return "\n".join(lines)


def case1_scenario_summary(sc: wj.Scenario) -> str:
    """The test case 1 scenario in words: period, window, measurements, thrust bound, process noise, and the
    printed observer state against its periodic correction."""
    validation.instance(sc, "sc", wj.Scenario)
    em, tm, chk = sc.system, sc.measurement_times, sc.row_checks["observer_t0"]
    return "\n".join([
        f"P_ref = {em.tu_to_days(sc.period):.3f} d; scenario {em.tu_to_days(sc.duration):.2f} d; window "
        f"{em.tu_to_days(sc.window[0]):.2f}-{em.tu_to_days(sc.window[1]):.2f} d; {tm.size} daily measurements "
        f"({em.tu_to_days(tm[0]):.2f} ... {em.tu_to_days(tm[-1]):.2f} d)",
        f"a_max = 1e-6 km/s^2 = {sc.a_max:.4f} LU/TU^2; q = {sc.q:g} LU^2/TU^3; measurement sigma 100 m per axis",
        f"observer x_S(t0): printed vy0 = {chk.vy0:.9f}, periodic vy0 = {chk.corrected.x0[4]:.9f} (difference "
        f"{chk.vy0_correction * _mps(em):.2f} m/s); printed state misses itself by {chk.raw_closure:.2f} LU after one "
        "period"])


def table2_slip(sc: wj.Scenario, sc2: wj.Scenario, n_nodes: int, sigma: float = 1.0) -> SlipStudy:
    """Fly the printed x_S(t0), price a transfer from it, and weigh the two readings of its slip.

    Parameters
    ----------
    sc, sc2 : Scenario
        Test cases 1 and 2 (their other Table 2/4 rows give the span of "adjacent" DROs).
    n_nodes : int
        Sundman nodes of the minimum-impulse transfer from the printed state.
    sigma : float
        Sundman exponent.
    """
    validation.instance(sc, "sc", wj.Scenario)
    validation.instance(sc2, "sc2", wj.Scenario)
    n_nodes = validation.integer(n_nodes, "n_nodes", minimum=4)
    sigma = validation.real(sigma, "sigma")
    em = sc.system
    try:
        propagate(em, sc.observer_x0_printed, [0.0, sc.duration])
        fate = "stays clear of the primaries"
    except ImpactError as exc:
        fate = f"hits the {exc.body} on day {em.tu_to_days(exc.time):.1f}"
    t, _, _ = sc.node_times(n_nodes, sigma)
    x = propagate(em, sc.observer_x0, t).x
    x[0] = sc.observer_x0_printed  # start from the printed state, guess along the corrected DRO
    transfer = scvx.solve_scvx(em, t, x, np.zeros((t.size, 3)), sc.control_bounds(t), x_final=sc.observer_xf)
    vy0_held = orbits.correct_symmetric(em, sc.observer_x0_printed + [0.02, 0, 0, 0, 0, 0], fix="vy0")
    readings = {SlipStudy.ADOPTED: (sc.observer_x0, sc.period), SlipStudy.REJECTED: (vy0_held.x0, vy0_held.period)}
    others = [c for s in (sc, sc2) for lab, c in s.row_checks.items() if lab != "observer_t0"]
    x0_span = (min(c.x0 for c in others), max(c.x0 for c in others))
    p_span = (min(em.tu_to_days(c.corrected.period) for c in others),
              max(em.tu_to_days(c.corrected.period) for c in others))
    adjacent, miss, miss23, windows = {}, {}, {}, {}
    for name, (x0_r, P_r) in readings.items():
        pd = em.tu_to_days(P_r)
        w1, w2 = (0.75 * pd, 1.5 * pd), (pd, 2.0 * pd)
        windows[name] = (w1, w2)
        adjacent[name] = bool(x0_span[0] <= x0_r[0] <= x0_span[1] and p_span[0] <= pd <= p_span[1])
        miss[name] = max(abs(w1[0] - 12.0), abs(w2[0] - 17.0), abs(w2[1] - 32.0))
        miss23[name] = abs(w1[1] - 23.0)
    return SlipStudy(fate, transfer.impulse * _mps(em), readings, len(others), x0_span, p_span,
                     max(c.raw_closure for c in others), adjacent, miss, miss23, windows)


# --------------------------------------------------------------------------------------------------------------
# test case 1, sections 2-3: nodes, models and the homotopy sweep both ways
# --------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Case1Sweep:
    """Test case 1 planned over a grid of homotopy weights (best of an upward and a downward sweep).

    Attributes
    ----------
    scenario : Scenario
    alphas : tuple of float
    t, u_max : ndarray
        Node times (TU) and thrust bounds per node (LU/TU^2; zero in the window).
    k_ws, k_we : int
        Window-start and window-end nodes.
    x_ball, u_ball : ndarray
        Ballistic guess.
    info : WindowInformation
    solver : ScenarioSolver
        ``solver(alpha, x_guess, u_guess)`` on this grid.
    sweep : SweepResult
    seconds : float
        Wall time of the sweep.
    """

    scenario: wj.Scenario
    alphas: tuple
    t: np.ndarray
    k_ws: int
    k_we: int
    u_max: np.ndarray
    x_ball: np.ndarray
    u_ball: np.ndarray
    info: object
    solver: object
    sweep: object
    seconds: float

    @property
    def best(self) -> list:
        return self.sweep.best

    @property
    def impulse_mps(self) -> np.ndarray:
        return self.sweep.column("impulse") * _mps(self.scenario.system)

    @property
    def mi(self) -> np.ndarray:
        return self.sweep.column("information")

    @property
    def in_window(self) -> np.ndarray:
        return self.u_max == 0

    @property
    def monotone(self) -> bool:
        """Impulse and MI non-decreasing in alpha_h (1e-6 relative)."""
        imp, mi = self.impulse_mps, self.mi
        return bool(np.all(np.diff(imp) >= -1e-6 * imp.max()) and np.all(np.diff(mi) >= -1e-6))

    @property
    def cost_gap(self) -> float:
        """Largest difference between the costs of the converged runs at one alpha_h (up against down)."""
        att = self.sweep.attempts
        return max(abs(min(r["cost"] for r in att if r["alpha"] == a and r["converged"])
                       - max(r["cost"] for r in att if r["alpha"] == a and r["converged"])) for a in self.alphas)

    @property
    def distinct_optima(self) -> bool:
        return bool(self.cost_gap > 1e-8 * (1 + max(abs(b.cost) for b in self.best)))

    def index(self, alpha: float) -> int:
        return self.alphas.index(alpha)

    def summary(self) -> str:
        em, att = self.scenario.system, self.sweep.attempts
        n_iter = sum(a["iterations"] for a in att)
        t, k_ws, k_we = self.t, self.k_ws, self.k_we
        lines = [f"{t.size} nodes; window nodes {k_ws}..{k_we} (t = {em.tu_to_days(t[k_ws]):.3f}, "
                 f"{em.tu_to_days(t[k_we]):.3f} d); node spacing {em.tu_to_days(np.diff(t)).min():.2f}-"
                 f"{em.tu_to_days(np.diff(t)).max():.2f} d",
                 f"ballistic: I = {self.info(self.x_ball[self.k_ws], 0):.3f} nats; |x(t_f) - x_S(t_f)| = "
                 f"{np.linalg.norm(self.x_ball[-1, :3] - self.scenario.observer_xf[:3]) * em.length_unit_km:.1f} km",
                 f"{len(att)} SCvx runs, {n_iter} iterations, {self.seconds:.0f} s "
                 f"({self.seconds / n_iter:.2f} s per iteration)", f"{'alpha_h':>8} {'dir':>5} {'ok':>3} {'iter':>5} {'cost':>14}"]
        lines += [f"{a['alpha']:8.4f} {a['direction']:>5} {'y' if a['converged'] else 'n':>3} {a['iterations']:5d} "
                  f"{a['cost']:14.9f} {a['error'][:60]}" for a in att]
        lines += ["best of sweeps: impulse [m/s] " + str(np.round(self.impulse_mps, 3)),
                  "                MI [nats]     " + str(np.round(self.mi, 3)),
                  "                from          " + str(self.sweep.source),
                  f"impulse and MI non-decreasing in alpha_h: {self.monotone}; largest up/down cost difference "
                  f"{self.cost_gap:.1e}"]
        return "\n".join(lines)


def sweep_test_case_1(sc: wj.Scenario, n_nodes: int, alphas, *, sigma: float = 1.0, forward_hessian: bool = False,
                      progress: bool = False) -> Case1Sweep:
    """Sundman nodes, the information model and the homotopy sweep of test case 1 (notebook 05, sections 2-3).

    Parameters
    ----------
    sc : Scenario
        Test case 1.
    n_nodes : int
    alphas : sequence of float
        Strictly increasing homotopy weights in [0, 1].
    sigma : float
        Sundman exponent.
    forward_hessian : bool
        Forward-difference Hessian of the MI (6 gradients instead of 12; it only shapes the trust-region model).
    """
    validation.instance(sc, "sc", wj.Scenario)
    n_nodes = validation.integer(n_nodes, "n_nodes", minimum=4)
    alphas = tuple(float(a) for a in _alphas(alphas))
    sigma = validation.real(sigma, "sigma")
    forward_hessian = validation.boolean(forward_hessian, "forward_hessian")
    validation.boolean(progress, "progress")
    t, k_ws, k_we = sc.node_times(n_nodes, sigma)
    x_ball, u_ball = sc.ballistic_guess(t)
    info = sc.information_model()
    if forward_hessian:
        info.hessian_scheme = "forward"
    solver = wj.ScenarioSolver(sc, t, k_ws, information=info, settings=scvx.SCvxSettings())
    t0 = time.perf_counter()
    sweep = scvx.homotopy_sweep(solver, list(alphas), x_ball, u_ball, progress=progress)
    seconds = time.perf_counter() - t0
    if any(b is None for b in sweep.best):
        raise RuntimeError("an alpha_h without any converged run")
    return Case1Sweep(sc, alphas, t, k_ws, k_we, solver.u_max, x_ball, u_ball, info, solver, sweep, seconds)


# --------------------------------------------------------------------------------------------------------------
# test case 1, section 4: the printed exact-penalty SCvx
# --------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PenaltyStudy:
    """The printed method (L1 exact penalty, linear MI model of Eq. 44) against our solver at one alpha_h.

    Attributes
    ----------
    alpha : float
    cold : SCvxResult
        Our solver from the ballistic DRO (its history is the convergence log).
    runs : list of dict
        Exact-penalty runs (``gamma, max_iter, model, converged, outcome, history, best, eta``): the gamma sweep,
        then gamma = 1e3 with the long iteration limit.
    hybrid : dict
        Exact penalty with our quadratic MI model, gamma = 1e3.
    n_iter : int
        The iteration limit of the gamma sweep.
    seconds : float
    """

    alpha: float
    cold: object
    runs: list
    hybrid: dict
    n_iter: int
    seconds: float

    @property
    def any_converged(self) -> bool:
        return any(r["converged"] for r in self.runs)

    @property
    def printed(self) -> dict:
        """The gamma = 1e3 run of the sweep (the one drawn against ours)."""
        return next(r for r in self.runs if r["gamma"] == 1e3 and r["max_iter"] == self.n_iter)

    @property
    def long_run(self) -> dict:
        return self.runs[-1]

    def summary(self, best_cost: float) -> str:
        h = self.cold.history
        lines = [f"cold start alpha_h = {self.alpha:g}: {self.cold.iterations} iterations, cost {self.cold.cost:.9f} "
                 f"(best of sweeps {best_cost:.9f})",
                 f"{'it':>3} {'predicted':>10} {'err defect':>11} {'err MI':>10} {'rho':>8} {'eta':>9} {'TR':>3} "
                 f"{'defect':>8}"]
        lines += [f"{r['iteration']:3d} {r['predicted']:10.2e} {r['model_error_defect']:11.2e} "
                  f"{r['model_error_info']:10.2e} {r['rho']:8.3f} {r['eta']:9.2e} {'on' if r['tr_active'] else '':>3} "
                  f"{r['max_defect']:8.1e}" for r in h]
        lines.append(f"printed method (L1 exact penalty, linear MI model of Eq. 44), alpha_h = {self.alpha:g}, from the "
                     f"ballistic DRO ({self.seconds:.0f} s for {len(self.runs) + 1} runs); best of sweeps: cost "
                     f"{best_cost:.6f}")
        lines += [f"  gamma {r['gamma']:7.0e}, {r['model']:>9} MI model, limit {r['max_iter']:3d}: {r['outcome']}; best "
                  f"accepted cost {r['best']:.6f}; last eta {r['eta']:.1e}" for r in self.runs + [self.hybrid]]
        return "\n".join(lines)


def _penalty_problem(case: Case1Sweep, alpha: float) -> tuple:
    """What one exact-penalty run needs, picklable (it may run in another process)."""
    sc = case.scenario
    return (sc.system, case.t, case.x_ball, case.u_ball, case.u_max, sc.observer_xf, case.info, case.k_ws, alpha)


def _penalty_task(problem: tuple, task: tuple) -> dict:
    """One exact-penalty run of :func:`penalty_study`: ``task = (gamma, max_iter, model)``."""
    system, t, x_ball, u_ball, u_max, x_final, info, k_ws, alpha = problem
    gamma, max_iter, model = task
    st = scvx.SCvxSettings(method="penalty", information_model=model, defect_weight=gamma, max_iter=max_iter)
    try:
        r = scvx.solve_scvx(system, t, x_ball, u_ball, u_max, x_final=x_final, info=info, info_node=k_ws, alpha=alpha,
                            settings=st)
        hist, outcome, ok = r.history, f"converged in {r.iterations} iterations (largest defect {r.max_defect:.1e})", True
    except scvx.SCvxError as exc:
        hist, outcome, ok = exc.history, exc.reason, False
    acc = [h["new_cost"] for h in hist if h["accepted"]]
    return dict(gamma=gamma, max_iter=max_iter, model=model, converged=ok, outcome=outcome, history=hist,
                best=min(acc) if acc else np.nan, eta=hist[-1]["eta"] if hist else np.nan)


def penalty_study(case: Case1Sweep, gammas, n_iter: int, n_iter_long: int, *, alpha: float = 5e-3,
                  executor=None, cold=None) -> PenaltyStudy:
    """Our solver cold from the ballistic DRO, and the printed exact-penalty SCvx over penalty weights ``gammas``
    (``n_iter`` iterations each), at gamma = 1e3 with ``n_iter_long`` iterations, and the hybrid (exact penalty,
    quadratic MI model) at gamma = 1e3 (notebook 05, section 4).

    The exact-penalty runs are independent: with an ``executor`` (``submit``, e.g. from
    :func:`cislunar.utils.executors.open_executor`) they run side by side through
    :func:`cislunar.utils.montecarlo.map_tasks`, the cold run of our solver here meanwhile; results do not depend
    on it.  ``cold``, an SCvxResult of ``case.solver(alpha, case.x_ball, case.u_ball)`` already at hand (e.g. the
    multi-start's ballistic start at ``alpha``, :func:`global_search.multi_start`), is used instead of solving it
    again (SCvx is deterministic: the same plan, bit for bit).
    """
    validation.instance(case, "case", Case1Sweep)
    n_iter = validation.integer(n_iter, "n_iter", minimum=1)
    n_iter_long = validation.integer(n_iter_long, "n_iter_long", minimum=1)
    gammas = _checks.vector(gammas, "gammas")
    if np.any(gammas <= 0):
        raise ValueError(f"gammas must be positive penalty weights; got {gammas}")
    alpha = validation.in_range(alpha, "alpha", 0.0, 1.0)
    _checks.executor(executor)
    if cold is not None:
        validation.instance(cold, "cold", scvx.SCvxResult)
        if cold.alpha != alpha or not np.array_equal(cold.t, case.t):
            raise ValueError(f"cold must be solved at alpha = {alpha:g} on the case's node grid; got alpha = "
                             f"{cold.alpha:g} on {np.size(cold.t)} nodes")
    tasks = [(float(g), n_iter, "linear") for g in gammas] + [(1e3, n_iter_long, "linear"), (1e3, n_iter, "quadratic")]
    run = functools.partial(_penalty_task, _penalty_problem(case, alpha))
    if executor is None:
        cold = case.solver(alpha, case.x_ball, case.u_ball) if cold is None else cold
        t0 = time.perf_counter()
        out = montecarlo.map_tasks(run, tasks, progress=False)
    else:
        t0 = time.perf_counter()
        with concurrent.futures.ThreadPoolExecutor(max_workers=1) as waiter:  # a thread only waits on the executor
            fut = waiter.submit(montecarlo.map_tasks, run, tasks, executor=executor, progress=False)
            cold = case.solver(alpha, case.x_ball, case.u_ball) if cold is None else cold
            out = fut.result()
    return PenaltyStudy(alpha, cold, out[:-1], out[-1], n_iter, time.perf_counter() - t0)


# --------------------------------------------------------------------------------------------------------------
# test case 1, section 5: re-flight and mesh check
# --------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Reflight:
    """Single-shooting re-flight of every best plan: terminal miss (km, mm/s), largest ``|u|/a_max`` outside the
    window, largest ``|u|`` inside it (LU/TU^2); one entry per alpha_h."""

    miss_km: tuple
    miss_mm_s: tuple
    max_ratio: tuple
    window_thrust: tuple

    def summary(self, case: Case1Sweep) -> str:
        mps = _mps(case.scenario.system)
        lines = [f"{'alpha_h':>8} {'impulse m/s':>12} {'MI nats':>9} {'iter':>5} {'defect':>8} {'miss km':>9} "
                 f"{'miss mm/s':>9} {'max|u|/umax':>11}"]
        lines += [f"{a:8.4f} {r.impulse * mps:12.4f} {r.information:9.4f} {r.iterations:5d} {r.max_defect:8.1e} "
                  f"{mk:9.1e} {mv:9.1e} {mr:11.4f}"
                  for a, r, mk, mv, mr in zip(case.alphas, case.best, self.miss_km, self.miss_mm_s, self.max_ratio)]
        lines.append(f"largest thrust inside the window: {max(self.window_thrust):.1e} LU/TU^2")
        return "\n".join(lines)


def reflight(case: Case1Sweep) -> Reflight:
    """Fly every best plan's FOH control from x_S(t0) through the nonlinear CR3BP and check its bounds."""
    validation.instance(case, "case", Case1Sweep)
    sc, em = case.scenario, case.scenario.system
    w = case.in_window
    miss_km, miss_v, ratio, win = [], [], [], []
    for r in case.best:
        xs = D.propagate_foh(em, sc.observer_x0, case.t, r.u)
        miss_km.append(float(np.linalg.norm(xs[-1, :3] - sc.observer_xf[:3]) * em.length_unit_km))
        miss_v.append(float(np.linalg.norm(xs[-1, 3:] - sc.observer_xf[3:]) * em.velocity_unit_km_s * 1e6))
        un = np.linalg.norm(r.u, axis=1)
        ratio.append(float(np.max(un[~w] / case.u_max[~w])))
        win.append(float(np.max(un[w])))
    return Reflight(tuple(miss_km), tuple(miss_v), tuple(ratio), tuple(win))


@dataclass(frozen=True)
class MeshCheck:
    """One alpha_h solved on two Sundman grids: impulse (m/s), MI (nats) and observer terminal RMS (km) on each."""

    alpha: float
    n_nodes: tuple
    impulse_mps: tuple
    information: tuple
    rms_km: tuple

    @property
    def impulse_change(self) -> float:
        return abs(self.impulse_mps[1] - self.impulse_mps[0]) / self.impulse_mps[0]

    @property
    def rms_change(self) -> float:
        return abs(self.rms_km[1] / self.rms_km[0] - 1)

    def summary(self) -> str:
        return (f"alpha_h = {self.alpha:g} on {self.n_nodes[0]} nodes: {self.impulse_mps[0]:.2f} m/s, I = "
                f"{self.information[0]:.3f} nats, observer RMS {self.rms_km[0]:.2f} km; on {self.n_nodes[1]} nodes: "
                f"{self.impulse_mps[1]:.2f} m/s, I = {self.information[1]:.3f} nats, RMS {self.rms_km[1]:.2f} km "
                f"(impulse change {100 * self.impulse_change:.1f} %)")


def mesh_check(case: Case1Sweep, n_alt: int, alpha: float, *, sigma: float = 1.0) -> MeshCheck:
    """Solve ``alpha`` again on an ``n_alt``-node Sundman grid, warm-started from the sweep's solution
    interpolated onto it, and compare."""
    validation.instance(case, "case", Case1Sweep)
    n_alt = validation.integer(n_alt, "n_alt", minimum=4)
    if validation.real(alpha, "alpha") not in case.alphas:
        raise ValueError(f"alpha must be one of the sweep's weights {case.alphas}; got {alpha!r}")
    sigma = validation.real(sigma, "sigma")
    sc, i = case.scenario, case.index(alpha)
    b = case.best[i]
    t_alt, k_alt, _ = sc.node_times(n_alt, sigma)
    x_alt = np.stack([np.interp(t_alt, case.t, b.x[:, j]) for j in range(6)], axis=1)
    u_alt = np.stack([np.interp(t_alt, case.t, b.u[:, j]) for j in range(3)], axis=1)
    solver = wj.ScenarioSolver(sc, t_alt, k_alt, information=case.info, settings=case.solver.settings)
    m = solver(alpha, x_alt, u_alt)
    rms = [wj.evaluate_crlb(sc, r.x[k]).terminal_rms_km[0] for r, k in ((b, case.k_ws), (m, k_alt))]
    mps = _mps(sc.system)
    return MeshCheck(alpha, (case.t.size, t_alt.size), (b.impulse * mps, m.impulse * mps),
                     (b.information, m.information), tuple(float(v) for v in rms))


def dense_flight(case: Case1Sweep, res, n: int = 600):
    """Dense re-flight of a plan (FOH control, linear between nodes): ``(t, x, u)`` on ``n`` points plus nodes."""
    validation.instance(case, "case", Case1Sweep)
    _checks.plan(res, "res", n=case.t.size)
    n = validation.integer(n, "n", minimum=2)
    sc = case.scenario
    td = np.union1d(case.t, np.linspace(0.0, case.t[-1], n))
    ud = np.stack([np.interp(td, case.t, res.u[:, i]) for i in range(3)], axis=1)
    return td, D.propagate_foh(sc.system, sc.observer_x0, td, ud), ud


def departures_km(case: Case1Sweep, n: int = 400) -> tuple:
    """Per alpha_h: ``(t, relative position to the reference DRO (k, 3) in km)``, and the largest distance (km)."""
    validation.instance(case, "case", Case1Sweep)
    n = validation.integer(n, "n", minimum=2)
    sc = case.scenario
    rel, dep = [], []
    for r in case.best:
        td, xd, _ = dense_flight(case, r, n)
        d = (xd[:, :3] - propagate(sc.system, sc.observer_x0, td).x[:, :3]) * sc.system.length_unit_km
        rel.append(d)
        dep.append(float(np.max(np.linalg.norm(d / 1e3, axis=1))) * 1e3)
    return rel, dep


# --------------------------------------------------------------------------------------------------------------
# test case 1, sections 7-8: CRLB, process-noise readings, equal impulse
# --------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class CrlbStudy:
    """The CRLB of every best plan (process noise along the trajectory), and of alpha_h = 0 and the largest under
    the literal unit fix of Table 3 (1e-11 km^2/s^3).

    Attributes
    ----------
    crlb : list of CRLBResult
    term_obs, term_tgt, mi_eval : ndarray
        Terminal position RMS (km) of observer and target; MI with Q along each trajectory (nats).
    q_literal : float
        1e-11 km^2/s^3 in LU^2/TU^3.
    literal : list of CRLBResult
        For alpha_h = 0 and the largest.
    """

    crlb: list
    term_obs: np.ndarray
    term_tgt: np.ndarray
    mi_eval: np.ndarray
    q_literal: float
    literal: list

    @property
    def literal_growth(self) -> list:
        """Window end over the 2nd measurement, observer RMS, literal Q (the Fig. 4 test)."""
        return [float(c.rms_km[0, -1] / c.rms_km[0, 1]) for c in self.literal]

    @property
    def bounded(self) -> bool:
        return bool(np.all(np.array([c.rms_km[:, -1] <= c.rms_km[:, 1] for c in self.crlb])))

    @property
    def transient(self) -> bool:
        return bool(np.all(np.array([c.rms_km[:, 1] > c.rms_km[:, 0] for c in self.crlb])))

    def spearman(self, mi) -> tuple:
        """Spearman rank correlation of ``mi`` with the terminal RMS of observer and target."""
        return (float(spearmanr(mi, self.term_obs).statistic), float(spearmanr(mi, self.term_tgt).statistic))


def crlb_study(case: Case1Sweep) -> CrlbStudy:
    """CRLB of every plan of the sweep, and the literal process-noise reading for the extreme weights."""
    validation.instance(case, "case", Case1Sweep)
    sc = case.scenario
    crlb = [wj.evaluate_crlb(sc, r.x[case.k_ws]) for r in case.best]
    q_lit = cov.psd_to_nondimensional(1e-11, sc.system)
    lit = [wj.evaluate_crlb(sc, case.best[i].x[case.k_ws], q=q_lit) for i in (0, len(case.alphas) - 1)]
    return CrlbStudy(crlb, np.array([c.terminal_rms_km[0] for c in crlb]),
                     np.array([c.terminal_rms_km[1] for c in crlb]), np.array([c.mutual_information for c in crlb]),
                     q_lit, lit)


@dataclass(frozen=True)
class BudgetRow:
    """The most informative plan at a prescribed impulse: budget, alpha_h, spent impulse (m/s), terminal RMS of
    observer and target (km), MI (nats), the log-interpolated RMS of the sweep at the spent impulse (km), solves."""

    budget: float
    alpha: float
    impulse: float
    rms_obs: float
    rms_tgt: float
    mi: float
    interp: float
    solves: int


def budget_study(case: Case1Sweep, term_obs, extras_mps, *, rtol: float = 0.02) -> tuple:
    """Solve for the alpha_h whose optimum spends the baseline's impulse plus each of ``extras_mps`` (m/s).

    Returns ``(rows, messages)``: a :class:`BudgetRow` per budget reached, and one line per budget (reached or
    not)."""
    validation.instance(case, "case", Case1Sweep)
    term_obs = _checks.vector(term_obs, "term_obs", n=len(case.alphas))
    if np.any(term_obs <= 0):
        raise ValueError("term_obs must be positive terminal RMS values (km)")
    extras_mps = _checks.vector(extras_mps, "extras_mps")
    rtol = validation.in_range(rtol, "rtol", 0.0, 1.0, closed=False)
    sc, mps = case.scenario, _mps(case.scenario.system)
    imp = case.impulse_mps
    rows, msgs = [], []
    for extra in extras_mps:
        b = imp[0] + extra
        j = int(np.searchsorted(imp, b))
        if j >= len(case.alphas):
            msgs.append(f"budget {b:.2f} m/s lies beyond the grid's largest impulse; not solved")
            continue
        try:
            hit = wj.solve_for_impulse(case.solver, b / mps, (case.alphas[j - 1], case.best[j - 1]),
                                       (case.alphas[j], case.best[j]), rtol=rtol)
        except wj.ImpulseBudgetError as exc:
            msgs.append(f"budget {b:.2f} m/s not reached: {exc.reason}")
            continue
        c = wj.evaluate_crlb(sc, hit.result.x[case.k_ws])
        interp = float(np.exp(np.interp(hit.result.impulse * mps, imp, np.log(term_obs))))  # log-linear
        rows.append(BudgetRow(b, hit.alpha, hit.result.impulse * mps, c.terminal_rms_km[0], c.terminal_rms_km[1],
                              hit.result.information, interp, len(hit.solves)))
        msgs.append(f"budget {b:6.2f} m/s (baseline + {extra:g}): alpha_h = {hit.alpha:.3e} spends "
                    f"{hit.result.impulse * mps:.2f} m/s ({len(hit.solves)} solves); terminal RMS observer "
                    f"{c.terminal_rms_km[0]:.2f} km, target {c.terminal_rms_km[1]:.2f} km = "
                    f"{c.terminal_rms_km[0] / term_obs[0]:.2f} x baseline (log-interpolation on the grid said "
                    f"{interp:.2f} km at that impulse: {c.terminal_rms_km[0] / interp:.2f} x)")
    return rows, msgs


# ==============================================================================================================
# test case 2 (notebook 06)
# ==============================================================================================================
@dataclass(frozen=True)
class GradientCheck:
    """The MI of the window at a window-start state, its reverse-mode gradient against fourth-order central
    differences, and its curvature out of the plane.

    Attributes
    ----------
    value, value_order1 : float
        MI (nats) from the order-0 and order-1 calls.
    gradient, gradient_fd : ndarray (6,)
        nats/LU, nats/(LU/TU).
    relative_error : float
        Largest difference over the largest central-difference component.
    hessian : ndarray (6, 6)
    mi_vz_up, mi_vz_down : float
        MI change (nats) for vz = +1 m/s and -1 m/s.
    """

    value: float
    value_order1: float
    gradient: np.ndarray
    gradient_fd: np.ndarray
    relative_error: float
    hessian: np.ndarray
    mi_vz_up: float
    mi_vz_down: float


def gradient_check(info, x, system, *, h: float = 2e-7) -> GradientCheck:
    """Check ``info``'s gradient at ``x`` by fourth-order central differences (step ``h``) and probe the MI's
    z-curvature (1 m/s in vz either way)."""
    validation.callable_(info, "info")
    x = validation.as_array(x, "x", shape=(6,))
    check_system(system)
    h = validation.positive(h, "h")
    i0 = info(x)
    i1, g = info(x, 1)
    g_fd = np.array([(8 * (info(x + h * e) - info(x - h * e)) - (info(x + 2 * h * e) - info(x - 2 * h * e)))
                     / (12 * h) for e in np.eye(6)])
    err = float(np.max(np.abs(g - g_fd)) / np.max(np.abs(g_fd)))
    H = info.hessian(x)
    dz = np.zeros(6)
    dz[5] = 1e-3 / system.velocity_unit_km_s  # 1 m/s in vz
    return GradientCheck(i0, i1, g, g_fd, err, H, info(x + dz) - i0, info(x - dz) - i0)


@dataclass(frozen=True)
class KeepOutScan:
    """MI of the window when the observer passes target 1 at ``d_km`` at the middle measurement (Newton on the
    STM); ``gain`` is the MI change against the ballistic window start (nats)."""

    d_km: np.ndarray
    mi: np.ndarray
    mi_ballistic: float

    @property
    def gain(self) -> np.ndarray:
        return self.mi - self.mi_ballistic

    def gain_at(self, d_km: float) -> float:
        """Log-interpolated MI gain at a pass distance (km)."""
        return float(np.interp(np.log(d_km), np.log(self.d_km), self.mi) - self.mi_ballistic)


def _observer_passing_at(system, t2, r_tgt, d_km, x0, iterations=6):
    x = x0.copy()
    r_now = propagate(system, x0, t2).x[-1, :3]
    goal = r_tgt + system.km_to_lu(d_km) * (r_now - r_tgt) / np.linalg.norm(r_now - r_tgt)
    for _ in range(iterations):
        tr = propagate_stm(system, x, t2)
        x[:3] += np.linalg.solve(tr.stm[-1][:3, :3], goal - tr.x[-1, :3])
    return x


def keep_out_scan(sc: wj.Scenario, info, x_ws, n_points: int, *, d_range_km=(1e-6, 3000.0)) -> KeepOutScan:
    """Scan the closest approach to target 1 at the middle measurement over ``n_points`` log-spaced distances."""
    validation.instance(sc, "sc", wj.Scenario)
    validation.callable_(info, "info")
    x_ws = validation.as_state(x_ws, "x_ws", batch=False)
    n_points = validation.integer(n_points, "n_points", minimum=2)
    d_range_km = validation.as_array(d_range_km, "d_range_km", shape=(2,))
    if not 0 < d_range_km[0] < d_range_km[1]:
        raise ValueError(f"d_range_km must be (closest, farthest) with 0 < closest < farthest; got {d_range_km}")
    em, tm = sc.system, sc.measurement_times
    t2 = tm[[0, tm.size // 2]]
    r_tgt = propagate(em, info.targets_x0[0], t2).x[-1, :3]
    d = np.geomspace(d_range_km[0], d_range_km[1], n_points)
    mi = np.array([info(_observer_passing_at(em, t2, r_tgt, d_, x_ws)) for d_ in d])
    return KeepOutScan(d, mi, float(info(x_ws)))


@dataclass(frozen=True)
class PlanRow:
    """One converged plan of test case 2 and its figures of merit (impulse m/s, MI nats, terminal miss km,
    closest approach to a target at a measurement km, largest ``|z|`` km, largest ``|u|/a_max``, largest ``|u|`` in the
    window LU/TU^2)."""

    alpha: float
    res: object
    source: str
    crlb: object
    dv: float
    mi: float
    miss_km: float
    min_range_km: float
    z_max_km: float
    u_ratio: float
    u_window: float

    def __getitem__(self, key):  # rows read like the dicts they replace
        return getattr(self, key)


def plan_row(sc: wj.Scenario, solver, k_ws: int, k_we: int, alpha: float, res, source: str = "") -> PlanRow:
    """Figures of merit of one converged plan on ``solver``'s grid."""
    validation.instance(sc, "sc", wj.Scenario)
    validation.instance(solver, "solver", wj.ScenarioSolver)
    k_ws, k_we = _node(k_ws, "k_ws", solver.t.size), _node(k_we, "k_we", solver.t.size)
    alpha = validation.real(alpha, "alpha")
    _checks.plan(res, "res", n=solver.t.size)
    validation.instance(source, "source", str)
    em = sc.system
    ko = sc.keep_out(k_ws)
    u_norm = np.linalg.norm(res.u, axis=1)
    on = solver.u_max > 0
    return PlanRow(alpha, res, source, wj.evaluate_crlb(sc, res.x[k_ws]), _dv(res, em), res.information,
                   wj.terminal_miss_km(sc, solver.t, res.u), float(ko.ranges(res.x[k_ws]).min() * em.length_unit_km),
                   float(np.max(np.abs(res.x[:, 2])) * em.length_unit_km), float(np.max(u_norm[on] / solver.u_max[on])),
                   float(np.max(u_norm[k_ws:k_we + 1])))


@dataclass(frozen=True)
class Case2Sweep:
    """Test case 2 planned over the alpha_h grid, swept both ways, one :class:`PlanRow` per converged weight.

    Attributes
    ----------
    alphas : tuple
    rows : list of PlanRow or None
    sweep : SweepResult
    seconds : float
    """

    scenario: wj.Scenario
    alphas: tuple
    t: np.ndarray
    k_ws: int
    k_we: int
    solver: object
    sweep: object
    rows: list
    seconds: float

    @property
    def ok(self) -> list:
        return [r for r in self.rows if r is not None]

    @property
    def by_alpha(self) -> dict:
        return {r.alpha: r for r in self.ok}

    @property
    def failed(self) -> list:
        return [a for a in self.sweep.attempts if not a["converged"]]

    def binds(self, r) -> bool:
        """The keep-out is active (closest approach within 0.1 % of it)."""
        return bool(r.min_range_km <= self.scenario.keep_out_km * (1 + 1e-3))

    @property
    def n_bind(self) -> int:
        return sum(self.binds(r) for r in self.ok if r.alpha > 0)

    @property
    def mi_q_rel(self) -> float:
        """Largest relative difference of the MI with Q held (planning) and Q along each plan (CRLB)."""
        return max(abs(r.crlb.mutual_information - r.mi) / r.mi for r in self.ok)

    def pick(self, a: float) -> tuple:
        """``(row, note)``: the row of ``a`` or of the converged weight nearest to it, with a note if replaced."""
        if a in self.by_alpha:
            return self.by_alpha[a], ""
        near = min(self.ok, key=lambda r: abs(np.log((r.alpha + 1e-6) / (a + 1e-6))))
        return near, f"(alpha {a:g} did not converge in either sweep; showing alpha {near.alpha:g} instead)"

    def summary(self) -> str:
        f = self.failed
        lines = [f"sweeps: {len(self.sweep.attempts)} runs in {self.seconds:.0f} s, {len(f)} hit the iteration limit ("
                 + (", ".join(f"{a['alpha']:g} {a['direction']} {a['start']}" for a in f) or "none")
                 + "; a failed warm start is retried from the ballistic guess)",
                 f"{'alpha':>7} {'sweep':>5} {'dV [m/s]':>9} {'MI [nats]':>10} {'RMS obs':>8} {'RMS tgt':>8} {'it':>4} "
                 f"{'defect':>8} {'miss [km]':>10} {'min range':>10} {'max|z| km':>10} {'|u|/umax':>9}"]
        lines += [f"{r.alpha:>7g} {r.source:>5} {r.dv:>9.3f} {r.mi:>10.3f} {r.crlb.terminal_rms_km[0]:>8.1f} "
                  f"{np.mean(r.crlb.terminal_rms_km[1:]):>8.1f} {r.res.iterations:>4d} {r.res.max_defect:>8.1e} "
                  f"{r.miss_km:>10.2e} {r.min_range_km:>10.1f} {r.z_max_km:>10.0f} {r.u_ratio:>9.3f}" for r in self.ok]
        lines += [f"424 km keep-out active (closest approach within 0.1 % of it) in {self.n_bind} of "
                  f"{sum(r.alpha > 0 for r in self.ok)} plans with alpha_h > 0",
                  "MI with Q held along the ballistic arc (planning) vs Q recomputed along each plan (CRLB): largest "
                  f"relative difference {self.mi_q_rel:.1e}"]
        return "\n".join(lines)


def case2_rows(sc: wj.Scenario, solver, k_ws: int, k_we: int, sweep, seconds: float = float("nan")) -> Case2Sweep:
    """Evaluate every best plan of a test-case-2 sweep (:func:`plan_row`)."""
    validation.instance(sc, "sc", wj.Scenario)
    validation.instance(solver, "solver", wj.ScenarioSolver)
    k_ws, k_we = _node(k_ws, "k_ws", solver.t.size), _node(k_we, "k_we", solver.t.size)
    validation.instance(sweep, "sweep", scvx.SweepResult)
    seconds = validation.real(seconds, "seconds", finite=False)
    rows = [None if res is None else plan_row(sc, solver, k_ws, k_we, a, res, src)
            for a, res, src in zip(sweep.alphas, sweep.best, sweep.source)]
    return Case2Sweep(sc, tuple(float(a) for a in sweep.alphas), solver.t, k_ws, k_we, solver, sweep, rows, seconds)


def departure_km(sc: wj.Scenario, t, res) -> float:
    """Largest distance (km) of a plan's re-flight from the reference DRO over the scenario."""
    validation.instance(sc, "sc", wj.Scenario)
    t = validation.time_grid(t, "t", increasing=True)
    _checks.plan(res, "res", n=t.size)
    tf, xf = wj.fly(sc, t, res.u, refine=4)
    rel = (xf - propagate(sc.system, sc.observer_x0, tf).x)[:, :3] * sc.system.length_unit_km
    return float(np.max(np.linalg.norm(rel, axis=1)))


@dataclass(frozen=True)
class GridDepartures:
    """Largest departure from the reference DRO per converged weight on one node grid, its rank correlation with
    alpha_h, and the Fig. 6 weight's impulse (m/s), MI (nats) and terminal RMS (km) on this grid (or None)."""

    n_nodes: int
    alphas: tuple
    departure_km: tuple
    spearman: float
    at_weight: tuple | None


def grid_departures(sc: wj.Scenario, t, k_ws: int, sweep, weight: float) -> GridDepartures:
    """Departures on one node grid from a sweep's best plans; ``weight``: the alpha_h of the mesh check."""
    validation.instance(sc, "sc", wj.Scenario)
    t = validation.time_grid(t, "t", increasing=True)
    k_ws = _node(k_ws, "k_ws", t.size)
    validation.instance(sweep, "sweep", scvx.SweepResult)
    weight = validation.real(weight, "weight")
    al, dep, at = [], [], None
    for a, res in zip(sweep.alphas, sweep.best):
        if res is None:
            continue
        al.append(float(a))
        dep.append(departure_km(sc, t, res))
        if a == weight:
            at = (_dv(res, sc.system), res.information, wj.evaluate_crlb(sc, res.x[k_ws]).terminal_rms_km[0])
    rho = float(spearmanr(al, dep).statistic) if len(al) > 2 else np.nan
    return GridDepartures(t.size, tuple(al), tuple(dep), rho, at)


_MIRROR = np.diag([1, 1, -1, 1, 1, -1.0])
_MIRROR_U = np.diag([1, 1, -1.0])


@dataclass(frozen=True)
class MirrorPair:
    """Two plans and the mirror of one: z at the window end (km), largest distance between the first and the
    mirror of the second and without mirroring (km)."""

    z_end_km: tuple
    d_mirror_km: float
    d_same_km: float


def mirror_pair(a, b, k_we: int, system) -> MirrorPair:
    """Compare plan ``a`` with plan ``b`` and with ``b``'s mirror image across z = 0."""
    _checks.plan(a, "a", controls=False)
    _checks.plan(b, "b", controls=False, n=np.shape(a.x)[0])
    k_we = _node(k_we, "k_we", np.shape(a.x)[0])
    check_system(system)
    L = system.length_unit_km
    return MirrorPair(tuple(float(x_[k_we, 2] * L) for x_ in (a.x, b.x)),
                      float(np.max(np.linalg.norm((a.x - b.x @ _MIRROR)[:, :3], axis=1)) * L),
                      float(np.max(np.linalg.norm((a.x - b.x)[:, :3], axis=1)) * L))


def mirrored(res) -> tuple:
    """``(x, u)`` of a plan mirrored across z = 0 (z, vz, a_z -> -z, -vz, -a_z)."""
    _checks.plan(res, "res")
    return res.x @ _MIRROR, res.u @ _MIRROR_U


def relative_rms_km(sc: wj.Scenario, x_window_start) -> tuple:
    """Terminal position RMS (km) of each object, of each target relative to the observer, and of the mean
    position of all four (the common part), from the CRLB recursion of Fig. 9."""
    validation.instance(sc, "sc", wj.Scenario)
    x_window_start = validation.as_state(x_window_start, "x_window_start", batch=False)
    em, tm = sc.system, sc.measurement_times
    lin = cov.linearize_augmented(em, x_window_start, sc.targets_at([tm[0]])[:, 0], tm, sc.model, sc.noise,
                                  sc.prior_covariance, q=sc.q)
    P = cov.covariance_analysis(*lin.arrays).posterior[-1]

    def rms(w):
        sel = np.hstack([wi * np.hstack([np.eye(3), np.zeros((3, 3))]) for wi in w])
        return float(np.sqrt(np.trace(sel @ P @ sel.T)) * em.length_unit_km)

    n = sc.n_targets + 1
    return (np.array([rms(np.eye(n)[i]) for i in range(n)]),
            np.array([rms(np.eye(n)[0] - np.eye(n)[i]) for i in range(1, n)]), rms(np.full(n, 1.0 / n)))


@dataclass(frozen=True)
class NoiseReadings:
    """CRLB under each reading of Tables 3/5's process noise: per reading ``(label, q km^2/s^3, test case 1
    terminal RMS km, its peak km, test case 2 ballistic terminal RMS km, test case 2 plan terminal RMS km)``, and
    the test case 1 curves ``(t TU, observer RMS km)``."""

    rows: list
    curves: list

    @property
    def spread(self) -> tuple:
        """Ratio of largest to smallest terminal RMS over the readings below 1e-12 km^2/s^3 (case 1, case 2)."""
        small = [r for r in self.rows if r[1] < 1e-12]
        return (max(r[2] for r in small) / min(r[2] for r in small), max(r[5] for r in small) / min(r[5] for r in small))


def noise_readings(sc2: wj.Scenario, x2_ball_ws, x2_plan_ws, sc1: wj.Scenario) -> NoiseReadings:
    """CRLB of test case 1's ballistic observer and of two test-case-2 window starts under every reading."""
    validation.instance(sc2, "sc2", wj.Scenario)
    x2_ball_ws = validation.as_state(x2_ball_ws, "x2_ball_ws", batch=False)
    x2_plan_ws = validation.as_state(x2_plan_ws, "x2_plan_ws", batch=False)
    validation.instance(sc1, "sc1", wj.Scenario)
    em = sc1.system
    x1_ws = propagate(em, sc1.observer_x0, [0.0, sc1.window[0]]).x[-1]
    rows, curves = [], []
    for label, q_km in wj.PROCESS_NOISE_READINGS_KM2_S3.items():
        q_nd = cov.psd_to_nondimensional(q_km, em)
        c1 = wj.evaluate_crlb(sc1, x1_ws, q=q_nd)
        curves.append((c1.t, c1.rms_km[0]))
        rows.append((label, q_km, c1.terminal_rms_km[0], float(np.max(c1.rms_km[0])),
                     wj.evaluate_crlb(sc2, x2_ball_ws, q=q_nd).terminal_rms_km[0],
                     wj.evaluate_crlb(sc2, x2_plan_ws, q=q_nd).terminal_rms_km[0]))
    return NoiseReadings(rows, curves)


@dataclass(frozen=True)
class Front:
    """The Pareto front of the converged plans: impulse (m/s), terminal RMS of observer and targets (km), MI
    (nats), rank correlations and the dominated plans ``(alpha, index, alpha of a cheaper plan no worse, index)``."""

    alphas: tuple
    dv: np.ndarray
    rms_obs: np.ndarray
    rms_tgt: np.ndarray
    mi: np.ndarray
    rank_obs: float
    rank_tgt: float
    mono_dv: bool
    mono_mi: bool
    dominated: list


def front(ok) -> Front:
    """Aggregate converged plans (:class:`PlanRow`, increasing alpha_h) into the front of Fig. 10."""
    ok = validation.sequence_of(ok, "ok", PlanRow, "PlanRow")
    dvs = np.array([r.dv for r in ok])
    rms_obs = np.array([r.crlb.terminal_rms_km[0] for r in ok])
    rms_tgt = np.array([r.crlb.terminal_rms_km[1:] for r in ok])
    mis = np.array([r.mi for r in ok])
    dominated = []
    for i in range(len(ok)):
        j = next((j for j in range(len(ok)) if dvs[j] < dvs[i] and rms_obs[j] <= rms_obs[i]), None)
        if j is not None:
            dominated.append((ok[i].alpha, i, ok[j].alpha, j))
    return Front(tuple(r.alpha for r in ok), dvs, rms_obs, rms_tgt, mis, float(spearmanr(mis, rms_obs).statistic),
                 float(spearmanr(mis, rms_tgt.mean(axis=1)).statistic), bool(np.all(np.diff(dvs) >= -1e-9 * np.max(dvs))),
                 bool(np.all(np.diff(mis) >= -1e-9 * np.max(mis))), dominated)


class RecordingInformation:
    """An information model that records the window-start state of every gradient call (= every SCvx
    reference)."""

    def __init__(self, inner):
        self.inner, self.refs = inner, []

    def __call__(self, x, order=0):
        if order >= 1:
            self.refs.append(np.array(x, dtype=float))
        return self.inner(x, order)

    def __getattr__(self, name):
        return getattr(self.inner, name)


@dataclass(frozen=True)
class FreeRun:
    """SCvx without a keep-out: the result or the error, and the closest approach (km) to a target at a
    measurement of each successive reference."""

    outcome: object
    ref_range_km: np.ndarray

    @property
    def failed(self) -> bool:
        return isinstance(self.outcome, scvx.SCvxError)

    @property
    def best_cost(self) -> float:
        """Best accepted cost of a failed run (NaN if it converged or accepted nothing)."""
        if not self.failed:
            return np.nan
        acc = [h["new_cost"] for h in self.outcome.history if h.get("accepted")]
        return min(acc) if acc else np.nan


def free_run(sc: wj.Scenario, t, k_ws: int, info, alpha: float, x_guess, u_guess, max_iter: int) -> FreeRun:
    """Solve ``alpha`` without any keep-out, recording the closest approach of every reference."""
    validation.instance(sc, "sc", wj.Scenario)
    t = validation.time_grid(t, "t", increasing=True)
    k_ws = validation.integer(k_ws, "k_ws", minimum=1, maximum=t.size - 2)
    validation.callable_(info, "info")
    alpha = validation.in_range(alpha, "alpha", 0.0, 1.0)
    x_guess = validation.as_array(x_guess, "x_guess", shape=(t.size, 6))
    u_guess = validation.as_array(u_guess, "u_guess", shape=(t.size, 3))
    max_iter = validation.integer(max_iter, "max_iter", minimum=1)
    rec = RecordingInformation(info)
    solver = wj.ScenarioSolver(sc, t, k_ws, information=rec, keep_out=False,
                               settings=scvx.SCvxSettings(max_iter=max_iter))
    try:
        out = solver(alpha, x_guess, u_guess)
    except scvx.SCvxError as exc:
        out = exc
    ko = sc.keep_out(k_ws)
    return FreeRun(out, np.array([ko.ranges(x_).min() for x_ in rec.refs]) * sc.system.length_unit_km)


@dataclass(frozen=True)
class RadiusRow:
    """A plan at the Fig. 6 weight under one keep-out radius ``d`` (km): start, impulse (m/s), MI (nats),
    terminal RMS (km), closest approach (km), node states, largest ``|z|`` (km), keep-out active, largest node
    distance to the adopted plan (km)."""

    d: float
    src: str
    dv: float
    mi: float
    rms: float
    closest: float
    x: np.ndarray
    z: float
    binds: bool
    apart: float

    def __getitem__(self, key):
        return getattr(self, key)


def radius_row(sc: wj.Scenario, k_ws: int, d: float, src: str, res, reference_x) -> RadiusRow:
    """Figures of merit of the plan solved with keep-out radius ``d`` km."""
    validation.instance(sc, "sc", wj.Scenario)
    _checks.plan(res, "res")
    k_ws = _node(k_ws, "k_ws", np.shape(res.x)[0])
    d = validation.positive(d, "d")
    validation.instance(src, "src", str)
    reference_x = validation.as_array(reference_x, "reference_x", shape=np.shape(res.x))
    em = sc.system
    closest = float(sc.keep_out(k_ws).ranges(res.x[k_ws]).min() * em.length_unit_km)
    return RadiusRow(d, src, _dv(res, em), res.information, wj.evaluate_crlb(sc, res.x[k_ws]).terminal_rms_km[0],
                     closest, res.x, float(np.max(np.abs(res.x[:, 2])) * em.length_unit_km),
                     bool(closest <= d * (1 + 1e-3)),
                     float(np.max(np.linalg.norm((res.x - reference_x)[:, :3], axis=1)) * em.length_unit_km))


def alt_grid_sweep(sc: wj.Scenario, info, n_nodes: int, alphas, settings, *, sigma: float = 1.0, executor=None,
                   directions=("up", "down")):
    """The two-way sweep of test case 2 (424 km keep-out) on another Sundman grid: ``(t, k_ws, SweepResult)``;
    with an executor its two chains run side by side; ``directions`` as in
    :func:`~cislunar.papers.wolf_jones.scenarios.sweep_both_ways` (one chain only, e.g. ``("up",)``)."""
    validation.instance(sc, "sc", wj.Scenario)
    validation.callable_(info, "info")
    n_nodes = validation.integer(n_nodes, "n_nodes", minimum=4)
    alphas = _alphas(alphas)
    validation.instance(settings, "settings", scvx.SCvxSettings)
    sigma = validation.real(sigma, "sigma")
    _checks.executor(executor)
    t, k, _ = sc.node_times(n_nodes, sigma)
    solver = wj.ScenarioSolver(sc, t, k, information=info, keep_out=True, settings=settings)
    return t, k, wj.sweep_both_ways(solver, alphas, *sc.ballistic_guess(t), executor=executor,
                                    directions=directions)



class _Deferred:
    """A serial stand-in for a future: the call runs when its result is asked for."""

    def __init__(self, fn, args):
        self._fn, self._args = fn, args

    def result(self):
        return self._fn(*self._args)


def _submit(executor, fn, *args):
    """``executor.submit(fn, *args)``, or a :class:`_Deferred` call when ``executor`` is None (serial)."""
    return _Deferred(fn, args) if executor is None else executor.submit(fn, *args)


def _outcome(future):
    """The result of a queued SCvx run, or its :class:`~cislunar.guidance.scvx.SCvxError`."""
    try:
        return future.result()
    except scvx.SCvxError as exc:
        return exc


@dataclass(frozen=True)
class Case2Runs:
    """The SCvx runs of test case 2 that do not depend on one another (notebook 06, sections 4, 6 and 7).

    Attributes
    ----------
    sweep : SweepResult
        The two-way sweep on the main grid.
    seconds : float
        Wall time until the main sweep was done (s).
    seeded : dict
        ``(alpha, sign) -> SCvxResult or SCvxError`` of the +z/-z seeded runs.
    alt : dict
        ``n_nodes -> (t, k_ws, SweepResult)``: the same two-way sweep on other Sundman grids.
    """

    sweep: object
    seconds: float
    seeded: dict
    alt: dict


def case2_runs(sc: wj.Scenario, solver, alphas, x_guess, u_guess, *, seed_alphas=(), alt_nodes=(),
               sigma: float = 1.0, executor=None, alt_directions=("up", "down")) -> Case2Runs:
    """Queue the independent runs of test case 2 on ``executor`` and collect them.

    The +z/-z seeded runs at ``seed_alphas`` (:meth:`Scenario.seeded_guess`), the two-way sweep of ``solver`` over
    ``alphas`` from ``(x_guess, u_guess)`` (:func:`~cislunar.papers.wolf_jones.scenarios.sweep_both_ways`) and the
    same sweep on each Sundman grid of ``alt_nodes`` nodes (:func:`alt_grid_sweep`, same settings; only the chains
    of ``alt_directions`` there, e.g. ``("up",)`` in a quick run).  With an
    executor (``submit``: a process pool or a Dask client from :func:`cislunar.utils.executors.open_executor`)
    every chain and seeded run is one task, queued in that order; without one they run here, one after the other.
    Every run is deterministic, so the results do not depend on the executor.
    """
    validation.instance(sc, "sc", wj.Scenario)
    validation.instance(solver, "solver", wj.ScenarioSolver)
    alphas = _alphas(alphas)
    x_guess = validation.as_array(x_guess, "x_guess", shape=(solver.t.size, 6))
    u_guess = validation.as_array(u_guess, "u_guess", shape=(solver.t.size, 3))
    seed_alphas = tuple(validation.in_range(a, f"seed_alphas[{i}]", 0.0, 1.0)
                        for i, a in enumerate(_checks.sequence(seed_alphas, "seed_alphas", allow_empty=True)))
    alt_nodes = tuple(validation.integer(n, f"alt_nodes[{i}]", minimum=4)
                      for i, n in enumerate(_checks.sequence(alt_nodes, "alt_nodes", allow_empty=True)))
    sigma = validation.real(sigma, "sigma")
    _checks.executor(executor)
    alt_directions = _checks.directions(alt_directions, "alt_directions")
    seed_jobs = {(a, z): _submit(executor, solver, a, *sc.seeded_guess(solver.t, z))
                 for a in seed_alphas for z in (+1, -1)}
    t0 = time.perf_counter()

    def alt(n):
        return alt_grid_sweep(sc, solver.information, n, alphas, solver.settings, sigma=sigma, executor=executor,
                              directions=alt_directions)

    if executor is None:
        sweep = wj.sweep_both_ways(solver, alphas, x_guess, u_guess)
        seconds = time.perf_counter() - t0
        alt_sweeps = {n: alt(n) for n in alt_nodes}
    else:
        # threads only wait on the executor: each two-way sweep blocks on its two chains
        with concurrent.futures.ThreadPoolExecutor(max_workers=1 + len(alt_nodes)) as waiter:
            main = waiter.submit(wj.sweep_both_ways, solver, alphas, x_guess, u_guess, executor=executor)
            sweep = main.result()
            seconds = time.perf_counter() - t0
            alt_jobs = {n: waiter.submit(alt, n) for n in alt_nodes}
            alt_sweeps = {n: job.result() for n, job in alt_jobs.items()}
    return Case2Runs(sweep, seconds, {key: _outcome(f) for key, f in seed_jobs.items()}, alt_sweeps)


class KeepOutJobs:
    """The keep-out radius and a_max solves of notebook 06, section 11, queued on an executor (a job handle, not a
    result: :meth:`collect` waits for them and returns the frozen :class:`KeepOutStudy`)."""

    def __init__(self, case, row6, radius_jobs: dict, amax_solvers: dict, amax_jobs: dict, radius_start: str):
        self.case, self.row6, self.radius_start = case, row6, radius_start
        self.radius_jobs, self.amax_solvers, self.amax_jobs = radius_jobs, amax_solvers, amax_jobs

    def collect(self, free: FreeRun) -> KeepOutStudy:
        """Wait for the queued solves and compare them, with the run without keep-out ``free``, against ``row6``."""
        return keep_out_study(self.case, self.row6, free, {d: _outcome(f) for d, f in self.radius_jobs.items()},
                              {lab: (self.amax_solvers[lab], _outcome(f)) for lab, f in self.amax_jobs.items()},
                              radius_start=self.radius_start)


def queue_keep_out_runs(case: Case2Sweep, row6, d_min_km, *, warm: bool, x_guess=None, u_guess=None,
                        executor=None) -> KeepOutJobs:
    """Queue, at ``row6``'s weight, one solve per keep-out radius of ``d_min_km`` (km) and one per other reading
    of Table 5's a_max (:data:`~cislunar.papers.wolf_jones.scenarios.A_MAX_READINGS_CASE2_KM_S2`).

    The radius solves start from ``row6``'s plan when ``warm``, else from ``(x_guess, u_guess)`` (the ballistic
    guess); the a_max solves always start from ``row6``'s plan.  Without an executor the solves run when
    :meth:`KeepOutJobs.collect` is called.
    """
    validation.instance(case, "case", Case2Sweep)
    validation.instance(row6, "row6", PlanRow)
    d_min_km = _checks.vector(d_min_km, "d_min_km")
    if np.any(d_min_km <= 0):
        raise ValueError(f"d_min_km must be positive keep-out radii (km); got {d_min_km}")
    validation.boolean(warm, "warm")
    if x_guess is not None:
        x_guess = validation.as_array(x_guess, "x_guess", shape=(case.t.size, 6))
    if u_guess is not None:
        u_guess = validation.as_array(u_guess, "u_guess", shape=(case.t.size, 3))
    _checks.executor(executor)
    sc, t, k_ws, info, settings, a6 = (case.scenario, case.t, case.k_ws, case.solver.information,
                                       case.solver.settings, row6.alpha)
    guess = (row6.res.x, row6.res.u) if warm else (x_guess, u_guess)
    if not warm and (x_guess is None or u_guess is None):
        raise ValueError("x_guess and u_guess are needed for cold radius solves (warm=False)")
    radius_jobs = {float(d): _submit(executor, wj.ScenarioSolver(sc, t, k_ws, information=info, keep_out=True,
                                                                 d_min_km=float(d), settings=settings), a6, *guess)
                   for d in d_min_km}
    amax_solvers = {label: wj.ScenarioSolver(wj.test_case_2(a_max_km_s2=a_km), t, k_ws, information=info,
                                             keep_out=True, settings=settings)
                    for label, a_km in wj.A_MAX_READINGS_CASE2_KM_S2.items() if a_km != wj.A_MAX_CASE2_KM_S2}
    amax_jobs = {label: _submit(executor, s_, a6, row6.res.x, row6.res.u) for label, s_ in amax_solvers.items()}
    return KeepOutJobs(case, row6, radius_jobs, amax_solvers, amax_jobs, "warm" if warm else "cold")


@dataclass(frozen=True)
class MirrorStudy:
    """The z-mirror question of Fig. 7.

    Attributes
    ----------
    pair : MirrorPair or None
        The sweep's optima at the paper's two weights (None when both fall on one converged weight).
    pair_alphas : tuple
    alpha : float
        Weight of the mirrored optimum.
    optimum, twin : SCvxResult
        The sweep's optimum there and its mirror image re-solved.
    twin_dcost, twin_km : float
        Relative cost difference and largest distance (km) of the re-solved mirror from the exact mirror.
    seeded : dict
        ``(alpha, sign) -> SCvxResult or SCvxError`` of the +z/-z seeded runs.
    rows : list of tuple
        Per seeded weight: ``(alpha, z end +seed km, z end -seed km, relative cost difference, distance to the
        mirror km, lower cost, sweep's best cost)``.
    """

    pair: MirrorPair | None
    pair_alphas: tuple
    alpha: float
    optimum: object
    twin: object
    twin_dcost: float
    twin_km: float
    seeded: dict
    rows: list

    @property
    def twin_is_optimum(self) -> bool:
        return bool(self.twin_dcost <= 1e-6 and self.twin_km <= 1.0)

    @property
    def seeds_mirror(self) -> bool:
        return bool(max(m[4] for m in self.rows) <= 1.0 and max(m[3] for m in self.rows) <= 1e-6)

    def curves(self) -> dict:
        """``(alpha, label) -> result`` for the z-mirror figure."""
        c = {(self.alpha, "sweep optimum"): self.optimum, (self.alpha, "its mirror, re-solved"): self.twin}
        c.update({(a, f"{'+' if s > 0 else '-'}z seed"): r for (a, s), r in self.seeded.items()})
        return c

    def summary(self) -> str:
        lines = []
        if self.pair:
            p = self.pair
            lines.append(f"sweep optima: z at the window end: alpha {self.pair_alphas[0]:g}: {p.z_end_km[0]:+.0f} km, "
                         f"alpha {self.pair_alphas[1]:g}: {p.z_end_km[1]:+.0f} km; largest distance between the first "
                         f"and the mirror image of the second {p.d_mirror_km:.0f} km (without mirroring "
                         f"{p.d_same_km:.0f} km)")
        lines.append(f"mirrored optimum of alpha {self.alpha:g}: {self.twin.iterations} iterations, relative cost "
                     f"difference {self.twin_dcost:.1e}, largest distance from the exact mirror {self.twin_km:.3f} km")
        for a in sorted({k[0] for k in self.seeded}):
            p, m = self.seeded[(a, +1)], self.seeded[(a, -1)]
            if isinstance(p, Exception) or isinstance(m, Exception):
                lines.append(f"alpha {a:g}: a seeded run failed ({p if isinstance(p, Exception) else m})")
        lines += [f"alpha {a:g}: z at window end {zp:+.0f} km (+z seed) / {zm:+.0f} km (-z seed); relative cost "
                  f"difference {dc:.1e}; largest distance between one and the mirror of the other {mis:.2f} km; cost "
                  f"{c:.6f} vs best of sweeps {b:.6f}" for a, zp, zm, dc, mis, c, b in self.rows]
        if self.rows:
            lines.append("seeded optimum costlier than the sweep's (a different, worse local optimum) at every seeded "
                         f"weight: {all(m[5] > m[6] for m in self.rows)}")
        return "\n".join(lines)


def mirror_study(case: Case2Sweep, pair_rows, mirror_row, seeded: dict) -> MirrorStudy:
    """Compare the sweep's optima at the paper's pair of weights, re-solve the mirror of ``mirror_row``'s optimum
    and compare the +z/-z seeded solutions ``seeded`` (``(alpha, sign) -> result or SCvxError``)."""
    validation.instance(case, "case", Case2Sweep)
    pair_rows = validation.sequence_of(pair_rows, "pair_rows", PlanRow, "PlanRow")
    if len(pair_rows) != 2:
        raise ValueError(f"pair_rows must hold two PlanRows; got {len(pair_rows)}")
    validation.instance(mirror_row, "mirror_row", PlanRow)
    validation.instance(seeded, "seeded", dict, "a dict {(alpha, sign): result or SCvxError}")
    em, k_we = case.scenario.system, case.k_we
    a, b = pair_rows
    pair = mirror_pair(a.res, b.res, k_we, em) if a.alpha != b.alpha else None
    opt = mirror_row.res
    twin = case.solver(mirror_row.alpha, *mirrored(opt))
    rows = []
    for al in sorted({k[0] for k in seeded}):
        p, m = seeded[(al, +1)], seeded[(al, -1)]
        if isinstance(p, Exception) or isinstance(m, Exception):
            continue
        pm = mirror_pair(p, m, k_we, em)
        best_sweep = case.by_alpha[al].res.cost if al in case.by_alpha else np.nan  # NaN: no sweep converged there
        rows.append((al, *pm.z_end_km, abs(p.cost - m.cost) / abs(p.cost), pm.d_mirror_km, min(p.cost, m.cost),
                     best_sweep))
    return MirrorStudy(pair, (a.alpha, b.alpha), mirror_row.alpha, opt, twin,
                       abs(twin.cost - opt.cost) / abs(opt.cost), mirror_pair(twin, opt, k_we, em).d_mirror_km,
                       seeded, rows)


def case2_budget(case: Case2Sweep, extra_mps: float, *, rtol: float = 0.02) -> tuple:
    """The most informative plan at the baseline's impulse plus ``extra_mps`` (m/s): ``(row or None, message)``;
    the row holds ``budget, alpha, dv, rms`` and the log-interpolated RMS of the sweep at the spent impulse."""
    validation.instance(case, "case", Case2Sweep)
    extra_mps = validation.real(extra_mps, "extra_mps")
    rtol = validation.in_range(rtol, "rtol", 0.0, 1.0, closed=False)
    ok, base, sc = case.ok, case.by_alpha.get(0.0), case.scenario
    if base is None:
        return None, "no converged baseline"
    b = base.dv + extra_mps
    j = next((i for i, r in enumerate(ok) if r.dv >= b), None)
    if j is None or j == 0:
        return None, f"budget {b:.2f} m/s outside the swept front; not solved"
    try:
        hit = wj.solve_for_impulse(case.solver, b / (sc.system.velocity_unit_km_s * 1e3), (ok[j - 1].alpha, ok[j - 1].res),
                                   (ok[j].alpha, ok[j].res), rtol=rtol)
    except (wj.ImpulseBudgetError, scvx.SCvxError) as exc:
        return None, f"budget {b:.2f} m/s not reached: {exc}"
    dv = _dv(hit.result, sc.system)
    rms = wj.evaluate_crlb(sc, hit.result.x[case.k_ws]).terminal_rms_km[0]
    interp = float(np.exp(np.interp(dv, [r.dv for r in ok], np.log([r.crlb.terminal_rms_km[0] for r in ok]))))
    row = dict(budget=b, alpha=hit.alpha, dv=dv, rms=rms, interp=interp)
    rms0 = base.crlb.terminal_rms_km[0]
    return row, (f"budget {b:.2f} m/s (baseline + {extra_mps:g}): alpha_h = {hit.alpha:.3e} spends {dv:.2f} m/s "
                 f"({len(hit.solves)} solves); observer RMS {rms:.1f} km vs {rms0:.0f} km at the baseline's "
                 f"{base.dv:.2f} m/s (log-interpolation on the grid at the spent impulse said {interp:.1f} km)")


def radius_summary(radius_rows, row6, d_min_km, keep_out_km: float, alpha: float, same_plan_km: float) -> str:
    """The keep-out radius table at the Fig. 6 weight, and what each radius below the adopted one found."""
    radius_rows = validation.sequence_of(radius_rows, "radius_rows", RadiusRow, "RadiusRow")
    validation.instance(row6, "row6", PlanRow)
    d_min_km = _checks.vector(d_min_km, "d_min_km")
    keep_out_km = validation.positive(keep_out_km, "keep_out_km")
    alpha = validation.real(alpha, "alpha")
    same_plan_km = validation.positive(same_plan_km, "same_plan_km")
    lines = [f"alpha_h = {alpha:g}: {'keep-out [km]':>13} {'start':>6} {'dV [m/s]':>9} {'MI [nats]':>10} "
             f"{'RMS obs [km]':>13} {'closest [km]':>13} {'binds':>6} {'max|z| [km]':>11}"]
    lines += [f"{'':>14}{r.d:>13.0f} {r.src:>6} {r.dv:>9.2f} {r.mi:>10.2f} {r.rms:>13.1f} {r.closest:>13.1f} "
              f"{str(r.binds):>6} {r.z:>11.0f}" for r in radius_rows]
    for d in [d for d in d_min_km if d < keep_out_km]:
        r = next((r_ for r_ in radius_rows if r_.d == d), None)
        if r is None:
            lines.append(f"keep-out {d:g} km (below the adopted one): solve failed, question open at this radius")
            continue
        lines.append(
            f"keep-out {d:g} km (below the adopted one): {'active' if r.binds else 'inactive'} at its optimum, impulse "
            f"{r.dv:.2f} vs {row6.dv:.2f} m/s, closest approach {r.closest:.0f} vs {row6.min_range_km:.0f} km, max|z| "
            f"{r.z:.0f} vs {row6.z_max_km:.0f} km, RMS {r.rms:.1f} vs {row6.crlb.terminal_rms_km[0]:.1f} km; the two "
            f"trajectories lie up to {r.apart:.0f} km apart: " + (
                f"the 424 km plan (within {same_plan_km:g} km)" if r.apart <= same_plan_km else
                f"a neighbouring local optimum (more than {same_plan_km:g} km apart)"))
    return "\n".join(lines)


def dominated_note(case: Case2Sweep, dominated, row6, radius_rows, amax_rows) -> str:
    """Why plans of the front are dominated: their closest approach, and re-solves at the Fig. 6 weight (other
    keep-out radii, other a_max readings) that reach a lower RMS than the sweep's plan there."""
    validation.instance(case, "case", Case2Sweep)
    dominated = _rows(dominated, "dominated", 4)
    validation.instance(row6, "row6", PlanRow)
    radius_rows = validation.sequence_of(radius_rows, "radius_rows", RadiusRow, "RadiusRow")
    amax_rows = _rows(amax_rows, "amax_rows", 4)
    if not dominated:
        return "no dominated plan"
    ko = case.scenario.keep_out_km
    note = ("closest approach at the dominated weights " + ", ".join(
        f"{a:g}: {case.by_alpha[a].min_range_km:.0f} km" for a, _, _, _ in dominated)
        + f" (keep-out {ko:.0f} km, binding if equal)")
    bound = row6.crlb.terminal_rms_km[0]
    better = ([f"keep-out {r.d:.0f} km: {r.rms:.1f} km at {r.dv:.2f} m/s" for r in radius_rows
               if r.d != ko and r.rms < bound]
              + [f"a_max {lab}: {r_:.1f} km at {d:.2f} m/s" for lab, d, r_, q_ in amax_rows if r_ < bound])
    if row6.alpha in [a for a, _, _, _ in dominated] and better:
        note += (f"; re-solves at alpha {row6.alpha:g} reach a lower RMS than the sweep's {bound:.1f} km: "
                 + "; ".join(better) + "; the Fig. 6/10 plan there is a keep-out-bound local optimum")
    return note


@dataclass(frozen=True)
class KeepOutStudy:
    """The keep-out radius and the a_max reading, swept at the Fig. 6 weight (notebook 06, section 11).

    Attributes
    ----------
    alpha : float
    free : FreeRun
        The run without any keep-out.
    free_range_km : float
        Its closest approach at a measurement if it converged (NaN otherwise).
    radius_rows : list of RadiusRow
        The adopted radius (the sweep's plan) and every radius whose solve converged, by radius.
    failed_radii : dict
        ``radius km -> SCvxError``.
    amax_rows : list of tuple
        ``(label, impulse m/s, observer terminal RMS km, largest |u|/a_max)`` per converged a_max reading.
    amax_failed : dict
        ``label -> SCvxError``.
    """

    alpha: float
    free: FreeRun
    free_range_km: float
    radius_rows: list
    failed_radii: dict
    amax_rows: list
    amax_failed: dict

    @property
    def rank_radii(self):
        """Spearman(MI, terminal RMS) across the radii (None below 3 radii)."""
        rr = self.radius_rows
        return float(spearmanr([r.mi for r in rr], [r.rms for r in rr]).statistic) if len(rr) >= 3 else None

    @property
    def radii_text(self) -> str:
        rk = self.rank_radii
        return (f"{rk:+.2f} across keep-out radii at alpha {self.alpha:g}" if rk is not None else
                f"across keep-out radii not computed ({len(self.radius_rows)} radii)")

    @property
    def rms_span(self) -> float:
        return max(r.rms for r in self.radius_rows) / min(r.rms for r in self.radius_rows)

    def summary(self, row6, d_min_km, keep_out_km: float, same_plan_km: float) -> str:
        f, nk = self.free, self.free.outcome
        if f.failed:
            rr = f.ref_range_km
            lines = [f"without the keep-out SCvx did not converge: {nk.reason}; best accepted cost {f.best_cost:.5f} "
                     f"(defects not yet closed) vs {row6.res.cost:.5f} of the constrained optimum",
                     f"closest approach to a target at a measurement over its {rr.size} references: last "
                     f"{rr[-1]:.1f} km, smallest {rr.min():.1f} km (first {rr[0]:.0f} km)"]
        else:
            lines = [f"without the keep-out (alpha {self.alpha:g}): closest approach {self.free_range_km:.3f} km at a "
                     f"measurement, MI {nk.information:.2f} nats vs {row6.mi:.2f} with it"]
        lines += [f"keep-out {d:g} km: no convergence ({e.reason})" for d, e in self.failed_radii.items()]
        lines.append(radius_summary(self.radius_rows, row6, d_min_km, keep_out_km, self.alpha, same_plan_km))
        lines += [f"a_max {lab}: failed ({e.reason})" for lab, e in self.amax_failed.items()]
        lines += [f"a_max {lab}: dV {d:.2f} m/s, observer RMS {r:.1f} km, largest |u|/a_max {q:.2f}"
                  for lab, d, r, q in self.amax_rows]
        lines.append(f"a_max 5e-7 (adopted): dV {row6.dv:.2f} m/s, observer RMS {row6.crlb.terminal_rms_km[0]:.1f} km, "
                     f"largest |u|/a_max {row6.u_ratio:.2f}")
        rk = self.rank_radii
        lines.append(f"across keep-out radii at alpha_h = {self.alpha:g}: Spearman(MI, terminal RMS) "
                     + (f"{rk:+.2f}" if rk is not None else f"not computed ({len(self.radius_rows)} radii)"))
        return "\n".join(lines)


def keep_out_study(case: Case2Sweep, row6, free: FreeRun, radius_results: dict, amax_results: dict, *,
                   radius_start: str = "cold") -> KeepOutStudy:
    """Collect the keep-out radius solves (``radius km -> result or SCvxError``, all at ``row6``'s weight) and the
    a_max readings (``label -> (solver, result or SCvxError)``) against the sweep's plan ``row6``."""
    validation.instance(case, "case", Case2Sweep)
    validation.instance(row6, "row6", PlanRow)
    validation.instance(free, "free", FreeRun)
    validation.instance(radius_results, "radius_results", dict, "a dict {radius km: result or SCvxError}")
    validation.instance(amax_results, "amax_results", dict, "a dict {label: (solver, result or SCvxError)}")
    validation.choice(radius_start, "radius_start", ("cold", "warm"))
    sc, k_ws = case.scenario, case.k_ws
    nk = free.outcome
    free_range = np.nan if free.failed else float(sc.keep_out(k_ws).ranges(nk.x[k_ws]).min() * sc.system.length_unit_km)
    rows = [radius_row(sc, k_ws, sc.keep_out_km, "sweep", row6.res, row6.res.x)]
    failed = {}
    for d, res in radius_results.items():
        if isinstance(res, Exception):
            failed[d] = res
        else:
            rows.append(radius_row(sc, k_ws, d, radius_start, res, row6.res.x))
    rows.sort(key=lambda r: r.d)
    amax_rows, amax_failed = [], {}
    for label, (solver, res) in amax_results.items():
        if isinstance(res, Exception):
            amax_failed[label] = res
            continue
        r = plan_row(sc, solver, k_ws, case.k_we, row6.alpha, res)
        amax_rows.append((label, r.dv, r.crlb.terminal_rms_km[0], r.u_ratio))
    return KeepOutStudy(row6.alpha, free, free_range, rows, failed, amax_rows, amax_failed)
