r"""The studies of the SCvx chapter (notebook 03): a minimum-impulse transfer on Wolf & Jones test case 1's boundary
conditions, solved by successive convexification with first-order hold (Eqs. 24-36, 42-43, Table 1).

What is here:

* :func:`transfer_problem`: the problem (corrected Table 2 observer DRO to the printed :math:`x_{\mathcal S}(t_f)`,
  Sundman nodes with the window ends on nodes, zero thrust bound inside the observation window).
* :func:`solve` : one SCvx run of the problem from the ballistic guess.
* :func:`iteration_summary`: what the iteration history says (accepted steps, the noise rule, multiplier updates,
  the largest-defect ratios that a superlinear rate would drive to zero, above the solver's round-off floor).
* :func:`single_shooting`: the converged first-order-hold control re-flown from the initial state alone.
* :class:`NodeDefects`: the node defects of a converged plan re-measured by an independent integrator (scipy DOP853).
* :func:`blended_guess`, :func:`guess_study`: the same problem from random initial guesses.
* :func:`printed_method_study`: the printed SCvx, fairly (issue 22 item 4): test case 1 with the information reward
  solved by every combination of the paper's ingredients (L1 exact penalty, linear MI model of Eq. 44) and ours
  (augmented Lagrangian, concave-quadratic MI model), under the strict stopping test and under the practical rule
  :class:`cislunar.guidance.scvx.PracticalStop`.
* ``figure_*``: the chapter's figures.

Units: non-dimensional (LU, TU, LU/TU, LU/TU^2) unless a name says ``_km``, ``_mm_s`` or ``_d``; Earth-Moon
rotating frame.
"""

from __future__ import annotations

import functools
import itertools
from dataclasses import dataclass, field

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp

from cislunar.cr3bp.dynamics import check_system
from cislunar.cr3bp.propagation import propagate
from cislunar.guidance import discretization as D
from cislunar.guidance import scvx
from cislunar.papers.wolf_jones import _checks, scenarios
from cislunar.publish import plotting
from cislunar.utils import validation
from cislunar.utils.montecarlo import map_tasks

__all__ = [
    "GuessStudy",
    "IterationSummary",
    "NodeDefects",
    "PRACTICAL_STOP",
    "PrintedMethodStudy",
    "VariantRun",
    "ShootingCheck",
    "TransferProblem",
    "blended_guess",
    "figure_converged_control",
    "figure_iterations",
    "figure_printed_method",
    "guess_study",
    "iteration_summary",
    "printed_method_study",
    "single_shooting",
    "solve",
    "transfer_problem",
]


@dataclass(frozen=True)
class TransferProblem:
    """Minimum-impulse transfer with test case 1's boundary conditions.

    Attributes
    ----------
    scenario : scenarios.Scenario
    x0, x_final : ndarray (6,)
        Corrected initial DRO state and the printed final state, LU and LU/TU.
    t : ndarray
        Sundman node times (window ends on nodes), TU.
    k_window : tuple of int
        First and last node of the observation window.
    u_max : ndarray
        Thrust-acceleration bound per node, LU/TU^2 (``a_max`` outside the window, zero inside).
    x_guess : ndarray (N, 6)
        Ballistic initial guess at the nodes.
    """

    scenario: scenarios.Scenario
    x0: np.ndarray
    x_final: np.ndarray
    t: np.ndarray
    k_window: tuple
    u_max: np.ndarray
    x_guess: np.ndarray
    sigma: float

    @property
    def in_window(self) -> np.ndarray:
        return self.u_max == 0

    @property
    def system(self):
        return self.scenario.system

    @property
    def ballistic_miss(self) -> float:
        """``|x_f - x(T)|`` of the ballistic arc over the transfer time, non-dimensional 6-vector norm."""
        return float(np.linalg.norm(propagate(self.system, self.x0, self.scenario.duration).x[-1] - self.x_final))


def transfer_problem(n_nodes: int, sigma: float = 1.0, *, a_max_km_s2: float | None = None) -> TransferProblem:
    """Test case 1's transfer on ``n_nodes`` Sundman nodes of exponent ``sigma`` (window ends moved onto nodes), with
    the thrust-acceleration bound ``a_max_km_s2`` (km/s^2; ``None``: Table 3's value)."""
    n = validation.integer(n_nodes, "n_nodes", minimum=4)
    sigma = validation.positive(sigma, "sigma", allow_zero=True)
    if a_max_km_s2 is not None:
        a_max_km_s2 = validation.positive(a_max_km_s2, "a_max_km_s2")
    sc = scenarios.test_case_1() if a_max_km_s2 is None else scenarios.test_case_1(a_max_km_s2=a_max_km_s2)
    dro = sc.row_checks["observer_t0"].corrected
    t, k_ws, k_we = sc.node_times(n, sigma)
    x_guess = propagate(sc.system, dro.x0, t).x
    return TransferProblem(sc, np.asarray(dro.x0), np.asarray(sc.observer_xf), t, (int(k_ws), int(k_we)),
                           sc.control_bounds(t), x_guess, float(sigma))


def solve(problem: TransferProblem, settings: scvx.SCvxSettings | None = None, *, x_guess=None,
          u_guess=None) -> scvx.SCvxResult:
    """One SCvx run of ``problem`` (default: ballistic state guess, zero controls, default settings)."""
    validation.instance(problem, "problem", TransferProblem)
    if settings is not None:
        validation.instance(settings, "settings", scvx.SCvxSettings)
    x = problem.x_guess if x_guess is None else x_guess
    u = np.zeros((problem.t.size, 3)) if u_guess is None else u_guess
    return scvx.solve_scvx(problem.system, problem.t, x, u, problem.u_max, x_final=problem.x_final,
                           settings=scvx.SCvxSettings() if settings is None else settings)


def _run(result, name: str = "result"):
    """An SCvx run with an iteration history (an SCvxResult, an SCvxError or any object with a ``history`` list)."""
    if not isinstance(getattr(result, "history", None), list):
        raise validation.ArgumentTypeError(f"{name} must be an SCvx run with a history list (an SCvxResult or "
                                           f"SCvxError); got {type(result).__name__}")
    return result


@dataclass(frozen=True)
class IterationSummary:
    """What an SCvx history says.

    ``forced``: iterations whose predicted decrease was at the noise level, ``|J - L| <= noise_tol (1 + |J|)``, so
    that rho was set to 1; ``forced_negative``: how many of them had a negative prediction; ``rho_range``: (min,
    max) of rho over the other steps; ``updates``: iterations after which the multipliers were updated;
    ``defect_ratio``: largest defect after each step over that after the previous step.  ``defects``: largest defect
    (LU) after each accepted step, in order; ``rate_floor``: the round-off floor (LU) of the rate test, the solver's
    own defect tolerance ``settings.defect_tol`` (below it the solver counts the defects as closed).
    """

    n_steps: int
    n_accepted: int
    forced: tuple
    forced_predicted: tuple
    forced_negative: int
    n_real: int
    rho_range: tuple
    updates: tuple
    eta_start: float
    eta_end: float
    defect_ratio: np.ndarray
    defects: np.ndarray
    rate_floor: float

    @property
    def rate_ratios(self) -> np.ndarray:
        """Ratios of successive largest defects over the accepted steps that start and end above ``rate_floor``
        (a defect below the floor is round-off, so a ratio with an end there measures nothing), in order."""
        d = self.defects
        above = (d[:-1] > self.rate_floor) & (d[1:] > self.rate_floor)
        return d[1:][above] / d[:-1][above]

    def superlinear(self, n_tail: int = 3, factor: float = 0.5) -> bool:
        """Whether the defect ratios tend to zero: the last ``n_tail`` of :attr:`rate_ratios` are contractions (< 1)
        and each is at most ``factor`` times the one before (a linear rate, whose ratios settle at a constant, fails;
        so does a run with fewer than ``n_tail`` steps above the floor, which cannot show a rate)."""
        r = self.rate_ratios
        if r.size < n_tail:
            return False
        tail = r[-n_tail:]
        return bool(np.all(tail < 1.0) and np.all(tail[1:] <= factor * tail[:-1]))


def iteration_summary(result, settings: scvx.SCvxSettings) -> IterationSummary:
    """Summarise ``result.history`` under the noise rule of ``settings``."""
    _run(result)
    validation.instance(settings, "settings", scvx.SCvxSettings)
    hist = result.history
    if not hist:
        raise ValueError("the result has no iteration history")
    noise = [abs(h["predicted"]) <= settings.noise_tol * (1 + abs(h["cost"])) for h in hist]
    forced = tuple(h["iteration"] for h, nl in zip(hist, noise) if nl)
    real = [h["rho"] for h, nl in zip(hist, noise) if not nl]
    defects = np.array([h["max_defect"] for h in hist])
    accepted = np.array([h["max_defect"] for h in hist if h["accepted"]], dtype=float)
    return IterationSummary(
        len(hist), int(sum(h["accepted"] for h in hist)), forced, tuple(hist[i]["predicted"] for i in forced),
        int(sum(hist[i]["predicted"] < 0 for i in forced)), len(real),
        (min(real), max(real)) if real else (float("nan"), float("nan")),
        tuple(h["iteration"] for h in hist if h["multiplier_update"]), float(hist[0]["eta"]), float(hist[-1]["eta"]),
        defects[1:] / defects[:-1], accepted, float(settings.defect_tol))


@dataclass(frozen=True)
class ShootingCheck:
    """The converged control flown from the initial state alone: states at the nodes and the terminal miss."""

    x: np.ndarray
    miss_km: float
    miss_mm_s: float


def single_shooting(problem: TransferProblem, u) -> ShootingCheck:
    """Fly the first-order-hold control ``u`` (LU/TU^2 at the nodes) through the nonlinear dynamics from ``x0``."""
    validation.instance(problem, "problem", TransferProblem)
    u = validation.as_array(u, "u", shape=(problem.t.size, 3))
    em = problem.system
    x = D.propagate_foh(em, problem.x0, problem.t, u)
    return ShootingCheck(x, float(np.linalg.norm(x[-1, :3] - problem.x_final[:3]) * em.length_unit_km),
                         float(np.linalg.norm(x[-1, 3:] - problem.x_final[3:]) * em.velocity_unit_km_s * 1e6))


@dataclass(frozen=True)
class NodeDefects:
    """Node defects of a first-order-hold plan measured by an integrator independent of the solver's.

    Each interval is re-propagated from its node state ``x_k`` under the FOH acceleration (linear from ``u_k`` to
    ``u_{k+1}``) with ``scipy.integrate.solve_ivp`` (DOP853) on the CR3BP vector field, and compared with ``x_{k+1}``:
    the defect of Eq. 34 as the solver measures it (the 2-norm of the 6-vector, LU and LU/TU), but without heyoka,
    the solver's discretisation or its bookkeeping.

    Attributes
    ----------
    defects : ndarray (N-1,)
        ``|x_{k+1} - phi(t_{k+1}; t_k, x_k, u)|`` with DOP853 at ``rtol = atol = rtol``.
    integrator_spread : ndarray (N-1,)
        Per interval, the distance between the end states of DOP853 at ``rtol`` and at the looser ``check_rtol``: an
        estimate of the looser run's error, so an upper estimate of the measuring run's.
    rtol, check_rtol : float
    """

    defects: np.ndarray
    integrator_spread: np.ndarray
    rtol: float
    check_rtol: float

    @property
    def largest(self) -> float:
        """Largest node defect (LU, LU/TU)."""
        return float(np.max(self.defects))

    @classmethod
    def of(cls, system, t, x, u, *, rtol: float = 1e-13, check_rtol: float = 1e-12) -> "NodeDefects":
        """Measure the node defects of the plan ``x`` (N, 6) with node accelerations ``u`` (N, 3, LU/TU^2, first-order
        hold) at node times ``t`` (N,, TU, increasing)."""
        check_system(system)
        t = validation.time_grid(t, "t", increasing=True)
        x = validation.as_array(x, "x", shape=(t.size, 6))
        u = validation.as_array(u, "u", shape=(t.size, 3))
        rtol = validation.in_range(rtol, "rtol", 1e-16, 1e-6)
        check_rtol = validation.in_range(check_rtol, "check_rtol", 1e-16, 1e-6)
        defects, spread = np.empty(t.size - 1), np.empty(t.size - 1)
        for k in range(t.size - 1):
            ends = [_foh_flight(system, x[k], u[k], u[k + 1], t[k], t[k + 1], tol) for tol in (rtol, check_rtol)]
            defects[k] = np.linalg.norm(x[k + 1] - ends[0])
            spread[k] = np.linalg.norm(ends[1] - ends[0])
        return cls(defects, spread, float(rtol), float(check_rtol))


def _foh_flight(system, x0, u0, u1, t0, t1, tol) -> np.ndarray:
    """End state of one FOH interval by DOP853 (scipy), ``rtol = atol = tol``."""
    du = (u1 - u0) / (t1 - t0)

    def rhs(tau, y):
        f = system.eom(y)
        f[3:] += u0 + (tau - t0) * du
        return f

    sol = solve_ivp(rhs, (t0, t1), x0, method="DOP853", rtol=tol, atol=tol)
    if not sol.success:
        raise RuntimeError(f"solve_ivp failed on [{t0}, {t1}]: {sol.message}")
    return sol.y[:, -1]


@dataclass(frozen=True)
class GuessStudy:
    """Impulses (LU/TU), iteration counts and converged plans (node states, LU and LU/TU) from random initial
    guesses; ``spread`` relative to a reference."""

    impulses: np.ndarray
    iterations: tuple
    spread: float
    plans: np.ndarray

    def impulse_gap(self, reference_impulse: float) -> float:
        """Largest ``|J_i - J_ref| / (1 + |J_ref|)`` over the runs, with ``J`` the impulse (LU/TU; at alpha_h = 0 and
        closed defects the cost): in the units of the solver's relative cost tolerance."""
        ref = validation.real(reference_impulse, "reference_impulse")
        return float(np.max(np.abs(self.impulses - ref)) / (1.0 + abs(ref)))

    def plan_distance(self, reference_x) -> float:
        """Largest position distance, over the runs and the nodes, from the reference plan ``reference_x`` (N, 6), LU."""
        ref = validation.as_array(reference_x, "reference_x", shape=self.plans.shape[1:])
        return float(np.max(np.linalg.norm(self.plans[:, :, :3] - ref[:, :3], axis=-1)))

    def same_optimum(self, reference_impulse: float, reference_x, *, cost_tol: float, distance: float) -> bool:
        """Every run reached the reference optimum: :meth:`impulse_gap` at most ``cost_tol`` and
        :meth:`plan_distance` at most ``distance`` (LU)."""
        cost_tol = validation.positive(cost_tol, "cost_tol")
        distance = validation.positive(distance, "distance")
        return bool(self.impulse_gap(reference_impulse) <= cost_tol and self.plan_distance(reference_x) <= distance)


def _solve_guess(task) -> tuple:
    """One SCvx run from a given guess, for :func:`cislunar.utils.montecarlo.map_tasks`: (impulse, iterations,
    converged node states)."""
    problem, x_guess, u_guess, max_iter = task
    r = solve(problem, scvx.SCvxSettings(max_iter=max_iter), x_guess=x_guess, u_guess=u_guess)
    return float(r.impulse), len(r.history), np.asarray(r.x)


def blended_guess(problem: TransferProblem) -> np.ndarray:
    """The straight blend ``(1 - s) x_fwd + s x_bwd``, ``s = t / t_f``, of the forward ballistic arc from ``x0`` and
    the backward ballistic arc from ``x_final``, at the nodes (LU, LU/TU)."""
    validation.instance(problem, "problem", TransferProblem)
    t = problem.t
    back = propagate(problem.system, problem.x_final, t[::-1]).x[::-1]
    s = (t / t[-1])[:, None]
    return (1 - s) * problem.x_guess + s * back


def guess_study(problem: TransferProblem, n_guesses: int, rng: np.random.Generator, reference_impulse: float, *,
                control_scale: float = 0.05, max_iter: int = 200, executor=None) -> GuessStudy:
    """Solve from ``n_guesses`` guesses: the straight blend of the forward and backward ballistic arcs
    (:func:`blended_guess`), with random node controls of ``control_scale * a_max`` per axis (zero in the window).

    The random controls are drawn from ``rng`` here, guess after guess; the runs then go through ``executor``
    (:func:`cislunar.utils.montecarlo.map_tasks`; ``None``: serially), so the result does not depend on it.
    """
    validation.instance(problem, "problem", TransferProblem)
    n = validation.integer(n_guesses, "n_guesses", minimum=1)
    validation.instance(rng, "rng", np.random.Generator)
    ref = validation.positive(reference_impulse, "reference_impulse")
    scale = validation.positive(control_scale, "control_scale", allow_zero=True)
    max_iter = validation.integer(max_iter, "max_iter", minimum=1)
    _checks.executor(executor)
    t = problem.t
    guess = blended_guess(problem)
    tasks = [(problem, guess,
              scale * problem.scenario.a_max * rng.standard_normal((t.size, 3)) * (problem.u_max > 0)[:, None],
              max_iter) for _ in range(n)]
    runs = map_tasks(_solve_guess, tasks, executor=executor, progress=False, desc="initial guesses")
    impulses = np.array([r[0] for r in runs])
    return GuessStudy(impulses, tuple(r[1] for r in runs), float((impulses.max() - impulses.min()) / ref),
                      np.stack([r[2] for r in runs]))


# ---------------------------------------------------------------------------------------------------------------
# The printed method, fairly (issue 22 item 4)
# ---------------------------------------------------------------------------------------------------------------
PRACTICAL_STOP = scvx.PracticalStop(window=5, defect_tol=1e-8, cost_tol=1e-8)
"""The practical stopping rule of :func:`printed_method_study`, fixed before any run: five consecutive accepted steps
with the largest defect at most 1e-8 (LU: 3.8 m; LU/TU: 1 cm/s) and a relative cost change at most 1e-8."""

VARIANTS = {  # label: (method, information model, practical rule?)
    "AL + quadratic, strict": ("augmented_lagrangian", "quadratic", False),
    "AL + linear, strict": ("augmented_lagrangian", "linear", False),
    "AL + linear, practical": ("augmented_lagrangian", "linear", True),
    "L1 + linear, practical": ("penalty", "linear", True),
    "L1 + quadratic, practical": ("penalty", "quadratic", True),
}
"""The runs of :func:`printed_method_study`: the package's default first (the reference optimum), the printed method
(L1 exact penalty, linear model of Eq. 44) last but one."""


@dataclass(frozen=True)
class VariantRun:
    r"""One SCvx run of :func:`printed_method_study`.

    ``converged``: the run stopped as a success (``stopped_by``: "strict" or "practical"), else ``outcome`` is the
    :class:`~cislunar.guidance.scvx.SCvxError` reason; ``cost``: objective :math:`(1-\alpha_h)\,\mathrm{impulse}
    - \alpha_h\mathcal I` (penalty excluded, non-dimensional) at the last accepted reference; ``max_defect``: its
    largest defect (LU or LU/TU); ``eta``: the last trust-region radius; ``tr_active``: fraction of the steps that
    ended on the trust-region boundary.
    """

    label: str
    method: str
    information_model: str
    practical: bool
    converged: bool
    stopped_by: str
    outcome: str
    iterations: int
    cost: float
    max_defect: float
    eta: float
    tr_active: float
    history: list


@dataclass(frozen=True)
class PrintedMethodStudy:
    """Test case 1 at one weight solved by every combination of the paper's SCvx ingredients and ours.

    ``runs``: label -> :class:`VariantRun` (labels of :data:`VARIANTS`, every L1 run at the package's penalty weight
    gamma = ``SCvxSettings.defect_weight``, 1e3); ``gamma_runs``: penalty weight gamma -> :class:`VariantRun` of
    the printed method (L1 exact penalty, linear MI model, practical rule) at the other weights asked for;
    ``reference``: the cost of the package's default run (augmented Lagrangian, quadratic MI model, strict stop),
    non-dimensional.
    """

    alpha: float
    n_nodes: int
    max_iter: int
    runs: dict
    gamma_runs: dict = field(default_factory=dict)

    @property
    def reference(self) -> float:
        return self.runs["AL + quadratic, strict"].cost

    def gap(self, label: str) -> float:
        """Cost of run ``label`` minus the reference (non-dimensional; positive: worse)."""
        return self.runs[validation.choice(label, "label", tuple(self.runs))].cost - self.reference

    def summary(self) -> str:
        lines = [f"test case 1, alpha_h = {self.alpha:g}, {self.n_nodes} nodes, at most {self.max_iter} iterations; "
                 f"practical rule: {PRACTICAL_STOP.window} accepted steps with defects <= "
                 f"{PRACTICAL_STOP.defect_tol:g} and relative cost change <= {PRACTICAL_STOP.cost_tol:g}",
                 f"{'run':<27} {'stops':>10} {'iter':>5} {'cost':>14} {'- reference':>12} {'defect':>8} {'eta':>8} "
                 f"{'on TR':>6}"]
        if not self.runs["AL + quadratic, strict"].converged:
            lines.insert(1, "(the reference run did not converge within the limit: distances are to its last iterate)")
        for r in self.runs.values():
            lines.append(f"{r.label:<27} {(r.stopped_by or 'no'):>10} {r.iterations:5d} {r.cost:14.10f} "
                         f"{r.cost - self.reference:12.2e} {r.max_defect:8.1e} {r.eta:8.1e} {r.tr_active:6.0%}"
                         + ("" if r.converged else f"  ({r.outcome})"))
        if self.gamma_runs:
            lines.append("the printed method (L1 + linear, practical) at other penalty weights gamma:")
        for r in self.gamma_runs.values():
            lines.append(f"{r.label:<27} {(r.stopped_by or 'no'):>10} {r.iterations:5d} {r.cost:14.10f} "
                         f"{r.cost - self.reference:12.2e} {r.max_defect:8.1e} {r.eta:8.1e} {r.tr_active:6.0%}"
                         + ("" if r.converged else f"  ({r.outcome})"))
        return "\n".join(lines)


def _variant_task(problem: tuple, task) -> VariantRun:
    """One run of :func:`printed_method_study` (module level: picklable for an executor): ``task`` is a label of
    :data:`VARIANTS` (package penalty weight) or a penalty weight gamma for the printed method."""
    system, t, x_ball, u_ball, u_max, x_final, info, k_ws, alpha, max_iter = problem
    if isinstance(task, str):
        label, extra = task, {}
    else:
        label, extra = f"L1 + linear, gamma {task:.0e}", {"defect_weight": float(task)}
    method, model, practical = VARIANTS[task if isinstance(task, str) else "L1 + linear, practical"]
    st = scvx.SCvxSettings(method=method, information_model=model, max_iter=max_iter, **extra)
    try:
        r = scvx.solve_scvx(system, t, x_ball, u_ball, u_max, x_final=x_final, info=info, info_node=k_ws, alpha=alpha,
                            settings=st, practical_stop=PRACTICAL_STOP if practical else None)
        hist, ok, by, outcome = r.history, True, r.stopped_by, f"{r.stopped_by} stop after {r.iterations} iterations"
    except scvx.SCvxError as exc:
        hist, ok, by, outcome = exc.history, False, "", exc.reason
    acc = [h for h in hist if h["accepted"]]
    last = acc[-1] if acc else None
    cost = (1.0 - alpha) * last["impulse"] - alpha * last["information"] if last else float("nan")
    return VariantRun(label, method, model, practical, ok, by, outcome, len(hist), float(cost),
                      float(last["max_defect"]) if last else float("nan"), float(hist[-1]["eta"]) if hist else float("nan"),
                      float(np.mean([h["tr_active"] for h in hist])) if hist else float("nan"), hist)


def printed_method_study(n_nodes: int, *, alpha: float = 5e-3, max_iter: int = 300, sigma: float = 1.0,
                         labels=None, gammas=(), executor=None) -> PrintedMethodStudy:
    """Test case 1 (information reward at weight ``alpha``) from the ballistic DRO by each variant of :data:`VARIANTS`.

    Parameters
    ----------
    n_nodes : int
        Sundman nodes (window ends moved onto nodes).
    alpha : float
        Homotopy weight in (0, 1].
    max_iter : int
        Iteration limit of every run.
    sigma : float
        Sundman exponent.
    labels : sequence of str, optional
        Subset of :data:`VARIANTS` (default all); the reference run is always included.
    gammas : sequence of float, optional
        Further penalty weights gamma (> 0) at which the printed method (L1 exact penalty, linear MI model, practical
        rule) is run, into ``gamma_runs`` (the paper does not print gamma; the variants use 1e3).
    executor : optional
        Runs the variants side by side (:func:`cislunar.utils.montecarlo.map_tasks`); results do not depend on it.
    """
    n = validation.integer(n_nodes, "n_nodes", minimum=4)
    alpha = validation.in_range(alpha, "alpha", 0.0, 1.0)
    if alpha == 0.0:
        raise ValueError("alpha must be > 0 (the information reward is what the linear model approximates)")
    max_iter = validation.integer(max_iter, "max_iter", minimum=1)
    sigma = validation.positive(sigma, "sigma", allow_zero=True)
    chosen = list(VARIANTS) if labels is None else list(labels)
    for lab in chosen:
        validation.choice(lab, "labels", tuple(VARIANTS))
    chosen = ["AL + quadratic, strict"] + [lab for lab in chosen if lab != "AL + quadratic, strict"]
    if not isinstance(gammas, (list, tuple, np.ndarray)):
        raise validation.ArgumentTypeError(f"gammas must be a sequence of penalty weights; got {type(gammas).__name__}")
    gammas = [float(validation.positive(g, "gammas")) for g in np.ravel(gammas)]
    _checks.executor(executor)
    sc = scenarios.test_case_1()
    t, k_ws, _ = sc.node_times(n, sigma)
    x_ball, u_ball = sc.ballistic_guess(t)
    problem = (sc.system, t, x_ball, u_ball, sc.control_bounds(t), np.asarray(sc.observer_xf), sc.information_model(),
               int(k_ws), float(alpha), max_iter)
    runs = map_tasks(functools.partial(_variant_task, problem), chosen + gammas, executor=executor, progress=False,
                     desc="SCvx variants")
    return PrintedMethodStudy(float(alpha), n, max_iter, {r.label: r for r in runs[:len(chosen)]},
                              dict(zip(gammas, runs[len(chosen):])))


# ---------------------------------------------------------------------------------------------------------------
# Figures
# ---------------------------------------------------------------------------------------------------------------


def figure_iterations(result, settings: scvx.SCvxSettings, velocity_unit_km_s: float):
    """Cost per step (with the multiplier-update jumps), impulse after each step and largest defect after each step."""
    _run(result)
    validation.instance(settings, "settings", scvx.SCvxSettings)
    velocity_unit_km_s = validation.positive(velocity_unit_km_s, "velocity_unit_km_s")
    hist = result.history
    updates = [h["iteration"] for h in hist if h["multiplier_update"]]
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.4), layout="constrained")
    # J as a sawtooth: each step runs from J before (at x = it) to J after (at x = it + 1); a multiplier/weight update
    # then redefines J at the same trajectory (vertical jump at x = it + 1)
    for h in hist:
        it = h["iteration"]
        axes[0].semilogy([it, it + 1], [h["cost"], h["new_cost"]], "-", color="C0", marker="o", ms=3)
    for h, nxt in itertools.pairwise(hist):
        if h["multiplier_update"]:
            axes[0].semilogy([h["iteration"] + 1] * 2, [h["new_cost"], nxt["cost"]], ":", color="C1", lw=1.5)
    axes[0].plot([], [], "-o", ms=3, color="C0", label="SCvx step (J does not rise)")
    axes[0].plot([], [], ":", lw=1.5, color="C1", label=r"$\lambda$ update, $w$ raised (J redefined)")
    axes[0].set(xlabel="iteration [-]", ylabel=r"augmented-Lagrangian cost $\mathcal{J}$ [non-dim.]",
                title="cost per SCvx step")
    impulse_hist = np.array([h["impulse"] for h in hist]) * velocity_unit_km_s * 1e3
    axes[1].plot([h["iteration"] + 1 for h in hist], impulse_hist, "o-", color="C2")
    axes[1].set(xlabel="iteration [-]", ylabel="total impulse after the step [m/s]",
                title="impulse rises as the defects close")
    axes[2].semilogy([h["iteration"] + 1 for h in hist], [max(h["max_defect"], 1e-16) for h in hist], "o-",
                     color="C0")
    axes[2].axhline(settings.defect_tol, color="0.4", ls="--", lw=0.8, label="convergence tolerance")
    axes[2].set(xlabel="iteration [-]", ylabel="largest defect after the step\n[LU or LU/TU]", title="defects")
    for ax in axes:
        ax.xaxis.set_major_locator(plt.MaxNLocator(integer=True))
        for it in updates:  # the updates happen between steps: mark them in every panel
            ax.axvline(it + 1, color="C1", lw=0.6, alpha=0.35, zorder=0)
    for ax in (axes[0], axes[2]):
        ax.yaxis.set_minor_formatter(plt.NullFormatter())  # decade labels only: no colliding minor tick labels
        ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.2), frameon=False)  # below the axes
    fig.suptitle("SCvx iterations, minimum-impulse DRO transfer (test case 1 boundary conditions); "
                 "faint red lines: multiplier updates")
    return fig


def figure_converged_control(problem: TransferProblem, u, shooting: ShootingCheck):
    """Thrust-acceleration norm at the nodes (window shaded) and the flown trajectory minus the initial DRO."""
    validation.instance(problem, "problem", TransferProblem)
    u = validation.as_array(u, "u", shape=(problem.t.size, 3))
    validation.instance(shooting, "shooting", ShootingCheck)
    em, t = problem.system, problem.t
    k_ws, k_we = problem.k_window
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.6), layout="constrained")
    unorm = np.linalg.norm(u, axis=1) * em.acceleration_unit_km_s2 * 1e9  # µm/s²
    a_max_um = problem.scenario.a_max * em.acceleration_unit_km_s2 * 1e9
    ax1.axvspan(em.tu_to_days(t[k_ws]), em.tu_to_days(t[k_we]), color="0.9", label="observation window (no thrust)")
    ax1.plot(em.tu_to_days(t), unorm, ".-", label="|u| at the nodes")
    ax1.set(xlabel="time [days]", ylabel="thrust acceleration [µm/s²]", ylim=(0, None),
            title=f"converged control ($a_{{max}}$ = {a_max_um:.0f} µm/s², off the scale)")
    ax1.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.15), frameon=False)  # below the axes
    rel = shooting.x - propagate(em, problem.x0, t).x
    rel_km = rel[:, :2] * em.length_unit_km
    plotting.plot_rotating(ax2, rel[None], em, "xy", units="km", marker=".")
    ax2.plot(*rel_km[0], "o", color="C2", ms=7, zorder=3, label="start (same state)")
    ax2.plot(*rel_km[-1], "s", color="C3", ms=7, zorder=3, label=r"end: $x_f$ on the neighbouring DRO")
    ax2.set(xlabel=r"$\Delta x$ [km]", ylabel=r"$\Delta y$ [km]",
            title="converged minus initial DRO, at the nodes (rotating frame)")
    ax2.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.15), ncol=2, frameon=False)
    return fig


def figure_printed_method(study: PrintedMethodStudy):
    """Each variant of :func:`printed_method_study`: distance of the cost to the reference optimum after each
    accepted step (non-dimensional), and the largest defect after each step (LU or LU/TU)."""
    validation.instance(study, "study", PrintedMethodStudy)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(13, 4.6), layout="constrained")
    styles = {"AL + quadratic, strict": ("C0", "-"), "AL + linear, strict": ("C2", "--"),
              "AL + linear, practical": ("C2", "-"), "L1 + linear, practical": ("C3", "-"),
              "L1 + quadratic, practical": ("C1", "-")}
    a, ref = study.alpha, study.reference
    for lab, r in study.runs.items():
        color, ls = styles.get(lab, ("0.5", "-"))
        acc = [h for h in r.history if h["accepted"]]
        it = np.array([h["iteration"] + 1 for h in acc])
        cost = np.array([(1 - a) * h["impulse"] - a * h["information"] for h in acc])
        end = "stops" if r.converged else "no stop"
        ax1.semilogy(it, np.maximum(np.abs(cost - ref), 1e-12), ls, color=color, lw=1.2,
                     label=f"{lab} ({end}, {r.iterations} it)")
        ax2.semilogy([h["iteration"] + 1 for h in r.history], [max(h["max_defect"], 1e-16) for h in r.history], ls,
                     color=color, lw=1.0)
    ax1.axhline(1e-6, color="0.4", ls=":", lw=0.8)
    ax1.set(xlabel="iteration [-]", ylabel="|cost - reference optimum| [non-dim.]\n(accepted steps)",
            title=rf"test case 1, $\alpha_h$ = {a:g}: distance to the optimum")
    ax2.axhline(PRACTICAL_STOP.defect_tol, color="0.4", ls="--", lw=0.8, label="practical rule: defects")
    ax2.set(xlabel="iteration [-]", ylabel="largest defect after the step [LU or LU/TU]", title="defects")
    for ax in (ax1, ax2):
        ax.xaxis.set_major_locator(plt.MaxNLocator(integer=True))
    ax1.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.17), ncol=2, frameon=False)
    ax2.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.17), frameon=False)
    fig.suptitle("The printed SCvx (L1 exact penalty, linear MI model) against the package's ingredients")
    return fig
